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


def cross_gradient(values: FloatArray, delta: float) -> FloatArray:
    """Central-difference gradient, shape (2,), from :func:`cross_points` values (eqs. 38–39)."""
    return np.array([values[0] - values[1], values[2] - values[3]]) / (2.0 * delta)


def nine_points(center: FloatArray, delta: float) -> FloatArray:
    """The 9 points of the FD Hessian stencil [deg], shape (9, 2) (eqs. 58–68)."""
    return center[None, :] + delta * _NINE


def nine_gradient_hessian(values: FloatArray, delta: float) -> tuple[FloatArray, FloatArray]:
    """Gradient (2,) and Hessian (2, 2) from :func:`nine_points` values.

    Eqs. 62–63 and 70–73 with the erratum h22 = (y+(2) − 2 y0 + y−(2)) / δ².
    """
    y0, y1p, y1m, y2p, y2m, y11, y12, y21, y22 = values
    g = np.array([y1p - y1m, y2p - y2m]) / (2.0 * delta)
    h11 = (y1p - 2.0 * y0 + y1m) / delta**2
    h22 = (y2p - 2.0 * y0 + y2m) / delta**2
    h12 = (y11 - y12 - y21 + y22) / (4.0 * delta**2)
    return g, np.array([[h11, h12], [h12, h22]])


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
