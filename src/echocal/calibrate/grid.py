"""Exhaustive grid search: the "manual calibration" baseline of the thesis introduction.

The grid spans x0 ± ``span`` [deg] in both angles with spacing ``step`` [deg] (clipped to
the bounds, duplicates removed); each iteration measures one row of the grid, and
:func:`~echocal.calibrate.calibrate` runs until every row is measured (an explicit
``max_iter`` or the budget may stop it earlier, with a warning).  ``recommend()`` is the
grid node with the highest 3 × 3 neighbourhood mean (a little smoothing against noise, as an
operator looking at the whole map would do), falling back to the best single value at the
edge of a partial grid.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import positive_float
from echocal.calibrate.base import Optimizer
from echocal.calibrate.registry import register_method
from echocal.errors import EchocalValueError

__all__ = ["MAX_GRID_POINTS", "GridSearch"]


MAX_GRID_POINTS = 100_000
"""The largest grid a grid search accepts: 100 000 measurements are hours on an instrument
(and a larger grid usually means a mistyped span or step)."""


def _inside(center: float, n: float, step: float, lo: float, hi: float) -> tuple[float, float]:
    """The range k_min..k_max (floats) of the nodes ``center + k·step``, |k| <= n, that lie
    within [lo, hi] (k_min > k_max when none does)."""
    k_lo = -n if not np.isfinite(lo) else max(-n, np.ceil((lo - center) / step))
    k_hi = n if not np.isfinite(hi) else min(n, np.floor((hi - center) / step))
    return float(k_lo), float(k_hi)


def _axis_count(center: float, n: float, step: float, lo: float, hi: float) -> float:
    """Upper bound on the nodes of one axis (computed without building it): the nodes
    within the bounds, plus the two bounds where nodes beyond them are clipped."""
    k_lo, k_hi = _inside(center, n, step, lo, hi)
    return max(0.0, k_hi - k_lo + 1.0) + float(k_lo > -n) + float(k_hi < n)


def _axis(center: float, n: int, step: float, lo: float, hi: float) -> FloatArray:
    """The nodes ``center + k·step``, |k| <= n, clipped to [lo, hi] and deduplicated, built
    from the nodes inside the bounds only (the same values as clipping all 2n + 1)."""
    k_lo, k_hi = (int(k) for k in _inside(center, float(n), step, lo, hi))
    k_lo, k_hi = max(k_lo - 1, -n), min(k_hi + 1, n)  # floating point at the bounds
    offs = np.arange(k_lo, k_hi + 1) * step
    nodes = np.clip(center + offs, lo, hi)
    extra = [lo] * (k_lo > -n) + [hi] * (k_hi < n)  # clipped nodes beyond the bounds
    return np.unique(np.concatenate([nodes, extra]))


@register_method("grid")
class GridSearch(Optimizer):
    """Row-by-row grid search over x0 ± span with spacing step [deg].

    The grid is clipped to the bounds; one of more than :data:`MAX_GRID_POINTS` nodes
    inside them is refused (EchocalValueError naming span and step) before anything is
    allocated or measured.

    Parameters
    ----------
    span : [deg] half-width of the grid around x0 in each angle.
    step : [deg] spacing of the grid's nodes.
    """

    def __init__(
        self,
        x0: ArrayLike,
        *,
        span: float = 5.0,
        step: float = 0.5,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize=normalize)
        self.span = positive_float("span", span)
        self.step = positive_float("step", step)
        n = np.floor(self.span / self.step + 1e-9)  # nodes each side of x0 (a float: may be huge)
        counts = [
            _axis_count(c, n, self.step, *b) for c, b in zip(self.x0, self.bounds, strict=True)
        ]
        total = counts[0] * counts[1]
        if not total <= MAX_GRID_POINTS:
            raise EchocalValueError(
                f"grid: span={self.span:g} deg with step={self.step:g} deg makes "
                f"{counts[0]:.4g} x {counts[1]:.4g} = {total:.4g} grid points inside the "
                f"bounds; a grid search measures every one, so at most {MAX_GRID_POINTS} are "
                f"allowed: use a smaller span or a larger step (span=5, step=0.5: 441 points)"
            )
        self.axes = [
            _axis(c, int(n), self.step, *b) for c, b in zip(self.x0, self.bounds, strict=True)
        ]
        self.values = np.full((len(self.axes[1]), len(self.axes[0])), np.nan)
        """Measured grid [energy units, normalized], shape (n_axis1, n_axis0); NaN = not yet."""
        self._row = 0

    @property
    def batch_size(self) -> int:  # type: ignore[override]
        return len(self.axes[0])

    @property
    def n_points(self) -> int:
        """Number of grid nodes."""
        return self.values.size

    @property
    def n_rows(self) -> int:
        """Number of grid rows — iterations — it takes to measure the whole grid; the driver
        runs that many (the default iteration limit, the settle and xtol rules do not cut
        an exhaustive search short)."""
        return self.values.shape[0]

    def _ask(self) -> FloatArray:
        a0, a1 = self.axes
        return np.stack([a0, np.full(len(a0), a1[self._row])], axis=1)

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        self.values[self._row] = values
        self._row += 1
        self._iterate = self._recommend()
        if self._row == len(self.axes[1]):
            self.finished = True
            self.finish_status = 5
            self._warn_on_edge()
        return True

    def _warn_on_edge(self) -> None:
        """Warn when the best node of the whole grid lies on its outer edge: the maximum may
        lie beyond it (a larger span, or x0 moved towards it, would show)."""
        (a0, a1), best = self.axes, self._iterate
        if len(a0) < 3 or len(a1) < 3:
            return
        (lo0, hi0), (lo1, hi1) = self.bounds  # an edge clipped at a bound: widening can't help
        edges = {a0[0], a0[-1]} - {lo0, hi0}, {a1[0], a1[-1]} - {lo1, hi1}
        if best[0] in edges[0] or best[1] in edges[1]:
            warnings.warn(
                f"grid: the best node ({best[0]:.4g}, {best[1]:.4g}) deg lies on the grid's "
                f"edge, so the maximum may lie outside it: widen span (now {self.span:g} deg) "
                "or start nearer the echo",
                UserWarning,
                stacklevel=4,
            )

    def _recommend(self) -> FloatArray:
        v = self.values
        if np.all(np.isnan(v)):
            return self.x0
        pad = np.pad(v, 1, constant_values=np.nan)
        stack = np.stack(
            [
                pad[1 + i : 1 + i + v.shape[0], 1 + j : 1 + j + v.shape[1]]
                for i in (-1, 0, 1)
                for j in (-1, 0, 1)
            ]
        )
        ok = np.isfinite(stack)
        cnt = ok.sum(axis=0)
        mean = np.where(cnt > 0, np.where(ok, stack, 0.0).sum(axis=0) / np.maximum(cnt, 1), -np.inf)
        mean = np.where(np.isfinite(v), mean, -np.inf)
        i, j = np.unravel_index(int(np.argmax(mean)), v.shape)
        return np.array([self.axes[0][j], self.axes[1][i]])
