"""The probe's detection radius and the search passes sized from it
(:mod:`echocal.measurement.detection_radius`).

Independent truth: Monte-Carlo noise draws added to the noiseless A-scans and put through
the detector itself (``EchoDetector.significance`` > 4.5, as the acquisition phase
tests), against the module's Rice (Marcum-Q) formula.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from echocal.calibrate import calibrate
from echocal.calibrate.auto import AUTO_SEARCH
from echocal.calibrate.objective import FunctionObjective
from echocal.constants import ECHO_THRESHOLD
from echocal.errors import EchocalValueError, GeometryError
from echocal.geometry import tilt_frame
from echocal.measurement import ReceiverSettings, SourceObjective
from echocal.measurement import detection_radius as dr
from echocal.setups import load_setup
from echocal.signal.detection import shared_detector
from echocal.signal.gates import resolve_gate
from echocal.signal.noise import noise_sigma_for_snr
from echocal.specimen.builtins import builtin_specimen

DRAWS = 2000


@pytest.fixture(scope="module")
def ray():
    setup = load_setup("immersion-5mhz-ray", seed=0)
    return setup, dr.lobe_profile(setup, setup.reference_position)


def _monte_carlo(setup, profile, snr, angles, seed=7):
    """P(g > 4.5) at ``angles`` [deg] along the profile's first direction, from DRAWS
    noisy A-scans each."""
    pos = np.asarray(setup.reference_position, float)
    centre = setup.normal_incidence_directions(pos)[0]
    frames = tilt_frame(centre[0] + np.asarray(angles), np.full(len(angles), centre[1]))
    scans = setup.ideal_samples(np.broadcast_to(pos, (len(angles), 3)), frames)
    sigma = float(noise_sigma_for_snr(profile.reference, snr, setup.window, setup.pulse))
    detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
    rng = np.random.default_rng(seed)
    out = []
    for scan in scans:
        noisy = scan + sigma * rng.standard_normal((DRAWS, scan.size))
        out.append(float(np.mean(detector.significance(noisy, sigma) > ECHO_THRESHOLD)))
    return np.array(out)


@pytest.fixture(scope="module")
def wave():
    setup = load_setup("immersion-5mhz", seed=0)
    return setup, dr.lobe_profile(setup, setup.reference_position, until_snr_db=30.0)


@pytest.mark.parametrize(
    ("model", "snr", "tight"), [("ray", 30.0, False), ("ray", 20.0, False), ("wave", 30.0, True)]
)
def test_the_rice_detection_probability_against_noise_draws_through_the_detector(
    request, model, snr, tight
):
    """Across the lobe's edge (0.1° steps along the first direction) the formula never
    exceeds the share of 2,000 noisy A-scans detected by more than 0.04 (3 binomial σ at
    P = 0.5 is 0.034): it counts only the echo's own cell, so it is a lower bound, and its
    90 % radius lies within 12 % below the draws' (measured: 6 % on the ray model, whose
    echo is spread over many rays' arrivals and so over several cells).  On the wave
    model's single clean echo it is close: within 0.06 both ways (0.054 measured, in the
    far tail where the neighbouring cells weigh most)."""
    setup, profile = request.getfixturevalue(model)
    first = profile.detection_probability(snr)[0]
    lo = max(int(np.flatnonzero(first < 0.99)[0]) - 1, 0)
    hi = int(np.flatnonzero(first < 0.1)[0])
    idx = np.unique(np.linspace(lo, hi, 12).round().astype(int))
    angles = profile.angles[idx]
    measured = _monte_carlo(setup, profile, snr, angles)
    formula = first[idx]
    assert measured.max() > 0.95 and measured.min() < 0.5  # the edge is spanned
    assert np.all(formula <= measured + 0.04)
    if tight:
        np.testing.assert_allclose(formula, measured, atol=0.06)
    r_formula = dr.first_crossing(angles, formula, 0.9)
    r_measured = dr.first_crossing(angles, measured, 0.9)
    assert 0.88 * r_measured <= r_formula <= r_measured + 0.05


def test_the_radius_grows_with_the_snr_and_the_wave_lobe_reaches_farther_than_the_ray_lobe(ray):
    _, profile = ray
    radii = [profile.radius(snr) for snr in (10.0, 20.0, 30.0)]
    assert radii[0] < radii[1] < radii[2]
    assert profile.radius(30.0, probability=0.98) < radii[2] < profile.radius(30.0, probability=0.5)
    wave = load_setup("immersion-5mhz", seed=0)
    wave_passes = dr.search_passes(wave, wave.reference_position)
    ray_passes = dr.search_passes(ray[0], ray[0].reference_position)
    assert wave_passes[0] > 1.8 * ray_passes[0]  # the diffraction tails: 8.6° against 4.2°


def test_passes_are_the_lattice_spacings_coarse_first_and_cached(ray):
    setup, profile = ray
    passes = dr.search_passes(setup, setup.reference_position)
    expected = [profile.lattice_spacing(snr) for snr in dr.SEARCH_SNRS]
    np.testing.assert_allclose(passes, expected, atol=0.006)  # rounded to 0.01°
    assert passes[0] > passes[1]
    n = len(dr._PROFILES)
    noisier = dataclasses.replace(setup, receiver=ReceiverSettings(snr_db=10.0), rng=5)
    assert dr.search_passes(noisier, setup.reference_position) == passes
    assert len(dr._PROFILES) == n  # the same probe: no new profile
    thesis = load_setup("thesis", seed=0)
    broad = dr.search_passes(thesis, thesis.reference_position)
    assert len(broad) == 1 and broad[0] >= np.sqrt(3.0) * 15.0 - 0.01  # seen beyond 15°


def test_auto_sizes_its_passes_from_the_simulated_probe_unless_told(ray):
    setup, _ = ray
    pos = setup.reference_position
    expected = list(dr.search_passes(setup, pos))

    def run(**options):
        obj = SourceObjective(setup, pos, parameterization="tilt", budget=12)
        return calibrate(obj, method="auto", x0=[0.5, 0.5], budget=12, rng=1, **options).options

    assert list(run()["passes"]) == expected
    assert list(run(passes=[5.0])["passes"]) == [5.0]
    plain = SourceObjective(setup, pos, parameterization="tilt", budget=12)
    res = calibrate(plain, method="acquisition", x0=[0.5, 0.5], budget=12, rng=1, fine_radius=3)
    assert tuple(res.options["passes"]) == ()  # only auto searches in passes by default
    analytic = FunctionObjective(lambda x: np.exp(-np.sum(x**2, axis=1)), budget=12)
    res = calibrate(analytic, method="auto", x0=[0.5, 0.5], budget=12, rng=1)
    assert list(res.options["passes"]) == list(AUTO_SEARCH["passes"])


def test_no_plan_for_a_gated_objective_or_a_position_off_the_part(monkeypatch):
    plate = load_setup("immersion-steel-plate", seed=0)
    pos = np.asarray(plate.reference_position, float)
    gate = resolve_gate(
        "back-wall", pulse=plate.pulse, thickness=plate.thickness, material=plate.material
    )
    # only whether the objective asks for passes: how they are sized is tested above on
    # other probes (this plate's lobe profile alone takes 35 s)
    sized = []
    with monkeypatch.context() as patch:
        patch.setattr(dr, "search_passes", lambda setup, at: sized.append(setup) or (4.0,))
        assert SourceObjective(plate, pos, gate=gate).search_passes() is None and sized == []
        assert SourceObjective(plate, pos).search_passes() == (4.0,) and sized == [plate]
    ball = dataclasses.replace(
        load_setup("immersion-5mhz", seed=0), specimen=builtin_specimen("sphere")
    )
    off = np.array([0.2, 0.2, 0.05])  # far beside the ball: no normal incidence
    with pytest.raises(GeometryError, match="position"):
        dr.lobe_profile(ball, off)
    assert SourceObjective(ball, off).search_passes() is None


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"directions": 0}, "directions"),
        ({"directions": True}, "directions"),
        ({"max_angle": -1.0}, "max_angle"),
        ({"max_angle": float("nan")}, "max_angle"),
    ],
)
def test_bad_profile_options_are_refused_naming_the_field(ray, kwargs, field):
    setup, _ = ray
    with pytest.raises(EchocalValueError, match=field):
        dr.lobe_profile(setup, setup.reference_position, **kwargs)


@pytest.mark.parametrize("probability", [1.5, -0.1, float("nan"), True])
def test_a_bad_probability_is_refused_naming_it(ray, probability):
    _, profile = ray
    with pytest.raises(EchocalValueError, match="probability"):
        profile.radius(30.0, probability=probability)


def test_a_rigs_twin_sizes_its_search_and_a_bare_source_has_no_plan(ray):
    from tests.measurement.fake_sources import GaussianEchoSource

    setup, _ = ray
    pos = setup.reference_position
    rig = GaussianEchoSource()
    assert SourceObjective(rig, pos, pulse=setup.pulse).search_passes() is None
    twin = SourceObjective(rig, pos, pulse=setup.pulse, twin=setup)
    assert twin.search_passes() == dr.search_passes(setup, pos)
    with pytest.raises(EchocalValueError, match="twin must be a simulated setup"):
        SourceObjective(rig, pos, pulse=setup.pulse, twin="immersion-5mhz")


class _StepProfile(dr.LobeProfile):
    """Detected with certainty within ``r`` [deg], never beyond: the closed forms below."""

    def __init__(self, r: float):
        angles = np.arange(0.0, 15.0001, 0.001)
        blank = np.zeros((1, angles.size))
        super().__init__(None, angles, blank, np.zeros(1), blank)
        self.r = r

    def detection_probability(self, snr_db, threshold=ECHO_THRESHOLD):
        return (self.angles <= self.r).astype(float)[None, :]


def test_lattice_spacing_against_the_closed_forms_of_a_step_lobe():
    """An echo seen exactly within r = 2°: full coverage needs the covering lattice
    (spacing √3 r); a share c ≤ π/(2√3) ≈ 0.907 of the plane, where the discs do not
    overlap, is covered at spacing r √(2π / (√3 c)) (disc area over cell area √3 s²/2).
    Tolerance 0.02°: the bisection's 0.01° and the 200 × 200 cell grid's."""
    step = _StepProfile(2.0)
    assert step.lattice_spacing(30.0, coverage=1.0) == pytest.approx(2.0 * np.sqrt(3.0), abs=0.02)
    for c in (0.5, 0.8):
        expected = 2.0 * np.sqrt(2.0 * np.pi / (np.sqrt(3.0) * c))
        assert step.lattice_spacing(30.0, coverage=c) == pytest.approx(expected, abs=0.02)


def test_lattice_spacing_covers_its_share_of_random_points(ray):
    """Independent of the cell grid: echoes at 20,000 random points of a large disc, the
    lattice's nearest measurement found with a k-d tree, P_detect (worst direction) at
    that distance averaged: the pass's stated coverage to 0.01 (20,000 draws of a
    bounded variable: σ ≤ 0.0035)."""
    from scipy.spatial import cKDTree

    from echocal.calibrate.acquisition import hex_spiral

    _, profile = ray
    spacing = profile.lattice_spacing(30.0, coverage=0.9)
    lattice = np.vstack(hex_spiral(np.zeros(2), spacing, 30))
    rng = np.random.default_rng(3)
    radius = 20.0 * spacing  # well inside the 30 rings
    rho, phi = radius * np.sqrt(rng.uniform(size=20_000)), rng.uniform(0, 2 * np.pi, 20_000)
    dist, _ = cKDTree(lattice).query(np.stack([rho * np.cos(phi), rho * np.sin(phi)], 1))
    prob = profile.detection_probability(30.0).min(axis=0)
    covered = np.interp(dist, profile.angles, prob, right=0.0).mean()
    assert covered == pytest.approx(0.9, abs=0.01)
    # more coverage or less SNR: a finer lattice
    assert profile.lattice_spacing(30.0, coverage=0.99) < spacing
    assert profile.lattice_spacing(20.0, coverage=0.9) < spacing


@pytest.mark.parametrize("coverage", [1.5, float("nan"), True])
def test_a_bad_coverage_is_refused_naming_it(ray, coverage):
    _, profile = ray
    with pytest.raises(EchocalValueError, match="coverage"):
        profile.lattice_spacing(30.0, coverage=coverage)
