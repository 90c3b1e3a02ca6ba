"""A lazily filled, interpolated table of an echo spectrum over two invariants.

Many echoes depend on a pose only through two numbers: an infinite plane's echo under an
axisymmetric probe through the plane's distance from the face and its tilt, a ball's
through the distance to its centre and the axis's angle off it.  Monte-Carlo studies, lobe
profiles, cost maps and sweeps evaluate thousands of A-scans at one setup, so the exact
spectrum is worth computing once per node of a uniform grid over the two invariants and
interpolating between nodes.

:class:`EchoTable` holds such a grid.  The caller gives the node function (the exact
spectrum at one (u, v), best demodulated so that what is tabled varies slowly: see the
callers in ``echocal.wave.model``) and the range of frequency bins worth keeping
(:func:`significant_bins`); each node is computed on first use and memoized.  A query at
(u, v) interpolates the (p + 1) × (p + 1) surrounding nodes, bin by bin, by tensor-product
Lagrange polynomials of degree p (cubic by default: 4 × 4 nodes), exact for any spectrum
that is a polynomial of degree ≤ p in u and in v; near the grid's ends the stencil shifts
inwards (still exact for such polynomials), or on an axis along which the spectrum is
even, reaches across its start to the mirrored nodes (``TableAxis.even``).  A real side
value per node (the echo's mean path time) is interpolated alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = ["EchoTable", "NodeStore", "TableAxis", "significant_bins"]

ComplexArray = NDArray[np.complex128]
NodeFunction = Callable[[float, float], tuple[ComplexArray, float]]
"""``node(u, v) -> (spectrum, side)``: the full one-sided spectrum ``(size,)`` and a real
side value at one grid node."""


class NodeStore(Protocol):
    """Where an :class:`EchoTable` keeps its nodes between processes (``DiskNodes`` in
    ``echocal.wave.table_cache``)."""

    def load(self, i: int, j: int, size: int) -> tuple[ComplexArray, float] | None:
        """Node (i, j)'s kept bins ``(size,)`` and side value, or None (a miss)."""

    def save(self, i: int, j: int, spectrum: ComplexArray, side: float) -> None:
        """Keep node (i, j)'s kept bins and side value."""


