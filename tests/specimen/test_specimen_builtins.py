"""Built-in specimens: registry, documented geometry, ground-truth normals."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.constants import MM
from echocal.errors import EchocalValueError, UnknownNameError
from echocal.geometry import orientation_normal
from echocal.specimen import (
    THESIS_MEASUREMENT_POINTS,
    TILTED_PLATE_ORIENTATION,
    Specimen,
    builtin_specimen,
    register_specimen,
    specimen_names,
)


def test_required_names_present():
    required = {"flat-plate", "tilted-plate", "thesis-block", "cylinder", "sphere"}
    assert required <= set(specimen_names())
    for name in specimen_names():
        spec = builtin_specimen(name)
        assert isinstance(spec, Specimen)
        assert spec.name == name


def test_unknown_name_lists_valid_names():
    with pytest.raises(UnknownNameError, match="cylinder, flat-plate") as info:
        builtin_specimen("teapot")
    assert "teapot" in str(info.value)


def test_duplicate_registration_refused():
    with pytest.raises(EchocalValueError, match="already registered"):
        register_specimen("sphere", lambda: builtin_specimen("sphere"))


def test_fresh_instance_each_time():
    assert builtin_specimen("flat-plate") is not builtin_specimen("flat-plate")


def test_flat_and_tilted_plate_normals():
    x = np.linspace(-0.03, 0.03, 7)  # inside the 100 mm plates even when rotated in plan
    np.testing.assert_allclose(
        builtin_specimen("flat-plate").surface_normal_below(x, 0.0), np.tile([0, 0, 1.0], (7, 1))
    )
    tilted = builtin_specimen("tilted-plate")
    expected = orientation_normal(*TILTED_PLATE_ORIENTATION)
    np.testing.assert_allclose(tilted.surface_normal_below(x, x[::-1]), np.tile(expected, (7, 1)))
    az, co = tilted.optimal_orientation_below(0.01, -0.02)
    np.testing.assert_allclose([az, co], TILTED_PLATE_ORIENTATION, atol=1e-9)
    below = tilted.surface_below(0.0, 0.0)
    np.testing.assert_allclose(below.point, [0, 0, 0], atol=1e-15)  # passes through origin


def test_surface_normal_below_shapes_and_misses():
    spec = builtin_specimen("flat-plate")
    n = spec.surface_normal_below(np.zeros((2, 3)), 0.0)
    assert n.shape == (2, 3, 3)
    off = spec.surface_normal_below([0.0, 1.0], [0.0, 0.0])
    assert np.all(np.isfinite(off[0])) and np.all(np.isnan(off[1]))
    az, co = spec.optimal_orientation_below(1.0, 1.0)
    assert np.isnan(az) and np.isnan(co)


def test_thesis_block_documented_optima():
    """The docstring's table: (20, 10) / pole / (165, 6) deg at the three points."""
    block = builtin_specimen("thesis-block")
    x, y = THESIS_MEASUREMENT_POINTS[:, 0], THESIS_MEASUREMENT_POINTS[:, 1]
    az, co = block.optimal_orientation_below(x, y)
    np.testing.assert_allclose(co, [10.0, 0.0, 6.0], atol=1e-9)
    np.testing.assert_allclose(az[[0, 2]], [20.0, 165.0], atol=1e-9)
    normals = block.surface_normal_below(x, y)
    np.testing.assert_allclose(normals[0], orientation_normal(20, 10), atol=1e-12)
    np.testing.assert_allclose(normals[1], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(normals[2], orientation_normal(165, 6), atol=1e-12)
    # the three optima differ pairwise by several degrees
    cos = normals @ normals.T
    assert np.all(np.degrees(np.arccos(np.clip(cos[np.triu_indices(3, 1)], -1, 1))) > 5)


def test_thesis_block_has_no_gaps_and_facets_under_footprints():
    block = builtin_specimen("thesis-block")
    g = np.linspace(-25, 25, 101) * MM
    xx, yy = np.meshgrid(g, g[20:81])  # y in [-15, 15] mm
    hits = block.surface_below(xx, yy)
    assert hits.hit.all()
    # the surface is continuous: neighbouring heights differ by at most slope * step
    z = hits.point[..., 2]
    assert np.abs(np.diff(z, axis=1)).max() < np.tan(np.radians(10.5)) * 0.5 * MM
    # footprints 10 x 10 mm under each measurement point land (mostly) on one facet
    f = np.linspace(-5, 5, 21) * MM
    fx, fy = np.meshgrid(f, f)
    for (px, py, _), facet, share in zip(
        THESIS_MEASUREMENT_POINTS, [1, 0, 2], [0.9, 0.75, 0.9], strict=True
    ):
        idx = block.surface_below(px + fx, py + fy).shape_index
        assert (idx == facet).mean() >= share


def test_cylinder_and_sphere_ground_truth():
    x = np.linspace(-15, 15, 7) * MM
    rod = builtin_specimen("cylinder")
    r = 20 * MM
    expected = np.stack([x / r, np.zeros_like(x), np.sqrt(r * r - x * x) / r], axis=1)
    np.testing.assert_allclose(rod.surface_normal_below(x, 0.01), expected, atol=1e-9)
    np.testing.assert_allclose(rod.surface_below(0.0, 0.0).point, [0, 0, 0], atol=1e-15)
    ball = builtin_specimen("sphere")
    r = 25 * MM
    y = x[::-1] * 0.5
    h = np.sqrt(r * r - x * x - y * y)
    np.testing.assert_allclose(
        ball.surface_normal_below(x, y), np.stack([x, y, h], axis=1) / r, atol=1e-9
    )
    np.testing.assert_allclose(ball.surface_below(0.0, 0.0).point, [0, 0, 0], atol=1e-15)


def test_wavy_surface_normals_match_facets():
    """The mesh normal below a point is the normal of the facet containing it (upward)."""
    spec = builtin_specimen("wavy-surface")
    mesh = spec[0]
    centroids = mesh.vertices[mesh.faces].mean(axis=1)[:40]
    n = spec.surface_normal_below(centroids[:, 0], centroids[:, 1])
    expected = mesh.face_normals[:40] * np.sign(mesh.face_normals[:40, 2:3])
    np.testing.assert_allclose(n, expected, atol=1e-12)
