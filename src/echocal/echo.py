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

Models (registry :func:`reflection_model_names`):

``lambertian`` (thesis §2.2.1)
    β = −nᵀd (cosine of the angle of incidence), the ray returns along its own
    path: τ = 2t′/c₀ (eq. 24), and its incidence angle on the sensor equals its
    departure angle.
``specular``
    The mirror-reflected ray r = d − 2(dᵀn)n is traced back to the transducer's
    plane; it contributes (β = 1) only if it lands on the sensor area, with
    τ = (t′ + s)/c₀ for the true path (s = length of the way back), weighted by
    the directivity at its angle of incidence on the sensor.  Secondary hits on
    the way back are not traced (single bounce).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, lookup, positive_float
from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import EchocalValueError
from echocal.raytrace import Hits, _as_shapes, _cast_soa, _hit_points
from echocal.specimen import Shape, Specimen
from echocal.transducer import Transducer

__all__ = [
    "RayEchoes",
    "ReflectionModel",
    "echo_arrays",
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
    incidence = np.arccos(np.clip(toward, -1.0, 1.0))
    amplitude = np.where(returns, transducer.directivity(incidence), 0.0)
    return amplitude, np.where(returns, t + back, np.inf)


_MODELS: dict[str, ReflectionModel] = {"lambertian": _lambertian, "specular": _specular}


def reflection_model_names() -> list[str]:
    """Names accepted by :func:`ray_echoes` (``lambertian``, ``specular``)."""
    return sorted(_MODELS)


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
    shapes = _as_shapes(specimen)
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
    for lo in range(0, n_poses, step):
        sl = slice(lo, lo + step)
        rays = _trace(transducer, shapes, pos[sl], frm[sl])
        amp, path = reflect(rays, transducer)
        amplitude[sl] = amp
        np.divide(path, c0, out=tof[sl])
        distance[sl] = rays.distance
        point[:, sl] = _hit_points(rays.origins, rays.directions, rays.distance)
        normal[:, sl] = rays.normal
        index[sl] = rays.shape_index
    hits = Hits(  # (3, P, N) -> (P, N, 3) as transposed views (no copy)
        distance=distance,
        point=point.transpose(1, 2, 0),
        normal=normal.transpose(1, 2, 0),
        shape_index=index,
    )
    return RayEchoes(amplitude=amplitude, tof=tof, hits=hits)
