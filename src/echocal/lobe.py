"""The echo's lobe: how the echo falls off as the probe tilts away from its optimum.

:func:`echo_lobe` measures, noiselessly, the envelope peak of the echo against the tilt
away from the best orientation at one position, with the recording window placed around
the echo by itself, and gives the −6 dB half-width.  It is what decides how many
measurements a calibration needs (how far one A-scan "sees" the optimum), and what the
thesis's ray models get wrong: beside it, the analytic limits of a flat piston over a
plane, the deep near field 2J₁(2ka sinα)/(2ka sinα) (what the ray models reproduce at any
distance) and the far field [2J₁(ka sinα)/(ka sinα)]².
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import j1

from echocal._validate import finite_array, positive_float
from echocal.errors import EchocalValueError, GeometryError
from echocal.geometry import tilt_frame, tilt_normal
from echocal.measurement.virtual import VirtualSetup
from echocal.raytrace import cast
from echocal.signal.gates import TimeGate, gated_metric
from echocal.signal.processing import peak_amplitude
from echocal.signal.window import RecordingWindow

__all__ = ["EchoLobe", "echo_lobe", "far_field_lobe", "near_field_lobe"]

FloatArray = NDArray[np.float64]


def _jinc(x: FloatArray) -> FloatArray:
    """2J₁(x)/x with its limit 1 at x = 0."""
    x = np.asarray(x, dtype=np.float64)
    safe = np.where(np.abs(x) < 1e-8, 1.0, x)
    return np.where(np.abs(x) < 1e-8, 1.0, 2.0 * j1(safe) / safe)


def _directivity(x: FloatArray, aperture: str) -> FloatArray:
    """A flat piston's one-way far-field directivity at x = ka·sinθ: 2J₁(x)/x for a disc
    (a its radius), sin x / x for a rectangle (a its half-side across the tilt)."""
    if aperture == "rectangular":
        return np.sinc(np.asarray(x, dtype=np.float64) / math.pi)
    return _jinc(x)


FAR_FIELD_MINUS6DB_X = {"circular": 1.616, "rectangular": 1.392}
"""x = ka·sinα at which the far-field pulse-echo lobe D(x)² falls to one half."""


def far_field_lobe(ka: float, tilt_deg: ArrayLike, aperture: str = "circular") -> FloatArray:
    """Pulse-echo lobe of a flat piston over a plane in the far field: D(x)², x = ka·sin(tilt),
    D = 2J₁(x)/x for a disc, sin x / x for a rectangle (amplitude relative to normal
    incidence)."""
    return _directivity(ka * np.sin(np.radians(tilt_deg)), aperture) ** 2


def near_field_lobe(ka: float, tilt_deg: ArrayLike, aperture: str = "circular") -> FloatArray:
    """Deep-near-field lobe D(2x), x = ka·sin(tilt): the thesis's ray models' (the mean of
    the reflected wave's phase ramp over the face)."""
    return _directivity(2.0 * ka * np.sin(np.radians(tilt_deg)), aperture)


@dataclass(frozen=True, kw_only=True)
class EchoLobe:
    """Envelope peak of the echo against tilt away from the optimum (noiseless).

    Attributes
    ----------
    setup : the setup's name.
    model : the echo model used.
    position : [m] probe position, shape ``(3,)``.
    optimum_deg : gimbal tilts (α, β) [deg] of the optimum the lobe is centred on.
    distance_m : [m] distance to the surface along the optimum's beam axis.
    tilt_deg : [deg] tilt offsets of α from the optimum, shape ``(n,)``.
    amplitude : [a.u.] envelope peak at each tilt, shape ``(n,)`` (``simulate``'s units).
    peak_amplitude : [a.u.] envelope peak at the optimum.
    minus6db_deg : [deg] half-width where the envelope peak falls to one half (mean of
        both sides; NaN if the curve never falls that far within the range).
    ka : k·a of the probe at the pulse's centre frequency: a is a disc's radius, or a
        rectangle's half-height (the first gimbal angle α tilts the beam across it).
    aperture : ``"circular"`` or ``"rectangular"`` (the analytic limits' shape).
    gate : the gate the envelope peak was taken in (:meth:`TimeGate.describe`), or None.
    """

    setup: str
    model: str
    position: FloatArray
    optimum_deg: tuple[float, float]
    distance_m: float
    tilt_deg: FloatArray
    amplitude: FloatArray
    peak_amplitude: float
    minus6db_deg: float
    ka: float
    aperture: str = "circular"
    gate: dict[str, object] | None = None

    @property
    def relative_db(self) -> FloatArray:
        """[dB] the lobe relative to its peak, shape ``(n,)``."""
        with np.errstate(divide="ignore"):
            return 20.0 * np.log10(self.amplitude / self.peak_amplitude)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "setup": self.setup,
            "model": self.model,
            "position_m": [float(v) for v in self.position],
            "optimum_tilt_deg": list(self.optimum_deg),
            "distance_m": self.distance_m,
            "minus6db_deg": self.minus6db_deg,
            "peak_amplitude": self.peak_amplitude,
            "ka": self.ka,
            "aperture": self.aperture,
            "gate": self.gate,
            "tilt_deg": [float(v) for v in self.tilt_deg],
            "amplitude": [float(v) for v in self.amplitude],
        }


