"""TriangleMesh: Möller–Trumbore vs barycentric truth, engines agree, file loading, errors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh
from hypothesis import assume, given
from hypothesis import strategies as st

from echocal.errors import DataFileError, EchocalValueError, GeometryError, UnknownNameError
from echocal.specimen import FinitePlane, TriangleMesh, embree_available, wavy_surface_mesh
from echocal.specimen.mesh import EMBREE_MIN_FACES

coords = st.floats(-0.05, 0.05)
vertex = st.tuples(coords, coords, coords)


def _direction(az, co):
    az, co = np.radians(az), np.radians(co)
    return np.array([np.sin(co) * np.cos(az), np.sin(co) * np.sin(az), np.cos(co)])


@given(
    v=st.tuples(vertex, vertex, vertex),
    u=st.floats(-0.5, 1.5),
    w=st.floats(-0.5, 1.5),
    t=st.floats(1e-3, 0.2),
    az=st.floats(-180, 180),
    co=st.floats(0, 180),
)
def test_triangle_hit_matches_barycentric_truth(v, u, w, t, az, co):
    """Ray built to pass through P = v0 + u e1 + w e2 at distance t: it hits iff (u, w)
    lies in the triangle.  rtol 1e-7 on t: Möller–Trumbore divides by det, which for
    thin triangles and oblique rays amplifies rounding by up to ~1e3 ulp."""
    verts = np.asarray(v)
    e1, e2 = verts[1] - verts[0], verts[2] - verts[0]
    cross = np.cross(e1, e2)
    area2 = np.linalg.norm(cross)
    assume(area2 > 1e-6)  # not sliver-thin
    d = _direction(az, co)
    assume(abs(d @ cross) / area2 > 0.05)  # not grazing
    margin = 1e-6
    inside = u >= margin and w >= margin and u + w <= 1 - margin
    outside = u < -margin or w < -margin or u + w > 1 + margin
    assume(inside or outside)
    target = verts[0] + u * e1 + w * e2
    mesh = TriangleMesh(verts, [[0, 1, 2]], engine="numpy")
    dist, normal = mesh.intersect((target - t * d)[None], d[None])
    if inside:
        np.testing.assert_allclose(dist[0], t, rtol=1e-7, atol=1e-12)
        n = cross / area2
        np.testing.assert_allclose(normal[0], -np.sign(n @ d) * n, atol=1e-9)
    else:
        assert dist[0] == np.inf


def test_grazing_and_behind_rays_miss():
    mesh = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], engine="numpy")
    o = np.array([[-1.0, 0.2, 0.0], [0.2, 0.2, 1.0], [0.2, 0.2, 1.0]])
    d = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    dist, _ = mesh.intersect(o, d)
    np.testing.assert_allclose(dist, [np.inf, np.inf, 1.0])


def test_flat_mesh_matches_finite_plane():
    """Two triangles forming a square give the same hits as the equivalent FinitePlane."""
    verts = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]) * 0.02
    mesh = TriangleMesh(verts, [[0, 1, 2], [0, 2, 3]], engine="numpy")
    plane = FinitePlane(center=(0, 0, 0), width=0.04, height=0.04)
    rng = np.random.default_rng(1)
    o = np.column_stack([rng.uniform(-0.03, 0.03, (500, 2)), np.full(500, 0.05)])
    d = np.column_stack([rng.normal(0, 0.2, (500, 2)), -np.ones(500)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    tm, nm = mesh.intersect(o, d)
    tp, np_ = plane.intersect(o, d)
    np.testing.assert_array_equal(np.isfinite(tm), np.isfinite(tp))
    np.testing.assert_allclose(tm[np.isfinite(tm)], tp[np.isfinite(tp)], rtol=1e-12)
    np.testing.assert_allclose(nm, np_, atol=1e-15)


def _icosphere_rays(radius: float, n: int, seed: int):
    """Rays aimed at impact parameters < 0.85 r (clear hits) or > 1.15 r (clear misses)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    helper = np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    impact = np.where(rng.random(n) < 0.7, rng.uniform(0, 0.85, n), rng.uniform(1.15, 1.5, n))
    o = -3 * radius * d + impact[:, None] * radius * u
    return o, d, impact < 1


