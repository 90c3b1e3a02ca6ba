"""Experiments: Monte-Carlo sweeps over calibration methods, parameters, SNRs and seeds.

A sweep file (TOML) crosses methods × parameter grid × SNRs × initial guesses × seeds on
one setup; :func:`run_sweep` runs every case (local processes or a Dask cluster),
writing tidy Parquet results incrementally so that an interrupted sweep resumes.

Thesis scenarios, reports and the demo live in ``echocal.experiments.scenarios``,
``echocal.experiments.report`` and ``echocal.experiments.demo`` (import them by their
full module path; this package imports only the sweep machinery).
"""

__all__: list[str] = []
