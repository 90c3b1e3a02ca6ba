"""Finite-difference gradient ascent, momentum and Nesterov (thesis eqs. 38–49).

Each iteration measures the 4 points θ ± δ e_i (eqs. 42–45) and estimates the gradient by
central differences (eqs. 38–39).  Updates:

* ``gradient``: θ ← θ + μ ĝ(θ) (eqs. 40–41);
* ``momentum``: v ← η v + μ ĝ(θ); θ ← θ + v (eqs. 46–47);
* ``nesterov``: v ← η v + μ ĝ(θ + η v); θ ← θ + v (eqs. 48–49) — the stencil is centred on
  the look-ahead point θ + η v.

Gains are scale-free: with ``mu=None`` (default) the step size is calibrated on the first
gradient so that the first step is ``first_step`` degrees long (μ = first_step / |ĝ₀|),
whatever the energy unit.  With an explicit ``mu`` (thesis presets: 0.05) use
``normalize="max"`` so energy is ~1 at the peak.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal.calibrate._fd import FloatArray, cap_step, cross_gradient, cross_points
from echocal.calibrate._options import in_range, positive_float
from echocal.calibrate.base import Optimizer
from echocal.calibrate.registry import register_method

__all__ = ["GradientAscent", "Momentum", "Nesterov"]


class _FDAscent(Optimizer):
    """Finite-difference gradient ascent, 4 measurements per iteration.

    Parameters
    ----------
    mu : [deg² / energy] step size μ; None calibrates it from the first gradient so the
        first step is ``first_step`` long.
    delta : [deg] finite-difference step δ.
    momentum : momentum η in [0, 1) (None: the method's default).
    first_step : [deg] length of the first step when ``mu`` is calibrated.
    max_step : [deg] cap on a step's length (None: no cap).
    """

    batch_size = 4
    _nesterov = False
    _default_momentum = 0.0

    def __init__(
        self,
        x0: ArrayLike,
        *,
        mu: float | None = None,
        delta: float = 0.25,
        momentum: float | None = None,
        first_step: float = 0.5,
        max_step: float | None = None,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize=normalize)
        self.mu = None if mu is None else positive_float("mu", mu)
        self.delta = positive_float("delta", delta)
        eta = self._default_momentum if momentum is None else momentum
        self.momentum = in_range("momentum", eta, 0.0, 0.999)
        self.first_step = positive_float("first_step", first_step)
        self.max_step = None if max_step is None else positive_float("max_step", max_step)
        self._v = np.zeros(2)
        self.gradient: FloatArray | None = None
        """Last gradient estimate [energy / deg], shape (2,) (normalized units)."""

    def _center(self) -> FloatArray:
        if self._nesterov:
            return self._iterate + self.momentum * self._v
        return self._iterate

    def _ask(self) -> FloatArray:
        return cross_points(self._center(), self.delta)

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        g = cross_gradient(values, points)
        self.gradient = g
        if self.mu is None:
            norm = float(np.hypot(*g))
            if norm == 0.0:
                return True  # flat: no information to calibrate the gain yet
            self.mu = self.first_step / norm
        self._v = cap_step(self.momentum * self._v + self.mu * g, self.max_step)
        self._iterate = self.clip(self._iterate + self._v)
        return True


@register_method("gradient")
class GradientAscent(_FDAscent):
    """FD stochastic gradient ascent (eqs. 38–45), 4 measurements per iteration."""


@register_method("momentum")
class Momentum(_FDAscent):
    """Gradient ascent with momentum η (eqs. 46–47; default η = 0.7, thesis Table 7)."""

    _default_momentum = 0.7


@register_method("nesterov")
class Nesterov(_FDAscent):
    """Nesterov accelerated gradient (eqs. 48–49): gradient at θ + η v; default η = 0.7."""

    _default_momentum = 0.7
    _nesterov = True
