"""A probe in a pipe's bore is in the coupling medium; an endless azimuth axis is accepted."""

from __future__ import annotations

import math

import numpy as np
import pytest

from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import GeometryError
from echocal.geometry import Pose
from echocal.measurement import PositionerLimits, ReceiverSettings, VirtualSetup
from echocal.measurement.protocol import ProtocolError, decode_limits, encode_limits
from echocal.signal import RecordingWindow, make_pulse
from echocal.specimen import Cylinder, Specimen, Sphere
from echocal.transducer import Transducer

MM = 1e-3
BORE = 40 * MM
PULSE = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
# the bore wall is 40 mm below the axis: round trip 2 * 40 mm / c ~ 54 us
WINDOW = RecordingWindow(fs=100e6, start=40e-6, n_samples=2048)


def pipe() -> Specimen:
    # horizontal pipe (axis along x): a solid rod of radius 50 mm with a 40 mm bore
    common = {"center": (0.0, 0.0, 0.0), "length": 0.2, "coelevation": 90.0}
    outer = Cylinder(radius=50 * MM, surface="outside", name="wall", **common)
    bore = Cylinder(radius=BORE, surface="inside", name="bore", **common)
    return Specimen([outer, bore], name="pipe")


def virtual(specimen: Specimen, at=(0.0, 0.0, 0.0)) -> VirtualSetup:
    return VirtualSetup(
        specimen=specimen,
        transducer=Transducer(n_h=8, n_v=8),
        pulse=PULSE,
        window=WINDOW,
        receiver=ReceiverSettings(snr_db=60.0),
        reference_position=at,
        rng=3,
    )


def test_probe_in_the_bore_builds_and_hears_the_bore_wall():
    setup = virtual(pipe())
    scan = setup.measure(Pose(0.0, 0.0, 0.0, 0.0, 0.0))
    envelope = np.abs(scan.samples)
    peak_time = scan.times[int(np.argmax(envelope))]
    # the echo peak lies within a few pulse periods (5 MHz: 0.2 us) of 2 r / c; the finite
    # aperture on the curved wall and the pulse shape shift it by well under 1 us
    assert peak_time == pytest.approx(2 * BORE / SOUND_SPEED_WATER, abs=1e-6)
    assert envelope.max() > 10 * np.median(envelope)


def test_containing_excludes_the_bore_but_not_the_wall():
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 45 * MM], [0.0, 0.0, 60 * MM]])
    # axis in the bore: medium; between bore and outer wall: material; outside: medium
    assert pipe().containing(points).tolist() == [-1, 0, -1]
    with pytest.raises(GeometryError, match="inside cylinder 'wall'"):
        virtual(pipe(), at=(0.0, 0.0, 45 * MM))
    # beyond the bore's length the rod is solid again
    short = Specimen(
        [
            Cylinder(center=(0, 0, 0), radius=50 * MM, length=0.2, coelevation=90.0),
            Cylinder(
                center=(0, 0, 0), radius=BORE, length=0.05, coelevation=90.0, surface="inside"
            ),
        ]
    )
    assert short.containing([[0.09, 0.0, 0.0], [0.0, 0.0, 0.0]]).tolist() == [0, -1]


@pytest.mark.parametrize(
    "shape",
    [
        Cylinder(center=(0, 0, 0), radius=50 * MM, length=0.2, coelevation=90.0),
        Sphere(center=(0, 0, 0), radius=50 * MM),
    ],
)
def test_probe_inside_a_plain_solid_is_still_refused(shape):
    with pytest.raises(GeometryError, match="probe must be outside the part"):
        virtual(Specimen([shape]))
    assert Specimen([shape]).containing([[0.0, 0.0, 0.0]]).tolist() == [0]


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
