"""Plane-wave reflection and transmission coefficients at a fluid–solid interface.

Conventions (as Schmerr, *Fundamentals of Ultrasonic Nondestructive Evaluation*,
2nd ed. 2016, §6; formulas of Brekhovskikh, *Waves in Layered Media*, 1980, §4):

- Time dependence e^{−iωt}.  Beyond a critical angle the refracted wave is evanescent,
  cos θ = +i·√(sin²θ − 1) (it decays away from the interface), and the coefficients
  are complex (a phase shift of the reflected wave).
- Every coefficient is a ratio of **stress (pressure) amplitudes**: a wave's amplitude is
  ρ·c·V, V its particle-velocity amplitude along its polarisation.  In a fluid that is
  the acoustic pressure.  A longitudinal wave is polarised along its direction of travel
  (compression positive, like pressure); a shear wave along k̂ × ŷ, where ŷ is normal to
  the plane of incidence, x̂ the interface tangent towards which the wave travels and ẑ
  the interface normal pointing from the incident medium into the other one.
- Angles are in degrees from the interface normal, incidence angles in [0, 90].

With the oblique impedances Z₁ = ρ₁c₁/cos θ₁, Z_L = ρ₂c_L/cos θ_L, Z_T = ρ₂c_T/cos θ_T
and D = Z_L cos²2θ_T + Z_T sin²2θ_T + Z₁:

- fluid → solid:  R = (Z_L cos²2θ_T + Z_T sin²2θ_T − Z₁)/D,
  T_L = 2Z_L cos 2θ_T / D,  T_T = 2Z_T sin 2θ_T / D;
- solid → fluid, longitudinal incidence:  R_LL = (Z₁ + Z_T sin²2θ_T − Z_L cos²2θ_T)/D,
  R_LT = 2Z_T sin 2θ_T cos 2θ_T / D,  T = 2Z₁ cos 2θ_T / D.

At normal incidence they reduce to (Z₂ − Z₁)/(Z₂ + Z₁), 2Z₂/(Z₁ + Z₂) and, on the way
back, 2Z₁/(Z₁ + Z₂); for a "solid" without shear (c_T = 0) to the fluid–fluid formulas.
Energy flux across the interface: |R|² + Σ (Z_in/Z_out)·|T|² = 1 over the propagating
waves (oblique impedances; evanescent waves carry none).  The code multiplies D by
cos θ₁ cos θ_L cos θ_T so that nothing divides by zero at a critical angle.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array
from echocal.errors import EchocalValueError


@runtime_checkable
class Material(Protocol):
    """What the coefficients need of a medium: :class:`echocal.materials.Material` has it
    (declared here so that this module, below ``materials`` in the house, imports nothing
    of it)."""

    @property
    def name(self) -> str: ...
    @property
    def density(self) -> float: ...  # [kg/m³]
    @property
    def longitudinal_speed(self) -> float: ...  # [m/s]
    @property
    def shear_speed(self) -> float: ...  # [m/s], 0 for a fluid
    @property
    def is_fluid(self) -> bool: ...


__all__ = [
    "CriticalAngles",
    "SolidReflection",
    "Transmission",
    "critical_angles",
    "reflection_fluid_solid",
    "reflection_normal",
    "reflection_solid_fluid",
    "snell_angle",
    "transmission_fluid_solid",
    "transmission_normal",
    "transmission_solid_fluid",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


class Transmission(NamedTuple):
    """Fluid → solid transmission; each field has the incidence angles' shape."""

    longitudinal: ComplexArray
    """T_L, complex stress amplitude of the refracted longitudinal wave per unit incident
    pressure (2Z₂/(Z₁ + Z₂) at normal incidence)."""
    shear: ComplexArray
    """T_T, likewise for the mode-converted shear wave (0 at normal incidence and in a
    fluid)."""
    angle_longitudinal: FloatArray
    """[deg] refraction angle by Snell's law; NaN beyond the first critical angle
    (evanescent wave)."""
    angle_shear: FloatArray
    """[deg] likewise; NaN beyond the second critical angle or in a fluid."""


class SolidReflection(NamedTuple):
    """Reflection of a longitudinal wave inside a solid at its interface with a fluid."""

    longitudinal: ComplexArray
    """R_LL, complex ((Z₁ − Z₂)/(Z₁ + Z₂) at normal incidence, Z₂ the solid's)."""
    shear: ComplexArray
    """R_LT, the mode-converted shear wave."""
    angle_shear: FloatArray
    """[deg] the reflected shear wave's angle by Snell's law (NaN for c_T = 0)."""


