"""The common setup of the image-form tests (test_wave_image.py, test_wave_pairs.py): water,
a 5 MHz Gabor pulse, the built-in flat plate at z = 0, a wave model whose window holds the
plate's echo from a probe ``d`` above it, the tilted plane the model sees there, |V(f)|
and the envelope peak of an echo.
"""

from __future__ import annotations

import math

import numpy as np
import references as ref
import scipy.signal

from echocal.geometry import tilt_frame
from echocal.signal.pulses import GaborPulse
from echocal.signal.window import RecordingWindow
from echocal.specimen.builtins import builtin_specimen
from echocal.wave import PistonProbe, RectangularProbe, WaveEchoModel, image

C = 1480.0
"""[m/s] the water's sound speed."""
F0 = 5e6
"""[Hz] the pulse's centre frequency."""
PULSE = GaborPulse(center_frequency=F0, bandwidth=60)
SIGMA_T = 1.0 / math.sqrt(2.0 * PULSE.alpha)
"""[s] the pulse's Gaussian width."""
PLANE = tuple(builtin_specimen("flat-plate"))
"""The built-in flat plate's shapes (its front face at z = 0)."""


def image_model(
    probe: PistonProbe | RectangularProbe, d: float, n_samples: int = 1024, **kw: object
) -> WaveEchoModel:
    """The wave model of ``probe`` with :data:`PULSE` in water, its window (100 MHz,
    ``n_samples``) starting 4 µs before the echo from a plane ``d`` [m] below the probe;
    ``kw`` go to :class:`~echocal.wave.WaveEchoModel`."""
    window = RecordingWindow(fs=100e6, start=2 * d / C - 4e-6, n_samples=n_samples)
    return WaveEchoModel(probe=probe, pulse=PULSE, window=window, sound_speed=C, **kw)  # type: ignore[arg-type]


def tilted_plane(
    model: WaveEchoModel, d: float, tilt: float, tilt_y: float = 0.0
) -> image.ImagePlane:
    """The image plane ``model`` sees of :data:`PLANE` from (0, 0, ``d``) [m] with the
    probe tilted by ``tilt`` [deg] (the first gimbal angle; ``tilt_y`` the second)."""
    frame = tilt_frame(np.array([tilt]), np.array([tilt_y]))[0]
    plane = model.image_plane(PLANE, np.array([0.0, 0.0, d]), frame)
    assert plane is not None
    return plane


def transfer(
    model: WaveEchoModel, plane: image.ImagePlane, freqs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(the model's grid frequencies nearest ``freqs`` [Hz] (n,), |V(f)| there (n,)): the
    image form's echo spectrum divided by the pulse's (the grid's spectrum is a sum over
    samples Δ apart: × Δ)."""
    spectrum, _ = model.image_spectrum(plane)
    f = model.frequencies
    idx = np.array([int(np.argmin(np.abs(f - fi))) for fi in freqs])
    dt = model._grid[1]
    return f[idx], np.abs(spectrum[idx] * dt / model.pulse.spectrum(f[idx]))


def envelope_peak(x: np.ndarray) -> float:
    """The largest value of the analytic envelope of an A-scan ``x`` (n_samples,)."""
    return float(np.abs(scipy.signal.hilbert(x)).max())


def exact_lobe(radius: float, distance: float, tilt: float) -> float:
    """The exact broadband tilt lobe: the envelope peak of :data:`PULSE`'s echo from a rigid
    plane ``distance`` [m] from a flat piston of radius ``radius`` [m] tilted ``tilt`` [deg]
    (the plane ``distance``/cos(tilt) along the axis), relative to normal incidence, by the
    exact angular spectrum (``references.pulse_echo_plane``) over the pulse's band."""
    along = distance / math.cos(math.radians(tilt))
    freqs = ref._band(radius, distance, F0, SIGMA_T, C, tilt)
    spectrum = ref.gabor_spectrum(freqs, F0, SIGMA_T)
    v_tilt = np.array([ref.pulse_echo_plane(radius, f, along, tilt, C) for f in freqs])
    v_level = np.array([ref.pulse_echo_plane(radius, f, distance, 0.0, C) for f in freqs])
    return float(
        ref.pulse_echo_envelope_peak(v_tilt, freqs, spectrum)
        / ref.pulse_echo_envelope_peak(v_level, freqs, spectrum)
    )
