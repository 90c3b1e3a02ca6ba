"""The image form over a tilted plane on hold-out geometries, against the exact angular
spectrum.

tests/physics/test_wave_pairs.py checks the pair rule (:mod:`echocal.wave.pairs`) on the
geometries it was tuned on (a 12.7 mm probe at 5 MHz, 20 and 50 mm, 10–30°).  Here the
geometries are drawn from a fixed seed over the ranges the model serves: probe radius
3–12.7 mm, centre frequency 1–10 MHz (Gabor pulse, 60 % bandwidth), water path 15–120 mm,
tilt 0–30° about a random azimuth, over a plate wide enough (1 m) that the beam's whole
footprint lies on it (the built-in 100 mm plate does not fill it at the longer water paths
and larger tilts, and the model then takes the Kirchhoff sum instead of the image form).

The reference (tests/physics/references.py, which never imports echocal) is the exact
angular-spectrum solution of a piston over a tilted rigid plane crossing the beam axis at
d/cos α (the probe stands d above the plate).  It gives V(f) in the e^{−iωt} convention
with the round trip's phase; the model's spectrum is on a grid starting at t₀ in numpy's
convention, so the model's V(f) is conj(X(f)·e^{−2πif t₀})·Δ_g/W(f).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest

from echocal.constants import MM
from echocal.geometry import tilt_frame
from echocal.signal.pulses import GaborPulse
from echocal.signal.window import RecordingWindow
from echocal.specimen.plane import FinitePlane
from echocal.wave import PistonProbe, WaveEchoModel, pairs

sys.path.insert(0, str(Path(__file__).parent))
import references as ref

C = 1480.0
SEED = 20261207
N_CASES = 10
PLATE = (FinitePlane(center=(0.0, 0.0, 0.0), width=1000 * MM, height=1000 * MM),)
BAND = (0.8, 1.0, 1.2)
"""The frequencies compared, in units of the centre frequency (the pulse's −6 dB band is
about 0.7–1.3 of it)."""


class Case(NamedTuple):
    radius: float  # [m]
    frequency: float  # [Hz] centre frequency
    distance: float  # [m] from the face centre to the plate, along its normal
    tilt: float  # [deg]
    azimuth: float  # [deg]

    def __str__(self) -> str:
        return (
            f"a={self.radius / MM:.2f}mm-f0={self.frequency / 1e6:.2f}MHz-"
            f"d={self.distance / MM:.1f}mm-tilt={self.tilt:.2f}-az={self.azimuth:.0f}"
        )


def _draw(seed: int, n: int) -> list[Case]:
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n):
        cases.append(
            Case(
                radius=float(rng.uniform(3.0, 12.7)) * MM,
                frequency=float(rng.uniform(1e6, 10e6)),
                distance=float(rng.uniform(15.0, 120.0)) * MM,
                tilt=float(rng.uniform(0.0, 30.0)),
                azimuth=float(rng.uniform(0.0, 360.0)),
            )
        )
    return cases


CASES = _draw(SEED, N_CASES)


def _frame(tilt: float, azimuth: float) -> np.ndarray:
    """The gimbal frame whose axis n leans ``tilt`` [deg] from +z towards ``azimuth`` [deg]:
    n = (sin α cos φ, sin α sin φ, cos α) = R_y(b)·R_x(a)·ẑ."""
    s, phi = math.sin(math.radians(tilt)), math.radians(azimuth)
    tilt_x = -math.degrees(math.asin(s * math.sin(phi)))
    tilt_y = math.degrees(math.atan2(s * math.cos(phi), math.cos(math.radians(tilt))))
    return tilt_frame(np.array([tilt_x]), np.array([tilt_y]))[0]


def _tolerance(tilt: float) -> float:
    """test_wave_pairs.py's: 5·10⁻³ of the largest local |V| up to 20°, 10⁻² beyond (at 30°
    the echo is 10⁻⁴·⁵ of the normal one and one frequency may sit near a null of |V|)."""
    return 5e-3 if tilt <= 20.0 else 1e-2


def test_the_draw_spans_the_ranges() -> None:
    """The drawn cases cover the ranges: radii, frequencies and water paths in both halves
    of their ranges, tilts from below 10° to beyond 20°."""
    radii = [case.radius for case in CASES]
    assert min(radii) < 7.85 * MM < max(radii)
    frequencies = [case.frequency for case in CASES]
    assert min(frequencies) < 5.5e6 < max(frequencies)
    distances = [case.distance for case in CASES]
    assert min(distances) < 67.5 * MM < max(distances)
    tilts = [case.tilt for case in CASES]
    assert min(tilts) < 10.0 and max(tilts) > 20.0


def _compare(case: Case, force_pairs: bool) -> tuple[float, float, float, bool]:
    """(complex error, |V| error, both over the largest |V_exact| of the three frequencies;
    that |V_exact|; whether the cost model takes the pair rule) of the image form's V(f)
    for ``case``; ``force_pairs``: the pair rule even where the cost model keeps the face
    rule."""
    pulse = GaborPulse(center_frequency=case.frequency, bandwidth=60)
    d = case.distance
    window = RecordingWindow(fs=100e6, start=2 * d / C - 4e-6, n_samples=4096)
    model = WaveEchoModel(
        probe=PistonProbe(radius=case.radius), pulse=pulse, window=window, sound_speed=C
    )
    plane = model.image_plane(PLATE, np.array([0.0, 0.0, d]), _frame(case.tilt, case.azimuth))
    assert plane is not None, "the plate fills the footprint: the image form applies"
    assert plane.sin_incidence == pytest.approx(math.sin(math.radians(case.tilt)), abs=1e-9)
    chosen = model._pairs_pay(plane)
    f = model.frequencies
    idx = np.array([int(np.argmin(np.abs(f - x * case.frequency))) for x in BAND])
    with pytest.MonkeyPatch.context() as patch:
        if force_pairs:
            patch.setattr(pairs, "pays", lambda *args: True)
        spectrum, _ = model.image_spectrum(plane)
    shifted = spectrum[idx] * np.exp(-2j * math.pi * f[idx] * model._t0)
    got = np.conj(shifted * model._grid[1] / pulse.spectrum(f[idx]))
    along = d / math.cos(math.radians(case.tilt))
    want = np.array([ref.pulse_echo_plane(case.radius, fi, along, case.tilt, C) for fi in f[idx]])
    scale = float(np.abs(want).max())
    error = float(np.abs(got - want).max()) / scale
    modulus = float(np.abs(np.abs(got) - np.abs(want)).max()) / scale
    return error, modulus, scale, chosen


@pytest.mark.parametrize("case", CASES, ids=str)
def test_pair_rule_equals_the_exact_angular_spectrum_on_holdout_geometries(case: Case) -> None:
    """Complex V(f) (modulus and phase) at 0.8, 1.0 and 1.2 f0 by the pair rule against the
    exact angular spectrum: |V_pairs − V_exact| below :func:`_tolerance` × the largest of
    the three |V_exact| (this bounds the error of |V| too).  The cost model takes the pair
    rule for every drawn case but the one at 0.21° (measured: errors 5.6·10⁻⁶ to 3.1·10⁻³,
    the largest at 28°, against 10⁻²; 8.3·10⁻⁴ at 19.9° against 5·10⁻³); there the pair
    rule is forced (error 5.6·10⁻⁶)."""
    error, modulus, scale, chosen = _compare(case, force_pairs=True)
    assert chosen is (case.tilt >= 1.0), "the pair rule takes every drawn echo but at 0.21°"
    assert error < _tolerance(case.tilt), (
        f"{case}: complex error {error:.3g}, |V| error {modulus:.3g} of max |V| {scale:.3g} "
        f"(tolerance {_tolerance(case.tilt)})"
    )


NEAR_NORMAL = next(case for case in CASES if case.tilt < 1.0)


@pytest.mark.parametrize("tilt", [0.0, NEAR_NORMAL.tilt])
def test_image_form_equals_the_exact_angular_spectrum_near_normal_incidence(tilt: float) -> None:
    """The drawn case at 0.21°, and the same probe level, with the rule the cost model
    picks (the face rule), against the exact angular spectrum within 5·10⁻³ of the largest
    local |V|.  With one ring per Fresnel zone (12 rings for its 11.2 zones) it was
    3.7·10⁻² off at 0° and 5.1·10⁻² at 0.21°: the face rule now takes two per zone
    (:data:`echocal.wave.image.FLAT_RINGS_PER_ZONE`)."""
    case = NEAR_NORMAL._replace(tilt=tilt)
    error, modulus, scale, chosen = _compare(case, force_pairs=False)
    assert not chosen
    assert error < _tolerance(case.tilt), (
        f"{case}: complex error {error:.3g}, |V| error {modulus:.3g} of max |V| {scale:.3g} "
        f"(tolerance {_tolerance(case.tilt)})"
    )
