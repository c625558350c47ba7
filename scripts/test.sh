#!/usr/bin/env bash
# The test command: builds everything (release: the numerics are slow
# unoptimized), runs the cargo tests, sets up the Python venv with fmpy,
# installs fmi-sim (a second FMI client; once per machine, about 9 min) and
# runs the fmpy suite. Works on a fresh Debian machine with rustup, python3
# and apt-get (as root, for libclang-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== cargo build --release"
cargo build --release --locked 2>&1 | tail -n 3
echo "== cargo test --release"
cargo test --release --locked
echo "== python venv"
PY=$(bash scripts/setup_venv.sh)
echo "== fmi-sim (second FMI client)"
bash scripts/setup_fmi_sim.sh
echo "== fmpy suite (pytest)"
set +e
"$PY" -m pytest tests/fmpy -q
rc=$?
set -e
if [ "$rc" -eq 5 ]; then echo "pytest: no fmpy tests collected"; rc=0; fi
exit "$rc"
