"""Ray → echo: reflection models giving each ray an amplitude and a time of flight.

This is the last geometric stage of the simulator.  For a batch of poses it
fires the transducer's rays, casts them at the specimen, and returns per ray

* ``amplitude = a · β`` — ``a`` the transducer's directivity at the ray's angle of
  incidence on the sensor, ``β`` the reflection factor of the model;
* ``tof`` [s] — the time of flight of the path out and back;

with ``amplitude = 0`` and ``tof = inf`` for rays that bring nothing back.

:func:`ray_echoes` also returns the hits (for plots and ground truth);
:func:`echo_arrays` returns only amplitude and τ and is the simulator's fast path.
Both work in structure-of-arrays layout ``(3, n_poses, n_rays)`` inside: rays come
from one small matrix product per block of poses (``Transducer._rays_soa``), are
cast without re-validation or transposes (``raytrace._cast_soa``), and are traced
in chunks of about 16k rays so that the temporaries stay in the CPU cache.

For the ``lambertian`` model on specimens whose shapes all provide
``Shape._kernel_params`` (planes and spheres), rays, closest hits, amplitudes and times
of flight come from one compiled pass over the rays (:func:`_lambertian_loops`, numba)
with no temporaries; other specimens and models, and installs without numba, take the
numpy path, which gives the same values to round-off.

The thesis's ray models (registry :func:`reflection_model_names`; every echo model a
setup can name, the diffraction model ``wave`` of :mod:`echocal.wave` included, is in
:func:`echo_model_names`):

``lambertian`` (thesis §2.2.1)
    β = −nᵀd (cosine of the angle of incidence), the ray returns along its own
    path: τ = 2t′/c₀ (eq. 24), and its incidence angle on the sensor equals its
    departure angle.
``specular``
    The mirror-reflected ray r = d − 2(dᵀn)n is traced back to the transducer's
    plane; it contributes (β = 1) only if it lands on the sensor area, with
    τ = (t′ + s)/c₀ for the true path (s = length of the way back), weighted once by
    the ray's own (transmit) directivity: landing on the sensor is the receive
    aperture (weighting the landing angle as well counted the directivity twice,
    which made the lobe 25–32 % too narrow).  Secondary hits on
    the way back are not traced (single bounce).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._numba import compiled
from echocal._validate import finite_array, lookup, positive_float
from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import EchocalValueError
from echocal.specimen import Shape, Specimen
from echocal.specimen.base import GRAZING_COS, KERNEL_PARAMS, KERNEL_PLANE, KERNEL_SPHERE
from echocal.specimen.casting import Hits, _as_shapes, _cast_soa, _hit_points
from echocal.transducer import Transducer

__all__ = [
    "WAVE_MODEL",
    "RayEchoes",
    "ReflectionModel",
    "echo_arrays",
    "echo_model_names",
    "ray_echoes",
    "reflection_model_names",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class RayEchoes:
    """What each ray brings back, for a batch of poses.

    Attributes
    ----------
    amplitude : a·β per ray, shape ``(n_poses, n_rays)``; 0 where nothing returns.
    tof : [s] time of flight per ray, shape ``(n_poses, n_rays)``; ``inf`` where nothing returns.
    hits : the closest hits of the outgoing rays (for plots and ground truth).
    """

    amplitude: FloatArray
    tof: FloatArray
    hits: Hits


@dataclass(frozen=True, slots=True)
class _Rays:
    """Rays and their closest hits for a chunk of poses, structure-of-arrays (internal).

    Attributes
    ----------
    origins : [m] shape ``(3, n_poses, n_rays)``.
    directions : unit, shape ``(3, n_poses, n_rays)``.
    distance : [m] shape ``(n_poses, n_rays)``; ``inf`` for a miss.
    normal : shape ``(3, n_poses, n_rays)``; facing the ray, zeros for a miss.
    shape_index : shape ``(n_poses, n_rays)``; index of the shape hit, −1 for a miss.
    positions : [m] shape ``(n_poses, 3)``.
    frames : shape ``(n_poses, 3, 3)``.
    """

    origins: FloatArray
    directions: FloatArray
    distance: FloatArray
    normal: FloatArray
    shape_index: NDArray[np.int64]
    positions: FloatArray
    frames: FloatArray


class ReflectionModel(Protocol):
    """Turns the closest hits of the rays of a chunk of poses into amplitudes and path lengths.

    Models work in the simulator's structure-of-arrays layout (component axis first,
    see :class:`_Rays`) so that no ``(n_poses, n_rays, 3)`` transposes are needed.
    """

    def __call__(self, rays: _Rays, transducer: Transducer) -> tuple[FloatArray, FloatArray]:
        """Return ``(amplitude, path_length [m])``, each shape ``(n_poses, n_rays)``."""
        ...


def _dot3(a: FloatArray, b: FloatArray) -> FloatArray:
    """Component-wise dot product of ``(3, ...)`` arrays -> ``(...)``."""
    out = a[0] * b[0]
    out += a[1] * b[1]
    out += a[2] * b[2]
    return out


def _lambertian(rays: _Rays, transducer: Transducer) -> tuple[FloatArray, FloatArray]:
    cos_incidence = _dot3(rays.normal, rays.directions)
    np.negative(cos_incidence, out=cos_incidence)
    hit = rays.distance < np.inf
    np.clip(cos_incidence, 0.0, 1.0, out=cos_incidence)
    amplitude = np.where(hit, cos_incidence, 0.0)
    amplitude *= transducer.weights
    return amplitude, 2.0 * rays.distance  # inf stays inf for a miss


def _specular(rays: _Rays, transducer: Transducer) -> tuple[FloatArray, FloatArray]:
    d, n, t = rays.directions, rays.normal, rays.distance
    hit = t < np.inf
    reflected = d - 2.0 * _dot3(d, n) * n  # (3, P, N)
    sensor_normal = rays.frames[:, :, 2].T[:, :, None]  # n of each pose, shape (3, P, 1)
    point = d * np.where(hit, t, 0.0)
    point += rays.origins  # hit point; the ray's origin for a miss (masked below)
    # Way back: p + s·r meets the sensor plane nᵀ(q − c) = 0.
    toward = _dot3(reflected, sensor_normal)
    gap = _dot3(rays.positions.T[:, :, None] - point, sensor_normal)
    with np.errstate(divide="ignore", invalid="ignore"):
        back = np.where(toward > 1e-12, gap / toward, np.inf)
    back = np.where(hit & (back > 0.0), back, np.inf)
    finite = back < np.inf
    offset = point + np.where(finite, back, 0.0) * reflected
    offset -= rays.positions.T[:, :, None]  # landing point relative to the sensor centre
    local_x = _dot3(offset, rays.frames[:, :, 0].T[:, :, None])
    local_y = _dot3(offset, rays.frames[:, :, 1].T[:, :, None])
    returns = finite & transducer.contains_local(np.stack([local_x, local_y], axis=-1))
    # the directivity counts once, on the way out (ray weight); landing on the sensor is
    # the receive aperture (weighting the landing angle too counted it twice)
    amplitude = np.where(returns, transducer.weights, 0.0)
    return amplitude, np.where(returns, t + back, np.inf)


_MODELS: dict[str, ReflectionModel] = {"lambertian": _lambertian, "specular": _specular}


def _reflection_model(name: str) -> ReflectionModel:
    """The model registered as ``name``; an unknown name lists the valid ones."""
    return lookup("reflection model", name, _MODELS)


def reflection_model_names() -> list[str]:
    """Names accepted by :func:`ray_echoes` (``lambertian``, ``specular``): the thesis's
    ray models."""
    return sorted(_MODELS)


WAVE_MODEL = "wave"
"""Name of the diffraction (Kirchhoff) echo model of :mod:`echocal.wave`."""


def echo_model_names() -> list[str]:
    """Every echo model a setup can use: the thesis's ray models and ``wave``."""
    return [*reflection_model_names(), WAVE_MODEL]


