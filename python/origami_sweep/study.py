"""The study file (TOML or JSON): what to build or load, what to sweep, how to
drive each run and what to keep. `load_study` checks it and names the key at
fault; `Study.runs()` lists every combination as one run description."""

from __future__ import annotations

import itertools
import json
import math
import pathlib
import tomllib
from dataclasses import dataclass, field

import numpy as np

SCENE_PREFIX = "scene."
METRIC_KINDS = ("max", "min", "final", "first_time", "fold_time", "angle_error")


class StudyError(ValueError):
    """A study file that cannot be run; the message names the key at fault."""


@dataclass(frozen=True)
class Signal:
    """A piecewise-linear input signal, held at its last value after the
    last time (and at its first value before the first)."""

    times: tuple
    values: tuple

    def at(self, t: float) -> float:
        return float(np.interp(t, self.times, self.values))

    def to_dict(self):
        return {"times": list(self.times), "values": list(self.values)}


@dataclass
class Study:
    """A checked study. `source` is {"fmu": path}, {"scene": path} or
    {"pattern": name, "args": {...}}; `sweep` maps each swept name to its
    values (names starting with "scene." are arguments of the pattern
    generator, the others FMU parameters set as start values)."""

    name: str
    path: pathlib.Path
    source: dict
    sweep: dict
    parameters: dict
    stop_time: float
    step: float
    time_limit: float
    input_derivatives: bool
    outputs: list
    inputs: dict
    metrics: dict
    plot: dict
    whatif: dict | None = None
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def steps(self) -> int:
        return round(self.stop_time / self.step)

    @property
    def scene_level(self) -> bool:
        return any(k.startswith(SCENE_PREFIX) for k in self.sweep)

    def combinations(self):
        """Every combination of the swept values (the first key varies
        slowest), as dicts name -> value."""
        names = list(self.sweep)
        for values in itertools.product(*(self.sweep[n] for n in names)):
            yield dict(zip(names, values))

    def runs(self):
        """One description per run: the swept values, the pattern arguments
        and FMU start values they give, and the what-if branch (or None)."""
        out = []
        branches = list(self.whatif["branches"]) if self.whatif else [None]
        for case, combo in enumerate(self.combinations()):
            scene_args = dict(self.source.get("args", {}))
            start_values = dict(self.parameters)
            for k, v in combo.items():
                if k.startswith(SCENE_PREFIX):
                    scene_args[k[len(SCENE_PREFIX):]] = v
                else:
                    start_values[k] = v
            for branch in branches:
                out.append(
                    {
                        "run": len(out),
                        "case": case,
                        "values": combo,
                        "scene_args": scene_args,
                        "start_values": start_values,
                        "branch": branch,
                    }
                )
        return out

    def signals_of(self, branch):
        """The input signals of a run: the study's inputs, and after the
        what-if time those of its branch (None: the study's inputs only)."""
        if branch is None:
            return self.inputs, None
        b = self.whatif["branches"][branch]
        return self.inputs, {**self.inputs, **b}


def load_study(path) -> Study:
    """Read and check a study file (.toml or .json)."""
    path = pathlib.Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise StudyError(f"{path}: cannot read the study file ({e.strerror})") from None
    try:
        if path.suffix == ".json":
            raw = json.loads(text)
        else:
            raw = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as e:
        raise StudyError(f"{path}: not valid {path.suffix[1:].upper() or 'TOML'}: {e}") from None
    return parse_study(raw, path)


