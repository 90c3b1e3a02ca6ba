"""Position scans: A-scans on a line or a raster at a fixed probe orientation.

* :class:`PositionScan` — the data (an xarray Dataset on dims (y, x, time) or (x, time),
  echocal's NetCDF schema ``position-scan/1``); :func:`position_scan` builds one.
* :func:`import_scan` with :class:`ScanFacts` — read MATLAB, CSV, NumPy, HDF5 and NDE files.
* :func:`simulate_position_scan` — the same kind recorded on the simulator (with its zero
  offset); :func:`receiver_noise` — noise draws of one noiseless simulation.
* :func:`front_wall_tof` — sub-sample front-wall time of flight of every trace.
* :func:`fit_surface` — robust least-squares plane, sphere or cylinder with 1-σ
  uncertainties (:class:`SurfaceFit`).
* :func:`layer_thickness` — the thickness of each layer under each trace (:class:`LayerMap`).
"""

from echocal.positionscan.dataset import FORMAT, PositionScan, position_scan
from echocal.positionscan.facts import ScanFacts, load_facts
from echocal.positionscan.fit import SHAPES, SurfaceFit, fit_surface
from echocal.positionscan.importing import import_scan
from echocal.positionscan.layers import LayerMap, layer_thickness
from echocal.positionscan.simulate import receiver_noise, simulate_position_scan, zero_offset
from echocal.positionscan.tof import front_wall_tof

__all__ = [
    "FORMAT",
    "SHAPES",
    "LayerMap",
    "PositionScan",
    "ScanFacts",
    "SurfaceFit",
    "fit_surface",
    "front_wall_tof",
    "import_scan",
    "layer_thickness",
    "load_facts",
    "position_scan",
    "receiver_noise",
    "simulate_position_scan",
    "zero_offset",
]