class CriticalAngles(NamedTuple):
    """Critical angles [deg] of incidence from a fluid; None where there is none."""

    longitudinal: float | None
    """First: beyond it the longitudinal wave is evanescent (needs c_L > c_fluid)."""
    shear: float | None
    """Second: beyond it the shear wave is too and the reflection is total, |R| = 1
    (needs c_T > c_fluid)."""


def _scalar_or_array(value: np.ndarray) -> np.ndarray:
    return value[()] if value.ndim == 0 else value  # 0-d → numpy scalar


def _impedances(name: str, value: ArrayLike) -> FloatArray:
    arr = finite_array(name, value)
    if np.any(arr <= 0):
        raise EchocalValueError(f"{name} must be > 0 (an acoustic impedance [Rayl])")
    return arr


def reflection_normal(z1: ArrayLike, z2: ArrayLike) -> FloatArray:
    """R = (Z₂ − Z₁)/(Z₂ + Z₁): pressure reflection at normal incidence from medium 1 on 2.

    ``z1``, ``z2`` [Rayl] broadcast together; > 0.
    """
    a, b = _impedances("z1", z1), _impedances("z2", z2)
    return _scalar_or_array((b - a) / (b + a))


def transmission_normal(z1: ArrayLike, z2: ArrayLike) -> FloatArray:
    """T = 2Z₂/(Z₂ + Z₁): pressure (stress) transmission at normal incidence from 1 into 2."""
    a, b = _impedances("z1", z1), _impedances("z2", z2)
    return _scalar_or_array(2.0 * b / (b + a))


def _angles(theta_deg: ArrayLike, name: str = "theta_deg") -> FloatArray:
    """Incidence angles [deg] in [0, 90] (a rounding overshoot of 1e-9 deg is clipped)."""
    theta = finite_array(name, theta_deg)
    if np.any((theta < -1e-9) | (theta > 90.0 + 1e-9)):
        raise EchocalValueError(f"{name} must lie in [0, 90] deg (from the interface normal)")
    return np.clip(theta, 0.0, 90.0)


def _check(fluid: Material, solid: Material) -> None:
    for role, value in (("fluid", fluid), ("solid", solid)):
        if not isinstance(value, Material):
            raise EchocalValueError(f"{role} must be a Material; got {type(value).__name__}")
    if not fluid.is_fluid:
        raise EchocalValueError(
            f"fluid: {fluid.name!r} has a shear speed; the incident side must be a fluid"
        )


def _cos(sin: FloatArray) -> ComplexArray:
    """cos θ from sin θ ≥ 0: real up to 90°, +i·√(sin² − 1) beyond (evanescent branch)."""
    return np.sqrt((1.0 - sin * sin).astype(np.complex128))


def _snell_deg(sin: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore"):
        return np.where(sin <= 1.0, np.degrees(np.arcsin(np.minimum(sin, 1.0))), np.nan)


def snell_angle(theta_deg: ArrayLike, c_in: float, c_out: float) -> FloatArray:
    """Refraction angle [deg] by Snell's law, sin θ_out = (c_out/c_in)·sin θ_in.

    NaN beyond the critical angle (no propagating refracted wave).  ``c_in``,
    ``c_out`` [m/s] > 0.
    """
    c_in, c_out = (float(_impedances(n, c)) for n, c in (("c_in", c_in), ("c_out", c_out)))
    sin = np.sin(np.radians(_angles(theta_deg)))
    return _scalar_or_array(_snell_deg(sin * c_out / c_in))


def _interface(
    sin_fluid: FloatArray, sin_l: FloatArray, sin_t: FloatArray, fluid: Material, solid: Material
) -> tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray, FloatArray, ComplexArray]:
    """The terms a = Z_L·Π, b = Z_T·Π, g = Z₁·Π (Π = cos θ₁ cos θ_L cos θ_T), D·Π, cos 2θ_T
    and sin 2θ_T, from the sines of the three angles."""
    cos_f, cos_l, cos_t = _cos(sin_fluid), _cos(sin_l), _cos(sin_t)
    cos2t = 1.0 - 2.0 * sin_t * sin_t
    sin2t = 2.0 * sin_t * cos_t
    a = solid.density * solid.longitudinal_speed * cos_t * cos_f
    b = solid.density * solid.shear_speed * cos_l * cos_f
    g = fluid.density * fluid.longitudinal_speed * cos_l * cos_t
    den = a * cos2t**2 + b * sin2t**2 + g
    return a, b, g, den, cos2t, sin2t


