"""Closest-hit casting: order over shapes, batch axes, vectorized vs loop, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.errors import EchocalValueError
from echocal.raytrace import Hits, cast
from echocal.specimen import (
    Cylinder,
    FinitePlane,
    Specimen,
    Sphere,
    builtin_specimen,
    specimen_names,
    wavy_surface_mesh,
)

DOWN = np.array([0.0, 0.0, -1.0])


def _random_rays(n: int, seed: int, *, spread: float = 0.04, height: float = 0.03):
    """Rays from a box above the specimens, pointing mostly down (some upwards/sideways)."""
    rng = np.random.default_rng(seed)
    o = np.column_stack([rng.uniform(-spread, spread, (n, 2)), rng.uniform(-0.01, height, n)])
    d = rng.normal(size=(n, 3)) * [0.4, 0.4, 1.0] + [0, 0, -0.8]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o, d


def _two_plates(upper_first: bool) -> Specimen:
    upper = FinitePlane(center=(0, 0, 0), width=0.02, height=0.02, name="upper")
    lower = FinitePlane(center=(0, 0, -0.001), width=0.04, height=0.04, name="lower")
    return Specimen([upper, lower] if upper_first else [lower, upper])


@pytest.mark.parametrize("upper_first", [True, False])
def test_closest_hit_wins_whatever_the_order(upper_first):
    spec = _two_plates(upper_first)
    upper_index = 0 if upper_first else 1
    o = np.array([[0.0, 0.0, 0.05], [0.015, 0.0, 0.05], [0.0, 0.0, -0.05], [0.05, 0.0, 0.05]])
    d = np.array([DOWN, DOWN, -DOWN, DOWN])
    hits = cast(spec, o, d)
    np.testing.assert_allclose(hits.distance, [0.05, 0.051, 0.049, np.inf])
    np.testing.assert_array_equal(
        hits.shape_index, [upper_index, 1 - upper_index, 1 - upper_index, -1]
    )
    np.testing.assert_array_equal(hits.hit, [True, True, True, False])
    np.testing.assert_allclose(hits.point[:3], o[:3] + hits.distance[:3, None] * d[:3])
    assert np.all(np.isinf(hits.point[3]))
    np.testing.assert_array_equal(hits.normal[3], 0.0)
    np.testing.assert_allclose(hits.normal[2], [0, 0, -1])  # from below: faces down


def test_ties_go_to_the_first_listed_shape():
    a = FinitePlane(center=(0, 0, 0), width=0.02, height=0.02, name="a")
    b = FinitePlane(center=(0, 0, 0), width=0.04, height=0.04, name="b")
    assert cast(Specimen([a, b]), [[0, 0, 1.0]], [DOWN]).shape_index[0] == 0
    assert cast(Specimen([b, a]), [[0, 0, 1.0]], [DOWN]).shape_index[0] == 0


def test_sphere_in_front_of_plate():
    plate = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    ball = Sphere(center=(0.0, 0.0, 0.01), radius=0.005)
    hits = cast(Specimen([plate, ball]), [[0, 0, 0.05], [0.02, 0, 0.05]], [DOWN, DOWN])
    np.testing.assert_allclose(hits.distance, [0.035, 0.05])
    np.testing.assert_array_equal(hits.shape_index, [1, 0])


@pytest.mark.parametrize("name", ["flat-plate", "thesis-block", "sphere", "cylinder"])
def test_vectorized_equals_one_ray_at_a_time(name):
    spec = builtin_specimen(name)
    o, d = _random_rays(200, seed=5)
    bundle = cast(spec, o, d)
    assert bundle.hit.sum() > 20  # the test exercises hits, not just misses
    # rtol 1e-14: BLAS may round a (3, 3) @ (3, M) product differently for M = 1 (FMA)
    for i in range(len(o)):
        single = cast(spec, o[i : i + 1], d[i : i + 1])
        np.testing.assert_allclose(single.distance[0], bundle.distance[i], rtol=1e-14)
        assert single.shape_index[0] == bundle.shape_index[i]
        np.testing.assert_allclose(single.normal[0], bundle.normal[i], rtol=0, atol=1e-14)


def test_vectorized_equals_loop_on_mixed_specimen():
    spec = Specimen(
        [
            builtin_specimen("thesis-block")[1],
            Sphere(center=(0.0, 0.0, -0.004), radius=0.006),
            Cylinder(
                center=(0.01, 0, 0),
                radius=0.003,
                length=0.02,
                azimuth=90,
                coelevation=90,
                caps=True,
            ),
            wavy_surface_mesh(n=9),
        ]
    )
    o, d = _random_rays(150, seed=6)
    bundle = cast(spec, o, d)
    assert len(set(bundle.shape_index[bundle.hit])) == 4  # every shape is hit at least once
    for i in range(len(o)):
        single = cast(spec, o[i], d[i][None])  # broadcasting one origin
        np.testing.assert_allclose(single.distance[0], bundle.distance[i], rtol=1e-14)
        assert single.shape_index[0] == bundle.shape_index[i]


@pytest.mark.parametrize("name", specimen_names())
def test_normals_unit_and_facing_the_ray(name):
    spec = builtin_specimen(name)
    o, d = _random_rays(1000, seed=7)
    hits = cast(spec, o, d)
    assert hits.hit.any()
    n = hits.normal[hits.hit]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)
    assert np.all(np.einsum("ij,ij->i", n, d[hits.hit]) <= 0.0)
    assert np.all(hits.distance[hits.hit] > 0)
    np.testing.assert_array_equal(hits.normal[~hits.hit], 0.0)


def test_batch_axes_preserved_and_equal_to_flat():
    spec = builtin_specimen("thesis-block")
    o, d = _random_rays(2 * 3 * 7, seed=8)
    flat = cast(spec, o, d)
    hits = cast(spec, o.reshape(2, 3, 7, 3), d.reshape(2, 3, 7, 3))
    assert hits.distance.shape == (2, 3, 7)
    assert hits.shape_index.shape == (2, 3, 7)
    assert hits.point.shape == (2, 3, 7, 3)
    assert hits.normal.shape == (2, 3, 7, 3)
    assert hits.hit.shape == (2, 3, 7)
    np.testing.assert_array_equal(hits.distance.ravel(), flat.distance)
    np.testing.assert_array_equal(hits.normal.reshape(-1, 3), flat.normal)
    np.testing.assert_array_equal(hits.point.reshape(-1, 3), flat.point)


def test_one_origin_broadcasts_and_directions_are_normalized():
    spec = builtin_specimen("flat-plate")
    d = np.array([[0.0, 0.0, -2.0], [0.0, 0.3, -0.4]])  # not unit
    hits = cast(spec, [0.0, 0.0, 0.04], d)
    np.testing.assert_allclose(hits.distance, [0.04, 0.05])
    np.testing.assert_allclose(hits.point[1], [0.0, 0.03, 0.0], atol=1e-15)


def test_shape_or_list_of_shapes_accepted():
    plate = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    for target in (plate, [plate], Specimen(plate)):
        np.testing.assert_allclose(cast(target, [[0, 0, 0.01]], [DOWN]).distance, [0.01])


def test_empty_specimen_misses_everything():
    hits = cast(Specimen([]), [[0, 0, 1.0]], [DOWN])
    assert hits.shape_index[0] == -1 and hits.distance[0] == np.inf


def test_hits_is_frozen():
    hits = cast(builtin_specimen("sphere"), [[0, 0, 1.0]], [DOWN])
    assert isinstance(hits, Hits)
    with pytest.raises(AttributeError):
        hits.distance = np.zeros(1)  # type: ignore[misc]


@pytest.mark.parametrize(
    ("origins", "directions", "match"),
    [
        ([[np.nan, 0, 1]], [DOWN], "origins must be finite"),
        ([[0, 0, 1]], [[np.inf, 0, -1]], "directions must be finite"),
        ([[0, 0, 1]], [[0, 0, 0]], "directions must be non-zero"),
        ([[0, 1]], [[0, -1]], r"origins must have trailing shape \(3,\)"),
        (np.zeros((2, 3)), np.ones((3, 3)), "must broadcast"),
    ],
)
def test_bad_rays(origins, directions, match):
    with pytest.raises(EchocalValueError, match=match):
        cast(builtin_specimen("flat-plate"), origins, directions)


def test_bad_specimen():
    with pytest.raises(EchocalValueError, match=r"shapes\[0\] must be a Shape"):
        cast(["plate"], [[0, 0, 1]], [DOWN])  # type: ignore[list-item]
    with pytest.raises(EchocalValueError, match="specimen must be"):
        cast(3.0, [[0, 0, 1]], [DOWN])  # type: ignore[arg-type]


def test_large_bundles_are_chunked_consistently():
    """More rays than one kernel chunk (8192): same hits as casting the pieces separately."""
    spec = builtin_specimen("thesis-block")
    o, d = _random_rays(20_000, seed=9)
    whole = cast(spec, o, d)
    parts = [cast(spec, o[a : a + 5000], d[a : a + 5000]) for a in range(0, 20_000, 5000)]
    np.testing.assert_array_equal(whole.distance, np.concatenate([p.distance for p in parts]))
    np.testing.assert_array_equal(whole.normal, np.concatenate([p.normal for p in parts]))
    np.testing.assert_array_equal(whole.shape_index, np.concatenate([p.shape_index for p in parts]))
