"""Materials: the coupling medium and the specimen's material, with attenuation.

A :class:`Material` is an isotropic medium given by its density [kg/m³], its
longitudinal and shear sound speeds [m/s] (shear 0 for a fluid) and its
attenuation α(f) = α₀·(f/f_ref)ⁿ [Np/m] (:class:`Attenuation`).  The built-in
table :data:`MATERIALS` holds literature values with their sources;
:func:`material` looks a name up (case-insensitive, with aliases such as
``aluminum``/``aluminium`` and ``pmma``/``acrylic``)::

    steel = material("steel")
    steel.impedance                      # 4.63e7 Rayl = ρ·c_L
    WATER.attenuation.factor(5e6, 0.1)   # amplitude left after 100 mm of water at 5 MHz

The plane-wave reflection and transmission coefficients at a fluid–solid
interface live in :mod:`echocal.coefficients` and are re-exported here.

Validation: every quantity must be a finite real number (bools refused); density
and longitudinal speed > 0; 0 ≤ shear speed < (√3/2)·longitudinal speed — at or
above that bound the bulk modulus K = ρ(c_L² − 4/3·c_T²) would be ≤ 0 (Poisson's
ratio ≤ −1), impossible for a stable isotropic solid.  A shear speed above
c_L/√2 (a negative Poisson ratio: auxetic foams, not engineering solids) is
legal but doubtful and warned about.  Messages name the attribute first
(``shear_speed must be below ...``) so that a setup file can prefix its path:
``specimen.material.shear_speed: must be below ...``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float, lookup
from echocal.coefficients import (
    CriticalAngles,
    SolidReflection,
    Transmission,
    critical_angles,
    reflection_fluid_solid,
    reflection_normal,
    reflection_solid_fluid,
    snell_angle,
    transmission_fluid_solid,
    transmission_normal,
    transmission_solid_fluid,
)
from echocal.errors import EchocalValueError

__all__ = [
    "MATERIALS",
    "NEPER_TO_DB",
    "WATER",
    "Attenuation",
    "CriticalAngles",
    "Material",
    "SolidReflection",
    "Transmission",
    "critical_angles",
    "db_per_m_to_np_per_m",
    "material",
    "material_names",
    "reflection_fluid_solid",
    "reflection_normal",
    "reflection_solid_fluid",
    "snell_angle",
    "transmission_fluid_solid",
    "transmission_normal",
    "transmission_solid_fluid",
    "water",
]

NEPER_TO_DB = 20.0 / math.log(10.0)
"""One neper in decibels (≈ 8.686): α [dB/m] = NEPER_TO_DB · α [Np/m]."""


def db_per_m_to_np_per_m(value: float) -> float:
    """An attenuation in dB/m → Np/m (``20 dB/m`` → 2.303 Np/m)."""
    return value / NEPER_TO_DB


def _real(name: str, value: Any) -> float:
    """``value`` as a finite float; bools (``true`` typed for a number) refused."""
    if isinstance(value, bool | np.bool_):
        raise EchocalValueError(f"{name} must be a number; got {value!r}")
    return finite_float(name, value)


@dataclass(frozen=True, kw_only=True)
class Attenuation:
    """Power-law attenuation of plane-wave amplitude: α(f) = α₀·|f/f_ref|ⁿ [Np/m].

    Attributes
    ----------
    alpha0 : [Np/m] amplitude attenuation at ``f_ref`` (>= 0; 0: lossless).
    f_ref : [Hz] reference frequency (> 0), 1 MHz by default.
    exponent : n, 0 to 4 (2 for water's viscous absorption; about 1 for absorption
        in solids and polymers; 4 for Rayleigh grain scattering).
    """

    alpha0: float = 0.0
    f_ref: float = 1.0e6
    exponent: float = 2.0

    def __post_init__(self) -> None:
        alpha0 = _real("alpha0", self.alpha0)
        if alpha0 < 0:
            raise EchocalValueError(
                f"alpha0 must be >= 0 (an attenuation, not a gain); got {alpha0:g} Np/m"
            )
        f_ref = _real("f_ref", self.f_ref)
        if f_ref <= 0:
            raise EchocalValueError(f"f_ref must be > 0; got {f_ref:g} Hz")
        exponent = _real("exponent", self.exponent)
        if not 0.0 <= exponent <= 4.0:
            raise EchocalValueError(f"exponent must lie in [0, 4]; got {exponent:g}")
        object.__setattr__(self, "alpha0", alpha0)
        object.__setattr__(self, "f_ref", f_ref)
        object.__setattr__(self, "exponent", exponent)

    @classmethod
    def from_db(
        cls, db_per_m: float, *, f_ref: float = 1.0e6, exponent: float = 2.0
    ) -> Attenuation:
        """The attenuation of ``db_per_m`` [dB/m] at ``f_ref`` [Hz] (0.2 dB/mm = 200 dB/m)."""
        return cls(
            alpha0=db_per_m_to_np_per_m(_real("db_per_m", db_per_m)), f_ref=f_ref, exponent=exponent
        )

    def alpha(self, f: ArrayLike) -> NDArray[np.float64]:
        """α(f) [Np/m] at frequencies ``f`` [Hz], any shape (even in f: α(−f) = α(f))."""
        ratio = np.abs(np.asarray(f, dtype=np.float64)) / self.f_ref
        return self.alpha0 * ratio**self.exponent

    def factor(self, f: ArrayLike, distance: ArrayLike) -> NDArray[np.float64]:
        """Amplitude factor exp(−α(f)·distance) after ``distance`` [m] (broadcast with ``f``).

        For a pulse-echo path of water depth d, pass ``2 * d``.
        """
        return np.exp(-self.alpha(f) * np.asarray(distance, dtype=np.float64))


LOSSLESS = Attenuation()


@dataclass(frozen=True, kw_only=True)
class Material:
    """An isotropic medium: fluid (``shear_speed`` 0) or elastic solid.

    Attributes
    ----------
    name : label, e.g. ``"steel"``.
    density : ρ [kg/m³] (> 0).
    longitudinal_speed : c_L [m/s] (> 0).
    shear_speed : c_T [m/s], 0 for a fluid, else below (√3/2)·c_L (see module doc).
    attenuation : of the longitudinal wave (lossless by default).
    shear_attenuation : of the shear wave; None: not modelled (a fluid must leave it None).
    """

    name: str = "custom"
    density: float
    longitudinal_speed: float
    shear_speed: float = 0.0
    attenuation: Attenuation = field(default=LOSSLESS)
    shear_attenuation: Attenuation | None = None

    def __post_init__(self) -> None:
        rho = _real("density", self.density)
        if rho <= 0:
            raise EchocalValueError(f"density must be > 0; got {rho:g} kg/m³")
        c_l = _real("longitudinal_speed", self.longitudinal_speed)
        if c_l <= 0:
            raise EchocalValueError(f"longitudinal_speed must be > 0; got {c_l:g} m/s")
        c_t = _real("shear_speed", self.shear_speed)
        if c_t < 0:
            raise EchocalValueError(f"shear_speed must be >= 0 (0 for a fluid); got {c_t:g} m/s")
        if c_t >= c_l:
            raise EchocalValueError(
                f"shear_speed must be below longitudinal_speed ({c_l:g} m/s); got {c_t:g} m/s"
            )
        if c_t >= 0.5 * math.sqrt(3.0) * c_l:
            raise EchocalValueError(
                f"shear_speed must be below √3/2·longitudinal_speed = {0.866025 * c_l:.6g} m/s "
                f"(else the bulk modulus is negative: no stable solid); got {c_t:g} m/s"
            )
        if c_t > c_l / math.sqrt(2.0):
            warnings.warn(
                f"material {self.name!r}: shear_speed {c_t:g} m/s above longitudinal_speed/√2 "
                f"= {c_l / math.sqrt(2.0):.6g} m/s means a negative Poisson ratio; "
                "check the speeds",
                UserWarning,
                stacklevel=3,
            )
        for name in ("attenuation", "shear_attenuation"):
            value = getattr(self, name)
            if not (isinstance(value, Attenuation) or (value is None and name != "attenuation")):
                raise EchocalValueError(
                    f"{name} must be an Attenuation; got {type(value).__name__}"
                )
        if c_t == 0 and self.shear_attenuation is not None:
            raise EchocalValueError(
                "shear_attenuation: a fluid (shear_speed 0) carries no shear wave; leave it out"
            )
        object.__setattr__(self, "density", rho)
        object.__setattr__(self, "longitudinal_speed", c_l)
        object.__setattr__(self, "shear_speed", c_t)

    @property
    def impedance(self) -> float:
        """Z = ρ·c_L [Rayl = kg/(m²·s)], the longitudinal acoustic impedance."""
        return self.density * self.longitudinal_speed

    @property
    def shear_impedance(self) -> float:
        """Z_T = ρ·c_T [Rayl] (0 for a fluid)."""
        return self.density * self.shear_speed

    @property
    def is_fluid(self) -> bool:
        """True when the material carries no shear wave (``shear_speed == 0``)."""
        return self.shear_speed == 0.0

    @property
    def poisson_ratio(self) -> float:
        """ν = (c_L² − 2c_T²) / (2(c_L² − c_T²)); 0.5 for a fluid."""
        cl2, ct2 = self.longitudinal_speed**2, self.shear_speed**2
        return (cl2 - 2.0 * ct2) / (2.0 * (cl2 - ct2))


def _solid(name: str, rho: float, c_l: float, c_t: float, db_per_mm_5mhz: float) -> Material:
    """A solid of the table, its longitudinal attenuation given in dB/mm at 5 MHz, α ∝ f."""
    att = Attenuation.from_db(1e3 * db_per_mm_5mhz, f_ref=5.0e6, exponent=1.0)
    return Material(
        name=name, density=rho, longitudinal_speed=c_l, shear_speed=c_t, attenuation=att
    )


WATER = Material(
    name="water",
    # 20 °C: c = 1482.3 m/s (Del Grosso & Mader 1972, JASA 52, 1442: 1482.343 m/s);
    # ρ = 998.2 kg/m³ (Kell 1975, J. Chem. Eng. Data 20, 97);
    # α/f² = 25.3e-15 s²/m → 0.0253 Np/m at 1 MHz, α ∝ f² (Pinkerton 1949, Nature 160,
    # 128; Kaye & Laby, Tables of Physical and Chemical Constants, §2.4.1).
    density=998.2,
    longitudinal_speed=1482.3,
    attenuation=Attenuation(alpha0=0.0253, f_ref=1.0e6, exponent=2.0),
)
"""Pure water at 20 °C (the default coupling medium)."""

_MARCZAK = (1402.385, 5.038813, -5.799136e-2, 3.287156e-4, -1.398845e-6, 2.787860e-9)
"""Sound speed of pure water [m/s] as a polynomial in T [°C], 0–95 °C (Marczak 1997,
J. Acoust. Soc. Am. 102, 2776; within 0.02 m/s of Del Grosso & Mader 1972)."""
_KELL = (999.83952, 16.945176, -7.9870401e-3, -46.170461e-6, 105.56302e-9, -280.54253e-12)
_KELL_B = 16.879850e-3
"""Density of air-free water [kg/m³] = Σ aᵢTⁱ / (1 + b·T), 0–150 °C (Kell 1975)."""


def water(temperature: float = 20.0) -> Material:
    """Pure water at ``temperature`` [°C] (0 to 95): sound speed (Marczak 1997) and
    density (Kell 1975) at that temperature; the attenuation stays the 20 °C value of
    :data:`WATER` (α falls by about 2 % per °C around 20 °C: Pinkerton 1949).

    ``water(20)`` gives 1482.4 m/s and 998.2 kg/m³ (:data:`WATER` rounds to 1482.3).
    """
    t = _real("temperature", temperature)
    if not 0.0 <= t <= 95.0:
        raise EchocalValueError(f"temperature must lie in [0, 95] °C (liquid water); got {t:g}")
    speed = sum(a * t**i for i, a in enumerate(_MARCZAK))
    density = sum(a * t**i for i, a in enumerate(_KELL)) / (1.0 + _KELL_B * t)
    return Material(
        name="water",
        density=round(density, 3),
        longitudinal_speed=round(speed, 2),
        attenuation=WATER.attenuation,
    )


# Solids.  Speeds and densities: Krautkrämer & Krautkrämer, *Ultrasonic Testing of
# Materials*, 4th ed. (1990), Appendix table; Olympus, *Ultrasonic Transducers Technical
# Notes* (2006), material sound velocities; steel as issue #14 (mild steel).  Longitudinal
# attenuation: representative values for fine-grained wrought material at 5 MHz with a
# linear frequency law (Ono 2020, Appl. Sci. 10, 2230: two thirds of engineering materials
# show α ∝ f); real parts differ by up to ×10 with grain size and heat treatment — measure
# yours and give it in the setup file.  PMMA: about 6.4 dB/cm at 5 MHz (Selfridge 1985,
# IEEE Trans. Sonics Ultrason. 32, 381; Ono's PMMA damping factor ≈ 0.013 gives the same).
_TABLE = (
    WATER,
    #       name               ρ [kg/m³]  c_L [m/s]  c_T [m/s]  α [dB/mm] at 5 MHz
    _solid("steel", 7850.0, 5900.0, 3230.0, 0.02),  # mild steel (issue #14; Krautkrämer)
    _solid("stainless-steel", 7890.0, 5790.0, 3100.0, 0.05),  # austenitic 347 (Kaye & Laby)
    _solid("aluminium", 2700.0, 6320.0, 3130.0, 0.01),  # Krautkrämer; Olympus
    _solid("titanium", 4500.0, 6100.0, 3120.0, 0.04),  # commercially pure (Olympus)
    _solid("copper", 8900.0, 4700.0, 2260.0, 0.05),  # Krautkrämer
    _solid("brass", 8400.0, 4400.0, 2200.0, 0.08),  # brass 58 (Krautkrämer)
    _solid("nickel", 8800.0, 5630.0, 2960.0, 0.05),  # Krautkrämer; Olympus
    _solid("glass", 2500.0, 5660.0, 3420.0, 0.005),  # crown glass (Krautkrämer; Olympus)
    _solid("acrylic", 1190.0, 2730.0, 1430.0, 0.64),  # PMMA (Olympus; Selfridge 1985)
    # cured unfilled epoxy (bisphenol-A resins, also fusion-bonded epoxy coatings):
    # ρ, c_L, c_T as Selfridge 1985 (epoxies 2.5–2.8 km/s, 1.1–1.3 km/s shear); loss from a
    # damping factor 0.02, α = πfD/c_L (Ono 2020's definition; PMMA's is 0.013) — a
    # representative value, cure and filler change it by ×3: measure yours
    _solid("epoxy", 1170.0, 2650.0, 1200.0, 1.03),
)

MATERIALS: MappingProxyType[str, Material] = MappingProxyType({m.name: m for m in _TABLE})
"""The built-in materials by name (read-only)."""

_ALIASES = {
    "aluminum": "aluminium",
    "al": "aluminium",
    "pmma": "acrylic",
    "plexiglas": "acrylic",
    "perspex": "acrylic",
    "stainless": "stainless-steel",
    "stainless steel": "stainless-steel",
    "stainless_steel": "stainless-steel",
    "mild-steel": "steel",
    "ti": "titanium",
    "cu": "copper",
    "ni": "nickel",
    "h2o": "water",
    "epoxy-resin": "epoxy",
    "fbe": "epoxy",  # fusion-bonded epoxy, the common pipeline coating
}


def material_names() -> tuple[str, ...]:
    """Names of the built-in materials, sorted (aliases such as ``aluminum`` not listed)."""
    return tuple(sorted(MATERIALS))


def material(name: str) -> Material:
    """The built-in material ``name`` (case-insensitive; aliases accepted).

    Raises
    ------
    UnknownNameError
        for an unknown name, listing the valid names.
    """
    if not isinstance(name, str):
        raise EchocalValueError(f"material must be a name; got {name!r}")
    key = name.strip().lower()
    return lookup("material", _ALIASES.get(key, key), MATERIALS)
