"""A multibody master coupled to the origami FMU: a payload on an origami
spring under gravity, stepped with fmpy's FMU2Slave.

The spring: examples/payload_spring.fold, a creased 50 x 25 mm strip of
2 mm plastic, clamped at x = 0; its other end is held by the attachment
`mount` (inputs mount.x/y/z/rx/ry/rz, outputs mount.force.* and
mount.moment.*, the wrench the sheet exerts on the mount). The payload: a
rigid body of mass M (50 times the strip's) on a vertical guide, fixed to
the mount, under gravity g (the strip's own weight, 2 % of the payload's,
is left out of the scene, so the flat strip is at rest).

Coupling (force-displacement, explicit, one FMU call per communication step
h): the master owns the payload's motion and sends the FMU the mount's
path over the step, z_k + v_k s + a_k s^2 / 2 (mount.z with its first and
second derivatives, fmi2SetRealInputDerivatives); the FMU returns the force
F_{k+1} the sheet exerts on the mount at t_{k+1}; the payload's velocity is
then completed with it, velocity Verlet:

    a_k = F_k / M - g,  z_{k+1} = z_k + v_k h + a_k h^2 / 2,
    v_{k+1} = v_k + (a_k + a_{k+1}) h / 2.

Stable for omega h < 2 (omega the loop's frequency) when the payload is
heavier than the part of the sheet that moves with it: F_{k+1} carries the
inertia of the held part at the acceleration a_k the master sent, a step
late (the added-mass effect): an error in the acceleration comes back
multiplied by about -m_added / M each step, so the loop diverges, whatever
h, once the sheet's added mass exceeds the payload's (measured: M = 2 m
diverges, 5 m runs; docs/fmu.md).

Steps:
1. The FMU's own static force-displacement curve: a damped instance (the
   scene's automatic damping) holds the mount at heights z and reads the
   settled force F(z); z_eq where F = M g, the tangent stiffness k there.
   Predicted frequency f = sqrt(k / M) / (2 pi).
2. The coupled run, undamped (damping.alpha = damping.beta = 0): the master
   lowers the payload smoothly to z_eq + A (held on its path, 0.3 s) and
   lets go; it oscillates about z_eq. Measured: the frequency (zero
   crossings) and the energy balance of the coupled system,
   1/2 M v^2 + M g z + the sheet's kinetic, strain and crease energy,
   against the oscillation's energy 1/2 k A^2.

    python examples/coupled_payload.py --out out

writes out/coupled_payload.csv and out/coupled_payload.png; builds the FMU
with the CLI first when it is missing. Prints the predicted and measured
frequency and the energy balance.
"""

import argparse
import csv
import math
import pathlib
import shutil
import subprocess
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "payload_spring.fold"
G = 9.81
# The strip's mass: density * thickness * area (kg).
SHEET_MASS = 1200 * 2e-3 * 0.05 * 0.025


def build_fmu(fmu: pathlib.Path) -> None:
    cli = ROOT / "target" / "release" / "origami-fmu"
    subprocess.run([str(cli), "build", str(SCENE), "-o", str(fmu)], check=True)


class Spring:
    """One FMU instance of the spring; the mount moves along z only."""

    def __init__(self, unzipdir, md, name, undamped=False):
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.s = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                           modelIdentifier=md.coSimulation.modelIdentifier,
                           instanceName=name)
        self.s.instantiate()
        self.s.setupExperiment(startTime=0.0)
        self.s.enterInitializationMode()
        if undamped:
            self.s.setReal([self.vr["damping.alpha"], self.vr["damping.beta"]], [0.0, 0.0])
        self.s.exitInitializationMode()
        self.z0 = self.s.getReal([self.vr["mount.z"]])[0]
        self.t = 0.0

    def step(self, h, z, v=0.0, a=0.0):
        """Mount at z with velocity v and acceleration a at the step's start;
        returns the force the sheet exerts on the mount at its end (z)."""
        vz = self.vr["mount.z"]
        self.s.setReal([vz], [self.z0 + z])
        self.s.setRealInputDerivatives([vz, vz], [1, 2], [v, a])
        self.s.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h
        return self.s.getReal([self.vr["mount.force.z"]])[0]

    def energy(self):
        return sum(self.s.getReal([self.vr[f"energy.{e}"] for e in ("kinetic", "strain", "crease")]))

    def close(self):
        self.s.terminate()
        self.s.freeInstance()


def smooth_path(z0, z1, t, T):
    """Smoothstep from z0 to z1 over T: position, velocity, acceleration."""
    x = min(max(t / T, 0.0), 1.0)
    d = z1 - z0
    p = z0 + d * x * x * (3 - 2 * x)
    v = d * 6 * x * (1 - x) / T if x < 1 else 0.0
    a = d * (6 - 12 * x) / T**2 if x < 1 else 0.0
    return p, v, a


def static_force(unzipdir, md, heights, h=1e-3, move=0.1, settle=0.4):
    """The settled force F(z) (N, the sheet on the mount) at each height z,
    in one damped instance: moved there smoothly, held until settled."""
    sp = Spring(unzipdir, md, "static")
    out = []
    try:
        z_prev = 0.0
        for z in heights:
            n_move, n_hold = int(round(move / h)), int(round(settle / h))
            for i in range(n_move):
                p, v, a = smooth_path(z_prev, z, i * h, move)
                sp.step(h, p, v, a)
            f = None
            for _ in range(n_hold):
                f = sp.step(h, z)
            out.append(f)
            z_prev = z
    finally:
        sp.close()
    return np.array(out)


