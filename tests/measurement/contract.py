"""The contract every MeasurementSource must honour, as plain check functions.

A source is plugged in as a :class:`SourceCase`: a factory making a *fresh* source
(same seed every call, so two fresh sources give the same data), a few poses
inside its limits, and how close the reached pose must be to the requested one.
``test_contract.py`` runs every check in :data:`CHECKS` against every case.

Adding a source is one entry in ``test_contract.CASES``, e.g.::

    "virtual": lambda tmp: simple_case(lambda: VirtualSetup(...), poses=[Pose(...), ...]),
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager as ContextManager
from dataclasses import dataclass, field

import numpy as np
import pytest

from echocal.ascan import AScan
from echocal.errors import EchocalError, LimitError
from echocal.geometry import Pose, angle_between
from echocal.measurement.base import MeasurementSource
from echocal.measurement.limits import PositionerLimits


@dataclass
class SourceCase:
    """A source under test.

    Attributes
    ----------
    make : returns a fresh source; two fresh sources must produce identical data
        for identical calls (seeded), which is what "deterministic" means here.
    poses : poses inside the source's limits to measure.
    position_tolerance : [m] allowed distance between requested and reached position.
    angle_tolerance : [deg] allowed angle between requested and reached beam normals.
    outside : poses beyond the limits (default: derived from the limits).
    """

    make: Callable[[], MeasurementSource]
    poses: Sequence[Pose]
    position_tolerance: float = 1e-12
    angle_tolerance: float = 1e-9
    outside: Sequence[Pose] | None = None
    _opened: list[MeasurementSource] = field(default_factory=list)

    def fresh(self) -> MeasurementSource:
        source = self.make()
        self._opened.append(source)
        return source

    def close_all(self) -> None:
        for source in self._opened:
            with contextlib.suppress(Exception):
                source.close()


def simple_case(
    make: Callable[[], MeasurementSource], poses: Sequence[Pose], **kwargs: float
) -> ContextManager[SourceCase]:
    """A case needing no resources beyond the source itself."""

    @contextlib.contextmanager
    def _case() -> Iterator[SourceCase]:
        case = SourceCase(make=make, poses=poses, **kwargs)  # type: ignore[arg-type]
        try:
            yield case
        finally:
            case.close_all()

    return _case()


def outside_poses(limits: PositionerLimits, inside: Pose) -> list[Pose]:
    """One pose per finite limit, beyond it by a full span (at least 1 cm or 10 deg)."""
    out = []
    for name in ("x", "y", "z", "azimuth", "coelevation"):
        low, high = getattr(limits, name)
        floor = 10.0 if name in ("azimuth", "coelevation") else 0.01
        margin = max(floor, high - low) if math.isfinite(high - low) else floor
        for bound, sign in ((high, 1.0), (low, -1.0)):
            if math.isfinite(bound):
                values = inside.as_array()
                values[("x", "y", "z", "azimuth", "coelevation").index(name)] = (
                    bound + sign * margin
                )
                out.append(Pose.from_array(values))
    return out


# -- the checks --------------------------------------------------------------------------------
def check_is_measurement_source(case: SourceCase) -> None:
    """The source satisfies the runtime-checkable protocol."""
    assert isinstance(case.fresh(), MeasurementSource)


def check_description(case: SourceCase) -> None:
    """A non-empty, one-line description."""
    text = case.fresh().description
    assert isinstance(text, str)
    assert text.strip()
    assert "\n" not in text


def check_measure_returns_ascan(case: SourceCase) -> None:
    """AScan with finite samples, fs > 0, one sampling format, reached pose near requested."""
    source = case.fresh()
    scans = [source.measure(p) for p in case.poses]
    for pose, scan in zip(case.poses, scans, strict=True):
        assert isinstance(scan, AScan)
        assert scan.is_finite
        assert scan.fs > 0
        assert math.isfinite(scan.start_time)
        assert scan.pose is not None
        assert np.linalg.norm(scan.pose.position - pose.position) <= case.position_tolerance
        assert float(angle_between(scan.pose.normal, pose.normal)) <= case.angle_tolerance
    assert len({(s.n_samples, s.fs, s.start_time) for s in scans}) == 1


def check_measure_many_equals_measure(case: SourceCase) -> None:
    """measure_many(poses) == [measure(p) ...] on two fresh, identically seeded sources."""
    many = case.fresh().measure_many(list(case.poses))
    single_source = case.fresh()
    single = [single_source.measure(p) for p in case.poses]
    assert len(many) == len(case.poses)
    for a, b in zip(many, single, strict=True):
        np.testing.assert_array_equal(a.samples, b.samples)
        assert (a.fs, a.start_time, a.pose) == (b.fs, b.start_time, b.pose)


def check_limits(case: SourceCase) -> None:
    """Case poses are within limits; poses beyond raise LimitError; the source then still works."""
    source = case.fresh()
    assert isinstance(source.limits, PositionerLimits)
    for pose in case.poses:
        assert source.limits.contains(pose), pose
    outside = (
        case.outside if case.outside is not None else outside_poses(source.limits, case.poses[0])
    )
    if not outside:
        pytest.skip("source has no finite limit to step over")
    for pose in outside:
        with pytest.raises(LimitError):
            source.measure(pose)
    assert source.measure(case.poses[0]).is_finite


def check_close(case: SourceCase) -> None:
    """After close(), measure raises an echocal error; close() twice is harmless."""
    source = case.fresh()
    source.measure(case.poses[0])
    source.close()
    source.close()
    with pytest.raises(EchocalError):
        source.measure(case.poses[0])


def check_results_survive_later_calls(case: SourceCase) -> None:
    """Returned A-scans are immutable and unchanged by later measurements or errors."""
    source = case.fresh()
    first = source.measure(case.poses[0])
    kept = first.samples.copy()
    with pytest.raises(ValueError):
        first.samples[0] = 1.0
    source.measure_many(list(case.poses))
    with contextlib.suppress(EchocalError):
        source.measure(Pose(0.0, 0.0, 0.0, 0.0, 1e3))
    np.testing.assert_array_equal(first.samples, kept)


CHECKS: tuple[Callable[[SourceCase], None], ...] = (
    check_is_measurement_source,
    check_description,
    check_measure_returns_ascan,
    check_measure_many_equals_measure,
    check_limits,
    check_close,
    check_results_survive_later_calls,
)
