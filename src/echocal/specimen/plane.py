"""Finite rectangular plane, thesis §2.2 (eqs. 13–23)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal.geometry import orientation_frame
from echocal.specimen.base import (
    GRAZING_COS,
    FloatArray,
    Shape,
    _angle,
    _check_name,
    _point,
    _size,
)

__all__ = ["FinitePlane"]


class FinitePlane(Shape):
    """A two-sided rectangle: centre, width × height, orientation of its normal.

    The plane's frame is :func:`echocal.geometry.orientation_frame` of
    ``(azimuth, coelevation)``: its normal is n (thesis eq. 8), its width runs
    along the frame's x' axis and its height along y' (thesis eqs. 19–20).

    Intersection (thesis eq. 21, with the numerator of the text — see
    DESIGN.md errata)::

        t' = nᵀ(p₀ − s) / nᵀd,   m = Tᵀ(s + t'd − p₀),   |m₀| <= w/2,  |m₁| <= h/2

    A ray parallel to the plane (``|nᵀd| <= GRAZING_COS``) misses it; so does a
    plane behind the ray's source (``t' <= eps``).  Both faces reflect.

    Parameters
    ----------
    center : [m], shape (3,)
    width, height : [m] extents along x' and y', > 0.
    azimuth, coelevation : [deg] orientation of the normal.
    name : label used in plots and reports.
    """

    kind = "plane"

    def __init__(
        self,
        *,
        center: ArrayLike,
        width: float,
        height: float,
        azimuth: float = 0.0,
        coelevation: float = 0.0,
        name: str = "plane",
    ) -> None:
        owner = "FinitePlane"
        self.center = _point(owner, "center", center)
        self.width = _size(owner, "width", width)
        self.height = _size(owner, "height", height)
        self.azimuth = _angle(owner, "azimuth", azimuth)
        self.coelevation = _angle(owner, "coelevation", coelevation)
        self.name = _check_name(owner, name)
        frame = orientation_frame(self.azimuth, self.coelevation)
        self.x_axis: FloatArray = frame[:, 0].copy()
        self.y_axis: FloatArray = frame[:, 1].copy()
        self.normal: FloatArray = frame[:, 2].copy()
        self._eps = self.eps

    def corners(self) -> FloatArray:
        """The four corners [m], shape (4, 3), in order around the rectangle."""
        hx = 0.5 * self.width * self.x_axis
        hy = 0.5 * self.height * self.y_axis
        c = self.center
        return np.stack([c - hx - hy, c + hx - hy, c + hx + hy, c - hx + hy])

    def bounds(self) -> FloatArray:
        hx = 0.5 * self.width * np.abs(self.x_axis)
        hy = 0.5 * self.height * np.abs(self.y_axis)
        return np.stack([self.center - hx - hy, self.center + hx + hy])

    def _intersect(
        self, origins: FloatArray, directions: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        n = self.normal
        n_dot_d = directions @ n
        rel = self.center - origins  # p0 - s, (M, 3)
        numer = rel @ n
        ok = np.abs(n_dot_d) > GRAZING_COS
        t = np.divide(numer, n_dot_d, out=np.full_like(numer, np.inf), where=ok)
        ok &= t > self._eps
        # local coordinates of the hit: m = T^T (s + t d - p0) = t T^T d - T^T (p0 - s)
        t_safe = np.where(ok, t, 0.0)
        a = t_safe * (directions @ self.x_axis) - rel @ self.x_axis
        b = t_safe * (directions @ self.y_axis) - rel @ self.y_axis
        ok &= (np.abs(a) <= 0.5 * self.width) & (np.abs(b) <= 0.5 * self.height)
        distance = np.where(ok, t, np.inf)
        # normal facing the ray: -sign(n.d) n  (zero for misses)
        sign = np.where(ok, -np.sign(n_dot_d), 0.0)
        return distance, sign[:, None] * n

    def __repr__(self) -> str:
        c = ", ".join(f"{v:g}" for v in self.center)
        return (
            f"FinitePlane(name={self.name!r}, center=[{c}], width={self.width:g}, "
            f"height={self.height:g}, azimuth={self.azimuth:g}, coelevation={self.coelevation:g})"
        )
