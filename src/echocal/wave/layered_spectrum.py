"""A layered plate's echo paths under a flat piston, exactly: over its plane-wave spectrum.

For an infinite flat layered plate every plane wave of the probe's angular spectrum
crosses the layers at its own angle, so each echo path (:mod:`echocal.wave.layered`) has a
response that is exact within linear elasticity (no paraxial step, the coefficients at
every component's own angle):

    V_path(f) = (ka)²/(4π) ∫₀^{π/2} sin θ dθ · A(θ, f) · C_path(sin θ)
                · exp(iω [2 d cos θ / c_w + Σ_legs h_j q_j(sin θ)]),

θ the plane wave's incidence angle on the face, d the probe centre's distance to the face
(along the face's normal), q_j = √(1/c_j² − sin²θ/c_w²) the vertical slowness in leg j's
layer (imaginary beyond its critical angle: the wave decays across the layer),
C_path the product of the path's longitudinal interface coefficients at that angle
(:func:`~echocal.wave.layered.pp_coefficient_arrays`), and A the probe's two-way
angular weight on the ring of directions of incidence θ:

    A(θ, f) = ∫₀^{2π} jinc(ka·p₊) jinc(ka·p₋) dφ,
    p±² = (sin θ cos φ cos t ± cos θ sin t)² + sin²θ sin²φ,

the transverse wavenumbers (per k) of the plane wave and of its mirror image in the
probe's frame, the probe tilted by t from the face's normal (jinc(x) = 2J₁(x)/x: the disc's
spectrum).  At t = 0, A = 2π·jinc²(ka sin θ) and the integral is one-dimensional (a
Hankel-type integral); at a tilt A is a smooth ring integral the paths share, so every
path is still a one-dimensional integral over θ.  It is the image-form derivation of the
pulse-echo response (average over the receiving face of the mirrored field), written in
the face's frame (dΩ is invariant under the rotation), with the rigid mirror replaced by
the path's plane-wave factor; propagating waves in water only (the evanescent part is
below 1e-4 at water paths of many wavelengths).

Quadrature: Gauss–Legendre panels of equal phase in θ over the whole quarter circle (the
piston edge's spectrum decays only like (ka sin θ)^−3/2, so it is not truncated), a
periodic trapezoid in φ; evaluated at :data:`FREQUENCIES` frequencies over the pulse's band
and interpolated between them after each path's axial delay is removed (what is left
varies slowly, as in :mod:`echocal.wave.curved_wall`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.special import j1, jv

from echocal.materials import Material
from echocal.specimen.interior import Layer
from echocal.wave.layered import mode_coefficients, path_factors
from echocal.wave.stack import stack_reflection

__all__ = [
    "FREQUENCIES",
    "PistonOverPlate",
    "Route",
    "band_responses",
    "path_responses",
    "stack_response",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

FREQUENCIES = 48
"""Frequencies over the band at which the paths' responses are integrated."""
_NODES_PER_PANEL = 12
"""Gauss–Legendre nodes per θ panel; a panel spans 4π of the integrand's phase at the
band's top frequency."""
_BAND_FLOOR = 1e-3
"""Frequencies where the pulse's spectrum is below this fraction of its peak are left out."""


def _jinc(x: ComplexArray | FloatArray) -> ComplexArray | FloatArray:
    """2J₁(x)/x with its limit 1 at x = 0 (x real or complex)."""
    safe = np.where(np.abs(x) < 1e-8, 1.0, x)
    bessel = jv(1, safe) if np.iscomplexobj(safe) else j1(safe)
    return np.where(np.abs(x) < 1e-8, 1.0, 2.0 * bessel / safe)


def _slowness(c: float, s: FloatArray, c_w: float) -> ComplexArray:
    """q = √(1/c² − s²/c_w²) [s/m] with Im q ≥ 0."""
    q = np.sqrt((1.0 / (c * c) - (s / c_w) ** 2).astype(np.complex128))
    return np.where(q.imag < 0, -q, q)


Route = tuple[tuple[int, ...], str]
"""An echo path's turns and the wave mode of each of its legs (``"L"`` or ``"S"``); no
turns: the front face's echo."""


