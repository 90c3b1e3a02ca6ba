"""Finite-difference stencils in 2-D (private): thesis eqs. 38–45 and 58–73."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

_CROSS = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
_NINE = np.array(
    [
        [0.0, 0.0],  # y0 (64)
        [1.0, 0.0],  # y+(1) (58)
        [-1.0, 0.0],  # y-(1) (59)
        [0.0, 1.0],  # y+(2) (60)
        [0.0, -1.0],  # y-(2) (61)
        [1.0, 1.0],  # y11 (65)
        [1.0, -1.0],  # y12 (66)
        [-1.0, 1.0],  # y21 (67)
        [-1.0, -1.0],  # y22 (68)
    ]
)


def cross_points(center: FloatArray, delta: float) -> FloatArray:
    """The 4 points θ ± δ e_i [deg], shape (4, 2), ordered (+1, −1, +2, −2) (eqs. 42–45)."""
    return center[None, :] + delta * _CROSS


def cross_gradient(values: FloatArray, points: FloatArray) -> FloatArray:
    """Central-difference gradient, shape (2,), from :func:`cross_points` values (eqs. 38–39).

    ``points`` [deg], shape (4, 2), are the points actually measured: near an angle bound
    the stencil is clipped, and each difference is divided by the real distance of its
    pair (2δ when nothing was clipped); a pair collapsed onto one point gives 0.
    """
    span = np.array([points[0, 0] - points[1, 0], points[2, 1] - points[3, 1]])
    rise = np.array([values[0] - values[1], values[2] - values[3]])
    return np.divide(rise, span, out=np.zeros(2), where=span > 0.0)


def nine_points(center: FloatArray, delta: float) -> FloatArray:
    """The 9 points of the FD Hessian stencil [deg], shape (9, 2) (eqs. 58–68)."""
    return center[None, :] + delta * _NINE


def nine_gradient_hessian(values: FloatArray, points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Gradient (2,) and Hessian (2, 2) from :func:`nine_points` values.

    Eqs. 62–63 and 70–73 with the erratum h22 = (y+(2) − 2 y0 + y−(2)) / δ², written for
    the points actually measured (``points`` [deg], shape (9, 2)): with a = x₊ − x₀ and
    b = x₀ − x₋ along an axis (both δ unless a bound clipped the stencil)

        g = (b²(y₊ − y₀) + a²(y₀ − y₋)) / (a b (a + b)),
        h = 2((y₊ − y₀)/a − (y₀ − y₋)/b) / (a + b),

    which reduce to the thesis's formulas for a = b = δ.  An axis clipped onto the centre
    (a or b = 0) keeps a one-sided gradient and reports no curvature (h = 0, which Newton's
    damping treats as not negative definite).
    """
    y0, y1p, y1m, y2p, y2m, y11, y12, y21, y22 = values
    c = points[0]
    g, h = np.zeros(2), np.zeros((2, 2))
    for axis, (yp, ym, ip, im) in enumerate(((y1p, y1m, 1, 2), (y2p, y2m, 3, 4))):
        a, b = points[ip, axis] - c[axis], c[axis] - points[im, axis]
        if a > 0.0 and b > 0.0:
            g[axis] = (b * b * (yp - y0) + a * a * (y0 - ym)) / (a * b * (a + b))
            h[axis, axis] = 2.0 * ((yp - y0) / a - (y0 - ym) / b) / (a + b)
        elif a > 0.0:
            g[axis] = (yp - y0) / a
        elif b > 0.0:
            g[axis] = (y0 - ym) / b
    area = (points[5, 0] - points[7, 0]) * (points[5, 1] - points[6, 1])
    if area > 0.0:
        h[0, 1] = h[1, 0] = (y11 - y12 - y21 + y22) / area
    return g, h


def cap_step(step: FloatArray, max_step: float | None) -> FloatArray:
    """Scale ``step`` [deg] down to length ``max_step`` if it is longer."""
    if max_step is None:
        return step
    norm = float(np.hypot(*step))
    return step * (max_step / norm) if norm > max_step else step


def trapezoid_rise(g_old: FloatArray, g_new: FloatArray, step: FloatArray) -> float:
    """Trapezoid estimate ½(ĝ_old + ĝ_new)ᵀs of f(θ + s) − f(θ) [energy units].

    g_old, g_new : gradients, shape (2,), at θ and θ + s; step : s [deg], shape (2,).
    Exact for quadratics; Newton and quasi-Newton reject a candidate with a negative rise.
    """
    return 0.5 * float((g_old + g_new) @ step)
