"""Position scans: A-scans on a line or a raster at a fixed probe orientation.

* :class:`PositionScan` — the data (an xarray Dataset on dims (y, x, time) or (x, time),
  echocal's NetCDF schema ``position-scan/1``); :func:`position_scan` builds one.
* :func:`import_scan` with :class:`ScanFacts` — read MATLAB, CSV, NumPy, HDF5 and NDE files.
"""

from echocal.positionscan.dataset import FORMAT, PositionScan, position_scan
from echocal.positionscan.facts import ScanFacts, load_facts
from echocal.positionscan.importing import import_scan

__all__ = [
    "FORMAT",
    "PositionScan",
    "ScanFacts",
    "import_scan",
    "load_facts",
    "position_scan",
]
