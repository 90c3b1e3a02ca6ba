"""Finite circular cylinder: convex outer surface or concave inner bore."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import one_of
from echocal.geometry import orientation_normal
from echocal.specimen.base import (
    GRAZING_COS,
    FloatArray,
    Shape,
    _angle,
    _check_name,
    _dot,
    _point,
    _signed_normals,
    _size,
)

__all__ = ["CYLINDER_SURFACES", "Cylinder"]

CYLINDER_SURFACES = ("outside", "inside")
"""Allowed values of ``Cylinder.surface``."""


class Cylinder(Shape):
    """A finite cylinder of ``radius`` and ``length`` [m] about an axis through ``center``.

    The axis direction is :func:`echocal.geometry.orientation_normal` of
    ``(azimuth, coelevation)`` [deg] (default: along z; ``azimuth=90,
    coelevation=90`` gives an axis along y).  The surface spans axial
    coordinates ``[-length/2, length/2]`` about ``center``.

    ``surface`` picks which face reflects:

    * ``"outside"`` — the convex outer wall of a solid rod: only hits where the
      ray arrives from outside the cylinder count (the entering root).
    * ``"inside"`` — the concave wall of a bore: only hits where the ray arrives
      from inside count (the exiting root); a probe inside the bore sees the
      wall in front of it.

    With ``caps=True`` the end discs are part of the surface too, with the same
    one-sided rule (outer faces for ``"outside"``, inner faces — the bottom of
    a blind bore — for ``"inside"``).  Normals are returned facing the ray.

    The lateral intersection solves ``|f⊥ + t d⊥|² = r²`` in the plane normal to
    the axis with the stable discriminant ``|d⊥|² r² − ((f × d)·a)²``.  A ray
    parallel to the axis never meets the wall; a tangent ray touches it once
    and counts for ``"outside"``.
    """

    kind = "cylinder"

    def __init__(
        self,
        *,
        center: ArrayLike,
        radius: float,
        length: float,
        azimuth: float = 0.0,
        coelevation: float = 0.0,
        surface: str = "outside",
        caps: bool = False,
        name: str = "cylinder",
    ) -> None:
        owner = "Cylinder"
        self.center = _point(owner, "center", center)
        self.radius = _size(owner, "radius", radius)
        self.length = _size(owner, "length", length)
        self.azimuth = _angle(owner, "azimuth", azimuth)
        self.coelevation = _angle(owner, "coelevation", coelevation)
        self.surface = one_of("Cylinder.surface", surface, CYLINDER_SURFACES)
        self.caps = bool(caps)
        self.name = _check_name(owner, name)
        self.axis: FloatArray = orientation_normal(self.azimuth, self.coelevation)
        self._eps = self.eps

    def bounds(self) -> FloatArray:
        a = self.axis
        half = 0.5 * self.length * np.abs(a)
        # extent of a disc of radius r normal to a, along each world axis: r * sqrt(1 - a_i^2)
        disc = self.radius * np.sqrt(np.clip(1.0 - a * a, 0.0, 1.0))
        ext = half + disc
        return np.stack([self.center - ext, self.center + ext])

    @property
    def closed(self) -> bool:
        """The ``"outside"`` wall bounds a solid rod (with or without drawn caps); a bore's
        wall (``"inside"``) bounds the hole the probe may enter, not a solid."""
        return self.surface == "outside"

    @property
    def bore(self) -> bool:
        """A bore (``"inside"``) is a hole: a probe inside it is not inside the material."""
        return self.surface == "inside"

    def _contains(self, points: FloatArray) -> NDArray[np.bool_]:
        f = points - self.center
        axial = f @ self.axis
        radial = f - axial[:, None] * self.axis
        inside_wall = np.einsum("ij,ij->i", radial, radial) < self.radius**2
        return inside_wall & (np.abs(axial) < 0.5 * self.length)

    def _intersect_soa(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        a, r, half = self.axis, self.radius, 0.5 * self.length
        eps = self._eps
        f = o - self.center[:, None]
        fa = a[0] * f[0] + a[1] * f[1] + a[2] * f[2]
        da = a[0] * d[0] + a[1] * d[1] + a[2] * d[2]
        f_perp = f - a[:, None] * fa
        d_perp = d - a[:, None] * da
        aa = _dot(d_perp, d_perp)
        bb = _dot(f_perp, d_perp)
        cc = _dot(f_perp, f_perp) - r * r
        # (f x d) . a, the signed area spanned in the plane normal to the axis
        cross_a = (
            a[0] * (f[1] * d[2] - f[2] * d[1])
            + a[1] * (f[2] * d[0] - f[0] * d[2])
            + a[2] * (f[0] * d[1] - f[1] * d[0])
        )
        disc = aa * r * r - cross_a * cross_a
        ok = (aa > GRAZING_COS**2) & (disc >= 0.0)
        root = np.sqrt(np.where(ok, disc, 0.0))
        q = -(bb + np.where(bb >= 0.0, root, -root))
        t1 = np.divide(q, aa, out=np.full_like(q, np.inf), where=ok)
        t2 = np.divide(cc, q, out=t1.copy(), where=ok & (q != 0.0))
        # entering root (smaller) is the outer face, exiting root the inner face
        t_wall = np.minimum(t1, t2) if self.surface == "outside" else np.maximum(t1, t2)
        axial = fa + np.where(ok, t_wall, 0.0) * da
        best = np.where(ok & (t_wall > eps) & (np.abs(axial) <= half), t_wall, np.inf)
        kind = np.zeros(len(best), dtype=np.int8)  # 0 wall, 1 cap at +half, 2 cap at -half
        if self.caps:
            cap_ok = np.abs(da) > GRAZING_COS
            safe_da = np.where(cap_ok, da, 1.0)
            for code, level, outward in ((1, half, 1.0), (2, -half, -1.0)):
                t_cap = (level - fa) / safe_da
                p = f_perp + t_cap * d_perp
                inside_disc = _dot(p, p) <= r * r
                from_outside = outward * da < 0.0  # arriving on the outer face of this cap
                side_ok = from_outside if self.surface == "outside" else ~from_outside
                better = cap_ok & (t_cap > eps) & inside_disc & side_ok & (t_cap < best)
                best = np.where(better, t_cap, best)
                kind = np.where(better, code, kind)
        hit = best < np.inf
        radial = (f_perp + np.where(hit, best, 0.0) * d_perp) / r
        radial /= np.maximum(np.sqrt(_dot(radial, radial)), 1e-300)
        if self.caps:
            cap_sign = np.where(kind == 1, 1.0, -1.0)
            normal = np.where(kind == 0, radial, a[:, None] * cap_sign)
        else:
            normal = radial
        return best, _signed_normals(normal, d, hit)

    def __repr__(self) -> str:
        c = ", ".join(f"{v:g}" for v in self.center)
        return (
            f"Cylinder(name={self.name!r}, center=[{c}], radius={self.radius:g}, "
            f"length={self.length:g}, azimuth={self.azimuth:g}, "
            f"coelevation={self.coelevation:g}, surface={self.surface!r}, caps={self.caps})"
        )
