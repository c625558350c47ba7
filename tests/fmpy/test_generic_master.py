"""The FMU in a generic master (fmpy.simulate_fmu, no input signal): it
folds with the parameter ramp.time, the experiment's relative tolerance
reaches the solver, and a failed step is not silent."""

import json
import subprocess
import sys

import numpy as np
import fmpy
from fmpy.validation import validate_fmu

from fmu_helpers import build, cli, scene_path


def _angle(res):
    names = [n for n in res.dtype.names if n.startswith("crease[")]
    return np.degrees(np.array([res[n][-1] for n in names]))


def test_ramp_time_folds_the_sheet_without_a_signal(fmu):
    path = fmu("square")
    flat = fmpy.simulate_fmu(path, stop_time=0.2, output_interval=0.01)
    assert np.all(np.abs(_angle(flat)) < 1e-9), "nothing drives fold: flat"
    folded = fmpy.simulate_fmu(path, stop_time=0.2, output_interval=0.01,
                               start_values={"ramp.time": 0.1})
    target = 90.0  # the square scene's diagonal folds to 90 deg at fold = 1
    assert np.all(np.abs(np.abs(_angle(folded)) - target) < 5.0), _angle(folded)


def test_build_says_which_input_to_drive_and_ramp_builds_a_self_folding_fmu(tmp_path):
    fold = scene_path("square")
    r = build(fold, tmp_path / "a.fmu")
    assert r.returncode == 0, r.stderr
    assert "drive the input fold from 0 (flat) to 1" in r.stdout, r.stdout
    out = tmp_path / "b.fmu"
    r = subprocess.run([str(cli()), "build", str(fold), "-o", str(out), "--ramp", "0.1"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "folds by itself: fold go from 0 to 1 over 0.1 s" in r.stdout, r.stdout
    res = fmpy.simulate_fmu(str(out), stop_time=0.2, output_interval=0.01)
    assert np.all(np.abs(_angle(res)) > 80.0), _angle(res)


def test_relative_tolerance_reaches_the_solver_and_validates(fmu):
    path = fmu("square")
    assert validate_fmu(str(path)) == []
    kw = dict(stop_time=0.2, output_interval=0.01, start_values={"ramp.time": 0.1})
    default = fmpy.simulate_fmu(path, **kw)
    tight = fmpy.simulate_fmu(path, relative_tolerance=1e-7, **kw)
    again = fmpy.simulate_fmu(path, relative_tolerance=1e-7, **kw)
    diff = max(np.max(np.abs(default[n] - tight[n])) for n in default.dtype.names)
    assert diff > 1e-6, "the tolerance changed nothing"
    assert all(np.array_equal(tight[n], again[n]) for n in tight.dtype.names)


def test_a_failed_step_is_printed_by_a_plain_master(tmp_path):
    """fmpy ends a run at fmi2Discard with fmi2Terminated; the reason now
    reaches its default logger (printed as [DISCARD]) without debug logging."""
    scene = json.loads(scene_path("square").read_text())
    scene["solver"]["max_internal_steps"] = 1
    scene["solver"]["max_step"] = 1e-4
    src = tmp_path / "tight.json"
    src.write_text(json.dumps(scene))
    out = tmp_path / "tight.fmu"
    r = build(src, out)
    assert r.returncode == 0, r.stderr
    code = ("import fmpy; r = fmpy.simulate_fmu(%r, stop_time=0.1, output_interval=0.01, "
            "start_values={'ramp.time': 0.05}); print('rows', len(r))" % str(out))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "[DISCARD]" in p.stdout and "solver.max_internal_steps" in p.stdout, p.stdout
