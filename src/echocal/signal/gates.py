"""Measurement gates as on a flaw detector: absolute and interface-triggered, by name.

A :class:`TimeGate` is a time window in which a metric (pseudo-energy, envelope peak,
energy in dB) is computed: every sample outside it is set to zero before the metric sees
the A-scan, so the metric inside the gate *is* the metric of the gated trace.

- An **absolute** gate has a fixed ``start`` [s] on the recording's time axis.
- An **interface-triggered** gate (a flaw detector's IF gate) starts ``delay`` [s] after
  the interface trigger: the first time |x| reaches ``threshold`` × the A-scan's own peak
  |x| in the whole recording (the front-wall echo), and 5 × the A-scan's noise σ: an
  A-scan without an interface echo above the noise does not trigger, and the gate then
  holds nothing.  When the water path changes, the
  front wall moves and the gate moves with it, so a back-wall gate stays on the back wall.

Named gates (:func:`resolve_gate`):

- ``front-wall``: interface-triggered, around the first strong echo: from ¾ of a pulse
  duration d before the trigger, 2 d wide (the pseudo-energy window's span); narrowed to
  2T/c_L on a plate thinner than that, so the back wall stays out.
- ``back-wall``: the front-wall gate moved 2T/c_L later (T the plate's thickness, c_L its
  material's longitudinal speed): centred on the back-wall echo.
- ``interface-K`` (a layered plate): the front-wall gate moved Σ 2h_i/c_i over the layers
  above interface K (K = 1 … N, N the back wall, which ``back-wall`` then names too),
  narrowed to the round trip of layer K: centred on that interface's primary echo.
- ``NAME``: a gate defined in the setup file (``[[gates]]``).
- ``START,WIDTH``: an absolute gate, µs unless a unit is given (``30us,2us``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float
from echocal.errors import EchocalValueError, UnknownNameError
from echocal.signal.noise import mad_sigma
from echocal.signal.processing import Gate, get_metric
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = [
    "BUILTIN_GATES",
    "INTERFACE_THRESHOLD",
    "TRIGGER_NOISE_LEVEL",
    "TimeGate",
    "check_gate",
    "gated_metric",
    "interface_trigger",
    "named_gate",
    "plate_layers",
    "resolve_gate",
    "setup_gate",
]

_F64 = NDArray[np.float64]

BUILTIN_GATES = ("front-wall", "back-wall")
"""The gate names every setup knows (``back-wall`` needs a plate thickness)."""

INTERFACE_THRESHOLD = 0.5
"""Default interface-trigger level: a fraction of each A-scan's peak |x|."""

_SEES_ECHO = 1e-3
"""A gate sees an echo when the noiseless reference A-scan inside it reaches this fraction
(−60 dB) of the reference's peak |x|, and the receiver's noise σ."""


TRIGGER_NOISE_LEVEL = 5.0
"""The interface trigger also needs |x| ≥ this × the A-scan's noise σ
(``echocal.signal.noise.mad_sigma``: 1.4826 × the median absolute deviation of its
samples, which are mostly noise), as a flaw
detector's interface gate is set above the noise: a sample of Gaussian noise reaches 5 σ
with probability 5.7·10⁻⁷, so a trace of 4,000 noise samples triggers in about 0.2 % of
A-scans.  Without it, an A-scan whose interface echo is lost (the probe tilted beyond
the front wall's lobe) triggers at half its own peak — on noise — and its gate holds a
random stretch of the trace, which can be the front wall itself."""


def interface_trigger(
    samples: ArrayLike, window: RecordingWindow, threshold: float = INTERFACE_THRESHOLD
) -> _F64:
    """[s] the interface trigger of each A-scan, shape ``(...,)``: the first time |x|
    reaches ``threshold`` × its own peak |x| in the whole recording, and at least
    :data:`TRIGGER_NOISE_LEVEL` × its noise σ (linearly interpolated between samples);
    NaN where no sample does (no interface echo above the noise, or an all-zero A-scan):
    a triggered gate then holds nothing."""
    whole = Gate(start=window.start, width=window.duration, threshold=threshold)
    return whole.first_crossing(samples, window, floor=TRIGGER_NOISE_LEVEL * mad_sigma(samples))


