#!/usr/bin/env bash
# Creates .venv with the Python packages the fmpy suite and the plots need
# (idempotent: a second run only checks). Prints the venv's python path.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv >&2
fi
if ! .venv/bin/python -c "import fmpy, pytest, matplotlib, numpy, meshio, PIL, dask.distributed, pandas" 2>/dev/null; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check -r scripts/requirements.txt >&2
fi
echo "$PWD/.venv/bin/python"
