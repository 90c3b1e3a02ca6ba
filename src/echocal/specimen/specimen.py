"""A specimen: any number of shapes, cast against together (closest hit wins)."""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array
from echocal.geometry import normal_to_orientation
from echocal.specimen.base import FloatArray, Shape, _check_name
from echocal.specimen.casting import Hits, _as_shapes, cast

__all__ = ["Specimen"]


class Specimen:
    """The object under test: a named, ordered collection of :class:`Shape` s.

    A ray cast at a specimen returns its closest hit over all shapes; the
    index of the shape hit refers to the order given here.

    Parameters
    ----------
    shapes : a shape or an iterable of shapes (may be empty: every ray misses).
    name : label used in plots, reports and configs.
    description : one line for humans (what it is, what it tests).
    """

    def __init__(
        self, shapes: Shape | Iterable[Shape], *, name: str = "specimen", description: str = ""
    ) -> None:
        self._shapes: tuple[Shape, ...] = _as_shapes(shapes)
        self._name = _check_name("Specimen", name)
        self._description = str(description)

    @property
    def shapes(self) -> tuple[Shape, ...]:
        """The shapes, in the order that ``Hits.shape_index`` refers to."""
        return self._shapes

    @property
    def name(self) -> str:
        """Label of the specimen."""
        return self._name

    @property
    def description(self) -> str:
        """One-line description."""
        return self._description

    def __len__(self) -> int:
        return len(self._shapes)

    def __iter__(self) -> Iterator[Shape]:
        return iter(self._shapes)

    def __getitem__(self, index: int) -> Shape:
        return self._shapes[index]

    def __repr__(self) -> str:
        kinds = ", ".join(f"{s.kind}:{s.name}" for s in self._shapes)
        return f"Specimen(name={self._name!r}, shapes=[{kinds}])"

    def bounds(self) -> FloatArray:
        """Axis-aligned box around all shapes [m], shape (2, 3); zeros if there are none."""
        if not self._shapes:
            return np.zeros((2, 3))
        boxes = np.stack([s.bounds() for s in self._shapes])
        return np.stack([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])

    def containing(self, points: ArrayLike) -> NDArray[np.int64]:
        """Index of the closed shape each point [m] ``(M, 3)`` lies inside, −1 if none, ``(M,)``.

        Only closed shapes (spheres, solid cylinders, watertight meshes) bound a solid; a
        probe position inside one is impossible (see :attr:`Shape.closed`).  A bore
        (:attr:`Shape.bore`, e.g. the ``"inside"`` cylinder of a pipe) is a hole cut into
        them: a point inside some solid but also inside a bore is in the coupling medium (−1).
        """
        pts = finite_array("points", points, shape_tail=(3,)).reshape(-1, 3)
        out = np.full(len(pts), -1, dtype=np.int64)
        in_hole = np.zeros(len(pts), dtype=bool)
        for shape in self._shapes:
            if shape.bore:
                in_hole |= shape._contains(pts)
        for index, shape in enumerate(self._shapes):
            if shape.closed:
                free = np.flatnonzero((out == -1) & ~in_hole)
                out[free[shape._contains(pts[free])]] = index
        return out

    def cast(self, origins: ArrayLike, directions: ArrayLike) -> Hits:
        """Closest hits of rays ``(..., N, 3)``; see :func:`echocal.raytrace.cast`."""
        return cast(self, origins, directions)

    # ---------------------------------------------------------- ground truth
    def surface_below(self, x: ArrayLike, y: ArrayLike) -> Hits:
        """Cast vertical rays (straight down, from above the specimen) at ``(x, y)`` [m].

        ``x`` and ``y`` broadcast to a common shape ``(...)``; the returned
        :class:`~echocal.raytrace.Hits` has that shape (``point`` and ``normal``
        gain a last axis of 3).  Normals face up (towards the ray).
        """
        xa = finite_array("x", x)
        ya = finite_array("y", y)
        xa, ya = np.broadcast_arrays(xa, ya)
        top = float(self.bounds()[1, 2]) + 1.0
        origins = np.stack([xa, ya, np.full(xa.shape, top)], axis=-1)
        directions = np.broadcast_to(np.array([0.0, 0.0, -1.0]), origins.shape)
        return cast(self, origins.reshape(-1, 3), directions.reshape(-1, 3)).reshape(*xa.shape)

    def surface_normal_below(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """Upward unit surface normal below ``(x, y)`` [m], shape ``(..., 3)``; NaN where nothing.

        This is the ground truth of calibration: the transducer orientation
        that fires perpendicular onto the surface at that point has ``n`` equal
        to this normal (the beam travels along ``-n``).
        """
        hits = self.surface_below(x, y)
        return np.where(hits.hit[..., None], hits.normal, np.nan)

    def optimal_orientation_below(
        self, x: ArrayLike, y: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """(azimuth, co-elevation) [deg] whose normal is the surface normal below ``(x, y)``.

        Canonical form of :func:`echocal.geometry.normal_to_orientation`
        (co-elevation >= 0; azimuth 0 at the pole); NaN where nothing is below.
        """
        hits = self.surface_below(x, y)
        azimuth = np.full(hits.distance.shape, np.nan)
        coelevation = np.full(hits.distance.shape, np.nan)
        if np.any(hits.hit):
            az, co = normal_to_orientation(hits.normal[hits.hit])
            azimuth[hits.hit] = az
            coelevation[hits.hit] = co
        return azimuth, coelevation
