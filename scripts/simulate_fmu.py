#!/usr/bin/env python3
"""Simulate an origami FMU with fmpy as a co-simulation master: ramp every
actuator input from 0 to 1 over `--ramp` seconds, then hold. Writes any of:
every output to CSV (--csv), fold angles and energies against time (--png),
an animation of the folding sheet (--gif, --mp4), a sheet of 3D snapshots
(--snapshots) and a ParaView series (--pvd); see fold_pictures.py. A step the
FMU cannot finish (fmi2Discard) ends the run with its reason and exit code 1,
after writing what was simulated up to there."""
import argparse
import pathlib
import sys
import time

import numpy as np
import fmpy
from fmpy.model_description import read_model_description


def run_ramp(fmu, md, actuators, outputs, stop_time, dt, ramp):
    """Step the FMU as a co-simulation master with input derivatives does
    (fmpy's FMU2Slave): before each step from t, every actuator gets the
    ramp's value min(t / ramp, 1) and its slope over the step
    (fmi2SetRealInputDerivatives), so the FMU sees the continuous ramp.
    (fmpy 0.3.32's simulate_fmu cannot hand derivatives to this FMU, and
    without them a sampled ramp is a staircase whose every step rings the
    sheet: 17x the CPU on the 4x4 Miura fold at 10 ms steps, benches/cosim.rs.)
    Returns the outputs at every communication point as a structured array
    (up to a failed step) and the failure's reason (None when the run ends)."""
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave
    import shutil

    unzipdir = extract(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="main")
    n = int(round(stop_time / dt))
    res = np.zeros(n + 1, dtype=[("time", np.float64)] + [(o, np.float64) for o in outputs])
    out_vrs = [vr[o] for o in outputs]
    act_vrs = [vr[x] for x in actuators]
    messages = []

    def logger(_component, _instance, status, _category, message):
        if status >= 2:  # discard, error, fatal
            messages.append(message.decode("utf-8", "replace"))

    from fmpy.fmi2 import fmi2CallbackLoggerTYPE, fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, \
        fmi2CallbackFreeMemoryTYPE, calloc, free
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    failure = None
    try:
        slave.instantiate(callbacks=callbacks)
        slave.setupExperiment(startTime=0.0, stopTime=n * dt)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        row = lambda k, t: res.__setitem__(k, (t, *slave.getReal(out_vrs)))
        row(0, 0.0)
        for k in range(n):
            t, h = k * dt, dt
            u0, u1 = min(t / ramp, 1.0), min((t + h) / ramp, 1.0)
            if act_vrs:
                slave.setReal(act_vrs, [u0] * len(act_vrs))
                slave.setRealInputDerivatives(act_vrs, [1] * len(act_vrs),
                                              [(u1 - u0) / h] * len(act_vrs))
            try:
                slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            except FMICallException as e:
                reason = "; ".join(messages) or f"fmi2DoStep returned status {e.status}"
                failure = f"the step from t = {t:g} s failed: {reason}"
                res = res[: k + 1]
                break
            row(k + 1, (k + 1) * dt)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return res, failure


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("fmu")
    ap.add_argument("--stop-time", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=0.005, help="communication step (s)")
    ap.add_argument("--ramp", type=float, default=0.6, help="time to reach full actuation (s)")
    ap.add_argument("--csv", help="every output at every communication point (CSV)")
    ap.add_argument("--png", help="fold angles and energies against time (PNG)")
    ap.add_argument("--gif", help="animation of the fold (GIF)")
    ap.add_argument("--mp4", help="animation of the fold (MP4; skipped when no encoder is available)")
    ap.add_argument("--snapshots", help="PNG sheet of 3D views of the sheet at several times")
    ap.add_argument("--pvd", metavar="DIR",
                    help="ParaView series: DIR/<fmu name>.pvd and one .vtu per output time")
    a = ap.parse_args(argv)

    md = read_model_description(a.fmu)
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    actuators = [n for n in inputs if "." not in n]
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    res, failure = run_ramp(a.fmu, md, actuators, outputs, a.stop_time, a.step, a.ramp)
    names = res.dtype.names
    if a.csv:
        np.savetxt(a.csv, np.column_stack([res[n] for n in names]), delimiter=",",
                   header=",".join(names), comments="")
    bad = [n for n in names if not np.all(np.isfinite(res[n]))]
    if bad:
        print("non-finite outputs:", bad[:5], file=sys.stderr)
        return 1
    if a.png:
        plot(a.png, md, res)
    if a.gif or a.mp4 or a.snapshots or a.pvd:
        try:
            pictures(a, md, outputs, res)
        except ValueError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
    crease_cols = [n for n in names if n.startswith("crease[")]
    final = {n: float(np.degrees(res[n][-1])) for n in crease_cols}
    written = ", ".join(p for p in [a.csv, a.png] if p)
    print(f"simulated {res['time'][-1]:g} s: {len(res)} rows, {len(outputs)} outputs"
          + (f" -> {written}" if written else ""))
    if final:
        vals = np.array(list(final.values()))
        print(f"final fold angles: min {vals.min():.1f} deg, max {vals.max():.1f} deg")
    if failure:
        print(f"error: {failure}; outputs up to t = {res['time'][-1]:g} s are written",
              file=sys.stderr)
        return 1
    return 0


def plot(path, md, res):
    """Fold angles and energies against time."""
    names = res.dtype.names
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for n in [n for n in names if n.startswith("crease[")]:
        ax1.plot(res["time"], np.degrees(res[n]), lw=0.8)
    ax1.set_ylabel("fold angle (deg)")
    ax1.set_title(f"{md.modelName}: fold angles of all creases")
    for n in [n for n in names if n.startswith("energy.")]:
        ax2.plot(res["time"], res[n], label=n)
    ax2.set_yscale("symlog", linthresh=1e-9)
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("energy (J)")
    ax2.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def pictures(a, md, outputs, res):
    """The animation, snapshot sheet and ParaView series the flags ask for."""
    try:  # installed with the package (pip install .)
        from . import fold_pictures as fp
    except ImportError:  # run from scripts/
        import fold_pictures as fp

    started = time.perf_counter()
    sheet = fp.load_sheet(a.fmu, outputs)
    X = fp.positions(res, sheet.n_vertices)
    ang = fp.crease_angles(res, sheet)
    t = res["time"]
    title = md.modelName
    for path in [a.gif, a.mp4]:
        if not path:
            continue
        try:
            n = fp.write_animation(path, sheet, t, X, ang, title=title)
            print(f"animation: {n} frames -> {path}")
        except RuntimeError as e:
            print(f"animation {path} skipped: {e}")
    if a.snapshots:
        fp.write_snapshots(a.snapshots, sheet, t, X, ang, title=f"{title}: folding")
        print(f"snapshots -> {a.snapshots}")
    if a.pvd:
        pvd = fp.write_pvd(a.pvd, pathlib.Path(a.fmu).stem, sheet, t, X, ang)
        print(f"ParaView series: {len(t)} times -> {pvd}")
    print(f"pictures took {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    sys.exit(main())
