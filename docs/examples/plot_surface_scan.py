"""
Scanning a surface
==================

At each probe position of a small raster over a sphere, find the surface normal (the
orientation of maximum echo) and the distance (time of flight), then compare with the
sphere's true normals and heights. Each point's calibration starts warm from its finished
neighbours.
"""

# %%
# The ``scan-5mhz`` setup: a 3 mm, 5 MHz probe 25 mm above a sphere. A 3 × 3 raster,
# 4 mm apart.
from echocal import load_setup
from echocal.scanning import ScanGrid, scan_surface

setup = load_setup("scan-5mhz", seed=1)
grid = ScanGrid.regular(x=(-4e-3, 4e-3, 4e-3), y=(-4e-3, 4e-3, 4e-3), z=25e-3)
scan = scan_surface(setup, grid, rng=1, progress=False)

# %%
# The summary holds the measured cost and, on a simulator, the error against the truth.
s = scan.summary
print(f"{s['found']} of {s['points']} points found")
print(f"{s['measurements_per_point']:.1f} measurements per point")
print(f"normal error: median {s['normal_error_deg']['median']:.4f}°")
print(f"|height error|: median {s['height_error_abs_m']['median'] * 1e3:.4f} mm")

# %%
# The surface normals found, as a map (the arrows are the normals' x–y components).
from echocal.plots.surface import normal_map_figure

fig = normal_map_figure(scan)
