"""Sphere against closed-form truth."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from echocal.errors import EchocalValueError, GeometryError
from echocal.specimen import Sphere

coords = st.floats(-0.05, 0.05)


def _perp_unit(d, angle):
    """A unit vector perpendicular to unit d, rotated by ``angle`` [rad] about d."""
    helper = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    return np.cos(angle) * u + np.sin(angle) * v


def _direction(az, co):
    az, co = np.radians(az), np.radians(co)
    return np.array([np.sin(co) * np.cos(az), np.sin(co) * np.sin(az), np.cos(co)])


@given(
    center=st.tuples(coords, coords, coords),
    radius=st.floats(1e-3, 0.05),
    impact=st.floats(0.0, 0.999),
    spin=st.floats(0, 2 * np.pi),
    az=st.floats(-180, 180),
    co=st.floats(0, 180),
    gap=st.floats(1e-3, 0.3),
)
def test_distance_matches_closed_form(center, radius, impact, spin, az, co, gap):
    """Impact parameter p = impact * r: t = L - sqrt(r^2 - p^2), with L the distance to
    the point of closest approach.  rtol 1e-9: the stable quadratic loses at most a few ulp
    times L/r (<= 300 here)."""
    c = np.asarray(center)
    d = _direction(az, co)
    p = impact * radius
    along = radius + gap  # closest approach lies this far ahead of the origin
    origin = c - along * d + p * _perp_unit(d, spin)
    dist, normal = Sphere(center=c, radius=radius).intersect(origin[None], d[None])
    expected = along - np.sqrt(radius**2 - p**2)
    np.testing.assert_allclose(dist[0], expected, rtol=1e-9, atol=1e-13)
    hit = origin + dist[0] * d
    np.testing.assert_allclose(normal[0], (hit - c) / radius, atol=1e-7)
    np.testing.assert_allclose(np.linalg.norm(normal[0]), 1.0, rtol=1e-12)
    assert normal[0] @ d <= 0.0


def test_tangent_ray_touches_and_slightly_outside_misses():
    s = Sphere(center=(0, 0, 0), radius=0.01)
    o = np.array([[-0.1, 0.0, 0.01], [-0.1, 0.0, 0.01 * (1 + 1e-9)], [-0.1, 0.0, 0.0]])
    d = np.tile([1.0, 0.0, 0.0], (3, 1))
    dist, normal = s.intersect(o, d)
    np.testing.assert_allclose(dist, [0.1, np.inf, 0.09])
    np.testing.assert_allclose(normal[0], [0, 0, 1], atol=1e-12)  # perpendicular to the ray
    np.testing.assert_allclose(normal[2], [-1, 0, 0])


@given(
    offset=st.tuples(*[st.floats(-0.7, 0.7)] * 3),
    az=st.floats(-180, 180),
    co=st.floats(0, 180),
)
def test_origin_inside_hits_far_side_with_inward_normal(offset, az, co):
    r = 0.02
    c = np.array([0.01, -0.02, 0.005])
    origin = c + r * np.asarray(offset) / np.sqrt(3)  # strictly inside (|offset| < 0.7·√3)
    d = _direction(az, co)
    dist, normal = Sphere(center=c, radius=r).intersect(origin[None], d[None])
    f = origin - c
    b = f @ d
    expected = -b + np.sqrt(b * b - (f @ f - r * r))  # the only positive root
    np.testing.assert_allclose(dist[0], expected, rtol=1e-9)
    hit = origin + dist[0] * d
    np.testing.assert_allclose(np.linalg.norm(hit - c), r, rtol=1e-9)
    np.testing.assert_allclose(normal[0], -(hit - c) / r, atol=1e-7)  # inward: facing the ray


def test_sphere_behind_source_misses():
    s = Sphere(center=(0, 0, 0), radius=0.01)
    dist, normal = s.intersect([[0, 0, 0.1]], [[0, 0, 1.0]])
    assert dist[0] == np.inf
    np.testing.assert_array_equal(normal, 0.0)


def test_bounds():
    np.testing.assert_allclose(
        Sphere(center=(0.1, 0, 0), radius=0.02).bounds(), [[0.08, -0.02, -0.02], [0.12, 0.02, 0.02]]
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"radius": 0.0}, r"Sphere.radius must be > 0; got 0"),
        ({"radius": -1.0}, r"Sphere.radius must be > 0; got -1"),
        ({"radius": float("nan")}, r"Sphere.radius must be finite"),
        ({"center": (np.inf, 0, 0)}, r"Sphere.center must be finite"),
    ],
)
def test_bad_input(kwargs, match):
    with pytest.raises(EchocalValueError, match=match):
        Sphere(**({"center": (0, 0, 0), "radius": 0.01} | kwargs))


def test_nonpositive_radius_is_geometry_error():
    with pytest.raises(GeometryError):
        Sphere(center=(0, 0, 0), radius=-0.01)


def test_ray_starting_on_surface_skips_its_own_point():
    """eps rule: a ray leaving the surface outward misses; inward it hits the far side."""
    s = Sphere(center=(0, 0, 0), radius=0.01)
    o = np.array([[0.0, 0.0, 0.01], [0.0, 0.0, 0.01]])
    d = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    dist, normal = s.intersect(o, d)
    np.testing.assert_allclose(dist, [np.inf, 0.02])
    np.testing.assert_allclose(normal[1], [0, 0, 1])