def _crossing(tilt: FloatArray, relative: FloatArray) -> float:
    """[deg] first |tilt| where ``relative`` (sorted by |tilt| from 0) falls below 0.5."""
    below = np.nonzero(relative < 0.5)[0]
    if below.size == 0 or below[0] == 0:
        return math.nan
    i = int(below[0])
    x0, x1 = abs(tilt[i - 1]), abs(tilt[i])
    y0, y1 = math.log(relative[i - 1]), math.log(max(relative[i], 1e-300))
    return x0 + (math.log(0.5) - y0) * (x1 - x0) / (y1 - y0)


def _half_width(tilt: FloatArray, amplitude: FloatArray, peak: float) -> float:
    relative = amplitude / peak
    right = tilt >= 0.0
    left = tilt <= 0.0
    sides = [
        _crossing(tilt[right], relative[right]),
        _crossing(tilt[left][::-1], relative[left][::-1]),
    ]
    finite = [s for s in sides if math.isfinite(s)]
    return float(np.mean(finite)) if finite else math.nan


def echo_lobe(
    setup: VirtualSetup,
    position: ArrayLike | None = None,
    *,
    max_tilt: float | None = None,
    n_points: int = 41,
    gate: TimeGate | None = None,
) -> EchoLobe:
    """The echo lobe of ``setup`` at ``position`` [m] (default: its reference position).

    The lobe is centred on the strongest direction of normal incidence on the surface
    (``VirtualSetup.normal_incidence_directions``), and
    tilts the first gimbal angle α from −``max_tilt`` to +``max_tilt`` [deg] (default:
    three far-field −6 dB half-widths of the probe) in ``n_points`` steps.  The recording
    window keeps the setup's sampling rate and is moved to hold the echo; with a ``gate``
    (:mod:`echocal.signal.gates`, e.g. the back wall) it is the setup's own window, and
    the envelope peak is taken inside the gate.
    """
    if position is None:
        position = setup.reference_position
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    if isinstance(n_points, bool) or not isinstance(n_points, int) or not 5 <= n_points <= 2001:
        raise EchocalValueError(f"n_points must be an integer in [5, 2001]; got {n_points!r}")
    aperture = setup.transducer.aperture
    # α tilts the beam across the face's y′ side (a rectangle's height)
    half = 0.5 * (setup.transducer.width if aperture == "circular" else setup.transducer.height)
    ka = 2.0 * math.pi * setup.pulse.center_frequency / setup.sound_speed * half
    if max_tilt is None:
        # three far-field −6 dB half-widths; never below 1° nor beyond 30°
        x6 = FAR_FIELD_MINUS6DB_X[aperture]
        max_tilt = min(max(3.0 * math.degrees(math.asin(min(x6 / ka, 1.0))), 1.0), 30.0)
    max_tilt = positive_float("max_tilt", max_tilt)
    if max_tilt > 60.0:
        raise EchocalValueError(f"max_tilt must be at most 60 deg; got {max_tilt:g}")
    optimum = _best_normal_incidence(setup, pos)
    distance = _distance_along(setup, pos, optimum)
    placed = (
        dataclasses.replace(setup, window=_window_around(setup, distance))
        if gate is None
        else setup  # the gate is placed on the setup's own time axis
    )
    tilts = np.linspace(-max_tilt, max_tilt, n_points)
    frames = tilt_frame(optimum[0] + tilts, np.full(n_points, optimum[1]))
    scans = placed.ideal_samples(np.broadcast_to(pos, (n_points, 3)), frames)
    amplitude = gated_metric("peak-amplitude", scans, placed.window, setup.pulse, gate)
    peak = float(amplitude[n_points // 2]) if n_points % 2 else float(np.max(amplitude))
    if not peak > 0.0:
        raise GeometryError(
            f"no echo at position ({pos[0]:g}, {pos[1]:g}, {pos[2]:g}) m: the lobe is undefined"
        )
    return EchoLobe(
        setup=setup.name,
        model=setup.reflection,
        position=pos,
        optimum_deg=(float(optimum[0]), float(optimum[1])),
        distance_m=distance,
        tilt_deg=tilts,
        amplitude=amplitude,
        peak_amplitude=peak,
        minus6db_deg=_half_width(tilts, amplitude, peak),
        ka=ka,
        aperture=aperture,
        gate=None if gate is None else gate.describe(),
    )


def _best_normal_incidence(setup: VirtualSetup, position: FloatArray) -> FloatArray:
    """Tilts [deg] ``(2,)`` of the strongest direction of normal incidence (noiseless
    envelope peak, window placed around each echo), each candidate refined to exact
    normal incidence first."""
    candidates = [
        _refine_normal(setup, position, c) for c in setup.normal_incidence_directions(position)
    ]
    best, best_value = candidates[0], -1.0
    for candidate in candidates:
        distance = _distance_along(setup, position, candidate)
        placed = dataclasses.replace(setup, window=_window_around(setup, distance))
        frame = tilt_frame(np.array([candidate[0]]), np.array([candidate[1]]))
        value = float(peak_amplitude(placed.ideal_samples(position[None], frame))[0])
        if value > best_value:
            best, best_value = candidate, value
    return np.asarray(best, dtype=np.float64)


def _refine_normal(setup: VirtualSetup, position: FloatArray, tilt: FloatArray) -> FloatArray:
    """Tilts [deg] of the beam from ``position`` at exact normal incidence near ``tilt``:
    aim along the surface normal where the beam lands, until it lands where it aims
    (one step on a plane; a few near a smooth curved surface)."""
    best = np.asarray(tilt, dtype=np.float64)
    best_cos = -1.0
    current = best
    for _ in range(8):
        direction = -tilt_normal(np.array([current[0]]), np.array([current[1]])).reshape(3)
        hits = cast(setup.specimen, position[None], direction[None])
        if not bool(hits.hit[0]):
            break
        normal = hits.normal[0]
        cos = float(-np.dot(normal, direction))
        if cos <= best_cos:
            break
        best, best_cos = current, cos
        if cos > 1.0 - 1e-15:
            break
        current = _tilts_of(normal)
    return best


def _tilts_of(normal: FloatArray) -> FloatArray:
    """Gimbal tilts [deg] of the orientation whose beam travels along −``normal``:
    n = R_y(β) R_x(α) ẑ = (sinβ cosα, −sinα, cosβ cosα)."""
    alpha = math.degrees(math.asin(max(-1.0, min(1.0, -normal[1]))))
    beta = math.degrees(math.atan2(normal[0], normal[2]))
    return np.array([alpha, beta])


def _distance_along(setup: VirtualSetup, position: FloatArray, tilt: FloatArray) -> float:
    direction = -tilt_normal(np.array([tilt[0]]), np.array([tilt[1]]))
    hits = cast(setup.specimen, position[None], direction.reshape(1, 3))
    if not bool(hits.hit[0]):
        raise GeometryError("the beam axis at the optimum misses the specimen")
    return float(hits.distance[0])


def _window_around(setup: VirtualSetup, distance: float) -> RecordingWindow:
    """The setup's sampling rate, a window of ±(8 pulse supports + the probe's transit)
    around the echo of a surface ``distance`` [m] away."""
    fs = setup.window.fs
    tof = 2.0 * distance / setup.sound_speed
    span = 8.0 * setup.pulse.support + 2.0 * setup.transducer.width / setup.sound_speed
    start = max(tof - span, 0.0)
    return RecordingWindow(fs=fs, start=start, n_samples=max(64, math.ceil(2.0 * span * fs)))
