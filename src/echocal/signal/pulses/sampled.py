"""A pulse from measured samples, through a cubic B-spline (see
:mod:`echocal.signal.pulses`)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import linalg

from echocal._validate import finite_array, finite_float, positive_float
from echocal.errors import DataFileError, EchocalValueError
from echocal.signal.analytic import analytic_signal
from echocal.signal.pulses.base import _F64, MAX_SAMPLED_PULSE_SAMPLES, Pulse

# ---------------------------------------------------------------------------------------
_PAD = 16  # zero samples added on each side of a sampled pulse before spline fitting


def _bspline3(u: _F64) -> _F64:
    """Centred cubic B-spline β³(u)."""
    a = np.abs(u)
    return np.where(
        a < 1.0, 2.0 / 3.0 - a * a + 0.5 * a**3, np.where(a < 2.0, (2.0 - a) ** 3 / 6.0, 0.0)
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class SampledPulse(Pulse):
    """A user-supplied pulse sampled at ``fs`` (for example a measured reference echo).

    Between samples the waveform is the cubic B-spline interpolant (zero beyond the padded
    ends), and :meth:`spectrum` is that interpolant's exact Fourier transform
    W(f) = Δt·sinc⁴(fΔt)·Σₖ cₖ exp(−i2πf tₖ), so direct and fast synthesis agree.

    Attributes
    ----------
    samples : shape ``(n_samples,)`` waveform [a.u.]; should taper to zero at both ends.
    fs : [Hz] sampling frequency of ``samples``.
    start_time : [s] time of the first sample relative to the pulse origin (the instant a
        ray's τ refers to).  ``None``: the origin is the peak of the analytic envelope.
    """

    samples: NDArray[np.float64]
    fs: float
    start_time: float | None = None
    name: ClassVar[str] = "sampled"

    def __post_init__(self) -> None:
        w = finite_array("samples", self.samples)
        if w.ndim != 1 or w.size < 4:
            raise EchocalValueError(
                f"samples must be a 1-D array of at least 4 values; got shape {w.shape}"
            )
        if w.size > MAX_SAMPLED_PULSE_SAMPLES:
            raise EchocalValueError(
                f"samples: a sampled pulse holds at most {MAX_SAMPLED_PULSE_SAMPLES} samples; "
                f"got {w.size} — cut the recording to the pulse (its spectrum is computed "
                "numerically, at a cost growing as the square of the length)"
            )
        peak = float(np.max(np.abs(w)))
        if peak == 0.0:
            raise EchocalValueError("samples must not be all zero")
        w = w.copy()
        w.setflags(write=False)
        object.__setattr__(self, "samples", w)
        fs = positive_float("fs", self.fs)
        object.__setattr__(self, "fs", fs)
        if self.start_time is None:
            k = int(np.argmax(np.abs(analytic_signal(w))))
            object.__setattr__(self, "start_time", -k / fs)
        else:
            object.__setattr__(self, "start_time", finite_float("start_time", self.start_time))
        if max(abs(w[0]), abs(w[-1])) > 0.01 * peak:
            warnings.warn(
                "samples do not taper to zero at the ends (> 1 % of the peak); the pulse is "
                "cut off there",
                stacklevel=3,
            )

    @classmethod
    def from_file(
        cls, path: str | Path, *, fs: float | None = None, start_time: float | None = None
    ) -> SampledPulse:
        """Load a pulse from ``.npy`` or ``.csv``/``.txt``.

        One column (or a 1-D array): amplitudes, ``fs`` [Hz] required.  Two columns: time
        [s], amplitude; ``fs`` follows from the (uniform) time step and, unless given,
        ``start_time`` is the first time value.  CSV may have ``#`` comment lines anywhere
        and one header line before the numbers, as the A-scan CSV of ``echocal simulate``
        has (a ``#`` summary line, then ``time_s,amplitude``).
        """
        path = Path(path)
        if not path.is_file():
            raise DataFileError(f"pulse file {str(path)!r} does not exist")
        try:
            if path.suffix.lower() == ".npy":
                data = np.load(path, allow_pickle=False)
            else:
                rows = _csv_rows(path.read_text(encoding="utf-8"))
                with warnings.catch_warnings():  # an empty file: refused below, by name
                    warnings.simplefilter("ignore", UserWarning)
                    data = np.loadtxt(rows, delimiter=",", ndmin=2)
        except (ValueError, OSError, EOFError, UnicodeDecodeError) as exc:
            raise DataFileError(
                f"pulse file {str(path)!r} is not a numeric .npy or CSV file: {exc}"
            ) from None
        data = np.asarray(data)
        if data.size == 0:
            raise DataFileError(f"pulse file {str(path)!r} holds no samples")
        if not np.issubdtype(data.dtype, np.number):
            raise DataFileError(f"pulse file {str(path)!r} must hold numbers; got {data.dtype}")
        data = data.astype(np.float64)
        if data.ndim == 2 and data.shape[1] == 1:
            data = data[:, 0]
        if data.ndim == 1:
            if fs is None:
                raise EchocalValueError(
                    f"fs is required for {str(path)!r}: it holds amplitudes only (one column)"
                )
            return cls(samples=data, fs=fs, start_time=start_time)
        if data.ndim != 2 or data.shape[1] != 2:
            raise DataFileError(
                f"pulse file {str(path)!r} must have 1 column (amplitude) or 2 columns "
                f"(time [s], amplitude); got shape {data.shape}"
            )
        t, w = data[:, 0], data[:, 1]
        if t.size < 4 or not np.all(np.isfinite(t)):
            raise DataFileError(f"pulse file {str(path)!r}: time column must be finite, >= 4 rows")
        dt = np.diff(t)
        step = float(np.median(dt))
        if step <= 0 or np.max(np.abs(dt - step)) > 1e-3 * step:
            raise DataFileError(
                f"pulse file {str(path)!r}: time column must increase in uniform steps"
            )
        if fs is None:
            fs = 1.0 / step
        return cls(samples=w, fs=fs, start_time=float(t[0]) if start_time is None else start_time)

    @cached_property
    def _spline(self) -> tuple[_F64, float]:
        """(coefficients, time of coefficient 0 [s]) of the cardinal cubic B-spline."""
        v = np.concatenate([np.zeros(_PAD), self.samples, np.zeros(_PAD)])
        n = v.size
        ab = np.empty((3, n))
        ab[0], ab[1], ab[2] = 1.0, 4.0, 1.0
        c = linalg.solve_banded((1, 1), ab, 6.0 * v)
        start = self.start_time
        assert start is not None  # __post_init__ sets it
        return c, start - _PAD / self.fs

    def waveform(self, t: ArrayLike) -> _F64:
        t = np.asarray(t, dtype=np.float64)
        c, t0 = self._spline
        x = (t - t0) * self.fs
        k0 = np.floor(x).astype(np.int64)
        out = np.zeros(t.shape)
        for j in (-1, 0, 1, 2):
            k = k0 + j
            ok = (k >= 0) & (k < c.size)
            out += np.where(ok, c[np.clip(k, 0, c.size - 1)], 0.0) * _bspline3(x - k)
        return out

    def spectrum(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Exact transform of the spline interpolant (closed form, see the class docstring)."""
        f = np.asarray(f, dtype=np.float64)
        c, t0 = self._spline
        dt = 1.0 / self.fs
        tk = t0 + np.arange(c.size) * dt
        flat = f.ravel()
        out = np.empty(flat.shape, dtype=np.complex128)
        chunk = max(1, 2_000_000 // c.size)
        for i in range(0, flat.size, chunk):
            fi = flat[i : i + chunk]
            out[i : i + chunk] = (np.exp(-2j * np.pi * np.outer(fi, tk)) @ c) * (
                dt * np.sinc(fi * dt) ** 4
            )
        return out.reshape(f.shape)

    @property
    def support(self) -> float:
        c, t0 = self._spline
        first, last = t0 - 2.0 / self.fs, t0 + (c.size + 1) / self.fs
        return max(abs(first), abs(last))

    @property
    def _scan_limit(self) -> float:
        return self.fs / 2.0


def _csv_rows(text: str) -> list[str]:
    """The data rows of a CSV text: without ``#`` comment lines, blank lines and a first
    line that is not numbers (a header such as ``time_s,amplitude``)."""
    rows = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if rows:
        try:
            [float(v) for v in rows[0].split(",")]
        except ValueError:
            rows = rows[1:]
    return rows
