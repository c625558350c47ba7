"""Helpers shared by the fmpy suite: find the CLI, build FMUs, open
instances with a capturing logger, and drive them step by step."""

import os
import pathlib
import subprocess
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))

# An FMI logger that records (status, category, message) tuples.
from origami_sweep.master import FmiLog as LogCapture  # noqa: E402

SCENES = ROOT / "tests" / "fmpy" / "scenes"
SHIPPED = ROOT / "scenes"
# Test scenes (scene JSON) and the shipped example scenes (FOLD).
EXAMPLES = sorted(p.stem for p in SCENES.glob("*.json")) + sorted(
    p.stem for p in SHIPPED.glob("*.fold"))


def scene_path(name: str) -> pathlib.Path:
    """The scene file of an example: tests/fmpy/scenes/NAME.json or scenes/NAME.fold."""
    p = SCENES / f"{name}.json"
    return p if p.exists() else SHIPPED / f"{name}.fold"


def cli() -> pathlib.Path:
    """The release CLI as `cargo build --release` leaves it."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    exe = target / "release" / "origami-fmu"
    if not exe.is_file():
        raise RuntimeError(f"{exe} is missing: run `cargo build --release` first")
    return exe


def build(scene: pathlib.Path, out: pathlib.Path) -> subprocess.CompletedProcess:
    """`origami-fmu build SCENE -o OUT` (not checked: callers look at it)."""
    return subprocess.run(
        [str(cli()), "build", str(scene), "-o", str(out)],
        capture_output=True,
        text=True,
    )


class Instance:
    """One FMU2Slave with its model description, value references and log."""

    def __init__(self, unzipdir, name="instance", logging_on=False):
        self.md = read_model_description(unzipdir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.by_causality = {}
        for v in self.md.modelVariables:
            self.by_causality.setdefault(v.causality, []).append(v.valueReference)
        self.log = LogCapture()
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.slave.instantiate(callbacks=self.log.callbacks, loggingOn=logging_on)
        self.time = 0.0

    @property
    def inputs(self):
        return self.by_causality.get("input", [])

    @property
    def outputs(self):
        return self.by_causality.get("output", [])

    def initialize(self, start_values=None, start_time=0.0):
        self.slave.setupExperiment(startTime=start_time)
        self.slave.enterInitializationMode()
        for name, value in (start_values or {}).items():
            self.slave.setReal([self.vr[name]], [value])
        self.slave.exitInitializationMode()
        self.time = start_time
        return self

    def step(self, h, inputs=None, slopes=None):
        """Set `inputs` (name -> value, in force from now and held over the
        step, FMI 2.0) and `slopes` (name -> first derivative over the
        step, fmi2SetRealInputDerivatives), then step."""
        for name, value in (inputs or {}).items():
            self.slave.setReal([self.vr[name]], [value])
        for name, slope in (slopes or {}).items():
            self.slave.setRealInputDerivatives([self.vr[name]], [1], [slope])
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def get(self, vrs=None):
        vrs = self.outputs if vrs is None else vrs
        return np.array(self.slave.getReal(list(vrs)))

    def close(self):
        try:
            self.slave.terminate()
        except Exception:
            pass
        self.slave.freeInstance()


def unzip(fmu, where) -> str:
    return extract(str(fmu), unzipdir=str(where))


def run_ramp(inst, steps, ramp_time=1.0, input_name=None):
    """Drive the first input from 0 to 1 linearly over `ramp_time` through the
    given communication steps: each step gets the ramp's value at its start
    and the slope that reaches the ramp's value at its end (so the input is
    the ramp itself wherever the steps do not straddle its end); return the
    output rows after each step."""
    name = input_name or inst.md.modelVariables[inst.inputs[0]].name
    rows = []
    for h in steps:
        u0 = min(inst.time / ramp_time, 1.0)
        u1 = min((inst.time + h) / ramp_time, 1.0)
        inst.step(h, {name: u0}, {name: (u1 - u0) / h})
        rows.append(inst.get())
    return np.array(rows)
