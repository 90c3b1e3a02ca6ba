"""The transducer as a pinhole camera (thesis §2.1.2) and its directivity.

The sensor is an imaging plane of ``width × height`` discretized into
``n_v × n_h`` pixels (optionally cut to a circular/elliptic aperture).  The
pinhole (the thesis's "focus") sits a distance ``l`` (``pinhole_distance``)
*behind* the plane — on the side away from the
specimen — so that with the beam travelling along ``−n``::

    focus = c + l · n              (thesis eq. 5 with the beam along −n)

Each pixel fires one ray from its centre (thesis: "s is the coordinate of the
centre of the pixel") in the direction from the focus through that centre.
Local pixel coordinates ``L`` (shape ``(2, n_pixels)``) map to global ones with
the frame of thesis eqs. (9)–(12): ``G = c + T · L`` with ``T = [x', y']``.

Directivity gives each ray an amplitude from its angle ψ to the beam axis:
``gaussian`` (opening angle = −6 dB half-angle), ``piston``
(2·J₁(x)/x, x = k·a·sin ψ) or ``none``.  Because every ray leaves through a
fixed pixel, ψ — and so the directivity weight — is a per-pixel constant,
computed once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.special import j1

from echocal._validate import lookup, positive_float, positive_int
from echocal.constants import DEFAULT_CENTER_FREQUENCY, MM, SOUND_SPEED_WATER
from echocal.errors import EchocalValueError

__all__ = [
    "Directivity",
    "GaussianDirectivity",
    "NoDirectivity",
    "PistonDirectivity",
    "RayBundle",
    "Transducer",
    "directivity_names",
    "make_directivity",
]

FloatArray = NDArray[np.float64]

_RAY_BLOCK = 16384  # rays generated per matrix product (see Transducer._rays_soa)


class Directivity(Protocol):
    """Amplitude of a ray from its angle to the beam axis."""

    @property
    def name(self) -> str:
        """The model's registry name."""
        ...

    def __call__(self, angle: FloatArray) -> FloatArray:
        """Amplitude in [0, 1] (1 on axis) for off-axis angles ψ [rad], any shape."""
        ...


@dataclass(frozen=True, slots=True)
class NoDirectivity:
    """Every ray has amplitude 1."""

    name: str = field(default="none", init=False)

    def __call__(self, angle: FloatArray) -> FloatArray:
        return np.ones_like(np.asarray(angle, dtype=np.float64))


@dataclass(frozen=True, slots=True)
class GaussianDirectivity:
    """Gaussian beam: amplitude ``2^(−(ψ/ψ₀)²)``, so ψ₀ is the −6 dB half-angle.

    Attributes
    ----------
    opening_angle : [deg] ψ₀, the half-angle where the amplitude falls to ½ (−6 dB).
    """

    opening_angle: float = 10.0
    name: str = field(default="gaussian", init=False)

    def __post_init__(self) -> None:
        angle = positive_float("directivity.opening_angle", self.opening_angle)
        if angle >= 90.0:
            raise EchocalValueError(f"directivity.opening_angle must be < 90 deg; got {angle:g}")
        object.__setattr__(self, "opening_angle", angle)

    def __call__(self, angle: FloatArray) -> FloatArray:
        ratio = np.asarray(angle, dtype=np.float64) / np.deg2rad(self.opening_angle)
        return np.exp2(-(ratio**2))


@dataclass(frozen=True, slots=True)
class PistonDirectivity:
    """Far-field directivity of a baffled circular piston, ``|2·J₁(x)/x|``, x = k·a·sin ψ.

    Attributes
    ----------
    radius : [m] piston radius a.
    frequency : [Hz] frequency giving the wavenumber k = 2πf/c.
    sound_speed : [m/s] c of the medium.
    """

    radius: float = 6.35 * MM
    frequency: float = DEFAULT_CENTER_FREQUENCY
    sound_speed: float = SOUND_SPEED_WATER
    name: str = field(default="piston", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive_float("directivity.radius", self.radius))
        object.__setattr__(
            self, "frequency", positive_float("directivity.frequency", self.frequency)
        )
        object.__setattr__(
            self, "sound_speed", positive_float("directivity.sound_speed", self.sound_speed)
        )

    @property
    def first_null(self) -> float:
        """[deg] angle of the first zero of the pattern (x = 3.8317...), or 90 if none."""
        s = 3.8317059702075125 / (2 * np.pi * self.frequency / self.sound_speed * self.radius)
        return float(np.rad2deg(np.arcsin(s))) if s < 1 else 90.0

    def __call__(self, angle: FloatArray) -> FloatArray:
        k = 2.0 * np.pi * self.frequency / self.sound_speed
        x = k * self.radius * np.sin(np.asarray(angle, dtype=np.float64))
        safe = np.where(np.abs(x) < 1e-8, 1.0, x)
        return np.abs(np.where(np.abs(x) < 1e-8, 1.0, 2.0 * j1(safe) / safe))


