"""Grain noise: the coherent backscatter of a material's grains.

The part holds a fixed random cloud of point scatterers (the grains' impedance
fluctuations) in a layer below its front face: ``scatterers`` points uniform in a square
of side ``width`` around the reference position and ``depth`` deep, each with a normal
random amplitude, drawn once from ``seed`` — a property of the part, not of the run, so a
pose always sees the same grains the same way and repeated A-scans at one pose repeat
their grain signal exactly (it does not average away, unlike the receiver's noise).
Neighbouring poses see overlapping sets of grains: the grain signal is correlated over
about a beam width.

Each scatterer returns the pulse delayed by its two-way path, the part of it below the
front face at the part's sound speed (a straight path: refraction is neglected, which
holds near normal incidence, where calibration works), weighted by the probe's pulse-echo
directivity D(ψ)², D the far-field pattern of a piston of the probe's radius at the
pulse's centre frequency.  The whole signal is scaled so that at the reference pose its
peak is ``level_db`` [dB] relative to the reference echo's peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal._validate import finite_float, positive_float
from echocal.errors import EchocalValueError
from echocal.signal import Pulse, RecordingWindow
from echocal.signal.synthesis import _synthesize_2d
from echocal.transducer import PistonDirectivity

__all__ = ["MAX_SCATTERERS", "GrainField", "GrainNoise"]

FloatArray = NDArray[np.float64]

MAX_SCATTERERS = 20000
"""The most grains a field may hold (each A-scan sums them all)."""


@dataclass(frozen=True, kw_only=True)
class GrainNoise:
    """The grain-noise settings (see the module).

    Attributes
    ----------
    level_db : [dB] the grain signal's peak at the reference pose relative to the
        reference echo's peak (e.g. -30).
    scatterers : how many grains (1 to :data:`MAX_SCATTERERS`).
    depth : [m] thickness of the scattering layer below the front face.
    width : [m] side of the square it covers, centred below the reference position.
    seed : the grain field's seed (the part's identity, not the run's).
    """

    level_db: float
    scatterers: int = 400
    depth: float = 0.01
    width: float = 0.02
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "level_db", finite_float("bench.grain.level_db", self.level_db))
        n = self.scatterers
        if (
            isinstance(n, bool)
            or not isinstance(n, int | np.integer)
            or not (1 <= n <= MAX_SCATTERERS)
        ):
            raise EchocalValueError(
                f"bench.grain.scatterers must be an integer in 1..{MAX_SCATTERERS}; got {n!r}"
            )
        object.__setattr__(self, "depth", positive_float("bench.grain.depth", self.depth))
        object.__setattr__(self, "width", positive_float("bench.grain.width", self.width))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise EchocalValueError(f"bench.grain.seed must be an integer >= 0; got {self.seed!r}")


@dataclass(frozen=True, kw_only=True)
class GrainField:
    """A drawn grain field and how its echoes reach the probe.

    Attributes
    ----------
    points : [m] scatterer positions, shape (S, 3).
    depths : [m] their depths below the front face, shape (S,).
    amplitudes : [a.u.] their reflectivities (before the level's scale), shape (S,).
    surface_normal : the front face's upward unit normal, shape (3,).
    directivity : the probe's far-field pattern D(ψ).
    sound_speed, part_speed : [m/s] in the coupling medium and in the part.
    """

    points: FloatArray
    depths: FloatArray
    amplitudes: FloatArray
    surface_normal: FloatArray
    directivity: PistonDirectivity
    sound_speed: float
    part_speed: float

    @classmethod
    def draw(
        cls,
        grain: GrainNoise,
        *,
        surface_point: FloatArray,
        surface_normal: FloatArray,
        directivity: PistonDirectivity,
        sound_speed: float,
        part_speed: float,
    ) -> GrainField:
        """The field of ``grain`` below ``surface_point`` [m] (3,) of a face whose upward
        normal is ``surface_normal`` (3,)."""
        rng = np.random.default_rng(grain.seed)
        n = grain.scatterers
        lateral = (rng.random((n, 2)) - 0.5) * grain.width
        depths = rng.random(n) * grain.depth
        amplitudes = rng.standard_normal(n)
        normal = surface_normal / np.linalg.norm(surface_normal)
        helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u = np.cross(normal, helper)
        u /= np.linalg.norm(u)
        v = np.cross(normal, u)
        points = surface_point + lateral[:, :1] * u + lateral[:, 1:] * v - depths[:, None] * normal
        return cls(
            points=points,
            depths=depths,
            amplitudes=amplitudes,
            surface_normal=normal,
            directivity=directivity,
            sound_speed=sound_speed,
            part_speed=part_speed,
        )

    def ascans(
        self, faces: FloatArray, frames: FloatArray, pulse: Pulse, window: RecordingWindow
    ) -> FloatArray:
        """Grain A-scans [a.u., unscaled] ``(P, n_samples)`` of probes at ``faces`` [m]
        ``(P, 3)`` whose acoustic frames are ``frames`` ``(P, 3, 3)``."""
        v = self.points[None, :, :] - faces[:, None, :]  # (P, S, 3)
        r = np.linalg.norm(v, axis=-1)
        beam = -frames[:, :, 2]  # (P, 3)
        cos_psi = np.clip(np.einsum("psk,pk->ps", v, beam) / r, -1.0, 1.0)
        weight = self.directivity(np.arccos(cos_psi)) ** 2
        height = np.maximum(-(v @ self.surface_normal), 1e-12)  # vertical drop to the grain
        in_part = np.minimum(r * self.depths[None, :] / height, r)
        tof = 2.0 * ((r - in_part) / self.sound_speed + in_part / self.part_speed)
        amps = np.where(cos_psi > 0.0, weight * self.amplitudes[None, :], 0.0)
        tof = np.where(cos_psi > 0.0, tof, np.inf)
        return _synthesize_2d(amps, tof, pulse, window, "fast", None)
