"""Quasi-Newton (BFGS) ascent (thesis eqs. 75–78, applied to −f).

Eqs. 76–78 are BFGS for *minimization*; here B approximates the Hessian of −f (positive
definite), the step is Δθ = μ B⁻¹ ĝ (an ascent direction) and the update uses s = Δθ, y = −b
with b = ĝ_{k+1} − ĝ_k (eq. 77).  The curvature condition yᵀs > 0, i.e. bᵀΔθ < 0, keeps B
positive definite; an update with bᵀΔθ ≥ 0 is skipped (counted in ``n_skipped``).

Start: B₀ = λ I (thesis λ ∈ {0.1, 0.5, 0.8, 0.9} with μ = 0.05 on energy normalized to ~1).
With ``lam=None`` (default) λ = |ĝ₀| / first_step, so the first step is ``first_step``
degrees long whatever the energy unit.

Never stepping downhill: each iteration measures the 4-point FD gradient at the candidate;
the change of f along the step is estimated by the trapezoid rule ½(ĝ_k + ĝ_{k+1})ᵀs (exact
for quadratics).  A candidate with a negative estimate is rejected: the iterate stays, the
(valid) curvature pair still updates B, and the next step is at most half as long.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal.calibrate._fd import (
    FloatArray,
    cap_step,
    cross_gradient,
    cross_points,
    trapezoid_rise,
)
from echocal.calibrate._options import positive_float
from echocal.calibrate.base import Optimizer
from echocal.calibrate.registry import register_method

__all__ = ["QuasiNewton", "bfgs_update"]


def bfgs_update(b: FloatArray, s: FloatArray, y: FloatArray) -> FloatArray | None:
    """BFGS update of a positive-definite Hessian approximation ``b`` (2, 2) of a
    function being *minimized*; None when the curvature condition yᵀs > 0 fails."""
    ys = float(y @ s)
    if not ys > 1e-12 * float(np.linalg.norm(y) * np.linalg.norm(s)):
        return None
    bs = b @ s
    return b + np.outer(y, y) / ys - np.outer(bs, bs) / float(s @ bs)


@register_method("quasi-newton")
class QuasiNewton(Optimizer):
    """BFGS ascent with FD gradients, 4 measurements per iteration.

    Parameters
    ----------
    mu : step multiplier (thesis: 0.05; default 1).
    lam : λ of B₀ = λ I [energy / deg²]; None calibrates it from the first gradient.
    delta : difference step δ [deg].
    first_step : [deg] first step length when ``lam`` is calibrated.
    max_step : [deg] cap on a step length.
    """

    batch_size = 4

    def __init__(
        self,
        x0: ArrayLike,
        *,
        mu: float = 1.0,
        lam: float | None = None,
        delta: float = 0.25,
        first_step: float = 0.5,
        max_step: float = 2.0,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize=normalize)
        self.mu = positive_float("mu", mu)
        self.lam = None if lam is None else positive_float("lam", lam)
        self.delta = positive_float("delta", delta)
        self.first_step = positive_float("first_step", first_step)
        self.max_step = positive_float("max_step", max_step)
        self.hess: FloatArray | None = None
        """B, the approximation of the Hessian of −f, shape (2, 2)."""
        self._g: FloatArray | None = None
        self._candidate = self._iterate.copy()
        self._limit = self.max_step
        self.n_skipped = 0
        self.n_rejected = 0

    @property
    def proposed_step(self) -> float:
        """Length [deg] of the step to the next candidate (used by the xtol rule)."""
        return float(np.hypot(*(self._candidate - self._iterate)))

    def _ask(self) -> FloatArray:
        return cross_points(self._candidate, self.delta)

    def _propose(self) -> None:
        assert self.hess is not None and self._g is not None
        step = cap_step(np.asarray(self.mu * np.linalg.solve(self.hess, self._g)), self._limit)
        self._candidate = self.clip(self._iterate + step)

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        g = cross_gradient(values, points)
        if self._g is None:
            self._g = g
            norm = float(np.hypot(*g))
            lam = self.lam if self.lam is not None else max(norm, 1e-300) / self.first_step
            self.hess = lam * np.eye(2)
            if norm > 0.0:
                self._propose()
            return True
        assert self.hess is not None
        s = self._candidate - self._iterate
        if not np.any(s):
            self._g = g
            self._propose()
            return True
        new = bfgs_update(self.hess, s, -(g - self._g))
        if new is None:
            self.n_skipped += 1
        else:
            self.hess = new
        if trapezoid_rise(self._g, g, s) < 0.0:
            self.n_rejected += 1
            self._limit = 0.5 * float(np.hypot(*s))
        else:
            self._iterate = self._candidate.copy()
            self._g = g
            self._limit = self.max_step
        self._propose()
        return True
