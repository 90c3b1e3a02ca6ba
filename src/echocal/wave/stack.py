"""The plane-wave reflection coefficient of a whole layered plate in a fluid (global matrix).

A plate of N solid layers (:class:`~echocal.specimen.interior.Layer`, top first) lies
between two half-spaces of the same fluid.  A longitudinal plane wave of horizontal
slowness p (sin θ/c_w) and frequency f meets its front face; the plate returns one
reflected wave, R(p, f), which holds every interface echo, every multiple and every
mode conversion (P and SV waves in every layer).  It is solved here as one linear system
per (p, f), the global matrix of Lowe (IEEE UFFC 42, 525, 1995):

- unknowns: the reflected wave's amplitude R in the upper fluid, the transmitted one in
  the lower fluid, and in each layer four partial waves (P and SV, down- and up-going);
  a down-going wave is referred to its layer's top and an up-going one to its bottom, so
  every factor e^{iωq h} in the matrix has modulus ≤ 1 (no growing exponentials in thick
  layers or beyond a critical angle: the system stays well conditioned);
- equations at every interface: u_z and σ_zz continuous; between two solids (welded)
  u_x and σ_xz too; on a solid's face against the fluid σ_xz = 0.

Displacement potentials, u = ∇φ + ∇×(ψŷ), e^{−iωt}; amplitudes are ρω² times the
potentials, so R is the pressure reflection coefficient at the front face (the same
convention as :func:`echocal.wave.layered.mode_coefficients`, whose paths' coefficients
multiply to the terms of R's multiple-reflection expansion).

Attenuation: each material's power law α(f) [Np/m] (its ``shear_attenuation`` for SV
waves where it has one, else its ``attenuation``, as the paths take it) enters as a
complex slowness 1/c + iα(f)/ω, so the waves decay along every leg at their own angle.
At a complex frequency f + iε/2π (a damped train, :func:`damped_grid`) α is taken at f:
the power law |f|ⁿ has no analytic continuation, and the change it makes is of relative
order nε/(2πf) on the attenuation (below 10⁻³ of it on a 2 MHz pulse).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from echocal.materials import Material
from echocal.specimen.interior import Layer

__all__ = [
    "FOLD_SUPPRESSION",
    "complex_slownesses",
    "damped_grid",
    "stack_reflection",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def complex_slownesses(material: Material, frequency: complex) -> tuple[complex, complex]:
    """(s_L, s_T) [s/m]: ``material``'s longitudinal and shear slownesses at ``frequency``
    [Hz] with its attenuation, 1/c + iα(f)/ω (s_T = 0 in a fluid), so that the wavenumber
    ωs is ω/c + iα; at a complex frequency α is taken at its real part (module doc)."""
    omega = 2.0 * math.pi * frequency
    alpha_l = float(material.attenuation.alpha(frequency.real))
    s_l = 1.0 / material.longitudinal_speed + 1j * alpha_l / omega
    if material.is_fluid:
        return s_l, 0j
    law = material.shear_attenuation or material.attenuation
    s_t = 1.0 / material.shear_speed + 1j * float(law.alpha(frequency.real)) / omega
    return s_l, s_t


def _vertical(s: complex, p: FloatArray) -> ComplexArray:
    """√(s² − p²) [s/m] ``(n,)`` with Im ≥ 0 (decaying along its direction)."""
    q = np.sqrt(s * s - (p * p).astype(np.complex128))
    return np.where(q.imag < 0, -q, q)


def _partial_waves(
    material: Material, frequency: complex, p: FloatArray, scale: tuple[float, float]
) -> tuple[ComplexArray, ComplexArray, ComplexArray]:
    """(down, up, q): the fields (u_x, u_z, σ_zz, σ_xz) ``(n, 4, m)`` of the m = 1 (fluid:
    P) or 2 (solid: P, SV) partial waves going down (+z) and up, per unit ω (stresses per
    unit ω²), displacements times ``scale[0]`` and stresses times ``scale[1]``; and their
    vertical slownesses ``(n, m)``."""
    s_l, s_t = complex_slownesses(material, frequency)
    rho = material.density
    q_l = _vertical(s_l, p)
    zero = np.zeros_like(q_l)
    su, ss = scale
    if material.is_fluid:
        fields = []
        for sign in (1.0, -1.0):
            wave = np.stack(
                [1j * p * su + zero, 1j * sign * q_l * su, -rho * ss + zero, zero], axis=-1
            )
            fields.append(wave[..., None])
        return fields[0], fields[1], q_l[:, None]
    mu = rho / (s_t * s_t)
    q_t = _vertical(s_t, p)
    fields = []
    for sign in (1.0, -1.0):
        ql, qt = sign * q_l, sign * q_t
        wave_p = np.stack(
            [
                1j * p * su + zero,
                1j * ql * su,
                -(rho - 2.0 * mu * p * p) * ss + zero,
                -2.0 * mu * p * ql * ss,
            ],
            axis=-1,
        )
        wave_s = np.stack(
            [
                -1j * qt * su,
                1j * p * su + zero,
                -2.0 * mu * p * qt * ss,
                mu * (qt * qt - p * p) * ss,
            ],
            axis=-1,
        )
        fields.append(np.stack([wave_p, wave_s], axis=-1))
    return fields[0], fields[1], np.stack([q_l, q_t], axis=-1)


def stack_reflection(
    slowness: FloatArray, frequency: complex, layers: Sequence[Layer], medium: Material
) -> ComplexArray:
    """R ``(n,)``: the pressure reflection coefficient, at the front face, of ``layers``
    (solids, top first) between two half-spaces of the fluid ``medium``, for a plane wave
    from above of horizontal slowness ``slowness`` [s/m] ``(n,)`` (sin θ/c_w, real) at
    ``frequency`` [Hz] (real part > 0; a complex frequency f + iε/2π gives the reflected
    train damped by e^{−εt}) (module doc)."""
    p = np.asarray(slowness, dtype=np.float64)
    omega = 2.0 * math.pi * frequency
    n_layers = len(layers)
    size = 4 * n_layers + 2
    scale = (medium.longitudinal_speed, 1.0 / medium.density)
    fluid_down, fluid_up, _ = _partial_waves(medium, frequency, p, scale)
    waves = []
    for layer in layers:
        down, up, q = _partial_waves(layer.material, frequency, p, scale)
        decay = np.exp(1j * omega * q * layer.thickness)  # (n, 2): across the layer
        waves.append((down, up, decay))
    matrix = np.zeros((p.size, size, size), dtype=np.complex128)
    rhs = np.zeros((p.size, size), dtype=np.complex128)
    row = 0
    for i in range(n_layers + 1):  # interface i: medium i above (0: fluid), i + 1 below
        above: list[tuple[int, ComplexArray]] = []  # (column, (n, 4) field at the interface)
        below: list[tuple[int, ComplexArray]] = []
        if i == 0:
            above.append((0, fluid_up[..., 0]))
        else:
            down, up, decay = waves[i - 1]
            base = 2 + 4 * (i - 1)
            for m in range(2):  # at the layer's bottom
                above.append((base + m, down[..., m] * decay[:, m, None]))
                above.append((base + 2 + m, up[..., m]))
        if i == n_layers:
            below.append((1, fluid_down[..., 0]))
        else:
            down, up, decay = waves[i]
            base = 2 + 4 * i
            for m in range(2):  # at the layer's top
                below.append((base + m, down[..., m]))
                below.append((base + 2 + m, up[..., m] * decay[:, m, None]))
        solid_above, solid_below = i > 0, i < n_layers
        continuous = [0, 1, 2, 3] if solid_above and solid_below else [1, 2]
        for component in continuous:  # above − below = 0
            for col, field in above:
                matrix[:, row, col] += field[:, component]
            for col, field in below:
                matrix[:, row, col] -= field[:, component]
            if i == 0:  # the incident wave, known, is above the front face
                rhs[:, row] = -fluid_down[:, component, 0]
            row += 1
        if solid_above != solid_below:  # σ_xz = 0 on the solid's side
            for col, field in above if solid_above else below:
                matrix[:, row, col] = field[:, 3]
            row += 1
    return np.asarray(np.linalg.solve(matrix, rhs[..., None])[:, 0, 0], dtype=np.complex128)


FOLD_SUPPRESSION = 1e-5
"""What of the plate's echo train folds back onto the window, at most, as a fraction of
its undamped value (:func:`damped_grid`)."""


def damped_grid(window_span: float, window_end: float, grid_period: float) -> tuple[int, float]:
    """(factor, ε [1/s]): a frequency grid ``factor`` times finer than one of period
    ``grid_period`` [s] and a damping ε for the whole stack's echo train, computed at the
    complex frequencies f + iε/2π (the train times e^{−εt}, exactly: the response is
    causal) and undamped after the inverse transform.  What the train holds one period P
    later folds back damped by e^{−εP} = :data:`FOLD_SUPPRESSION`, so the plate may ring
    for any time.  The period is at least three times the window's span ``window_span``
    [s] (from the grid's first point to the window's end, with the pulse's support), so
    that undamping the window's end multiplies the response's numerical error there by
    at most e^{εP/3} ≈ 46; and at least the window's end ``window_end`` [s] (from t = 0,
    with the pulse's support), so that nothing from before t = 0 (where the response is
    0 but for what the propagating spectrum alone puts near t = 0) folds forward onto
    the window, where undamping would raise it by 1/:data:`FOLD_SUPPRESSION`."""
    factor = max(1, math.ceil(max(3.0 * window_span, window_end) / grid_period))
    return factor, math.log(1.0 / FOLD_SUPPRESSION) / (factor * grid_period)
