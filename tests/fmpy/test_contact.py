"""Self-contact through fmpy (scene diagonal_contact: a 0.1 m square of a
0.5 mm sheet, vertex 1 clamped, folded on its creased diagonal 0-2 to
180 degrees): the contact variables exist with contact and only then; the
fold closes flat and stops at the sheet thickness; FMU states continue
bit-identically while the contact pattern grows; contact.friction is a
parameter that refuses negative values."""

import json

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_helpers import Instance, build, run_ramp, unzip

FMI2_ERROR = 3
THICKNESS = 5e-4
H = 0.005  # communication step (s)
RAMP = 0.6  # the fold input goes 0 -> 1 over this time (s), then holds
END = 1.0

# name -> unit (None: dimensionless)
CONTACT_OUTPUTS = {
    "contact.min_gap": "m",
    "contact.pairs": None,
    "contact.normal_force": "N",
    "energy.contact": "J",
    "energy.friction": "J",
    "contact.chord_error": "m",
}


# diagonal_contact as FOLD, refined twice (32 facets). Not in scenes/: the
# every-scene tests would fold it in 0.1 s, which takes minutes.
FINE_FOLD = {
    "file_spec": 1.2,
    "frame_classes": ["creasePattern"],
    "vertices_coords": [[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]],
    "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]],
    "edges_assignment": ["B", "B", "B", "B", "V"],
    "edges_foldAngle": [None, None, None, None, 180],
    "faces_vertices": [[0, 1, 2], [0, 2, 3]],
    "ancf:name": "diagonal_contact_fine",
    "ancf:material": {"thickness": THICKNESS},
    "ancf:supports": [{"vertices": [1], "fix": "clamped"}],
    "ancf:contact": {"enabled": True, "friction": 0.0},
    "ancf:refine": 2,
}


def columns(inst):
    """Output name -> column of the rows that Instance.get returns."""
    return {inst.md.modelVariables[vr].name: k for k, vr in enumerate(inst.outputs)}


def fold_until(inst, t_end):
    """The fold ramp (value and slope each step) from the instance's time to
    `t_end` in steps of H; the output rows after each step."""
    n = round((t_end - inst.time) / H)
    return run_ramp(inst, [H] * n, ramp_time=RAMP, input_name="fold")


def corner_distance(row, col):
    p = [np.array([row[col[f"vertex[{i}].{c}"]] for c in "xyz"]) for i in (1, 3)]
    return float(np.linalg.norm(p[0] - p[1]))


def test_contact_variables_exist_only_with_contact(unzipped):
    md = read_model_description(unzipped("diagonal_contact"))
    by_name = {v.name: v for v in md.modelVariables}
    for name, unit in CONTACT_OUTPUTS.items():
        v = by_name[name]
        assert (v.type, v.causality, v.variability) == ("Real", "output", "continuous"), name
        assert v.unit == unit, name
    f = by_name["contact.friction"]
    assert (f.type, f.causality, f.variability, f.initial) == ("Real", "parameter", "fixed", "exact")
    assert float(f.start) == 0.0  # the scene's friction
    outputs = {u.variable.name for u in md.outputs}
    assert set(CONTACT_OUTPUTS) <= outputs

    plain = {v.name for v in read_model_description(unzipped("square")).modelVariables}
    assert not [n for n in plain if n.startswith("contact.")]
    assert not set(CONTACT_OUTPUTS) & plain


def test_diagonal_folded_flat_stops_at_the_thickness(unzipped):
    """Fold over 0.6 s, hold to 1 s: the gap never goes negative, every
    output stays finite, and at the end the sheet lies folded flat in
    contact with the free corners one thickness apart (within 10 %).
    Without friction no friction work is done."""
    inst = Instance(unzipped("diagonal_contact"), "fold-flat").initialize()
    try:
        col = columns(inst)
        rows = fold_until(inst, END)
    finally:
        inst.close()
    assert len(rows) == round(END / H)
    assert np.all(np.isfinite(rows))
    gap = rows[:, col["contact.min_gap"]]
    assert np.all(gap >= 0.0), f"negative gap {gap.min():.3e} m at step {gap.argmin()}"
    last = rows[-1]
    assert last[col["contact.pairs"]] > 0
    assert last[col["contact.normal_force"]] > 0.0
    d = corner_distance(last, col)
    assert THICKNESS <= d <= 1.1 * THICKNESS, f"corners {d:.4e} m apart"
    assert np.all(rows[:, col["energy.friction"]] == 0.0)


