"""A probe from its echo: synthetic Gabor echoes of known centre frequency and bandwidth,
with white or coloured Gaussian noise of known σ."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.signal

from cli_helpers import run_main
from echocal.positionscan import position_scan
from echocal.positionscan.probe import probe_from_echo
from echocal.signal import RecordingWindow, make_pulse, synthesize
from echocal.signal.pulses import SampledPulse

FS, T0, N = 100e6, 20e-6, 1024
SIGMA = 0.01


def _scan(noise: np.ndarray):
    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)  # -6 dB: 3.5 .. 6.5 MHz
    window = RecordingWindow(fs=FS, start=T0, n_samples=N)
    tau = 26e-6 + 1e-9 * np.arange(40).reshape(5, 8)
    clean = synthesize(np.ones((5, 8, 1)), tau[..., None], pulse, window)
    clean /= np.abs(clean).max()
    return position_scan(
        clean + noise, fs=FS, start_time=T0, x=np.arange(8) * 1e-3, y=np.arange(5) * 1e-3
    )


def test_white_noise_and_a_gabor_echo():
    rng = np.random.default_rng(5)
    est = probe_from_echo(_scan(SIGMA * rng.standard_normal((5, 8, N))))
    # the Gabor pulse's amplitude spectrum is a Gaussian centred on 5 MHz, half height at
    # 5 MHz x (1 +- 0.3): the averaged echo keeps it to a fraction of a percent
    assert est.center_frequency == pytest.approx(5e6, rel=0.01)
    assert est.bandwidth_percent == pytest.approx(60.0, abs=2.0)
    assert est.band[0] == pytest.approx(3.5e6, rel=0.02) and est.band[1] == pytest.approx(
        6.5e6, rel=0.02
    )
    # 40 traces x ~560 noise samples: the robust sigma within 3 %
    assert est.noise_sigma == pytest.approx(SIGMA, rel=0.03)
    assert est.white and est.spectral_flatness > 0.9


def test_coloured_noise_is_not_white(tmp_path):
    rng = np.random.default_rng(6)
    b, a = scipy.signal.butter(4, 0.2)  # low-pass at 10 MHz: strongly coloured
    noise = scipy.signal.lfilter(b, a, rng.standard_normal((5, 8, N)), axis=-1)
    est = probe_from_echo(_scan(SIGMA * noise / noise.std()))
    assert not est.white and est.whiteness_p_value < 1e-6 and est.spectral_flatness < 0.5


def test_pulse_file_round_trips_into_a_setup_pulse(tmp_path, capsys, monkeypatch):
    rng = np.random.default_rng(7)
    scan = _scan(SIGMA * rng.standard_normal((5, 8, N)))
    path = tmp_path / "scan.nc"
    scan.save(path)
    pulse_csv = tmp_path / "pulse.csv"
    code, stdout, err = run_main(
        ["probe", str(path), "--pulse", str(pulse_csv), "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    summary = json.loads(stdout)
    assert summary["center_frequency_hz"] == pytest.approx(5e6, rel=0.01)
    pulse = SampledPulse.from_file(pulse_csv)
    assert pulse.fs == pytest.approx(FS, rel=1e-6)
    # its time origin is its envelope peak: the Gabor's own origin
    env = np.abs(scipy.signal.hilbert(pulse.samples))
    assert abs(pulse.start_time + np.argmax(env) / FS) <= 1 / FS
