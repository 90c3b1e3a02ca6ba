"""The posterior search under coloured noise: the echo's likelihood is the coloured
detector's, and the effective SNR is the in-band one."""

from __future__ import annotations

import numpy as np
from _bench_setups import bench_setup
from scipy.stats import rice

from echocal.constants import ECHO_THRESHOLD
from echocal.geometry import Pose
from echocal.measurement.detection_radius import cached_lobe_profile, white_equivalent_sigma
from echocal.signal.detection import shared_detector

AR = (0.6,)
COLOURED = "[bench.receiver]\nnoise_ar = [0.6]\n"


def _in_band_power_ratio(pulse, fs: float, a: float) -> float:
    """∫|P(f)|² S(f) df / ∫|P(f)|² df: the power AR(1) noise of unit variance (PSD
    S(f) = (1 − a²) / |1 − a e^{−2πif/fs}|²) puts through a filter matched to ``pulse``,
    against white noise of unit variance (S = 1), by numpy's FFT of the pulse's samples."""
    t = np.arange(-4e-6, 4e-6, 1.0 / fs)
    spectrum = np.abs(np.fft.rfft(pulse.waveform(t), n=1 << 14)) ** 2
    f = np.fft.rfftfreq(1 << 14, 1.0 / fs)
    psd = (1.0 - a * a) / np.abs(1.0 - a * np.exp(-2j * np.pi * f / fs)) ** 2
    return float(np.sum(spectrum * psd) / np.sum(spectrum))


def test_the_white_equivalent_sigma_is_the_colours_in_band_power(tmp_path):
    setup, _ = bench_setup(tmp_path, COLOURED, noise="snr_db = 20")
    ratio = _in_band_power_ratio(setup.pulse, setup.window.fs, AR[0])
    got = white_equivalent_sigma(setup, 2.0, AR) / 2.0
    # the detectors' noise gains are measured on 1,024 noise A-scans of 256 samples each
    # (the power to about 1 %, each gain to 0.5 %): the power ratio within 3 %
    np.testing.assert_allclose(got**2, ratio, rtol=0.03)
    assert ratio > 1.5  # 5 MHz at 50 MHz: S(f₀) = 0.64 / |1 − 0.6 e^{−iπ/5}|² = 1.65
    assert white_equivalent_sigma(setup, 2.0, ()) == 2.0


def _half_chance_rate(setup, noise_ar, model_ar) -> tuple[float, float]:
    """The misalignment [deg] where the likelihood of colour ``model_ar`` predicts a
    detection (g > 4.5) one time in two, and the share of 400 A-scans there (100 in each
    of the profile's 4 directions) that the detector calibrated on ``noise_ar`` sees."""
    pos = np.asarray(setup.reference_position, float)
    profile = cached_lobe_profile(setup, pos)
    model = profile.echo_likelihood(setup.noise_sigma, noise_ar=model_ar)
    assert model is not None
    k = int(np.argmin(np.abs(rice.sf(model.threshold, model.echo) - 0.5)))
    theta = float(model.angles[k])
    phi = np.repeat(np.linspace(0.0, 2.0 * np.pi, 4, endpoint=False), 100)
    tilts = profile.centre + theta * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    scans = setup.measure_many([Pose.from_tilt(*pos, *t) for t in tilts])
    window = setup.window
    detector = shared_detector(setup.pulse, window.fs, window.n_samples, noise_ar)
    g = detector.significance(np.array([s.samples for s in scans]), setup.noise_sigma)
    return theta, float(np.mean(g > ECHO_THRESHOLD))


def test_the_coloured_likelihood_is_as_right_under_coloured_noise_as_white_under_white(
    tmp_path,
):
    white_setup, _ = bench_setup(tmp_path, noise="snr_db = 14")
    coloured_setup, _ = bench_setup(tmp_path, COLOURED, noise="snr_db = 14")
    # the one-cell model errs the same way on either noise (on this tiny probe's lobe it
    # under-predicts: the echo's neighbouring cells add their own chances), so the check
    # is that the colour changes nothing about it.  400 A-scans per rate: ±2 % (1 σ at
    # 0.8); the two rates within 0.1
    theta_w, white = _half_chance_rate(white_setup, (), ())
    theta_c, coloured = _half_chance_rate(coloured_setup, AR, AR)
    assert theta_c < theta_w  # the colour costs reach: the echo is weaker in the band
    assert abs(coloured - white) < 0.1
    # the white model on the coloured bench: where it expects what white noise gives,
    # coloured noise detects far less often (the evidence it would over-weigh)
    _, misjudged = _half_chance_rate(coloured_setup, AR, ())
    assert misjudged < white - 0.25
