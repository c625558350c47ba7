#!/usr/bin/env bash
# Work-precision report: error against CPU time for each integrator and step
# (benches/work_precision.rs), written to out/work_precision.csv and plotted
# to out/work_precision.png. Takes a few minutes; pass --quick for a smoke run.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p out
cargo bench --locked --bench work_precision -- --csv out/work_precision.csv "$@"
PY=$(bash scripts/setup_venv.sh)
"$PY" scripts/plot_work_precision.py out/work_precision.csv out/work_precision.png
