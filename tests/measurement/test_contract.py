"""Run the MeasurementSource contract (contract.py) against every source.

To add a source, add one entry to CASES: a function of pytest's ``tmp_path_factory``
returning a context manager that yields a SourceCase (``simple_case`` does that).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager as ContextManager

import pytest
from contract import CHECKS, SourceCase, simple_case
from fake_sources import GaussianEchoSource

from echocal.geometry import Pose
from echocal.measurement import (
    HardwareSource,
    InstrumentServer,
    PositionerLimits,
    ReceiverSettings,
    RecordingGrid,
    ReplaySource,
    VirtualSetup,
    record,
)
from echocal.signal import RecordingWindow, make_pulse
from echocal.specimen import builtin_specimen
from echocal.transducer import Transducer

# Replay grid: steps of 10 deg (azimuth) and 5 deg (co-elevation), two positions 5 mm apart.
GRID = RecordingGrid.regular(
    azimuth=(0.0, 60.0, 7), coelevation=(-10.0, 10.0, 5), positions=[(0, 0, 0.02), (0.005, 0, 0.02)]
)
REPLAY_POSES = [
    Pose(0.0, 0.0, 0.02, 31.0, 4.4),
    Pose(0.005, 0.0, 0.02, 0.0, -10.0),
    Pose(0.0049, 0.0, 0.02, 58.0, 9.0),
]
HARDWARE_POSES = [
    Pose(0.0, 0.0, 0.02, 30.0, 4.0),
    Pose(0.005, -0.002, 0.025, -45.0, -12.0),
    Pose(0.0, 0.0, 0.02, 0.0, 0.0),
]


def _recording(tmp_path_factory: pytest.TempPathFactory) -> str:
    """One noisy recording shared by the replay cases (made once per session)."""
    path = tmp_path_factory.getbasetemp() / "contract-replay.nc"
    if not path.exists():
        record(GaussianEchoSource(noise_std=0.02, seed=3), GRID, path, repeats=2, progress=False)
    return str(path)


def replay_case(mode: str) -> Callable[[pytest.TempPathFactory], ContextManager[SourceCase]]:
    @contextlib.contextmanager
    def factory(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SourceCase]:
        path = _recording(tmp_path_factory)
        # nearest modes snap to the grid: reached position within 0.1 mm of the requested
        # (0.0049 vs 0.005 m), and the normal within the half-step diagonal hypot(5, 2.5) deg,
        # an upper bound of the angle between the two normals; interpolate keeps the angles.
        exact = mode == "interpolate"
        case = SourceCase(
            make=lambda: ReplaySource.open(path, mode=mode, rng=7),
            poses=REPLAY_POSES,
            position_tolerance=1.01e-4,
            angle_tolerance=1e-9 if exact else 5.6,
        )
        try:
            yield case
        finally:
            case.close_all()

    return factory


@contextlib.contextmanager
def hardware_case(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SourceCase]:
    """HardwareSource over real loopback sockets to an emulated rig (a fresh one per source)."""
    servers: list[InstrumentServer] = []

    def make() -> HardwareSource:
        server = InstrumentServer(GaussianEchoSource(noise_std=0.02, seed=5)).start()
        servers.append(server)
        return HardwareSource.connect(*server.address, timeout=2.0, retries=1)

    # the emulated positioner is exact and the protocol sends repr floats: exact pose
    case = SourceCase(make=make, poses=HARDWARE_POSES, position_tolerance=0.0, angle_tolerance=0.0)
    try:
        yield case
    finally:
        case.close_all()
        for server in servers:
            server.close()


def _small_virtual_setup() -> VirtualSetup:
    """A fast simulator: flat plate, 12 x 12 rays, 1024 samples, noisy (seeded)."""
    return VirtualSetup(
        specimen=builtin_specimen("flat-plate"),
        transducer=Transducer(n_h=12, n_v=12),
        pulse=make_pulse("gabor", center_frequency=5e6, bandwidth=60),
        # echoes at 2 z / c = 24..34 us for z = 18..25 mm: inside [20, 40.5] us
        window=RecordingWindow(fs=50e6, start=20e-6, n_samples=1024),
        receiver=ReceiverSettings(snr_db=30.0),
        limits=PositionerLimits(z=(0.01, 0.04), coelevation=(-30.0, 30.0)),
        rng=1,
    )


def virtual_case(tmp_path_factory: pytest.TempPathFactory) -> ContextManager[SourceCase]:
    # the simulator reaches the requested pose exactly (default tolerances: 1e-12 m, 1e-9 deg)
    return simple_case(_small_virtual_setup, poses=HARDWARE_POSES)


CASES: dict[str, Callable[[pytest.TempPathFactory], ContextManager[SourceCase]]] = {
    "replay-nearest": replay_case("nearest"),
    "replay-random-repeat": replay_case("random-repeat"),
    "replay-interpolate": replay_case("interpolate"),
    "hardware-tcp": hardware_case,
    "virtual": virtual_case,
}


@pytest.fixture(params=sorted(CASES))
def source_case(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[SourceCase]:
    with CASES[request.param](tmp_path_factory) as case:
        yield case


@pytest.mark.parametrize("check", CHECKS, ids=[c.__name__ for c in CHECKS])
def test_contract(source_case: SourceCase, check: Callable[[SourceCase], None]) -> None:
    check(source_case)
