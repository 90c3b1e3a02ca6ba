"""Closest-hit casting of a ray bundle against a specimen (re-exported by
:mod:`echocal.raytrace`; it lives with the shapes so that a specimen can cast rays without
importing anything above it).

:func:`cast` is the one entry point: rays with any leading batch axes
``(..., N, 3)`` go in, a :class:`Hits` of the same batch shape comes out.
It is vectorized over rays; the only Python loop runs over the (few) shapes.
``cast`` validates and normalizes its input; the simulator, whose rays are valid
by construction, calls the unchecked structure-of-arrays kernel ``_cast_soa``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array
from echocal.errors import EchocalValueError
from echocal.specimen.base import FloatArray, Shape, _dot

__all__ = ["Hits", "cast"]


@dataclass(frozen=True, slots=True)
class Hits:
    """Closest hit of every ray of a bundle.

    Attributes
    ----------
    distance : [m], shape ``(..., N)``; distance t′ along the (unit) ray, ``inf`` for a miss.
    point : [m], shape ``(..., N, 3)``; hit point ``s + t′ d``, ``inf`` for a miss.
    normal : shape ``(..., N, 3)``; unit surface normal facing the ray
        (``n · d <= 0``), zeros for a miss.
    shape_index : shape ``(..., N)``, int; index into ``specimen.shapes``, −1 for a miss.
    """

    distance: FloatArray
    point: FloatArray
    normal: FloatArray
    shape_index: NDArray[np.int64]

    @property
    def hit(self) -> NDArray[np.bool_]:
        """True where the ray hit something, shape ``(..., N)``."""
        return self.shape_index >= 0

    @property
    def shape(self) -> tuple[int, ...]:
        """Batch shape ``(..., N)``."""
        return self.distance.shape

    def reshape(self, *shape: int) -> Hits:
        """The same hits with the ray axes reshaped to ``shape``."""
        shp = tuple(shape[0]) if len(shape) == 1 and isinstance(shape[0], tuple) else shape
        return Hits(
            distance=self.distance.reshape(shp),
            point=self.point.reshape((*shp, 3)),
            normal=self.normal.reshape((*shp, 3)),
            shape_index=self.shape_index.reshape(shp),
        )


def _as_shapes(specimen: Shape | Iterable[Shape]) -> tuple[Shape, ...]:
    """The shapes of a specimen (anything with a ``shapes`` tuple), of one shape, or of an
    iterable of shapes."""
    shapes = getattr(specimen, "shapes", None)
    if isinstance(shapes, tuple):
        return shapes
    if isinstance(specimen, Shape):
        return (specimen,)
    try:
        items = tuple(specimen)
    except TypeError:
        raise EchocalValueError(
            f"specimen must be a Specimen, a Shape or shapes; got {type(specimen).__name__}"
        ) from None
    for i, item in enumerate(items):
        if not isinstance(item, Shape):
            raise EchocalValueError(
                f"Specimen.shapes[{i}] must be a Shape (FinitePlane, Sphere, Cylinder, "
                f"TriangleMesh, ...); got {type(item).__name__}"
            )
    return items


_CHUNK = 16384  # rays per kernel call: keeps the kernels' temporaries in cache


def _closest(
    shapes: tuple[Shape, ...], o: FloatArray, d: FloatArray
) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Closest hit over ``shapes`` of rays (3, M): distance (M,), normal (3, M), index (M,)."""
    m = o.shape[1]
    if not shapes:
        return np.full(m, np.inf), np.zeros((3, m)), np.full(m, -1, dtype=np.int64)
    best_t, best_n = shapes[0]._intersect_soa(o, d)
    best_i = np.where(best_t < np.inf, 0, -1)
    for index, shape in enumerate(shapes[1:], start=1):
        t, n = shape._intersect_soa(o, d)
        closer = t < best_t
        best_t = np.where(closer, t, best_t)
        best_n = np.where(closer, n, best_n)
        best_i[closer] = index
    return best_t, best_n, best_i


def _cast_soa(
    shapes: tuple[Shape, ...], o: FloatArray, d: FloatArray
) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Internal fast path of :func:`cast`: no checks, no copies of the rays.

    Parameters
    ----------
    shapes : the specimen's shapes.
    o : [m] finite origins, shape ``(3, M)`` (structure of arrays).
    d : finite **unit** directions, shape ``(3, M)``.

    Returns
    -------
    distance [m] ``(M,)`` (``inf`` for a miss), normal ``(3, M)`` (facing the ray,
    zeros for a miss), shape index ``(M,)`` (−1 for a miss).
    """
    m = o.shape[1]
    if m <= _CHUNK:
        return _closest(shapes, o, d)
    distance = np.empty(m)
    normal = np.empty((3, m))
    shape_index = np.empty(m, dtype=np.int64)
    # chunks keep the kernels' temporaries in cache for large batches
    for lo in range(0, m, _CHUNK):
        sl = slice(lo, min(m, lo + _CHUNK))
        distance[sl], normal[:, sl], shape_index[sl] = _closest(shapes, o[:, sl], d[:, sl])
    return distance, normal, shape_index


def _hit_points(o: FloatArray, d: FloatArray, distance: FloatArray) -> FloatArray:
    """Hit points ``o + t·d`` [m], shape ``(3, ...)``; ``inf`` where ``distance`` is inf."""
    hit = distance < np.inf
    point = d * np.where(hit, distance, 0.0)
    point += o
    np.copyto(point, np.inf, where=~hit)
    return point


def cast(specimen: Shape | Iterable[Shape], origins: ArrayLike, directions: ArrayLike) -> Hits:
    """Closest hit of each ray over all shapes of ``specimen``.

    Parameters
    ----------
    specimen : a :class:`~echocal.specimen.Specimen`, one shape, or shapes.
    origins : [m], shape ``(..., N, 3)``
    directions : shape ``(..., N, 3)``, broadcastable with ``origins`` (e.g. one
        origin for all rays); normalized here, so distances are in metres.

    Returns
    -------
    Hits with batch shape ``(..., N)``.  Ties between shapes go to the shape
    listed first.
    """
    shapes = _as_shapes(specimen)
    o = finite_array("origins", origins, shape_tail=(3,))
    d = finite_array("directions", directions, shape_tail=(3,))
    try:
        o, d = np.broadcast_arrays(o, d)
    except ValueError:
        raise EchocalValueError(
            f"origins and directions must broadcast; got shapes {o.shape} and {d.shape}"
        ) from None
    batch = o.shape[:-1]
    # structure-of-arrays (3, M): numpy is much faster on long 1-D components
    o_soa = np.ascontiguousarray(o.reshape(-1, 3).T)
    d_soa = np.ascontiguousarray(d.reshape(-1, 3).T)
    norm = np.sqrt(_dot(d_soa, d_soa))
    if np.any(norm == 0.0):
        raise EchocalValueError("directions must be non-zero vectors; got a zero vector")
    if np.any(np.abs(norm - 1.0) > 1e-12):
        d_soa = d_soa / norm  # a new array: d_soa may be a view of the caller's data
    distance, normal, shape_index = _cast_soa(shapes, o_soa, d_soa)
    point = _hit_points(o_soa, d_soa, distance)
    # (3, M) -> (..., N, 3) as transposed views (no copy)
    return Hits(
        distance=distance.reshape(batch),
        point=point.T.reshape((*batch, 3)),
        normal=normal.T.reshape((*batch, 3)),
        shape_index=shape_index.reshape(batch),
    )
