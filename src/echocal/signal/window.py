"""The recording window of a receiver: sampling frequency, start delay, number of samples."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float, positive_float, positive_int
from echocal.errors import EchocalValueError
from echocal.signal.pulses import Pulse

__all__ = ["RecordingWindow", "check_echoes", "check_window"]


@dataclass(frozen=True, kw_only=True)
class RecordingWindow:
    """What the digitizer records, like an instrument's time base.

    Attributes
    ----------
    fs : [Hz] sampling frequency.
    start : [s] time of the first sample after the transmit pulse (recording delay).
    n_samples : number of samples (>= 2).
    """

    fs: float
    start: float = 0.0
    n_samples: int = 4096

    def __post_init__(self) -> None:
        object.__setattr__(self, "fs", positive_float("fs", self.fs))
        object.__setattr__(self, "start", finite_float("start", self.start))
        n = positive_int("n_samples", self.n_samples)
        if n < 2:
            raise EchocalValueError(f"n_samples must be >= 2; got {n}")
        object.__setattr__(self, "n_samples", n)

    @classmethod
    def spanning(
        cls, t_first: float, t_last: float, *, fs: float, pulse: Pulse | None = None
    ) -> RecordingWindow:
        """A window covering echoes arriving in [t_first, t_last] [s], widened by the pulse
        support on both sides when ``pulse`` is given."""
        t_first = finite_float("t_first", t_first)
        t_last = finite_float("t_last", t_last)
        if t_last < t_first:
            raise EchocalValueError(f"t_last must be >= t_first; got {t_last:g} < {t_first:g}")
        fs = positive_float("fs", fs)
        margin = pulse.support if pulse is not None else 0.0
        start = t_first - margin
        n = math.ceil((t_last + margin - start) * fs) + 1
        return cls(fs=fs, start=start, n_samples=max(n, 2))

    @property
    def dt(self) -> float:
        """[s] sampling interval 1/fs."""
        return 1.0 / self.fs

    @property
    def end(self) -> float:
        """[s] time of the last sample."""
        return self.start + (self.n_samples - 1) / self.fs

    @property
    def duration(self) -> float:
        """[s] length n_samples / fs."""
        return self.n_samples / self.fs

    @property
    def times(self) -> NDArray[np.float64]:
        """[s] time of each sample, shape ``(n_samples,)``."""
        return self.start + np.arange(self.n_samples) / self.fs

    def sample_position(self, t: ArrayLike) -> NDArray[np.float64]:
        """Fractional sample index (t − start)·fs of times ``t`` [s]."""
        return (np.asarray(t, dtype=np.float64) - self.start) * self.fs


def check_window(window: RecordingWindow, pulse: Pulse) -> None:
    """Refuse a window that would alias the pulse; warn when it is shorter than the pulse.

    Raises
    ------
    EchocalValueError
        naming ``fs`` when fs < 2 · pulse.highest_frequency (−60 dB point of |W|).
    """
    f_hi = pulse.highest_frequency
    if window.fs < 2.0 * f_hi:
        raise EchocalValueError(
            f"fs = {window.fs:.6g} Hz aliases the {pulse.name} pulse: it must be at least "
            f"2 × its highest frequency ({f_hi:.6g} Hz, −60 dB) = {2 * f_hi:.6g} Hz"
        )
    if window.duration < pulse.duration:
        warnings.warn(
            f"the recording window ({window.duration:.3g} s) is shorter than the pulse "
            f"({pulse.duration:.3g} s at −20 dB)",
            stacklevel=2,
        )


def check_echoes(window: RecordingWindow, pulse: Pulse, tofs: ArrayLike) -> None:
    """Refuse a window that cannot contain any echo of the rays that hit something.

    Raises
    ------
    EchocalValueError
        naming ``window`` when finite times of flight ``tofs`` [s] exist but none of them
        lies within [start − support, end + support].
    """
    tofs = np.asarray(tofs, dtype=np.float64)
    hit = tofs[np.isfinite(tofs)]
    if hit.size == 0:
        return
    s = pulse.support
    inside = (hit > window.start - s) & (hit < window.end + s)
    if not np.any(inside):
        raise EchocalValueError(
            f"window [{window.start:.6g} s, {window.end:.6g} s] cannot contain any echo: the "
            f"times of flight lie in [{hit.min():.6g} s, {hit.max():.6g} s]; move start or "
            "increase n_samples"
        )
