#!/usr/bin/env bash
# The test command: checks formatting, builds everything (release: the
# numerics are slow unoptimized), runs clippy (warnings are errors) and the
# cargo tests, runs a C host of the FMU under valgrind, cross-builds the
# win64 DLL and tests it under wine (scripts/windows_test.sh), sets up the Python
# venv with fmpy, installs fmi-sim (a second FMI client; once per machine,
# about 9 min), installs the JavaScript FOLD readers (scripts/setup_node.sh)
# and runs the fmpy suite. Works on a fresh Debian machine with rustup, cc,
# python3 and apt-get (as root, for libclang-dev, valgrind, wine, MinGW-w64,
# Debian's Rust with its source, and nodejs with npm).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
  rustup component add rustfmt clippy
fi
echo "== cargo fmt --check"
cargo fmt --check
echo "== cargo build --release"
cargo build --release --locked 2>&1 | tail -n 3
echo "== cargo clippy (all targets, -D warnings)"
cargo clippy --all-targets --release --locked --quiet -- -D warnings
echo "== cargo test --release"
cargo test --release --locked
echo "== C host under valgrind"
bash scripts/c_host_test.sh
echo "== win64 DLL under wine"
bash scripts/windows_test.sh
echo "== python venv"
PY=$(bash scripts/setup_venv.sh)
echo "== fmi-sim (second FMI client)"
bash scripts/setup_fmi_sim.sh
echo "== JavaScript FOLD readers (fold, rabbit-ear)"
bash scripts/setup_node.sh
echo "== fmpy suite (pytest)"
set +e
# The sequence tests read --fold-out files in the JavaScript readers set up
# above: here a missing reader fails them instead of skipping.
ORIGAMI_REQUIRE_NODE=1 "$PY" -m pytest tests/fmpy -q
rc=$?
set -e
if [ "$rc" -eq 5 ]; then echo "pytest: no fmpy tests collected"; rc=0; fi
exit "$rc"
