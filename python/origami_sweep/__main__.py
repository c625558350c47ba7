"""python -m origami_sweep STUDY [options]: run a parameter study and write
OUT/<name>.csv and OUT/<name>.png (see --help)."""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

from . import execute, report
from .scenes import BuildError
from .study import StudyError, load_study


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="sweep",
        description="Run every combination of a study file's values as FMU runs on Dask "
        "and write one CSV row per run and a plot of its metrics.",
    )
    ap.add_argument("study", help="study file (.toml or .json)")
    ap.add_argument("-o", "--out", help="output folder (default: out/<study name>)")
    ap.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (e.g. tcp://host:8786) "
                    "instead of a LocalCluster")
    ap.add_argument("--workers", type=int, help="LocalCluster worker processes (default: the cores)")
    ap.add_argument("--serial", action="store_true", help="no Dask: the runs one after the other here")
    ap.add_argument("--time-limit", type=float, metavar="S", help="per-run limit in seconds (overrides run.time_limit)")
    ap.add_argument("--whatif-from-start", action="store_true",
                    help="run each what-if branch from t = 0 instead of from the saved state (a check)")
    ap.add_argument("--series", action="store_true", help="also write each run's time series to OUT/series/")
    a = ap.parse_args(argv)

    try:
        study = load_study(a.study)
        if a.time_limit is not None and not a.time_limit > 0:
            raise StudyError("--time-limit must be positive")
        out = pathlib.Path(a.out or pathlib.Path("out") / study.name)
        started = time.perf_counter()
        p = execute.plan(study, out, time_limit=a.time_limit, whatif_from_start=a.whatif_from_start)
    except (StudyError, BuildError, KeyError, OSError) as e:
        print(f"error: {e.args[0] if isinstance(e, KeyError) else e}", file=sys.stderr)
        return 2
    print(f"{study.name}: {len(p.rows)} runs ({len(p.tasks) - len(p.rows)} what-if bases), "
          f"{len(p.fmus)} FMU(s) in {out / 'fmus'}", flush=True)
    if a.serial:
        results = execute.run_serial(p, progress=report.progress_line)
    else:
        client, cluster = execute.connect(a.scheduler, a.workers)
        try:
            where = a.scheduler or f"LocalCluster of {len(client.scheduler_info()['workers'])} workers"
            print(f"on {where}", flush=True)
            results = execute.run_dask(p, client, progress=report.progress_line)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    df = report.table(results)
    csv = report.write_csv(df, out / f"{study.name}.csv")
    png = report.plot(df, study, out / f"{study.name}.png")
    if a.series:
        report.write_series(results, out / "series")
    n_ok = int((df["status"] == "ok").sum())
    wrote = f"{csv} and {png}" if png else f"{csv} (no metrics to plot)"
    print(f"{n_ok} of {len(df)} runs completed in {time.perf_counter() - started:.1f} s; wrote {wrote}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
