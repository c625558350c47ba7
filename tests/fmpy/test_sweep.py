"""Parameter studies on Dask (python/origami_sweep): rows from a two-worker
LocalCluster and from a separately started scheduler and workers equal
serial runs bit for bit; failures and runs over the time limit are rows
with their reason; what-if branches continued from a saved state equal the
same branches run from the start."""

import json
import math
import os
import subprocess
import sys
import time

import pandas as pd
import pytest
from dask.distributed import Client

from fmu_helpers import ROOT  # also puts python/ (origami_sweep) on the path
from origami_sweep import execute
from origami_sweep.__main__ import main as sweep_main
from origami_sweep.study import StudyError, parse_study

TIMES = ("wall_s", "cpu_s")  # measured, so never equal between runs
FOLD = {"times": [0.0, 0.05], "values": [0.0, 1.0]}
METRICS = {
    "fold_time": {"kind": "fold_time", "fraction": 0.9},
    "peak_strain_energy": {"kind": "max", "output": "energy.strain"},
    "final_shape_error": {"kind": "angle_error"},
}


def make_study(tmp_path, scene, sweep, parameters=None, inputs=None, whatif=None, time_limit=60, stop=0.1,
               input_derivatives=False):
    """A short study (0.1 s in 10 ms steps, tolerance 1e-4 unless swept)."""
    params = {"solver.tolerance": 1e-4}
    params.update(parameters or {})
    for k in sweep:
        params.pop(k, None)
    raw = {
        "name": "t",
        "scene": scene,
        "sweep": sweep,
        "parameters": params,
        "run": {"stop_time": stop, "step": 0.01, "time_limit": time_limit,
                "outputs": ["energy.strain", "energy.kinetic"], "input_derivatives": input_derivatives},
        "inputs": {"fold": inputs or FOLD},
        "metrics": METRICS,
    }
    if whatif:
        raw["whatif"] = whatif
    path = tmp_path / "study.json"
    path.write_text(json.dumps(raw))
    return parse_study(raw, path)


def comparable(results):
    """Rows without their wall and CPU times, and the time series as
    bytes-exact floats: what must be identical between two ways of running
    a study."""
    out = []
    for r in results:
        row = {k: v for k, v in r["row"].items() if k not in TIMES}
        out.append((json.dumps(row, sort_keys=True), json.dumps(r["times"]), json.dumps(r["series"])))
    return out


@pytest.fixture(scope="module")
def client():
    """A two-worker LocalCluster, as the CLI starts by default."""
    c, cluster = execute.connect(workers=2)
    yield c
    c.close()
    cluster.close()


def test_local_cluster_rows_equal_serial_runs(tmp_path, client):
    # Scene level (one FMU per sector angle, built through the CLI) times a
    # parameter (start values): 4 runs.
    study = make_study(
        tmp_path,
        {"pattern": "single-crease", "args": {"width": 0.02, "length": 0.02}},
        {"scene.angle": [60.0, 120.0], "crease.length_scale": [0.01, 0.1]},
    )
    p = execute.plan(study, tmp_path / "out")
    assert len(p.fmus) == 2 and len(p.rows) == 4
    on_cluster = execute.run_dask(p, client)
    serial = execute.run_serial(p, isolate=False)
    assert comparable(on_cluster) == comparable(serial)
    rows = [r["row"] for r in serial]
    assert [r["status"] for r in rows] == ["ok"] * 4
    # The runs differ where they should: the angle and the crease stiffness
    # change the peak strain.
    peaks = [r["peak_strain_energy"] for r in rows]
    assert len(set(peaks)) == 4
    assert all(0.0 < r["fold_time"] < 0.1 for r in rows)


