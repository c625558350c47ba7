"""A study's results: one CSV row per run (floats written to round-trip
exactly), the series of each run on request, and a plot of the chosen
metrics against the first swept name (one line per combination of the
other swept names and per what-if branch; failed runs marked on the axis)."""

from __future__ import annotations

import math
import pathlib

import pandas as pd


def table(results) -> pd.DataFrame:
    return pd.DataFrame([r["row"] for r in results])


def write_csv(df: pd.DataFrame, path):
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False)
    return path


def write_series(results, folder):
    """One CSV per run: time and every recorded output."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for r in results:
        cols = {"time": r["times"]}
        for i, name in enumerate(r["record"]):
            cols[name] = [row[i] for row in r["series"]]
        pd.DataFrame(cols).to_csv(folder / f"run{r['row']['run']}.csv", index=False)


def plot(df: pd.DataFrame, study, path, title=None):
    """Each plot metric against plot.x; lines group the runs that share the
    other swept values (and branch). None (no file) for a study without
    metrics."""
    if not study.plot["metrics"]:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = study.plot["x"]
    names = study.plot["metrics"]
    others = [k for k in study.sweep if k != x] + (["branch"] if "branch" in df else [])
    fig, axes = plt.subplots(1, len(names), figsize=(4.6 * len(names), 3.6), squeeze=False)
    groups = df.groupby(others, sort=False) if others else [((), df)]
    for ax, m in zip(axes[0], names):
        for key, g in groups:
            key = key if isinstance(key, tuple) else (key,)
            label = ", ".join(f"{k}={v}" for k, v in zip(others, key)) or None
            ok = g[g["status"] == "ok"].sort_values(x)
            ax.plot(ok[x], ok[m], "o-", label=label)
        failed = df[df["status"] != "ok"]
        if len(failed):
            ax.plot(failed[x], [ax.get_ylim()[0]] * len(failed), "rx", label="failed")
        ax.set_xlabel(study.plot.get("xlabel", x))
        unit = study.metrics[m].get("unit")
        ax.set_ylabel(f"{m} ({unit})" if unit else m)
        ax.grid(alpha=0.3)
        if others or len(failed):
            ax.legend(fontsize=7)
    n_ok = int((df["status"] == "ok").sum())
    fig.suptitle(title or f"{study.name}: {n_ok} of {len(df)} runs completed", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def progress_line(done, total, row):
    """One line per finished run: its values, status and metrics."""
    vals = ", ".join(f"{k}={_fmt(v)}" for k, v in row.items() if k not in ("run", "case", "status", "reason")
                     and not k.startswith("final:") and k not in ("t_end", "wall_s", "cpu_s"))
    status = row["status"] + ("" if row["status"] == "ok" else f" ({row['reason'][:120]})")
    wall, cpu = row.get("wall_s", math.nan), row.get("cpu_s", math.nan)
    print(f"[{done}/{total}] run {row['run']}: {vals}: {status}, {wall:.1f} s ({cpu:.1f} s CPU)", flush=True)


def _fmt(v):
    return f"{v:.4g}" if isinstance(v, float) else str(v)
