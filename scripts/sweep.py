"""Run a parameter study: `python scripts/sweep.py STUDY.toml [--scheduler ADDRESS]`
(the package is python/origami_sweep; see its --help)."""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))

from origami_sweep.__main__ import main  # noqa: E402

if __name__ == "__main__":  # Dask's worker processes import this file again
    sys.exit(main())
