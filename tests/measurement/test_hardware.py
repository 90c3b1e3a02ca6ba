"""HardwareSource over TCP against the emulated rig: composition, errors and injected faults.

Every test talks over real sockets on 127.0.0.1 with short timeouts.  Command
counting for the faults: connecting sends *IDN? and LIMITS? (2 commands); each
measurement sends MOVE, POS?, ACQ? (3 commands).
"""

from __future__ import annotations

import socket

import numpy as np
import pytest
from fake_sources import GaussianEchoSource

from echocal.ascan import AScan
from echocal.errors import InstrumentError, LimitError, UnknownNameError
from echocal.geometry import Pose
from echocal.measurement.hardware import (
    HardwareSource,
    Positioner,
    Receiver,
    TcpInstrument,
    TcpPositioner,
)
from echocal.measurement.instrument_server import MALFORMED_KINDS, Faults, InstrumentServer
from echocal.measurement.limits import PositionerLimits

POSES = [
    Pose(0.0, 0.0, 0.02, 30.0, 4.0),
    Pose(0.002, 0.0, 0.02, 20.0, 8.0),
    Pose(0.0, 0.003, 0.022, -40.0, -6.0),
    Pose(0.0, 0.0, 0.018, 0.0, 0.0),
    Pose(-0.004, 0.0, 0.02, 90.0, 12.0),
]
# timeout 1 s: generous against a loaded CI machine (a spurious timeout would show up as an
# extra reconnect), yet well below the 2 s late answers injected below
FAST = {"timeout": 1.0, "retries": 2, "backoff": 0.01}


def truth(pose: Pose) -> np.ndarray:
    """Noiseless samples of the analytic fake: the independent reference."""
    return GaussianEchoSource().clean_samples(pose)


def run(server: InstrumentServer, poses: list[Pose], **kw: float) -> list[AScan]:
    with HardwareSource.connect(*server.address, **{**FAST, **kw}) as source:
        return [source.measure(p) for p in poses]


def test_measurements_match_the_source_exactly() -> None:
    # base64 float64 and repr floats are exact: no tolerance
    with InstrumentServer(GaussianEchoSource()) as server:
        scans = run(server, POSES)
    for pose, scan in zip(POSES, scans, strict=True):
        np.testing.assert_array_equal(scan.samples, truth(pose))
        assert scan.pose == pose
        assert scan.metadata["source"] == "hardware"


def test_move_time_still_measures_correctly() -> None:
    with InstrumentServer(GaussianEchoSource(), move_time=0.02) as server:
        scans = run(server, POSES[:2])
    np.testing.assert_array_equal(scans[1].samples, truth(POSES[1]))


def test_drop_mid_run_is_retried_and_results_are_unaffected() -> None:
    # drop the 11th command = ACQ? of the 3rd measurement (2 + 3 + 3 + MOVE + POS? = 10 before)
    noisy = {"noise_std": 0.05, "seed": 11}
    with InstrumentServer(GaussianEchoSource(**noisy)) as server:
        reference = run(server, POSES)
    with InstrumentServer(GaussianEchoSource(**noisy), faults=Faults(drop_after=10)) as server:
        source = HardwareSource.connect(*server.address, **FAST)
        scans = [source.measure(p) for p in POSES]
        assert source.positioner.instrument.n_reconnects == 1
        source.close()
    # a dropped command is not executed, so even the noise draws are in step
    for a, b in zip(scans, reference, strict=True):
        np.testing.assert_array_equal(a.samples, b.samples)


