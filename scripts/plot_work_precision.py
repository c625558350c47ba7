"""Plot the work-precision CSV of benches/work_precision.rs: error against
CPU time, log-log, one panel per case, one series per integrator."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    rows = list(csv.DictReader(open(csv_path)))
    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4.2))
    labels = {
        "crease": "single crease, position error / size",
        "cantilever": "cantilever, |first frequency error|",
        "miura": "Miura 2x2, position error / size",
    }
    for ax, case in zip(axes, cases):
        for method, marker in [
            ("generalized-alpha fixed step", "o-"),
            ("generalized-alpha adaptive", "s-"),
            ("central differences", "^"),
        ]:
            pts = [
                (float(r["cpu_s"]), abs(float(r["error"])))
                for r in rows
                if r["case"] == case and r["integrator"] == method
            ]
            if pts:
                x, y = zip(*sorted(pts))
                ax.loglog(x, y, marker, label=method)
        ax.set_title(labels.get(case, case))
        ax.set_xlabel("CPU time (s)")
        ax.set_ylabel("error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    print(f"wrote {png_path}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
