"""Sphere: closed-form ray intersection."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal.specimen.base import (
    KERNEL_PARAMS,
    KERNEL_SPHERE,
    FloatArray,
    Shape,
    _check_name,
    _dot,
    _point,
    _signed_normals,
    _size,
)

__all__ = ["Sphere"]


class Sphere(Shape):
    """A sphere surface of ``radius`` [m] about ``center`` [m].

    Solves ``|s + t d − c|² = r²`` with the numerically stable form
    ``disc = r² − |f − (f·d) d|²`` (``f = s − c``) and ``q = −b − sign(b)√disc``
    so that neither root suffers cancellation.  A tangent ray (``disc = 0``)
    touches the sphere at one point and counts as a hit; a ray starting inside
    hits the far side (its normal then points inward, towards the ray).
    """

    kind = "sphere"

    def __init__(self, *, center: ArrayLike, radius: float, name: str = "sphere") -> None:
        self.center = _point("Sphere", "center", center)
        self.radius = _size("Sphere", "radius", radius)
        self.name = _check_name("Sphere", name)
        self._eps = self.eps
        params = np.zeros(KERNEL_PARAMS)
        params[:5] = *self.center, self.radius, self._eps
        params.setflags(write=False)
        self._params = params

    def _kernel_params(self) -> tuple[int, FloatArray]:
        """Centre (3), radius, eps."""
        return KERNEL_SPHERE, self._params

    def bounds(self) -> FloatArray:
        return np.stack([self.center - self.radius, self.center + self.radius])

    @property
    def closed(self) -> bool:
        """A sphere bounds a ball: a probe cannot be inside it."""
        return True

    def _contains(self, points: FloatArray) -> NDArray[np.bool_]:
        d = points - self.center
        return np.einsum("ij,ij->i", d, d) < self.radius**2

    def _intersect_soa(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        r = self.radius
        f = o - self.center[:, None]
        b = _dot(f, d)
        perp = f - b * d
        disc = r * r - _dot(perp, perp)
        ok = disc >= 0.0
        root = np.sqrt(np.where(ok, disc, 0.0))
        c = _dot(f, f) - r * r
        q = -b - np.where(b >= 0.0, root, -root)  # |q| >= |b|: no cancellation
        q_ok = q != 0.0
        t2 = np.divide(c, q, out=np.zeros_like(q), where=q_ok)
        t_lo = np.minimum(q, t2)
        t_hi = np.maximum(q, t2)
        eps = self._eps
        t = np.where(t_lo > eps, t_lo, np.where(t_hi > eps, t_hi, np.inf))
        t = np.where(ok, t, np.inf)
        hit = t < np.inf
        normal = (f + np.where(hit, t, 0.0) * d) / r
        normal /= np.maximum(np.sqrt(_dot(normal, normal)), 1e-300)
        return t, _signed_normals(normal, d, hit)

    def __repr__(self) -> str:
        c = ", ".join(f"{v:g}" for v in self.center)
        return f"Sphere(name={self.name!r}, center=[{c}], radius={self.radius:g})"
