"""The instrument line protocol: exact round trips and clear errors for nonsense."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from echocal.errors import InstrumentError
from echocal.geometry import Pose
from echocal.measurement import PositionerLimits, protocol
from echocal.measurement.protocol import ProtocolError, decode_limits, encode_limits

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@given(st.tuples(finite, finite, finite, finite, finite), st.booleans())
def test_pose_round_trip_is_exact(values: tuple[float, ...], gimbal: bool) -> None:
    pose = Pose(*values, gimbal=gimbal)
    text = protocol.encode_pose(pose)
    assert text.endswith(" GIMBAL") == gimbal
    assert protocol.decode_pose(text) == pose


def test_gimbal_flag_is_the_only_sixth_token() -> None:
    pose = protocol.decode_pose("0 0 0.02 30 4 GIMBAL")
    assert pose == Pose(0.0, 0.0, 0.02, 30.0, 4.0, gimbal=True)
    # same beam axis, different roll about it: that is what the flag carries
    plain = Pose(0.0, 0.0, 0.02, 30.0, 4.0)
    np.testing.assert_allclose(pose.frame[:, 2], plain.frame[:, 2], atol=1e-15)
    assert not np.allclose(pose.frame[:, 0], plain.frame[:, 0], atol=1e-3)
    with pytest.raises(InstrumentError, match="5 numbers"):
        protocol.decode_pose("0 0 0.02 30 4 TILT")


@given(
    st.lists(finite, min_size=1, max_size=50),
    st.floats(min_value=1.0, max_value=1e12),
    finite,
)
def test_ascan_round_trip_is_exact(samples: list[float], fs: float, start: float) -> None:
    header, payload = protocol.encode_ascan(np.array(samples), fs, start)
    got_fs, got_start, n = protocol.decode_ascan_header(header)
    assert (got_fs, got_start, n) == (fs, start, len(samples))
    np.testing.assert_array_equal(protocol.decode_samples(payload, n), samples)


def test_payload_is_little_endian_float64_base64() -> None:
    # independent truth: 1.0 as little-endian IEEE-754 double is 00 00 00 00 00 00 f0 3f
    _, payload = protocol.encode_ascan(np.array([1.0]), 1.0, 0.0)
    assert payload == "AAAAAAAA8D8="


def test_limits_round_trip_with_unlimited_axes() -> None:
    limits = PositionerLimits(z=(0.01, 0.05), coelevation=(-30.0, 30.0))
    text = protocol.encode_limits(limits)
    assert "inf" in text
    assert protocol.decode_limits(text) == limits


def test_lines_are_newline_terminated_and_refuse_embedded_newlines() -> None:
    assert protocol.encode_line("MOVE", 1.0, 0.5) == b"MOVE 1.0 0.5\n"
    with pytest.raises(protocol.ProtocolError, match="newline"):
        protocol.encode_line("A\nB")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 2 3 4", "5 numbers"),
        ("1 2 3 4 x", "'x' is not a number"),
        ("1 2 3 4 nan", "not a finite number"),
        ("1 2 3 4 inf", "not a finite number"),
    ],
)
def test_bad_pose_text(text: str, message: str) -> None:
    with pytest.raises(InstrumentError, match=message):
        protocol.decode_pose(text)


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ("ASCAN 1e6 0", "'ASCAN fs start n' header"),
        ("SCAN 1e6 0 3", "'ASCAN fs start n' header"),
        ("ASCAN 1e6 0 3.5", "not an integer"),
        ("ASCAN -1 0 3", "fs > 0"),
        ("ASCAN 1e6 0 0", "n >= 1"),
    ],
)
def test_bad_ascan_header(header: str, message: str) -> None:
    with pytest.raises(InstrumentError, match=message):
        protocol.decode_ascan_header(header)


def test_bad_samples() -> None:
    _, payload = protocol.encode_ascan(np.arange(4.0), 1.0, 0.0)
    with pytest.raises(InstrumentError, match="holds 4 samples; the header announced 5"):
        protocol.decode_samples(payload, 5)
    with pytest.raises(InstrumentError, match="not base64"):
        protocol.decode_samples("%%%%", 1)
    _, nan_payload = protocol.encode_ascan(np.array([0.0, math.nan]), 1.0, 0.0)
    with pytest.raises(InstrumentError, match="NaN"):
        protocol.decode_samples(nan_payload, 2)


def test_bad_limits() -> None:
    with pytest.raises(InstrumentError, match="10 numbers"):
        protocol.decode_limits("0 1")
    with pytest.raises(InstrumentError, match="low <= high"):
        protocol.decode_limits("1 0 0 1 0 1 0 1 0 1")


REPLY = "-1 1 -1 1 0 0.5 {az} -60 60"


@pytest.mark.parametrize("az", ["-inf inf", "-inf 90", "0 inf"])
def test_endless_azimuth_reply_means_a_full_turn(az):
    limits = decode_limits(REPLY.format(az=az))
    assert limits.azimuth == (-180.0, 180.0)
    assert limits.coelevation == (-60.0, 60.0)
    assert limits.contains(Pose(0.0, 0.0, 0.1, 179.0, 10.0))
    # finite now, so the midpoint and optimiser bounds stay numbers
    assert all(math.isfinite(b) for b in limits.azimuth)
    assert decode_limits(encode_limits(limits)) == limits


def test_limits_within_a_turn_are_kept_and_bad_ones_refused():
    assert PositionerLimits(azimuth=(0.0, 360.0)).azimuth == (0.0, 360.0)
    assert PositionerLimits(azimuth=(-math.inf, math.inf)).azimuth == (-180.0, 180.0)
    # finite bounds outside [-360, 360] stay refused (a unit slip, not an endless axis)
    for bounds in [(300.0, 500.0), (-720.0, 720.0)]:
        with pytest.raises(ValueError, match="azimuth"):
            PositionerLimits(azimuth=bounds)
    with pytest.raises(ValueError, match="azimuth"):
        PositionerLimits(azimuth=(math.inf, -math.inf))
    with pytest.raises(ProtocolError, match="coelevation"):
        decode_limits(REPLY.replace("-60 60", "-inf inf").format(az="-inf inf"))
    with pytest.raises(ProtocolError, match="coelevation"):
        decode_limits(REPLY.replace("-60 60", "-100 100").format(az="-180 180"))
