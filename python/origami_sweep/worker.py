"""What a Dask worker runs: one FMU run in a subprocess that is killed at
the study's time limit (so a hung run never hangs the study), and its row.

The FMU travels as bytes (a cluster's workers need not share a disk); each
worker machine unpacks it once into its temporary folder. The subprocess is
`python -m origami_sweep.worker SPEC RESULT` (JSON files; floats round-trip
exactly through Python's JSON)."""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import zipfile

from . import master, metrics

CACHE = pathlib.Path(tempfile.gettempdir()) / "origami_sweep_fmus"


def unpack(fmu_bytes: bytes, cache_dir=CACHE) -> str:
    """Extract an FMU given as bytes once per machine, into a folder named by
    its content hash (atomic rename: concurrent workers do not race)."""
    digest = hashlib.sha256(fmu_bytes).hexdigest()[:24]
    target = pathlib.Path(cache_dir) / digest
    if not (target / "modelDescription.xml").is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = pathlib.Path(tempfile.mkdtemp(dir=target.parent, prefix=digest + "."))
        (tmp / "x.fmu").write_bytes(fmu_bytes)
        with zipfile.ZipFile(tmp / "x.fmu") as z:
            z.extractall(tmp / "fmu")
        try:
            (tmp / "fmu").rename(target)
        except OSError:  # another worker was first
            pass
        shutil.rmtree(tmp, ignore_errors=True)
    return str(target)


def drive_isolated(unzipdir: str, spec: dict, time_limit: float | None):
    """master.drive in a subprocess, killed after `time_limit` seconds (None:
    in this process, without a limit). A killed or crashed subprocess is a
    result with status "timeout" or "crashed"."""
    if time_limit is None:
        return master.drive(unzipdir, spec)
    with tempfile.TemporaryDirectory(prefix="origami_sweep_run.") as tmp:
        spec_file, result_file = pathlib.Path(tmp, "spec.json"), pathlib.Path(tmp, "result.json")
        spec_file.write_text(json.dumps({"unzipdir": unzipdir, "spec": spec}))
        env = dict(os.environ)
        package_parent = str(pathlib.Path(__file__).resolve().parent.parent)
        env["PYTHONPATH"] = os.pathsep.join([package_parent] + [p for p in [env.get("PYTHONPATH")] if p])
        proc = subprocess.Popen(
            [sys.executable, "-m", "origami_sweep.worker", str(spec_file), str(result_file)],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        try:
            _, err = proc.communicate(timeout=time_limit)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            return {
                "status": "timeout",
                "reason": f"stopped at the time limit of {time_limit:g} s (process {proc.pid} killed)",
                "times": [],
                "series": [],
                "state": None,
                "t_end": None,
            }
        if proc.returncode != 0 or not result_file.is_file():
            tail = err.decode(errors="replace").strip().splitlines()[-3:]
            return {
                "status": "crashed",
                "reason": f"run process exited with code {proc.returncode}: " + " | ".join(tail),
                "times": [],
                "series": [],
                "state": None,
                "t_end": None,
            }
        return json.loads(result_file.read_text())


def run_task(task: dict, fmu_bytes: bytes, base: dict | None = None, isolate: bool = True):
    """One run of a study (built by execute.plan): drive the FMU, then make
    its row. For a what-if branch, `base` is the base run's result: the run
    continues from its saved state, and the row is computed on the base's
    series followed by the continuation's. Returns {"row", "times",
    "series", "record"}, or for a base run (task["base"]) the raw result."""
    started = time.perf_counter()
    unzipdir = unpack(fmu_bytes)
    limit = task["time_limit"] if isolate else None
    spec = dict(task["drive"])
    if base is not None:
        if base["status"] != "ok":
            result = {**base, "reason": "what-if base run: " + base["reason"]}
        else:
            spec["state"] = base["state"]
            result = drive_isolated(unzipdir, spec, limit)
            # The continuation's first row is the restored state at t_k0.
            result["times"] = base["times"][:-1] + result["times"]
            result["series"] = base["series"][:-1] + result["series"]
    else:
        result = drive_isolated(unzipdir, spec, limit)
    if task.get("base"):
        return result
    row = make_row(task, result)
    row["wall_s"] = time.perf_counter() - started
    return {"row": row, "times": result["times"], "series": result["series"], "record": spec["record"]}


def failed_task(task):
    """The result of a task that could not run (task["failed"] says why)."""
    row = make_row(task, task["failed"])
    row["wall_s"] = float("nan")
    return {"row": row, "times": [], "series": [], "record": task["drive"]["record"]}


def make_row(task, result):
    """The table row of a run: its swept values, status and reason, the time
    reached, the metrics (NaN unless the run completed) and final outputs."""
    row = {"run": task["run"], "case": task["case"]}
    if task.get("branch") is not None:
        row["branch"] = task["branch"]
    row.update(task["values"])
    row["status"] = result["status"]
    row["reason"] = result["reason"]
    row["t_end"] = result["t_end"] if result["t_end"] is not None else float("nan")
    row["cpu_s"] = result.get("cpu_s", float("nan"))
    record = task["drive"]["record"]
    ok = result["status"] == "ok"
    if ok:
        columns = {n: [r[i] for r in result["series"]] for i, n in enumerate(record)}
        row.update(metrics.compute(task["metrics"], result["times"], columns, task["targets"], task["final_inputs"]))
    else:
        row.update({m: float("nan") for m in task["metrics"]})
    last = result["series"][-1] if ok else None
    for o in task["outputs"]:
        row[f"final:{o}"] = last[record.index(o)] if ok else float("nan")
    return row


def _child(spec_file, result_file):
    job = json.loads(pathlib.Path(spec_file).read_text())
    result = master.drive(job["unzipdir"], job["spec"])
    tmp = pathlib.Path(str(result_file) + ".part")
    tmp.write_text(json.dumps(result))
    tmp.rename(result_file)


if __name__ == "__main__":
    _child(sys.argv[1], sys.argv[2])
