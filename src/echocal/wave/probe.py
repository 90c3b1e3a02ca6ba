"""The wave model's view of a transducer: a baffled piston, circular (flat or focused) or
rectangular (flat).

A flat piston is given by its radius.  A spherically focused piston (a bowl) is given, as
probe makers quote it, by its **acoustic focal length in water**: the distance from the
face to the maximum of the on-axis pressure at the centre frequency.  That maximum lies
closer than the bowl's geometric radius of curvature R_f (the "geometric focus"); O'Neil's
closed form of the on-axis field (O'Neil, JASA 21 (1949) 516)

    |p/(ρcv₀)| = |2/(1 − z/R_f) · sin(k/2 (√((z − h)² + a²) − z))|,  h = R_f − √(R_f² − a²)

(z from the bowl's apex) converts one into the other (:func:`curvature_for_focus`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import positive_float
from echocal.errors import EchocalValueError
from echocal.wave import sir

__all__ = [
    "Aperture",
    "PistonProbe",
    "RectangularProbe",
    "curvature_for_focus",
    "oneil_on_axis",
    "transmit_field",
]

FloatArray = NDArray[np.float64]


def oneil_on_axis(
    z: ArrayLike, *, radius: float, curvature: float, wavenumber: float
) -> FloatArray:
    """O'Neil's on-axis |p/(ρcv₀)| of a bowl (``z`` [m] from the apex, ``radius`` a [m],
    ``curvature`` R_f [m], ``wavenumber`` k [1/m]); shape of ``z``."""
    z = np.asarray(z, dtype=np.float64)
    h = curvature - math.sqrt(curvature**2 - radius**2)
    path = np.sqrt((z - h) ** 2 + radius**2) - z
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.abs(2.0 / (1.0 - z / curvature) * np.sin(0.5 * wavenumber * path))
    # at z = R_f the limit is k·h (the geometric focus)
    return np.where(np.isclose(z, curvature, rtol=1e-12), wavenumber * h, out)


def curvature_for_focus(
    focus: float, *, radius: float, frequency: float, sound_speed: float
) -> float:
    """Radius of curvature R_f [m] of a bowl whose on-axis maximum at ``frequency`` [Hz]
    lies at ``focus`` [m] from the apex (O'Neil's closed form, solved by root finding).

    Raises
    ------
    EchocalValueError
        when no bowl of this radius focuses that far (the focus must lie well inside the
        near-field length a²/λ of the flat piston).
    """
    import scipy.optimize  # lazy: costs a CLI start 0.3 CPU-s

    k = 2.0 * math.pi * frequency / sound_speed
    near_field = radius**2 * frequency / sound_speed

    def peak(curvature: float) -> float:
        grid = np.linspace(
            0.2 * curvature, min(1.2 * curvature, 3.0 * near_field + curvature), 2001
        )
        values = oneil_on_axis(grid, radius=radius, curvature=curvature, wavenumber=k)
        i = int(np.argmax(values))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        best = scipy.optimize.minimize_scalar(
            lambda z: -float(oneil_on_axis(z, radius=radius, curvature=curvature, wavenumber=k)),
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": 1e-9},
        )
        return float(best.x)

    if not focus < 0.9 * near_field:
        raise EchocalValueError(
            f"transducer.focus: {focus * 1e3:g} mm is not a focus this probe can reach: a "
            f"{2e3 * radius:g} mm probe at {frequency / 1e6:g} MHz focuses only well inside its "
            f"near-field length a²/λ = {near_field * 1e3:.4g} mm; give a shorter focus"
        )
    lo, hi = focus * 1.0000001, focus * 50.0
    lo = max(lo, radius * 1.0001)
    try:
        return float(scipy.optimize.brentq(lambda rf: peak(rf) - focus, lo, hi, xtol=1e-10))
    except ValueError:
        raise EchocalValueError(
            f"transducer.focus: no spherically focused {2e3 * radius:g} mm probe peaks at "
            f"{focus * 1e3:g} mm at {frequency / 1e6:g} MHz; give a focus between the probe "
            "radius and its near-field length"
        ) from None


class Aperture(Protocol):
    """What the wave model asks of a piston's face (:class:`PistonProbe`,
    :class:`RectangularProbe`): the SIR kernel's aperture code and parameters, its size and
    shape."""

    @property
    def kind(self) -> int: ...

    @property
    def parameters(self) -> FloatArray: ...

    @property
    def radius(self) -> float:
        """[m] radius of the smallest circle about the face centre that holds the face."""
        ...

    @property
    def spread_radius(self) -> float:
        """[m] the half-width that sets the diffracted beam's widest spread λ/(2a)."""
        ...

    @property
    def curvature(self) -> float | None: ...

    @property
    def area(self) -> float: ...

    @property
    def depth(self) -> float: ...


