"""``echocal.wave.echo_table``: the lazily filled, interpolated spectrum table."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.wave.echo_table import EchoTable, TableAxis, significant_bins

SIZE = 12
BINS = slice(3, 9)


def _cubic(u: float, v: float) -> tuple[np.ndarray, float]:
    """A spectrum whose every bin is a different polynomial of degree 3 in u and in v (the
    bicubic term u³v³ included), and a side value of the same kind."""
    k = np.arange(SIZE)
    spectrum = (
        (1.0 + 0.3j * k) * u**3 * v**3
        - (0.7 - 0.1j * k) * u**2 * v
        + 0.2 * k * u * v**3
        + (2.0 - 1j) * v**2
        + 1.5j * k
    )
    return spectrum, 4.0 * u**3 - 3.0 * v**3 * u + 0.5


def _table_axes() -> tuple[TableAxis, TableAxis]:
    return TableAxis(-1.0, 0.25, 9), TableAxis(2.0, 0.5, 7)


def _table(node=_cubic, degree: int = 3) -> EchoTable:
    return EchoTable(node, *_table_axes(), BINS, SIZE, degree)


def test_cubic_interpolation_is_exact_off_nodes_and_at_the_ends() -> None:
    """Exact (to rounding) for bicubic spectra anywhere in the grid, the stencil shifted
    inwards in the first and last cells; zero outside the kept bins."""
    table = _table()
    rng = np.random.default_rng(20261208)
    queries = np.column_stack([rng.uniform(-1.0, 1.0, 40), rng.uniform(2.0, 5.0, 40)])
    queries = np.vstack([queries, [[-1.0, 2.0], [1.0, 5.0], [-0.99, 4.97], [0.5, 3.0]]])
    for u, v in queries:
        got, side = table(u, v)
        want, want_side = _cubic(u, v)
        assert np.abs(got[BINS] - want[BINS]).max() <= 1e-12 * np.abs(want[BINS]).max() + 1e-12
        assert np.all(got[: BINS.start] == 0.0) and np.all(got[BINS.stop :] == 0.0)
        assert side == pytest.approx(want_side, rel=1e-12, abs=1e-12)


def test_linear_interpolation_is_not_exact_for_cubics() -> None:
    """The degree matters: linear interpolation misses the cubic terms off the nodes."""
    got, _ = _table(degree=1)(0.1, 3.3)
    want, _ = _cubic(0.1, 3.3)
    assert np.abs(got[BINS] - want[BINS]).max() > 1e-3


def test_nodes_are_computed_once_and_only_where_needed() -> None:
    calls: list[tuple[float, float]] = []

    def node(u: float, v: float) -> tuple[np.ndarray, float]:
        calls.append((u, v))
        return _cubic(u, v)

    table = _table(node)
    table(0.1, 3.3)
    assert table.nodes_filled == len(calls) == 16  # 4 × 4 about the query
    table(0.12, 3.4)  # the same cell
    assert len(calls) == 16
    table(0.25, 3.0)  # a node: its own value only, already filled
    assert len(calls) == 16
    assert len(set(calls)) == len(calls)


def test_an_even_axis_interpolates_across_its_start_from_the_mirrored_nodes() -> None:
    """Along an even axis the stencil near its start takes the nodes at −v from those at
    v: exact for spectra even in v of degree ≤ 3 (here 2), even in v to rounding, and no
    node below the start is ever computed."""
    calls: list[float] = []

    def node(u: float, v: float) -> tuple[np.ndarray, float]:
        calls.append(v)
        k = np.arange(SIZE)
        return (1.0 + 0.5j * k) * u**3 * v**2 + (2.0 - k) * v**2 + 1j * u, u * v**2

    table = EchoTable(node, TableAxis(-1.0, 0.25, 9), TableAxis(0.0, 0.1, 6, even=True), BINS, SIZE)
    for u, v in [(0.3, 0.04), (-0.6, 0.13), (0.9, -0.07), (0.2, 0.0), (0.1, -0.5)]:
        got, side = table(u, v)
        want, want_side = node(u, abs(v))
        assert np.abs(got[BINS] - want[BINS]).max() <= 1e-12 * np.abs(want[BINS]).max()
        assert side == pytest.approx(want_side, rel=1e-12, abs=1e-13)
        assert np.array_equal(table(u, -v)[0], got)
    assert min(calls) >= 0.0
    with pytest.raises(ValueError, match=r"\[-0.5"):
        table(0.0, -0.6)


def test_bad_queries_and_arguments_raise_one_clear_error() -> None:
    table = _table()
    with pytest.raises(ValueError, match="outside the table's range"):
        table(1.2, 3.0)
    with pytest.raises(ValueError, match="at least 4 nodes"):
        EchoTable(_cubic, TableAxis(0.0, 1.0, 3), TableAxis(0.0, 1.0, 9), BINS, SIZE)
    with pytest.raises(ValueError, match="step > 0"):
        TableAxis(0.0, 0.0, 9)
    with pytest.raises(ValueError, match="expected"):
        EchoTable(lambda u, v: (np.zeros(3), 0.0), *_table_axes(), BINS, SIZE)(0.1, 3.3)


def test_significant_bins_spans_every_bin_above_the_cut() -> None:
    magnitude = np.array([0.0, 1e-9, 1e-3, 0.5, 1.0, 1e-7, 2e-3, 0.0])
    assert significant_bins(magnitude, 1e-3) == slice(2, 7)
    assert significant_bins(magnitude, 0.4) == slice(3, 5)
    with pytest.raises(ValueError, match="cut"):
        significant_bins(np.zeros(4), 1e-3)
