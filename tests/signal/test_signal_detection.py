"""EchoDetector: the matched-filter peak significance, N(0, 1)-like on noise, large on echoes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from echocal.errors import EchocalValueError
from echocal.signal import RecordingWindow, make_pulse
from echocal.signal.detection import EchoDetector
from echocal.signal.pulses import GaborPulse

PULSE = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
WINDOW = RecordingWindow(fs=100e6, start=0.0, n_samples=2048)


@pytest.fixture(scope="module")
def detector():
    return EchoDetector(PULSE, WINDOW.fs, WINDOW.n_samples)


def _echo(amplitude: float, at: float = 10e-6) -> np.ndarray:
    t = WINDOW.times
    return amplitude * np.asarray(PULSE.waveform(t - at))


def test_noise_only_significance_is_standard_normal_like(detector):
    # 4000 fresh noise A-scans (not the detector's calibration seed).  Rice's law of the
    # Rayleigh maximum is asymptotic: measured mean 0.03, sd 0.97-0.99.  Sampling errors
    # over 4000: mean 0.016, sd 0.011, P(g > 2) 0.0024 (nominal 0.0228).
    x = np.random.default_rng(1).standard_normal((4000, WINDOW.n_samples)) * 0.3
    g = detector.significance(x, 0.3)
    assert abs(np.mean(g)) < 0.1
    assert 0.9 < np.std(g) < 1.1
    assert 0.0228 - 0.008 < np.mean(g > 2.0) < 0.0228 + 0.008
    # the false-alarm rate at 3 "sigma": nominal 1.35e-3 (5.4 of 4000); at most 2x
    assert np.mean(g > 3.0) < 2.7e-3


def test_significance_is_scale_free_and_grows_with_the_echo(detector):
    rng = np.random.default_rng(2)
    noise = rng.standard_normal(WINDOW.n_samples)
    amplitudes = np.array([0.0, 0.5, 1.0, 2.0, 4.0])
    scans = amplitudes[:, None] * _echo(1.0)[None, :] + noise[None, :]
    g = detector.significance(scans, 1.0)
    assert np.all(np.diff(g[1:]) > 0)  # same noise, larger echo: more significant
    # σ and the samples scaled together: the same significance (a ratio; 1e-9 for round-off)
    np.testing.assert_allclose(detector.significance(7.5 * scans, 7.5), g, rtol=1e-9)
    # a clear echo: matched-filter SNR sqrt(E_pulse)/σ far above the noise maximum
    assert g[-1] > 8.0


def test_noiseless_and_extreme_values(detector):
    clean = _echo(1.0)
    assert detector.significance(clean, 0.0) == np.inf
    assert detector.significance(np.zeros(WINDOW.n_samples), 0.0) < -8.0
    g = detector.significance_of_peak(np.array([np.nan, np.inf, 0.0, -1.0]), 1.0)
    assert np.isnan(g[0]) and g[1] == np.inf and g[2] == g[3] < -6.0  # no echo: hopeless
    # far beyond double precision the asymptotic tail is used: finite, increasing
    peaks = detector.noise_gain * np.array([30.0, 40.0, 1e3])
    g = detector.significance_of_peak(peaks, 1.0)
    assert np.all(np.isfinite(g)) and np.all(np.diff(g) > 0)
    with pytest.raises(EchocalValueError, match="sigma"):
        detector.significance(clean, -1.0)
    with pytest.raises(EchocalValueError, match="n_samples"):
        detector.peak(np.zeros(WINDOW.n_samples + 1))


@pytest.mark.parametrize(
    ("fs", "n", "field"), [(-1.0, 2048, "fs"), (100e6, 0, "n_samples"), (100e6, 2.5, "n_samples")]
)
def test_bad_construction_names_the_field(fs, n, field):
    with pytest.raises(EchocalValueError, match=field):
        EchoDetector(PULSE, fs, n)


def test_simulate_and_the_objective_share_one_calibrated_detector(tmp_path, monkeypatch):
    """`echocal simulate` used to calibrate its own detector (1,024 noise A-scans) on every
    run; now every caller in a process shares one per (pulse, fs, length)."""
    from typer.testing import CliRunner

    from echocal.cli import app
    from echocal.signal import detection

    detection.shared_detector.cache_clear()
    built = []
    real = detection.EchoDetector.__post_init__
    monkeypatch.setattr(
        detection.EchoDetector, "__post_init__", lambda self: built.append(1) or real(self)
    )
    for k in range(2):
        result = CliRunner().invoke(
            app,
            ["simulate", "--setup", "thesis", "--pose", "0,0,20", "--out", str(tmp_path / f"r{k}")],
        )
        assert result.exit_code == 0, result.output
    assert len(built) == 1


@pytest.mark.parametrize("sigma", [0.01, 0.3])
def test_threshold_amplitude_is_the_echo_detected_at_that_significance(detector, sigma):
    # an independent round trip: a clean echo placed off-centre, scaled so its analytic
    # envelope peaks at the threshold amplitude, must score g = 4.5 (to 0.01) through
    # significance(); the level scales with sigma (to 1e-9 relative)
    level = detector.threshold_amplitude(sigma, 4.5)
    from scipy.signal import hilbert

    unit = _echo(1.0, at=7.3e-6)
    echo = unit * level / np.max(np.abs(hilbert(unit)))
    assert float(detector.significance(echo, sigma)) == pytest.approx(4.5, abs=0.01)
    assert detector.threshold_amplitude(2 * sigma, 4.5) == pytest.approx(2 * level, rel=1e-9)
    assert detector.threshold_amplitude(0.0, 4.5) == 0.0


@pytest.mark.parametrize("sigma", [0.01, 0.3])
def test_threshold_peak_inverts_the_significance_of_a_peak(detector, sigma):
    # the matched-envelope peak at the threshold scores the threshold (to 1e-6 σ), and
    # the level scales with sigma
    level = detector.threshold_peak(sigma, 4.5)
    assert float(detector.significance_of_peak(level, sigma)) == pytest.approx(4.5, abs=1e-6)
    assert detector.threshold_peak(2 * sigma, 4.5) == pytest.approx(2 * level, rel=1e-9)
    assert detector.threshold_peak(0.0, 4.5) == 0.0


def test_a_detectors_calibration_is_kept_on_disk(tmp_path, monkeypatch):
    """The second detector of the same pulse, rate and length — in a new process as in
    this one — reads its two numbers from the cache instead of filtering 1,024 noise
    A-scans; a damaged cache file is a miss, and is rewritten."""
    import echocal.signal.detection as detection
    from echocal.signal import detector_cache

    monkeypatch.setenv(detector_cache.CACHE_ENV, str(tmp_path))
    calls = []
    original = detection.matched_envelope

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(detection, "matched_envelope", counting)
    pulse = GaborPulse(center_frequency=5e6, bandwidth=60)
    first = detection.EchoDetector(pulse, 100e6, 512)
    assert len(calls) == 8  # 1,024 scans in chunks of 128
    (cached,) = tmp_path.glob("detector-*.json")
    calls.clear()
    second = detection.EchoDetector(pulse, 100e6, 512)
    assert calls == []
    assert (second.noise_gain, second.n_cells) == (first.noise_gain, first.n_cells)
    other = detection.EchoDetector(pulse, 100e6, 1024)  # another length: another key
    assert len(calls) == 8 and len(list(tmp_path.glob("detector-*.json"))) == 2
    calls.clear()
    cached.write_text("{not json", encoding="utf-8")
    third = detection.EchoDetector(pulse, 100e6, 512)
    assert len(calls) == 8 and third.noise_gain == first.noise_gain
    assert json.loads(cached.read_text(encoding="utf-8"))["n_cells"] == first.n_cells
    assert other.n_cells != first.n_cells
