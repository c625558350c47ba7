"""What a Dask worker runs: one FMU run in a subprocess that is killed at
the study's time limit (so a hung run never hangs the study), and its row.

The FMU travels as bytes (a cluster's workers need not share a disk); each
worker machine unpacks it once into its temporary folder. The subprocess is
`python -m origami_sweep.worker`, kept between runs, with JSON lines in and
out (floats round-trip exactly through Python's JSON)."""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import shutil
import select
import signal
import subprocess
import sys
import tempfile
import threading
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


def _no_result(status, reason):
    return {"status": status, "reason": reason, "times": [], "series": [], "state": None, "t_end": None}


class RunProcess:
    """A subprocess (`python -m origami_sweep.worker`) that runs specs one
    after the other: a JSON line in on its stdin, a JSON line out. It stays
    warm between runs (no interpreter start per run); a run over its time
    limit gets the process group killed (SIGKILL), and the next run starts a
    new process."""

    def __init__(self):
        self.proc = None
        self.stderr = None

    def _start(self):
        env = dict(os.environ)
        package_parent = str(pathlib.Path(__file__).resolve().parent.parent)
        env["PYTHONPATH"] = os.pathsep.join([package_parent] + [p for p in [env.get("PYTHONPATH")] if p])
        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "origami_sweep.worker"],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            start_new_session=True,
        )

    def _stop(self):
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.proc.wait()
        self.proc = None

    def _stderr_tail(self):
        self.stderr.seek(0)
        lines = self.stderr.read().decode(errors="replace").strip().splitlines()
        return " | ".join(lines[-3:])

    def run(self, unzipdir, spec, time_limit):
        if self.proc is None or self.proc.poll() is not None:
            self._start()
        deadline = time.monotonic() + time_limit
        try:
            self.proc.stdin.write((json.dumps({"unzipdir": unzipdir, "spec": spec}) + "\n").encode())
            self.proc.stdin.flush()
        except BrokenPipeError:
            pass  # it died: reading says how
        fd, buf = self.proc.stdout.fileno(), b""
        while not buf.endswith(b"\n"):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                pid = self.proc.pid
                self._stop()
                return _no_result("timeout", f"stopped at the time limit of {time_limit:g} s (process {pid} killed)")
            if not select.select([fd], [], [], remaining)[0]:
                continue
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                code = self.proc.wait()
                self.proc = None
                return _no_result("crashed", f"run process exited with code {code}: {self._stderr_tail()}")
            buf += chunk
        return json.loads(buf)


_local = threading.local()


def drive_isolated(unzipdir: str, spec: dict, time_limit: float | None):
    """master.drive in this thread's RunProcess, stopped after `time_limit`
    seconds (None: in this process, without a limit). A killed or crashed
    run is a result with status "timeout" or "crashed"."""
    if time_limit is None:
        return master.drive(unzipdir, spec)
    if not hasattr(_local, "runner"):
        _local.runner = RunProcess()
    return _local.runner.run(unzipdir, spec, time_limit)


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


def _serve():
    """The RunProcess side: one JSON job per stdin line, one JSON result per
    stdout line. Anything else written to stdout (by a library) goes to
    /dev/null, so it cannot garble the answers."""
    answers = os.fdopen(os.dup(1), "w")
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    for line in sys.stdin:
        job = json.loads(line)
        answers.write(json.dumps(master.drive(job["unzipdir"], job["spec"])) + "\n")
        answers.flush()


if __name__ == "__main__":
    _serve()
