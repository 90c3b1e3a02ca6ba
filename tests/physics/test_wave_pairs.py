"""The pair rule of the image form (a flat disc over a tilted plane) against the exact
angular spectrum.

:mod:`echocal.wave.pairs` takes a flat disc's echo from a plane at large tilts: the double
surface integral over the face and its mirror image, with the faces' y-direction in closed
form.  The reference (tests/physics/references.py, which never imports echocal) is the
exact angular-spectrum solution of a piston over a tilted rigid plane.  Its plane crosses
the beam axis at the distance it is given; the model's probe here stands ``d`` above a
level plane and tilts, so its axis meets the plane at d/cos α.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from echocal.geometry import tilt_frame
from echocal.wave import PistonProbe, WaveEchoModel, pairs

sys.path.insert(0, str(Path(__file__).parent))
import references as ref
from image_setup import PLANE, C, envelope_peak, exact_lobe, image_model, transfer
from image_setup import tilted_plane as _plane

RADIUS = 6.35e-3


def _model(d: float, **kw: object) -> WaveEchoModel:
    return image_model(PistonProbe(radius=RADIUS), d, n_samples=2048, **kw)


@pytest.mark.parametrize(
    ("d_mm", "tilt", "tolerance"),
    [(50, 10.0, 5e-3), (50, 20.0, 5e-3), (50, 30.0, 1e-2), (20, 30.0, 1e-2)],
)
def test_pair_rule_equals_the_exact_angular_spectrum_at_large_tilts(
    d_mm: float, tilt: float, tolerance: float
) -> None:
    """|V(f)| at 4, 5 and 6 MHz of a 12.7 mm probe ``d`` above a plane, tilted 10–30°
    (the echo 10⁻³–10⁻⁴·⁵ of the normal one), against the exact angular spectrum at the
    axis distance d/cos α.  Tolerance 5·10⁻³ of the largest of the three local |V| at
    10–20° (measured ≤ 1.1·10⁻³; the face rule it replaces: 1.5·10⁻³ at 20°), 10⁻² at 30°
    (measured 4.2·10⁻³ and 4.3·10⁻³, at 6 MHz near a null of |V|: 2·10⁻⁷ of the normal
    |V|; the face rule: 2.8·10⁻³).  The model's tolerance on |V| elsewhere is 5·10⁻³ of
    the normal |V|."""
    d = d_mm * 1e-3
    model = _model(d)
    plane = _plane(model, d, tilt)
    assert model._pairs_pay(plane), "the pair rule takes this echo"
    f, got = transfer(model, plane, np.array([4e6, 5e6, 6e6]))
    along = d / math.cos(math.radians(tilt))
    want = np.abs([ref.pulse_echo_plane(RADIUS, fi, along, tilt, C) for fi in f])
    assert np.abs(got - want).max() < tolerance * want.max(), f"{got} vs exact {want}"


@pytest.mark.slow
@pytest.mark.parametrize("tilt", [10.0, 20.0])
def test_broadband_lobe_at_large_tilts_is_the_exact_one(tilt: float) -> None:
    """The echo's envelope peak relative to normal incidence (12.7 mm probe 50 mm above
    the plane) against the exact angular spectrum's over the pulse's band (91 and 146
    frequencies) at the axis distance d/cos α.  Tolerance 2·10⁻³ of the local value
    (measured 9·10⁻⁵ at 10°, 3.4·10⁻⁴ at 20°; against the reference at the axis distance d
    instead, whose plane lies nearer the probe, the lobe was 3.7 % and 7.5 % low)."""
    d = 0.05
    model = _model(d)
    pos = np.array([[0.0, 0.0, d]])
    level = model.ascans(PLANE, pos, tilt_frame(np.array([0.0]), np.array([0.0])))[0]
    tilted = model.ascans(PLANE, pos, tilt_frame(np.array([tilt]), np.array([0.0])))[0]
    got = envelope_peak(tilted) / envelope_peak(level)
    assert got == pytest.approx(exact_lobe(RADIUS, d, tilt), rel=2e-3)


def test_pair_rule_is_taken_where_it_is_cheaper_and_keeps_the_face_rule_elsewhere() -> None:
    """At 50 mm the pair rule takes the echo from 2° on (estimated cheaper), not at normal
    incidence (one face node per ring) nor for a 12.7 mm probe 10 mm above a plane tilted
    0.5° (4,656 pairs against 94 face nodes); a reflection coefficient that varies with the
    angle of each face node keeps the face rule, whose nodes carry it."""
    model = _model(0.05)
    assert not model._pairs_pay(_plane(model, 0.05, 0.0))
    for tilt in (2.0, 5.0, 20.0):
        assert model._pairs_pay(_plane(model, 0.05, tilt))
    near = _model(0.01)
    assert not near._pairs_pay(_plane(near, 0.01, 0.5))

    def reflection(theta: np.ndarray) -> np.ndarray:
        return np.asarray(0.9 - 1e-3 * theta, dtype=np.complex128)

    angled = _model(0.05, reflection=reflection)
    plane = _plane(angled, 0.05, 20.0)
    spectrum, _ = angled.image_spectrum(plane)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(pairs, "pays", lambda *args: False)
        face, _ = angled.image_spectrum(plane)
    np.testing.assert_array_equal(spectrum, face)


def test_pair_rule_carries_a_coefficient_and_a_delay() -> None:
    """An interior's echo (one complex coefficient, a delay added to every path): the pair
    rule's spectrum is the plane's times conj(coefficient)·e^{−iωτ} (numpy's sign), to
    round-off of the grid's peak."""
    d, tilt, delay = 0.05, 8.0, 3 * 2e-8  # a whole number of grid steps
    model = _model(d)
    plane = _plane(model, d, tilt)
    assert model._pairs_pay(plane)
    plain, t_plain = model.image_spectrum(plane)
    coefficient = 0.3 - 0.4j
    shifted, t_shifted = model.image_spectrum(plane, coefficient, delay)
    f = model.frequencies
    want = plain * np.conj(coefficient) * np.exp(-2j * math.pi * f * delay)
    assert np.abs(shifted - want).max() < 1e-9 * np.abs(want).max()
    assert t_shifted == pytest.approx(t_plain + delay, rel=1e-12)
