"""Sphere: closed-form ray intersection."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal.specimen.base import FloatArray, Shape, _check_name, _point, _size

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

    def bounds(self) -> FloatArray:
        return np.stack([self.center - self.radius, self.center + self.radius])

    def _intersect(
        self, origins: FloatArray, directions: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        f = origins - self.center
        b = np.einsum("ij,ij->i", f, directions)
        perp = f - b[:, None] * directions
        disc = self.radius**2 - np.einsum("ij,ij->i", perp, perp)
        ok = disc >= 0.0
        root = np.sqrt(np.where(ok, disc, 0.0))
        c = np.einsum("ij,ij->i", f, f) - self.radius**2
        q = -b - np.where(b >= 0.0, root, -root)  # |q| >= |b|, no cancellation
        t1 = q
        with np.errstate(divide="ignore", invalid="ignore"):
            t2 = np.where(q != 0.0, c / q, 0.0)
        t_lo = np.minimum(t1, t2)
        t_hi = np.maximum(t1, t2)
        t = np.where(t_lo > self._eps, t_lo, np.where(t_hi > self._eps, t_hi, np.inf))
        t = np.where(ok, t, np.inf)
        hit = np.isfinite(t)
        t_safe = np.where(hit, t, 0.0)
        normal = (f + t_safe[:, None] * directions) / self.radius
        normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
        facing = np.einsum("ij,ij->i", normal, directions) > 0.0
        sign = np.where(hit, np.where(facing, -1.0, 1.0), 0.0)
        return t, sign[:, None] * normal

    def __repr__(self) -> str:
        c = ", ".join(f"{v:g}" for v in self.center)
        return f"Sphere(name={self.name!r}, center=[{c}], radius={self.radius:g})"