def _path_terms(
    layers: Sequence[Layer], medium: Material, routes: Sequence[Route], s: FloatArray
) -> tuple[ComplexArray, ComplexArray]:
    """(C, τ) ``(n_paths, n)``: each route's coefficient product and its vertical travel
    time Σ h_j q_j [s] (complex beyond a critical angle) at the water incidence sines
    ``s`` ``(n,)``."""
    c_w = medium.longitudinal_speed
    media = [medium, *(layer.material for layer in layers), medium]
    p = s / c_w  # the horizontal slowness, common to every layer
    table: dict[tuple[bool, int, str], dict[tuple[str, str], ComplexArray]] = {}

    def coefficients_at(from_above: bool, i: int, mode: str) -> dict[tuple[str, str], ComplexArray]:
        key = (from_above, i, mode)
        if key not in table:
            upper, lower = (media[i], media[i + 1]) if from_above else (media[i + 1], media[i])
            # from below the frame is turned 180° about y (x and z reversed), so that a
            # shear potential means the same wave on both sides of a leg
            table[key] = mode_coefficients(p if from_above else -p, upper, lower, mode)
        return table[key]

    def speed(material: Material, mode: str) -> float:
        return material.longitudinal_speed if mode == "L" else material.shear_speed

    coefficients = np.ones((len(routes), s.size), dtype=np.complex128)
    times = np.zeros((len(routes), s.size), dtype=np.complex128)
    for j, (turns, modes) in enumerate(routes):
        if not turns:  # the front face's own echo
            coefficients[j] = coefficients_at(True, 0, "L")[("R", "L")]
            continue
        legs, factors = path_factors(turns)
        for k, (from_above, i, which) in enumerate(factors):
            incident = modes[k - 1] if k > 0 else "L"
            outgoing = modes[k] if k < len(legs) else "L"
            kind = "R" if which == 0 else "T"
            coefficients[j] *= coefficients_at(from_above, i, incident)[(kind, outgoing)]
        for leg, mode in zip(legs, modes, strict=True):
            layer = layers[leg - 1]
            times[j] += layer.thickness * _slowness(speed(layer.material, mode), s, c_w)
    return coefficients, times


