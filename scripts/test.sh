#!/usr/bin/env bash
# The test command: builds everything (release: the numerics are slow
# unoptimized), runs the cargo tests, sets up the Python venv with fmpy and
# runs the fmpy suite. Works on a fresh machine with only rustup and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== cargo build --release"
cargo build --release --locked 2>&1 | tail -n 3
echo "== cargo test --release"
cargo test --release --locked
echo "== python venv"
PY=$(bash scripts/setup_venv.sh)
echo "== fmpy suite (pytest)"
set +e
"$PY" -m pytest tests/fmpy -q
rc=$?
set -e
if [ "$rc" -eq 5 ]; then echo "pytest: no fmpy tests collected"; rc=0; fi
exit "$rc"
