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
normal-incidence or slightly tilted probe reads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal.materials import Material
from echocal.specimen.interior import Layer, turn_sequences

__all__ = ["EchoPath", "echo_paths", "path_label", "pp_coefficients"]

FloatArray = NDArray[np.float64]


def pp_coefficients(sin_in: float, upper: Material, lower: Material) -> tuple[complex, complex]:
    """(R, T): a longitudinal plane wave in ``upper`` meeting ``lower`` at incidence sine
    ``sin_in``: the reflected and transmitted longitudinal waves' stress amplitudes per unit
    incident stress (pressure in a fluid), in the e^{−iωt} convention of
    :mod:`echocal.coefficients`.

    Solved from the boundary conditions of the P–SV problem with displacement potentials
    (u = ∇φ + ∇×(ψŷ)): u_z and σ_zz continuous; between two solids (welded) u_x and σ_xz
    too; on a solid's face against a fluid σ_xz = 0.  A wave of potential amplitude a has
    stress amplitude ρω²a, so R = a_r/a_i and T = ρ₂a_t/(ρ₁a_i).  At normal incidence:
    (Z₂ − Z₁)/(Z₂ + Z₁) and 2Z₂/(Z₁ + Z₂)."""
    omega = 1.0
    kx = sin_in / upper.longitudinal_speed

    def kz(speed: float) -> complex:
        value = np.sqrt(complex((omega / speed) ** 2 - kx * kx))
        return -value if value.imag < 0 else value  # decaying away from the interface

    def columns(medium: Material, sign: float) -> list[NDArray[np.complex128]]:
        """(u_x, u_z, σ_zz, σ_xz)/(ρ₁ω²) of the P (and SV) partial waves travelling along
        ``sign``·z (z from upper into lower)."""
        rho, c_l, c_t = medium.density, medium.longitudinal_speed, medium.shear_speed
        mu = rho * c_t * c_t
        k_t2 = (omega / c_t) ** 2 if c_t > 0 else 0.0
        kzl = sign * kz(c_l)
        scale = upper.density * omega * omega
        p_wave = np.array(
            [1j * kx, 1j * kzl, -(rho * omega**2 - 2.0 * mu * kx * kx), -2.0 * mu * kx * kzl],
            dtype=np.complex128,
        )
        p_wave[2:] /= scale
        out = [p_wave]
        if c_t > 0:
            kzt = sign * kz(c_t)
            s_wave = np.array(
                [-1j * kzt, 1j * kx, -2.0 * mu * kx * kzt, mu * (kzt * kzt - kx * kx)],
                dtype=np.complex128,
            )
            s_wave[2:] /= scale
            assert k_t2 > 0
            out.append(s_wave)
        return out

    incident = columns(upper, 1.0)[0]
    reflected = columns(upper, -1.0)
    transmitted = columns(lower, 1.0)
    solid_up, solid_down = not upper.is_fluid, not lower.is_fluid
    # unknowns: upper's reflected waves (+), lower's transmitted waves (−), continuity rows
    rows = [1, 2]  # u_z, σ_zz
    if solid_up and solid_down:
        rows += [0, 3]  # u_x, σ_xz
    matrix = [[col[r] for col in reflected] + [-col[r] for col in transmitted] for r in rows]
    rhs = [-incident[r] for r in rows]
    if solid_up != solid_down:  # σ_xz = 0 on the solid's face
        solid_side = [
            *(col[3] for col in reflected),
            *(0.0 * col[3] for col in transmitted),
        ]
        if solid_down:
            solid_side = [*(0.0 * col[3] for col in reflected), *(col[3] for col in transmitted)]
        matrix.append(solid_side)
        rhs.append(-incident[3] if solid_up else 0.0)
    x = np.linalg.solve(np.array(matrix, dtype=np.complex128), np.array(rhs, dtype=np.complex128))
    r = complex(x[0])
    t = complex(x[len(reflected)]) * lower.density / upper.density
    return r, t


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
    attenuation_path : ((layer, metres), …) the distance it travels in each layer.
    """

    turns: tuple[int, ...]
    legs: tuple[int, ...]
    coefficient: complex
    equivalent_depth: float
    delay: float
    plate_time: float
    attenuation_path: tuple[tuple[int, float], ...]

    @property
    def label(self) -> str:
        """``interface-2`` for a primary echo, ``interface-2.1.2`` for a multiple."""
        return path_label(self.turns)


def path_label(turns: Sequence[int]) -> str:
    """The label of the echo that reflects at ``turns`` (interface numbers, in order)."""
    return "interface-" + ".".join(str(t) for t in turns)


def echo_paths(
    layers: Sequence[Layer], medium: Material, sin_water: float, order: int
) -> list[EchoPath]:
    """Every longitudinal echo path through ``layers`` (top first) in ``medium`` up to
    ``order`` (module doc), at the beam axis's incidence sine ``sin_water`` in the fluid."""
    c_w = medium.longitudinal_speed
    media = [medium, *(layer.material for layer in layers), medium]  # index = layer number
    sines = [sin_water * m.longitudinal_speed / c_w for m in media]
    blocked = any(s >= 1.0 for s in sines[1:-1])

    def down(i: int) -> tuple[complex, complex]:  # at interface i from above: (R, T)
        return pp_coefficients(sines[i], media[i], media[i + 1])

    def up(i: int) -> tuple[complex, complex]:  # at interface i from below
        return pp_coefficients(sines[i + 1], media[i + 1], media[i])

    n = len(layers)
    cache_down = {} if blocked else {i: down(i) for i in range(n + 1)}
    cache_up = {} if blocked else {i: up(i) for i in range(n)}

    def factor(table: dict[int, tuple[complex, complex]], i: int, which: int) -> complex:
        return 1.0 if blocked else table[i][which]

    out = []
    for turns in turn_sequences(n, order):
        coefficient = factor(cache_down, 0, 1)  # into layer 1
        legs: list[int] = []
        level, going_down = 0, True  # the last interface met
        for turn in turns:
            if going_down:  # layers level+1 … turn, then reflect at turn from above
                for i in range(level + 1, turn + 1):
                    legs.append(i)
                    if i < turn:
                        coefficient *= factor(cache_down, i, 1)
                coefficient *= factor(cache_down, turn, 0)
            else:  # layers level … turn+1 upwards, then reflect at turn from below
                for i in range(level, turn, -1):
                    legs.append(i)
                    if i - 1 > turn:
                        coefficient *= factor(cache_up, i - 1, 1)
                coefficient *= factor(cache_up, turn, 0)
            level, going_down = turn, not going_down
        for i in range(level, 0, -1):  # back up and out through the front face
            legs.append(i)
            coefficient *= factor(cache_up, i - 1, 1)
        out.append(_path(turns, tuple(legs), 0j if blocked else coefficient, layers, sines, c_w))
    return out


def _path(
    turns: tuple[int, ...],
    legs: tuple[int, ...],
    coefficient: complex,
    layers: Sequence[Layer],
    sines: list[float],
    c_w: float,
) -> EchoPath:
    equivalent = delay = time = 0.0
    lengths: dict[int, float] = {}
    for leg in legs:
        layer = layers[leg - 1]
        c, h = layer.material.longitudinal_speed, layer.thickness
        cos = math.sqrt(max(1e-12, 1.0 - min(1.0, sines[leg]) ** 2))
        equivalent += 0.5 * h * c / c_w
        delay += h * (1.0 / c - c / c_w**2)
        time += h / (c * cos)
        lengths[leg] = lengths.get(leg, 0.0) + h / cos
    return EchoPath(
        turns, legs, coefficient, equivalent, delay, time, tuple(sorted(lengths.items()))
    )