def _theta_nodes(
    radius: float, f_max: float, c_w: float, distance: float, tilt: float, spread: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """θ nodes [rad] and weights (sin θ dθ) on [0, π/2]: panels of equal phase at
    ``f_max``, the phase being the water path's 2d(1 − cos θ)/c_w, the paths' largest
    spread ``spread`` [s] (on :func:`np.linspace` (0, π/2, spread.size)), and the probe
    spectrum's oscillation (4ka + 2ka·sin t)·sin θ."""
    theta = np.linspace(0.0, 0.5 * math.pi, spread.size)
    omega = 2.0 * math.pi * f_max
    ka = omega / c_w * radius
    phase = omega * (2.0 * distance * (1.0 - np.cos(theta)) / c_w + spread)
    phase = phase + (4.0 + 2.0 * math.sin(tilt)) * ka * np.sin(theta) + 20.0 * theta
    phase = np.maximum.accumulate(phase)
    n_panels = max(4, math.ceil(phase[-1] / (4.0 * math.pi)))
    edges = np.interp(np.linspace(0.0, phase[-1], n_panels + 1), phase, theta)
    x, w = np.polynomial.legendre.leggauss(_NODES_PER_PANEL)
    half = 0.5 * np.diff(edges)[:, None]
    nodes = (0.5 * (edges[:-1] + edges[1:])[:, None] + half * x).ravel()
    weights = (half * w).ravel() * np.sin(nodes)
    return nodes, weights


def _ring_weight(
    theta: FloatArray, ka: FloatArray | ComplexArray, tilt: float
) -> FloatArray | ComplexArray:
    """A(θ, f) ``(n_f, n)`` (module doc) for ka ``(n_f,)`` (complex at a complex
    frequency: A is analytic in ω)."""
    st, ct = np.sin(theta), np.cos(theta)
    if abs(tilt) < 1e-12:
        return 2.0 * math.pi * _jinc(ka[:, None] * st) ** 2
    n_half = 8 + math.ceil(2.0 * float(np.abs(ka).max()) * abs(math.sin(tilt)))
    phi = np.linspace(0.0, math.pi, n_half + 1)
    w_phi = np.full(phi.size, 2.0 * math.pi / n_half)  # both half circles
    w_phi[[0, -1]] *= 0.5
    out = np.zeros((ka.size, theta.size), dtype=np.result_type(ka, np.float64))
    along = st[:, None] * np.cos(phi) * math.cos(tilt)
    across2 = (st[:, None] * np.sin(phi)) ** 2
    lift = (ct * math.sin(tilt))[:, None]
    p_plus = np.sqrt((along + lift) ** 2 + across2)
    p_minus = np.sqrt((along - lift) ** 2 + across2)
    for i, k in enumerate(ka):
        out[i] = (_jinc(k * p_plus) * _jinc(k * p_minus)) @ w_phi
    return out


@dataclass(frozen=True)
class PistonOverPlate:
    """A flat piston over a flat layered plate.

    Attributes
    ----------
    radius : [m] the piston's radius a.
    medium : the coupling fluid (its ``longitudinal_speed`` c_w; density for the
        coefficients).
    layers : the plate's layers, top first.
    distance : [m] the probe centre's distance to the face along its normal.
    tilt : [rad] the beam axis's angle to the face's normal.
    """

    radius: float
    medium: Material
    layers: Sequence[Layer]
    distance: float
    tilt: float


def path_responses(
    setting: PistonOverPlate, routes: Sequence[Route], freqs: FloatArray
) -> ComplexArray:
    """Each route's exact response V(f) ``(n_paths, n_f)`` (module doc; e^{−iωt},
    normalized as :meth:`~echocal.wave.WaveEchoModel.spectrum_of_response` takes it) in
    ``setting``: ``routes`` each path's turns
    (:func:`~echocal.specimen.interior.turn_sequences`) and its legs' wave modes, at
    ``freqs`` [Hz] ``(n_f,)`` (positive)."""
    radius, medium, layers = setting.radius, setting.medium, setting.layers
    distance, tilt = setting.distance, setting.tilt
    c_w = medium.longitudinal_speed
    coarse = np.linspace(0.0, 0.5 * math.pi, 2001)
    _, times = _path_terms(layers, medium, routes, np.sin(coarse))
    spread = (times[:, :1] - times).real.max(axis=0) if len(routes) else np.zeros(coarse.size)
    theta, weights = _theta_nodes(radius, float(freqs.max()), c_w, distance, tilt, spread)
    coefficients, times = _path_terms(layers, medium, routes, np.sin(theta))
    omega = 2.0 * math.pi * freqs
    ka = omega / c_w * radius
    weight = _ring_weight(theta, ka, tilt) * weights * (ka * ka / (4.0 * math.pi))[:, None]
    water = 2.0 * distance * np.cos(theta) / c_w
    out = np.empty((len(routes), freqs.size), dtype=np.complex128)
    for j in range(len(routes)):
        phase = np.exp(1j * omega[:, None] * (water + times[j]))
        out[j] = np.sum(weight * phase * coefficients[j], axis=1)
    return out


def band_responses(
    setting: PistonOverPlate,
    routes: Sequence[Route],
    freqs: FloatArray,
    pulse_spectrum: FloatArray,
) -> ComplexArray:
    """:func:`path_responses` on every frequency of ``freqs`` ``(n_f,)`` [Hz] (0 where the
    pulse's spectrum magnitude ``pulse_spectrum`` ``(n_f,)`` is below :data:`_BAND_FLOOR` of
    its peak), integrated at :data:`FREQUENCIES` frequencies over the band and interpolated
    between them after each path's axial delay 2d/c_w + Σ h_j/c_j is removed."""
    out = np.zeros((len(routes), freqs.size), dtype=np.complex128)
    band = (pulse_spectrum > _BAND_FLOOR * pulse_spectrum.max()) & (freqs > 0.0)
    if not np.any(band) or not routes:
        return out
    fb = freqs[band]
    nodes = np.linspace(float(fb.min()), float(fb.max()), FREQUENCIES)
    responses = path_responses(setting, routes, nodes)
    _, axial = _path_terms(setting.layers, setting.medium, routes, np.zeros(1))
    delays = 2.0 * setting.distance / setting.medium.longitudinal_speed + axial[:, 0].real
    for j in range(len(routes)):
        smooth = responses[j] * np.exp(-2j * math.pi * nodes * delays[j])
        values = np.interp(fb, nodes, smooth.real) + 1j * np.interp(fb, nodes, smooth.imag)
        out[j, band] = values * np.exp(2j * math.pi * fb * delays[j])
    return out


def stack_response(setting: PistonOverPlate, freqs: ComplexArray, span: float) -> ComplexArray:
    """The whole plate's exact response V(f) ``(n_f,)`` in ``setting`` at ``freqs`` [Hz]
    ``(n_f,)`` (real parts positive; complex frequencies f + iε/2π give the response
    damped by e^{−εt}): the module doc's integral with the plate's own reflection
    coefficient R(sin θ/c_w, f) (:func:`echocal.wave.stack.stack_reflection`: every
    multiple and mode conversion, attenuation as complex slownesses) in place of a path's
    C·exp(iωΣh q): the front face's echo and the whole echo train in one.  The θ panels
    resolve the train's components up to ``span`` [s] after the front face's echo (the
    vertical time of any path that long spreads at most span·(1 − c q(θ)) over θ, c q
    the cosine in its fastest-spreading layer and mode)."""
    radius, medium, layers = setting.radius, setting.medium, setting.layers
    c_w = medium.longitudinal_speed
    coarse = np.linspace(0.0, 0.5 * math.pi, 2001)
    s = np.sin(coarse)
    spread = np.zeros(coarse.size)
    for layer in layers:
        for c in (layer.material.longitudinal_speed, layer.material.shear_speed):
            spread = np.maximum(spread, span * (1.0 - (c * _slowness(c, s, c_w)).real))
    f_max = float(freqs.real.max())
    theta, weights = _theta_nodes(radius, f_max, c_w, setting.distance, setting.tilt, spread)
    slowness = np.sin(theta) / c_w
    water = 2.0 * setting.distance * np.cos(theta) / c_w
    out = np.empty(freqs.size, dtype=np.complex128)
    for i, f in enumerate(freqs):
        omega = 2.0 * math.pi * complex(f)
        ka = np.array([omega / c_w * radius])
        weight = _ring_weight(theta, ka, setting.tilt)[0] * weights * (ka[0] ** 2 / (4.0 * math.pi))
        r = stack_reflection(slowness, complex(f), layers, medium)
        out[i] = np.sum(weight * np.exp(1j * omega * water) * r)
    return out
