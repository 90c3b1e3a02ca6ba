"""Geometry conventions: thesis eq. (8)–(10), the tilt parameterization, poses."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from echocal import EchocalValueError, GeometryError, Pose
from echocal.geometry import (
    angle_between,
    beam_direction,
    normal_to_orientation,
    normal_to_tilt,
    orientation_frame,
    orientation_normal,
    orientation_to_tilt,
    poses_to_arrays,
    tilt_frame,
    tilt_normal,
    tilt_to_orientation,
)

angles = st.floats(-180.0, 180.0, allow_nan=False)
coelevations = st.floats(-89.0, 89.0, allow_nan=False)
tilts = st.floats(-80.0, 80.0, allow_nan=False)

# Double-precision trig on O(1) values: 1e-12 leaves ~1e4 ulp of headroom.
TOL = 1e-12


def test_zero_orientation_fires_straight_down():
    assert_allclose(orientation_normal(0.0, 0.0), [0, 0, 1], atol=TOL)
    assert_allclose(beam_direction(0.0, 0.0), [0, 0, -1], atol=TOL)
    assert_allclose(tilt_normal(0.0, 0.0), [0, 0, 1], atol=TOL)


def test_eq8_known_values():
    # θ = 90°, φ = 90° → n = ŷ ; θ = 30°, φ = 0 → n = [1/2, 0, √3/2]
    assert_allclose(orientation_normal(90.0, 90.0), [0, 1, 0], atol=TOL)
    assert_allclose(orientation_normal(0.0, 30.0), [0.5, 0, np.sqrt(3) / 2], atol=TOL)


def test_signed_coelevation_is_the_opposite_azimuth():
    assert_allclose(orientation_normal(20.0, -7.0), orientation_normal(200.0, 7.0), atol=TOL)


@given(angles, coelevations)
def test_frame_is_orthonormal_right_handed(az, coel):
    frame = orientation_frame(az, coel)
    assert_allclose(frame.T @ frame, np.eye(3), atol=TOL)
    assert np.linalg.det(frame) == pytest.approx(1.0, abs=TOL)
    assert_allclose(frame[:, 2], orientation_normal(az, coel), atol=TOL)
    # eq. (10): x' = y' × n
    assert_allclose(frame[:, 0], np.cross(frame[:, 1], frame[:, 2]), atol=TOL)


@given(tilts, tilts)
def test_tilt_frame_is_rotation(tx, ty):
    frame = tilt_frame(tx, ty)
    assert_allclose(frame.T @ frame, np.eye(3), atol=TOL)
    assert np.linalg.det(frame) == pytest.approx(1.0, abs=TOL)


@given(tilts, tilts)
def test_tilt_round_trip_through_orientation(tx, ty):
    az, coel = tilt_to_orientation(tx, ty)
    tx2, ty2 = orientation_to_tilt(az, coel)
    assert_allclose([tx2, ty2], [tx, ty], atol=1e-9)
    assert_allclose(orientation_normal(az, coel), tilt_normal(tx, ty), atol=TOL)


@given(angles, st.floats(0.01, 89.0))
def test_orientation_round_trip_through_tilt(az, coel):
    tx, ty = orientation_to_tilt(az, coel)
    az2, coel2 = tilt_to_orientation(tx, ty)
    # Same beam; the canonical azimuth may differ by 360°.
    assert angle_between(orientation_normal(az2, coel2), orientation_normal(az, coel)) < 1e-9
    assert coel2 == pytest.approx(coel, abs=1e-9)
    assert np.cos(np.deg2rad(az2 - az)) == pytest.approx(1.0, abs=1e-12)


def test_tilt_axes_meaning():
    # Tilting about +x by α rotates ẑ towards −y; about +y by β towards +x.
    assert_allclose(
        tilt_normal(10.0, 0.0), [0, -np.sin(np.deg2rad(10)), np.cos(np.deg2rad(10))], atol=TOL
    )
    assert_allclose(
        tilt_normal(0.0, 10.0), [np.sin(np.deg2rad(10)), 0, np.cos(np.deg2rad(10))], atol=TOL
    )


def test_pole_has_zero_azimuth():
    az, coel = normal_to_orientation([0.0, 0.0, 2.0])
    assert az == 0.0 and coel == 0.0


def test_vectorized_shapes():
    az = np.linspace(-30, 30, 7)[:, None]
    coel = np.linspace(0, 20, 5)[None, :]
    assert orientation_normal(az, coel).shape == (7, 5, 3)
    assert orientation_frame(az, coel).shape == (7, 5, 3, 3)
    assert normal_to_tilt(orientation_normal(az, coel))[0].shape == (7, 5)


def test_angle_between_small_angles_accurate():
    a = np.array([0.0, 0.0, 1.0])
    b = orientation_normal(0.0, 1e-6)
    assert angle_between(a, b) == pytest.approx(1e-6, rel=1e-6)


def test_pose_properties_and_round_trip():
    pose = Pose(0.01, -0.02, 0.02, 30.0, 5.0)
    assert_allclose(pose.position, [0.01, -0.02, 0.02])
    assert_allclose(pose.beam_direction, -pose.normal)
    assert Pose.from_array(pose.as_array()) == pose
    tx, ty = pose.tilt
    again = Pose.from_tilt(pose.x, pose.y, pose.z, tx, ty)
    assert angle_between(again.normal, pose.normal) < 1e-9
    positions, frames = poses_to_arrays([pose, pose.with_orientation(0, 0)])
    assert positions.shape == (2, 3) and frames.shape == (2, 3, 3)


@pytest.mark.parametrize("field", ["x", "y", "z", "azimuth", "coelevation"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_pose_refuses_non_finite(field, bad):
    kwargs = {"x": 0.0, "y": 0.0, "z": 0.02, "azimuth": 0.0, "coelevation": 0.0, field: bad}
    with pytest.raises(EchocalValueError, match=f"pose.{field} must be finite"):
        Pose(**kwargs)


def test_zero_normal_is_a_geometry_error():
    with pytest.raises(GeometryError, match="non-zero"):
        normal_to_orientation([0.0, 0.0, 0.0])


def test_gimbal_pose_frame_does_not_roll_near_pole():
    # Two nearby tilts on either side of the pole have azimuths 180° apart, but the
    # gimbal frame stays continuous: its x' axis hardly moves.
    a = Pose.from_tilt(0, 0, 0.02, 0.0, 1e-3)
    b = Pose.from_tilt(0, 0, 0.02, 0.0, -1e-3)
    assert abs(a.azimuth - b.azimuth) == pytest.approx(180.0)
    assert angle_between(a.frame[:, 0], b.frame[:, 0]) < 1e-2
    assert_allclose(a.frame[:, 2], a.normal, atol=TOL)
    _, frames = poses_to_arrays([a, Pose(0, 0, 0.02, 10.0, 3.0)])
    assert_allclose(frames[0], a.frame, atol=TOL)
    assert_allclose(frames[1], orientation_frame(10.0, 3.0), atol=TOL)


@given(tilts, tilts)
def test_pose_from_angles_round_trips_both_parameterizations(a, b):
    from echocal.geometry import angles_of, convert_angles, pose_from_angles

    pose = pose_from_angles([0, 0, 0.02], a, b, "tilt")
    assert_allclose(angles_of(pose, "tilt"), [a, b], atol=1e-9)
    az, coel = convert_angles(a, b, "tilt", "azimuth-coelevation")
    assert_allclose([az, coel], [pose.azimuth, pose.coelevation], atol=1e-12)


@given(angles, coelevations)
def test_single_pose_arrays_match_the_vectorized_frames(az, coel):
    pose = Pose(0.01, 0.02, 0.03, az, coel)
    positions, frames = poses_to_arrays([pose])
    assert_allclose(positions, [[0.01, 0.02, 0.03]])
    # np.cos/np.sin vs math.cos/math.sin: both correctly rounded to about 1 ulp.
    assert_allclose(frames[0], orientation_frame(az, coel), atol=1e-15)


CONVERSIONS = [
    lambda a, b: tilt_to_orientation(a, b),
    lambda a, b: orientation_to_tilt(a, b),
    lambda a, b: normal_to_orientation(tilt_normal(a, b)),
    lambda a, b: normal_to_tilt(orientation_normal(a, b)),
]


@pytest.mark.parametrize("convert", CONVERSIONS)
@pytest.mark.parametrize("a, b", [(0.0, 0.0), (0.0, -0.0), (180.0, 0.0), (1.0, 2.0), (0, -3)])
def test_conversions_return_one_scalar_type_and_no_negative_zero(convert, a, b):
    # scalar angles in: two numpy.float64 scalars out (not a 0-d array and a float)
    out = convert(a, b)
    assert all(type(v) is np.float64 for v in out), [type(v) for v in out]
    assert not any(v == 0.0 and np.signbit(v) for v in out), out


@pytest.mark.parametrize("convert", CONVERSIONS)
def test_conversions_of_arrays_return_arrays_of_the_broadcast_shape(convert):
    a, b = np.zeros((2, 3)), np.array([0.0, -0.0, 5.0])
    for v in convert(a, b):
        assert isinstance(v, np.ndarray) and v.shape == (2, 3)
        assert not np.any((v == 0.0) & np.signbit(v))


def test_convert_angles_to_the_same_parameterization_is_consistent_too():
    from echocal.geometry import convert_angles

    out = convert_angles(-0.0, 1, "tilt", "tilt")
    assert all(type(v) is np.float64 for v in out) and not np.signbit(out[0])
