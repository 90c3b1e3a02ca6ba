"""Pulses against closed forms and independent numerics."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import signal as sps

from echocal import DataFileError, EchocalValueError, UnknownNameError
from echocal.signal import (
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


def numeric_spectrum(pulse: Pulse, fs: float, f: np.ndarray) -> np.ndarray:
    """W(f) as the Riemann sum Σ w(t_k)·exp(−i2πf t_k)/fs over ±2·support (a DTFT of the
    waveform, independent of spectrum(); exact up to aliasing of content above fs/2)."""
    n = math.ceil(2 * pulse.support * fs)
    t = np.arange(-n, n + 1) / fs
    return np.exp(-2j * np.pi * np.outer(f, t)) @ pulse.waveform(t) / fs


@pytest.mark.parametrize("phase", [0.0, 37.0, 90.0])
@pytest.mark.parametrize(("fc", "bw"), [(1e6, 40.0), (5e6, 60.0), (15e6, 80.0)])
def test_gabor_spectrum_matches_fft_of_waveform(fc, bw, phase):
    p = GaborPulse(center_frequency=fc, bandwidth=bw, phase=phase)
    fs = 40 * fc
    f = np.linspace(0, 3 * fc, 301)
    ref = numeric_spectrum(p, fs, f)
    # FFT grid spacing fs/2^16 is fine compared with the Gaussian width; linear interpolation
    # of a smooth spectrum on that grid is accurate to ~1e-4 of the peak.
    peak = np.abs(p.spectrum(fc))
    assert np.max(np.abs(p.spectrum(f) - ref)) < 2e-4 * peak


def test_gabor_bandwidth_conversion_is_minus_6db():
    p = GaborPulse(center_frequency=5e6, bandwidth=60.0)
    edges = 5e6 * np.array([1 - 0.3, 1 + 0.3])
    ratio = np.abs(p.spectrum(edges)) / np.abs(p.spectrum(5e6))
    # negative-frequency lobe adds ~exp(-π²(2fc)²/α) ~ 1e-40 relative: exact to rounding
    np.testing.assert_allclose(ratio, 0.5, rtol=1e-9)
    q = GaborPulse.from_alpha(alpha=p.alpha, center_frequency=5e6)
    assert q.bandwidth == pytest.approx(60.0, rel=1e-12)
    assert make_pulse("gabor", alpha=p.alpha).alpha == pytest.approx(p.alpha, rel=1e-12)


def test_gabor_scalars_match_definitions():
    p = GaborPulse(center_frequency=5e6, bandwidth=60.0)
    env = lambda t: math.exp(-p.alpha * t * t)  # noqa: E731
    assert env(p.support) == pytest.approx(1e-7, rel=1e-9)
    assert env(p.duration / 2) == pytest.approx(0.1, rel=1e-9)
    mag = np.abs(p.spectrum(np.array([5e6, p.highest_frequency])))
    assert mag[1] / mag[0] == pytest.approx(1e-3, rel=1e-6)


def test_gabor_autocorrelation_closed_form_matches_generic_numeric():
    p = GaborPulse(center_frequency=5e6, bandwidth=60.0, phase=30.0)
    lags = np.linspace(-1e-6, 1e-6, 41)
    # generic path integrates |W|² numerically (trapezoid, spectrally accurate)
    np.testing.assert_allclose(
        Pulse.autocorrelation(p, lags), p.autocorrelation(lags), atol=1e-6 * p.energy
    )


@pytest.mark.parametrize("phase", [0.0, 45.0, 90.0])
def test_gabor_energy_closed_form_in_low_bandwidth_limit(phase):
    # large bandwidth makes the cos(2φ) term visible: fc=1 MHz, 150 %
    p = GaborPulse(center_frequency=1e6, bandwidth=150.0, phase=phase)
    a, fc = p.alpha, 1e6
    closed = (
        0.5
        * math.sqrt(math.pi / (2 * a))
        * (1 + math.exp(-2 * math.pi**2 * fc**2 / a) * math.cos(2 * math.radians(phase)))
    )
    fs = 200e6
    t = np.arange(-2 * p.support, 2 * p.support, 1 / fs)
    assert np.sum(p.waveform(t) ** 2) / fs == pytest.approx(closed, rel=1e-9)
    assert p.energy == pytest.approx(closed, rel=1e-12)


def test_ricker_spectrum_closed_form_and_peak():
    p = RickerPulse(center_frequency=4e6)
    f = np.linspace(0, 20e6, 201)
    ref = numeric_spectrum(p, 200e6, f)
    np.testing.assert_allclose(p.spectrum(f), ref, atol=2e-4 * abs(p.spectrum(4e6)))
    # |W| ∝ f² exp(−f²/fc²) peaks at fc
    assert Pulse.center_frequency.fget(p) == pytest.approx(4e6, rel=2e-3)
    # thesis eq. 32 literally
    t = np.linspace(-1e-6, 1e-6, 11)
    w = 2 * np.pi * 4e6
    np.testing.assert_allclose(
        p.waveform(t), (1 - 0.5 * w**2 * t**2) * np.exp(-0.25 * w**2 * t**2), rtol=1e-12
    )
    assert abs(p.waveform(p.support)) == pytest.approx(1e-7, rel=1e-6)


@pytest.mark.parametrize("window", ["boxcar", "hann", "kaiser"])
def test_sinc_spectrum_is_rect_in_band(window):
    p = SincPulse(center_frequency=5e6, bandwidth=1e6, window=window, lobes=40)
    inband = np.linspace(4.5e6, 5.5e6, 21)
    stop = np.concatenate([np.linspace(0, 3e6, 10), np.linspace(7e6, 10e6, 10)])
    level = 1 / (4 * 1e6)  # A' = 1/(2B) split over two lobes
    # 40 lobes: the truncation ripple (Gibbs for boxcar) stays within ~6 % of the level
    np.testing.assert_allclose(np.abs(p.spectrum(inband)), level, rtol=0.06)
    assert np.max(np.abs(p.spectrum(stop))) < 0.06 * level
    # quadrature spectrum agrees with the FFT of the waveform
    f = np.linspace(0, 10e6, 101)
    np.testing.assert_allclose(p.spectrum(f), numeric_spectrum(p, 100e6, f), atol=2e-3 * level)


@pytest.mark.parametrize("name", [w for w in WINDOW_NAMES if w != "kaiser"] + ["kaiser"])
def test_continuous_windows_match_scipy(name):
    n = 33
    z = 2 * np.arange(n) / (n - 1) - 1
    p = SincPulse(center_frequency=5e6, bandwidth=1e6, window=name)  # only its kaiser_beta
    from echocal.signal.pulses.analytic import _WINDOWS

    spec = ("kaiser", p.kaiser_beta) if name == "kaiser" else name
    np.testing.assert_allclose(
        _WINDOWS[name](z, p.kaiser_beta), sps.get_window(spec, n, fftbins=False), atol=1e-12
    )


def test_sampled_pulse_reproduces_gabor():
    g = GaborPulse()
    fs = 100e6
    t = np.arange(-120, 121) / fs
    s = SampledPulse(samples=g.waveform(t), fs=fs, start_time=t[0])
    tt = np.linspace(-0.5e-6, 0.5e-6, 997)
    # cubic spline at 10 samples per carrier period: interpolation error ~ (2π f/fs)^4/… ~ 1e-3
    np.testing.assert_allclose(s.waveform(tt), g.waveform(tt), atol=2e-3)
    f = np.linspace(0, 12e6, 121)
    np.testing.assert_allclose(s.spectrum(f), numeric_spectrum(s, 800e6, f), atol=1e-3 * 1.1e-7)
    # default origin = envelope peak
    assert SampledPulse(samples=g.waveform(t), fs=fs).start_time == pytest.approx(t[0])


def test_sampled_from_files(tmp_path):
    g = GaborPulse()
    fs = 100e6
    t = np.arange(-100, 101) / fs
    w = g.waveform(t)
    np.save(tmp_path / "p.npy", w)
    np.savetxt(tmp_path / "p2.csv", np.column_stack([t, w]), delimiter=",", header="t,w")
    a = SampledPulse.from_file(tmp_path / "p.npy", fs=fs)
    b = SampledPulse.from_file(tmp_path / "p2.csv")
    assert b.fs == pytest.approx(fs, rel=1e-9)
    assert b.start_time == pytest.approx(t[0])
    np.testing.assert_allclose(a.samples, b.samples)
    with pytest.raises(EchocalValueError, match="fs"):
        SampledPulse.from_file(tmp_path / "p.npy")
    (tmp_path / "bad.csv").write_text("a,b\nx,y\n")
    with pytest.raises(DataFileError, match="bad.csv"):
        SampledPulse.from_file(tmp_path / "bad.csv")
    (tmp_path / "three.csv").write_text("1,2,3\n4,5,6\n")
    with pytest.raises(DataFileError, match="columns"):
        SampledPulse.from_file(tmp_path / "three.csv")
    with pytest.raises(DataFileError, match="does not exist"):
        SampledPulse.from_file(tmp_path / "missing.npy", fs=fs)
    for name, text in (("empty.csv", ""), ("header.csv", "time,amplitude\n")):
        (tmp_path / name).write_text(text)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no numpy "input contained no data" warning leaks
            with pytest.raises(DataFileError, match=f"{name}' holds no samples"):
                SampledPulse.from_file(tmp_path / name, fs=fs)
    np.savetxt(tmp_path / "jitter.csv", np.column_stack([t**2, w]), delimiter=",")
    with pytest.raises(DataFileError, match="uniform"):
        SampledPulse.from_file(tmp_path / "jitter.csv")


def test_registry():
    assert {"gabor", "gaussian", "sinc", "ricker", "sampled"} <= set(pulse_names())
    with pytest.raises(UnknownNameError, match="gabor, gaussian, ricker, sampled, sinc"):
        make_pulse("triangle")
    with pytest.raises(EchocalValueError, match="already registered"):
        register_pulse("gabor", GaborPulse)
    with pytest.raises(EchocalValueError, match="bandwidth: unknown option for ricker; valid: "):
        make_pulse("ricker", bandwidth=3)
    with pytest.raises(EchocalValueError, match="not both"):
        make_pulse("gabor", alpha=1e13, bandwidth=50)


@pytest.mark.parametrize(
    ("name", "params", "field"),
    [
        ("gabor", {"center_frequency": 0.0}, "center_frequency"),
        ("gabor", {"center_frequency": -5e6}, "center_frequency"),
        ("gabor", {"bandwidth": 0.0}, "bandwidth"),
        ("gabor", {"bandwidth": float("nan")}, "bandwidth"),
        ("gabor", {"alpha": -1.0}, "alpha"),
        ("sinc", {"bandwidth": -1.0}, "bandwidth"),
        ("sinc", {"center_frequency": 0}, "center_frequency"),
        ("ricker", {"center_frequency": 0}, "center_frequency"),
        ("sampled", {"samples": [0, 0, 0, 0], "fs": 1e6}, "samples"),
        ("sampled", {"samples": [0, 1, 0, 0], "fs": 0}, "fs"),
    ],
)
def test_bad_parameters_name_the_field(name, params, field):
    with pytest.raises(EchocalValueError, match=field):
        make_pulse(name, **params)


def test_unknown_window_lists_names():
    with pytest.raises(UnknownNameError, match="hann"):
        SincPulse(window="welch-ish")


def test_make_pulse_inspects_a_factory_once(monkeypatch) -> None:
    import inspect

    import echocal.signal.pulses as pulses
    from echocal.signal.pulses import registry

    calls = []
    real = inspect.signature
    monkeypatch.setattr(inspect, "signature", lambda f: calls.append(f) or real(f))

    def tone(center_frequency: float = 5e6) -> pulses.Pulse:
        return pulses.make_pulse("gabor", center_frequency=center_frequency)

    pulses.register_pulse("tone-once", tone)
    try:
        for _ in range(3):
            pulses.make_pulse("tone-once", center_frequency=4e6)
    finally:
        registry._PULSES.pop("tone-once")
    assert calls.count(tone) == 1
