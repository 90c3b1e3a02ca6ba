"""Finite rectangular plane, thesis §2.2 (eqs. 13–23)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal.geometry import orientation_frame
from echocal.specimen.base import (
    GRAZING_COS,
    KERNEL_PARAMS,
    KERNEL_PLANE,
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

    Intersection (thesis eq. 21, with the numerator of the text — see docs/physics.md,
    "The thesis's errata")::

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
        self._frame_t = np.ascontiguousarray(frame.T)  # rows x', y', n
        self._center_local = self._frame_t @ self.center
        self._eps = self.eps
        params = np.zeros(KERNEL_PARAMS)
        params[:9] = self._frame_t.ravel()
        params[9:12] = self._center_local
        params[12:15] = 0.5 * self.width, 0.5 * self.height, self._eps
        params.setflags(write=False)
        self._params = params

    def _kernel_params(self) -> tuple[int, FloatArray]:
        """Rows x', y', n of the frame (9), the centre in that frame (3), w/2, h/2, eps."""
        return KERNEL_PLANE, self._params

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

    def _intersect_soa(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        # local coordinates (x', y', n) of s - p0 and of d: rows of (3, M)
        s_loc = self._frame_t @ o
        s_loc -= self._center_local[:, None]
        d_loc = self._frame_t @ d
        n_dot_d = d_loc[2]
        # t' = n^T (p0 - s) / n^T d  (thesis eq. 21 with the text's numerator); rays with
        # |n^T d| <= GRAZING_COS are masked out, whatever their (inf, nan) quotient
        ok = np.abs(n_dot_d) > GRAZING_COS
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.divide(s_loc[2], n_dot_d)
            np.negative(t, out=t)
            ok &= t > self._eps
            # in-plane coordinates of the hit, m = T^T (s + t d - p0) (eq. 23): |m| <= w/2, h/2
            m = np.multiply(t, d_loc[0], out=d_loc[0])  # rows 0, 1 of d_loc are not needed after
            m += s_loc[0]
            ok &= np.abs(m, out=m) <= 0.5 * self.width
            m = np.multiply(t, d_loc[1], out=d_loc[1])
            m += s_loc[1]
            ok &= np.abs(m, out=m) <= 0.5 * self.height
        distance = np.where(ok, t, np.inf)
        # normal facing the ray: -sign(n.d) n, zero for misses
        sign = np.copysign(ok, -n_dot_d)
        return distance, self.normal[:, None] * sign

    def __repr__(self) -> str:
        c = ", ".join(f"{v:g}" for v in self.center)
        return (
            f"FinitePlane(name={self.name!r}, center=[{c}], width={self.width:g}, "
            f"height={self.height:g}, azimuth={self.azimuth:g}, coelevation={self.coelevation:g})"
        )
