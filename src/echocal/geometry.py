"""Frames, orientations and poses — the conventions of echocal in one place.

Conventions (docs/getting-started.md, "Conventions"):

* SI units: positions in metres.  Angles are **degrees** in every public
  function here; radians appear only inside.
* World frame: z up; the specimen lies around z = 0, the transducer above it.
* Orientation (azimuth φ, co-elevation θ), thesis eq. (8)::

      n = [sin θ cos φ, sin θ sin φ, cos θ]

  The beam travels along **−n**, so θ = 0 fires straight down.  Signed θ is
  allowed: (φ, −θ) is the same beam as (φ + 180°, θ).  At θ = 0 the azimuth
  has no effect (the pole).
* The pole-free alternative, as on a gimbal positioner: tilt α about the
  world x axis, then tilt β about the world y axis, applied to the up vector::

      n = R_y(β) R_x(α) ẑ = [sin β cos α, −sin α, cos β cos α]

  (α, β) = (0, 0) fires straight down; the map is smooth there.  Conversions
  between the two are exact (up to floating point) both ways.
* The transducer frame (thesis eqs. 9–10) has columns ``[x', y', n]`` with
  ``y' = [−sin φ, cos φ, 0]`` and ``x' = y' × n``; it is right-handed and
  orthonormal for every orientation.

All functions broadcast over leading axes: angles of shape ``(...)`` give
vectors of shape ``(..., 3)`` and frames of shape ``(..., 3, 3)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, finite_float, one_of
from echocal.errors import GeometryError

__all__ = [
    "PARAMETERIZATIONS",
    "Pose",
    "angle_between",
    "angles_of",
    "beam_direction",
    "convert_angles",
    "normal_to_orientation",
    "normal_to_tilt",
    "orientation_frame",
    "orientation_normal",
    "orientation_to_tilt",
    "pose_from_angles",
    "poses_to_arrays",
    "tilt_frame",
    "tilt_normal",
    "tilt_to_orientation",
]

FloatArray = NDArray[np.float64]


def orientation_normal(azimuth: ArrayLike, coelevation: ArrayLike) -> FloatArray:
    """Unit normal n of an orientation, thesis eq. (8).

    Parameters
    ----------
    azimuth, coelevation : [deg], broadcastable shapes ``(...)``

    Returns
    -------
    n : shape ``(..., 3)``; the beam travels along ``-n``.
    """
    phi = np.deg2rad(np.asarray(azimuth, dtype=np.float64))
    theta = np.deg2rad(np.asarray(coelevation, dtype=np.float64))
    phi, theta = np.broadcast_arrays(phi, theta)
    sin_t = np.sin(theta)
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), np.cos(theta)], axis=-1)


def beam_direction(azimuth: ArrayLike, coelevation: ArrayLike) -> FloatArray:
    """Unit direction the beam travels, ``-n``; shape ``(..., 3)``."""
    return -orientation_normal(azimuth, coelevation)


def orientation_frame(azimuth: ArrayLike, coelevation: ArrayLike) -> FloatArray:
    """Transducer frame ``[x', y', n]`` as columns, thesis eqs. (8)–(10).

    Returns
    -------
    frame : shape ``(..., 3, 3)``; ``frame[..., :, 0]`` is x', ``[..., :, 1]`` is
        y', ``[..., :, 2]`` is n.  Orthonormal and right-handed.
    """
    phi = np.deg2rad(np.asarray(azimuth, dtype=np.float64))
    theta = np.deg2rad(np.asarray(coelevation, dtype=np.float64))
    phi, theta = np.broadcast_arrays(phi, theta)
    cp, sp, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
    frame = np.empty((*phi.shape, 3, 3))
    frame[..., :, 0] = _columns(ct * cp, ct * sp, -st)  # x' = y' × n
    frame[..., :, 1] = _columns(-sp, cp, 0.0)  # y'
    frame[..., :, 2] = _columns(st * cp, st * sp, ct)  # n
    return frame


def _columns(x: ArrayLike, y: ArrayLike, z: ArrayLike) -> FloatArray:
    """Stack three broadcastable components into vectors on a new last axis."""
    x, y, z = np.broadcast_arrays(x, y, z)
    out = np.empty((*x.shape, 3))
    out[..., 0], out[..., 1], out[..., 2] = x, y, z
    return out


def tilt_normal(tilt_x: ArrayLike, tilt_y: ArrayLike) -> FloatArray:
    """Unit normal for gimbal tilts: ``n = R_y(tilt_y) R_x(tilt_x) ẑ``; shape ``(..., 3)``.

    Parameters
    ----------
    tilt_x, tilt_y : [deg] rotations about the world x axis, then the world y axis.
    """
    return tilt_frame(tilt_x, tilt_y)[..., :, 2]


def tilt_frame(tilt_x: ArrayLike, tilt_y: ArrayLike) -> FloatArray:
    """Gimbal frame ``R_y(tilt_y) R_x(tilt_x)`` as a ``(..., 3, 3)`` rotation matrix.

    Its columns are the images of the world x, y, z axes; column 2 is n.
    """
    a = np.deg2rad(np.asarray(tilt_x, dtype=np.float64))
    b = np.deg2rad(np.asarray(tilt_y, dtype=np.float64))
    a, b = np.broadcast_arrays(a, b)
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    frame = np.empty((*a.shape, 3, 3))
    frame[..., :, 0] = _columns(cb, 0.0, -sb)
    frame[..., :, 1] = _columns(sb * sa, ca, cb * sa)
    frame[..., :, 2] = _columns(sb * ca, -sa, cb * ca)
    return frame


def _unit(name: str, vectors: ArrayLike) -> FloatArray:
    v = finite_array(name, vectors, shape_tail=(3,))
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise GeometryError(f"{name} must be non-zero vectors; got a zero vector")
    return v / norm


def _angles_out(values: FloatArray) -> FloatArray:
    """Angles [deg] as returned by the conversions here: a ``numpy.float64`` for one
    orientation (shape ``()``), else an array of shape ``(...)``; never −0.0."""
    return (np.asarray(values, dtype=np.float64) + 0.0)[()]  # −0.0 + 0.0 is +0.0


def normal_to_orientation(normal: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Inverse of :func:`orientation_normal` with θ ∈ [0, 180] and φ ∈ (−180, 180].

    At the pole (θ = 0 or 180) the azimuth is undefined and returned as 0.

    Returns
    -------
    azimuth, coelevation : [deg], shape ``(...)``: ``numpy.float64`` scalars for one
        normal of shape ``(3,)``, arrays otherwise; never −0.0.
    """
    n = _unit("normal", normal)
    horizontal = np.hypot(n[..., 0], n[..., 1])
    coelevation = np.rad2deg(np.arctan2(horizontal, n[..., 2]))
    azimuth = np.rad2deg(np.arctan2(n[..., 1], n[..., 0]))
    azimuth = np.where(horizontal > 1e-15, azimuth, 0.0)
    azimuth = np.where(azimuth <= -180.0, azimuth + 360.0, azimuth)
    return _angles_out(azimuth), _angles_out(coelevation)


