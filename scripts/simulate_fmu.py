"""Simulate an origami FMU with fmpy: ramp every actuator input from 0 to 1
over `--ramp` seconds, then hold; write every output to CSV and plot fold
angles and energies against time."""
import argparse
import sys

import numpy as np
import fmpy
from fmpy.model_description import read_model_description


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("fmu")
    ap.add_argument("--stop-time", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=0.005, help="communication step (s)")
    ap.add_argument("--ramp", type=float, default=0.6, help="time to reach full actuation (s)")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--png", required=True)
    a = ap.parse_args(argv)

    md = read_model_description(a.fmu)
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    actuators = [n for n in inputs if "." not in n]
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    t = np.array([0.0, a.ramp, max(a.stop_time, a.ramp)])
    sig = np.zeros(len(t), dtype=[("time", np.float64)] + [(n, np.float64) for n in actuators])
    sig["time"] = t
    for n in actuators:
        sig[n] = [0.0, 1.0, 1.0]
    res = fmpy.simulate_fmu(a.fmu, stop_time=a.stop_time, output_interval=a.step,
                            input=sig if actuators else None, output=outputs)
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
    crease_cols = [n for n in names if n.startswith("crease[")]
    final = {n: float(np.degrees(res[n][-1])) for n in crease_cols}
    print(f"simulated {a.stop_time} s: {len(res)} rows, {len(outputs)} outputs -> {a.csv}, {a.png}")
    if final:
        vals = np.array(list(final.values()))
        print(f"final fold angles: min {vals.min():.1f} deg, max {vals.max():.1f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
