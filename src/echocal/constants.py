"""Physical defaults of echocal, in SI units."""

from __future__ import annotations

SOUND_SPEED_WATER = 1480.0
"""Speed of sound in water at about 20 °C [m/s] (thesis default c₀)."""

DEFAULT_CENTER_FREQUENCY = 5.0e6
"""Centre frequency of the default probe [Hz]."""

DEFAULT_SAMPLING_FREQUENCY = 100.0e6
"""Sampling frequency of the default receiver [Hz]."""

DEFAULT_SETTLE = (0.01, 8)
"""The settle stop every calibration uses unless told otherwise (``calibrate(settle=...)``,
``echocal calibrate --settle``): ``(tol [deg], patience)``, stop once the last 8
recommendations lie within 0.01° of their mean."""

MM = 1.0e-3
"""One millimetre [m], for readable literals: ``20 * MM``."""

US = 1.0e-6
"""One microsecond [s]."""

ECHO_THRESHOLD = 4.5
"""Detection significance g (Gaussian-equivalent σ, see
:class:`~echocal.signal.detection.EchoDetector`) above which an A-scan shows an echo: pure
noise exceeds it about 3·10⁻⁶ of the time (``echocal simulate``; the acquisition phase's
default ``threshold``)."""
