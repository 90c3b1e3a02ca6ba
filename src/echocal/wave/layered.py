"""Echo paths through a layered plate: which interfaces an echo turns at, its coefficient,
its equivalent water path and its time.

A plate of N layers (:class:`~echocal.specimen.interior.Layer`, top first) lies below
the front face in the coupling fluid, with the same fluid below it.  Interface 0 is the
front face (fluid / layer 1), interface i (1 ≤ i < N) lies between layers i and i+1 and
interface N is the back wall (layer N / fluid).  A longitudinal wave entering the plate
is transmitted or reflected at every interface it meets; an **echo path** is the
sequence of interfaces at which it turns (its reflections) until it leaves through the
front face: ``(2,)`` is the primary echo of interface 2, ``(2, 1, 2)`` its multiple that
rang once in layer 2.  Paths are listed up to an *order* M: every path with at most
2M − 1 reflections (M = 1: the primaries; M = 2 adds the first multiples), as the
single plate's back-wall echoes k = 1…M.

Each path carries (taken at the beam axis's angle of incidence θ_w, Snell's law giving
the angle in each layer, sin θ_j = sin θ_w · c_j/c_w):

- its coefficient, the product of the plane-wave stress transmission coefficients of
  every interface crossed and the reflection coefficients of every turn
  (:func:`pp_coefficients`: fluid–solid, solid–solid (welded) and solid–fluid, the
  longitudinal → longitudinal ones of the full P–SV interface problem, so the energy the
  mode-converted shear waves take is accounted for); 0 when a layer is beyond its
  critical angle;
- its equivalent water path (the paraxial equivalence of :mod:`echocal.wave.interior`
  applied leg by leg: a leg of thickness h in a layer of speed c diffracts like h·c/c_w
  of water) and the two-way delay correction Σ h·(1/c − c/c_w²);
- its ray time Σ h/(c cos θ) in the plate and its attenuation Σ α(f)·h/cos θ.

Mode-converted (shear) legs are not listed: the longitudinal paths carry the echo train a
normal-incidence or slightly tilted probe reads.  Under a flat piston, over a plate whose
face fills the beam, each path is evaluated exactly over the probe's plane-wave spectrum
instead (:mod:`echocal.wave.layered_spectrum`, with :func:`mode_coefficients` at every
component's angle); the axis-angle coefficient and equivalent path serve the other probes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal.materials import Material
from echocal.specimen.interior import Layer, echo_routes

__all__ = [
    "EchoPath",
    "echo_paths",
    "mode_coefficients",
    "path_factors",
    "path_label",
    "pp_coefficient_arrays",
    "pp_coefficients",
    "speed",
]

FloatArray = NDArray[np.float64]


def pp_coefficients(sin_in: float, upper: Material, lower: Material) -> tuple[complex, complex]:
    """(R, T): a longitudinal plane wave in ``upper`` meeting ``lower`` at incidence sine
    ``sin_in``: the reflected and transmitted longitudinal waves' stress amplitudes per unit
    incident stress (pressure in a fluid), in the e^{−iωt} convention of
    :mod:`echocal.coefficients` (:func:`pp_coefficient_arrays` at one sine)."""
    r, t = pp_coefficient_arrays(np.array([sin_in]), upper, lower)
    return complex(r[0]), complex(t[0])


def _vertical(slowness: float, kx: FloatArray) -> NDArray[np.complex128]:
    """k_z/ω = √(1/c² − k_x²/ω²) with Im ≥ 0 (decaying away from the interface)."""
    value = np.sqrt((slowness * slowness - kx * kx).astype(np.complex128))
    return np.where(value.imag < 0, -value, value)


def pp_coefficient_arrays(
    sin_in: FloatArray, upper: Material, lower: Material
) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
    """(R, T) of :func:`pp_coefficients` at every incidence sine of ``sin_in`` ``(n,)``
    (sines beyond 1, evanescent incident waves, continue analytically), each ``(n,)``
    (:func:`mode_coefficients` of a longitudinal wave, its longitudinal waves)."""
    slowness = np.asarray(sin_in, dtype=np.float64) / upper.longitudinal_speed
    out = mode_coefficients(slowness, upper, lower, "L")
    return out[("R", "L")], out[("T", "L")]


def mode_coefficients(
    slowness: FloatArray, upper: Material, lower: Material, incident: str
) -> dict[tuple[str, str], NDArray[np.complex128]]:
    """A plane wave of mode ``incident`` (``"L"`` longitudinal, ``"S"`` shear (SV), in a
    solid) in ``upper`` meeting ``lower``, at horizontal slowness ``slowness`` [s/m]
    ``(n,)`` (sin θ/c, the same on both sides by Snell's law): ``{("R" or "T", mode):
    (n,)}``, the reflected and transmitted waves' amplitudes per unit incident amplitude,
    a wave's amplitude being ρω² times its displacement potential (a longitudinal wave's
    normal stress; a fluid's pressure), in the e^{−iωt} convention of
    :mod:`echocal.coefficients`.  Shear entries only on a solid's side.

    Solved from the boundary conditions of the P–SV problem with displacement potentials
    (u = ∇φ + ∇×(ψŷ)): u_z and σ_zz continuous; between two solids (welded) u_x and σ_xz
    too; on a solid's face against a fluid σ_xz = 0.  So R = a_r/a_i and T = ρ₂a_t/(ρ₁a_i)
    for potential amplitudes a; at normal incidence (L → L): (Z₂ − Z₁)/(Z₂ + Z₁) and
    2Z₂/(Z₁ + Z₂)."""
    kx = np.asarray(slowness, dtype=np.float64)  # per unit ω

    def columns(medium: Material, sign: float) -> dict[str, NDArray[np.complex128]]:
        """(n, 4) (u_x, u_z, σ_zz, σ_xz)/(ρ₁ω²) of the L (and S) partial waves travelling
        along ``sign``·z (z from upper into lower), per unit ω."""
        rho, c_t = medium.density, medium.shear_speed
        mu = rho * c_t * c_t
        kzl = sign * _vertical(1.0 / medium.longitudinal_speed, kx)
        scale = upper.density
        zero = np.zeros_like(kzl)
        out = {
            "L": np.stack(
                [
                    1j * kx + zero,
                    1j * kzl,
                    -(rho - 2.0 * mu * kx * kx) / scale + zero,
                    -2.0 * mu * kx * kzl / scale,
                ],
                axis=-1,
            )
        }
        if c_t > 0:
            kzt = sign * _vertical(1.0 / c_t, kx)
            out["S"] = np.stack(
                [
                    -1j * kzt,
                    1j * kx + zero,
                    -2.0 * mu * kx * kzt / scale,
                    mu * (kzt * kzt - kx * kx) / scale,
                ],
                axis=-1,
            )
        return out

    waves = columns(upper, 1.0)[incident]
    reflected = columns(upper, -1.0)
    transmitted = columns(lower, 1.0)
    solid_up, solid_down = not upper.is_fluid, not lower.is_fluid
    # unknowns: upper's reflected waves (+), lower's transmitted waves (−), continuity rows
    rows = [1, 2]  # u_z, σ_zz
    if solid_up and solid_down:
        rows += [0, 3]  # u_x, σ_xz
    unknowns = [*reflected.values(), *(-col for col in transmitted.values())]
    matrix = [[col[:, r] for col in unknowns] for r in rows]
    rhs = [-waves[:, r] for r in rows]
    if solid_up != solid_down:  # σ_xz = 0 on the solid's face
        keep_up, keep_down = float(solid_up), float(solid_down)
        matrix.append(
            [keep_up * col[:, 3] for col in reflected.values()]
            + [keep_down * col[:, 3] for col in transmitted.values()]
        )
        rhs.append(-keep_up * waves[:, 3])
    a = np.moveaxis(np.array(matrix, dtype=np.complex128), (0, 1), (1, 2))  # (n, rows, cols)
    b = np.moveaxis(np.array(rhs, dtype=np.complex128), 0, 1)[..., None]
    x = np.linalg.solve(a, b)[..., 0]
    names = [("R", m) for m in reflected] + [("T", m) for m in transmitted]
    ratio = lower.density / upper.density
    scaled = x * np.array([ratio if name[0] == "T" else 1.0 for name in names])
    return {name: np.asarray(scaled[:, j], dtype=np.complex128) for j, name in enumerate(names)}


@dataclass(frozen=True)
class EchoPath:
    """One echo through the layers.

    Attributes
    ----------
    turns : the interfaces (1 … N) at which it reflects, in order.
    legs : the layers (1 … N) it crosses, in order (each a thickness crossed once).
    coefficient : the product of its transmission and reflection coefficients (complex;
        0 when a layer it crosses is beyond its critical angle).
    equivalent_depth : [m] half its equivalent water path in the plate, Σ h·c/c_w / 2: the
        depth below the face of the water mirror that diffracts like it.
    delay : [s] two-way delay correction Σ h·(1/c − c/c_w²) over its legs.
    plate_time : [s] ray time in the plate, Σ h/(c·cos θ).
    attenuation_path : ((layer, mode, metres), …) the distance it travels in each layer
        in each mode.
    modes : each leg's wave mode, ``"L"`` (longitudinal) or ``"S"`` (shear), one letter
        per leg; c above is the leg's speed in its mode.
    """

    turns: tuple[int, ...]
    legs: tuple[int, ...]
    coefficient: complex
    equivalent_depth: float
    delay: float
    plate_time: float
    attenuation_path: tuple[tuple[int, str, float], ...]
    modes: str

    @property
    def label(self) -> str:
        """``interface-2`` for a primary echo, ``interface-2.1.2`` for a multiple; a path
        with shear legs adds its legs' modes: ``interface-1:LS``."""
        if "S" in self.modes:
            return f"{path_label(self.turns)}:{self.modes}"
        return path_label(self.turns)


