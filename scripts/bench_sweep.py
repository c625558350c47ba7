"""Speed-up of a study on Dask: the same runs serial in this process, serial
with the runs in a subprocess (what a worker does), and on
LocalClusters of 1 .. N worker processes. Prints a table (wall times
exclude building the FMUs, which happens once before, and starting the
cluster, which has its own column).

    .venv/bin/python scripts/bench_sweep.py [STUDY] [--workers 1,2] [--repeat 3]
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
    ap.add_argument("--repeat", type=int, default=3, help="rounds over the modes (the table keeps each one's fastest)")
    a = ap.parse_args()
    study = load_study(a.study)
    with tempfile.TemporaryDirectory() as tmp:
        p = execute.plan(study, tmp)
        modes = [("serial, in process", 0.0, lambda: execute.run_serial(p, isolate=False)),
                 ("serial, runs in a kept subprocess", 0.0, lambda: execute.run_serial(p))]
        clusters = []
        try:
            for n in [int(w) for w in a.workers.split(",")]:
                startup, (client, cluster) = timed(lambda: execute.connect(workers=n))
                clusters.append((client, cluster))
                modes.append((f"LocalCluster, {n} worker{'s' if n > 1 else ''}", startup,
                              lambda client=client: execute.run_dask(p, client)))
            load = os.getloadavg()[0]
            # Round robin, fastest of the repeats: the other users of a
            # shared machine weigh on every mode alike.
            best = {}
            for _ in range(a.repeat):
                for name, _, fn in modes:
                    t, results = timed(fn)
                    if name not in best or t < best[name][0]:
                        best[name] = (t, results)
        finally:
            for client, cluster in clusters:
                client.close()
                cluster.close()
        rows, reference = [], None
        for name, startup, _ in modes:
            wall, results = best[name]
            ok = sum(r["row"]["status"] == "ok" for r in results)
            run_s = sum(r["row"]["wall_s"] for r in results) / len(results)
            cpu_s = sum(r["row"]["cpu_s"] for r in results) / len(results)
            reference = reference or wall
            rows.append((name, len(results), ok, startup, wall, run_s, cpu_s, reference / wall))
        load_end = os.getloadavg()[0]
    print(f"study {study.name}: {len(p.rows)} runs, {os.cpu_count()} cores, "
          f"load average {load:.2f} at the start, {load_end:.2f} at the end")
    print("| mode | runs | ok | cluster start s | study wall s | wall s per run | CPU s per run | speed-up vs serial |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, n, ok, startup, wall, per_run, cpu, speedup in rows:
        print(f"| {name} | {n} | {ok} | {startup:.1f} | {wall:.1f} | {per_run:.2f} | {cpu:.2f} | {speedup:.2f} |")


if __name__ == "__main__":
    main()
