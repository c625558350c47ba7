"""Plan a study's runs and run them: every run a Dask task on a LocalCluster
(workers = cores) or on a cluster's scheduler, or one after the other in
this process (serial). What-if branches: one base task per combination runs
to whatif.at and saves the FMU state; each branch task waits for it and
continues from the deserialized state in its own instance."""

from __future__ import annotations

import io
import os
import pathlib
import time
import zipfile

from . import master, metrics, scenes, worker


class Plan:
    """The FMUs of a study (name -> bytes) and its tasks (JSON-able dicts;
    a what-if branch names its base task in "after")."""

    def __init__(self, fmus, tasks):
        self.fmus = fmus
        self.tasks = tasks

    @property
    def rows(self):
        return [t for t in self.tasks if not t.get("base")]


def _segments(*parts):
    return [[k, {n: s.to_dict() for n, s in sig.items()}] for k, sig in parts]


def _check_fmu(study, run, fmu):
    """Check the study's names against an FMU (KeyError naming a wrong one);
    return its crease targets and the outputs a run records."""
    var = master.Variables.of_fmu(fmu)
    if study.input_derivatives and not var.md.coSimulation.canInterpolateInputs:
        raise KeyError(f"run.input_derivatives: the FMU {pathlib.Path(fmu).name} cannot interpolate inputs "
                       "(canInterpolateInputs is false)")
    var.check(run["start_values"], "parameter", "swept or set parameter")
    var.check(study.inputs, "input", "input")
    for b in (study.whatif or {}).get("branches", {}).values():
        var.check(b, "input", "what-if input")
    var.check(study.outputs, "output", "output")
    targets = master.crease_targets(fmu)
    record = list(dict.fromkeys(study.outputs + metrics.needed_outputs(study.metrics, targets)))
    var.check(record, "output", "metric output")
    return targets, record


def _given_fmu(path):
    p = pathlib.Path(path)
    if not zipfile.is_zipfile(p):
        raise scenes.BuildError(f"scene.fmu: {p} is not an FMU (missing or not a zip file)")
    return p


def plan(study, out_dir, time_limit=None, whatif_from_start=False) -> Plan:
    """Build the study's FMUs (one per scene) and describe every run. With
    whatif_from_start, each branch runs from t = 0 with the base inputs up
    to whatif.at and the branch's after it (no saved state: to check it)."""
    out_dir = pathlib.Path(out_dir)
    fmu_paths, build_errors = {}, {}

    def fmu_of(run):
        src = study.source
        if "fmu" in src:
            key, make = "fmu", lambda: _given_fmu(src["fmu"])
        elif "scene" in src:
            key, make = "scene", lambda: scenes.scene_fmu(src["scene"], out_dir / "fmus")
        else:
            args = run["scene_args"]
            key = scenes.scene_key(src["pattern"], args)
            make = lambda: scenes.pattern_fmu(src["pattern"], args, out_dir / "fmus")  # noqa: E731
        if key not in fmu_paths and key not in build_errors:
            try:
                fmu_paths[key] = make()
            except scenes.BuildError as e:
                if "pattern" not in src:
                    raise  # the study's one FMU: nothing can run
                build_errors[key] = str(e)  # one scene of a geometry sweep: its rows say why
        return key

    limit = study.time_limit if time_limit is None else time_limit
    n = study.steps
    tasks, checked = [], {}
    base_of_case = {}
    for run in study.runs():
        key = fmu_of(run)
        if key in build_errors:
            checked.setdefault(key, ([], list(study.outputs)))
        elif key not in checked:
            checked[key] = _check_fmu(study, run, fmu_paths[key])
        targets, record = checked[key]
        base_inputs, branch_inputs = study.signals_of(run["branch"])
        last = study.inputs if branch_inputs is None else branch_inputs
        common = {
            "case": run["case"],
            "values": run["values"],
            "fmu": key,
            "time_limit": limit,
            "metrics": study.metrics,
            "targets": targets,
            "outputs": study.outputs,
            "final_inputs": {n_: s.at((n - 1) * study.step) for n_, s in last.items()},
        }
        drive = {
            "name": f"run{run['run']}",
            "start_values": run["start_values"],
            "step": study.step,
            "k0": 0,
            "k1": n,
            "record": record,
            "save_state": False,
            "input_derivatives": study.input_derivatives,
        }
        task = {**common, "run": run["run"], "branch": run["branch"], "drive": drive}
        if key in build_errors:
            task["failed"] = {"status": "error", "reason": "building the scene failed: " + build_errors[key],
                              "times": [], "series": [], "t_end": None}
            drive["segments"] = []
        elif branch_inputs is None:
            drive["segments"] = _segments((0, base_inputs))
        else:
            k_at = round(study.whatif["at"] / study.step)
            if whatif_from_start:
                drive["segments"] = _segments((0, base_inputs), (k_at, branch_inputs))
            else:
                if run["case"] not in base_of_case:
                    base = {
                        **common,
                        "run": f"base{run['case']}",
                        "base": True,
                        "drive": {**drive, "name": f"base{run['case']}", "k1": k_at,
                                  "save_state": True, "segments": _segments((0, base_inputs))},
                    }
                    base_of_case[run["case"]] = base["run"]
                    tasks.append(base)
                drive.update(k0=k_at, segments=_segments((k_at, branch_inputs)))
                task["after"] = base_of_case[run["case"]]
        tasks.append(task)
    fmus = {k: pathlib.Path(p).read_bytes() for k, p in fmu_paths.items()}
    return Plan(fmus, tasks)


