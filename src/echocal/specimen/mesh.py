"""Triangle meshes: STL/OBJ via trimesh, numpy Möller–Trumbore or embree ray engine."""

from __future__ import annotations

import importlib.util
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._numba import compiled
from echocal._validate import finite_array, one_of
from echocal.errors import DataFileError, GeometryError
from echocal.specimen.base import (
    GRAZING_COS,
    FloatArray,
    Shape,
    _check_name,
    _dot,
    _safe_inverse,
    _signed_normals,
    _size,
    _slab_hits,
    _validate_rays,
)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product of (3, K) component arrays."""
    return np.stack(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


__all__ = ["EMBREE_MIN_FACES", "MESH_ENGINES", "TriangleMesh", "embree_available"]

MESH_ENGINES = ("auto", "numpy", "embree")
"""Allowed values of ``TriangleMesh.engine``."""

EMBREE_MIN_FACES = 1000
"""With ``engine="auto"``, meshes with at least this many faces use embree when installed."""

_LEAF = 16  # faces per leaf box of the numpy engine's hierarchy
_BRANCH = 8  # children per inner node
_PAIR_CHUNK = 400_000  # (ray, face) candidate pairs tested at once: bounds the memory


def embree_available() -> bool:
    """True when the optional ``embreex`` package (trimesh's fast ray engine) is importable."""
    return importlib.util.find_spec("embreex") is not None


class TriangleMesh(Shape):
    """A two-sided triangle mesh.

    Parameters
    ----------
    vertices : [m], shape ``(V, 3)``
    faces : vertex indices, shape ``(F, 3)``, integers in ``[0, V)``.
    engine : ``"numpy"`` (vectorized Möller–Trumbore behind a bounding-box
        hierarchy, chunked so memory stays bounded), ``"embree"`` (embreex via
        trimesh, float32 inside; the hit triangle's distance is then recomputed
        in float64), or ``"auto"``: embree when installed and the mesh has at
        least ``EMBREE_MIN_FACES`` faces, numpy otherwise.
    name : label used in plots and reports.

    Notes
    -----
    Zero-area faces are dropped with a warning; a mesh with no faces left is a
    :class:`~echocal.errors.GeometryError`.  Normals are the faces' geometric
    normals (``(v1 − v0) × (v2 − v0)``, unit), flipped to face the ray.
    """

    kind = "mesh"

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        engine: str = "auto",
        name: str = "mesh",
    ) -> None:
        owner = "TriangleMesh"
        self.name = _check_name(owner, name)
        verts = finite_array(f"{owner}.vertices", vertices, shape_tail=(3,))
        if verts.ndim != 2:
            raise GeometryError(f"{owner}.vertices must have shape (V, 3); got {verts.shape}")
        face_arr = np.asarray(faces)
        if face_arr.size == 0:
            raise GeometryError(f"{owner}.faces is empty; a mesh needs at least one triangle")
        if face_arr.ndim != 2 or face_arr.shape[1] != 3:
            raise GeometryError(f"{owner}.faces must have shape (F, 3); got {face_arr.shape}")
        if not np.issubdtype(face_arr.dtype, np.integer):
            as_int = face_arr.astype(np.int64) if np.issubdtype(face_arr.dtype, np.number) else None
            if as_int is None or not np.array_equal(as_int, face_arr):
                raise GeometryError(f"{owner}.faces must hold integer vertex indices")
            face_arr = as_int
        face_arr = face_arr.astype(np.int64)
        if face_arr.min() < 0 or face_arr.max() >= len(verts):
            raise GeometryError(
                f"{owner}.faces must index vertices in [0, {len(verts) - 1}]; "
                f"got indices in [{face_arr.min()}, {face_arr.max()}]"
            )
        tri = verts[face_arr]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        double_area = np.linalg.norm(cross, axis=1)
        scale = float(np.linalg.norm(verts.max(axis=0) - verts.min(axis=0)))
        good = double_area > 1e-12 * max(scale, 1e-300) ** 2
        if not np.any(good):
            raise GeometryError(f"{owner} is degenerate: every face has zero area")
        if not np.all(good):
            warnings.warn(
                f"{owner} {name!r}: dropped {int((~good).sum())} zero-area face(s)",
                stacklevel=2,
            )
        self.vertices: FloatArray = verts.copy()
        self.faces: NDArray[np.int64] = face_arr[good]
        self.face_normals: FloatArray = cross[good] / double_area[good, None]
        self.engine = one_of("TriangleMesh.engine", engine, MESH_ENGINES)
        if self.engine == "embree" and not embree_available():
            raise GeometryError(
                "TriangleMesh.engine='embree' needs the optional package embreex "
                "(pip install embreex); use engine='numpy' or 'auto'"
            )
        tri = tri[good]
        self._v0 = np.ascontiguousarray(tri[:, 0].T)  # (3, F)
        self._e1 = np.ascontiguousarray((tri[:, 1] - tri[:, 0]).T)
        self._e2 = np.ascontiguousarray((tri[:, 2] - tri[:, 0]).T)
        self._normals_soa = np.ascontiguousarray(self.face_normals.T)
        self._det_tol = GRAZING_COS * double_area[good]
        # cached: a (V, 3) min/max costs milliseconds on a large mesh, every cast needs it
        self._bounds = np.stack([verts.min(axis=0), verts.max(axis=0)])
        self._eps = self.eps
        # embree hits nearer than this (float32 tolerance) are re-cast with numpy
        self._embree_near = 1e-5 * max(
            float(np.linalg.norm(self._bounds[1] - self._bounds[0])), 1e-300
        )
        self._hierarchy = _build_hierarchy(tri, pad=1e-9 * max(scale, 1.0))
        self._embree: Any = None  # trimesh's embree intersector, built on first use
        self._closed: bool | None = None  # watertight? computed on first use

    # ------------------------------------------------------------- construction
    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        scale: float = 1.0,
        engine: str = "auto",
        name: str | None = None,
    ) -> TriangleMesh:
        """Read an STL, OBJ, PLY, ... file with trimesh.

        Parameters
        ----------
        path : the mesh file.
        scale : factor applied to the file's coordinates to get metres
            (``1e-3`` for a CAD file in millimetres).
        engine, name : as in the constructor; ``name`` defaults to the file stem.
        """
        import trimesh

        p = Path(path)
        factor = _size("TriangleMesh.load", "scale", scale)
        if not p.is_file():
            raise DataFileError(f"mesh file not found: {p}")
        if p.suffix.lower() == ".stl":
            _check_binary_stl(p)
        try:
            loaded = trimesh.load_mesh(str(p), process=False)
        except Exception as exc:  # trimesh raises many types for unreadable files
            raise DataFileError(f"cannot read mesh file {p}: {exc}") from exc
        faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))))
        if faces.size == 0:
            raise DataFileError(f"mesh file {p} holds no triangles (unreadable or empty)")
        return cls(
            np.asarray(loaded.vertices, dtype=np.float64) * factor,
            faces,
            engine=engine,
            name=name if name is not None else p.stem,
        )

    @classmethod
    def from_trimesh(
        cls, mesh: object, *, engine: str = "auto", name: str = "mesh"
    ) -> TriangleMesh:
        """Wrap a ``trimesh.Trimesh`` (coordinates already in metres)."""
        return cls(mesh.vertices, mesh.faces, engine=engine, name=name)  # type: ignore[attr-defined]

    # ------------------------------------------------------------------- queries
    @property
    def n_faces(self) -> int:
        """Number of (non-degenerate) triangles."""
        return len(self.faces)

    @property
    def resolved_engine(self) -> str:
        """The engine actually used: ``"numpy"`` or ``"embree"``."""
        if self.engine == "auto":
            use = embree_available() and self.n_faces >= EMBREE_MIN_FACES
            return "embree" if use else "numpy"
        return self.engine

    def bounds(self) -> FloatArray:
        return self._bounds.copy()

    @property
    def closed(self) -> bool:
        """True when the mesh is watertight: every edge (vertices merged by position) is
        shared by exactly two faces, so the mesh bounds a solid."""
        if self._closed is None:
            verts = np.round(self.vertices / max(self._embree_near, 1e-300) * 1e3)
            _, merged = np.unique(verts, axis=0, return_inverse=True)
            f = merged.reshape(-1)[self.faces]
            edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
            edges.sort(axis=1)
            _, counts = np.unique(edges, axis=0, return_counts=True)
            self._closed = bool(np.all(counts == 2))
        return self._closed

    def _contains(self, points: FloatArray) -> NDArray[np.bool_]:
        """Ray parity: a point is inside when a ray from it crosses the surface an odd
        number of times (an irregular direction, so edges and vertices are not hit)."""
        out = np.zeros(len(points), dtype=bool)
        lo, hi = self._bounds
        candidates = np.nonzero(np.all((points > lo) & (points < hi), axis=1))[0]
        if candidates.size == 0:
            return out
        direction = np.array([0.5773, 0.5771, 0.5776])
        direction /= np.linalg.norm(direction)
        unique, inverse = np.unique(points[candidates], axis=0, return_inverse=True)
        kernel = compiled(_crossing_counts)
        if kernel is not None:
            crossings = kernel(
                np.ascontiguousarray(unique),
                self._v0,
                self._e1,
                self._e2,
                self._det_tol,
                direction,
                self._eps,
            )
        else:  # numpy: every (point, face) pair, in chunks of at most _PAIR_CHUNK
            n_pairs = len(unique) * self.n_faces
            crossings = np.zeros(len(unique), dtype=np.int64)
            for start in range(0, n_pairs, _PAIR_CHUNK):
                pair = np.arange(start, min(start + _PAIR_CHUNK, n_pairs))
                point, face = np.divmod(pair, self.n_faces)
                o = np.ascontiguousarray(unique[point].T)
                d = np.broadcast_to(direction[:, None], o.shape)
                hit = self._moller_trumbore(o, d, face) < np.inf
                crossings += np.bincount(point[hit], minlength=len(unique))
        odd = crossings % 2 == 1
        out[candidates] = odd[inverse.reshape(-1)]
        return out

    def intersect_faces(
        self, origins: ArrayLike, directions: ArrayLike
    ) -> tuple[FloatArray, NDArray[np.int64]]:
        """Closest hit distance [m] ``(M,)`` and face index ``(M,)`` (−1 for a miss)."""
        o, d = _validate_rays(origins, directions)
        return self._cast(np.ascontiguousarray(o.T), np.ascontiguousarray(d.T))

    def _cast(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        """Rays (3, M) -> distance (M,) [m] and face index (M,) (−1 for a miss)."""
        if self.resolved_engine == "embree":
            return self._cast_embree(o, d)
        return self._cast_numpy(o, d)

    def _intersect_soa(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        t, face = self._cast(o, d)
        hit = face >= 0
        normal = self._normals_soa[:, np.where(hit, face, 0)]
        return t, _signed_normals(normal, d, hit)

    # ---------------------------------------------------------------- engines
    def _cast_numpy(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        """Traverse the box hierarchy breadth-first, then Möller–Trumbore on leaf faces."""
        m = o.shape[1]
        best_t = np.full(m, np.inf)
        best_face = np.full(m, -1, dtype=np.int64)
        if m == 0:
            return best_t, best_face
        inv = _safe_inverse(d)
        levels, order = self._hierarchy
        ray_chunk = max(1, _PAIR_CHUNK // (_LEAF * 32))
        for start in range(0, m, ray_chunk):
            stop = min(m, start + ray_chunk)
            oc, dc, ic = o[:, start:stop], d[:, start:stop], inv[:, start:stop]
            top_lo, top_hi = levels[-1]
            hit = _slab_hits(oc[:, :, None], ic[:, :, None], top_lo[:, None, :], top_hi[:, None, :])
            ray_idx, node_idx = np.nonzero(hit)
            for depth in range(len(levels) - 2, -1, -1):
                lo, hi = levels[depth]
                child = node_idx[:, None] * _BRANCH + np.arange(_BRANCH)
                ray_idx = np.broadcast_to(ray_idx[:, None], child.shape).ravel()
                child = child.ravel()
                keep = child < lo.shape[1]
                ray_idx, child = ray_idx[keep], child[keep]
                ok = _slab_hits(oc[:, ray_idx], ic[:, ray_idx], lo[:, child], hi[:, child])
                ray_idx, node_idx = ray_idx[ok], child[ok]
            # leaves -> faces
            slot = node_idx[:, None] * _LEAF + np.arange(_LEAF)
            face = order[slot.ravel()]
            ray_idx = np.broadcast_to(ray_idx[:, None], slot.shape).ravel()
            keep = face >= 0
            ray_idx, face = ray_idx[keep], face[keep]
            t_chunk = best_t[start:stop]  # views: updated in place
            f_chunk = best_face[start:stop]
            for p0 in range(0, len(face), _PAIR_CHUNK):
                r_i = ray_idx[p0 : p0 + _PAIR_CHUNK]
                f_i = face[p0 : p0 + _PAIR_CHUNK]
                t = self._moller_trumbore(oc[:, r_i], dc[:, r_i], f_i)
                good = t < np.inf
                r_i, f_i, t = r_i[good], f_i[good], t[good]
                np.minimum.at(t_chunk, r_i, t)
                winner = t == t_chunk[r_i]
                f_chunk[r_i[winner]] = f_i[winner]
        return best_t, best_face

    def _moller_trumbore(
        self, o: FloatArray, d: FloatArray, face: NDArray[np.int64], *, bounded: bool = True
    ) -> FloatArray:
        """Distance [m] of each ray (3, K) to its face (K,); ``inf`` where it misses."""
        v0, e1, e2 = self._v0[:, face], self._e1[:, face], self._e2[:, face]
        p = _cross(d, e2)
        det = _dot(e1, p)
        ok = np.abs(det) > self._det_tol[face]
        inv_det = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
        s = o - v0
        q = _cross(s, e1)
        t = _dot(e2, q) * inv_det
        if bounded:
            u = _dot(s, p) * inv_det
            v = _dot(d, q) * inv_det
            ok &= (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0)
        ok &= t > self._eps
        return np.where(ok, t, np.inf)

    def _cast_embree(self, o: FloatArray, d: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        """Embree finds the face (float32); its distance is recomputed in float64.

        Rays whose embree hit lies within embree's float32 tolerance of the
        origin (a ray starting on the surface) are re-cast with the numpy engine
        so both engines honour the same ``t > eps`` rule.
        """
        if self._embree is None:
            import trimesh
            from trimesh.ray.ray_pyembree import RayMeshIntersector

            tm = trimesh.Trimesh(self.vertices, self.faces, process=False)
            self._embree = RayMeshIntersector(tm)
        m = o.shape[1]
        best_t = np.full(m, np.inf)
        best_face = np.full(m, -1, dtype=np.int64)
        if m == 0:
            return best_t, best_face
        tri, ray = self._embree.intersects_id(o.T, d.T, multiple_hits=False)
        tri = np.asarray(tri, dtype=np.int64)
        ray = np.asarray(ray, dtype=np.int64)
        t = self._moller_trumbore(o[:, ray], d[:, ray], tri, bounded=False)
        best_t[ray] = t
        best_face[ray] = np.where(t < np.inf, tri, -1)
        redo = np.union1d(np.nonzero(best_t <= self._embree_near)[0], ray[~(t < np.inf)])
        if len(redo):
            t2, f2 = self._cast_numpy(o[:, redo], d[:, redo])
            best_t[redo] = t2
            best_face[redo] = f2
        return best_t, best_face

    def __repr__(self) -> str:
        return f"TriangleMesh(name={self.name!r}, n_faces={self.n_faces}, engine={self.engine!r})"


def _build_hierarchy(
    tri: FloatArray, *, pad: float
) -> tuple[list[tuple[FloatArray, FloatArray]], NDArray[np.int64]]:
    """Boxes over spatially sorted faces: leaves of ``_LEAF`` faces, ``_BRANCH`` children per node.

    Faces are ordered by recursive median splits of their centroids along the
    longest axis, so consecutive faces (and consecutive nodes) are close in
    space.  Returns the box levels (leaves first, each ``(lo, hi)`` of shape
    ``(3, n_nodes)``) and the face order padded with −1 to whole leaves.
    """
    centroid = tri.mean(axis=1)
    order = np.arange(len(tri))
    stack = [(0, len(tri))]
    while stack:
        a, b = stack.pop()
        if b - a <= _LEAF:
            continue
        idx = order[a:b]
        c = centroid[idx]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        # split at a multiple of the leaf size so leaves never straddle two halves
        half = ((b - a) // 2 + _LEAF - 1) // _LEAF * _LEAF
        half = min(max(half, _LEAF), b - a - 1)
        part = np.argpartition(c[:, axis], half)
        order[a:b] = idx[part]
        stack.extend([(a, a + half), (a + half, b)])
    n_leaves = -(-len(tri) // _LEAF)
    padded = np.full(n_leaves * _LEAF, -1, dtype=np.int64)
    padded[: len(tri)] = order
    lo_face = tri.min(axis=1) - pad
    hi_face = tri.max(axis=1) + pad
    starts = np.arange(0, len(tri), _LEAF)
    lo = np.minimum.reduceat(lo_face[order], starts, axis=0)
    hi = np.maximum.reduceat(hi_face[order], starts, axis=0)
    levels = [(lo, hi)]
    while len(levels[-1][0]) > _BRANCH * 4:
        lo, hi = levels[-1]
        starts = np.arange(0, len(lo), _BRANCH)
        levels.append(
            (np.minimum.reduceat(lo, starts, axis=0), np.maximum.reduceat(hi, starts, axis=0))
        )
    soa = [(np.ascontiguousarray(lo.T), np.ascontiguousarray(hi.T)) for lo, hi in levels]
    return soa, padded


def _check_binary_stl(path: Path) -> None:
    """Refuse a binary STL whose size disagrees with its triangle count (a truncated
    download or copy), naming the file and both sizes; an ASCII STL passes."""
    try:
        size = path.stat().st_size
        with path.open("rb") as fh:
            head = fh.read(84)
            ascii_start = head.lstrip().startswith(b"solid") and b"facet" in fh.read(1024)
    except OSError as exc:
        raise DataFileError(f"cannot read mesh file {path}: {exc.strerror or exc}") from None
    if ascii_start:
        return
    if size < 84:
        raise DataFileError(
            f"mesh file {path} is truncated: {size} bytes, less than a binary STL's 84-byte "
            "header; copy or export it again"
        )
    count = int.from_bytes(head[80:84], "little")
    expected = 84 + 50 * count
    if size < expected:  # (a few trailing bytes, as some exporters write, are harmless)
        raise DataFileError(
            f"mesh file {path} is truncated: its header announces {count} "
            f"triangles ({expected} bytes) but it holds {size} bytes; copy or export it again"
        )


def _crossing_counts(points, v0, e1, e2, det_tol, direction, eps):  # pragma: no cover - numba
    """How many faces a ray from each point along ``direction`` crosses, ``(n_points,)``.

    The loop form of :meth:`TriangleMesh._moller_trumbore` (same tolerances), compiled by
    numba: points ``(n, 3)`` [m]; the faces' first vertex and edges ``(3, F)``."""
    n = points.shape[0]
    counts = np.zeros(n, dtype=np.int64)
    dx, dy, dz = direction[0], direction[1], direction[2]
    for f in range(v0.shape[1]):
        e1x, e1y, e1z = e1[0, f], e1[1, f], e1[2, f]
        e2x, e2y, e2z = e2[0, f], e2[1, f], e2[2, f]
        px, py, pz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
        det = e1x * px + e1y * py + e1z * pz
        if abs(det) <= det_tol[f]:
            continue
        inv = 1.0 / det
        for i in range(n):
            sx, sy, sz = points[i, 0] - v0[0, f], points[i, 1] - v0[1, f], points[i, 2] - v0[2, f]
            u = (sx * px + sy * py + sz * pz) * inv
            if u < 0.0 or u > 1.0:
                continue
            qx, qy, qz = sy * e1z - sz * e1y, sz * e1x - sx * e1z, sx * e1y - sy * e1x
            v = (dx * qx + dy * qy + dz * qz) * inv
            if v < 0.0 or u + v > 1.0:
                continue
            if (e2x * qx + e2y * qy + e2z * qz) * inv > eps:
                counts[i] += 1
    return counts
