"""Simulate an origami FMU with fmpy: ramp every actuator input from 0 to 1
over `--ramp` seconds, then hold; write every output to CSV and plot fold
angles and energies against time. Optionally also an animation of the
folding sheet (--gif, --mp4), a sheet of 3D snapshots (--snapshots) and a
ParaView series (--pvd); see fold_pictures.py."""
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
    sheet: about 45x the CPU on the 4x4 Miura fold, benches/cosim.rs.)
    Returns the outputs at every communication point as a structured array."""
    from fmpy import extract
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
    try:
        slave.instantiate()
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
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            row(k + 1, (k + 1) * dt)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("fmu")
    ap.add_argument("--stop-time", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=0.005, help="communication step (s)")
    ap.add_argument("--ramp", type=float, default=0.6, help="time to reach full actuation (s)")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--png", required=True)
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
    res = run_ramp(a.fmu, md, actuators, outputs, a.stop_time, a.step, a.ramp)
    names = res.dtype.names
    np.savetxt(a.csv, np.column_stack([res[n] for n in names]), delimiter=",",
               header=",".join(names), comments="")
    bad = [n for n in names if not np.all(np.isfinite(res[n]))]
    if bad:
        print("non-finite outputs:", bad[:5], file=sys.stderr)
        return 1

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
    fig.savefig(a.png, dpi=110)
    plt.close(fig)
    if a.gif or a.mp4 or a.snapshots or a.pvd:
        try:
            pictures(a, md, outputs, res)
        except ValueError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
    crease_cols = [n for n in names if n.startswith("crease[")]
    final = {n: float(np.degrees(res[n][-1])) for n in crease_cols}
    print(f"simulated {a.stop_time} s: {len(res)} rows, {len(outputs)} outputs -> {a.csv}, {a.png}")
    if final:
        vals = np.array(list(final.values()))
        print(f"final fold angles: min {vals.min():.1f} deg, max {vals.max():.1f} deg")
    return 0


def pictures(a, md, outputs, res):
    """The animation, snapshot sheet and ParaView series the flags ask for."""
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
