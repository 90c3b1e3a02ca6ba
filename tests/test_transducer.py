"""Pinhole transducer (thesis §2.1.2) and directivity models."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy.special import j1

from echocal import MM, EchocalValueError, UnknownNameError
from echocal.geometry import orientation_frame
from echocal.transducer import (
    GaussianDirectivity,
    PistonDirectivity,
    Transducer,
    make_directivity,
)


def test_pixel_grid_centres_and_count():
    t = Transducer(width=4 * MM, height=2 * MM, n_h=4, n_v=2)
    assert t.n_rays == 8
    assert_allclose(np.unique(t.local_pixels[0]), np.array([-1.5, -0.5, 0.5, 1.5]) * MM)
    assert_allclose(np.unique(t.local_pixels[1]), np.array([-0.5, 0.5]) * MM)


def test_circular_aperture_drops_corner_pixels():
    t = Transducer(width=10 * MM, height=10 * MM, n_h=64, n_v=64, aperture="circular")
    r = np.hypot(*t.local_pixels)
    assert r.max() <= 5 * MM
    # Area ratio of disc to square is π/4; pixel count follows within a rim of pixels.
    assert t.n_rays / 64**2 == pytest.approx(np.pi / 4, abs=0.02)


@given(st.floats(-180, 180), st.floats(-60, 60))
def test_rays_start_on_plane_and_leave_from_focus(az, coel):
    t = Transducer(n_h=5, n_v=3, pinhole_distance=15 * MM)
    frame = orientation_frame(az, coel)[None]
    centre = np.array([[0.01, -0.02, 0.03]])
    rays = t.rays(centre, frame)
    n = frame[0, :, 2]
    # Origins lie in the imaging plane through the centre, eq. (12).
    assert_allclose((rays.origins[0] - centre) @ n, 0.0, atol=1e-15)
    # Directions are unit and point away from the focus f = c + l·n (behind the plane).
    assert_allclose(np.linalg.norm(rays.directions[0], axis=1), 1.0, atol=1e-12)
    focus = centre[0] + 15 * MM * n
    towards = rays.origins[0] - focus
    towards /= np.linalg.norm(towards, axis=1, keepdims=True)
    assert_allclose(rays.directions[0], towards, atol=1e-12)
    # Every ray goes forward, along −n.
    assert np.all(rays.directions[0] @ n < 0)


def test_centre_ray_is_the_beam_axis():
    t = Transducer(n_h=3, n_v=3)
    rays = t.rays(np.zeros((1, 3)), orientation_frame(0.0, 0.0)[None])
    assert_allclose(rays.directions[0, 4], [0, 0, -1], atol=1e-15)
    assert t.weights[4] == pytest.approx(1.0)


def test_gaussian_directivity_is_minus_6db_at_opening_angle():
    d = GaussianDirectivity(opening_angle=8.0)
    assert d(np.deg2rad(8.0)) == pytest.approx(0.5, rel=1e-12)
    assert d(0.0) == 1.0


def test_piston_directivity_matches_bessel_and_first_null():
    d = PistonDirectivity(radius=6.35 * MM, frequency=5e6, sound_speed=1480.0)
    psi = np.deg2rad(1.0)
    x = 2 * np.pi * 5e6 / 1480.0 * 6.35 * MM * np.sin(psi)
    assert d(psi) == pytest.approx(abs(2 * j1(x) / x), rel=1e-12)
    assert d(np.deg2rad(d.first_null)) == pytest.approx(0.0, abs=1e-9)
    assert d.first_null == pytest.approx(1.6290, abs=1e-3)  # ka ≈ 134.79 → asin(3.8317/ka)


def test_weights_follow_ray_angles():
    t = Transducer(directivity=make_directivity("gaussian", opening_angle=5.0))
    assert_allclose(t.weights, np.exp2(-((t.ray_angles / np.deg2rad(5.0)) ** 2)))
    flat = Transducer(directivity=make_directivity("none"))
    assert np.all(flat.weights == 1.0)


def test_batched_rays_equal_single_pose_rays():
    t = Transducer(n_h=8, n_v=8)
    frames = orientation_frame([0.0, 30.0, -45.0], [0.0, 5.0, 12.0])
    positions = np.array([[0, 0, 0.02], [0.01, 0, 0.02], [0, -0.01, 0.03]])
    batch = t.rays(positions, frames)
    for p in range(3):
        single = t.rays(positions[p : p + 1], frames[p : p + 1])
        assert_allclose(batch.origins[p], single.origins[0])
        assert_allclose(batch.directions[p], single.directions[0])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"width": 0.0}, "transducer.width"),
        ({"height": -1e-3}, "transducer.height"),
        ({"n_h": 0}, "transducer.n_h"),
        ({"n_v": 2.5}, "transducer.n_v"),
        ({"pinhole_distance": float("nan")}, "transducer.pinhole_distance"),
        ({"aperture": "hexagonal"}, "transducer.aperture"),
        ({"directivity": None}, "transducer.directivity"),
    ],
)
def test_bad_transducer_names_the_field(kwargs, field):
    with pytest.raises(EchocalValueError, match=field):
        Transducer(**kwargs)


def test_unknown_directivity_lists_names():
    with pytest.raises(UnknownNameError, match="gaussian, none, piston"):
        make_directivity("cardioid")
