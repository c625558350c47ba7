"""`pip install .` gives the Python commands: origami-sweep and
origami-simulate-fmu, importable from the installed package (not from the
checkout). Installed here with --no-deps into a target folder, so the test
takes seconds; a fresh venv with its dependencies is the same install."""

import os
import pathlib
import subprocess
import sys

import numpy as np

from fmu_helpers import cli

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_pip_install_gives_the_sweep_and_simulate_commands(tmp_path, fmu):
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--disable-pip-version-check",
                        "--target", str(target), str(ROOT)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    bin_dir = target / "bin"
    env = dict(os.environ, PYTHONPATH=str(target),
               PATH=f"{pathlib.Path(cli()).parent}{os.pathsep}{os.environ['PATH']}")
    for cmd in ["origami-sweep", "origami-simulate-fmu"]:
        r = subprocess.run([str(bin_dir / cmd), "--help"], capture_output=True, text=True,
                           env=env, cwd=tmp_path)
        assert r.returncode == 0 and "usage" in r.stdout, (cmd, r.stderr)
    # The helper runs from the installed package (fold_pictures beside it).
    csv = tmp_path / "out.csv"
    r = subprocess.run([str(bin_dir / "origami-simulate-fmu"), str(fmu("square")),
                        "--stop-time", "0.05", "--step", "0.01", "--ramp", "0.05",
                        "--csv", str(csv)], capture_output=True, text=True, env=env,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    data = np.genfromtxt(csv, delimiter=",", names=True)
    assert len(data) == 6
    # A one-run study through the installed sweep command.
    study = tmp_path / "s.toml"
    study.write_text(
        f'name = "one"\n[scene]\nfmu = "{fmu("square")}"\n'
        '[sweep]\n"solver.tolerance" = [1e-3]\n'
        '[run]\nstop_time = 0.02\nstep = 0.01\noutputs = ["energy.crease"]\n'
        '[inputs]\nfold = { times = [0.0, 0.02], values = [0.0, 1.0] }\n')
    r = subprocess.run([str(bin_dir / "origami-sweep"), str(study), "--serial", "--out",
                        str(tmp_path / "o")],
                       capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