def run(fmu, mass_ratio=50.0, h=5e-4, amplitude=2e-5, place=0.3, free=0.5):
    unzipdir = extract(str(fmu))
    md = read_model_description(unzipdir)
    M = mass_ratio * SHEET_MASS
    try:
        # 1. The static curve near the payload's weight.
        coarse = np.linspace(0.0, -1e-3, 5)
        f = static_force(unzipdir, md, coarse)
        k0 = -np.polyfit(coarse, f, 1)[0]
        z_eq = np.interp(M * G, f, coarse) if f[-1] >= M * G else -M * G / k0
        local = z_eq + amplitude * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
        f_local = static_force(unzipdir, md, local)
        fit = np.polyfit(local - z_eq, f_local, 2)
        k = -fit[1]
        z_eq += (fit[2] - M * G) / k
        f_pred = math.sqrt(k / M) / (2 * math.pi)

        # 2. The coupled run: placed at z_eq + A, then let go.
        sp = Spring(unzipdir, md, "coupled", undamped=True)
        rows = []
        try:
            z1 = z_eq + amplitude
            n_place = int(round(place / h))
            force = 0.0
            for i in range(n_place):
                p, v, a = smooth_path(0.0, z1, i * h, place)
                force = sp.step(h, p, v, a)
            z, v = z1, 0.0
            acc = force / M - G
            t0 = sp.t
            for _ in range(int(round(free / h))):
                e_sheet = sp.energy()
                rows.append((sp.t - t0, z, v, force, e_sheet))
                force = sp.step(h, z, v, acc)
                z += v * h + 0.5 * acc * h * h
                new = force / M - G
                v += 0.5 * (acc + new) * h
                acc = new
            rows.append((sp.t - t0, z, v, force, sp.energy()))
        finally:
            sp.close()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
    rows = np.array(rows)
    t, z, v, F, es = rows.T
    # Frequency: mean period between upward zero crossings of z - z_eq.
    y = z - z_eq
    up = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
          for i in range(len(y) - 1) if y[i] < 0 <= y[i + 1]]
    f_meas = (len(up) - 1) / (up[-1] - up[0])
    energy = 0.5 * M * v**2 + M * G * z + es
    e_osc = 0.5 * k * amplitude**2
    drift = np.max(np.abs(energy - energy[0])) / e_osc
    return dict(rows=rows, M=M, k=k, z_eq=z_eq, f_pred=f_pred, f_meas=f_meas,
                energy=energy, e_osc=e_osc, drift=drift, h=h,
                curve=(np.concatenate([coarse, local]), np.concatenate([f, f_local])))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "out" / "payload_spring.fmu"))
    ap.add_argument("--out", default=str(ROOT / "out"))
    ap.add_argument("--step", type=float, default=5e-4, help="communication step (s)")
    ap.add_argument("--mass-ratio", type=float, default=50.0, help="payload mass / strip mass")
    ap.add_argument("--free-time", type=float, default=0.5, help="s of free oscillation")
    a = ap.parse_args(argv)
    fmu = pathlib.Path(a.fmu)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if not fmu.exists():
        fmu.parent.mkdir(parents=True, exist_ok=True)
        build_fmu(fmu)
    r = run(fmu, mass_ratio=a.mass_ratio, h=a.step, free=a.free_time)
    t, z, v, F, es = r["rows"].T
    with open(out / "coupled_payload.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time", "z", "velocity", "mount_force_z", "sheet_energy", "total_energy"])
        for row, e in zip(r["rows"], r["energy"]):
            w.writerow([f"{x:.12g}" for x in (*row, e)])
    err = r["f_meas"] / r["f_pred"] - 1
    print(f"payload M = {r['M']:.4g} kg, static stiffness k = {r['k']:.5g} N/m at "
          f"z_eq = {r['z_eq'] * 1e3:.4f} mm; frequency predicted {r['f_pred']:.4f} Hz, "
          f"measured {r['f_meas']:.4f} Hz ({err:+.2%}); energy balance: largest "
          f"|E - E0| = {r['drift']:.2%} of the oscillation's energy (h = {r['h']:g} s)")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(3, 1, figsize=(7, 7))
        zc, fc = r["curve"]
        order = np.argsort(zc)
        ax[0].plot(zc[order] * 1e3, fc[order], "o-", ms=3, label="settled force F(z)")
        ax[0].axhline(r["M"] * G, color="k", lw=0.8, ls="--", label="payload weight M g")
        ax[0].set_xlabel("mount z (mm)")
        ax[0].set_ylabel("force on mount (N)")
        ax[0].legend(loc="upper right")
        ax[0].set_title("static force-displacement curve of the FMU")
        ax[1].plot(t, (z - r["z_eq"]) * 1e6)
        ax[1].set_ylabel("z - z_eq (um)")
        ax[1].set_title(f"coupled: predicted {r['f_pred']:.3f} Hz, measured {r['f_meas']:.3f} Hz")
        ax[2].plot(t, (r["energy"] - r["energy"][0]) / r["e_osc"] * 100)
        ax[2].set_ylabel("E - E0 (% of 1/2 k A^2)")
        ax[2].set_xlabel("time after release (s)")
        fig.tight_layout()
        fig.savefig(out / "coupled_payload.png", dpi=100)
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
