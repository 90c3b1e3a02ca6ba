"""A-scan signal layer (thesis §3, eqs. 25–37, and eq. 79).

From ray amplitudes a·β and times of flight τ [s] (``inf`` = miss), shape
``(..., n_rays)``, to A-scans ``(..., n_samples)`` and their metrics::

    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
    window = RecordingWindow(fs=100e6, start=20e-6, n_samples=4096)
    x = synthesize(amplitudes, tofs, pulse, window)          # thesis eq. 28
    receiver = Receiver.from_snr(x_reference, 30.0, window, pulse)
    y = receiver.receive(x, rng=seed)
    energy = pseudo_energy(y, window, pulse)                  # thesis eq. 79
"""

from __future__ import annotations

from echocal.signal.noise import Receiver, noise_sigma_for_snr, signal_power
from echocal.signal.processing import (
    METRICS,
    Gate,
    distance,
    energy_db,
    envelope,
    get_metric,
    matched_envelope,
    matched_filter,
    metric_names,
    peak_amplitude,
    pseudo_energy,
    register_metric,
    time_of_flight,
)
from echocal.signal.pulses import (
    WINDOW_NAMES,
    GaborPulse,
    Pulse,
    RickerPulse,
    SampledPulse,
    SincPulse,
    make_pulse,
    pulse_names,
    register_pulse,
)
from echocal.signal.synthesis import SYNTHESIS_METHODS, synthesize
from echocal.signal.window import RecordingWindow, check_echoes, check_window

__all__ = [
    "METRICS",
    "SYNTHESIS_METHODS",
    "WINDOW_NAMES",
    "GaborPulse",
    "Gate",
    "Pulse",
    "Receiver",
    "RecordingWindow",
    "RickerPulse",
    "SampledPulse",
    "SincPulse",
    "check_echoes",
    "check_window",
    "distance",
    "energy_db",
    "envelope",
    "get_metric",
    "make_pulse",
    "matched_envelope",
    "matched_filter",
    "metric_names",
    "noise_sigma_for_snr",
    "peak_amplitude",
    "pseudo_energy",
    "pulse_names",
    "register_metric",
    "register_pulse",
    "signal_power",
    "synthesize",
    "time_of_flight",
]
