"""The Kirchhoff sum over a ball (echocal.wave.model) against an independent physical-optics
sum (references.pulse_echo_ball_kirchhoff: the disc's exact field on the ball from its rim
integral, no echocal code).

A 12.7 mm 5 MHz probe 50 mm above the top of a 25 mm ball, as in benchmarks/bench_wave.py,
tilted 0–20° from the vertical, and 10 mm above it.  Compared: the echo within
[−1.5, +2.5] µs of the top's specular time 2h/c (the echo's own window; the lit surface's
later parts, the limb, are outside it and outside the reference), max |difference|
relative to the reference's peak there.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from echocal.geometry import tilt_frame
from echocal.signal.pulses import GaborPulse
from echocal.signal.window import RecordingWindow
from echocal.specimen import Sphere
from echocal.wave import PistonProbe, WaveEchoModel

sys.path.insert(0, str(Path(__file__).parent))
import references as ref

C = 1480.0
A = 6.35e-3
RADIUS = 0.025


def _errors(tilt: float, height: float = 0.05) -> tuple[float, float]:
    """max |model − reference| from 1.5 µs before to 2.5 µs after 2·``height``/c [m], and
    max |model| from 6 µs after it to the window's end (the late window: the reference's
    ball, lit side up to 20 µs after it, is below 0.1 % there at 10°), both relative to
    the reference's peak in the echo's window, at ``tilt`` [deg]."""
    t_echo = 2.0 * height / C
    model = WaveEchoModel(
        probe=PistonProbe(radius=A),
        pulse=GaborPulse(center_frequency=5e6, bandwidth=60),
        window=RecordingWindow(fs=100e6, start=t_echo - 8e-6, n_samples=4096),
        sound_speed=C,
    )
    ball = (Sphere(center=(0.0, 0.0, -RADIUS), radius=RADIUS),)
    frame = tilt_frame(np.array([tilt]), np.array([0.0]))
    got = model.ascans(ball, np.array([[0.0, 0.0, height]]), frame)[0]
    window = model.window
    t = window.start + np.arange(window.n_samples) / window.fs
    gate = (t >= t_echo - 1.5e-6) & (t <= t_echo + 2.5e-6)
    # the reference's spectrum: 0.8–10.5 MHz (the pulse below 1e-3 of its peak outside),
    # every 50 kHz (a 20 µs period: the reference's echo lasts under 12 µs)
    df = 50e3
    f = np.arange(0.8e6, 10.5e6, df)
    v = ref.pulse_echo_ball_kirchhoff(A, f, height, RADIUS, tilt, t_echo + 3.5e-6, C)
    w = model.pulse.spectrum(f)
    phase = np.exp(2j * np.pi * np.outer(t[gate], f))
    want = 2.0 * df * np.real(phase @ (w * np.conj(v)))
    peak = float(np.abs(want).max())
    late = float(np.abs(got[t > t_echo + 6e-6]).max())
    return float(np.abs(got[gate] - want).max()) / peak, late / peak


@pytest.mark.parametrize(
    ("tilt", "tolerance"),
    [
        (0.0, 0.01),
        pytest.param(2.0, 0.01, marks=pytest.mark.slow),
        pytest.param(5.0, 0.01, marks=pytest.mark.slow),
        pytest.param(10.0, 0.04, marks=pytest.mark.slow),
        pytest.param(20.0, 0.12, marks=pytest.mark.slow),
    ],
)
def test_the_balls_echo_is_the_physical_optics_one(tilt: float, tolerance: float) -> None:
    """50 mm above the ball: within 1 % of the echo's peak at 0–5° (measured 0.15, 0.22,
    0.59 %; the reference agrees with itself at 1.5× its nodes to 2·10⁻⁴ at 0°, 5·10⁻⁴ at
    10°), 4 % at 10° (measured 3.0 %: 3.1 and 3.4 % at 1.0 and 0.7 of the Nyquist spacing,
    3.3 and 3.0 % with 1.5 and 2 Fresnel margins; the echo is 0.6 % of the normal one) and
    12 % at 20° (measured 9.8 % at every spacing, 7.5 and 6.9 % with 1.5 and 2 margins: the
    echo is 0.05 % of the normal one, 17 mm off the beam axis, lit by the side lobes).
    Before the sum covered the ball's cap (a fan about the beam axis): 0.27, 0.67, 0.53,
    4.6 and 383 %.  And nothing late: from 6 µs after the echo to the window's end
    (27 µs) below 1 % of its peak at 10° and 20° (measured 0.11 and 0.42 %; the fan about
    the axis gave 27 % at 10°, from the ball's flank it lit, sampled too coarsely for its
    grazing incidence)."""
    gated, late = _errors(tilt)
    assert gated < tolerance
    if tilt >= 10.0:
        assert late < 0.01


def test_the_balls_echo_near_the_probe_is_the_physical_optics_one() -> None:
    """10 mm above the ball at normal incidence, where the probe's rim is seen 32° off the
    axis: within 1 % (measured 0.68 %, 8,341 samples over the cap; 0.62 % with 5,681 over
    the fan about the axis; 11 % at 1.35 λ before the footprint rule)."""
    assert _errors(0.0, 0.01)[0] < 0.01