def run_serial(p: Plan, isolate=True, progress=None):
    """Every task in this process, one after the other (isolate: each run in
    its subprocess with the time limit, as on a worker)."""
    done, results = {}, []
    for task in p.tasks:
        base = done.get(task.get("after"))
        if "failed" in task:
            r = worker.failed_task(task)
        else:
            r = worker.run_task(task, p.fmus[task["fmu"]], base, isolate=isolate)
        if task.get("base"):
            done[task["run"]] = r
        else:
            results.append(r)
            if progress:
                progress(len(results), len(p.rows), r["row"])
    return sorted(results, key=lambda r: r["row"]["run"])


def package_zip() -> bytes:
    """This package as a zip, for client.upload_file: a cluster's workers
    import the task functions from it."""
    here = pathlib.Path(__file__).resolve().parent
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for f in sorted(here.glob("*.py")):
            z.write(f, f"origami_sweep/{f.name}")
    return buf.getvalue()


def connect(scheduler=None, workers=None):
    """A dask.distributed Client: of the scheduler at `scheduler`, or of a new
    LocalCluster with `workers` single-threaded worker processes (default:
    the machine's cores). Returns (client, cluster or None)."""
    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(
        n_workers=workers or os.cpu_count(),
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
    )
    return Client(cluster), cluster


def run_dask(p: Plan, client, progress=None):
    """Every task on the client's cluster; rows come back as runs finish. A
    task that fails on the worker (not a run's failure, which is already a
    row) still gives a row with the reason."""
    import tempfile

    from dask.distributed import as_completed

    with tempfile.TemporaryDirectory() as tmp:
        z = pathlib.Path(tmp, "origami_sweep.zip")
        z.write_bytes(package_zip())
        client.upload_file(str(z))
    fmu_futures = {k: client.scatter(b, hash=True) for k, b in p.fmus.items()}
    futures, by_future, results = {}, {}, []
    for task in p.tasks:
        if "failed" in task:
            results.append(worker.failed_task(task))
            continue
        args = [task, fmu_futures[task["fmu"]]]
        if task.get("after"):
            args.append(futures[task["after"]])
        f = client.submit(worker.run_task, *args, pure=False, key=f"origami-sweep-{task['run']}-{time.time_ns()}")
        futures[task["run"]] = f
        if not task.get("base"):
            by_future[f] = task
    total = len(results) + len(by_future)
    if progress:
        for i, r in enumerate(results):
            progress(i + 1, total, r["row"])
    for f in as_completed(list(by_future)):
        task = by_future[f]
        try:
            r = f.result()
        except Exception as e:  # the task, not the run, failed: still a row
            task = {**task, "failed": {"status": "error", "reason": f"task failed on the worker: "
                                       f"{type(e).__name__}: {e}", "times": [], "series": [], "t_end": None}}
            r = worker.failed_task(task)
        results.append(r)
        if progress:
            progress(len(results), total, r["row"])
    return sorted(results, key=lambda r: r["row"]["run"])
