"""What the simulator's receiver and sampler accept: the receiver's noise, ADC and
saturation settings, and the largest A-scan a simulation may allocate."""

from __future__ import annotations

import functools
import math
import platform
from dataclasses import dataclass

import numpy as np

from echocal._validate import positive_float
from echocal.errors import EchocalValueError
from echocal.signal import Pulse, RecordingWindow
from echocal.units import format_frequency

__all__ = ["MAX_SIMULATED_SAMPLES", "ReceiverSettings", "check_sample_count"]

_MALLOC_WARMUP_BYTES = 16 << 20

MAX_SIMULATED_SAMPLES = 1 << 20
"""Most samples one simulated A-scan may need: the window plus the pulse's support on both
sides at ``fs`` (the synthesis pads by it).  A pulse of seconds sampled at MHz rates — 5 Hz
typed for 5 MHz — would otherwise allocate GiB; 2^20 samples are 10 ms at 100 MHz."""


@functools.cache
def _raise_malloc_threshold() -> None:
    """Let glibc's malloc keep the simulator's temporaries instead of returning them to the OS.

    glibc serves blocks above its mmap threshold (128 KiB at process start) with fresh
    ``mmap`` pages and unmaps them on ``free``, so every 0.1–1 MiB numpy temporary of a
    batch page-faults anew: measured, a batch of 10 poses then costs twice as much per
    pose as after warm-up.  glibc raises the threshold (and its trim threshold, to twice
    that) to the size of the largest mmapped block freed, up to 32 MiB; freeing one
    untouched 16 MiB block once per process does that.  Elsewhere it is harmless.
    """
    if platform.system() == "Linux" and platform.libc_ver()[0] == "glibc":
        block = np.empty(_MALLOC_WARMUP_BYTES // 8)  # pages are never touched
        del block


def check_sample_count(pulse: Pulse, window: RecordingWindow) -> int:
    """Samples one simulated A-scan needs: the window plus the pulse's support on both sides.

    Raises
    ------
    EchocalValueError
        when that exceeds :data:`MAX_SIMULATED_SAMPLES` (a pulse of seconds at MHz rates:
        usually a frequency typed without its unit), naming the pulse and ``window.fs``.
    """
    fs = window.fs
    needed = window.n_samples + 2 * math.ceil(min(pulse.support * fs, 1e300))
    if needed > MAX_SIMULATED_SAMPLES:
        fc = pulse.parameters().get("center_frequency")
        given = f"center_frequency = {format_frequency(fc)}; " if fc is not None else ""
        raise EchocalValueError(
            f"pulse: an A-scan would need {needed:.4g} samples (window.n_samples "
            f"{window.n_samples} + the {pulse.name} pulse's support ±{pulse.support:.3g} s on "
            f"both sides at window.fs = {format_frequency(fs)}); at most "
            f"{MAX_SIMULATED_SAMPLES} — check the pulse ({given}frequencies are in Hz) and "
            "window.fs"
        )
    return needed


@dataclass(frozen=True, kw_only=True)
class ReceiverSettings:
    """How the virtual receiver degrades the ideal A-scan.

    Attributes
    ----------
    snr_db : [dB] SNR of the reference echo (normal incidence at the reference
        position); ``None`` for a noiseless receiver.
    adc_bits : ADC resolution, or None for no quantization.
    full_scale : saturation level as a multiple of the reference echo's peak
        (e.g. 2.0 clips at twice the best echo), or None for no limit.
    """

    snr_db: float | None = 30.0
    adc_bits: int | None = None
    full_scale: float | None = None

    def __post_init__(self) -> None:
        if self.snr_db is not None:
            from echocal.signal.noise import check_snr_db

            object.__setattr__(self, "snr_db", check_snr_db("noise.snr_db", self.snr_db))
        if self.full_scale is not None:
            object.__setattr__(
                self, "full_scale", positive_float("noise.full_scale", self.full_scale)
            )
        if self.adc_bits is not None and self.full_scale is None:
            raise EchocalValueError("noise.adc_bits: needs noise.full_scale (the ADC range)")