def test_study_on_a_separately_started_scheduler_and_workers(tmp_path, fmu):
    # Scheduler and workers as a cluster runs them: their own processes,
    # without this checkout on their path (the client uploads the package).
    study_file = tmp_path / "study.json"
    raw = {
        "name": "remote",
        "scene": {"fmu": str(fmu("square"))},
        "sweep": {"damping.alpha": [0.0, 10.0, 20.0]},
        "parameters": {"solver.tolerance": 1e-4},
        "run": {"stop_time": 0.1, "step": 0.01, "outputs": ["energy.strain"]},
        "inputs": {"fold": FOLD},
        "metrics": METRICS,
    }
    study_file.write_text(json.dumps(raw))
    sched_file = tmp_path / "scheduler.json"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    dask = [sys.executable, "-m", "dask"]
    procs = [subprocess.Popen(dask + ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                      "--scheduler-file", str(sched_file)],
                              cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.time() + 30
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(dask + ["worker", address, "--nworkers", "2", "--nthreads", "1",
                                              "--no-dashboard"],
                                      cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        with Client(address, timeout=30) as c:  # fail here, not hang, if the workers do not come
            c.wait_for_workers(2, timeout=60)
        assert sweep_main([str(study_file), "--scheduler", address, "-o", str(tmp_path / "out")]) == 0
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    df = pd.read_csv(tmp_path / "out" / "remote.csv", keep_default_na=False)
    assert (tmp_path / "out" / "remote.png").stat().st_size > 0
    p = execute.plan(parse_study(raw, study_file), tmp_path / "serial")
    serial = [r["row"] for r in execute.run_serial(p, isolate=False)]
    assert len(df) == 3
    for got, want in zip(df.to_dict("records"), serial):
        for k, v in want.items():
            if k not in TIMES:
                assert got[k] == v, k


def test_failing_runs_are_rows_with_their_reason(tmp_path, fmu, client):
    # A NaN start value is refused at initialization, a NaN input at the
    # first step; the runs around them go on.
    study = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"damping.alpha": [0.0, math.nan, 20.0]})
    p = execute.plan(study, tmp_path / "out")
    nan_input = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"damping.alpha": [0.0]},
                           inputs={"times": [0.0, 0.05], "values": [0.0, math.nan]})
    q = execute.plan(nan_input, tmp_path / "out")
    # A scene the generator refuses: its row says why; the other scene runs.
    bad_scene = make_study(tmp_path, {"pattern": "single-crease"}, {"scene.angle": [60.0, 200.0]})
    s = execute.plan(bad_scene, tmp_path / "out")
    # A step the FMU cannot finish (one internal step allowed, ten of at
    # most 1 ms needed).
    cut_short = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"solver.max_internal_steps": [1.0]},
                           parameters={"solver.max_step": 1e-3})
    d = execute.plan(cut_short, tmp_path / "out")
    rows = [r["row"] for plan in (p, q, s, d) for r in execute.run_dask(plan, client)]
    assert [r["status"] for r in rows[:6]] == ["ok", "error", "ok", "error", "ok", "error"]
    assert "building the scene failed" in rows[5]["reason"] and "200 must be in [-180, 180]" in rows[5]["reason"]
    assert rows[6]["status"] in ("discard", "error") and rows[6]["t_end"] == 0.0
    # The reason names the call and time, then gives the FMU's logged words.
    assert rows[6]["reason"].startswith(f"fmi2DoStep returned {rows[6]['status']} at t = 0: ")
    assert "max_internal_steps" in rows[6]["reason"]
    bad, bad_input = rows[1], rows[3]
    assert "fmi2SetReal returned error while setting damping.alpha = nan during initialization" in bad["reason"]
    assert math.isnan(bad["fold_time"]) and math.isnan(bad["t_end"])
    assert "fmi2SetReal returned error while setting input fold = nan at t = 0.01" in bad_input["reason"]
    assert bad_input["t_end"] == pytest.approx(0.01) and math.isnan(bad_input["peak_strain_energy"])


def test_a_run_over_its_time_limit_is_stopped_and_reported(tmp_path, fmu):
    # Tolerance 1e-9 with 10 us internal steps over 1 s takes about 30 s on
    # this machine; the limit stops it after 3 s.
    study = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"solver.max_step": [1e-5]},
                       parameters={"solver.tolerance": 1e-9}, time_limit=3.0, stop=1.0)
    p = execute.plan(study, tmp_path / "out")
    started = time.perf_counter()
    (r,) = execute.run_serial(p)
    assert time.perf_counter() - started < 15
    row = r["row"]
    assert row["status"] == "timeout"
    assert "time limit of 3 s" in row["reason"]
    pid = int(row["reason"].split("process ")[1].split(" ")[0])
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    assert math.isnan(row["fold_time"])