def test_numpy_engine_on_icosphere_hits_the_sphere():
    """Every clear hit lands on the polyhedron: between the inscribed and circumscribed
    sphere radii (icosphere subdivision 3 deviates < 0.5 % from the sphere)."""
    r = 0.03
    ico = trimesh.creation.icosphere(subdivisions=3, radius=r)
    mesh = TriangleMesh(ico.vertices, ico.faces, engine="numpy")
    o, d, expect_hit = _icosphere_rays(r, 2000, seed=2)
    dist, normal = mesh.intersect(o, d)
    np.testing.assert_array_equal(np.isfinite(dist), expect_hit)
    p = o[expect_hit] + dist[expect_hit, None] * d[expect_hit]
    np.testing.assert_allclose(np.linalg.norm(p, axis=1), r, rtol=5e-3)
    np.testing.assert_allclose(np.linalg.norm(normal[expect_hit], axis=1), 1.0, rtol=1e-12)
    assert np.all(np.einsum("ij,ij->i", normal, d) <= 0)


def test_numpy_engine_matches_brute_force():
    """The box hierarchy must not lose hits: compare with testing every face."""
    mesh = wavy_surface_mesh(n=15)
    rng = np.random.default_rng(3)
    o = np.column_stack([rng.uniform(-0.035, 0.035, (300, 2)), np.full(300, 0.02)])
    d = np.column_stack([rng.normal(0, 0.3, (300, 2)), -np.ones(300)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    dist, face = mesh.intersect_faces(o, d)
    all_t = np.stack(
        [
            TriangleMesh(mesh.vertices, f[None], engine="numpy").intersect(o, d)[0]
            for f in mesh.faces
        ]
    )
    np.testing.assert_array_equal(dist, all_t.min(axis=0))
    hit = np.isfinite(dist)
    np.testing.assert_array_equal(all_t[face[hit], np.nonzero(hit)[0]], dist[hit])


@pytest.mark.skipif(not embree_available(), reason="embreex not installed")
def test_embree_and_numpy_engines_agree():
    """Same hit set and distances to float32 precision (rtol 1e-6) on clear hits/misses."""
    r = 0.03
    ico = trimesh.creation.icosphere(subdivisions=4, radius=r)
    o, d, expect_hit = _icosphere_rays(r, 3000, seed=4)
    t_np, n_np = TriangleMesh(ico.vertices, ico.faces, engine="numpy").intersect(o, d)
    t_em, n_em = TriangleMesh(ico.vertices, ico.faces, engine="embree").intersect(o, d)
    np.testing.assert_array_equal(np.isfinite(t_np), expect_hit)
    np.testing.assert_array_equal(np.isfinite(t_em), expect_hit)
    np.testing.assert_allclose(t_em[expect_hit], t_np[expect_hit], rtol=1e-6)
    # normals may differ only where a ray hits an edge shared by two faces
    same = np.all(np.abs(n_em - n_np) < 1e-6, axis=1)
    assert same.mean() > 0.995


@pytest.mark.skipif(not embree_available(), reason="embreex not installed")
def test_embree_honours_eps_for_rays_starting_on_the_surface():
    """A ray leaving the surface must not re-hit its start face (embree has no eps)."""
    mesh = wavy_surface_mesh()
    embree = TriangleMesh(mesh.vertices, mesh.faces, engine="embree")
    start = mesh.vertices[mesh.faces[:50]].mean(axis=1)
    up = np.tile([0.0, 0.0, 1.0], (50, 1))
    t_em, _ = embree.intersect(start, up)
    t_np, _ = mesh.intersect(start, up)
    np.testing.assert_array_equal(t_em, t_np)
    assert np.all(np.isinf(t_np[start[:, 2] > 0.0009]))  # a crest sees nothing above


def test_auto_engine_resolution():
    small = wavy_surface_mesh(n=5)
    assert small.resolved_engine == "numpy"
    assert TriangleMesh(small.vertices, small.faces, engine="numpy").resolved_engine == "numpy"
    big = wavy_surface_mesh(n=41)  # 3200 faces >= EMBREE_MIN_FACES
    assert big.n_faces >= EMBREE_MIN_FACES
    assert big.resolved_engine == ("embree" if embree_available() else "numpy")


@pytest.mark.parametrize("suffix", [".stl", ".obj"])
def test_load_round_trip(tmp_path, suffix):
    ico = trimesh.creation.icosphere(subdivisions=2, radius=30.0)  # a CAD file in mm
    path = tmp_path / f"ball{suffix}"
    ico.export(path)
    mesh = TriangleMesh.load(path, scale=1e-3, engine="numpy")
    assert mesh.name == "ball"
    assert mesh.n_faces == len(ico.faces)
    np.testing.assert_allclose(mesh.bounds(), ico.bounds * 1e-3, rtol=1e-6)
    dist, _ = mesh.intersect([[0, 0, 0.1]], [[0, 0, -1.0]])
    np.testing.assert_allclose(dist, [0.07], rtol=1e-3)


def test_load_errors_name_the_path(tmp_path):
    missing = tmp_path / "nope.stl"
    with pytest.raises(DataFileError, match="nope.stl"):
        TriangleMesh.load(missing)
    garbage = tmp_path / "garbage.stl"
    garbage.write_text("this is not a mesh")
    with pytest.raises(DataFileError, match="garbage.stl"):
        TriangleMesh.load(garbage)
    with pytest.raises(GeometryError, match="scale must be > 0"):
        TriangleMesh.load(garbage, scale=0.0)


def test_degenerate_and_empty_meshes():
    with pytest.raises(GeometryError, match="faces is empty"):
        TriangleMesh(np.zeros((3, 3)), np.zeros((0, 3), dtype=int))
    with pytest.raises(GeometryError, match="every face has zero area"):
        TriangleMesh([[0, 0, 0], [1, 1, 1], [2, 2, 2]], [[0, 1, 2]])
    with pytest.warns(UserWarning, match="dropped 1 zero-area"):
        mesh = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2], [0, 1, 3]])
    assert mesh.n_faces == 1


