"""Ask/tell optimizer base (nevergrad style): the base owns order, counters and NaN policy.

Subclasses implement ``_ask() -> points (k, 2)`` and ``_tell(points, values) -> bool`` (True
when the call completed an iteration, i.e. the iterate may have moved; False for setup
batches such as SPSA gain calibration or acquisition rings), optionally ``_recommend()``.

NaN policy: a failed measurement is never handed to a method as a number silently: it is
counted (``n_nan``), flagged in ``last_nan`` (shape (k,)) and replaced by the *worst* value
seen so far, capped at 0 — "no evidence of an echo there" (the model-based method leaves
it out of its fit).

Normalization: the thesis's gains (step μ = 0.05) assume a peak of about 1; ``normalize``
divides every value handed to a method by ``"none"`` 1, ``"first"`` the first finite
non-zero |value|, or ``"max"`` the running maximum of |values| (updated before each tell).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._rng import RngLike, as_generator
from echocal._validate import one_of
from echocal.calibrate.objective import as_bounds, as_points
from echocal.errors import EchocalValueError

__all__ = ["NORMALIZE_MODES", "Optimizer"]

FloatArray = NDArray[np.float64]

NORMALIZE_MODES = ("none", "first", "max")


class Optimizer:
    """Base of every calibration method (maximization of f over 2 angles [deg]).

    Parameters
    ----------
    x0 : [deg], shape (2,) — the starting orientation.
    bounds : [deg], shape (2, 2), or None; asked points are clipped into them.
    rng : seed or Generator (used by randomized methods).
    normalize : ``"none"``, ``"first"`` or ``"max"`` (see module docstring).
    """

    name: ClassVar[str] = "optimizer"
    batch_size: ClassVar[int] = 1
    """Measurements per regular iteration."""

    def __init__(
        self,
        x0: ArrayLike,
        *,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        self.x0 = as_points("x0", x0)[0]
        self.bounds = as_bounds(bounds)
        self.rng = as_generator(rng)
        self.normalize = one_of("normalize", normalize, NORMALIZE_MODES)
        self._iterate = self.x0.copy()
        self._pending: FloatArray | None = None
        self._scale = 1.0
        self._scale_set = False
        self._worst = np.inf
        self.n_asks = 0
        self.n_tells = 0
        self.n_iterations = 0
        self.n_told = 0
        self.n_nan = 0
        self.last_nan = np.zeros(0, dtype=bool)
        self.finished = False
        """True when the method has nothing left to do (e.g. the grid is complete)."""
        self.finish_status: int | None = None
        """Status code (see :mod:`echocal.calibrate.result`) when ``finished``."""

    # -- contract for subclasses ---------------------------------------------------------
    def _ask(self) -> ArrayLike:  # pragma: no cover - abstract
        raise NotImplementedError

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:  # pragma: no cover
        raise NotImplementedError

    def _recommend(self) -> FloatArray:
        return self._iterate

    @property
    def min_budget(self) -> int:
        """Measurements the first iteration needs (setup batches included)."""
        return self.batch_size

    # -- public ------------------------------------------------------------------------
    @property
    def iterate(self) -> FloatArray:
        """Current iterate [deg], shape (2,)."""
        return np.array(self._iterate, dtype=np.float64)

    @property
    def pending(self) -> FloatArray | None:
        """Points asked and not yet told [deg], shape (k, 2), or None."""
        return None if self._pending is None else self._pending.copy()

    def clip(self, points: ArrayLike) -> FloatArray:
        """Clip points [deg], shape (..., 2), into the bounds."""
        return np.clip(np.asarray(points, dtype=np.float64), self.bounds[:, 0], self.bounds[:, 1])

    def ask(self) -> FloatArray:
        """Return the next points to measure [deg], shape (k, 2).

        Raises EchocalValueError if the previous ask has not been told yet.
        """
        if self._pending is not None:
            raise EchocalValueError(
                f"ask() called again before tell(): {len(self._pending)} value(s) for the "
                "previous ask are still expected"
            )
        if self.finished:
            raise EchocalValueError(f"{self.name}: the method has finished; nothing to ask")
        pts = self.clip(as_points("asked points", self._ask()))
        self._pending = pts
        self.n_asks += 1
        return pts.copy()

    def tell(self, values: ArrayLike) -> bool:
        """Report the values measured at the last asked points; return True if an
        iteration was completed.

        values : [energy units], shape (k,) with k the number of asked points; NaN allowed.
        """
        if self._pending is None:
            raise EchocalValueError("tell() called without a pending ask(); call ask() first")
        try:
            vals = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError):
            raise EchocalValueError(f"values must be numeric; got {values!r}") from None
        k = len(self._pending)
        if vals.shape != (k,):
            raise EchocalValueError(
                f"tell() expects {k} value(s) of shape ({k},) for the asked points; "
                f"got shape {vals.shape}"
            )
        nan = ~np.isfinite(vals)
        finite = vals[~nan]
        if finite.size:
            self._worst = min(self._worst, float(finite.min()))
        fill = min(0.0, self._worst) if np.isfinite(self._worst) else 0.0
        vals = np.where(nan, fill, vals)
        self.n_nan += int(nan.sum())
        self.last_nan = nan
        if self.normalize == "first" and not self._scale_set:
            nz = np.abs(finite[finite != 0])
            if nz.size:
                self._scale = float(nz[0])
                self._scale_set = True
        elif self.normalize == "max" and finite.size:
            self._scale = max(self._scale if self._scale_set else 0.0, float(np.abs(finite).max()))
            if self._scale > 0:
                self._scale_set = True
            else:
                self._scale = 1.0
        pts = self._pending
        self._pending = None
        self.n_tells += 1
        self.n_told += k
        done = bool(self._tell(pts, vals / self._scale))
        if done:
            self.n_iterations += 1
        return done

    def recommend(self) -> FloatArray:
        """Best estimate of the maximizer [deg], shape (2,) (a model's or the
        iterate; never merely the luckiest noisy sample)."""
        return np.array(self.clip(self._recommend()), dtype=np.float64)

    def recommend_value(self) -> float | None:
        """The model's value at :meth:`recommend` in the caller's units, when a model exists."""
        return None

    @property
    def concave(self) -> bool | None:
        """Whether the method's model of f is concave at :meth:`recommend` and has its
        maximum there — evidence a convergence claim needs; None for a method without
        a model of the curvature."""
        return None
