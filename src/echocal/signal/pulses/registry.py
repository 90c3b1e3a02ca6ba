"""Pulses by name: the registry, its options, and the plausibility checks at the user
boundary (see :mod:`echocal.signal.pulses`)."""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal._validate import lookup
from echocal.constants import DEFAULT_CENTER_FREQUENCY
from echocal.errors import EchocalValueError
from echocal.signal.pulses.analytic import GaborPulse, RickerPulse, SincPulse
from echocal.signal.pulses.base import MAX_PULSE_CYCLES, Pulse
from echocal.signal.pulses.sampled import SampledPulse
from echocal.units import format_frequency, parse_quantity


# ---------------------------------------------------------------------------------------
def _gabor_factory(
    *,
    center_frequency: float = DEFAULT_CENTER_FREQUENCY,
    bandwidth: float | None = None,
    alpha: float | None = None,
    phase: float = 0.0,
) -> GaborPulse:
    if alpha is not None and bandwidth is not None:
        raise EchocalValueError("give either alpha [1/s²] or bandwidth [%], not both")
    if alpha is not None:
        return GaborPulse.from_alpha(alpha=alpha, center_frequency=center_frequency, phase=phase)
    return GaborPulse(
        center_frequency=center_frequency,
        bandwidth=60.0 if bandwidth is None else bandwidth,
        phase=phase,
    )


def _sampled_factory(
    *,
    samples: ArrayLike | None = None,
    fs: float | None = None,
    file: str | Path | None = None,
    start_time: float | None = None,
) -> SampledPulse:
    if (samples is None) == (file is None):
        raise EchocalValueError("a sampled pulse needs exactly one of samples or file")
    if file is not None:
        return SampledPulse.from_file(file, fs=fs, start_time=start_time)
    if fs is None:
        raise EchocalValueError("fs is required with samples")
    return SampledPulse(samples=np.asarray(samples), fs=fs, start_time=start_time)


_PULSES: dict[str, Callable[..., Pulse]] = {}


def register_pulse(name: str, factory: Callable[..., Pulse]) -> None:
    """Add a pulse factory ``factory(**params) -> Pulse`` under ``name`` (no duplicates)."""
    if name in _PULSES:
        raise EchocalValueError(f"pulse name {name!r} is already registered")
    _PULSES[name] = factory


def pulse_names() -> tuple[str, ...]:
    """Registered pulse names, sorted."""
    return tuple(sorted(_PULSES))


def make_pulse(name: str, **params: Any) -> Pulse:
    """Build the pulse registered as ``name`` with keyword parameters (SI units, degrees).

    Example: ``make_pulse("gabor", center_frequency=5e6, bandwidth=60)``.
    """
    factory = lookup("pulse", name, _PULSES)
    valid = pulse_options(name)
    if valid is not None:
        for key in params:
            if key not in valid:
                raise EchocalValueError(
                    f"{key}: unknown option for {name}; valid: {', '.join(valid)}"
                )
    try:
        return factory(**params)
    except TypeError as exc:
        raise EchocalValueError(f"bad parameters for pulse {name!r}: {exc}") from None


def pulse_options(name: str) -> tuple[str, ...] | None:
    """Keyword options of the pulse registered as ``name``, sorted (None: any keyword).

    ``pulse_options("gabor")`` is ``("alpha", "bandwidth", "center_frequency", "phase")``.
    """
    return _factory_options(lookup("pulse", name, _PULSES))


@functools.cache
def _factory_options(factory: Callable[..., Pulse]) -> tuple[str, ...] | None:
    """:func:`pulse_options` of one factory, inspected once (make_pulse checks every call's
    keywords against it; a re-registered name is a new factory, inspected anew)."""
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):  # a builtin or C callable: cannot tell
        return None
    kinds = (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in signature.parameters.values()):
        return None
    return tuple(sorted(p.name for p in signature.parameters.values() if p.kind in kinds))


SINC_MIN_BANDWIDTH = 1e3
"""[Hz] the smallest plausible one-sided bandwidth B of a :class:`SincPulse` at the user
boundary (a bare ``60`` meant as 60 % is 60 Hz for sinc)."""


def plausible_bandwidth(
    name: str,
    bandwidth: float,
    center_frequency: float,
    *,
    field: str = "bandwidth",
    bare: bool = False,
    lobes: int = 4,
) -> float:
    """Return ``bandwidth`` (as :func:`parse_bandwidth` gives it) unless it is implausible.

    A sinc B [Hz] below :data:`SINC_MIN_BANDWIDTH` is refused; when the user typed a
    ``bare`` number the message suggests the readings (``'60%'``, ``'60 kHz'``,
    ``'60 MHz'``) that give a computable pulse of B <= f_c [Hz].  Other pulses pass.
    """
    if name != "sinc" or not SINC_MIN_BANDWIDTH > bandwidth > 0:
        return bandwidth
    hints = []
    if bare:
        fc = center_frequency
        for text, b in (
            (f"'{bandwidth:g}%'", bandwidth / 100.0 * fc / 2.0),
            (f"'{bandwidth:g} kHz'", bandwidth * 1e3),
            (f"'{bandwidth:g} MHz'", bandwidth * 1e6),
        ):
            if SINC_MIN_BANDWIDTH <= b <= fc and lobes * (fc + b) / b <= MAX_PULSE_CYCLES:
                hints.append(f"{text} (B = {format_frequency(b)})")
    raise EchocalValueError(
        f"{field}: B = {format_frequency(bandwidth)} is implausible for the sinc pulse (its "
        "bandwidth is the one-sided B in Hz, at least "
        f"{format_frequency(SINC_MIN_BANDWIDTH)}; gabor's is in %)"
        + (f" — did you mean {' or '.join(hints)}?" if hints else "")
    )


def parse_bandwidth(
    name: str, value: Any, center_frequency: float, field: str = "bandwidth"
) -> float:
    """A ``bandwidth`` as typed by a user → the value the pulse ``name`` takes.

    The pulses disagree on units: ``gabor``/``gaussian`` take the fractional −6 dB
    bandwidth in %, ``sinc`` the one-sided baseband bandwidth B in Hz.  So:

    * ``"60%"`` is 60 % for gabor; for sinc the −6 dB passband 2B is 60 % of
      ``center_frequency`` [Hz] (B = 0.3·f_c);
    * a frequency with a unit (``"3 MHz"``) is the full −6 dB width for gabor
      (converted to % of f_c) and B for sinc;
    * a bare number is % for gabor and Hz for sinc.

    Other pulses and non-numbers are returned unchanged (the pulse refuses them by name).
    """
    gabor = name in ("gabor", "gaussian")
    if not (gabor or name == "sinc") or isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return float(value)
    if not isinstance(value, str):
        return value
    text = value.strip()
    if text.endswith("%"):
        pct = parse_quantity(field, text[:-1], "frequency", "Hz")  # a plain number
        return pct if gabor else pct / 100.0 * center_frequency / 2.0
    if gabor:
        try:
            return float(text)  # bare number: percent
        except ValueError:
            return 100.0 * parse_quantity(field, text, "frequency", "Hz") / center_frequency
    return parse_quantity(field, text, "frequency", "Hz")


register_pulse("gabor", _gabor_factory)
register_pulse("gaussian", _gabor_factory)
register_pulse("sinc", SincPulse)
register_pulse("ricker", RickerPulse)
register_pulse("sampled", _sampled_factory)
