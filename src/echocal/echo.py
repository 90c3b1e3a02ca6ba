"""Ray → echo: reflection models giving each ray an amplitude and a time of flight.

This is the last geometric stage of the simulator.  For a batch of poses it
fires the transducer's rays, casts them at the specimen, and returns per ray

* ``amplitude = a · β`` — ``a`` the transducer's directivity at the ray's angle of
  incidence on the sensor, ``β`` the reflection factor of the model;
* ``tof`` [s] — the time of flight of the path out and back;

with ``amplitude = 0`` and ``tof = inf`` for rays that bring nothing back.

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
from numpy.typing import NDArray

from echocal._validate import lookup, positive_float
from echocal.constants import SOUND_SPEED_WATER
from echocal.raytrace import Hits, cast
from echocal.specimen import Specimen
from echocal.transducer import RayBundle, Transducer

__all__ = [
    "RayEchoes",
    "ReflectionModel",
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


class ReflectionModel(Protocol):
    """Turns the hits of a ray bundle into amplitudes and path lengths."""

    def __call__(
        self,
        rays: RayBundle,
        hits: Hits,
        transducer: Transducer,
        positions: FloatArray,
        frames: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Return ``(amplitude, path_length [m])``, each shape ``(n_poses, n_rays)``."""
        ...


def _lambertian(
    rays: RayBundle,
    hits: Hits,
    transducer: Transducer,
    positions: FloatArray,
    frames: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    cos_incidence = -np.einsum("pni,pni->pn", hits.normal, rays.directions)
    hit = np.isfinite(hits.distance)
    beta = np.where(hit, np.clip(cos_incidence, 0.0, 1.0), 0.0)
    amplitude = rays.weights[None, :] * beta
    return amplitude, np.where(hit, 2.0 * hits.distance, np.inf)


def _specular(
    rays: RayBundle,
    hits: Hits,
    transducer: Transducer,
    positions: FloatArray,
    frames: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    hit = np.isfinite(hits.distance)
    d, n = rays.directions, hits.normal
    reflected = d - 2.0 * np.einsum("pni,pni->pn", d, n)[..., None] * n
    sensor_normal = frames[:, None, :, 2]  # n of each pose, shape (P, 1, 3)
    point = np.where(hit[..., None], hits.point, 0.0)
    # Way back: p + s·r meets the sensor plane nᵀ(q − c) = 0.
    toward = np.einsum("pni,pni->pn", reflected, np.broadcast_to(sensor_normal, reflected.shape))
    gap = np.einsum("pni,pi->pn", positions[:, None, :] - point, frames[:, :, 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        back = np.where(toward > 1e-12, gap / toward, np.inf)
    back = np.where(hit & (back > 0.0), back, np.inf)
    landing = point + np.where(np.isfinite(back), back, 0.0)[..., None] * reflected
    local = np.einsum("pni,pik->pnk", landing - positions[:, None, :], frames[:, :, :2])
    returns = np.isfinite(back) & transducer.contains_local(local)
    incidence = np.arccos(np.clip(toward, -1.0, 1.0))
    amplitude = np.where(returns, transducer.directivity(incidence), 0.0)
    return amplitude, np.where(returns, hits.distance + back, np.inf)


_MODELS: dict[str, ReflectionModel] = {"lambertian": _lambertian, "specular": _specular}


def reflection_model_names() -> list[str]:
    """Names accepted by :func:`ray_echoes` (``lambertian``, ``specular``)."""
    return sorted(_MODELS)


def ray_echoes(
    transducer: Transducer,
    specimen: Specimen,
    positions: FloatArray,
    frames: FloatArray,
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
    RayEchoes with arrays of shape ``(n_poses, n_rays)``.
    """
    reflect = lookup("reflection model", model, _MODELS)
    c0 = positive_float("sound_speed", sound_speed)
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    frames = np.asarray(frames, dtype=np.float64).reshape(-1, 3, 3)
    rays = transducer.rays(positions, frames)
    hits = cast(specimen, rays.origins, rays.directions)
    amplitude, path = reflect(rays, hits, transducer, positions, frames)
    return RayEchoes(amplitude=amplitude, tof=path / c0, hits=hits)
