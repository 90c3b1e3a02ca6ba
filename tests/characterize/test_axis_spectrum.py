"""Beam axis, squint, centre frequency and bandwidth against independent truth: the squint
the setup's [bench] sets, and the pulse's own spectrum by numpy's FFT."""

from __future__ import annotations

import numpy as np
import pytest
from _probe_setups import BENCH, FLAT, SQUINT, write_setup

from echocal.characterize import AxisScan, measure_beam_axis, measure_spectrum
from echocal.errors import EchocalValueError
from echocal.geometry import Pose
from echocal.setups import setup_with_overrides


@pytest.mark.parametrize("snr", [None, 30.0])
def test_the_squint_set_on_the_bench_is_recovered(tmp_path, snr):
    virtual = setup_with_overrides(write_setup(tmp_path, FLAT + BENCH), snr_db=snr)
    axis = measure_beam_axis(virtual, [0.0, 0.0, 0.05])
    # the bound: 0.05 deg (the fine grid's step is 0.1 deg, the fit's vertex
    # lands within a few thousandths of the truth on this lobe)
    assert np.allclose(axis.squint_deg, SQUINT, atol=0.05)
    # the positioner reaches the beam at minus the squint to first order (0.5 deg tilts:
    # the second-order term is below 1e-3 deg)
    assert np.allclose(axis.tilts_deg, -np.array(SQUINT), atol=0.05)
    # an honest 1-sigma: the error is within 5 sigma plus the lobe's asymmetry floor
    err = np.abs(axis.squint_deg - SQUINT)
    assert np.all(err <= 5 * axis.squint_sigma_deg + 0.005)
    assert np.all(axis.squint_sigma_deg > 0)


def test_no_squint_on_an_ideal_bench(tmp_path):
    virtual = setup_with_overrides(write_setup(tmp_path, FLAT), snr_db=None)
    axis = measure_beam_axis(virtual, [0.0, 0.0, 0.05], AxisScan(coarse_points=7, fine_points=9))
    assert np.allclose(axis.squint_deg, 0.0, atol=0.01)


def _pulse_band(pulse, fs: float) -> tuple[float, float]:
    """f_c and the −6 dB bandwidth [Hz] of ``pulse`` by a zero-padded numpy FFT of its
    samples, written here without echocal's spectrum code."""
    t = np.arange(-2e-6, 2e-6, 1.0 / fs)
    amp = np.abs(np.fft.rfft(pulse.waveform(t), n=1 << 16))
    f = np.fft.rfftfreq(1 << 16, 1.0 / fs)
    amp /= amp.max()
    above = f[amp >= 0.5]
    lo, hi = above.min(), above.max()
    return 0.5 * (lo + hi), hi - lo


def test_centre_frequency_and_bandwidth_are_the_pulses(tmp_path):
    virtual = setup_with_overrides(write_setup(tmp_path, FLAT + BENCH), snr_db=30.0)
    axis = measure_beam_axis(virtual, [0.0, 0.0, 0.05], AxisScan(coarse_points=7, fine_points=9))
    spectrum = measure_spectrum(virtual, axis.pose, n_ascans=16)
    f_c, band = _pulse_band(virtual.pulse, 400e6)
    # 2 % (the bound): the echo at the axis is the pulse itself on the ray model;
    # 30 dB noise averaged over 16 A-scans moves f_c and the band by ~0.1 %
    assert spectrum.center_hz == pytest.approx(f_c, rel=0.02)
    assert spectrum.bandwidth_hz == pytest.approx(band, rel=0.02)
    assert 0 < spectrum.center_sigma_hz < 0.01 * f_c
    assert spectrum.lower_hz < spectrum.peak_hz < spectrum.upper_hz


def test_bad_arguments_name_the_field(tmp_path):
    virtual = setup_with_overrides(write_setup(tmp_path, FLAT), snr_db=None)
    with pytest.raises(EchocalValueError, match="span"):
        AxisScan(span_deg=-1)
    with pytest.raises(EchocalValueError, match="fine_points"):
        AxisScan(fine_points=3)
    with pytest.raises(EchocalValueError, match="position"):
        measure_beam_axis(virtual, [0, 0])
    with pytest.raises(EchocalValueError, match="gate_db"):
        measure_spectrum(virtual, Pose(0, 0, 0.05), gate_db=3)
