#!/usr/bin/env bash
# The main job: build the default Miura-ori FMU and fold it with fmpy.
# Writes out/miura.fold, out/miura.fmu, out/miura.csv, out/miura.png (angles and
# energies against time), out/miura.gif (an animation of the fold; also
# out/miura.mp4 where ffmpeg is installed) and out/miura_snapshots.png (3D views).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p out
echo "== cargo build --release"
cargo build --release --locked 2>&1 | tail -n 1
BIN=target/release/origami-fmu
"$BIN" pattern miura -o out/miura.fold
"$BIN" build out/miura.fold -o out/miura.fmu
PY=$(bash scripts/setup_venv.sh)
"$PY" scripts/simulate_fmu.py out/miura.fmu --stop-time 1.0 --step 0.005 --ramp 0.6 \
    --csv out/miura.csv --png out/miura.png \
    --gif out/miura.gif --mp4 out/miura.mp4 --snapshots out/miura_snapshots.png