_DIRECTIVITIES: dict[str, type] = {
    "none": NoDirectivity,
    "gaussian": GaussianDirectivity,
    "piston": PistonDirectivity,
}


def directivity_names() -> list[str]:
    """Names accepted by :func:`make_directivity`."""
    return sorted(_DIRECTIVITIES)


def make_directivity(name: str, **params: float) -> Directivity:
    """Build a directivity model by name (``none``, ``gaussian``, ``piston``)."""
    cls = lookup("directivity model", name, _DIRECTIVITIES)
    try:
        return cls(**params)
    except TypeError as exc:
        raise EchocalValueError(f"directivity {name!r}: {exc}") from None


@dataclass(frozen=True, slots=True)
class RayBundle:
    """Rays fired by the transducer at a batch of poses.

    Attributes
    ----------
    origins : [m] pixel centres, shape ``(n_poses, n_rays, 3)``.
    directions : unit directions, shape ``(n_poses, n_rays, 3)``.
    weights : directivity amplitude per ray, shape ``(n_rays,)`` (same for every pose).
    """

    origins: FloatArray
    directions: FloatArray
    weights: FloatArray


@dataclass(frozen=True)
class Transducer:
    """Pinhole-camera transducer (thesis §2.1.2).

    Attributes
    ----------
    width, height : [m] size of the imaging plane (sensor area).  For a circular
        aperture they are the diameters (equal for a disc).
    n_h, n_v : number of horizontal and vertical pixels (one ray each).
    pinhole_distance : [m] distance l of the ray model's pinhole (the thesis's "focus")
        behind the plane's centre: it only spreads the rays.  Not an acoustic focus.
    focus : [m] acoustic focal length in water of a spherically focused probe (the distance
        of the on-axis maximum at the pulse's centre frequency), or None for a flat probe.
        Used by the ``wave`` echo model (circular apertures).
    aperture : ``"rectangular"`` or ``"circular"`` (pixels outside the inscribed
        disc/ellipse are dropped).
    directivity : amplitude per ray from its angle to the beam axis.
    """

    width: float = 10.0 * MM
    height: float = 10.0 * MM
    n_h: int = 64
    n_v: int = 64
    pinhole_distance: float = 20.0 * MM
    focus: float | None = None
    aperture: Literal["rectangular", "circular"] = "rectangular"
    directivity: Directivity = field(default_factory=GaussianDirectivity)

    def __post_init__(self) -> None:
        object.__setattr__(self, "width", positive_float("transducer.width", self.width))
        object.__setattr__(self, "height", positive_float("transducer.height", self.height))
        object.__setattr__(self, "n_h", positive_int("transducer.n_h", self.n_h))
        object.__setattr__(self, "n_v", positive_int("transducer.n_v", self.n_v))
        object.__setattr__(
            self,
            "pinhole_distance",
            positive_float("transducer.pinhole_distance", self.pinhole_distance),
        )
        if self.focus is not None:
            object.__setattr__(self, "focus", positive_float("transducer.focus", self.focus))
        if self.aperture not in ("rectangular", "circular"):
            raise EchocalValueError(
                f"transducer.aperture must be 'rectangular' or 'circular'; got {self.aperture!r}"
            )
        if not callable(self.directivity):
            raise EchocalValueError(
                "transducer.directivity must be a directivity model (see make_directivity: "
                f"{', '.join(directivity_names())}); got {self.directivity!r}"
            )
        local = self._local_pixels()  # never empty: the central pixel is always inside
        local.setflags(write=False)
        object.__setattr__(self, "_local", local)
        # Direction through each pixel in the local frame [x', y', n]: (u, v, −l) / norm.
        depth = np.full(local.shape[1], -self.pinhole_distance)
        dirs = np.stack([local[0], local[1], depth], axis=1)
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        dirs.setflags(write=False)
        object.__setattr__(self, "_local_directions", dirs)
        weights = np.asarray(self.directivity(self.ray_angles), dtype=np.float64)
        weights.setflags(write=False)
        object.__setattr__(self, "_weights", weights)
        # Constants of the ray kernel (structure of arrays, one GEMM per pose batch):
        # origins = [x', y', c] @ [u; v; 1], directions = [x', y', n] @ [du; dv; dn].
        pixels_h = np.ascontiguousarray(np.vstack([local, np.ones(local.shape[1])]))
        dirs_soa = np.ascontiguousarray(dirs.T)
        pixels_h.setflags(write=False)
        dirs_soa.setflags(write=False)
        object.__setattr__(self, "_pixels_h", pixels_h)
        object.__setattr__(self, "_dirs_soa", dirs_soa)

    def _local_pixels(self) -> FloatArray:
        u = (np.arange(self.n_h) + 0.5) / self.n_h * self.width - self.width / 2
        v = (np.arange(self.n_v) + 0.5) / self.n_v * self.height - self.height / 2
        uu, vv = np.meshgrid(u, v)  # shape (n_v, n_h): rows are vertical pixels
        local = np.stack([uu.ravel(), vv.ravel()])
        if self.aperture == "circular":
            inside = (local[0] / (self.width / 2)) ** 2 + (local[1] / (self.height / 2)) ** 2
            local = local[:, inside <= 1.0]
        return np.ascontiguousarray(local)

    @property
    def local_pixels(self) -> FloatArray:
        """[m] local pixel-centre coordinates L (x', y'), shape ``(2, n_rays)`` (eq. 12)."""
        return self._local  # type: ignore[attr-defined]

    @property
    def face_radius(self) -> float:
        """[m] the face's largest radius: half the larger diameter of a disc or ellipse, half
        the diagonal of a rectangle."""
        if self.aperture == "rectangular":
            return 0.5 * math.hypot(self.width, self.height)
        return 0.5 * max(self.width, self.height)

    @property
    def n_rays(self) -> int:
        """Number of rays fired per pose (pixels inside the aperture)."""
        return int(self._local.shape[1])  # type: ignore[attr-defined]

    @property
    def local_directions(self) -> FloatArray:
        """Unit ray directions in the transducer frame ``[x', y', n]``, shape ``(n_rays, 3)``."""
        return self._local_directions  # type: ignore[attr-defined]

    @property
    def ray_angles(self) -> FloatArray:
        """[rad] angle ψ of each ray to the beam axis −n, shape ``(n_rays,)``."""
        r = np.hypot(self._local[0], self._local[1])  # type: ignore[attr-defined]
        return np.arctan2(r, self.pinhole_distance)

    @property
    def weights(self) -> FloatArray:
        """Directivity amplitude of each ray, shape ``(n_rays,)``."""
        return self._weights  # type: ignore[attr-defined]

    @property
    def fan_half_angle(self) -> float:
        """[deg] largest angle of a ray to the beam axis."""
        return float(np.rad2deg(self.ray_angles.max()))

    def contains_local(self, local: FloatArray) -> NDArray[np.bool_]:
        """Whether local points (x', y') [m], shape ``(..., 2)``, lie on the sensor area."""
        x = local[..., 0] / (self.width / 2)
        y = local[..., 1] / (self.height / 2)
        if self.aperture == "circular":
            return x**2 + y**2 <= 1.0
        return (np.abs(x) <= 1.0) & (np.abs(y) <= 1.0)

    def rays(self, positions: FloatArray, frames: FloatArray) -> RayBundle:
        """Fire the rays at a batch of poses.

        Parameters
        ----------
        positions : [m] centres of the imaging plane, shape ``(n_poses, 3)``.
        frames : transducer frames ``[x', y', n]`` as columns, shape ``(n_poses, 3, 3)``
            (from :func:`echocal.geometry.orientation_frame`).

        Returns
        -------
        RayBundle with origins and directions of shape ``(n_poses, n_rays, 3)``.
        """
        positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        frames = np.asarray(frames, dtype=np.float64).reshape(-1, 3, 3)
        o, d = self._rays_soa(positions, frames)
        # (3, P, N) -> (P, N, 3) as transposed views (no copy)
        return RayBundle(
            origins=o.transpose(1, 2, 0), directions=d.transpose(1, 2, 0), weights=self.weights
        )

    def _rays_soa(self, positions: FloatArray, frames: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Kernel of :meth:`rays`: float64 ``(P, 3)``, ``(P, 3, 3)`` in, no checks.

        Returns origins [m] and unit directions in structure-of-arrays layout
        ``(3, n_poses, n_rays)`` (C-contiguous): component k of ray n at pose p is
        ``[k, p, n]``.  Each is a matrix product ``[x', y', c] @ [u; v; 1]`` resp.
        ``[x', y', n] @ [du; dv; dn]``, done in small blocks of poses: one large GEMM
        is many times slower per pose (OpenBLAS threads and leaves the cache).
        """
        p = positions.shape[0]
        n = self.n_rays
        lhs = np.empty((2, 3, p, 3))  # [origins|directions, k, pose, j]
        frames_t = frames.transpose(1, 0, 2)  # [k, p, j] = frame[p][k, j]
        lhs[0, :, :, :2] = frames_t[:, :, :2]
        lhs[0, :, :, 2] = positions.T
        lhs[1] = frames_t
        pixels, dirs = self._pixels_h, self._dirs_soa  # type: ignore[attr-defined]
        block = max(1, _RAY_BLOCK // n)
        if p <= block:
            origins = (lhs[0].reshape(3 * p, 3) @ pixels).reshape(3, p, n)
            directions = (lhs[1].reshape(3 * p, 3) @ dirs).reshape(3, p, n)
            return origins, directions
        origins = np.empty((3, p, n))
        directions = np.empty((3, p, n))
        for lo in range(0, p, block):
            sl = slice(lo, lo + block)
            for k in range(3):
                np.matmul(lhs[0, k, sl], pixels, out=origins[k, sl])
                np.matmul(lhs[1, k, sl], dirs, out=directions[k, sl])
        return origins, directions
