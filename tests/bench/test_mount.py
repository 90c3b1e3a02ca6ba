"""Squint and pivot offset, against geometry the test computes with its own rotations."""

from __future__ import annotations

import math

import numpy as np
from _bench_setups import bench_setup
from scipy.optimize import minimize

from echocal.geometry import Pose


def _rx(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])


def _ry(deg: float) -> np.ndarray:
    b = math.radians(deg)
    return np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])


SQUINT = (0.8, -0.6)  # [deg] about the probe's x' then y' axis


def test_the_true_optimum_is_the_acoustic_one_minus_the_squint(tmp_path):
    ideal, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    squinted, _ = bench_setup(
        tmp_path, f"[bench.probe]\nsquint = [{SQUINT[0]}, {SQUINT[1]}]\n", noise="snr_db = 'none'"
    )
    position = ideal.reference_position
    acoustic = np.array(ideal.true_optimum(position, parameterization="tilt"))
    mechanical = np.array(squinted.true_optimum(position, parameterization="tilt"))
    # independent: the mechanical tilts t whose gimbal R_y(t_y) R_x(t_x), carrying the
    # squinted axis m = R_y(s_y) R_x(s_x) ẑ, points it along the acoustic optimum's normal
    n = _ry(acoustic[1]) @ _rx(acoustic[0]) @ np.array([0.0, 0.0, 1.0])
    m = _ry(SQUINT[1]) @ _rx(SQUINT[0]) @ np.array([0.0, 0.0, 1.0])
    exact = minimize(
        lambda t: np.linalg.norm(_ry(t[1]) @ _rx(t[0]) @ m - n) ** 2,
        (0.0, 0.0),
        method="Nelder-Mead",
        options={"xatol": 1e-7, "fatol": 1e-16},
    ).x
    # 0.02°: the tolerance; the truth's own search converges to 1e-5°
    np.testing.assert_allclose(mechanical, exact, atol=0.02)
    # and to first order it is the acoustic optimum minus the squint (second-order terms
    # are ~ s_x s_y π/180 ≈ 0.008° here)
    np.testing.assert_allclose(mechanical, acoustic - np.array(SQUINT), atol=0.02)


def test_a_tilt_about_an_offset_pivot_moves_the_face_as_the_rotation_says(tmp_path):
    offset = np.array([0.001, -0.002, -0.03])  # [m] pivot → face, probe frame
    shifted, _ = bench_setup(
        tmp_path,
        "[bench.probe]\npivot_offset = [{}, {}, {}]\n".format(*offset.tolist()),
        noise="snr_db = 'none'",
    )
    ideal, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    x, y, z = ideal.reference_position
    tilt = (4.0, -3.0)
    # independent: the face moves by (R − I) o, R = R_y(t_y) R_x(t_x)
    rotation = _ry(tilt[1]) @ _rx(tilt[0])
    face = np.array([x, y, z]) + (rotation - np.eye(3)) @ offset
    on_bench = shifted.measure(Pose.from_tilt(x, y, z, *tilt)).samples
    expected = ideal.measure(Pose.from_tilt(*face, *tilt)).samples
    # the same rays from the same place: equal to rounding (positions agree to 1e-18 m;
    # the synthesis turns that into 1e-11 of the peak at most)
    np.testing.assert_allclose(on_bench, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    # and the face did move: the echo arrives later than from the pivot's own position
    pivot = ideal.measure(Pose.from_tilt(x, y, z, *tilt)).samples
    assert np.abs(pivot - on_bench).max() > 0.1 * np.abs(pivot).max()
    # without a tilt the face is where it is commanded
    np.testing.assert_array_equal(
        shifted.measure(Pose.from_tilt(x, y, z, 0.0, 0.0)).samples,
        ideal.measure(Pose.from_tilt(x, y, z, 0.0, 0.0)).samples,
    )