def test_instrument_gone_raises_after_retries_and_keeps_earlier_results() -> None:
    faults = Faults(drop_after=10, drop_forever=True)  # gone at the 3rd measurement's ACQ?
    with InstrumentServer(GaussianEchoSource(), faults=faults) as server:
        source = HardwareSource.connect(*server.address, **FAST)
        log = [source.measure(p) for p in POSES[:2]]
        kept = [s.samples.copy() for s in log]
        with pytest.raises(InstrumentError, match=r"ACQ\?.*failed after 3 attempts"):
            source.measure(POSES[2])
        assert source.n_measurements == 2
        source.close()
    for scan, samples, pose in zip(log, kept, POSES[:2], strict=True):
        np.testing.assert_array_equal(scan.samples, samples)
        np.testing.assert_array_equal(scan.samples, truth(pose))


def test_late_answer_is_retried() -> None:
    # the 2nd ACQ? answers 2 s late, beyond the 1 s timeout: the client reconnects and asks again
    faults = Faults(late_acquisition=2, late_delay=2.0)
    with InstrumentServer(GaussianEchoSource(), faults=faults) as server:
        source = HardwareSource.connect(*server.address, **FAST)
        scans = [source.measure(p) for p in POSES[:3]]
        assert source.positioner.instrument.n_reconnects == 1
        assert server.n_acquisitions == 4  # the late one was executed, then asked again
        source.close()
    for pose, scan in zip(POSES[:3], scans, strict=True):
        np.testing.assert_array_equal(scan.samples, truth(pose))


def test_late_answer_without_retries_is_a_timeout_error() -> None:
    faults = Faults(late_acquisition=1, late_delay=2.0)
    with InstrumentServer(GaussianEchoSource(), faults=faults) as server:
        source = HardwareSource.connect(*server.address, timeout=1.0, retries=0)
        with pytest.raises(InstrumentError, match=r"ACQ\?.*timed out"):
            source.measure(POSES[0])
        source.close()


@pytest.mark.parametrize("kind", MALFORMED_KINDS)
def test_malformed_ascan_raises_naming_the_command_then_recovers(kind: str) -> None:
    faults = Faults(malformed_acquisition=2, malformed_kind=kind)
    with InstrumentServer(GaussianEchoSource(), faults=faults) as server:
        source = HardwareSource.connect(*server.address, **FAST)
        first = source.measure(POSES[0])
        kept = first.samples.copy()
        with pytest.raises(InstrumentError, match=r"ACQ\?.*answered nonsense"):
            source.measure(POSES[1])
        # not retried (documented): the caller measures again, on a fresh connection
        again = source.measure(POSES[1])
        source.close()
    np.testing.assert_array_equal(first.samples, kept)
    np.testing.assert_array_equal(again.samples, truth(POSES[1]))


def test_limits_come_from_the_instrument_and_are_checked_before_moving() -> None:
    fake = GaussianEchoSource()
    with InstrumentServer(fake) as server:
        source = HardwareSource.connect(*server.address, **FAST)
        assert source.limits == fake.limits
        with pytest.raises(LimitError, match="coelevation"):
            source.measure(POSES[0].with_orientation(0.0, 45.0))
        assert server.n_commands == 2  # nothing was sent for the refused pose
        source.close()


def test_instrument_limit_refusal_is_a_limit_error() -> None:
    # the client believes in wider limits; the instrument answers ERR LIMIT
    with InstrumentServer(GaussianEchoSource()) as server:
        instrument = TcpInstrument(*server.address, **FAST)
        positioner = TcpPositioner(instrument)
        with pytest.raises(LimitError, match="instrument refused.*coelevation"):
            positioner.move_to(POSES[0].with_orientation(0.0, 45.0))
        assert positioner.position() == server.pose  # the connection is still in step
        instrument.close()


def test_unknown_command_and_bad_arguments_are_reported() -> None:
    with InstrumentServer(GaussianEchoSource()) as server:
        instrument = TcpInstrument(*server.address, **FAST)
        with pytest.raises(InstrumentError, match=r"FOO\?.*SYNTAX.*unknown command"):
            instrument.query_line("FOO?")
        with pytest.raises(InstrumentError, match="MOVE.*SYNTAX.*5 numbers"):
            instrument.query_line("MOVE 1 2")
        assert instrument.identify().startswith("echocal,instrument-server")
        instrument.close()
        with pytest.raises(InstrumentError, match="closed"):
            instrument.identify()


