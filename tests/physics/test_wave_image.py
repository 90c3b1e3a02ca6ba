"""The image form of the wave model over planes, against independent references.

Over a plane that fills the beam, :class:`echocal.wave.WaveEchoModel` integrates the probe's
own spatial impulse response over its mirror image (:mod:`echocal.wave.image`) instead of
the Kirchhoff sum over the lit surface.  References (tests/physics/references.py, which
never imports echocal): the brute-force double Rayleigh integral of a flat piston and of a
spherically focused bowl over a tilted mirror, and the exact angular spectrum's broadband
tilt lobe.  Tolerances are stated with each test.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from echocal.geometry import tilt_frame
from echocal.signal.pulses import GaborPulse
from echocal.signal.window import RecordingWindow
from echocal.specimen import FinitePlane, Sphere
from echocal.wave import PistonProbe, RectangularProbe, WaveEchoModel, image, sir
from echocal.wave import model as model_module
from echocal.wave.model import _IMAGE_NYQUIST_FRACTION

sys.path.insert(0, str(Path(__file__).parent))
import references as ref
from image_setup import F0, PLANE, SIGMA_T, C, envelope_peak, tilted_plane, transfer
from image_setup import image_model as _model_of


def _model(radius: float, d: float, curvature: float | None = None, **kw: object) -> WaveEchoModel:
    return _model_of(PistonProbe(radius=radius, curvature=curvature), d, **kw)


def _transfer(
    model: WaveEchoModel, d: float, tilt: float, freqs: np.ndarray, tilt_y: float = 0.0
) -> np.ndarray:
    """|V(f)| of the model at the grid frequencies nearest ``freqs`` [Hz], at a plane
    tilted by ``tilt`` [deg] (``tilt_y`` the second gimbal angle)."""
    return transfer(model, tilted_plane(model, d, tilt, tilt_y), freqs)[1]


@pytest.mark.parametrize(
    ("radius_mm", "curvature_mm", "d_mm"),
    [(6.35, None, 50), (6.35, 60, 50), (6.35, 60, 30), (5.0, 30, 12), (3.0, 25, 20)],
)
def test_single_frequency_echo_equals_the_double_rayleigh_integral(
    radius_mm: float, curvature_mm: float | None, d_mm: float
) -> None:
    """|V(f)| at 4, 5 and 6 MHz and tilts 0, 0.5 and 1.5°, flat and focused probes (the
    bowls at and inside their focus, where the Kirchhoff sum was up to 10× off).

    Tolerance 0.5 % of the largest normal-incidence |V| of the three: the reference is
    converged to 1e-8 (its node counts × 1.5 change nothing); the model's time grid (five
    points per period of the pulse's highest frequency, its B-spline projection undone in
    the frequency domain) and its radial nodes leave 0.02–0.3 % (measured)."""
    a, d = radius_mm * 1e-3, d_mm * 1e-3
    rf = None if curvature_mm is None else curvature_mm * 1e-3
    model = _model(a, d, rf)
    freqs = np.array([4e6, 5e6, 6e6])
    freqs = model.frequencies[[int(np.argmin(np.abs(model.frequencies - f))) for f in freqs]]

    def reference(tilt: float) -> np.ndarray:
        if rf is None:
            return np.abs([ref.pulse_echo_plane_rayleigh(a, f, d, tilt, C) for f in freqs])
        return np.abs([ref.pulse_echo_bowl_rayleigh(a, rf, f, d, tilt, C) for f in freqs])

    normal = reference(0.0)
    scale = normal.max()
    for tilt in (0.0, 0.5, 1.5):
        want = normal if tilt == 0.0 else reference(tilt)
        got = _transfer(model, d, tilt, freqs)
        err = np.max(np.abs(got - want) / scale)
        assert err < 5e-3, f"tilt {tilt}°: {got} vs {want} ({err:.1e} of the peak)"


@pytest.mark.parametrize(("radius_mm", "d_mm"), [(6.35, 10), (6.35, 50), (1.5, 50)])
def test_broadband_tilt_lobe_matches_the_exact_angular_spectrum(
    radius_mm: float, d_mm: float
) -> None:
    """The envelope peak vs tilt (0.3–5°), relative to normal incidence.  Tolerance 5e-3
    of the peak: measured ≤ 9.3e-4 for the 12.7 mm probe, ≤ 1.9e-3 for the 3 mm probe at
    150 mm (where the Kirchhoff sum is off by as much); the 3 mm probe at 50 mm, whose
    two-way impulse response is shorter than the time grid's step, 0.9e-3 to 4.1e-3 as the
    echo's place between grid points moves (the grid's B-spline aliasing: the window's
    start moved by fractions of a sample; 3.5e-3 where the grid is anchored here)."""
    a, d = radius_mm * 1e-3, d_mm * 1e-3
    model = _model(a, d)
    tilts = np.array([0.3, 1.0, 2.0, 3.0, 5.0])
    want = ref.tilt_envelope_curve(a, d, F0, tilts, sigma_t=SIGMA_T, c=C, accuracy=0.5)
    top = _peak(model, d, 0.0, 0.0)
    got = np.array([_peak(model, d, t, 0.0) for t in tilts]) / top
    np.testing.assert_allclose(got, want, atol=5e-3)


def _peak(model: WaveEchoModel, d: float, tilt_x: float, tilt_y: float) -> float:
    frame = tilt_frame(np.array([tilt_x]), np.array([tilt_y]))
    return envelope_peak(model.ascans(PLANE, np.array([[0.0, 0.0, d]]), frame)[0])


def test_level_plane_echo_is_symmetric_and_peaks_exactly_at_the_normal() -> None:
    """The face's nodes are symmetric under x → −x and y → −y, so ± tilts give the same
    echo to round-off, and the maximum sits at the normal."""
    model = _model(6.35e-3, 0.05)
    top = _peak(model, 0.05, 0.0, 0.0)
    for t in (0.01, 0.1, 0.7):
        values = [_peak(model, 0.05, sx * t, 0.0) for sx in (1, -1)]
        values += [_peak(model, 0.05, 0.0, sy * t) for sy in (1, -1)]
        assert max(values) - min(values) < 1e-9 * top
        assert max(values) < top


@pytest.mark.parametrize(
    ("probe", "tilt_x", "tilt_y"),
    [
        (PistonProbe(radius=6.35e-3), 3.0, 2.0),
        (PistonProbe(radius=6.35e-3), 0.0, 0.0),
        (PistonProbe(radius=6.35e-3, curvature=0.06), 1.0, -4.0),
        (PistonProbe(radius=6.35e-3, curvature=0.06), 0.0, 0.0),
        (RectangularProbe(half_width=4e-3, half_height=2.5e-3), 0.0, 6.0),
        (RectangularProbe(half_width=4e-3, half_height=2.5e-3), 0.0, 0.0),
    ],
)
def test_symmetric_half_of_the_face_rule_gives_the_full_rule_sum(
    probe: PistonProbe | RectangularProbe, tilt_x: float, tilt_y: float
) -> None:
    """The image form keeps one node of each pair the plane's mirror symmetry maps onto
    each other (one per ring at normal incidence): its grid equals the full rule's (its
    rings' angles starting at the tilt direction), summed node by node with the same SIR
    kernel, to round-off (1e-12 of the grid's peak), with at
    most 0.55 of the nodes (1/8 at normal incidence for a disc or a bowl, 0.3 for a
    rectangle)."""
    d = 0.03
    model = _model_of(probe, d)
    plane = tilted_plane(model, d, tilt_x, tilt_y)
    points, weights = model.image_nodes(plane)
    lam = model._shortest_wavelength
    spacing = image.node_spacing(lam, plane.sin_incidence, _IMAGE_NYQUIST_FRACTION)
    face, full_weights = image.face_quadrature(model.probe, plane.axis_distance, lam, spacing)
    if probe.kind != sir.RECT:  # the same rule with its angles starting at the tilt direction
        psi = math.atan2(plane.normal[1], plane.normal[0])
        rotation = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
        face[:2] = rotation @ face[:2]
    _, dt, pad, n_fft = model._grid
    t0 = model.window.start - pad * dt

    def grid(nodes: np.ndarray, w: np.ndarray) -> np.ndarray:
        out = np.zeros(n_fft)
        scratch = np.zeros((4, sir.scratch_bins(C, dt, 4.0 * model.probe.radius)))
        sir.accumulate_one_way(
            probe.kind, probe.parameters, nodes, w, np.zeros(w.size), C, t0, dt, out, scratch
        )
        return out

    want = grid(plane.mirror(face), full_weights)
    got = grid(points, weights)
    assert np.abs(got - want).max() < 1e-12 * np.abs(want).max()
    normal = tilt_x == 0.0 and tilt_y == 0.0
    share = (0.3 if probe.kind == sir.RECT else 0.125) if normal else 0.55
    assert weights.size <= share * full_weights.size
    np.testing.assert_allclose(weights.sum(), full_weights.sum(), rtol=1e-12)


def test_image_form_and_kirchhoff_sum_agree_on_a_plane() -> None:
    """Two formulations of the same physics: sample by sample within 0.5 % of the peak for
    a flat 12.7 mm probe at 50 mm (measured 0.2 %), near and off the normal."""
    peak = _peak(_model(6.35e-3, 0.05), 0.05, 0.0, 0.0)
    for tilt in (0.0, 0.4, 1.2):
        frame = tilt_frame(np.array([tilt]), np.array([0.3]))
        pos = np.array([[0.0, 0.0, 0.05]])
        image = _model(6.35e-3, 0.05).ascans(PLANE, pos, frame)[0]
        kirchhoff = _model(6.35e-3, 0.05, image_planes=False).ascans(PLANE, pos, frame)[0]
        assert np.abs(image - kirchhoff).max() < 5e-3 * peak


def test_image_form_applies_only_where_a_plane_fills_the_beam() -> None:
    model = _model(6.35e-3, 0.05)
    pos, frame = np.array([0.0, 0.0, 0.05]), tilt_frame(np.array([0.0]), np.array([0.0]))[0]
    assert model.image_plane(PLANE, pos, frame) is not None
    small = (FinitePlane(center=[0.0, 0.0, 0.0], width=0.01, height=0.01),)
    assert model.image_plane(small, pos, frame) is None  # its edges lie in the beam
    ball = (Sphere(center=[0.0, 0.0, -0.0125], radius=0.0125),)
    assert model.image_plane(ball, pos, frame) is None
    # a plane seen at 10° still fills the beam; one the axis misses does not
    assert model.image_plane(PLANE, pos, tilt_frame(np.array([10.0]), np.array([0.0]))[0])
    away = tilt_frame(np.array([0.0]), np.array([0.0]))[0] * np.array([1.0, -1.0, -1.0])
    assert model.image_plane(PLANE, pos, away) is None


# --------------------------------------------------------------------------- rectangles
RECT_ACCURACY = 0.6
"""Node-count factor of the rectangle's double Rayleigh reference: 0.6 × the default nodes
per side agree with the default's |V| to 1.6·10⁻¹⁴ of the peak on the near-field square
(5 × 5 mm half-sides, 10 mm, 4–6 MHz, tilts 0–1.5°) and to 9.2·10⁻¹⁰ on the others
(measured, tests/physics/references.py, 2026-12-07); 0.45 still agrees to 7·10⁻⁸: the
default is over-converged, and it cost the near-field square 20 CPU-s."""


@pytest.mark.parametrize(
    ("ax_mm", "ay_mm", "d_mm"), [(5.0, 5.0, 10), (5.0, 3.0, 20), (2.0, 1.5, 50)]
)
def test_rectangle_echo_equals_the_double_rayleigh_integral(
    ax_mm: float, ay_mm: float, d_mm: float
) -> None:
    """A flat rectangular probe's |V(f)| at 4, 5 and 6 MHz, tilted about either side by
    0.5–1.5°, against the brute-force double Rayleigh integral over the rectangle.  The first
    gimbal angle tilts the beam across the face's height (about x′), the second across its
    width.  Tolerance 1.5·10⁻³ of the largest normal-incidence |V| (measured ≤ 6.4·10⁻⁴; the
    reference is converged to 1e-9, see ``RECT_ACCURACY``)."""
    ax, ay, d = ax_mm * 1e-3, ay_mm * 1e-3, d_mm * 1e-3
    model = _model_of(RectangularProbe(half_width=ax, half_height=ay), d)
    nearest = [int(np.argmin(np.abs(model.frequencies - f))) for f in (4e6, 5e6, 6e6)]
    freqs = model.frequencies[nearest]

    def reference(along: float, tilt: float, axis: str = "y") -> np.ndarray:
        return np.abs(
            [
                ref.pulse_echo_rect_rayleigh(
                    ax, ay, f, along, tilt, C, tilt_axis=axis, accuracy=RECT_ACCURACY
                )
                for f in freqs
            ]
        )

    normal = reference(d, 0.0)
    scale = normal.max()
    np.testing.assert_allclose(_transfer(model, d, 0.0, freqs), normal, atol=1.5e-3 * scale)
    for first, second, axis in ((0.5, 0.0, "x"), (0.0, 1.0, "y"), (1.5, 0.0, "x")):
        tilt = first + second
        along = d / np.cos(np.radians(tilt))  # the probe is d above the plane: d/cos along its axis
        want = reference(along, tilt, axis)
        got = _transfer(model, d, first, freqs, tilt_y=second)
        np.testing.assert_allclose(got, want, atol=1.5e-3 * scale)


def test_square_probe_broadband_lobe_matches_the_rayleigh_reference() -> None:
    """The thesis's probe (4 mm square, 1 MHz Gabor pulse of 60 % bandwidth) 20 mm above a
    level plane (20 mm/cos α along its axis): the echo's envelope peak against tilt α,
    relative to normal incidence,
    against the envelope of the double Rayleigh integral over the band (120 frequencies,
    tests/physics/references.py).  Tolerance 10⁻³ (measured ≤ 2·10⁻⁴; the reference's −6 dB
    half-width is 8.905°)."""
    pulse = GaborPulse(center_frequency=1e6, bandwidth=60)
    window = RecordingWindow(fs=20e6, start=2 * 0.02 / C - 8e-6, n_samples=512)
    probe = RectangularProbe(half_width=2e-3, half_height=2e-3)
    model = WaveEchoModel(probe=probe, pulse=pulse, window=window, sound_speed=C)
    freqs = np.linspace(0.025e6, 3e6, 120)

    def reference(tilt: float) -> float:
        along = 0.02 / np.cos(np.radians(tilt))  # the probe is 20 mm above the plane
        v = np.array(
            [
                ref.pulse_echo_rect_rayleigh(2e-3, 2e-3, f, along, tilt, C, tilt_axis="x")
                for f in freqs
            ]
        )
        return float(ref.pulse_echo_envelope_peak(v, freqs, pulse.spectrum(freqs)))

    tilts = (4.0, 8.0, 12.0)
    want = np.array([reference(t) for t in tilts]) / reference(0.0)
    got = np.array([_peak(model, 0.02, t, 0.0) for t in tilts]) / _peak(model, 0.02, 0.0, 0.0)
    np.testing.assert_allclose(got, want, atol=1e-3)


@pytest.mark.parametrize("d_mm", [20, 50, 100])
def test_rectangle_kirchhoff_sum_agrees_with_the_image_form(d_mm: float) -> None:
    """Over curved parts a rectangle takes the Kirchhoff sum; on a plane it must agree with
    the exact image form: envelope peaks within 3·10⁻³ of the normal-incidence peak for a
    10 × 5 mm probe at 20–100 mm, tilted about both sides (measured ≤ 1.7·10⁻³; at 10 mm it
    is 2·10⁻², the disc's 4·10⁻³: docs/physics.md)."""
    d = d_mm * 1e-3
    probe = RectangularProbe(half_width=5e-3, half_height=2.5e-3)
    image, kirchhoff = _model_of(probe, d), _model_of(probe, d, image_planes=False)
    top = _peak(image, d, 0.0, 0.0)
    for first, second in ((0.0, 0.0), (0.3, 0.0), (0.0, 0.6), (1.0, 0.5), (2.0, 0.0)):
        assert abs(_peak(image, d, first, second) - _peak(kirchhoff, d, first, second)) < 3e-3 * top


@pytest.mark.parametrize(("d_mm", "tilt"), [(50, 10.0), (20, 10.0), (50, 20.0)])
def test_band_limited_face_rule_keeps_the_echo(
    d_mm: float, tilt: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """At large tilts the image form uses the band-limited face rule (nodes per ring from a
    bound on every path's phase rate, :func:`echocal.wave.image.angular_bandwidth`), with
    1.6–6× fewer nodes than the Nyquist rule here.  Its |V(f)| at 4, 5 and 6 MHz stays
    within the single-frequency test's tolerance of the exact angular spectrum (5e-3 of the
    normal-incidence |V|), and within 3e-3 of the local |V| of the Nyquist rule's (the
    same integral, a denser quadrature; measured ≤ 1e-3 at 10°).  The broadband echo
    stays within 4e-3 of its own peak of the echo of a rule at 0.3 of the Nyquist spacing
    (4–5× its nodes per direction; measured ≤ 1.8e-3, the Nyquist rule's own error
    1.4e-3)."""
    a, d = 6.35e-3, d_mm * 1e-3
    model = _model(a, d)
    frame = tilt_frame(np.array([tilt]), np.array([0.0]))
    plane = model.image_plane(PLANE, np.array([0.0, 0.0, d]), frame[0])
    assert plane is not None
    band_nodes = model.image_nodes(plane)[1].size
    freqs = np.array([4e6, 5e6, 6e6])
    got = _transfer(model, d, tilt, freqs)
    f = model.frequencies[[int(np.argmin(np.abs(model.frequencies - fi))) for fi in freqs]]
    want = np.abs([ref.pulse_echo_plane(a, fi, d, tilt, C) for fi in f])
    normal = np.abs([ref.pulse_echo_plane(a, fi, d, 0.0, C) for fi in f]).max()
    assert np.abs(got - want).max() < 5e-3 * normal
    band_echo = model.ascans(PLANE, np.array([[0.0, 0.0, d]]), frame)[0]

    monkeypatch.setattr(image, "angular_bandwidth", lambda *args: 0.0)  # the Nyquist rule
    assert band_nodes * 1.5 < model.image_nodes(plane)[1].size  # 1.6× at 20 mm, 6× at 50 mm, 20°
    nyquist = _transfer(model, d, tilt, freqs)
    assert np.abs(got - nyquist).max() < 3e-3 * want.max()
    monkeypatch.setattr(model_module, "_IMAGE_NYQUIST_FRACTION", 0.3)
    dense = model.ascans(PLANE, np.array([[0.0, 0.0, d]]), frame)[0]
    assert np.abs(band_echo - dense).max() < 4e-3 * np.abs(dense).max()


@pytest.mark.parametrize("z", [0.5, 5.0, 50.0, 200.0, 800.0, 2000.0])
def test_trapezoid_count_resolves_a_ring_of_bandwidth_z(z: float) -> None:
    """The band-limited rule's nodes on a ring: the uniform rule with
    :func:`echocal.wave.image.trapezoid_count` nodes averages e^{iz cos φ} (harmonics up to
    about z, the phase of one path around a ring of bandwidth z) to J₀(z), the closed form,
    within 3e-4 (the error is about 2J_n(z), n = z + 3z^⅓ + 4: measured ≤ 1.3e-4)."""
    from scipy.special import j0

    n = image.trapezoid_count(z)
    assert n % 4 == 0
    phi = 2.0 * np.pi * np.arange(n) / n
    assert abs(np.exp(1j * z * np.cos(phi)).mean() - j0(z)) < 3e-4