@dataclass(frozen=True, kw_only=True)
class TimeGate:
    """A named gate: absolute (``start``) or interface-triggered (``delay``).

    Attributes
    ----------
    name : how results and plots call it.
    width : [s] gate width (> 0).
    start : [s] absolute start on the recording's time axis; None for a triggered gate.
    delay : [s] start after the interface trigger (may be negative); None for an absolute
        gate.  Exactly one of ``start`` and ``delay`` is given.
    threshold : interface-trigger level, a fraction (0, 1] of each A-scan's peak |x|
        (triggered gates only).
    """

    name: str
    width: float
    start: float | None = None
    delay: float | None = None
    threshold: float = INTERFACE_THRESHOLD

    def __post_init__(self) -> None:
        where = f"gate {self.name}"
        if not isinstance(self.name, str) or not self.name.strip():
            raise EchocalValueError(f"gate name must be a non-empty text; got {self.name!r}")
        for key in ("width", "start", "delay", "threshold"):
            if isinstance(getattr(self, key), bool):
                raise EchocalValueError(
                    f"{where}: {key} must be a number, not the boolean {getattr(self, key)}"
                )
        width = finite_float(f"{where}: width", self.width)
        if width <= 0:
            raise EchocalValueError(f"{where}: width must be > 0 s; got {width:g}")
        object.__setattr__(self, "width", width)
        if (self.start is None) == (self.delay is None):
            raise EchocalValueError(
                f"{where}: give either start (an absolute gate) or delay (triggered by the "
                "interface echo), not both or neither"
            )
        for key in ("start", "delay"):
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, finite_float(f"{where}: {key}", value))
        threshold = finite_float(f"{where}: threshold", self.threshold)
        if not 0.0 < threshold <= 1.0:
            raise EchocalValueError(
                f"{where}: threshold is a fraction of the A-scan's peak and must lie in "
                f"(0, 1]; got {threshold:g}"
            )
        object.__setattr__(self, "threshold", threshold)

    @property
    def triggered(self) -> bool:
        """Whether the gate follows the interface echo."""
        return self.delay is not None

    def starts(self, samples: ArrayLike, window: RecordingWindow) -> _F64:
        """[s] the gate's start for each A-scan, shape ``(...,)`` (NaN where a triggered
        gate finds no interface echo)."""
        x = np.asarray(samples, dtype=np.float64)
        if self.start is not None:
            return np.full(x.shape[:-1], self.start)
        assert self.delay is not None
        return interface_trigger(x, window, self.threshold) + self.delay

    def masks(self, samples: ArrayLike, window: RecordingWindow) -> NDArray[np.bool_]:
        """Which samples of each A-scan lie inside the gate, shape of ``samples``."""
        x = np.asarray(samples, dtype=np.float64)
        lo = self.starts(x, window)[..., None]
        t = window.times
        return (t >= lo) & (t <= lo + self.width)  # NaN start: nothing inside

    def apply(self, samples: ArrayLike, window: RecordingWindow) -> _F64:
        """The gated A-scans: ``samples`` with every sample outside the gate set to 0."""
        x = np.asarray(samples, dtype=np.float64)
        return np.where(self.masks(x, window), x, 0.0)

    def spans(self, samples: ArrayLike, window: RecordingWindow) -> tuple[_F64, _F64]:
        """[s] (start, end) of the gate for each A-scan, each shape ``(...,)``."""
        lo = self.starts(samples, window)
        return lo, lo + self.width

    def describe(self) -> dict[str, Any]:
        """The gate as plain data (for result files and provenance), times in seconds."""
        if self.start is not None:
            return {"name": self.name, "start_s": self.start, "width_s": self.width}
        return {
            "name": self.name,
            "trigger": "interface",
            "delay_s": self.delay,
            "width_s": self.width,
            "threshold": self.threshold,
            "trigger_noise_level": TRIGGER_NOISE_LEVEL,  # × the A-scan's robust noise σ
        }

    def label(self) -> str:
        """One short line for legends and messages, times in µs."""
        if self.start is not None:
            return f"{self.name} [{self.start * 1e6:.4g}, {(self.start + self.width) * 1e6:.4g}] µs"
        assert self.delay is not None
        return f"{self.name} (IF {self.delay * 1e6:+.4g} µs, {self.width * 1e6:.4g} µs wide)"


def gated_metric(
    metric: str,
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    gate: TimeGate | None = None,
    window_length: float | None = None,
) -> _F64:
    """The registered ``metric`` of each A-scan computed inside ``gate`` (the whole
    recording without one), shape ``(...,)``: the metric of the gated trace."""
    fn = get_metric(metric)
    x = np.asarray(samples, dtype=np.float64)
    if gate is not None:
        x = gate.apply(x, window)
    if window_length is not None and metric != "peak-amplitude":
        return np.asarray(fn(x, window, pulse, window_length), dtype=np.float64)
    return np.asarray(fn(x, window, pulse), dtype=np.float64)


