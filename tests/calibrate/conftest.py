"""Known-solution problems for the calibration tests (analytic truth, stated optima)."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.calibrate import FunctionObjective

OPT = np.array([0.7, -0.4])
"""Optimum [deg] of both test problems (off the origin on purpose)."""

_Q = np.array([[1.0, 0.3], [0.3, 2.0]])  # negative Hessian / 2 of the quadratic (SPD)


def quadratic(points: np.ndarray) -> np.ndarray:
    """Concave quadratic 10 − (x − x*)ᵀ Q (x − x*), maximum 10 at OPT."""
    d = np.atleast_2d(points) - OPT
    return 10.0 - np.einsum("ki,ij,kj->k", d, _Q, d)


def gaussian(points: np.ndarray, *, peak: float = 3.7, width: float = 1.0) -> np.ndarray:
    """Gaussian peak of height ``peak`` [arbitrary energy] and width [deg] at OPT."""
    d = np.atleast_2d(points) - OPT
    return peak * np.exp(-np.sum(d**2, axis=1) / (2.0 * width**2))


@pytest.fixture
def quad_objective():
    def make(**kw):
        return FunctionObjective(quadratic, optimum=OPT, **kw)

    return make


@pytest.fixture
def gauss_objective():
    def make(**kw):
        return FunctionObjective(gaussian, optimum=OPT, **kw)

    return make