@pytest.mark.parametrize(
    ("vertices", "faces", "error", "match"),
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], GeometryError, r"faces must index"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1]], GeometryError, r"faces must have shape"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 1.5]], GeometryError, r"integer vertex"),
        ([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], EchocalValueError, r"vertices"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], EchocalValueError, r"vertices must have"),
    ],
)
def test_bad_mesh_input(vertices, faces, error, match):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(error, match=match):
            TriangleMesh(vertices, faces)


def test_unknown_engine_lists_choices():
    with pytest.raises(UnknownNameError, match="auto, embree, numpy"):
        TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], engine="optix")


@pytest.mark.parametrize("use_numba", [True, False], ids=["numba", "numpy"])
def test_containment_of_many_points_matches_the_sphere_it_meshes(monkeypatch, use_numba):
    """Ray parity — the compiled loop, or numpy over (point, face) pairs in chunks (a small
    chunk forces many) — against |p| < r for points clear of the faceted surface."""
    import echocal._numba
    import echocal.specimen.mesh as mesh_module

    monkeypatch.setattr(echocal._numba, "USE_NUMBA", use_numba)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.01)
    mesh = TriangleMesh.from_trimesh(sphere)
    rng = np.random.default_rng(4)
    points = rng.uniform(-0.012, 0.012, size=(300, 3))
    r = np.linalg.norm(points, axis=1)
    points = points[(r < 0.0095) | (r > 0.0102)]  # the facets lie within 0.5 % of r
    monkeypatch.setattr(mesh_module, "_PAIR_CHUNK", 997)
    got = mesh._contains(points)
    np.testing.assert_array_equal(got, np.linalg.norm(points, axis=1) < 0.01)
