#!/usr/bin/env bash
# Installs fmi-sim (crates.io: a pure-Rust FMI simulator), the second,
# independent FMI client that the fmpy suite compares against fmpy.
# Idempotent: does nothing when fmi-sim $VERSION is on PATH.
# Measured on a 2-core machine: about 20 s for libclang-dev (apt; fmi-sim's
# fmi-sys runs bindgen, which needs libclang) and about 8.5 min for
# `cargo install` (343 crates, release).
set -euo pipefail
VERSION=0.7.0
export PATH="$HOME/.cargo/bin:$PATH"
# (fmi-sim 0.7.0 prints its version to stderr and exits non-zero.)
if command -v fmi-sim >/dev/null 2>&1; then
  have=$(fmi-sim --version 2>&1 || true)
  case "$have" in *"fmi-sim $VERSION"*) exit 0 ;; esac
fi
if ! ldconfig -p 2>/dev/null | grep -q 'libclang[-.0-9]*\.so'; then
  echo "installing libclang-dev (needed to build fmi-sim)" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >&2
  apt-get install -y -qq libclang-dev >&2
fi
echo "cargo install fmi-sim $VERSION (several minutes, once per machine)" >&2
# Its own temporary target dir, not the project's.
env -u CARGO_TARGET_DIR cargo install fmi-sim --version "$VERSION" --locked --force --quiet >&2
