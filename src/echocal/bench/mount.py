"""How the probe sits on the positioner: beam squint and pivot offset.

A real probe's acoustic axis is not its mechanical axis (beam squint, measured by
EN 12668-2 and ASTM E1065), and a gimbal's axes do not pass through the centre of the
probe's face (pivot offset), so a tilt also moves the face.  :class:`ProbeMount` turns the
positioner's frame into the acoustic frame and face position the sound leaves from.

Conventions (frames are ``[x', y', n]`` as columns; the beam travels along −n):

- squint ``(s_x, s_y)`` [deg]: the acoustic frame is ``F · S`` with ``S =
  R_y(s_y) R_x(s_x)`` (:func:`~echocal.geometry.tilt_frame`), a rotation about the probe's
  own x' axis by ``s_x`` then about its y' axis by ``s_y``;
- pivot offset ``o`` [m], in the probe frame: the vector from the gimbal's centre of
  rotation to the face centre.  The commanded position is where the face centre is at zero
  tilt, so a frame ``F`` puts the face at ``p + (F − I) · o``.  A face 30 mm below the
  pivot is ``o = (0, 0, −0.03)`` (n points up, away from the part).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal._validate import finite_array
from echocal.geometry import tilt_frame

__all__ = ["ProbeMount"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, kw_only=True)
class ProbeMount:
    """The probe's acoustic axis and face relative to the positioner.

    Attributes
    ----------
    squint : [deg] ``(s_x, s_y)``, the acoustic axis's rotation about the probe's x' then
        y' axis, shape (2,).
    pivot_offset : [m] from the gimbal's centre of rotation to the face centre, in the
        probe frame ``[x', y', n]``, shape (3,).
    """

    squint: tuple[float, float] = (0.0, 0.0)
    pivot_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        squint = finite_array("bench.probe.squint", self.squint, shape_tail=(2,)).reshape(2)
        offset = finite_array("bench.probe.pivot_offset", self.pivot_offset, shape_tail=(3,))
        object.__setattr__(self, "squint", (float(squint[0]), float(squint[1])))
        object.__setattr__(self, "pivot_offset", tuple(float(v) for v in offset.reshape(3)))

    @property
    def is_ideal(self) -> bool:
        """True when the acoustic axis is the mechanical one and the pivot is on the face."""
        return not any(self.squint) and not any(self.pivot_offset)

    @property
    def squint_rotation(self) -> FloatArray:
        """``S``, shape (3, 3): the acoustic frame in the probe frame."""
        return tilt_frame(*self.squint)

    def place(self, positions: FloatArray, frames: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Face centres [m] ``(P, 3)`` and acoustic frames ``(P, 3, 3)`` of the positioner's
        commanded positions [m] ``(P, 3)`` and frames ``(P, 3, 3)``."""
        offset = np.asarray(self.pivot_offset)
        faces = positions + np.einsum("pij,j->pi", frames, offset) - offset
        acoustic = frames @ self.squint_rotation if any(self.squint) else frames
        return faces, acoustic

    def mechanical_tilts(self, acoustic_tilts: FloatArray) -> FloatArray:
        """Gimbal tilts [deg] ``(n, 2)`` whose acoustic axis is that of ``acoustic_tilts``
        [deg] ``(n, 2)``: ``R_y(t_y) R_x(t_x) m = n_a`` with ``m = S ẑ`` solved exactly
        for the normal (the roll about the axis is the gimbal's)."""
        m = self.squint_rotation[:, 2]
        target = tilt_frame(acoustic_tilts[:, 0], acoustic_tilts[:, 1])[:, :, 2]
        # R_y R_x m = n_a  ⇔  R_x m = R_y⁻¹ n_a; the x component of R_x m is m_x, so
        # t_y solves cos(t_y) n_x − sin(t_y) n_z = m_x, i.e. ρ cos(t_y + ψ) = m_x; then t_x
        # turns (m_y, m_z) onto the rest
        nx, nz = target[:, 0], target[:, 2]
        rho, phi = np.hypot(nx, nz), np.arctan2(nz, nx)
        ty = np.arccos(np.clip(m[0] / rho, -1.0, 1.0)) - phi
        ty = np.where(ty > np.pi, ty - 2.0 * np.pi, ty)
        ty = np.where(ty < -np.pi, ty + 2.0 * np.pi, ty)
        alt = -np.arccos(np.clip(m[0] / rho, -1.0, 1.0)) - phi  # the other root: the smaller
        alt = np.where(alt < -np.pi, alt + 2.0 * np.pi, alt)
        ty = np.where(np.abs(alt) < np.abs(ty), alt, ty)
        cy, sy = np.cos(ty), np.sin(ty)
        # v = R_y⁻¹ n_a: its (y, z) is R_x applied to (m_y, m_z)
        vy = target[:, 1]
        vz = sy * nx + cy * nz
        tx = np.arctan2(vz, vy) - np.arctan2(m[2], m[1])
        tx = (tx + np.pi) % (2.0 * np.pi) - np.pi
        return np.rad2deg(np.stack([tx, ty], axis=1))
