"""Every command in the README's code blocks runs as written, so the README
cannot rot: shell blocks line by line (in order, in a scratch folder that
sees the repository's scenes/, studies/, scripts/ ...), then the Python
blocks. A command whose comment says `long:` or `needs a cluster` is only
checked: its program's `--help` (or `bash -n` for a script) must succeed.
origami-fmu comes from target/release, fmpy and the installed package's
commands (origami-sweep, origami-simulate-fmu) from a --no-deps install."""

import os
import pathlib
import re
import shlex
import subprocess
import sys

import numpy as np

from fmu_helpers import cli

ROOT = pathlib.Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
CHECK_ONLY = ("long:", "needs a cluster")


def code_blocks():
    """(language, text) of every fenced block, in order."""
    return re.findall(r"^```(\w*)\n(.*?)^```", README.read_text(), flags=re.M | re.S)


def shell_commands():
    """(command, check_only) of every line of the sh blocks (continuations joined)."""
    out = []
    for lang, text in code_blocks():
        if lang not in ("sh", "bash"):
            continue
        for line in text.replace("\\\n", " ").splitlines():
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            comment = line.split(" #", 1)[1] if " #" in line else ""
            out.append((line, any(m in comment for m in CHECK_ONLY)))
    return out


def check_command(line):
    """What a check-only line runs: `bash -n SCRIPT`, or the program (and
    its subcommand) with --help."""
    words = shlex.split(line, comments=True)
    if words[0] == "bash":
        return ["bash", "-n", words[1]]
    head = [words[0]]
    for w in words[1:]:
        if w.startswith("-") or "/" in w or "." in w:
            break
        head.append(w)
    return head + ["--help"]


def test_readme_lists_commands():
    cmds = shell_commands()
    assert len(cmds) >= 10
    assert any(c.startswith("origami-fmu simulate") for c, _ in cmds)
    assert sum(check for _, check in cmds) <= 6, "most commands must really run"


def test_every_readme_command_runs(tmp_path):
    site = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--disable-pip-version-check", "--target", str(site), str(ROOT)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    work = tmp_path / "work"
    work.mkdir()
    for d in ["scenes", "studies", "scripts", "tests", "examples", "docs"]:
        (work / d).symlink_to(ROOT / d)
    path = os.pathsep.join([str(pathlib.Path(cli()).parent), str(site / "bin"),
                            str(pathlib.Path(sys.executable).parent), os.environ["PATH"]])
    env = dict(os.environ, PATH=path, PYTHONPATH=str(site))
    for line, check_only in shell_commands():
        cmd = check_command(line) if check_only else ["bash", "-c", line]
        r = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, f"README command failed: {line}\n{r.stdout}\n{r.stderr}"
    for lang, text in code_blocks():
        if lang == "python":
            r = subprocess.run([sys.executable, "-c", text], cwd=work, env=env,
                               capture_output=True, text=True, timeout=600)
            assert r.returncode == 0, f"README Python block failed:\n{text}\n{r.stderr}"
    # What the quick start promises: pictures, and a sheet that folds.
    for f in ["miura.gif", "miura.png", "miura.fmu", "crease.png"]:
        assert (work / f).stat().st_size > 1000, f
    res = np.genfromtxt(work / "miura_ramp.csv", delimiter=",", names=True)
    angles = [n for n in res.dtype.names if n.startswith("crease")]
    assert max(abs(res[n][-1]) for n in angles) > 1.0, "the ramp.time FMU folded"
