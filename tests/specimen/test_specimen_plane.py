"""FinitePlane against closed-form truth (thesis §2.2, eqs. 13–23)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from echocal.errors import EchocalValueError, GeometryError
from echocal.geometry import orientation_frame
from echocal.specimen import FinitePlane

angles = st.floats(-180.0, 180.0)
coords = st.floats(-0.05, 0.05)
sizes = st.floats(1e-3, 0.2)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


@given(
    center=st.tuples(coords, coords, coords),
    az=angles,
    co=angles,
    w=sizes,
    h=sizes,
    a_frac=st.floats(-0.95, 0.95),
    b_frac=st.floats(-0.95, 0.95),
    t=st.floats(1e-4, 0.5),
    dir_az=angles,
    dir_co=st.floats(0.0, 180.0),
)
def test_distance_matches_constructed_hit(center, az, co, w, h, a_frac, b_frac, t, dir_az, dir_co):
    """A ray built to pass through local point (a, b) at distance t hits there.

    Tolerance 1e-9 relative + 1e-12 m absolute: double rounding in a handful of
    products of numbers of size <= 1 m.
    """
    plane = FinitePlane(center=center, width=w, height=h, azimuth=az, coelevation=co)
    frame = orientation_frame(az, co)
    d = _unit([np.sin(np.radians(dir_co)) * np.cos(np.radians(dir_az)),
               np.sin(np.radians(dir_co)) * np.sin(np.radians(dir_az)),
               np.cos(np.radians(dir_co))])  # fmt: skip
    cos_inc = float(d @ frame[:, 2])
    assume(abs(cos_inc) > 1e-3)  # well away from grazing
    target = np.asarray(center) + a_frac * w / 2 * frame[:, 0] + b_frac * h / 2 * frame[:, 1]
    origin = target - t * d
    dist, normal = plane.intersect(origin[None], d[None])
    np.testing.assert_allclose(dist[0], t, rtol=1e-9, atol=1e-12)
    expected_n = -np.sign(cos_inc) * frame[:, 2]
    np.testing.assert_allclose(normal[0], expected_n, atol=1e-12)
    assert normal[0] @ d <= 0.0


@given(
    az=angles,
    co=angles,
    w=sizes,
    h=sizes,
    origin=st.tuples(coords, coords, st.floats(0.01, 0.2)),
    target=st.tuples(coords, coords, coords),
)
def test_matches_linear_solve(az, co, w, h, origin, target):
    """Independent truth: solve s + t d = p0 + a x' + b y' for (t, a, b) with numpy."""
    plane = FinitePlane(center=(0, 0, 0), width=w, height=h, azimuth=az, coelevation=co)
    frame = orientation_frame(az, co)
    s = np.asarray(origin)
    d = np.asarray(target) - s
    assume(np.linalg.norm(d) > 1e-6)
    d = d / np.linalg.norm(d)
    assume(abs(d @ frame[:, 2]) > 1e-3)
    t, a, b = np.linalg.solve(np.column_stack([d, -frame[:, 0], -frame[:, 1]]), -s)
    # keep clear of the edges and of t = 0, where rounding may legitimately decide
    assume(abs(abs(a) - w / 2) > 1e-9 and abs(abs(b) - h / 2) > 1e-9 and abs(t) > 1e-9)
    inside = abs(a) <= w / 2 and abs(b) <= h / 2 and t > 0
    dist, _ = plane.intersect(s[None], d[None])
    if inside:
        np.testing.assert_allclose(dist[0], t, rtol=1e-9, atol=1e-12)
    else:
        assert dist[0] == np.inf


def test_misses_outside_finite_extent():
    plane = FinitePlane(center=(0, 0, 0), width=0.02, height=0.01)  # x in ±10 mm, y in ±5 mm
    x = np.array([0.0, 0.0099, 0.0101, -0.0101, 0.0, 0.0, 0.0])
    y = np.array([0.0, 0.0, 0.0, 0.0, 0.0049, 0.0051, -0.0051])
    o = np.stack([x, y, np.full_like(x, 0.1)], axis=1)
    d = np.tile([0.0, 0.0, -1.0], (len(x), 1))
    dist, normal = plane.intersect(o, d)
    np.testing.assert_array_equal(np.isfinite(dist), [1, 1, 0, 0, 1, 0, 0])
    np.testing.assert_allclose(dist[np.isfinite(dist)], 0.1)
    np.testing.assert_array_equal(normal[~np.isfinite(dist)], 0.0)


def test_grazing_and_in_plane_rays_miss():
    plane = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    o = np.array([[-0.2, 0.0, 0.001], [-0.2, 0.0, 0.0], [0.0, 0.0, 0.0]])
    d = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    dist, normal = plane.intersect(o, d)
    assert np.all(dist == np.inf)
    assert np.all(normal == 0.0)


def test_plane_behind_source_misses_and_both_sides_reflect():
    plane = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    o = np.array([[0, 0, 0.05], [0, 0, 0.05], [0, 0, -0.05]])
    d = np.array([[0, 0, 1.0], [0, 0, -1.0], [0, 0, 1.0]])
    dist, normal = plane.intersect(o, d)
    np.testing.assert_allclose(dist, [np.inf, 0.05, 0.05])
    np.testing.assert_allclose(normal, [[0, 0, 0], [0, 0, 1], [0, 0, -1]])


def test_ray_starting_on_plane_does_not_rehit_it():
    plane = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    dist, _ = plane.intersect([[0.01, 0.0, 0.0]], [[0.0, 0.6, 0.8]])
    assert dist[0] == np.inf


def test_width_runs_along_frame_x_axis():
    """Thesis eqs. 19–20: width along x', height along y' of orientation_frame."""
    plane = FinitePlane(center=(0, 0, 0), width=0.1, height=0.01, azimuth=90.0, coelevation=0.0)
    # azimuth 90 at the pole: x' = (0, 1, 0), so the long side runs along world y
    o = np.array([[0.0, 0.04, 0.1], [0.04, 0.0, 0.1]])
    dist, _ = plane.intersect(o, [[0, 0, -1.0], [0, 0, -1.0]])
    np.testing.assert_allclose(dist, [0.1, np.inf])
    np.testing.assert_allclose(plane.corners()[:, 2], 0.0, atol=1e-15)


def test_bounds_contain_corners():
    plane = FinitePlane(center=(0.01, 0, 0), width=0.03, height=0.02, azimuth=30, coelevation=40)
    lo, hi = plane.bounds()
    corners = plane.corners()
    assert np.all(corners >= lo - 1e-15) and np.all(corners <= hi + 1e-15)
    np.testing.assert_allclose(corners.min(axis=0), lo, atol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"width": -0.01}, r"FinitePlane.width must be > 0; got -0.01"),
        ({"width": 0.0}, r"FinitePlane.width must be > 0; got 0"),
        ({"height": 0.0}, r"FinitePlane.height must be > 0"),
        ({"width": float("inf")}, r"FinitePlane.width must be finite"),
        ({"center": (0, float("nan"), 0)}, r"FinitePlane.center must be finite"),
        ({"center": (0, 0)}, r"FinitePlane.center must have trailing shape"),
        ({"azimuth": float("nan")}, r"FinitePlane.azimuth must be finite"),
        ({"coelevation": float("inf")}, r"FinitePlane.coelevation must be finite"),
        ({"name": ""}, r"FinitePlane.name must be a non-empty string"),
    ],
)
def test_bad_input(kwargs, match):
    args = {"center": (0, 0, 0), "width": 0.01, "height": 0.01} | kwargs
    with pytest.raises(EchocalValueError, match=match):
        FinitePlane(**args)


def test_zero_size_is_geometry_error():
    with pytest.raises(GeometryError):
        FinitePlane(center=(0, 0, 0), width=0.0, height=0.01)


def test_constructor_is_keyword_only():
    with pytest.raises(TypeError):
        FinitePlane((0, 0, 0), 0.01, 0.01)  # type: ignore[misc]


def test_intersect_rejects_bad_rays():
    plane = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    with pytest.raises(EchocalValueError, match="origins must be finite"):
        plane.intersect([[np.nan, 0, 1]], [[0, 0, -1]])
    with pytest.raises(EchocalValueError, match=r"shape \(M, 3\)"):
        plane.intersect([[0, 0, 1]], [[0, 0, -1], [0, 0, -1]])
