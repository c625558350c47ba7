"""FMUs of a study, built through the origami-fmu CLI: a given FMU as it is,
a scene file through `origami-fmu build`, and a generated pattern (one FMU
per combination of its arguments) through `origami-fmu pattern KIND --ARG
VALUE ... -o X.fold` and `origami-fmu build X.fold -o X.fmu`."""

from __future__ import annotations

import os
import pathlib
import re
import shutil
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]


class BuildError(RuntimeError):
    """The CLI refused a scene; the message carries its reason."""


def cli() -> str:
    """The CLI: $ORIGAMI_FMU, the release build of this checkout, or
    origami-fmu on PATH."""
    if os.environ.get("ORIGAMI_FMU"):
        return os.environ["ORIGAMI_FMU"]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    exe = target / "release" / "origami-fmu"
    if exe.is_file():
        return str(exe)
    found = shutil.which("origami-fmu")
    if found:
        return found
    raise BuildError(f"origami-fmu not found: run `cargo build --release` (looked for {exe}) or set ORIGAMI_FMU")


def _run(args):
    r = subprocess.run([cli(), *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise BuildError(f"origami-fmu {' '.join(args)}: {r.stderr.strip() or r.stdout.strip()}")


def scene_key(pattern: str, args: dict) -> str:
    """A file name for a pattern and its arguments (sorted, so the same
    scene always gets the same name)."""
    parts = [pattern] + [f"{k}-{v}" for k, v in sorted(args.items())]
    return re.sub(r"[^A-Za-z0-9_.+-]", "_", "_".join(parts))


def pattern_fmu(pattern: str, args: dict, out_dir) -> pathlib.Path:
    """Generate the pattern with `args` as CLI options and build its FMU."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    key = scene_key(pattern, args)
    fold, fmu = out_dir / f"{key}.fold", out_dir / f"{key}.fmu"
    flags = []
    for k, v in args.items():
        flags += [f"--{k.replace('_', '-')}", str(v)]
    _run(["pattern", pattern, *flags, "-o", str(fold)])
    _run(["build", str(fold), "-o", str(fmu)])
    return fmu


def scene_fmu(scene, out_dir) -> pathlib.Path:
    """Build the FMU of a scene file (.fold or scene .json)."""
    scene = pathlib.Path(scene)
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{scene.stem}.fmu"
    _run(["build", str(scene), "-o", str(fmu)])
    return fmu