def path_label(turns: Sequence[int]) -> str:
    """The label of the echo that reflects at ``turns`` (interface numbers, in order)."""
    return "interface-" + ".".join(str(t) for t in turns)


def speed(material: Material, mode: str) -> float:
    """[m/s] ``material``'s speed of mode ``"L"`` or ``"S"``."""
    return material.longitudinal_speed if mode == "L" else material.shear_speed


def echo_paths(
    layers: Sequence[Layer],
    medium: Material,
    sin_water: float,
    order: int,
    shear_legs: int = 0,
) -> list[EchoPath]:
    """Every echo path through ``layers`` (top first) in ``medium`` up to ``order``
    (module doc), with at most ``shear_legs`` shear legs
    (:func:`~echocal.specimen.interior.echo_routes`), at the beam axis's incidence sine
    ``sin_water`` in the fluid."""
    c_w = medium.longitudinal_speed
    media = [medium, *(layer.material for layer in layers), medium]  # index = layer number
    slowness = np.array([sin_water / c_w])
    table: dict[tuple[bool, int, str], dict[tuple[str, str], NDArray[np.complex128]]] = {}

    def coefficient(from_above: bool, i: int, incident: str, kind: str, outgoing: str) -> complex:
        key = (from_above, i, incident)
        if key not in table:
            upper, lower = (media[i], media[i + 1]) if from_above else (media[i + 1], media[i])
            # from below the frame is turned 180° about y (x and z reversed), so that a
            # shear potential means the same wave on both sides of a leg
            table[key] = mode_coefficients(
                slowness if from_above else -slowness, upper, lower, incident
            )
        return complex(table[key][(kind, outgoing)][0])

    out = []
    for turns, modes in echo_routes(len(layers), order, shear_legs):
        legs, factors = path_factors(turns)
        sines = [
            sin_water * speed(layers[leg - 1].material, m) / c_w
            for leg, m in zip(legs, modes, strict=True)
        ]
        product = 0j
        if all(s < 1.0 for s in sines):
            product = 1.0 + 0j
            for k, (from_above, i, which) in enumerate(factors):
                incident = modes[k - 1] if k > 0 else "L"
                outgoing = modes[k] if k < len(legs) else "L"
                product *= coefficient(from_above, i, incident, "RT"[which], outgoing)
        out.append(_path(turns, legs, modes, product, layers, sines, c_w))
    return out


