"""Rigid obstacles through fmpy's FMU2Slave, the way a master reads them:
tests/fmpy/scenes/ground.json is a 0.1 x 0.1 m square of 0.5 mm paper
(800 kg/m^3) under gravity, 2.5 mm above the ground `ground` (a half-space,
friction 0.3)."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_helpers import Instance

G = 9.81
THICKNESS = 5e-4
GROUND = -0.0025
WEIGHT = 800 * THICKNESS * 0.1 * 0.1 * G  # N


def vec(inst, prefix):
    return inst.get([inst.vr[f"{prefix}.{c}"] for c in "xyz"])


def test_a_sheet_dropped_on_the_ground_rests_on_it_with_its_weight(unzipped):
    """Stepped at 10 ms for 0.5 s (no inputs): the sheet falls, lands and
    comes to rest; no vertex ever comes within half the thickness of the
    ground, at rest every vertex is half the thickness above it within the
    barrier width (a tenth of it), and the ground's force output is the
    weight pressing it down within 1e-3 relative, its moment about the
    plane's point (0, 0, -2.5 mm) the weight's at the square's centre."""
    inst = Instance(unzipped("ground"), "drop").initialize()
    try:
        zs = [inst.vr[f"vertex[{i}].z"] for i in range(4)]
        for _ in range(50):
            inst.step(0.01)
            height = np.array(inst.get(zs)) - GROUND
            assert np.all(height > THICKNESS / 2), height
        assert np.all(height - THICKNESS / 2 < 0.1 * THICKNESS / 2), height
        force = vec(inst, "ground.force")
        assert force == pytest.approx([0.0, 0.0, -WEIGHT], abs=1e-3 * WEIGHT)
        moment = vec(inst, "ground.moment")
        want = np.cross([0.05, 0.05, 0.0], [0.0, 0.0, -WEIGHT])
        assert moment == pytest.approx(want, abs=1e-3 * WEIGHT * 0.05)
        assert inst.get([inst.vr["energy.contact"]])[0] > 0.0
    finally:
        inst.close()


CONVEYOR = -0.00026  # the moving ground's plane in tests/fmpy/scenes/conveyor.json
MASS = 800 * THICKNESS * 0.1 * 0.1  # kg


def test_a_conveyor_with_input_derivatives_drags_the_sheet_to_its_speed(unzipped):
    """conveyor.json: the sheet rests on the moving ground (friction 0.3).
    The master moves the ground along x at V = 5 cm/s, setting ground.x =
    V t and its derivative V at every 2 ms communication point: after 60 ms
    (friction catches the sheet up in V / (mu g) = 17 ms) every vertex moves
    at V within 1 %, and of the ground's work on the sheet (energy.input_work,
    m V^2) half is dissipated and half is kinetic energy, within 3 %."""
    inst = Instance(unzipped("conveyor"), "belt").initialize()
    try:
        for _ in range(10):
            inst.step(0.01)
        w0, d0 = inst.get([inst.vr["energy.input_work"], inst.vr["energy.dissipated"]])
        xs = [inst.vr[f"vertex[{i}].x"] for i in range(4)]
        speed, h, t = 0.05, 0.002, 0.0
        x_prev = inst.get(xs)
        for _ in range(30):
            inst.step(h, inputs={"ground.x": speed * t}, slopes={"ground.x": speed})
            t += h
            x = inst.get(xs)
            v = (x - x_prev) / h
            x_prev = x
        assert v == pytest.approx([speed] * 4, rel=1e-2)
        w, d, k = inst.get(
            [inst.vr[n] for n in ("energy.input_work", "energy.dissipated", "energy.kinetic")]
        )
        mv2 = MASS * speed**2
        assert w - w0 == pytest.approx(mv2, rel=3e-2)
        assert d - d0 == pytest.approx(0.5 * mv2, rel=6e-2)
        assert k == pytest.approx(0.5 * mv2, rel=6e-2)
    finally:
        inst.close()


def test_a_plain_master_lifts_the_sheet_with_held_inputs(unzipped):
    """A master without input derivatives raises the ground 10 um per 10 ms
    (held inputs: the ground steps up at each communication point, within
    the barrier's reach): no vertex ever comes within half the thickness of
    the ground, and the sheet rides it up carrying its weight. A jump of 2
    mm into the sheet is refused (doStep fails, the log names the obstacle),
    and the instance goes on from a state saved before it."""
    inst = Instance(unzipped("conveyor"), "lift").initialize()
    try:
        zs = [inst.vr[f"vertex[{i}].z"] for i in range(4)]
        for _ in range(10):
            inst.step(0.01)
        for k in range(1, 21):
            ground = CONVEYOR + 1e-5 * k
            inst.step(0.01, inputs={"ground.z": ground})
            assert np.all(inst.get(zs) - ground > THICKNESS / 2)
        assert np.all(inst.get(zs) - ground < THICKNESS / 2 + 5e-5)
        force = vec(inst, "ground.force")
        assert force[2] == pytest.approx(-WEIGHT, rel=2e-2)
        before = inst.get(zs)
        saved = inst.slave.getFMUstate()
        with pytest.raises(FMICallException):
            inst.step(0.01, inputs={"ground.z": ground + 0.002})
        assert "obstacle ground" in inst.log.messages()[-1]
        # FMI 2.0: a failed step is left through a saved state.
        inst.slave.setFMUstate(saved)
        inst.slave.freeFMUstate(saved)
        inst.step(0.01, inputs={"ground.z": ground})
        assert inst.get(zs) == pytest.approx(before, abs=1e-5)
    finally:
        inst.close()
