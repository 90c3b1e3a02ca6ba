"""
A small sweep
=============

How reliably, and with how many measurements, do two methods find the optimum? A sweep
runs every combination of methods × SNRs × initial guesses × seeds and tabulates each
run. Here: two methods, two SNRs, three seeds, random starts 2–3° from the truth, in one
local process. (The same sweep runs on a Dask cluster with ``scheduler=...``: see the
tutorial on sweeps.)
"""

# %%
# A sweep is a TOML file, a built-in name or, as here, a dict with the same keys.
import tempfile

from echocal.experiments import run_sweep

spec = {
    "name": "gallery",
    "setup": "thesis",
    "position": ["10 mm", 0, "22 mm"],
    "parameterization": "tilt",
    "budget": 40,
    "settle": [0.01, 8],
    "tolerance": 0.1,
    "seeds": 3,
    "snr_db": [30, 15],
    "x0": {"offset": [2, 3]},
    "methods": [{"name": "auto"}, {"name": "spsa"}],
}
out = tempfile.mkdtemp(prefix="echocal-sweep-")
results = run_sweep(spec, f"{out}/gallery", workers=1, progress=False)
print(f"{len(results.runs)} runs")

# %%
# One row per configuration: success rate (final error within the tolerance) and the
# measurements the successful runs needed.
summary = results.summary()
print(summary[["label", "snr_db", "success_rate", "median_measurements_to_tol"]])

# %%
# The success rate of each method, per SNR.
from echocal.plots.sweep import success_rate_figure

fig = success_rate_figure(summary, title="success within 0.1°")