def normal_to_tilt(normal: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Inverse of :func:`tilt_normal`: tilts with tilt_x ∈ [−90, 90], tilt_y ∈ (−180, 180].

    Returns
    -------
    tilt_x, tilt_y : [deg], shape ``(...)``: ``numpy.float64`` scalars for one normal of
        shape ``(3,)``, arrays otherwise; never −0.0.
    """
    n = _unit("normal", normal)
    tilt_x = np.rad2deg(np.arcsin(np.clip(-n[..., 1], -1.0, 1.0)))
    tilt_y = np.rad2deg(np.arctan2(n[..., 0], n[..., 2]))
    return _angles_out(tilt_x), _angles_out(tilt_y)


def orientation_to_tilt(
    azimuth: ArrayLike, coelevation: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """(azimuth, co-elevation) [deg] → (tilt_x, tilt_y) [deg] of the same beam.

    Broadcasts; returns ``numpy.float64`` scalars for scalar angles, arrays of the
    broadcast shape otherwise (as :func:`normal_to_tilt`); never −0.0.
    """
    return normal_to_tilt(orientation_normal(azimuth, coelevation))


def tilt_to_orientation(tilt_x: ArrayLike, tilt_y: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """(tilt_x, tilt_y) [deg] → canonical (azimuth, co-elevation) [deg] of the same beam.

    Broadcasts; returns ``numpy.float64`` scalars for scalar angles, arrays of the
    broadcast shape otherwise (as :func:`normal_to_orientation`); never −0.0.
    """
    return normal_to_orientation(tilt_normal(tilt_x, tilt_y))


def angle_between(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Angle between vectors [deg], accurate for tiny angles (atan2 form); shape ``(...)``."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    return np.rad2deg(np.arctan2(cross, dot))


@dataclass(frozen=True, slots=True)
class Pose:
    """Where the transducer is and where it points.

    Attributes
    ----------
    x, y, z : [m] position of the centre of the transducer's imaging plane.
    azimuth, coelevation : [deg] orientation, thesis eq. (8); the beam travels
        along ``-n``.  Signed co-elevation is allowed.
    """

    x: float
    y: float
    z: float
    azimuth: float = 0.0
    coelevation: float = 0.0
    gimbal: bool = False

    def __post_init__(self) -> None:
        for field in ("x", "y", "z", "azimuth", "coelevation"):
            object.__setattr__(self, field, finite_float(f"pose.{field}", getattr(self, field)))
        object.__setattr__(self, "gimbal", bool(self.gimbal))

    @classmethod
    def from_tilt(cls, x: float, y: float, z: float, tilt_x: float, tilt_y: float) -> Pose:
        """Pose from gimbal tilts [deg] about the world x then y axes.

        The pose is marked ``gimbal=True``: its frame is the gimbal's rotation
        (:func:`tilt_frame`), so the probe does not roll about its axis as the
        tilts pass near the pole — as on a real gimbal positioner.
        """
        tx = finite_float("pose.tilt_x", tilt_x)
        ty = finite_float("pose.tilt_y", tilt_y)
        azimuth, coelevation = tilt_to_orientation(tx, ty)
        return cls(x, y, z, float(azimuth), float(coelevation), gimbal=True)

    @property
    def position(self) -> FloatArray:
        """[m] position as an array of shape ``(3,)``."""
        return np.array([self.x, self.y, self.z])

    @property
    def normal(self) -> FloatArray:
        """Unit normal n, shape ``(3,)``."""
        return orientation_normal(self.azimuth, self.coelevation)

    @property
    def beam_direction(self) -> FloatArray:
        """Unit direction the beam travels (``-n``), shape ``(3,)``."""
        return -self.normal

    @property
    def frame(self) -> FloatArray:
        """Transducer frame ``[x', y', n]`` as columns, shape ``(3, 3)``.

        Thesis eqs. (9)–(10) for an azimuth/co-elevation positioner; the gimbal
        rotation for poses made with :meth:`from_tilt`.  Column 2 is n either way.
        """
        if self.gimbal:
            return tilt_frame(*self.tilt)
        return orientation_frame(self.azimuth, self.coelevation)

    @property
    def tilt(self) -> tuple[float, float]:
        """(tilt_x, tilt_y) [deg] of the same beam."""
        tx, ty = orientation_to_tilt(self.azimuth, self.coelevation)
        return float(tx), float(ty)

    def with_orientation(self, azimuth: float, coelevation: float) -> Pose:
        """The same position with another orientation [deg]."""
        return Pose(self.x, self.y, self.z, azimuth, coelevation)

    def with_tilt(self, tilt_x: float, tilt_y: float) -> Pose:
        """The same position with another orientation given as gimbal tilts [deg]."""
        return Pose.from_tilt(self.x, self.y, self.z, tilt_x, tilt_y)

    def as_array(self) -> FloatArray:
        """``[x, y, z, azimuth, coelevation]`` ([m], [deg]), shape ``(5,)``; no gimbal flag."""
        return np.array([self.x, self.y, self.z, self.azimuth, self.coelevation])

    @classmethod
    def from_array(cls, values: ArrayLike) -> Pose:
        """Inverse of :meth:`as_array`."""
        v = finite_array("pose", values, shape_tail=(5,))
        x, y, z, azimuth, coelevation = (float(c) for c in v)
        return cls(x, y, z, azimuth, coelevation)


def poses_to_arrays(poses: Sequence[Pose]) -> tuple[FloatArray, FloatArray]:
    """Stack poses into positions ``(P, 3)`` [m] and frames ``(P, 3, 3)``."""
    if len(poses) == 1 and not poses[0].gimbal:  # the hot path of single measurements
        pose = poses[0]
        return np.array([[pose.x, pose.y, pose.z]]), _scalar_frame(pose.azimuth, pose.coelevation)
    values = np.array([(p.x, p.y, p.z, p.azimuth, p.coelevation) for p in poses]).reshape(-1, 5)
    frames = orientation_frame(values[:, 3], values[:, 4])
    gimbal = np.array([p.gimbal for p in poses], dtype=bool)
    if gimbal.any():
        tx, ty = orientation_to_tilt(values[gimbal, 3], values[gimbal, 4])
        frames[gimbal] = tilt_frame(tx, ty)
    return values[:, :3], frames


def _scalar_frame(azimuth: float, coelevation: float) -> FloatArray:
    """:func:`orientation_frame` of one orientation [deg], shape ``(1, 3, 3)`` (scalar math)."""
    phi, theta = math.radians(azimuth), math.radians(coelevation)
    cp, sp, ct, st = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
    return np.array([[[ct * cp, -sp, st * cp], [ct * sp, cp, st * sp], [-st, 0.0, ct]]])


PARAMETERIZATIONS = ("azimuth-coelevation", "tilt")
"""Names of the two orientation parameterizations: (azimuth, co-elevation) and gimbal tilts."""


def pose_from_angles(position: ArrayLike, a: float, b: float, parameterization: str) -> Pose:
    """Pose at ``position`` [m] whose orientation is ``(a, b)`` [deg] in ``parameterization``.

    ``"azimuth-coelevation"``: (a, b) = (φ, θ); ``"tilt"``: (a, b) = (tilt_x, tilt_y).
    """
    x, y, z = (float(v) for v in finite_array("position", position, shape_tail=(3,)))
    if parameterization == "tilt":
        return Pose.from_tilt(x, y, z, a, b)
    one_of("parameterization", parameterization, PARAMETERIZATIONS)
    return Pose(x, y, z, a, b)


def angles_of(pose: Pose, parameterization: str) -> tuple[float, float]:
    """The orientation of ``pose`` as ``(a, b)`` [deg] in ``parameterization``."""
    one_of("parameterization", parameterization, PARAMETERIZATIONS)
    if parameterization == "tilt":
        return pose.tilt
    return pose.azimuth, pose.coelevation


def convert_angles(
    a: ArrayLike, b: ArrayLike, source: str, target: str
) -> tuple[FloatArray, FloatArray]:
    """Convert orientation angles [deg] between parameterizations (vectorized).

    Returns ``numpy.float64`` scalars for scalar angles, arrays otherwise; never −0.0.
    """
    one_of("parameterization", source, PARAMETERIZATIONS)
    one_of("parameterization", target, PARAMETERIZATIONS)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if source == target:
        return _angles_out(a), _angles_out(b)
    if source == "tilt":
        return tilt_to_orientation(a, b)
    return orientation_to_tilt(a, b)
