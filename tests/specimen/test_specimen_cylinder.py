"""Cylinder (outer and inner surfaces, finite length, caps) against closed-form truth."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from echocal.errors import EchocalValueError, GeometryError, UnknownNameError
from echocal.geometry import orientation_normal
from echocal.specimen import Cylinder

R = 0.02
DOWN = np.array([0.0, 0.0, -1.0])


def rod(**kw):
    """Rod along y (azimuth 90, co-elevation 90), axis at z = -R: top line at z = 0."""
    args = {"center": (0, 0, -R), "radius": R, "length": 0.1, "azimuth": 90, "coelevation": 90}
    return Cylinder(**(args | kw))


@given(x=st.floats(-0.999 * R, 0.999 * R), y=st.floats(-0.049, 0.049), z0=st.floats(0.001, 0.1))
def test_outside_vertical_rays_closed_form(x, y, z0):
    """z_surface = -R + sqrt(R^2 - x^2); normal (x, 0, z_surface + R)/R.  rtol 1e-9: the
    discriminant form is stable; atol 1e-12 m covers the subtraction near the rim."""
    dist, normal = rod().intersect([[x, y, z0]], DOWN[None])
    z_surface = -R + np.sqrt(R * R - x * x)
    np.testing.assert_allclose(dist[0], z0 - z_surface, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(normal[0], [x / R, 0.0, (z_surface + R) / R], atol=1e-9)


def test_finite_length_cut_off_and_beyond_radius_miss():
    o = np.array([[0.0, 0.0499, 0.05], [0.0, 0.0501, 0.05], [0.0201, 0.0, 0.05]])
    dist, _ = rod().intersect(o, np.tile(DOWN, (3, 1)))
    np.testing.assert_allclose(dist, [0.05, np.inf, np.inf])


def test_ray_parallel_to_axis_misses_wall():
    dist, _ = rod().intersect([[0.0, -0.2, -R]], [[0.0, 1.0, 0.0]])
    assert dist[0] == np.inf


def test_caps_hit_along_axis():
    """With caps, a ray along the axis hits the near end disc at its outer face."""
    dist, normal = rod(caps=True).intersect([[0.001, -0.2, -R]], [[0.0, 1.0, 0.0]])
    np.testing.assert_allclose(dist, [0.15])
    np.testing.assert_allclose(normal[0], [0, -1, 0], atol=1e-12)


def test_inside_surface_from_the_axis():
    """A probe on the axis of a bore sees the wall at distance R, normal pointing back."""
    bore = rod(surface="inside")
    angles = np.linspace(0, 2 * np.pi, 9)
    d = np.stack([np.cos(angles), np.zeros_like(angles), np.sin(angles)], axis=1)
    o = np.tile([0.0, 0.01, -R], (len(angles), 1))
    dist, normal = bore.intersect(o, d)
    np.testing.assert_allclose(dist, R, rtol=1e-12)
    np.testing.assert_allclose(normal, -d, atol=1e-12)


def test_inside_surface_from_outside_sees_far_wall_and_outside_sees_near_wall():
    o = np.array([[0.0, 0.0, 0.03]])
    d = DOWN[None]
    near, n_near = rod(surface="outside").intersect(o, d)
    far, n_far = rod(surface="inside").intersect(o, d)
    np.testing.assert_allclose(near, [0.03])
    np.testing.assert_allclose(far, [0.03 + 2 * R])
    np.testing.assert_allclose(n_near[0], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(n_far[0], [0, 0, 1], atol=1e-12)  # inner wall faces up


def test_inside_blind_bore_bottom_cap():
    bore = Cylinder(center=(0, 0, -0.01), radius=0.005, length=0.02, surface="inside", caps=True)
    dist, normal = bore.intersect([[0.001, 0.0, -0.005]], [DOWN])
    np.testing.assert_allclose(dist, [0.015])
    np.testing.assert_allclose(normal[0], [0, 0, 1], atol=1e-12)


@given(
    az=st.floats(-180, 180),
    co=st.floats(0, 180),
    origin=st.tuples(*[st.floats(-0.05, 0.05)] * 3),
    target=st.tuples(*[st.floats(-0.01, 0.01)] * 3),
    surface=st.sampled_from(["outside", "inside"]),
)
def test_hits_lie_on_the_surface_and_match_quadratic(az, co, origin, target, surface):
    """Any hit lies on the wall (radial distance R, |axial| <= L/2) and equals the
    entering (outside) or exiting (inside) root of the infinite-cylinder quadratic."""
    cyl = Cylinder(center=(0, 0, 0), radius=R, length=0.06, azimuth=az, coelevation=co,
                   surface=surface)  # fmt: skip
    a = orientation_normal(az, co)
    s = np.asarray(origin)
    d = np.asarray(target) - s
    if np.linalg.norm(d) < 1e-6:
        return
    d /= np.linalg.norm(d)
    dist, normal = cyl.intersect(s[None], d[None])
    fp = s - (s @ a) * a
    dp = d - (d @ a) * a
    roots = np.roots([dp @ dp, 2 * fp @ dp, fp @ fp - R * R])
    roots = np.sort(roots[np.isreal(roots)].real)
    if dist[0] < np.inf:
        p = s + dist[0] * d
        radial = p - (p @ a) * a
        np.testing.assert_allclose(np.linalg.norm(radial), R, rtol=1e-7)
        assert abs(p @ a) <= 0.03 + 1e-12
        expected = roots[0] if surface == "outside" else roots[-1]
        np.testing.assert_allclose(dist[0], expected, rtol=1e-6, atol=1e-10)
        np.testing.assert_allclose(np.linalg.norm(normal[0]), 1.0, rtol=1e-12)
        assert normal[0] @ d <= 1e-12
    elif len(roots) == 2 and abs(roots[0] - roots[1]) > 1e-6:
        # a clean miss: the chosen root is behind the origin or beyond the ends
        chosen = roots[0] if surface == "outside" else roots[-1]
        axial = (s + chosen * d) @ a
        assert chosen <= 1e-9 or abs(axial) >= 0.03 - 1e-9


def test_bounds_along_y():
    np.testing.assert_allclose(rod().bounds(), [[-R, -0.05, -2 * R], [R, 0.05, 0.0]], atol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"radius": 0.0}, GeometryError, r"Cylinder.radius must be > 0; got 0"),
        ({"length": -0.1}, GeometryError, r"Cylinder.length must be > 0; got -0.1"),
        ({"azimuth": np.nan}, GeometryError, r"Cylinder.azimuth must be finite"),
        ({"center": (0, 0, np.nan)}, EchocalValueError, r"Cylinder.center must be finite"),
        ({"surface": "both"}, UnknownNameError, r"Cylinder.surface.*inside, outside"),
    ],
)
def test_bad_input(kwargs, error, match):
    with pytest.raises(error, match=match):
        rod(**kwargs)
