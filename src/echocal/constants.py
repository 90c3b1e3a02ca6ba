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

MAP_POINTS = 64
"""The most noiseless A-scans a calibration's path plot simulates for its cost map by
default where no lobe profile describes the metric (a gated metric, a lobe with two humps;
``echocal calibrate --map-points N``; :mod:`echocal.plots.path_map`).  Where one does,
the map is the profile's, within its reach (9.4° for the 12.7 mm 5 MHz probe, where the
metric is more than 40 dB down, below the map's floor), and simulates nothing by default:
a far-start calibration on the wave model takes about 2 CPU-s once its profile is cached,
while 52 A-scans beyond that reach cost 5–6."""
MAP_SECONDS = 60.0
"""[s] a path plot's cost map stops simulating after this long (its budget in time)."""
