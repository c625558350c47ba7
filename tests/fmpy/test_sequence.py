"""Folding in sequence through the masters and out as FOLD: the same
`ancf:sequence` run by fmpy's simulate_fmu (held inputs), fmi-sim and the
CLI (input slopes) ends in the same state; the motion `simulate --fold-out`
writes reads in the FOLD format's own JavaScript library and in Rabbit Ear
(installed by scripts/setup_node.sh), every frame intact, its last frame's
fold angles the FMU's outputs."""

import csv
import json
import math
import os
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu

from fmu_helpers import ROOT, SCENES, Instance, build, cli
from test_second_client import fmi_sim

SCENE = SCENES / "sequence_strip.fold"
SIZE = 0.09  # the strip's longest side, m


@pytest.fixture(scope="module")
def strip_fmu(tmp_path_factory):
    out = tmp_path_factory.mktemp("sequence") / "sequence_strip.fmu"
    r = build(SCENE, out)
    assert r.returncode == 0, r.stderr
    return out


def positions(names, row):
    """The vertex positions (n x 3) from outputs `names` and values `row`."""
    idx = {n: i for i, n in enumerate(names)}
    n = sum(1 for x in names if x.startswith("vertex[") and x.endswith(".x"))
    return np.array([[row[idx[f"vertex[{v}].{c}"]] for c in "xyz"] for v in range(n)])


def test_the_sequence_ends_in_the_same_state_through_every_master(strip_fmu, tmp_path):
    """fold ramps 0 -> 1 over 1 s and holds to 1.5 s: simulate_fmu hands the
    FMU one held sample per 10 ms step, fmi-sim the table's value at each
    step, the CLI the table with its slopes. All end within 1e-4 of the
    sheet size of each other (the folds settle under the automatic
    damping)."""
    md = read_model_description(str(strip_fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    signal = np.array([(0.0, 0.0), (1.0, 1.0), (1.5, 1.0)], dtype=[("time", float), ("fold", float)])
    res = simulate_fmu(str(strip_fmu), stop_time=1.5, output_interval=0.01, input=signal, output=outputs)
    assert res["time"][-1] == pytest.approx(1.5)
    assert res["sequence.stage"][-1] == 1.0 and res["sequence.progress"][-1] == 1.0
    # Halfway the valley is folded and the mountain not yet.
    half = np.searchsorted(res["time"], 0.5)
    assert math.degrees(res["crease[8].angle"][half]) > 80
    assert abs(math.degrees(res["crease[9].angle"][half])) < 2
    finals = {"fmpy": positions(outputs, [res[n][-1] for n in outputs])}

    table = tmp_path / "input.csv"
    table.write_text("time,fold\n0.0,0.0\n1.0,1.0\n1.5,1.0\n")
    out = tmp_path / "cli.csv"
    r = subprocess.run([str(cli()), "simulate", str(SCENE), "--input", str(table), "--stop-time", "1.5",
                        "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    finals["cli"] = positions(rows[0][1:], [float(x) for x in rows[-1][1:]])

    if fmi_sim() is not None:
        result = tmp_path / "fmi_sim.csv"
        r = subprocess.run([fmi_sim(), "--model", str(strip_fmu), "-i", str(table), "-o", str(result),
                            "co-simulation", "-s", "0", "-f", "1.5", "--output-interval", "0.01"],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        with open(result, newline="") as f:
            rows = list(csv.reader(f))
        finals["fmi-sim"] = positions(rows[0], [float(x) for x in rows[-1]])
    names = list(finals)
    for a in names:
        for b in names:
            gap = np.abs(finals[a] - finals[b]).max()
            assert gap < 1e-4 * SIZE, f"{a} and {b} end {gap:.3e} m apart"
    if fmi_sim() is None:
        pytest.skip("fmi-sim is not installed (scripts/setup_fmi_sim.sh); fmpy and the CLI agree")


def node_modules():
    """The JavaScript FOLD readers (scripts/setup_node.sh), or skip where
    Node.js is missing or npm cannot install them; under the test command
    (ORIGAMI_REQUIRE_NODE=1, after it ran setup_node.sh) fail instead."""
    missing = pytest.fail if os.environ.get("ORIGAMI_REQUIRE_NODE") == "1" else pytest.skip
    if shutil.which("node") is None or shutil.which("npm") is None:
        missing("Node.js (node and npm) is not installed")
    r = subprocess.run(["bash", str(ROOT / "scripts" / "setup_node.sh")], capture_output=True, text=True)
    if r.returncode != 0:
        missing(f"npm could not install fold and rabbit-ear: {r.stderr.strip()[-300:]}")
    return r.stdout.strip()


def test_the_motion_reads_in_fold_and_rabbit_ear_and_ends_at_the_fmus_outputs(strip_fmu, tmp_path):
    """`simulate --fold-out` with the built-in ramp (1 s) to 1.5 s: 151
    frames. The FOLD library and Rabbit Ear read every frame with the
    crease pattern's vertices, edges and faces and finite fold angles whose
    signs Rabbit Ear reads as their M/V letters; the last frame's angles are
    the FMU's crease outputs after the same run (ramp.time = 1, 150 steps of
    10 ms) within 1e-9 rad, its vertices the FMU's positions within 1e-9
    of the sheet; this project reads the file back as 151 stages."""
    motion = tmp_path / "motion.fold"
    r = subprocess.run([str(cli()), "simulate", str(SCENE), "--ramp", "1", "--stop-time", "1.5",
                        "--fold-out", str(motion)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "motion: 151 frames" in r.stderr

    modules = node_modules()
    r = subprocess.run(["node", str(ROOT / "tests" / "node" / "check_fold.js"), str(motion)],
                       capture_output=True, text=True, env={"NODE_PATH": modules, "PATH": os.environ["PATH"]})
    assert r.returncode == 0, r.stderr
    read = json.loads(r.stdout)
    assert read["frames"] == 151 and read["vertices"] == 8 and read["edges"] == 10 and read["faces"] == 3
    assert read["assignment_checked"] > 0 and read["assignment_agree"] == read["assignment_checked"]

    unzipdir = extract(str(strip_fmu), str(tmp_path / "unzipped"))
    inst = Instance(unzipdir).initialize({"ramp.time": 1.0})
    try:
        for _ in range(150):
            inst.step(0.01)
        names = [inst.md.modelVariables[vr].name for vr in inst.outputs]
        values = dict(zip(names, inst.get()))
    finally:
        inst.close()
    for e in (8, 9):
        got = math.radians(read["last_angles"][e])
        assert abs(got - values[f"crease[{e}].angle"]) < 1e-9, e
    for v, p in enumerate(read["last_coords"]):
        for c, x in zip("xyz", p):
            assert abs(x - values[f"vertex[{v}].{c}"]) < 1e-9 * SIZE

    r = subprocess.run([str(cli()), "check", str(motion)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "frames 1-151 read as a folding sequence" in r.stdout