def parse_study(raw: dict, path: pathlib.Path) -> Study:
    """Check a study given as a dict (as read from its file at `path`, which
    relative paths are taken against)."""
    where = str(path)

    def fail(key, why):
        raise StudyError(f"{where}: {key}: {why}")

    known = {"name", "scene", "sweep", "parameters", "run", "inputs", "metrics", "plot", "whatif"}
    for k in raw:
        if k not in known:
            fail(k, f"unknown key (known: {', '.join(sorted(known))})")

    base = path.parent
    scene = raw.get("scene")
    if not isinstance(scene, dict):
        fail("scene", "missing: give scene.fmu, scene.file or scene.pattern")
    given = [k for k in ("fmu", "file", "pattern") if k in scene]
    if len(given) != 1:
        fail("scene", "give exactly one of fmu, file, pattern")
    for k in scene:
        if k not in ("fmu", "file", "pattern", "args"):
            fail(f"scene.{k}", "unknown key (known: fmu, file, pattern, args)")
    if "pattern" in scene:
        args = scene.get("args", {})
        if not isinstance(args, dict):
            fail("scene.args", "must be a table of generator options")
        source = {"pattern": str(scene["pattern"]), "args": args}
    else:
        if "args" in scene:
            fail("scene.args", "only with scene.pattern")
        kind = given[0]
        p = pathlib.Path(scene[kind])
        source = {"fmu" if kind == "fmu" else "scene": str(p if p.is_absolute() else base / p)}

    sweep = {}
    for name, spec in (raw.get("sweep") or {}).items():
        sweep[name] = _values(spec, f"sweep.{name}", fail)
        if name.startswith(SCENE_PREFIX) and "pattern" not in source:
            fail(f"sweep.{name}", "scene.* values need scene.pattern (the FMU is built per value)")
    if not sweep:
        fail("sweep", "missing or empty: name at least one parameter and its values")

    parameters = {}
    for name, v in (raw.get("parameters") or {}).items():
        if not _is_number(v):
            fail(f"parameters.{name}", "must be a number")
        if name in sweep:
            fail(f"parameters.{name}", "also swept; give it in one place")
        parameters[name] = float(v)

    run = raw.get("run") or {}
    run_keys = ("stop_time", "step", "time_limit", "outputs", "input_derivatives")
    for k in run:
        if k not in run_keys:
            fail(f"run.{k}", f"unknown key (known: {', '.join(run_keys)})")
    stop_time = _positive(run, "run", "stop_time", None, fail)
    step = _positive(run, "run", "step", None, fail)
    if abs(stop_time / step - round(stop_time / step)) > 1e-9 * stop_time / step:
        fail("run.step", f"must divide run.stop_time ({stop_time}) into whole steps")
    time_limit = _positive(run, "run", "time_limit", 600.0, fail)
    input_derivatives = run.get("input_derivatives", False)
    if not isinstance(input_derivatives, bool):
        fail("run.input_derivatives", "must be true or false")
    outputs = run.get("outputs", [])
    if not isinstance(outputs, list) or not all(isinstance(o, str) for o in outputs):
        fail("run.outputs", "must be a list of output names")

    inputs = {n: _signal(s, f"inputs.{n}", fail) for n, s in (raw.get("inputs") or {}).items()}

    metrics = {}
    for name, m in (raw.get("metrics") or {}).items():
        key = f"metrics.{name}"
        if not isinstance(m, dict) or m.get("kind") not in METRIC_KINDS:
            fail(key, f"needs kind = one of {', '.join(METRIC_KINDS)}")
        kind = m["kind"]
        if kind in ("max", "min", "final", "first_time") and not isinstance(m.get("output"), str):
            fail(f"{key}.output", f"kind {kind} needs the name of an output")
        if kind == "first_time" and not _is_number(m.get("threshold")):
            fail(f"{key}.threshold", "kind first_time needs a number")
        if kind == "fold_time":
            frac = m.get("fraction", 0.9)
            if not _is_number(frac) or not 0 < frac <= 1:
                fail(f"{key}.fraction", "must be in (0, 1]")
        metrics[name] = dict(m)

    plot = raw.get("plot") or {}
    plot_metrics = plot.get("metrics", list(metrics)[:2])
    if isinstance(plot_metrics, str):
        plot_metrics = [plot_metrics]
    for m in plot_metrics:
        if m not in metrics:
            fail("plot.metrics", f"'{m}' is not a metric of this study")
    x = plot.get("x", next(iter(sweep)))
    if x not in sweep:
        fail("plot.x", f"'{x}' is not a swept name")
    plot = {"metrics": plot_metrics, "x": x, "xlabel": str(plot.get("xlabel", x))}

    whatif = raw.get("whatif")
    if whatif is not None:
        at = _positive(whatif, "whatif", "at", None, fail)
        k_at = at / step
        if abs(k_at - round(k_at)) > 1e-9 * k_at or not 0 < round(k_at) < round(stop_time / step):
            fail("whatif.at", "must be a whole number of steps, after 0 and before run.stop_time")
        branches = {}
        for bname, b in (whatif.get("branches") or {}).items():
            if not isinstance(b, dict):
                fail(f"whatif.branches.{bname}", "must be a table of input signals")
            branches[bname] = {n: _signal(s, f"whatif.branches.{bname}.{n}", fail) for n, s in b.items()}
        if not branches:
            fail("whatif.branches", "missing or empty: name at least one branch")
        whatif = {"at": at, "branches": branches}

    return Study(
        name=str(raw.get("name", path.stem)),
        path=path,
        source=source,
        sweep=sweep,
        parameters=parameters,
        stop_time=stop_time,
        step=step,
        time_limit=time_limit,
        input_derivatives=input_derivatives,
        outputs=outputs,
        inputs=inputs,
        metrics=metrics,
        plot=plot,
        whatif=whatif,
        raw=raw,
    )


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _positive(table, prefix, key, default, fail):
    v = table.get(key, default)
    if v is None:
        fail(f"{prefix}.{key}", "missing")
    if not _is_number(v) or not math.isfinite(v) or v <= 0:
        fail(f"{prefix}.{key}", f"must be a positive number, got {v!r}")
    return float(v)


