"""Transmit pulses (thesis §3.2): Gabor, windowed sinc, Ricker and sampled waveforms.

Every pulse is a frozen, keyword-only dataclass describing the real RF waveform
``w(t)`` that one unit-amplitude ray with time of flight τ = 0 contributes to an
A-scan, so that thesis eq. (28) reads ``x(t) = Σₙ aₙ w(t − τₙ)``.  A pulse gives
its spectrum ``W(f) = ∫ w(t) exp(−i2πft) dt`` (closed form where one exists),
autocorrelation, energy spectral density and the few scalar facts the synthesis
and processing stages need (``support``, ``highest_frequency``, ``duration``).

Registry: :func:`make_pulse` ``(name, **params)`` and :func:`pulse_names`.

The package has one module per job: ``base`` (the interface),
``analytic`` (closed-form pulses),
``sampled`` (measured waveforms) and
``registry`` (names, options, plausibility).
"""

from echocal.signal.pulses.analytic import WINDOW_NAMES, GaborPulse, RickerPulse, SincPulse
from echocal.signal.pulses.base import MAX_PULSE_CYCLES, MAX_SAMPLED_PULSE_SAMPLES, Pulse
from echocal.signal.pulses.registry import (
    SINC_MIN_BANDWIDTH,
    make_pulse,
    parse_bandwidth,
    plausible_bandwidth,
    pulse_names,
    pulse_options,
    register_pulse,
)
from echocal.signal.pulses.sampled import SampledPulse

__all__ = [
    "MAX_PULSE_CYCLES",
    "MAX_SAMPLED_PULSE_SAMPLES",
    "SINC_MIN_BANDWIDTH",
    "WINDOW_NAMES",
    "GaborPulse",
    "Pulse",
    "RickerPulse",
    "SampledPulse",
    "SincPulse",
    "make_pulse",
    "parse_bandwidth",
    "plausible_bandwidth",
    "pulse_names",
    "pulse_options",
    "register_pulse",
]