@pytest.mark.parametrize("input_derivatives", [False, True])
def test_whatif_branches_from_a_saved_state_equal_runs_from_the_start(tmp_path, fmu, client, input_derivatives):
    # Fold to half by 0.05 s, save the state, then three different futures
    # (inputs held over each step, or following the signal's slope).
    whatif = {"at": 0.05, "branches": {
        "hold": {"fold": 0.5},
        "unfold": {"fold": {"times": [0.05, 0.1], "values": [0.5, 0.0]}},
        "fold": {"fold": {"times": [0.05, 0.08], "values": [0.5, 1.0]}},
    }}
    study = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"damping.alpha": [0.0, 20.0]},
                       inputs={"times": [0.0, 0.05], "values": [0.0, 0.5]}, whatif=whatif,
                       input_derivatives=input_derivatives)
    restored = execute.plan(study, tmp_path / "a")
    assert len(restored.tasks) == 2 + 6 and len(restored.rows) == 6
    from_start = execute.plan(study, tmp_path / "b", whatif_from_start=True)
    assert len(from_start.tasks) == 6
    a = execute.run_dask(restored, client)
    b = execute.run_serial(from_start, isolate=False)
    assert comparable(a) == comparable(b)
    rows = [r["row"] for r in a]
    assert [r["branch"] for r in rows] == ["hold", "unfold", "fold"] * 2
    assert all(r["status"] == "ok" for r in rows)
    finals = [r["final:energy.strain"] for r in rows[:3]]
    assert len(set(finals)) == 3
    if input_derivatives:  # the slopes reach the FMU: not the held-input runs
        held = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"damping.alpha": [0.0]},
                          inputs={"times": [0.0, 0.05], "values": [0.0, 0.5]}, whatif=whatif)
        (h, *_) = execute.run_serial(execute.plan(held, tmp_path / "c"), isolate=False)
        assert h["series"][1:] != a[0]["series"][1:]


def test_study_file_errors_name_the_key(tmp_path, fmu):
    good = {"scene": {"fmu": "x.fmu"}, "sweep": {"damping.alpha": [0.0]},
            "run": {"stop_time": 0.1, "step": 0.01}, "inputs": {"fold": FOLD}, "metrics": METRICS}
    cases = [
        ({"sweep": {}}, "sweep: missing or empty"),
        ({"run": {"stop_time": 0.1, "step": 0.03}}, "run.step: must divide"),
        ({"run": {"stop_time": -1, "step": 0.01}}, "run.stop_time: must be a positive number"),
        ({"metrics": {"m": {"kind": "median"}}}, "metrics.m: needs kind"),
        ({"sweep": {"scene.angle": [1]}}, "sweep.scene.angle: scene.* values need scene.pattern"),
        ({"sweep": {"x": {"start": 0, "stop": 1}}}, "sweep.x: a range needs num"),
        ({"inputs": {"fold": {"times": [0, 0], "values": [0, 1]}}}, "inputs.fold.times: must increase"),
        ({"whatif": {"at": 0.2, "branches": {"a": {"fold": 1}}}}, "whatif.at: must be a whole number of steps"),
        ({"colour": 1}, "colour: unknown key"),
    ]
    for change, message in cases:
        with pytest.raises(StudyError, match=message.replace(".", r"\.").replace("*", r"\*")):
            parse_study({**good, **change}, tmp_path / "s.toml")
    study = parse_study({**good, "sweep": {"damping.alfa": [0.0]}, "scene": {"fmu": str(fmu("square"))}},
                        tmp_path / "s.toml")
    with pytest.raises(KeyError, match="'damping.alfa' is not a parameter of the FMU"):
        execute.plan(study, tmp_path / "out")
    assert parse_study({**good, "sweep": {"x": {"start": 1, "stop": 3, "num": 3}}}, tmp_path / "s").sweep["x"] \
        == [1.0, 2.0, 3.0]


def test_example_study_file_is_valid():
    from origami_sweep.study import load_study

    study = load_study(ROOT / "studies" / "miura_sector_angle.toml")
    assert study.scene_level and len(study.runs()) == 8


def test_a_run_process_that_dies_is_reported_and_replaced(tmp_path, fmu):
    # The run process dies (here: an exception outside the run's own error
    # handling, as a segfaulting FMU would): the result says so with the
    # last lines of its stderr, and the next run gets a new process.
    from origami_sweep import worker

    study = make_study(tmp_path, {"fmu": str(fmu("square"))}, {"damping.alpha": [0.0]})
    (task,) = execute.plan(study, tmp_path / "out").tasks
    dead = worker.drive_isolated(str(tmp_path / "no_such_fmu"), task["drive"], 30)
    assert dead["status"] == "crashed"
    assert "exited with code 1" in dead["reason"] and "no_such_fmu" in dead["reason"]
    p = execute.plan(study, tmp_path / "out")
    (r,) = execute.run_serial(p)
    assert r["row"]["status"] == "ok"
