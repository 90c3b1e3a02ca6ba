"""``ScanGrid``: the x–y raster of probe positions [m] and its serpentine measuring order."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, finite_float, one_of, positive_float
from echocal.errors import EchocalValueError

__all__ = ["ScanGrid", "axis_values"]

FloatArray = NDArray[np.float64]

_MAX_POINTS = 1_000_000


def axis_values(name: str, first: float, last: float, step: float) -> FloatArray:
    """Values ``first``, ``first + step``, … up to ``last`` [m] (included up to rounding).

    ``first == last`` gives the single value; ``last < first`` or ``step <= 0`` is refused.
    """
    first = finite_float(f"{name} first", first)
    last = finite_float(f"{name} last", last)
    step = positive_float(f"{name} step", step)
    if last < first:
        raise EchocalValueError(f"{name}: last ({last:g} m) must be >= first ({first:g} m)")
    count = math.floor((last - first) / step * (1 + 1e-9) + 1e-9) + 1
    if count > _MAX_POINTS:
        raise EchocalValueError(f"{name}: {count} points is too many; use a larger step")
    return first + step * np.arange(count, dtype=np.float64)


@dataclass(frozen=True, kw_only=True)
class ScanGrid:
    """Probe positions of a surface scan: a raster in x and y at stand-off height(s) z.

    Attributes
    ----------
    x : [m] raster columns, shape (n_x,), strictly increasing.
    y : [m] raster rows, shape (n_y,), strictly increasing.
    z : [m] probe height: one stand-off for every point, or shape (n_y, n_x) per point.
    """

    x: tuple[float, ...]
    y: tuple[float, ...]
    z: float | tuple[tuple[float, ...], ...] = 0.025

    def __post_init__(self) -> None:
        for name in ("x", "y"):
            arr = finite_array(name, np.atleast_1d(getattr(self, name)))
            if arr.ndim != 1 or arr.size == 0:
                raise EchocalValueError(f"grid {name} must be a non-empty 1-D sequence [m]")
            if arr.size > 1 and np.any(np.diff(arr) <= 0):
                raise EchocalValueError(f"grid {name} must be strictly increasing [m]")
            object.__setattr__(self, name, tuple(float(v) for v in arr))
        z = np.asarray(self.z, dtype=np.float64)
        if z.ndim == 0:
            object.__setattr__(self, "z", finite_float("grid z", float(z)))
        else:
            z = finite_array("grid z", z)
            if z.shape != self.shape:
                raise EchocalValueError(
                    f"grid z must be one height or shape (n_y, n_x) = {self.shape} [m]; "
                    f"got shape {z.shape}"
                )
            object.__setattr__(self, "z", tuple(tuple(float(v) for v in row) for row in z))

    @classmethod
    def regular(
        cls,
        *,
        x: tuple[float, float, float],
        y: tuple[float, float, float],
        z: float | ArrayLike = 0.025,
    ) -> ScanGrid:
        """Grid from ``(first, last, step)`` [m] per axis and stand-off ``z`` [m]."""
        return cls(
            x=tuple(axis_values("grid x", *x)),
            y=tuple(axis_values("grid y", *y)),
            z=z,  # type: ignore[arg-type]  # __post_init__ normalizes any array of heights
        )

    @property
    def shape(self) -> tuple[int, int]:
        """(n_y, n_x)."""
        return len(self.y), len(self.x)

    @property
    def size(self) -> int:
        """Number of probe positions."""
        return len(self.y) * len(self.x)

    @property
    def spacing(self) -> float:
        """[m] the larger raster step (1 mm for a single point)."""
        steps = [np.min(np.diff(v)) for v in (self.x, self.y) if len(v) > 1]
        return float(max(steps)) if steps else 1e-3

    def heights(self) -> FloatArray:
        """[m] probe height per point, shape (n_y, n_x)."""
        return np.broadcast_to(np.asarray(self.z, dtype=np.float64), self.shape).copy()

    def positions(self) -> FloatArray:
        """[m] probe positions, shape (n_y, n_x, 3)."""
        xx, yy = np.meshgrid(self.x, self.y, indexing="xy")
        return np.stack([xx, yy, self.heights()], axis=-1)

    def order(self, start: str = "centre") -> list[tuple[int, int]]:
        """Measuring order of (iy, ix): serpentine (boustrophedon) rows.

        ``start="corner"``: row 0 left to right, row 1 back, ... — consecutive points
        are raster neighbours.  ``start="centre"`` (default): the centre point first,
        then the rest of the centre row (right, then left), then the rows above it and
        the rows below it, each swept in serpentine — every point after the first has a
        finished raster neighbour, and the first (cold) start is over the middle of the
        part, where the stand-off is normally set and the surface faces the probe.
        """
        one_of("start", start, ("centre", "corner"))
        n_y, n_x = self.shape
        out: list[tuple[int, int]]
        if start == "corner":
            out = []
            for iy in range(n_y):
                cols = range(n_x) if iy % 2 == 0 else range(n_x - 1, -1, -1)
                out.extend((iy, ix) for ix in cols)
            return out
        cy, cx = n_y // 2, n_x // 2
        out = [(cy, ix) for ix in range(cx, n_x)] + [(cy, ix) for ix in range(cx - 1, -1, -1)]
        for rows in (range(cy + 1, n_y), range(cy - 1, -1, -1)):
            for k, iy in enumerate(rows):
                cols = range(n_x) if k % 2 == 0 else range(n_x - 1, -1, -1)
                out.extend((iy, ix) for ix in cols)
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready description [m]."""
        return {"x": list(self.x), "y": list(self.y), "z": self.z}

    def digest(self) -> str:
        """Short hash of the grid (to refuse resuming a different scan)."""
        text = json.dumps(self.to_dict(), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]
