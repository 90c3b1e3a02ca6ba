"""Surface detection: scan a specimen on an x–y raster, map its normals and distances.

* :class:`ScanGrid` — probe positions [m] (raster + stand-off) in serpentine order.
* :func:`scan_surface` — calibrate the orientation of maximum echo at every point
  (warm-started from the neighbours), then the time of flight → surface point.
* :class:`SurfaceScan` — the result: an xarray Dataset (dims y, x) with units,
  errors against the truth when known, and summaries; NetCDF in and out.
"""

from echocal.scanning.checks import check_scan
from echocal.scanning.dataset import FORMAT, STATUS, SurfaceScan, surface_dataset
from echocal.scanning.grid import ScanGrid, axis_values
from echocal.scanning.scan import CONVERGED_STATUSES, echo_snr, scan_surface
from echocal.scanning.store import PointStore, partial_path

__all__ = [
    "CONVERGED_STATUSES",
    "FORMAT",
    "STATUS",
    "PointStore",
    "ScanGrid",
    "SurfaceScan",
    "axis_values",
    "check_scan",
    "echo_snr",
    "partial_path",
    "scan_surface",
    "surface_dataset",
]