def path_factors(
    turns: Sequence[int],
) -> tuple[tuple[int, ...], tuple[tuple[bool, int, int], ...]]:
    """The layers (1 … N) the path that turns at ``turns`` crosses, in order, and the
    interface coefficients it picks up: ``(from_above, interface, 0 for R / 1 for T)``
    (the front face's transmission in, every crossing and turn, and out again)."""
    legs: list[int] = []
    factors: list[tuple[bool, int, int]] = [(True, 0, 1)]  # into layer 1
    level, going_down = 0, True  # the last interface met
    for turn in turns:
        if going_down:  # layers level+1 … turn, then reflect at turn from above
            for i in range(level + 1, turn + 1):
                legs.append(i)
                if i < turn:
                    factors.append((True, i, 1))
            factors.append((True, turn, 0))
        else:  # layers level … turn+1 upwards, then reflect at turn from below
            for i in range(level, turn, -1):
                legs.append(i)
                if i - 1 > turn:
                    factors.append((False, i - 1, 1))
            factors.append((False, turn, 0))
        level, going_down = turn, not going_down
    for i in range(level, 0, -1):  # back up and out through the front face
        legs.append(i)
        factors.append((False, i - 1, 1))
    return tuple(legs), tuple(factors)


def _path(
    turns: tuple[int, ...],
    legs: tuple[int, ...],
    modes: str,
    coefficient: complex,
    layers: Sequence[Layer],
    sines: list[float],
    c_w: float,
) -> EchoPath:
    """The path's fields (:class:`EchoPath`); ``sines`` its legs' sines of propagation."""
    equivalent = delay = time = 0.0
    lengths: dict[tuple[int, str], float] = {}
    for leg, mode, sine in zip(legs, modes, sines, strict=True):
        layer = layers[leg - 1]
        c, h = speed(layer.material, mode), layer.thickness
        cos = math.sqrt(max(1e-12, 1.0 - min(1.0, sine) ** 2))
        equivalent += 0.5 * h * c / c_w
        delay += h * (1.0 / c - c / c_w**2)
        time += h / (c * cos)
        lengths[(leg, mode)] = lengths.get((leg, mode), 0.0) + h / cos
    return EchoPath(
        turns,
        legs,
        coefficient,
        equivalent,
        delay,
        time,
        tuple((leg, mode, metres) for (leg, mode), metres in sorted(lengths.items())),
        modes,
    )
