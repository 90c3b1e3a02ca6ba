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

KERNEL_PLANE = 1
"""``_kernel_params`` code of a :class:`~echocal.specimen.FinitePlane` (see ``echocal.echo``)."""
KERNEL_SPHERE = 2
"""``_kernel_params`` code of a :class:`~echocal.specimen.Sphere`."""
KERNEL_PARAMS = 16
"""Length of the parameter vector of ``_kernel_params``."""


class Shape(abc.ABC):
    """A reflecting surface that a bundle of rays can be cast against.

    Subclasses implement :meth:`_intersect_soa` (inputs already validated, in
    structure-of-arrays layout ``(3, M)``: numpy is several times faster on
    long 1-D component arrays than on rows of 3) and :meth:`bounds`; they set
    the class attribute ``kind`` and take a ``name``.
    """

    kind: ClassVar[str] = "shape"
    name: str

    @abc.abstractmethod
    def bounds(self) -> FloatArray:
        """Axis-aligned box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` [m], shape (2, 3)."""

    @abc.abstractmethod
    def _intersect_soa(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Kernel: ``o``, ``d`` (3, M), ``d`` unit -> distance (M,), normal (3, M)."""

    @property
    def closed(self) -> bool:
        """True when the shape bounds a solid, so a probe cannot be inside (:meth:`contains`)."""
        return False

    @property
    def bore(self) -> bool:
        """True when the shape bounds a hole cut into the solids around it (a cylinder with
        ``surface="inside"``): a point in it (:meth:`_contains`) is in the coupling medium."""
        return False

    def contains(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point [m], shape ``(M, 3)``, lies strictly inside the solid, ``(M,)``.

        Open surfaces (planes, bores, open meshes) bound no solid: always False.
        """
        pts = finite_array("points", points, shape_tail=(3,)).reshape(-1, 3)
        if not self.closed:
            return np.zeros(len(pts), dtype=bool)
        return self._contains(pts)

    def _contains(self, points: FloatArray) -> NDArray[np.bool_]:
        """Whether checked ``(M, 3)`` points [m] lie strictly inside the volume the shape
        bounds: the solid of a :attr:`closed` shape (kernel of :meth:`contains`), the hole
        of a :attr:`bore`."""
        return np.zeros(len(points), dtype=bool)

    def _kernel_params(self) -> tuple[int, FloatArray] | None:
        """``(code, parameters (KERNEL_PARAMS,))`` for the simulator's compiled ray kernel.

        Shapes whose intersection the fused kernel of :mod:`echocal.echo` implements
        (``KERNEL_PLANE``, ``KERNEL_SPHERE``) return their constants; the default None
        sends every specimen holding the shape through the generic :meth:`_intersect_soa`.
        """
        return None

    def _intersect(
        self, origins: FloatArray, directions: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Validated ``(M, 3)`` rays -> distance ``(M,)``, normal ``(M, 3)``."""
        t, n = self._intersect_soa(
            np.ascontiguousarray(origins.T), np.ascontiguousarray(directions.T)
        )
        return t, _aos(n)

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


def _aos(v: FloatArray) -> FloatArray:
    """(3, M) components -> C-contiguous rows (M, 3)."""
    out = np.empty((v.shape[1], 3))
    out[:, 0], out[:, 1], out[:, 2] = v[0], v[1], v[2]
    return out


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise dot product of (3, ...) component arrays -> (...)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _signed_normals(normal: FloatArray, d: FloatArray, hit: NDArray[np.bool_]) -> FloatArray:
    """Flip (3, M) normals to face the rays ``d`` (``n · d <= 0``); zero them where not ``hit``."""
    sign = np.where(_dot(normal, d) > 0.0, -1.0, 1.0)
    sign = np.where(hit, sign, 0.0)
    return normal * sign


def _slab_hits(
    o: FloatArray, inv_d: FloatArray, box_lo: FloatArray, box_hi: FloatArray
) -> NDArray[np.bool_]:
    """Ray/box overlap test, any ``t >= 0``; all arguments (3, ...) and broadcastable.

    ``inv_d`` must be finite (zero direction components replaced by a tiny
    value before inverting, see :func:`_safe_inverse`).
    """
    t_near = np.full(np.broadcast_shapes(o.shape[1:], box_lo.shape[1:]), -np.inf)
    t_far = np.full(t_near.shape, np.inf)
    for k in range(3):
        t1 = (box_lo[k] - o[k]) * inv_d[k]
        t2 = (box_hi[k] - o[k]) * inv_d[k]
        np.maximum(t_near, np.minimum(t1, t2), out=t_near)
        np.minimum(t_far, np.maximum(t1, t2), out=t_far)
    return (t_near <= t_far) & (t_far >= 0.0)


def _safe_inverse(directions: FloatArray) -> FloatArray:
    """``1 / d`` with zero components replaced by ``±1e-30`` first (finite, sign kept)."""
    tiny = np.where(np.signbit(directions), -1e-30, 1e-30)
    safe = np.where(np.abs(directions) < 1e-30, tiny, directions)
    return 1.0 / safe