def _from_fluid(theta_deg: ArrayLike, fluid: Material, solid: Material):
    _check(fluid, solid)
    sin = np.sin(np.radians(_angles(theta_deg)))
    sin_l = sin * (solid.longitudinal_speed / fluid.longitudinal_speed)
    sin_t = sin * (solid.shear_speed / fluid.longitudinal_speed)
    return sin_l, sin_t, _interface(sin, sin_l, sin_t, fluid, solid)


def reflection_fluid_solid(theta_deg: ArrayLike, fluid: Material, solid: Material) -> ComplexArray:
    """Complex pressure reflection R(θ) of a plane wave in ``fluid`` on ``solid``.

    Parameters
    ----------
    theta_deg : [deg] incidence angles in [0, 90], any shape.
    fluid : the incident medium (``shear_speed`` 0).
    solid : the other side, elastic solid or fluid (c_T = 0: the fluid–fluid formula).

    Returns
    -------
    R, complex, the shape of ``theta_deg``: (Z₂ − Z₁)/(Z₂ + Z₁) at 0°, |R| = 1 beyond the
    second critical angle (and beyond the first for a fluid ``solid``).
    """
    _, _, (a, b, g, den, cos2t, sin2t) = _from_fluid(theta_deg, fluid, solid)
    return _scalar_or_array((a * cos2t**2 + b * sin2t**2 - g) / den)


def transmission_fluid_solid(
    theta_deg: ArrayLike, fluid: Material, solid: Material
) -> Transmission:
    """Stress transmission coefficients (T_L, T_T) from ``fluid`` into ``solid``, with the
    refraction angles by Snell's law; see :class:`Transmission` and the module doc."""
    sin_l, sin_t, (a, b, _, den, cos2t, sin2t) = _from_fluid(theta_deg, fluid, solid)
    t_l = 2.0 * a * cos2t / den
    t_t = 2.0 * b * sin2t / den
    angle_t = _snell_deg(sin_t) if not solid.is_fluid else np.full(sin_t.shape, np.nan)
    return Transmission(
        *(_scalar_or_array(np.asarray(v)) for v in (t_l, t_t, _snell_deg(sin_l), angle_t))
    )


def _from_solid(theta_deg: ArrayLike, solid: Material, fluid: Material):
    _check(fluid, solid)
    sin_l = np.sin(np.radians(_angles(theta_deg)))
    sin_f = sin_l * (fluid.longitudinal_speed / solid.longitudinal_speed)
    sin_t = sin_l * (solid.shear_speed / solid.longitudinal_speed)
    return sin_f, sin_t, _interface(sin_f, sin_l, sin_t, fluid, solid)


def transmission_solid_fluid(
    theta_deg: ArrayLike, solid: Material, fluid: Material
) -> ComplexArray:
    """Pressure in ``fluid`` per unit stress of a longitudinal wave in ``solid`` hitting
    the interface at ``theta_deg`` [deg] (the way back out of a part).

    2Z_fluid/(Z_fluid + Z_solid) at normal incidence; the transmitted wave's angle is
    :func:`snell_angle` ``(theta_deg, c_L, c_fluid)``.
    """
    _, _, (_, _, g, den, cos2t, _) = _from_solid(theta_deg, solid, fluid)
    return _scalar_or_array(2.0 * g * cos2t / den)


def reflection_solid_fluid(
    theta_deg: ArrayLike, solid: Material, fluid: Material
) -> SolidReflection:
    """Reflection (R_LL, R_LT) of a longitudinal wave in ``solid`` at its interface with
    ``fluid`` (a back wall), incidence ``theta_deg`` [deg]; see :class:`SolidReflection`."""
    _, sin_t, (a, b, g, den, cos2t, sin2t) = _from_solid(theta_deg, solid, fluid)
    r_ll = (g + b * sin2t**2 - a * cos2t**2) / den
    r_lt = 2.0 * b * sin2t * cos2t / den
    angle_t = _snell_deg(sin_t) if not solid.is_fluid else np.full(sin_t.shape, np.nan)
    return SolidReflection(*(_scalar_or_array(np.asarray(v)) for v in (r_ll, r_lt, angle_t)))


def critical_angles(fluid: Material, solid: Material) -> CriticalAngles:
    """First (longitudinal) and second (shear) critical angles [deg] from ``fluid`` on
    ``solid``: arcsin(c_fluid/c_L) and arcsin(c_fluid/c_T); None where the wave in the
    solid is not faster than in the fluid (water–steel: 14.5° and 27.3°)."""
    _check(fluid, solid)
    c0 = fluid.longitudinal_speed

    def angle(c: float) -> float | None:
        return float(np.degrees(np.arcsin(c0 / c))) if c > c0 else None

    return CriticalAngles(angle(solid.longitudinal_speed), angle(solid.shear_speed))