def _plate_round_trip(thickness: float | None, material: Any, field: str) -> float:
    """[s] 2T/c_L of the plate, or a one-line refusal naming the fix."""
    speed = getattr(material, "longitudinal_speed", None)
    if thickness is None or speed is None:
        raise EchocalValueError(
            f"{field} back-wall: the setup has no plate thickness (give [specimen] "
            "thickness and a solid material, e.g. --setup immersion-steel-plate), or gate "
            "the back wall by time with --gate START,WIDTH"
        )
    return 2.0 * float(thickness) / float(speed)


def plate_layers(setup: Any) -> tuple[tuple[float, float], ...]:
    """``((h [m], c_L [m/s]), …)`` of a setup's layered plate, top first; empty for a
    setup without layers."""
    interior = getattr(setup, "interior", None)
    layers = getattr(interior, "layers", ()) or ()
    return tuple((layer.thickness, layer.material.longitudinal_speed) for layer in layers)


def _interface_gate(
    name: str, layers: tuple[tuple[float, float], ...], delay: float, width: float
) -> TimeGate | None:
    """The ``interface-K`` gate of a layered plate, or None when ``name`` is not one."""
    if not layers or not name.startswith("interface-") or not name[10:].isdigit():
        return None
    k = int(name[10:])
    if not 1 <= k <= len(layers):
        return None
    trips = [2.0 * h / c for h, c in layers]
    return TimeGate(name=name, delay=delay + sum(trips[:k]), width=min(width, trips[k - 1]))


def named_gate(
    name: str,
    *,
    pulse: Pulse,
    thickness: float | None = None,
    material: Any = None,
    defined: Iterable[TimeGate] = (),
    field: str = "--gate",
    layers: tuple[tuple[float, float], ...] = (),
) -> TimeGate:
    """The gate called ``name``: ``front-wall``, ``back-wall`` or one of ``defined``.

    Parameters
    ----------
    pulse : the transmitted pulse; its duration d [s] sizes the built-in gates.
    thickness : [m] the plate's thickness T (None: no interior).
    material : the plate's material (its ``longitudinal_speed`` c_L [m/s]).
    defined : the setup file's own gates.
    layers : a layered plate's ``(h [m], c_L [m/s])`` per layer (:func:`plate_layers`).
    """
    own = {g.name: g for g in defined}
    if name in own:
        return own[name]
    d = float(pulse.duration)
    width, delay = 2.0 * d, -0.75 * d
    if layers:
        if name == "back-wall":
            name = f"interface-{len(layers)}"
        gate = _interface_gate(name, layers, delay, min(width, 2.0 * layers[0][0] / layers[0][1]))
        if gate is not None:
            return gate
    if thickness is not None and getattr(material, "longitudinal_speed", None) is not None:
        width = min(width, _plate_round_trip(thickness, material, field))
    if name == "front-wall":
        return TimeGate(name=name, delay=delay, width=width)
    if name == "back-wall":
        return TimeGate(
            name=name, delay=delay + _plate_round_trip(thickness, material, field), width=width
        )
    interfaces = [f"interface-1…{len(layers)}"] if layers else []
    valid = ", ".join([*BUILTIN_GATES, *interfaces, *sorted(own)])
    raise UnknownNameError(
        f"{field}: unknown gate {name!r}; valid: {valid}, or START,WIDTH (µs unless a unit)"
    )


def resolve_gate(
    text: str,
    *,
    pulse: Pulse,
    thickness: float | None = None,
    material: Any = None,
    defined: Iterable[TimeGate] = (),
    field: str = "--gate",
    layers: tuple[tuple[float, float], ...] = (),
) -> TimeGate:
    """The gate a command line names: a gate name (:func:`named_gate`) or ``START,WIDTH``
    (µs unless a unit is given, e.g. ``30us,2us``), an absolute gate."""
    from echocal.units import parse_quantity

    if not isinstance(text, str) or not text.strip():
        raise EchocalValueError(f"{field} must name a gate or give START,WIDTH; got {text!r}")
    text = text.strip()
    if "," not in text:
        return named_gate(
            text,
            pulse=pulse,
            thickness=thickness,
            material=material,
            defined=defined,
            field=field,
            layers=layers,
        )
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise EchocalValueError(f"{field} takes START,WIDTH (µs unless a unit); got {text!r}")
    start, width = (
        parse_quantity(f"{field} {key}", value, "time", "us")
        for key, value in zip(("start", "width"), parts, strict=True)
    )
    if width <= 0:
        raise EchocalValueError(f"{field} width must be > 0; got {width * 1e6:g} µs")
    return TimeGate(name=f"{start * 1e6:g}us,{width * 1e6:g}us", start=start, width=width)