class _BrokenSource(GaussianEchoSource):
    """A source whose acquisition fails with an error that is not echocal's."""

    def measure(self, pose: Pose) -> AScan:
        raise ZeroDivisionError("digitizer fell over")


def test_unexpected_source_failure_is_reported_as_fault_and_the_server_keeps_serving() -> None:
    with InstrumentServer(_BrokenSource()) as server:
        instrument = TcpInstrument(*server.address, **FAST)
        with pytest.raises(InstrumentError, match=r"ACQ\?.*FAULT.*ZeroDivisionError"):
            instrument.query_line("ACQ?")
        # answered, not dropped: no reconnect, and the same connection still works
        assert instrument.n_reconnects == 0
        assert instrument.identify().startswith("echocal,instrument-server")
        instrument.close()


def test_non_protocol_reply_is_nonsense() -> None:
    # a server that answers garbage to everything
    listener = socket.create_server(("127.0.0.1", 0))
    import threading

    def garbage() -> None:
        conn, _ = listener.accept()
        with conn:
            conn.recv(100)
            conn.sendall(b"ASCAN 1e6 0 3\n1 2 3\n")

    thread = threading.Thread(target=garbage, daemon=True)
    thread.start()
    instrument = TcpInstrument(*listener.getsockname(), **FAST)
    from echocal.measurement.hardware import TcpReceiver

    with pytest.raises(InstrumentError, match=r"ACQ\?.*not base64"):
        TcpReceiver(instrument).acquire()
    instrument.close()
    thread.join(2)
    listener.close()


def test_connection_refused_names_the_command() -> None:
    probe = socket.create_server(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # nothing listens there now
    with pytest.raises(InstrumentError, match=r"\*IDN\?.*failed after 2 attempts"):
        HardwareSource.connect("127.0.0.1", port, timeout=1.0, retries=1, backoff=0.0)


def test_invalid_client_settings() -> None:
    with pytest.raises(ValueError, match="timeout"):
        TcpInstrument("127.0.0.1", 1, timeout=0.0)
    with pytest.raises(ValueError, match="retries"):
        TcpInstrument("127.0.0.1", 1, retries=-1)
    with pytest.raises(UnknownNameError, match="malformed_kind"):
        Faults(malformed_acquisition=1, malformed_kind="bogus")


class OffsetPositioner:
    """In-process positioner that lands 0.1 mm off in x (a real rig is never exact)."""

    def __init__(self) -> None:
        self.limits = PositionerLimits()
        self.pose = Pose(0.0, 0.0, 0.02)

    def move_to(self, pose: Pose) -> Pose:
        self.pose = Pose(pose.x + 1e-4, pose.y, pose.z, pose.azimuth, pose.coelevation)
        return self.pose

    def position(self) -> Pose:
        return self.pose

    def close(self) -> None:
        pass


class FakeReceiver:
    def __init__(self, positioner: OffsetPositioner) -> None:
        self.positioner = positioner

    def acquire(self) -> AScan:
        return AScan(truth(self.positioner.pose), fs=50e6, start_time=20e-6)

    def close(self) -> None:
        pass


def test_composition_reports_the_pose_reached() -> None:
    positioner = OffsetPositioner()
    receiver = FakeReceiver(positioner)
    assert isinstance(positioner, Positioner)
    assert isinstance(receiver, Receiver)
    source = HardwareSource(positioner, receiver, description="bench rig")
    scan = source.measure(POSES[0])
    assert scan.pose == Pose(1e-4, 0.0, 0.02, 30.0, 4.0)
    np.testing.assert_array_equal(scan.metadata["requested_pose"], POSES[0].as_array())
    assert source.description == "bench rig"
