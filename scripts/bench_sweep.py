"""Speed-up of a study on Dask: the same runs serial in this process, serial
with each run in its own subprocess (what a worker does), and on
LocalClusters of 1 .. N worker processes. Prints a table (wall times
exclude building the FMUs, which happens once before, and starting the
cluster, which has its own column).

    .venv/bin/python scripts/bench_sweep.py [STUDY] [--workers 1,2] [--repeat 1]
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))

from origami_sweep import execute  # noqa: E402
from origami_sweep.study import load_study  # noqa: E402


def timed(fn):
    t = time.perf_counter()
    results = fn()
    return time.perf_counter() - t, results


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", nargs="?", default=str(ROOT / "studies" / "miura_sector_angle.toml"))
    ap.add_argument("--workers", default=f"1,{os.cpu_count()}", help="LocalCluster sizes (comma-separated)")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each mode (the table keeps the fastest)")
    a = ap.parse_args()
    study = load_study(a.study)
    with tempfile.TemporaryDirectory() as tmp:
        p = execute.plan(study, tmp)
        modes = [("serial, in process", lambda: execute.run_serial(p, isolate=False)),
                 ("serial, a subprocess per run", lambda: execute.run_serial(p))]
        for n in [int(w) for w in a.workers.split(",")]:
            modes.append((f"LocalCluster, {n} worker{'s' if n > 1 else ''}", n))
        load = os.getloadavg()[0]
        rows, reference = [], None
        for name, how in modes:
            startup, client, cluster = 0.0, None, None
            if isinstance(how, int):  # a cluster of `how` workers, started outside the timing
                startup, (client, cluster) = timed(lambda: execute.connect(workers=how))
                how = lambda: execute.run_dask(p, client)  # noqa: E731
            try:
                best, results = min((timed(how) for _ in range(a.repeat)), key=lambda x: x[0])
            finally:
                if client is not None:
                    client.close()
                    cluster.close()
            ok = sum(r["row"]["status"] == "ok" for r in results)
            run_s = sum(r["row"]["wall_s"] for r in results) / len(results)
            cpu_s = sum(r["row"]["cpu_s"] for r in results) / len(results)
            reference = reference or best
            rows.append((name, len(results), ok, startup, best, run_s, cpu_s, reference / best))
        load_end = os.getloadavg()[0]
    print(f"study {study.name}: {len(p.rows)} runs, {os.cpu_count()} cores, "
          f"load average {load:.2f} at the start, {load_end:.2f} at the end")
    print("| mode | runs | ok | cluster start s | study wall s | wall s per run | CPU s per run | speed-up vs serial |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, n, ok, startup, wall, per_run, cpu, speedup in rows:
        print(f"| {name} | {n} | {ok} | {startup:.1f} | {wall:.1f} | {per_run:.2f} | {cpu:.2f} | {speedup:.2f} |")


if __name__ == "__main__":
    main()
