"""A tilted plate whose edge cuts the beam's footprint: the image form, not the Kirchhoff sum.

``immersion-5mhz``'s plate (100 mm square, its normal 4° off the vertical) seen from the
setup's reference position, 50 mm above its centre, with the probe tilted 30° from the
plate's normal along the plate's tilt: the rim of the beam's footprint passes the plate's
edge.  The Kirchhoff integral over the plate is the one over its infinite plane less the one
over the plane beyond the edges, nothing of which arrives before the paths 2(D − ρ) (D the
distance from the face centre to the nearest point beyond the edges, ρ the face's radius;
here 2·(68.2 − 6.35) mm, 83.6 µs), while the infinite plane's echo ends with the paths
2h + 2ρ (h = 49.9 mm, 76 µs): the plate's echo is the infinite plane's, exactly, and the
reference is the exact angular spectrum of a piston over an infinite tilted plane
(tests/physics/references.py, which never imports echocal).  The edges' own echo (measured
with the Kirchhoff sum over a strip beyond the edge: 2.6 % of the plate echo's peak at 25°,
18 % at 30°, 23 µs after it) is left out, as it is wherever the plate fills the footprint.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from echocal.geometry import orientation_frame
from echocal.signal.window import RecordingWindow
from echocal.specimen import FinitePlane
from echocal.wave import PistonProbe, WaveEchoModel, image

sys.path.insert(0, str(Path(__file__).parent))
from image_setup import PULSE, C, envelope_peak, exact_lobe

RADIUS = 6.35e-3
"""[m] the 12.7 mm probe's radius."""
AZIMUTH, COELEVATION = 30.0, 4.0
"""[deg] the plate's normal (``immersion-5mhz``'s plate)."""
PLATE = (
    FinitePlane(
        center=[0.0, 0.0, 0.0],
        width=0.1,
        height=0.1,
        azimuth=AZIMUTH,
        coelevation=COELEVATION,
    ),
)
POSITION = np.array([0.0, 0.0, 0.05])
"""[m] the face centre, 50 mm above the plate's centre."""


def _model(**kw: object) -> WaveEchoModel:
    """The probe in water, its window from 60 µs for 40.96 µs (``immersion-5mhz``'s): the
    plate's echo and the edges'."""
    window = RecordingWindow(fs=100e6, start=60e-6, n_samples=4096)
    return WaveEchoModel(
        probe=PistonProbe(radius=RADIUS), pulse=PULSE, window=window, sound_speed=C, **kw
    )  # type: ignore[arg-type]


def _frame(tilt: float) -> np.ndarray:
    """``(3, 3)`` the probe tilted ``tilt`` [deg] from the plate's normal along its tilt."""
    return orientation_frame(np.array([AZIMUTH]), np.array([COELEVATION + tilt]))[0]


def test_a_plate_whose_edge_cuts_the_footprints_rim_takes_the_image_form() -> None:
    """At 25° the plate fills the footprint; at 30° a rim ray passes its edge (the strict
    test rejects it, the A-scan's test with the edges' clearance takes it); at 45° the
    footprint's inner ring passes the edge too (the Kirchhoff sum); and a plate whose edge
    lies near the specular point (10 mm square) never takes the image form."""
    model = _model()
    assert model.image_plane(PLATE, POSITION, _frame(25.0)) is not None
    assert model.image_plane(PLATE, POSITION, _frame(30.0)) is None
    assert model.image_plane(PLATE, POSITION, _frame(30.0), edges=True) is not None
    assert model.image_plane(PLATE, POSITION, _frame(45.0), edges=True) is None
    small = (FinitePlane(center=[0.0, 0.0, 0.0], width=0.01, height=0.01),)
    level = orientation_frame(np.array([0.0]), np.array([0.0]))[0]
    assert image.edge_margin(small[0], POSITION) < model._edge_clearance
    assert model.image_plane(small, POSITION, level, edges=True) is None


def test_edge_margin_is_the_distance_beyond_the_edges_less_the_height() -> None:
    """D − h against a brute-force minimum over points just beyond the four edges (0.1 mm
    apart): the same to 10 µm; 0 once the foot of the perpendicular passes an edge."""
    plate = PLATE[0]
    h = float(plate.normal @ POSITION)
    s = np.linspace(-0.05, 0.05, 1001)
    edge = np.full_like(s, 0.05)
    u = np.concatenate([edge, -edge, s, s])  # along the width, then along the height
    v = np.concatenate([s, s, edge, -edge])
    rim = plate.center[:, None] + np.outer(plate.x_axis, u) + np.outer(plate.y_axis, v)
    brute = float(np.linalg.norm(rim - POSITION[:, None], axis=0).min()) - h
    assert image.edge_margin(plate, POSITION) == pytest.approx(brute, abs=1e-5)
    beyond = POSITION + 0.06 * plate.x_axis
    assert image.edge_margin(plate, beyond) == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("tilt", [30.0])
def test_plate_echo_past_its_edge_is_the_exact_infinite_plane_echo(tilt: float) -> None:
    """The envelope peak of the plate's echo (the A-scan up to 80 µs, before anything from
    beyond the edges arrives) relative to the plate's at normal incidence, against the exact
    angular spectrum's over the pulse's band at the plane's axis distance and incidence.
    Tolerance 10⁻² of the local value: the image form's at 30° (its |V| within 4.3·10⁻³ of
    the exact one, its broadband echo within 5.8·10⁻³ of a dense face rule's,
    docs/benchmarks/wave.md); measured −9.7·10⁻⁴.  The Kirchhoff sum over the footprint it
    replaces was 4.6× low there (its fan, 3° wide, holds none of the directions the 30°
    echo leaves in)."""
    model = _model()
    pos = POSITION[None]
    h = float(PLATE[0].normal @ POSITION)  # the plate passes through the origin
    tilted = model.ascans(PLATE, pos, _frame(tilt)[None])[0]
    level = model.ascans(PLATE, pos, _frame(0.0)[None])[0]
    gate = slice(0, round((80e-6 - model.window.start) * model.window.fs))
    got = envelope_peak(tilted[gate]) / envelope_peak(level[gate])
    assert got == pytest.approx(exact_lobe(RADIUS, h, tilt), rel=1e-2)
