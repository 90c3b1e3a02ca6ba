"""Newton's method with a finite-difference Hessian (thesis eqs. 58–74, corrected).

Each iteration measures the 9-point stencil around the candidate θ (eqs. 58–68) and builds ĝ
and H with the erratum h22 = (y₊⁽²⁾ − 2y⁽⁰⁾ + y₋⁽²⁾)/δ². Maximizing, the step is d = −H⁻¹ĝ,
which ascends only where H is negative definite.  Elsewhere (``damping="levenberg"``,
default) H is shifted to H − λI with λ chosen so that the largest eigenvalue becomes
−max(|eig|, |ĝ|/max_step): an ascent direction of bounded length.  ``damping="gradient"``
instead takes a gradient step of length ``max_step``.  θ ← θ + μ d, |μ d| ≤ ``max_step``.

Never stepping downhill silently: the stencil at a new candidate measures its centre y⁽⁰⁾;
if it is lower than at the current iterate *and* the trapezoid estimate ½(ĝ_old + ĝ_new)ᵀs
of the change (exact for quadratics) is negative, the candidate is rejected: the iterate
stays, and the next candidate is half the step from it.  Rejections are counted
(``n_rejected``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal._validate import one_of
from echocal.calibrate._fd import (
    FloatArray,
    cap_step,
    nine_gradient_hessian,
    nine_points,
    trapezoid_rise,
)
from echocal.calibrate._options import positive_float
from echocal.calibrate.base import Optimizer
from echocal.calibrate.registry import register_method

__all__ = ["Newton", "newton_direction"]


def newton_direction(
    g: FloatArray, h: FloatArray, *, max_step: float, damping: str = "levenberg"
) -> tuple[FloatArray, bool]:
    """Ascent direction for maximization and whether H was negative definite.

    g : gradient, shape (2,); h : Hessian, shape (2, 2) (symmetrized here).
    """
    h = 0.5 * (h + h.T)
    eig = np.linalg.eigvalsh(h)
    scale = max(float(np.abs(eig).max()), 1e-300)
    if eig[-1] < -1e-9 * scale:
        return np.asarray(-np.linalg.solve(h, g), dtype=np.float64), True
    gnorm = float(np.hypot(*g))
    if gnorm == 0.0:
        return np.zeros(2), False
    if damping == "gradient":
        return g * (max_step / gnorm), False
    target = max(scale, gnorm / max_step)
    lam = eig[-1] + target
    return -np.linalg.solve(h - lam * np.eye(2), g), False


@register_method("newton")
class Newton(Optimizer):
    """FD Newton ascent, 9 measurements per iteration.

    Parameters
    ----------
    mu : step multiplier (thesis Table 5: 0.05; default 1, the full Newton step).
    delta : difference step δ [deg] (larger δ averages noise in the Hessian).
    max_step : [deg] cap on a step length.
    damping : ``"levenberg"`` or ``"gradient"`` where H is not negative definite.
    """

    batch_size = 9

    def __init__(
        self,
        x0: ArrayLike,
        *,
        mu: float = 1.0,
        delta: float = 0.5,
        max_step: float = 2.0,
        damping: str = "levenberg",
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize=normalize)
        self.mu = positive_float("mu", mu)
        self.delta = positive_float("delta", delta)
        self.max_step = positive_float("max_step", max_step)
        self.damping = one_of("damping", damping, ("levenberg", "gradient"))
        self._candidate = self._iterate.copy()
        self._state: tuple[float, FloatArray, FloatArray] | None = None  # y0, g, H at iterate
        self._step = np.zeros(2)
        self.n_rejected = 0
        self.n_indefinite = 0

    @property
    def proposed_step(self) -> float:
        """Length [deg] of the step to the next candidate (used by the xtol rule)."""
        return float(np.hypot(*(self._candidate - self._iterate)))

    @property
    def concave(self) -> bool | None:
        """True when the FD Hessian measured at the iterate is negative definite."""
        if self._state is None:
            return None
        h = self._state[2]
        return bool(np.linalg.eigvalsh(0.5 * (h + h.T))[-1] < 0.0)

    def _ask(self) -> FloatArray:
        return nine_points(self._candidate, self.delta)

    def _propose(self, g: FloatArray, h: FloatArray, limit: float) -> None:
        d, nd = newton_direction(g, h, max_step=self.max_step, damping=self.damping)
        if not nd:
            self.n_indefinite += 1
        self._step = cap_step(self.mu * d, limit)
        self._candidate = self.clip(self._iterate + self._step)

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        g, h = nine_gradient_hessian(values, points)
        y0 = float(values[0])
        if self._state is not None:
            y_old, g_old, _h_old = self._state
            s = self._candidate - self._iterate
            if y0 < y_old and trapezoid_rise(g_old, g, s) < 0.0:
                self.n_rejected += 1
                half = 0.5 * float(np.hypot(*s))
                self._step = cap_step(s, half)
                self._candidate = self.clip(self._iterate + self._step)
                return True
        self._iterate = self._candidate.copy()
        self._state = (y0, g, h)
        self._propose(g, h, self.max_step)
        return True
