"""Beam widths and the focal distance over a point target against closed forms written
here: the far-field piston's pulse-echo profile and the setup's acoustic focus."""

from __future__ import annotations

import numpy as np
import pytest
from _probe_setups import PORE_TOP, pore_setup, write_setup
from scipy.optimize import brentq
from scipy.special import j1

from echocal.characterize.profile import half_max_width, measure_beam_profile, measure_focus
from echocal.errors import EchocalValueError
from echocal.setups import setup_with_overrides


def _far_field_width(radius: float, distance: float, frequency: float, c: float) -> float:
    """−6 dB width [m] across the axis at ``distance`` of a flat piston's pulse-echo
    profile over a point: [2J₁(ka sinθ)/(ka sinθ)]² (d/r)², θ = atan(x/d), r = √(d² + x²)
    (the far-field directivity, transmit and receive, and the spherical spreading)."""
    ka = 2 * np.pi * frequency / c * radius

    def level(x: float) -> float:
        r = np.hypot(distance, x)
        u = ka * x / r
        return (2 * j1(u) / u) ** 2 * (distance / r) ** 2 - 0.5

    return 2 * brentq(level, 1e-6, 0.5 * distance)


def test_beam_width_is_the_far_field_pistons(tmp_path):
    virtual = setup_with_overrides(write_setup(tmp_path, pore_setup()), snr_db=None)
    distances = [0.055, 0.07]  # 16 and 21 near-field lengths a²/λ = 3.4 mm: far field
    profile = measure_beam_profile(
        virtual, PORE_TOP, distances, half_span=0.009, points=37, axes=("x", "y")
    )
    for d, widths in zip(distances, profile.width, strict=True):
        # 2 % (the bound): a 10 % band moves the width by ~0.1 %, the distance
        # from the far field by < 0.5 %, linear interpolation on 0.5 mm steps by < 0.1 %
        expected = _far_field_width(1e-3, d, 5e6, 1480.0)
        assert widths == pytest.approx([expected, expected], rel=0.02)
    assert np.all(np.abs(profile.centre) < 1e-4)  # the beam's axis crosses the pore
    assert profile.on_axis[0] > profile.on_axis[1]  # beyond the focus, the echo falls


def test_focal_distance_is_the_probes_acoustic_focus(tmp_path):
    text = pore_setup(width="12.7 mm", focus="50 mm", start="40 us")
    virtual = setup_with_overrides(write_setup(tmp_path, text), snr_db=None)
    scan = measure_focus(virtual, PORE_TOP, np.arange(0.04, 0.0601, 0.0025))
    # the setup's focus is the on-axis maximum of the one-way pressure at 5 MHz; the
    # pulse-echo from a point is that pressure squared, so its maximum is the same: the
    # issue's bound, 1 mm
    assert scan.focal_distance == pytest.approx(0.05, abs=1e-3)
    assert scan.focal_sigma < 1e-3


def test_half_max_width_of_a_triangle():
    x = np.linspace(-1.75, 2.25, 9)
    width, centre, _ = half_max_width(x, np.maximum(1 - np.abs(x - 0.25), 0))
    assert (width, centre) == pytest.approx((1.0, 0.25))
    assert np.isnan(half_max_width(x, np.ones(9))[0])


def test_bad_arguments_name_the_field(tmp_path):
    virtual = setup_with_overrides(write_setup(tmp_path, pore_setup()), snr_db=None)
    with pytest.raises(EchocalValueError, match="distances"):
        measure_beam_profile(virtual, PORE_TOP, [-0.01])
    with pytest.raises(EchocalValueError, match="axes"):
        measure_beam_profile(virtual, PORE_TOP, [0.05], axes=("z",))
    with pytest.raises(EchocalValueError, match="distances"):
        measure_focus(virtual, PORE_TOP, [0.05, 0.06])
