"""Parameter studies of origami-fmu: every combination of a study's values is
one FMU run, run as a Dask task (a LocalCluster or a scheduler address), and
the runs' rows are gathered into one table and a plot.

Modules: `study` (the study file and its combinations), `master` (the FMU
driven step by step through fmpy, state save/restore), `metrics` (the derived
values of a run), `worker` (one run in a subprocess with a time limit),
`scenes` (FMUs built through the CLI), `execute` (Dask), `report` (CSV, plot).
"""

from .study import Study, StudyError, load_study  # noqa: F401
