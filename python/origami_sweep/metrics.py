"""Derived values of one run, computed from its recorded time series.

Kinds (a study's [metrics] table):
- max, min, final: of one output over the run;
- first_time: first time an output reaches `threshold` (rising, or falling
  with `falling = true`), interpolated linearly between communication points;
- fold_time: first time the fold progress reaches `fraction` (default 0.9);
  the progress is the projection of the crease angles onto the scene's
  target angles, sum(theta theta*) / sum(theta*^2) over the rest-angle
  actuators' creases (1 = folded to the targets);
- angle_error: the final shape error, the RMS over those creases of the
  final angle minus the rest angle the actuator asks for at the end
  (u_end theta*), in rad.
A metric that is never reached is NaN."""

from __future__ import annotations

import math

import numpy as np


def needed_outputs(metrics, targets):
    """The outputs the metrics read (crease angles for fold_time and
    angle_error)."""
    names = []
    for m in metrics.values():
        if m["kind"] in ("fold_time", "angle_error"):
            if not targets:
                raise KeyError(f"metric kind {m['kind']} needs a scene with rest-angle actuators")
            names += [t[0] for t in targets]
        elif "output" in m:
            names.append(m["output"])
    return names


def first_crossing(times, values, threshold, falling=False):
    """First time `values` reaches `threshold`, linearly interpolated."""
    v = -np.asarray(values) if falling else np.asarray(values)
    c = -threshold if falling else threshold
    hit = np.nonzero(v >= c)[0]
    if len(hit) == 0:
        return math.nan
    i = hit[0]
    if i == 0:
        return float(times[0])
    t0, t1, v0, v1 = times[i - 1], times[i], v[i - 1], v[i]
    return float(t0 + (c - v0) / (v1 - v0) * (t1 - t0))


def compute(metrics, times, columns, targets, final_inputs):
    """metrics: name -> definition; columns: output name -> array over
    `times`; targets: (output, target, actuator) of the creases;
    final_inputs: input name -> its value over the last step."""
    out = {}
    times = np.asarray(times)
    for name, m in metrics.items():
        kind = m["kind"]
        if kind in ("max", "min", "final"):
            col = columns[m["output"]]
            out[name] = float({"max": np.max, "min": np.min, "final": lambda c: c[-1]}[kind](col))
        elif kind == "first_time":
            out[name] = first_crossing(times, columns[m["output"]], m["threshold"], m.get("falling", False))
        elif kind == "fold_time":
            theta = np.array([columns[o] for o, _, _ in targets])
            star = np.array([t for _, t, _ in targets])
            progress = star @ theta / (star @ star)
            out[name] = first_crossing(times, progress, m.get("fraction", 0.9))
        elif kind == "angle_error":
            err = [columns[o][-1] - final_inputs.get(a, 0.0) * t for o, t, a in targets]
            out[name] = float(np.sqrt(np.mean(np.square(err))))
    return out