@dataclass(frozen=True)
class TableAxis:
    """One axis of an :class:`EchoTable`'s grid: nodes at ``start + k·step``,
    k = 0 … ``count`` − 1 (in the caller's unit of u or v).

    ``count`` may be large: nodes are only computed where queries need them.  ``even``:
    the tabled spectrum is even about ``start`` (a tilt's sign, say); queries may then lie
    anywhere in [2·start − stop, stop] and the stencil reaches across ``start`` to the
    mirrored nodes (the node at −k is the node at k), so that interpolation near ``start``
    is centred, and even, instead of one-sided."""

    start: float
    step: float
    count: int
    even: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.start) and math.isfinite(self.step) and self.step > 0.0):
            raise ValueError(f"table axis needs a finite start and a step > 0, got {self}")

    @property
    def stop(self) -> float:
        """The last node's value."""
        return self.start + (self.count - 1) * self.step

    def stencil(self, value: float, points: int) -> tuple[int, NDArray[np.float64]]:
        """The first index of the ``points`` nodes about ``value`` (negative across the
        start of an ``even`` axis: node −k stands for node k) and their Lagrange weights
        ``(points,)`` (exactly 1 at a node and 0 elsewhere when ``value`` is a node).

        Raises ValueError if ``value`` lies outside the axis (by more than 10⁻⁹ step)."""
        x = (value - self.start) / self.step
        last = float(self.count - 1)
        lowest = -last if self.even else 0.0
        if not (lowest - 1e-9 <= x <= last + 1e-9):
            low = 2.0 * self.start - self.stop if self.even else self.start
            raise ValueError(
                f"table query {value!r} lies outside the table's range [{low!r}, {self.stop!r}]"
            )
        x = min(abs(x) if self.even else max(x, 0.0), last)  # an even axis: at |v|, exactly
        first = math.floor(x) - (points // 2 - 1)
        first = min(max(first, round(lowest)), self.count - points)
        offsets = [x - (first + m) for m in range(points)]  # x − x_m
        weights = np.ones(points)
        for k in range(points):
            for m in range(points):
                if m != k:
                    weights[k] *= offsets[m] / (k - m)
        return first, weights


def significant_bins(magnitude: NDArray[np.float64], cut: float) -> slice:
    """The smallest contiguous range of bins holding every bin whose ``magnitude`` is at
    least ``cut`` times the largest (a pulse's spectrum, say): what a table keeps.

    ``magnitude`` ``(n,)`` ≥ 0, not all zero; 0 < ``cut`` < 1."""
    magnitude = np.asarray(magnitude, dtype=np.float64)
    peak = float(magnitude.max(initial=0.0))
    if not peak > 0.0 or not 0.0 < cut < 1.0:
        raise ValueError(f"significant_bins needs a non-zero magnitude and 0 < cut < 1, got {cut}")
    kept = np.flatnonzero(magnitude >= cut * peak)
    return slice(int(kept[0]), int(kept[-1]) + 1)


class EchoTable:
    """A spectrum over a uniform 2-D grid of two invariants (u, v), filled lazily and
    interpolated by tensor-product Lagrange polynomials (see the module docstring).
    Calling the table at (u, v) returns the interpolated spectrum ``(size,)`` and side
    value; a query outside the grid raises ValueError.

    Parameters
    ----------
    node : ``node(u, v) -> (spectrum, side)``, the exact one-sided spectrum ``(size,)``
        (complex) and a real side value (the echo's path time [s], say) at one node; called
        at most once per node, and never below the start of an ``even`` axis.
    u, v : the grid's axes (:class:`TableAxis`), each with at least ``degree`` + 1 nodes.
    bins : the bins the nodes keep (:func:`significant_bins`); queries return 0 outside.
    size : the full spectrum's length.
    degree : p, the interpolating polynomials' degree in each of u and v (3: cubic, 4 × 4
        nodes per query); at least 1.
    store : where nodes are also kept between processes (:class:`NodeStore`), or None:
        a node found there is not computed again, a computed one is saved there.
    """

    def __init__(
        self,
        node: NodeFunction,
        u: TableAxis,
        v: TableAxis,
        bins: slice,
        size: int,
        degree: int = 3,
        store: NodeStore | None = None,
    ) -> None:
        if degree < 1:
            raise ValueError(f"an EchoTable's degree must be at least 1, got {degree}")
        for name, axis in (("u", u), ("v", v)):
            if axis.count < degree + 1:
                raise ValueError(
                    f"an EchoTable of degree {degree} needs at least {degree + 1} nodes "
                    f"on {name}, got {axis.count}"
                )
        lo, hi, step = bins.indices(size)
        if step != 1 or not 0 <= lo < hi <= size:
            raise ValueError(f"an EchoTable's bins must be a non-empty slice of 0…{size}")
        self._node = node
        self.u = u
        self.v = v
        self.bins = slice(lo, hi)
        self.size = int(size)
        self.degree = int(degree)
        self._store = store
        self._spectra: dict[tuple[int, int], ComplexArray] = {}
        self._sides: dict[tuple[int, int], float] = {}

    @property
    def nodes_filled(self) -> int:
        """How many nodes have been computed so far."""
        return len(self._spectra)

    def node_value(self, i: int, j: int) -> tuple[ComplexArray, float]:
        """The kept bins ``(bins,)`` and side value of node (i, j), computed on first use."""
        key = (i, j)
        spectrum = self._spectra.get(key)
        if spectrum is None:
            kept = self.bins.stop - self.bins.start
            stored = None if self._store is None else self._store.load(i, j, kept)
            if stored is not None:
                spectrum, side = stored
            else:
                spectrum, side = self._compute(i, j)
                if self._store is not None:
                    self._store.save(i, j, spectrum, side)
            self._spectra[key] = spectrum
            self._sides[key] = side
        return spectrum, self._sides[key]

    def _compute(self, i: int, j: int) -> tuple[ComplexArray, float]:
        """Node (i, j) by the node function: its kept bins and side value."""
        full, side = self._node(self.u.start + i * self.u.step, self.v.start + j * self.v.step)
        full = np.asarray(full, dtype=np.complex128)
        if full.shape != (self.size,):
            raise ValueError(
                f"an EchoTable's node function returned shape {full.shape}, expected ({self.size},)"
            )
        return np.ascontiguousarray(full[self.bins]), float(side)

    def __call__(self, u: float, v: float) -> tuple[ComplexArray, float]:
        points = self.degree + 1
        iu, wu = self.u.stencil(float(u), points)
        iv, wv = self.v.stencil(float(v), points)
        weights: list[float] = []
        spectra: list[ComplexArray] = []
        sides: list[float] = []
        for a in range(points):
            for b in range(points):
                weight = float(wu[a] * wv[b])
                if weight != 0.0:  # exactly 0 at the other nodes of a node's own line
                    spectrum, value = self.node_value(abs(iu + a), abs(iv + b))
                    weights.append(weight)
                    spectra.append(spectrum)
                    sides.append(value)
        w = np.asarray(weights)
        # real weights on the real view: numpy's mixed real @ complex product is ~2,000× slower
        kept = (w @ np.asarray(spectra).view(np.float64)).view(np.complex128)
        side = float(w @ np.asarray(sides))
        out = np.zeros(self.size, dtype=np.complex128)
        out[self.bins] = kept
        return out, side