def _values(spec, key, fail):
    """A list of values, or a range {start, stop, num[, log]}."""
    if isinstance(spec, list):
        if not spec:
            fail(key, "empty list of values")
        return list(spec)
    if isinstance(spec, dict):
        unknown = set(spec) - {"start", "stop", "num", "log"}
        if unknown:
            fail(key, f"unknown range key {sorted(unknown)[0]} (known: start, stop, num, log)")
        if not all(_is_number(spec.get(k)) for k in ("start", "stop")):
            fail(key, "a range needs numbers start and stop")
        num = spec.get("num")
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            fail(key, "a range needs num, a whole number >= 1")
        if spec.get("log"):
            if spec["start"] <= 0 or spec["stop"] <= 0:
                fail(key, "a log range needs positive start and stop")
            return [float(v) for v in np.geomspace(spec["start"], spec["stop"], num)]
        return [float(v) for v in np.linspace(spec["start"], spec["stop"], num)]
    fail(key, "must be a list of values or a range {start, stop, num}")


def _signal(spec, key, fail):
    """A constant, or {times = [...], values = [...]} with increasing times."""
    if _is_number(spec):
        return Signal((0.0,), (float(spec),))
    if not isinstance(spec, dict) or set(spec) != {"times", "values"}:
        fail(key, "must be a number or {times = [...], values = [...]}")
    t, v = spec["times"], spec["values"]
    if not (isinstance(t, list) and isinstance(v, list) and len(t) == len(v) >= 1):
        fail(key, "times and values must be lists of the same, non-zero length")
    if not all(_is_number(x) and math.isfinite(x) for x in t):
        fail(f"{key}.times", "must be finite numbers")
    if not all(_is_number(x) for x in v):
        fail(f"{key}.values", "must be numbers")
    if any(b <= a for a, b in zip(t, t[1:])):
        fail(f"{key}.times", "must increase")
    return Signal(tuple(float(x) for x in t), tuple(float(x) for x in v))