def transmit_field(
    probe: Aperture, points: ArrayLike, frequency: float, sound_speed: float
) -> NDArray[np.complex128]:
    """Normalized transmit pressure p/(ρcv₀) at ``points`` [m] (aperture frame: face centre
    or bowl apex at the origin, beam along +z; a rectangle's sides along x and y), shape
    ``(n, 3)`` → ``(n,)``, at one ``frequency`` [Hz], from the Fourier transform of the
    closed-form SIR:
    p/(ρcv₀) = −ik·H(ω), H(ω) = ∫ h(t) e^{iωt} dt (time convention e^{−iωt})."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    k = 2.0 * math.pi * frequency / sound_speed
    dt = 1.0 / (64.0 * frequency)  # bin averages: the box filter is undone below
    prm = probe.parameters
    n_bins = sir.scratch_bins(sound_speed, dt, 2.0 * probe.radius)
    h = np.zeros(n_bins)
    hm = np.zeros(n_bins)
    work = np.zeros((2, n_bins))
    geo = np.zeros(sir.GEOMETRY_SIZE)
    out = np.zeros(pts.shape[0], dtype=np.complex128)
    tmax = math.acos(prm[2]) if probe.kind == sir.BOWL else 0.0
    bps = np.zeros(sir.MAX_BREAKPOINTS)
    for i, (x, y, z) in enumerate(pts):
        if not sir._sample_geometry(probe.kind, prm, x, y, z, 0.0, 0.0, 1.0, geo):
            continue
        nb = sir.breakpoints(probe.kind, prm, geo, sound_speed, tmax, bps)
        k0, n = sir._bin_sir(probe.kind, prm, geo, sound_speed, bps, nb, 0.0, dt, h, hm, work)
        t = (k0 + np.arange(n) + 0.5) * dt
        spectrum = np.sum(h[:n] * np.exp(2j * math.pi * frequency * t)) * dt
        out[i] = -1j * k * spectrum / np.sinc(frequency * dt) ** 3
    return out


@dataclass(frozen=True, kw_only=True)
class PistonProbe:
    """A baffled circular piston: flat, or a spherical bowl.

    Attributes
    ----------
    radius : [m] aperture radius a (half the diameter).
    curvature : [m] radius of curvature R_f of a focused bowl (its geometric focus), or
        None for a flat piston.
    """

    radius: float
    curvature: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive_float("transducer.width", self.radius))
        if self.curvature is not None:
            rf = positive_float("transducer.focus", self.curvature)
            if rf <= self.radius:
                raise EchocalValueError(
                    f"transducer.focus: the bowl's radius of curvature {rf * 1e3:g} mm must "
                    f"exceed the probe radius {self.radius * 1e3:g} mm"
                )
            object.__setattr__(self, "curvature", rf)

    @property
    def kind(self) -> int:
        """Aperture code of ``echocal.wave.sir``."""
        return sir.DISC if self.curvature is None else sir.BOWL

    @property
    def parameters(self) -> FloatArray:
        """``(a, R_f, cos θmax)`` for the SIR kernels (R_f = cos θmax = 0 for a flat disc)."""
        if self.curvature is None:
            return np.array([self.radius, 0.0, 0.0])
        return np.array(
            [self.radius, self.curvature, math.sqrt(1.0 - (self.radius / self.curvature) ** 2)]
        )

    @property
    def area(self) -> float:
        """[m²] projected area πa² (the normalization of the echo)."""
        return math.pi * self.radius**2

    @property
    def depth(self) -> float:
        """[m] depth of the bowl (0 for a flat face): the rim lies this far ahead of the apex."""
        if self.curvature is None:
            return 0.0
        return self.curvature - math.sqrt(self.curvature**2 - self.radius**2)

    @property
    def spread_radius(self) -> float:
        """[m] the half-width that sets the diffracted beam's spread λ/(2a): the radius."""
        return self.radius

    def field(
        self, points: ArrayLike, frequency: float, sound_speed: float
    ) -> NDArray[np.complex128]:
        """:func:`transmit_field` of this probe."""
        return transmit_field(self, points, frequency, sound_speed)


@dataclass(frozen=True, kw_only=True)
class RectangularProbe:
    """A baffled flat rectangular piston (the thesis's square probe), its sides along the
    transducer frame's x′ (width) and y′ (height) axes.

    Attributes
    ----------
    half_width, half_height : [m] half the sides along x′ and y′.
    """

    half_width: float
    half_height: float
    curvature: None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "half_width", positive_float("transducer.width", self.half_width))
        object.__setattr__(
            self, "half_height", positive_float("transducer.height", self.half_height)
        )

    @property
    def kind(self) -> int:
        """Aperture code of ``echocal.wave.sir``."""
        return sir.RECT

    @property
    def parameters(self) -> FloatArray:
        """``(half-diagonal, half-width, half-height)`` [m] for the SIR kernels."""
        return np.array([self.radius, self.half_width, self.half_height])

    @property
    def radius(self) -> float:
        """[m] the half-diagonal: the radius of the circle that holds the face."""
        return math.hypot(self.half_width, self.half_height)

    @property
    def spread_radius(self) -> float:
        """[m] the shorter half-side: it sets the widest diffraction spread λ/(2a)."""
        return min(self.half_width, self.half_height)

    @property
    def area(self) -> float:
        """[m²] the face's area 4·(half-width)·(half-height) (the echo's normalization)."""
        return 4.0 * self.half_width * self.half_height

    @property
    def depth(self) -> float:
        """[m] 0: the face is flat."""
        return 0.0

    def field(
        self, points: ArrayLike, frequency: float, sound_speed: float
    ) -> NDArray[np.complex128]:
        """:func:`transmit_field` of this probe."""
        return transmit_field(self, points, frequency, sound_speed)