@pytest.mark.parametrize("friction", [0.0, 0.5])
@pytest.mark.parametrize("save_at", [0.5, 0.7], ids=["before-contact", "in-contact"])
def test_states_continue_bit_identically_through_contact(unzipped, save_at, friction):
    """Save at `save_at`, run to 1 s, restore, run again: the same bits;
    also after serializing the state into a fresh instance that was
    initialized with the scene's own parameters (friction 0), so with
    friction 0.5 the restore must also bring the parameter back. Saved at
    0.5 s the panels are still centimetres apart and close after the save;
    saved at the first step from 0.7 s with pairs in the barrier they are
    in contact (pairs active, friction lagged)."""
    d = unzipped("diagonal_contact")
    a = Instance(d, "original").initialize({"contact.friction": friction})
    b = Instance(d, "restored").initialize()
    try:
        col = columns(a)
        fold_until(a, save_at)
        if save_at > RAMP:
            # The free corners rest at the edge of the barrier (the crease
            # stop holds the fold just short of pressing them): save at the
            # first step from here with pairs in it.
            while a.get()[col["contact.pairs"]] == 0 and a.time < END - 0.1:
                fold_until(a, a.time + H)
        in_contact = a.get()[col["contact.pairs"]] > 0
        assert in_contact == (save_at > RAMP)
        state = a.slave.getFMUstate()
        t0 = a.time
        first = fold_until(a, END)
        assert first[-1, col["contact.pairs"]] > 0
        assert np.all(np.isfinite(first))

        a.slave.setFMUstate(state)
        a.time = t0
        second = fold_until(a, END)
        assert first.tobytes() == second.tobytes()

        blob = a.slave.serializeFMUstate(state)
        restored = b.slave.deSerializeFMUstate(blob)
        b.slave.setFMUstate(restored)
        assert b.slave.getReal([b.vr["contact.friction"]]) == [friction]
        b.time = t0
        third = fold_until(b, END)
        assert first.tobytes() == third.tobytes()

        a.slave.freeFMUstate(state)
        b.slave.freeFMUstate(restored)
    finally:
        a.close()
        b.close()


def test_states_restore_the_contact_pattern(tmp_path):
    """The same on the square refined to 32 facets (FINE_FOLD).
    In diagonal_contact the two facets are near each other from the first
    step, so the matrix pattern only grows then and a restore that ignored
    the pattern would go unnoticed; here facets away from the crease come
    near while it folds: saved at 0.4 s, the pattern has grown before the
    save (which the fresh instance only gets from the state) and grows
    again by 0.45 s (which the restore must undo)."""
    scene = tmp_path / "diagonal_contact_fine.fold"
    scene.write_text(json.dumps(FINE_FOLD))
    r = build(scene, tmp_path / "fine.fmu")
    assert r.returncode == 0, r.stderr
    d = unzip(tmp_path / "fine.fmu", tmp_path / "fine")
    a = Instance(d, "original").initialize()
    b = Instance(d, "restored").initialize()
    try:
        fold_until(a, 0.4)
        state = a.slave.getFMUstate()
        t0 = a.time
        first = fold_until(a, 0.45)
        assert np.all(np.isfinite(first))

        a.slave.setFMUstate(state)
        a.time = t0
        assert first.tobytes() == fold_until(a, 0.45).tobytes()

        restored = b.slave.deSerializeFMUstate(a.slave.serializeFMUstate(state))
        b.slave.setFMUstate(restored)
        b.time = t0
        assert first.tobytes() == fold_until(b, 0.45).tobytes()

        a.slave.freeFMUstate(state)
        b.slave.freeFMUstate(restored)
    finally:
        a.close()
        b.close()


def test_contact_friction_is_set_before_initialization_and_not_negative(unzipped):
    """A negative coefficient is fmi2Error with the reason logged and the
    value kept; 0.5 is taken and acts (friction does work in the folded
    stack, where the scene's own 0 does none); after initialization the
    parameter is fixed."""
    inst = Instance(unzipped("diagonal_contact"), "friction")
    try:
        vr = inst.vr["contact.friction"]
        assert inst.slave.getReal([vr]) == [0.0]
        with pytest.raises(FMICallException) as e:
            inst.slave.setReal([vr], [-0.1])
        assert e.value.status == FMI2_ERROR
        message = inst.log.messages()[-1]
        assert "contact.friction" in message and "must be zero or positive" in message
        assert inst.slave.getReal([vr]) == [0.0]

        inst.slave.setReal([vr], [0.5])
        assert inst.slave.getReal([vr]) == [0.5]
        inst.initialize()
        col = columns(inst)
        rows = fold_until(inst, END)
        work = rows[:, col["energy.friction"]]
        assert np.all(np.isfinite(rows))
        assert work[-1] > 0.0
        assert np.all(np.diff(work) >= 0.0)

        with pytest.raises(FMICallException) as e:
            inst.slave.setReal([vr], [0.3])
        assert e.value.status == FMI2_ERROR
        assert "fixed parameter" in inst.log.messages()[-1]
        assert inst.slave.getReal([vr]) == [0.5]
    finally:
        inst.close()


def test_contact_outputs_read_their_start_values_before_initialization_and_after_reset(unzipped):
    """Issue 38: reading the contact outputs before initialization or after
    fmi2Reset killed the instance (fmi2Fatal); FMI 2.0 allows the read."""
    inst = Instance(unzipped("diagonal_contact"), "contact-outputs")
    try:
        names = ["contact.min_gap", "contact.pairs", "contact.normal_force"]
        vrs = [inst.vr[n] for n in names]
        starts = [0.0, 0.0, 0.0]  # docs/fmu.md, "State machine"
        assert starts == inst.slave.getReal(vrs)
        inst.initialize()
        inst.step(0.01, {"fold": 0.5})
        assert np.all(np.isfinite(inst.slave.getReal(vrs)))
        inst.slave.reset()
        assert starts == inst.slave.getReal(vrs)
        inst.initialize()
        inst.step(0.01)
        assert np.all(np.isfinite(inst.get()))
    finally:
        inst.close()
