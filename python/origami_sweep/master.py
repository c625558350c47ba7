"""One run of an FMU driven step by step through fmpy's FMU2Slave: fixed
communication steps t_k = k h, inputs set to their signal's value at the
start of each step (and, if asked, its slope over the step), outputs read
after each step, and the FMU state saved
at the end or restored at the start (what-if branches).

A failure is a result: any exception of fmpy or of the FMU (an fmi2Discard,
fmi2Error or fmi2Fatal status, a failed instantiation) ends the run with its
status, the time reached and the FMU's logged reason."""

from __future__ import annotations

import base64
import ctypes
import json
import math
import time
import zipfile

import numpy as np
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)
from fmpy.logging import addLoggerProxy

STATUS = {1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}


class Variables:
    """Names, value references and causalities of an FMU's model description,
    with the checks a study needs (a wrong name is an error naming it)."""

    def __init__(self, md):
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.causality = {v.name: v.causality for v in md.modelVariables}

    @classmethod
    def of_fmu(cls, fmu):
        return cls(read_model_description(str(fmu)))

    def names(self, causality):
        return [n for n, c in self.causality.items() if c == causality]

    def check(self, names, causality, what):
        for n in names:
            if self.causality.get(n) != causality:
                known = self.names(causality)
                hint = ", ".join(known[:12]) + (" ..." if len(known) > 12 else "")
                article = "an" if causality[0] in "aeiou" else "a"
                raise KeyError(f"{what} '{n}' is not {article} {causality} of the FMU (its {causality}s: {hint})")


def crease_targets(fmu):
    """The rest-angle actuators' creases of an FMU's scene: a list of
    (output name, target angle in rad, actuator name), read from the scene
    the FMU carries (resources/scene.json)."""
    with zipfile.ZipFile(fmu) as z:
        scene = json.loads(z.read("resources/scene.json"))
    edges = scene["mesh"]["edges"]
    out = []
    for a in scene.get("actuators", []):
        if a.get("mode") != "RestAngle":
            continue
        for e in a["edges"]:
            edge = edges[e]
            if edge.get("fold_edge") is not None and edge.get("fold_target"):
                out.append((f"crease[{edge['fold_edge']}].angle", float(edge["fold_target"]), a["name"]))
    return out


class FmiLog:
    """An FMI logger keeping (status, category, message) of every call it
    sees (fmpy's proxy formats the C-variadic message first); its
    `callbacks` go to fmi2Instantiate."""

    def __init__(self):
        self.lines = []

        def log(env, instance, status, category, message):
            self.lines.append((int(status), category.decode(errors="replace"), message.decode(errors="replace")))

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(ctypes.byref(self.callbacks))

    def messages(self):
        return [m for _, _, m in self.lines]

    def reasons(self):
        """Messages of calls that returned warning or worse."""
        return [m for s, _, m in self.lines if s >= 1]


def _signal_values(segments, k, t):
    """Input values at time t of the signals in force for the step starting
    at t_k: the last segment whose first step is <= k (piecewise linear)."""
    chosen = segments[0][1]
    for k_from, sig in segments:
        if k_from <= k:
            chosen = sig
    return {n: float(np.interp(t, s["times"], s["values"])) for n, s in chosen.items()}


def drive(unzipdir, spec):
    """Run one FMU from `spec` and return a JSON-able result.

    spec: start_values {name: value}, segments [[k_from, {input: {times,
    values}}], ...], step h, k0, k1 (steps k0 .. k1-1 are taken), record
    [output names], state (base64 of a serialized FMU state to restore
    before step k0, or None), save_state (serialize the state after k1),
    input_derivatives (also set each input's slope over the step, so the
    FMU follows the straight line between the step's end values instead of
    holding the start value).
    The result has status ("ok", "discard", "error", "fatal"), reason,
    times, series (one row of the recorded outputs per time), state, t_end
    (the last time reached) and cpu_s (CPU seconds of this run)."""
    cpu_start = time.process_time()
    md = read_model_description(unzipdir)
    var = Variables(md)
    h, k0, k1 = spec["step"], spec["k0"], spec["k1"]
    record = spec["record"]
    vrs = [var.vr[n] for n in record]
    times, series = [], []
    result = {"status": "ok", "reason": "", "times": times, "series": series, "state": None}
    log = FmiLog()
    slave = None
    k = k0
    phase, doing = "instantiation", ""
    try:
        slave = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=spec.get("name", "run"),
        )
        slave.instantiate(callbacks=log.callbacks, loggingOn=False)
        _log_failures(slave, md)
        phase = "initialization"
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        for name, value in spec["start_values"].items():
            doing = f" while setting {name} = {float(value):g}"
            slave.setReal([var.vr[name]], [float(value)])
        doing = ""
        slave.exitInitializationMode()
        if spec.get("state"):
            phase = "state restore"
            blob = base64.b64decode(spec["state"])
            state = slave.deSerializeFMUstate(blob)
            slave.setFMUstate(state)
            slave.freeFMUstate(state)
        phase = "simulation"
        times.append(k0 * h)
        series.append(slave.getReal(vrs))
        for k in range(k0, k1):
            inputs = _signal_values(spec["segments"], k, k * h)
            for name, value in inputs.items():
                doing = f" while setting input {name} = {value:g}"
                slave.setReal([var.vr[name]], [value])
            if spec.get("input_derivatives"):
                ahead = _signal_values(spec["segments"], k, (k + 1) * h)
                for name, value in inputs.items():
                    slope = (ahead[name] - value) / h
                    doing = f" while setting the derivative of input {name} = {slope:g}"
                    slave.setRealInputDerivatives([var.vr[name]], [1], [slope])
            doing = ""
            slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            times.append((k + 1) * h)
            series.append(slave.getReal(vrs))
            if not all(math.isfinite(v) for v in series[-1]):
                raise FloatingPointError(f"non-finite output at t = {(k + 1) * h:g}")
        if spec.get("save_state"):
            state = slave.getFMUstate()
            result["state"] = base64.b64encode(slave.serializeFMUstate(state)).decode()
            slave.freeFMUstate(state)
    except FMICallException as e:
        result["status"] = STATUS.get(getattr(e, "status", 3), "error")
        result["reason"] = _reason(f"{e.function} returned {result['status']}{doing}", phase, k, h, log)
    except Exception as e:  # any failure is a row of the study, with its reason
        result["status"] = "error"
        result["reason"] = _reason(f"{type(e).__name__}: {e}{doing}", phase, k, h, log)
    finally:
        if slave is not None:
            _close(slave, instantiated=phase != "instantiation")
    result["t_end"] = times[-1] if times else None
    result["cpu_s"] = time.process_time() - cpu_start
    return result


def _log_failures(slave, md):
    """Ask the FMU to log its failures (the FMI 2.0 categories logStatus*,
    where it declares them; an FMU may log nothing with logging off)."""
    categories = [c.name for c in md.logCategories if c.name.startswith("logStatus")]
    if categories:
        try:
            slave.setDebugLogging(True, categories)
        except FMICallException:
            pass  # the reasons then come without the FMU's own words


def _reason(what, phase, k, h, log):
    where = f" at t = {k * h:g}" if phase == "simulation" else f" during {phase}"
    logged = log.reasons()
    return what + where + (": " + " | ".join(logged[-3:]) if logged else "")


def _close(slave, instantiated):
    if instantiated:
        try:
            slave.terminate()
        except Exception:
            pass
        try:
            slave.freeInstance()
        except Exception:
            pass
