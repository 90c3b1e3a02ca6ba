"""The :class:`Shape` interface every specimen surface implements, and shared helpers.

A shape answers one question for a bundle of rays: how far along each ray is
the first surface point, and which way does the surface face there.

Conventions
-----------
* Rays are ``origins + t * directions`` with ``origins``, ``directions`` of
  shape ``(M, 3)`` [m] and unit ``directions``.
* ``distance`` [m], shape ``(M,)``: the smallest ``t > eps`` at which the ray
  meets the surface, ``inf`` for a miss.  ``eps`` is ``EPS_REL`` times the
  shape's size (at least ``EPS_REL`` m), so a ray starting *on* a surface (a
  reflected ray) does not hit that surface again at ``t ≈ 0``.
* ``normal``, shape ``(M, 3)``: the unit surface normal at the hit, **facing the
  incoming ray** (``n · d <= 0``); zeros for misses.
* Rays that graze a surface (``|n · d| <= GRAZING_COS``) miss it.
"""

from __future__ import annotations

import abc
import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array
from echocal.errors import EchocalValueError, GeometryError

__all__ = ["EPS_REL", "GRAZING_COS", "Shape"]

FloatArray = NDArray[np.float64]

EPS_REL = 1e-9
"""Relative self-intersection tolerance: hits with ``t <= EPS_REL * max(1 m, size)`` are ignored."""

GRAZING_COS = 1e-12
"""Rays with ``|cos(angle to the normal)| <= GRAZING_COS`` graze a flat surface and miss it."""


class Shape(abc.ABC):
    """A reflecting surface that a bundle of rays can be cast against.

    Subclasses implement :meth:`_intersect` (inputs already validated) and
    :meth:`bounds`; they set the class attribute ``kind`` and take a ``name``.
    """

    kind: ClassVar[str] = "shape"
    name: str

    @abc.abstractmethod
    def bounds(self) -> FloatArray:
        """Axis-aligned box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` [m], shape (2, 3)."""

    @abc.abstractmethod
    def _intersect(
        self, origins: FloatArray, directions: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Kernel of :meth:`intersect`; inputs are float64 ``(M, 3)``, directions unit."""

    def intersect(self, origins: ArrayLike, directions: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Closest hit of each ray with this shape.

        Parameters
        ----------
        origins : [m], shape ``(M, 3)``
        directions : unit vectors, shape ``(M, 3)``

        Returns
        -------
        distance : [m], shape ``(M,)``; ``inf`` for a miss.
        normal : unit normals facing the ray (``n · d <= 0``), shape ``(M, 3)``; zeros for misses.
        """
        o, d = _validate_rays(origins, directions)
        return self._intersect(o, d)

    @property
    def eps(self) -> float:
        """[m] self-intersection tolerance of this shape (see ``EPS_REL``)."""
        box = self.bounds()
        size = float(np.linalg.norm(box[1] - box[0]))
        return EPS_REL * max(1.0, size)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"


# ---------------------------------------------------------------- helpers (private)


def _check_name(owner: str, name: Any) -> str:
    if not isinstance(name, str) or not name:
        raise EchocalValueError(f"{owner}.name must be a non-empty string; got {name!r}")
    return name


def _point(owner: str, field: str, value: ArrayLike) -> FloatArray:
    """A finite point/vector of shape (3,) [m]."""
    arr = finite_array(f"{owner}.{field}", value, shape_tail=(3,))
    if arr.shape != (3,):
        raise GeometryError(f"{owner}.{field} must have shape (3,); got {arr.shape}")
    return arr.copy()


def _size(owner: str, field: str, value: Any) -> float:
    """A finite length > 0 [m]; zero or negative sizes are a :class:`GeometryError`."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise GeometryError(f"{owner}.{field} must be a real number; got {value!r}") from None
    if not math.isfinite(out):
        raise GeometryError(f"{owner}.{field} must be finite; got {out}")
    if out <= 0.0:
        raise GeometryError(f"{owner}.{field} must be > 0; got {out:g}")
    return out


def _angle(owner: str, field: str, value: Any) -> float:
    """A finite angle [deg]."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise GeometryError(f"{owner}.{field} must be a real number [deg]; got {value!r}") from None
    if not math.isfinite(out):
        raise GeometryError(f"{owner}.{field} must be finite [deg]; got {out}")
    return out


def _validate_rays(origins: ArrayLike, directions: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Finite float64 ``(M, 3)`` origins and directions of equal shape."""
    o = finite_array("origins", origins, shape_tail=(3,))
    d = finite_array("directions", directions, shape_tail=(3,))
    if o.ndim != 2 or o.shape != d.shape:
        raise EchocalValueError(
            f"origins and directions must both have shape (M, 3); got {o.shape} and {d.shape}"
        )
    return o, d


def _face_the_ray(normal: FloatArray, directions: FloatArray) -> FloatArray:
    """Flip each normal (M, 3) so that ``n · d <= 0``."""
    flip = np.einsum("ij,ij->i", normal, directions) > 0.0
    return np.where(flip[:, None], -normal, normal)


def _miss_arrays(m: int) -> tuple[FloatArray, FloatArray]:
    return np.full(m, np.inf), np.zeros((m, 3))


def _slab_hits(
    origins: FloatArray, inv_dirs: FloatArray, box_min: FloatArray, box_max: FloatArray
) -> NDArray[np.bool_]:
    """Ray/box overlap test for ray rows against box rows (broadcast), any t >= 0.

    ``inv_dirs`` must be finite (zero direction components replaced by a tiny
    value before inverting).  Shapes broadcast: e.g. origins (R, 1, 3) against
    boxes (1, B, 3) give (R, B).
    """
    t1 = (box_min - origins) * inv_dirs
    t2 = (box_max - origins) * inv_dirs
    t_near = np.minimum(t1, t2).max(axis=-1)
    t_far = np.maximum(t1, t2).min(axis=-1)
    return (t_near <= t_far) & (t_far >= 0.0)


def _safe_inverse(directions: FloatArray) -> FloatArray:
    """``1 / d`` with zero components replaced by ``±1e-30`` first (finite, sign kept)."""
    tiny = np.where(np.signbit(directions), -1e-30, 1e-30)
    safe = np.where(np.abs(directions) < 1e-30, tiny, directions)
    return 1.0 / safe
