"""Materials in the wave model: reflection coefficients and attenuation against references."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.signal

from echocal import load_setup
from echocal.coefficients import reflection_fluid_solid
from echocal.materials import WATER, material
from echocal.signal.window import RecordingWindow
from echocal.wave import PistonProbe, WaveEchoModel

sys.path.insert(0, str(Path(__file__).parent))
import references as ref
from test_wave_model import PLANE, PULSE

D = 0.05
WINDOW = RecordingWindow(fs=100e6, start=2 * D / 1480.0 - 4e-6, n_samples=1024)


def _echo(**kwargs: object) -> np.ndarray:
    model = WaveEchoModel(
        probe=PistonProbe(radius=6.35e-3), pulse=PULSE, window=WINDOW, sound_speed=1480.0, **kwargs
    )
    frame = np.eye(3)[None]
    return model.ascans(PLANE, np.array([[0.0, 0.0, D]]), frame)[0]


def test_steel_plate_echo_is_the_impedance_reflection_coefficient_times_a_perfect_one() -> None:
    steel = material("steel")
    water = dataclasses.replace(WATER, longitudinal_speed=1480.0)
    want = ref.normal_incidence_reflection(
        water.density * water.longitudinal_speed, steel.density * steel.longitudinal_speed
    )
    perfect = _echo()
    on_steel = _echo(reflection=lambda theta: reflection_fluid_solid(theta, water, steel))
    ratio = (
        np.abs(scipy.signal.hilbert(on_steel)).max() / np.abs(scipy.signal.hilbert(perfect)).max()
    )
    # R(θ) of water–steel changes by < 1e-4 within the few degrees the beam spans
    assert ratio == pytest.approx(want, rel=1e-3)
    assert want == pytest.approx(0.938, abs=0.001)  # Z: 1.477 vs 46.3 MRayl


def test_attenuation_in_water_scales_the_spectrum_by_exp_minus_2_alpha_d() -> None:
    lossless = _echo()
    lossy = _echo(attenuation=WATER.attenuation.alpha)
    f = np.fft.rfftfreq(WINDOW.n_samples, 1.0 / WINDOW.fs)
    band = (f > 3e6) & (f < 7e6)
    ratio = np.abs(np.fft.rfft(lossy))[band] / np.abs(np.fft.rfft(lossless))[band]
    # independent: water's α(f) = 0.0253 Np/m·(f/1 MHz)² (Pinkerton), path 2d
    alpha = 0.0253 * (f[band] / 1e6) ** 2
    np.testing.assert_allclose(ratio, np.exp(-alpha * 2 * D), rtol=2e-3)


def test_attenuation_lowers_the_centre_frequency() -> None:
    def centre(x: np.ndarray) -> float:
        f = np.fft.rfftfreq(x.size, 1.0 / WINDOW.fs)
        p = np.abs(np.fft.rfft(x)) ** 2
        return float(np.sum(f * p) / np.sum(p))

    strong = dataclasses.replace(WATER.attenuation, alpha0=2.0)  # a lossy couplant
    assert centre(_echo(attenuation=strong.alpha)) < centre(_echo()) - 20e3


def test_a_steel_plate_setup_echoes_less_than_a_perfect_reflector(tmp_path: Path) -> None:
    base = load_setup("immersion-5mhz-wave")
    steel = dataclasses.replace(base, material=material("steel"))
    frame = np.eye(3)[None]
    pos = np.array([[0.0, 0.0, 0.05]])
    a = np.abs(scipy.signal.hilbert(base.ideal_samples(pos, frame)[0])).max()
    b = np.abs(scipy.signal.hilbert(steel.ideal_samples(pos, frame)[0])).max()
    assert b / a == pytest.approx(0.938, abs=0.003)
    assert math.isfinite(b)