_POSE_CHUNK_RAYS = 16384  # rays traced per chunk of poses: temporaries stay in cache


def check_pose_arrays(positions: ArrayLike, frames: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Finite float64 positions ``(P, 3)`` and frames ``(P, 3, 3)`` (cheap: per pose, not ray)."""
    pos = finite_array("positions", positions, shape_tail=(3,)).reshape(-1, 3)
    frm = finite_array("frames", frames, shape_tail=(3, 3)).reshape(-1, 3, 3)
    if pos.shape[0] != frm.shape[0]:
        raise EchocalValueError(
            f"positions and frames must hold the same number of poses; got {pos.shape[0]} "
            f"and {frm.shape[0]}"
        )
    return pos, frm


def _trace(
    transducer: Transducer,
    shapes: tuple[Shape, ...],
    positions: FloatArray,
    frames: FloatArray,
) -> _Rays:
    """Fire and cast the rays of a chunk of poses (checked inputs), structure of arrays."""
    o, d = transducer._rays_soa(positions, frames)
    if not _orthonormal(frames):
        # A sheared or scaled frame gives non-unit directions: normalize as cast() does.
        norm = np.sqrt(_dot3(d, d))
        if np.any(norm == 0.0):
            raise EchocalValueError("frames must not map a ray direction to the zero vector")
        if np.any(np.abs(norm - 1.0) > 1e-12):
            d /= norm
    p, n = o.shape[1], o.shape[2]
    t, normal, index = _cast_soa(shapes, o.reshape(3, -1), d.reshape(3, -1))
    return _Rays(
        origins=o,
        directions=d,
        distance=t.reshape(p, n),
        normal=normal.reshape(3, p, n),
        shape_index=index.reshape(p, n),
        positions=positions,
        frames=frames,
    )


def _orthonormal(frames: FloatArray) -> bool:
    """Whether every frame is orthonormal to 1e-14 (then rotated unit rays stay unit)."""
    gram = np.matmul(frames.transpose(0, 2, 1), frames)
    return bool(np.all(np.abs(gram - np.eye(3)) <= 1e-14))


def _pose_chunk(n_rays: int) -> int:
    return max(1, _POSE_CHUNK_RAYS // max(n_rays, 1))


# --- fused lambertian kernel (numba) -----------------------------------------------------


def _kernel_table(shapes: tuple[Shape, ...]) -> tuple[NDArray[np.int64], FloatArray] | None:
    """Codes ``(S,)`` and parameters ``(S, KERNEL_PARAMS)`` of the shapes, or None if any
    shape has no compiled intersection (then the generic path is used).

    Only kernel-ready shapes (small planes and spheres) enter the cache: it holds its keys
    alive, and a key holding a large mesh would pin its memory for the process's life."""
    if any(s._kernel_params() is None for s in shapes):
        return None
    return _kernel_table_cached(shapes)


@lru_cache(maxsize=64)
def _kernel_table_cached(shapes: tuple[Shape, ...]) -> tuple[NDArray[np.int64], FloatArray]:
    entries = [s._kernel_params() for s in shapes]
    codes = np.array([e[0] for e in entries], dtype=np.int64)  # type: ignore[index]
    params = np.zeros((len(entries), KERNEL_PARAMS))
    for i, e in enumerate(entries):
        params[i] = e[1]  # type: ignore[index]
    codes.setflags(write=False)
    params.setflags(write=False)
    return codes, params


def _lambertian_loops(pixels, dirs, weights, positions, frames, codes, params, c0, amp, tof):
    """Fire, cast and reflect (lambertian) every ray of every pose in one pass.

    The arithmetic of ``Transducer._rays_soa``, the shapes' ``_intersect_soa`` and
    :func:`_lambertian`, ray by ray: pixels ``(3, N)`` ([u; v; 1]), local directions
    ``(3, N)``, directivity weights ``(N,)``, positions ``(P, 3)``, frames ``(P, 3, 3)``,
    shape codes ``(S,)`` and parameters ``(S, KERNEL_PARAMS)``, c₀ [m/s]; writes
    amplitude and τ [s] ``(P, N)``.  Returns 1 if a frame maps a ray to the zero vector
    (nothing is valid then), else 0.
    """
    n_poses = positions.shape[0]
    n_rays = pixels.shape[1]
    n_shapes = codes.shape[0]
    for p in range(n_poses):
        f = frames[p]  # a view per pose; per ray, no views are made
        unit = True  # orthonormal frame: rotated unit directions stay unit
        for i in range(3):
            for j in range(3):
                g = f[0, i] * f[0, j] + f[1, i] * f[1, j] + f[2, i] * f[2, j]
                if abs(g - (1.0 if i == j else 0.0)) > 1e-14:
                    unit = False
        f00, f01, f02 = f[0, 0], f[0, 1], f[0, 2]
        f10, f11, f12 = f[1, 0], f[1, 1], f[1, 2]
        f20, f21, f22 = f[2, 0], f[2, 1], f[2, 2]
        cx, cy, cz = positions[p, 0], positions[p, 1], positions[p, 2]
        for n in range(n_rays):
            u = pixels[0, n]
            v = pixels[1, n]
            ox = f00 * u + f01 * v + cx
            oy = f10 * u + f11 * v + cy
            oz = f20 * u + f21 * v + cz
            du = dirs[0, n]
            dv = dirs[1, n]
            dn = dirs[2, n]
            dx = f00 * du + f01 * dv + f02 * dn
            dy = f10 * du + f11 * dv + f12 * dn
            dz = f20 * du + f21 * dv + f22 * dn
            if not unit:
                norm = math.sqrt(dx * dx + dy * dy + dz * dz)
                if norm == 0.0:
                    return 1
                dx /= norm
                dy /= norm
                dz /= norm
            best = np.inf
            cos = 0.0
            for s in range(n_shapes):
                t = np.inf
                c = 0.0
                if codes[s] == KERNEL_PLANE:
                    sx = params[s, 0] * ox + params[s, 1] * oy + params[s, 2] * oz - params[s, 9]
                    sy = params[s, 3] * ox + params[s, 4] * oy + params[s, 5] * oz - params[s, 10]
                    sz = params[s, 6] * ox + params[s, 7] * oy + params[s, 8] * oz - params[s, 11]
                    ndd = params[s, 6] * dx + params[s, 7] * dy + params[s, 8] * dz
                    if abs(ndd) > GRAZING_COS:
                        tt = -(sz / ndd)
                        if tt > params[s, 14]:
                            m0 = (
                                tt * (params[s, 0] * dx + params[s, 1] * dy + params[s, 2] * dz)
                                + sx
                            )
                            m1 = (
                                tt * (params[s, 3] * dx + params[s, 4] * dy + params[s, 5] * dz)
                                + sy
                            )
                            if abs(m0) <= params[s, 12] and abs(m1) <= params[s, 13]:
                                t = tt
                                c = ndd if ndd < 0.0 else -ndd  # n facing the ray: n·d <= 0
                elif codes[s] == KERNEL_SPHERE:
                    r = params[s, 3]
                    fx = ox - params[s, 0]
                    fy = oy - params[s, 1]
                    fz = oz - params[s, 2]
                    b = fx * dx + fy * dy + fz * dz
                    px = fx - b * dx
                    py = fy - b * dy
                    pz = fz - b * dz
                    disc = r * r - (px * px + py * py + pz * pz)
                    if disc >= 0.0:
                        root = math.sqrt(disc)
                        cc = (fx * fx + fy * fy + fz * fz) - r * r
                        qq = -b - (root if b >= 0.0 else -root)
                        t2 = cc / qq if qq != 0.0 else 0.0
                        lo = min(qq, t2)
                        hi = max(qq, t2)
                        if lo > params[s, 4]:
                            t = lo
                        elif hi > params[s, 4]:
                            t = hi
                        if t < np.inf:
                            nx = (fx + t * dx) / r
                            ny = (fy + t * dy) / r
                            nz = (fz + t * dz) / r
                            nn = max(math.sqrt(nx * nx + ny * ny + nz * nz), 1e-300)
                            nd = (nx * dx + ny * dy + nz * dz) / nn
                            c = -nd if nd > 0.0 else nd
                if t < best:
                    best = t
                    cos = c
            if best < np.inf:
                cos = min(max(-cos, 0.0), 1.0)
                amp[p, n] = cos * weights[n]
            else:
                amp[p, n] = 0.0
            tof[p, n] = (2.0 * best) / c0
    return 0


def _fused_lambertian(
    transducer: Transducer,
    shapes: tuple[Shape, ...],
    positions: FloatArray,
    frames: FloatArray,
    c0: float,
) -> tuple[FloatArray, FloatArray] | None:
    """Amplitude and τ ``(P, N)`` from the compiled kernel, or None where it does not apply
    (numba missing, or a shape without ``_kernel_params``)."""
    table = _kernel_table(shapes) if shapes else None
    if table is None:
        return None
    kernel = compiled(_lambertian_loops)
    if kernel is None:
        return None
    n_poses, n_rays = positions.shape[0], transducer.n_rays
    amplitude = np.empty((n_poses, n_rays))
    tof = np.empty((n_poses, n_rays))
    status = kernel(
        transducer._pixels_h,  # type: ignore[attr-defined]
        transducer._dirs_soa,  # type: ignore[attr-defined]
        transducer.weights,
        positions,
        frames,
        table[0],
        table[1],
        c0,
        amplitude,
        tof,
    )
    if status:
        raise EchocalValueError("frames must not map a ray direction to the zero vector")
    return amplitude, tof


def _echo_arrays_unchecked(
    transducer: Transducer,
    shapes: tuple[Shape, ...],
    pos: FloatArray,
    frm: FloatArray,
    reflect: ReflectionModel,
    c0: float,
) -> tuple[FloatArray, FloatArray]:
    """:func:`echo_arrays` of checked float64 ``(P, 3)``, ``(P, 3, 3)`` arrays (no copies)."""
    if reflect is _lambertian:
        fused = _fused_lambertian(transducer, shapes, pos, frm, c0)
        if fused is not None:
            return fused
    n_poses, n_rays = pos.shape[0], transducer.n_rays
    amplitude = np.empty((n_poses, n_rays))
    tof = np.empty((n_poses, n_rays))
    step = _pose_chunk(n_rays)
    for lo in range(0, n_poses, step):
        sl = slice(lo, lo + step)
        amp, path = reflect(_trace(transducer, shapes, pos[sl], frm[sl]), transducer)
        amplitude[sl] = amp
        np.divide(path, c0, out=tof[sl])
    return amplitude, tof


def echo_arrays(
    transducer: Transducer,
    specimen: Specimen,
    positions: ArrayLike,
    frames: ArrayLike,
    *,
    model: str = "lambertian",
    sound_speed: float = SOUND_SPEED_WATER,
) -> tuple[FloatArray, FloatArray]:
    """Amplitude and time of flight [s] of every ray, without the hit geometry.

    The simulator's fast path: the same values as :func:`ray_echoes`, but the
    rays are traced in chunks of poses whose temporaries stay in cache and only
    the two ``(n_poses, n_rays)`` results are kept.

    Parameters
    ----------
    As :func:`ray_echoes`.

    Returns
    -------
    amplitude : a·β per ray, shape ``(n_poses, n_rays)``; 0 where nothing returns.
    tof : [s] shape ``(n_poses, n_rays)``; ``inf`` where nothing returns.
    """
    reflect = lookup("reflection model", model, _MODELS)
    c0 = positive_float("sound_speed", sound_speed)
    pos, frm = check_pose_arrays(positions, frames)
    return _echo_arrays_unchecked(transducer, _as_shapes(specimen), pos, frm, reflect, c0)


def ray_echoes(
    transducer: Transducer,
    specimen: Specimen,
    positions: ArrayLike,
    frames: ArrayLike,
    *,
    model: str = "lambertian",
    sound_speed: float = SOUND_SPEED_WATER,
) -> RayEchoes:
    """Fire, cast and reflect: amplitude and time of flight of every ray at every pose.

    Parameters
    ----------
    transducer, specimen : the probe and the part.
    positions : [m] imaging-plane centres, shape ``(n_poses, 3)``.
    frames : transducer frames ``[x', y', n]``, shape ``(n_poses, 3, 3)``.
    model : reflection model name (``lambertian`` or ``specular``).
    sound_speed : [m/s] c₀ of the medium.

    Returns
    -------
    RayEchoes with arrays of shape ``(n_poses, n_rays)`` and the hits of the
    outgoing rays.  (:func:`echo_arrays` gives the same amplitudes and times of
    flight faster when the hits are not needed.)
    """
    reflect = lookup("reflection model", model, _MODELS)
    c0 = positive_float("sound_speed", sound_speed)
    pos, frm = check_pose_arrays(positions, frames)
    shapes = _as_shapes(specimen)
    n_poses, n_rays = pos.shape[0], transducer.n_rays
    amplitude = np.empty((n_poses, n_rays))
    tof = np.empty((n_poses, n_rays))
    distance = np.empty((n_poses, n_rays))
    point = np.empty((3, n_poses, n_rays))
    normal = np.empty((3, n_poses, n_rays))
    index = np.empty((n_poses, n_rays), dtype=np.int64)
    step = _pose_chunk(n_rays)
    fused = _fused_lambertian(transducer, shapes, pos, frm, c0) if reflect is _lambertian else None
    for lo in range(0, n_poses, step):
        sl = slice(lo, lo + step)
        rays = _trace(transducer, shapes, pos[sl], frm[sl])
        if fused is None:
            amp, path = reflect(rays, transducer)
            amplitude[sl] = amp
            np.divide(path, c0, out=tof[sl])
        distance[sl] = rays.distance
        point[:, sl] = _hit_points(rays.origins, rays.directions, rays.distance)
        normal[:, sl] = rays.normal
        index[sl] = rays.shape_index
    if fused is not None:  # the same amplitudes and τ as echo_arrays, bit for bit
        amplitude, tof = fused
    hits = Hits(  # (3, P, N) -> (P, N, 3) as transposed views (no copy)
        distance=distance,
        point=point.transpose(1, 2, 0),
        normal=normal.transpose(1, 2, 0),
        shape_index=index,
    )
    return RayEchoes(amplitude=amplitude, tof=tof, hits=hits)