def check_gate(
    gate: TimeGate,
    window: RecordingWindow,
    reference: ArrayLike | None = None,
    *,
    noise_sigma: float = 0.0,
    field: str = "--gate",
    sees_echo: bool = True,
) -> None:
    """Refuse a gate outside the recording ``window`` or, given the noiseless
    ``reference`` A-scan (the echo at the optimum, ``(n_samples,)``), one that never sees
    an echo there (the gated reference below −60 dB of its peak or below ``noise_sigma``;
    skipped when not ``sees_echo``).
    """
    us = 1e6
    span = f"[{window.start * us:.4g}, {window.end * us:.4g}] µs"
    if gate.start is not None and (
        gate.start < window.start or gate.start + gate.width > window.end
    ):
        raise EchocalValueError(
            f"{field} {gate.name}: [{gate.start * us:.4g}, {(gate.start + gate.width) * us:.4g}]"
            f" µs is outside the recording window {span}; give a gate inside it"
        )
    if reference is None:
        return
    x = np.asarray(reference, dtype=np.float64)
    lo, hi = (float(v) for v in gate.spans(x, window))
    if math.isnan(lo):
        raise EchocalValueError(
            f"{field} {gate.name}: no interface echo triggers it at the reference pose; "
            "give an absolute gate START,WIDTH"
        )
    if lo < window.start or hi > window.end:
        raise EchocalValueError(
            f"{field} {gate.name}: at the reference pose it spans [{lo * us:.4g}, "
            f"{hi * us:.4g}] µs, outside the recording window {span}; move the gate or "
            "lengthen the window"
        )
    if not sees_echo:
        return
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    inside = float(np.max(np.abs(gate.apply(x, window))))
    if peak <= 0.0 or inside < max(_SEES_ECHO * peak, float(noise_sigma)):
        raise EchocalValueError(
            f"{field} {gate.name}: never sees an echo (at the reference pose, noiseless, "
            f"the gate [{lo * us:.4g}, {hi * us:.4g}] µs holds {inside / peak if peak else 0:.2g}"
            " of the peak); put it on an echo (see `echocal simulate --json` for the echoes)"
        )


def setup_gate(text: str, setup: Any, *, field: str = "--gate", sees_echo: bool = True) -> TimeGate:
    """The gate ``text`` names on a simulated ``setup`` (a
    :class:`~echocal.measurement.VirtualSetup`: its pulse, plate and own gates), checked
    before anything is measured: inside the recording window and (``sees_echo``) seeing an
    echo in the noiseless reference A-scan above the receiver's noise σ.  A look at one
    A-scan (``echocal simulate``) may gate pure noise: ``sees_echo=False``."""
    gate = resolve_gate(
        text,
        pulse=setup.pulse,
        thickness=getattr(setup, "thickness", None),
        material=getattr(setup, "material", None),
        defined=getattr(setup, "gates", ()),
        field=field,
        layers=plate_layers(setup),
    )
    if not (gate.triggered or sees_echo):
        check_gate(gate, setup.window, field=field)
        return gate
    check_gate(  # a triggered gate's place needs the reference echo
        gate,
        setup.window,
        setup.reference_samples,
        noise_sigma=float(setup.noise_sigma) if sees_echo else 0.0,
        field=field,
        sees_echo=sees_echo,
    )
    return gate


def gates_by_name(gates: Iterable[TimeGate]) -> Mapping[str, TimeGate]:
    """``{name: gate}``; a name used twice or shadowing a built-in gate is refused."""
    out: dict[str, TimeGate] = {}
    for gate in gates:
        if gate.name in BUILTIN_GATES or gate.name in out:
            raise EchocalValueError(
                f"gates: the name {gate.name!r} is "
                + ("a built-in gate" if gate.name in BUILTIN_GATES else "used twice")
                + "; choose another"
            )
        out[gate.name] = gate
    return out
