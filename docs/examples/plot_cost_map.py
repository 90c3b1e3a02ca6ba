"""
A cost map
==========

The pseudo-energy as a function of the two orientation angles: the landscape every
calibration method climbs. One batched, noiseless simulation evaluates the whole grid.
"""

# %%
# A 41 × 41 grid of gimbal tilts, ±4° around the true optimum of the realistic probe:
# its main lobe is only about a degree wide.
import numpy as np

from echocal import load_setup
from echocal.evaluation import cost_map

setup = load_setup("immersion-5mhz", seed=0)
where = setup.reference_position
truth = setup.true_optimum(where, parameterization="tilt")
cmap = cost_map(
    setup,
    where,
    parameterization="tilt",
    a_range=(truth[0] - 4.0, truth[0] + 4.0),
    b_range=(truth[1] - 4.0, truth[1] + 4.0),
    n=41,
)
print(f"true optimum: tilt ({truth[0]:.3f}°, {truth[1]:.3f}°)")
print(f"grid: {cmap.values.shape}, axes {cmap.names} [deg]")

# %%
# How much of the grid has an echo within 20 dB of the best one: the region where a
# local method can climb from.
db = 10 * np.log10(np.maximum(cmap.values / cmap.values.max(), 1e-12))
print(f"{100 * np.mean(db > -20):.1f} % of the ±4° grid is within 20 dB of the peak")
# the lobe's width along tilt x, through the peak: where the energy is within 6 dB
row = db[:, np.argmax(cmap.values.max(axis=0))]
inside = cmap.a[row > -6.0]
print(f"-6 dB width along tilt x: {inside.max() - inside.min():.2f}° (grid step 0.2°)")

# %%
# Drawn as a map in dB, with the truth marked.
from echocal.plots.calibration import path_figure

fig = path_figure(cmap, {}, truth=truth, title="immersion-5mhz: pseudo-energy", db_floor=-40.0)
