"""Exhaustive grid search: the "manual calibration" baseline of the thesis introduction.

The grid spans x0 ± ``span`` [deg] in both angles with spacing ``step``
[deg] (clipped to the bounds, duplicates removed); each iteration measures
one row of the grid.  ``recommend()`` is the grid node with the highest
3 × 3 neighbourhood mean (a little smoothing against noise, as an operator
looking at the whole map would do), falling back to the best single value
at the edge of a partial grid.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal._validate import positive_float
from echocal.calibrate._fd import FloatArray
from echocal.calibrate.base import Optimizer
from echocal.calibrate.registry import register_method

__all__ = ["GridSearch"]


@register_method("grid")
class GridSearch(Optimizer):
    """Row-by-row grid search over x0 ± span with spacing step [deg]."""

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
        n = int(np.floor(self.span / self.step + 1e-9))
        offs = np.arange(-n, n + 1) * self.step
        a0 = np.unique(np.clip(self.x0[0] + offs, *self.bounds[0]))
        a1 = np.unique(np.clip(self.x0[1] + offs, *self.bounds[1]))
        self.axes = [a0, a1]
        self.values = np.full((len(a1), len(a0)), np.nan)
        """Measured grid [energy units, normalized], shape (n_axis1, n_axis0); NaN = not yet."""
        self._row = 0

    @property
    def batch_size(self) -> int:  # type: ignore[override]
        return len(self.axes[0])

    @property
    def n_points(self) -> int:
        """Number of grid nodes."""
        return self.values.size

    def _ask(self) -> FloatArray:
        a0, a1 = self.axes
        return np.stack([a0, np.full(len(a0), a1[self._row])], axis=1)

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        self.values[self._row] = values
        self._row += 1
        if self._row == len(self.axes[1]):
            self.finished = True
            self.finish_status = 5
        self._iterate = self._recommend()
        return True

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
