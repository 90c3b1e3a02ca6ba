"""The probe's lobe as a model of the echo (:mod:`echocal.calibrate.lobe_template`) and
its use by ``model-based``.

Independent truth: closed-form lobes the tests build themselves (a Gaussian, an
anisotropic Gaussian, a far-field piston's jinc⁴ with a tail), sampled where the test
chooses; the simulated probe's own metric, measured through ``metric_values`` at tilts
the test picks (not through the lobe profile the template is built from).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import j1
from tests.run_helpers import measurements_to_stay_within

from echocal.calibrate import FunctionObjective, calibrate
from echocal.calibrate.lobe_template import LobeTemplate, fit_template
from echocal.calibrate.model_based import ModelBased
from echocal.measurement import SourceObjective
from echocal.measurement.detection_radius import LobeProfile
from echocal.setups import setup_with_overrides
from echocal.signal.gates import resolve_gate

ANGLES = np.arange(0.0, 8.0 + 1e-9, 0.1)


def _gaussian(width: float, directions: int = 4) -> LobeTemplate:
    values = np.exp(-0.5 * (ANGLES / width) ** 2)
    phi = np.linspace(0.0, 2.0 * np.pi, directions, endpoint=False)
    return LobeTemplate(ANGLES, phi, np.tile(values, (directions, 1)))


def _piston(ka: float) -> np.ndarray:
    """Pulse-echo far-field piston energy lobe (2 J₁(u)/u)⁴, u = ka·sin θ (ka = 135: a
    12.7 mm probe at 5 MHz in water), with a tail 0.09·e^(−θ/0.8°) standing in for a
    broadband pulse's edge waves (a monochromatic lobe has nulls, at 1.63° first; the
    simulated 5 MHz probe's pseudo-energy is 0.02, 0.007, 0.002 of its peak at 1.2, 2,
    3°, which this tail matches)."""
    u = ka * np.sin(np.deg2rad(ANGLES))
    jinc = np.where(u > 1e-12, 2.0 * j1(np.maximum(u, 1e-12)) / np.maximum(u, 1e-12), 1.0)
    return np.maximum(jinc**4, 0.09 * np.exp(-ANGLES / 0.8))


def test_an_isotropic_template_is_its_profile_in_every_direction():
    template = _gaussian(0.4)
    rng = np.random.default_rng(0)
    offsets = rng.uniform(-2.0, 2.0, (200, 2))
    expected = np.exp(-0.5 * np.hypot(*offsets.T) ** 2 / 0.4**2)
    # linear interpolation on a 0.1° grid: error ≤ (0.1²/8)·max|g''| = 0.0016·(1/0.4²)
    assert np.max(np.abs(template(offsets) - expected)) < 0.011
    assert template.width == pytest.approx(0.4, abs=0.003)


def test_an_anisotropic_template_is_exact_along_its_directions_and_linear_between():
    widths = np.array([0.3, 0.6, 0.3, 0.6])  # narrow along x, broad along y
    values = np.exp(-0.5 * (ANGLES[None, :] / widths[:, None]) ** 2)
    template = LobeTemplate(ANGLES, np.linspace(0.0, 2.0 * np.pi, 4, endpoint=False), values)
    d = 0.5
    along_x = template(np.array([[d, 0.0], [-d, 0.0]]))
    along_y = template(np.array([[0.0, d], [0.0, -d]]))
    assert along_x == pytest.approx(np.exp(-0.5 * (d / 0.3) ** 2), rel=1e-9)
    assert along_y == pytest.approx(np.exp(-0.5 * (d / 0.6) ** 2), rel=1e-9)
    diagonal = template(np.array([[d, d]]) / np.sqrt(2.0))[0]
    assert diagonal == pytest.approx(0.5 * (along_x[0] + along_y[0]), rel=1e-9)


def test_the_fit_finds_a_peak_seen_only_from_its_tail():
    """Seven points 1.2–2.6° from a jinc⁴ lobe's peak (0.41° to e^(−1/2)), all below 3 %
    of the peak: noiseless, the fit puts the peak within the fine grid's 0.01°."""
    template = LobeTemplate(ANGLES, np.zeros(1), _piston(135.0)[None, :])
    assert template.width == pytest.approx(0.41, abs=0.02)  # jinc(u)⁴ = e^(−1/2) at u ≈ 0.97
    truth, energy = np.array([0.7, -0.4]), 5.0
    ang = np.arange(7) * 2.0 * np.pi / 7.0
    radius = np.linspace(1.2, 2.6, 7)
    points = truth + radius[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    values = energy * template(points - truth)
    assert values.max() < 0.03 * energy
    around = points[0] + np.array([0.037, 0.013])  # the truth on no grid node
    fit = fit_template(template, points, values, np.full(7, 1e-4), around, 4.0)
    assert fit is not None
    assert np.hypot(*(fit.centre - truth)) <= 0.01 * np.sqrt(2.0) / 2.0 + 1e-9
    assert fit.energy == pytest.approx(energy, rel=0.02)


def test_the_fit_of_pure_noise_is_not_a_significant_echo():
    template = _gaussian(0.35)
    rng = np.random.default_rng(3)
    points = rng.uniform(-3.0, 3.0, (30, 2))
    sigma = np.full(30, 1.0)
    fits = [
        fit_template(template, points, rng.normal(0.0, 1.0, 30), sigma, np.zeros(2), 4.0)
        for _ in range(20)
    ]
    significant = [f for f in fits if f is not None and f.measured > 4.0 * f.energy_sigma]
    # the best of ~1,300 candidate peaks on 30 noise values: E₀/σ(E₀) is a max of
    # correlated normals, above 4 (the threshold model-based uses) in 3 of 200 draws
    # measured (1.5 %); ≤ 2 of 20 fails with probability 0.4 % at that rate
    assert len(significant) <= 2


def test_no_weight_no_fit():
    template = _gaussian(0.35)
    points = np.zeros((3, 2))
    assert fit_template(template, points, np.full(3, np.nan), np.ones(3), np.zeros(2), 1.0) is None


def _tail_objective(truth: np.ndarray, template: LobeTemplate, seed: int) -> FunctionObjective:
    def f(points: np.ndarray) -> np.ndarray:
        return 100.0 * template(points - truth) + 1.0

    return FunctionObjective(f, noise_sigma=0.05, noise_floor=1.0, budget=40, rng=seed)


def _measurements_to_stay_within(result, truth: np.ndarray, tolerance: float) -> int | None:
    """On a function of two plain coordinates: the error is the distance [deg]."""
    err = np.hypot(*(np.asarray(result.iterates) - truth).T)
    return measurements_to_stay_within(result, err, tolerance)


def test_model_based_climbs_from_the_tail_faster_with_the_template():
    """A piston lobe with a broadband tail, seen from 2.2° off (every point of the
    7-point design below 3 % of the peak): with the template every seed stays within
    0.1° after at most 10 measurements (8–10 measured), without it none before 12
    (12–13: the log-quadratic reads the tail as a lobe twice as broad).  From the tail
    alone the peak's energy and distance trade off (an exponential tail), so the first
    step lands on the flank, not the top; the next lands on it."""
    template = LobeTemplate(ANGLES, np.zeros(1), _piston(135.0)[None, :])
    truth = np.array([1.3, -0.6])
    x0 = truth + np.array([-1.8, 1.27])
    counts: dict[bool, list[int | None]] = {True: [], False: []}
    for seed in range(6):
        for given in (True, False):
            objective = _tail_objective(truth, template, seed=seed)
            options = {"lobe_template": (lambda: template)} if given else {}
            result = calibrate(
                objective, method="model-based", x0=x0, budget=30, rng=seed, settle=None, **options
            )
            counts[given].append(_measurements_to_stay_within(result, truth, 0.1))
    assert None not in counts[True] and None not in counts[False], counts
    assert max(counts[True]) <= 11, counts  # type: ignore[type-var]  # measured 10, +1
    assert max(counts[True]) < min(counts[False]), counts  # type: ignore[type-var]


def test_model_based_calls_the_template_once():
    calls = []

    def template() -> LobeTemplate:
        calls.append(1)
        return _gaussian(0.35)

    objective = _tail_objective(np.zeros(2), _gaussian(0.35), seed=2)
    calibrate(objective, method="model-based", x0=(1.0, 0.5), budget=15, lobe_template=template)
    assert len(calls) == 1


@pytest.fixture(scope="module")
def plate():
    setup = setup_with_overrides("immersion-5mhz", snr_db=30.0, seed=0)
    return setup, np.asarray(setup.reference_position, float)


def test_the_simulated_probes_template_is_its_pseudo_energy_off_its_peak(plate):
    """The template against the simulator's own metric at tilts the test picks around the
    true optimum: within 3 % of the peak's energy plus 15 % of the value (the template
    interpolates between 4 directions; the tilted plate's lobe differs by up to ±15 %
    between them at 0.5°)."""
    setup, pos = plate
    objective = SourceObjective(setup, pos, parameterization="tilt")
    template = objective.lobe_template()
    assert template is not None
    truth = np.array(setup.true_optimum(pos, parameterization="tilt"))
    rng = np.random.default_rng(5)
    offsets = rng.uniform(-1.5, 1.5, (24, 2))
    tilts = truth + offsets
    values = setup.metric_values(pos, tilts[:, 0], tilts[:, 1], parameterization="tilt")
    peak = float(setup.metric_values(pos, truth[:1], truth[1:], parameterization="tilt")[0])
    relative = values / peak
    assert np.all(np.abs(template(offsets) - relative) <= 0.03 + 0.15 * relative)
    # the simulator's template knows its peak's pseudo-energy, in the objective's units
    assert template.peak == pytest.approx(peak, rel=0.01)


def test_a_rigs_twin_gives_the_lobe_but_not_its_peak_energy(plate):
    """A setup file does not give the rig's echo amplitude in the rig's units."""
    from tests.measurement.fake_sources import GaussianEchoSource

    setup, pos = plate
    rig = SourceObjective(
        GaussianEchoSource(), pos, pulse=setup.pulse, twin=setup, parameterization="tilt"
    )
    template = rig.lobe_template()
    assert template is not None and template.peak is None


def test_the_simulators_normal_echo_is_its_pseudo_energy_at_normal_incidence(plate):
    """``normal_echo`` against the simulator's own noiseless metric at the direction the
    test finds for normal incidence over the plate (the true optimum there): within 1 %
    (the profile's scans and the metric's are the same noiseless simulation; 1 % allows
    the optimum search's tolerance).  A rig's twin and a gate give none."""
    from tests.measurement.fake_sources import GaussianEchoSource

    setup, pos = plate
    objective = SourceObjective(setup, pos, parameterization="tilt")
    truth = np.array(setup.true_optimum(pos, parameterization="tilt"))
    peak = float(setup.metric_values(pos, truth[:1], truth[1:], parameterization="tilt")[0])
    assert objective.normal_echo() == pytest.approx(peak, rel=0.01)
    rig = SourceObjective(
        GaussianEchoSource(), pos, pulse=setup.pulse, twin=setup, parameterization="tilt"
    )
    assert rig.normal_echo() is None
    gate = resolve_gate("front-wall", pulse=setup.pulse)
    assert SourceObjective(setup, pos, gate=gate, parameterization="tilt").normal_echo() is None


def test_no_normal_echo_where_the_optimum_may_be_weaker_or_the_units_differ(plate):
    """A receiver that saturates measures less than the noiseless echo; bounds that
    exclude normal incidence may hold a weaker optimum; other angles than tilts get none
    (as the template: no lobe profile is computed for them)."""
    import dataclasses

    from echocal.measurement.receiver_settings import ReceiverSettings

    setup, pos = plate
    clipped = dataclasses.replace(setup, receiver=ReceiverSettings(snr_db=30.0, full_scale=2.0))
    assert SourceObjective(clipped, pos, parameterization="tilt").normal_echo() is None
    truth = np.array(setup.true_optimum(pos, parameterization="tilt"))
    away = [(truth[0] + 5.0, truth[0] + 10.0), (truth[1] - 5.0, truth[1] + 5.0)]
    beside = SourceObjective(setup, pos, parameterization="tilt", bounds=away)
    assert beside.normal_echo() is None
    assert SourceObjective(setup, pos).normal_echo() is None  # azimuth, co-elevation


def test_no_template_for_a_gate_another_metric_or_other_angles(plate):
    setup, pos = plate
    gate = resolve_gate("front-wall", pulse=setup.pulse)
    assert SourceObjective(setup, pos, parameterization="tilt", gate=gate).lobe_template() is None
    other = SourceObjective(setup, pos, parameterization="tilt", metric="peak-amplitude")
    assert other.lobe_template() is None
    assert SourceObjective(setup, pos).lobe_template() is None  # azimuth, co-elevation


def _ring(angles: np.ndarray) -> np.ndarray:
    """A near-field lobe over a ball: a central peak, a dip, a ring at 0.8 of the peak."""
    return np.exp(-0.5 * (angles / 0.3) ** 2) + 0.8 * np.exp(-0.5 * ((angles - 1.6) / 0.3) ** 2)


def test_no_template_for_a_lobe_that_does_not_peak_at_normal_incidence(plate):
    """Two humps off normal incidence (a large probe over a rod) are not one peak, and a
    side lobe below half the peak gets no template; a ring above half of it (the probe's
    near field over a ball) is part of the template."""
    setup = plate[0]
    angles = np.arange(0.0, 3.0, 0.1)
    humps = np.exp(-0.5 * ((angles - 1.5) / 0.4) ** 2) + 0.8
    profile = LobeProfile(setup, angles, humps[None, :], np.zeros(4), humps[None, :])
    assert profile.energy_template() is None
    ring = _ring(angles)
    ringed = LobeProfile(setup, angles, ring[None, :], np.zeros(4), ring[None, :])
    assert ringed.energy_template().values == pytest.approx(ring[None, :] / ring[0])
    side = np.exp(-0.5 * (angles / 0.3) ** 2) + 0.21 * np.exp(-0.5 * ((angles - 1.6) / 0.3) ** 2)
    side_lobed = LobeProfile(setup, angles, side[None, :], np.zeros(4), side[None, :])
    assert side_lobed.energy_template() is None  # rises by 0.21, to 0.21 < half the peak
    single = np.exp(-0.5 * (angles / 0.4) ** 2)
    template = LobeProfile(setup, angles, single[None, :], np.zeros(4), 3.0 * single[None, :])
    assert template.energy_template().values == pytest.approx(single[None, :])


def test_the_top_of_a_ringed_lobe_is_its_main_lobe_only():
    """A ring at 0.8 of the peak is above half of it but is not the top: ``on_top`` holds
    inside the main lobe (half energy at 0.3·√(2 ln 2) = 0.353°, the ring's share there
    ~0) and nowhere on the ring or in the dip."""
    template = LobeTemplate(ANGLES, np.zeros(1), _ring(ANGLES)[None, :] / _ring(ANGLES)[0])
    phi = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    around = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    assert template.on_top(0.34 * around).all()
    assert not template.on_top(0.37 * around).any()
    assert template(1.6 * around).min() > 0.75  # the ring: high, yet not the top
    assert not template.on_top(1.6 * around).any()
    assert not template.on_top(0.8 * around).any()  # the dip


def test_the_top_is_each_directions_own_main_lobe():
    """Along +x the lobe stays above half to 1.0°; along −x it dips to 0.2 at 0.4° and
    rises to a ring of 0.83 at 0.8°; along ±y it never falls below half in the template's
    8° (its last value holds beyond).  A point on the −x ring is not on the top, though
    the +x lobe reaches farther; 0.8° along +x is; ±y is top to the end and beyond."""
    main = np.clip(1.0 - 0.5 * ANGLES / 1.0, 0.0, 1.0)  # 0.5 at 1.0°
    ringed = np.interp(ANGLES, [0.0, 0.4, 0.8, 1.2, 8.0], [1.0, 0.2, 0.83, 0.3, 0.0])
    broad = np.maximum(1.0 - 0.05 * ANGLES, 0.55)
    values = np.stack([main, broad, ringed, broad])
    template = LobeTemplate(ANGLES, np.linspace(0.0, 2.0 * np.pi, 4, endpoint=False), values)
    assert template.on_top(np.array([0.8, 0.0]))
    assert not template.on_top(np.array([-0.8, 0.0]))
    assert template(np.array([-0.8, 0.0])) > 0.8  # on the ring
    assert template.on_top(np.array([[0.0, 5.0], [0.0, -7.9], [0.0, 9.0]])).all()
    assert not template.on_top(np.array([1.1, 0.0]))


def test_a_previous_peak_is_kept_unless_the_data_clearly_prefer_another():
    """One measurement of 0.6 of a known peak energy puts the peak anywhere on the circle
    where the Gaussian lobe is 0.6 (radius 0.4·√(2 ln(1/0.6)) = 0.405°): every centre there
    fits alike, and the previous one is kept.  A second measurement of the full peak
    energy 0.405° the other way is a clear preference (χ² ≫ 9): the fit moves there.
    "Kept" is to the coarse grid's 0.2°: the previous peak is refined on the fine grid
    within that of it, where the circle's points tie."""
    template = _gaussian(0.4)
    r = 0.4 * np.sqrt(2.0 * np.log(1.0 / 0.6))
    points, values, sigmas = np.zeros((1, 2)), np.array([0.6]), np.array([0.01])
    for previous in (np.array([r, 0.0]), np.array([0.0, -r]), np.array([-0.7 * r, 0.7 * r])):
        fit = fit_template(
            template, points, values, sigmas, np.zeros(2), 2.0, peak=1.0, previous=previous
        )
        assert np.hypot(*(fit.centre - previous)) <= 0.2 + 1e-9
        assert np.hypot(*fit.centre) == pytest.approx(r, abs=0.01)
    points = np.array([[0.0, 0.0], [-r, 0.0]])
    values, sigmas = np.array([0.6, 1.0]), np.array([0.01, 0.01])
    fit = fit_template(
        template, points, values, sigmas, np.zeros(2), 2.0, peak=1.0, previous=np.array([r, 0.0])
    )
    assert np.hypot(*(fit.centre - [-r, 0.0])) <= 0.1  # the flat top: ±0.05° fit alike


@pytest.mark.parametrize(("delta_chi2", "kept"), [(8.5, True), (9.5, False)])
def test_a_previous_peak_is_kept_up_to_a_chi2_of_9(delta_chi2: float, kept: bool):
    """Noiseless points of a Gaussian lobe (σ_w 0.4°) peaked at the origin, previous peak
    0.6° out: the best kept peak is 0.4° out (the fine grid within the coarse 0.2° step of
    the previous one), whose χ² the test computes itself (E₀ by least squares, no prior:
    S = Σ (y − Ê g)² / σ²).  The measurement σ is set so that χ² there exceeds the
    origin's (0) by 8.5 — kept — or 9.5 — the fit moves to the origin."""
    template = _gaussian(0.4)
    x = np.stack([np.linspace(-0.6, 0.6, 5), np.zeros(5)], axis=1)
    y = np.exp(-0.5 * np.hypot(*x.T) ** 2 / 0.4**2)
    g = np.exp(-0.5 * np.hypot(*(x - [0.4, 0.0]).T) ** 2 / 0.4**2)
    residual = float(np.sum((y - (y @ g) / (g @ g) * g) ** 2))
    sigma = np.sqrt(residual / delta_chi2)
    fit = fit_template(
        template, x, y, np.full(5, sigma), np.zeros(2), 2.0, previous=np.array([0.6, 0.0])
    )
    expected = [0.4, 0.0] if kept else [0.0, 0.0]
    assert fit.centre == pytest.approx(expected, abs=1e-9)


def _path(optimizer: ModelBased, f, n: int, recommend_calls: int = 0) -> np.ndarray:
    """The points an ask/tell loop of ``n`` measurements asks for, calling ``recommend()``
    ``recommend_calls`` times after each tell."""
    asked = []
    for _ in range(n):
        points = optimizer.ask()
        optimizer.tell(f(points))
        asked.append(points)
        for _ in range(recommend_calls):
            optimizer.recommend()
    return np.vstack(asked)


def _strong_lobe(points: np.ndarray) -> np.ndarray:
    return 100.0 * _gaussian(0.35)(points - np.array([0.8, -0.5])) + 1.0


def test_without_a_noise_model_the_template_is_not_used():
    """Without a live noise model the template cannot weigh the measurements: the same
    path as without a template."""
    with_template = ModelBased((0.0, 0.0), lobe_template=lambda: _gaussian(0.35), rng=0)
    without = ModelBased((0.0, 0.0), rng=0)
    path = _path(with_template, _strong_lobe, 12)
    assert with_template._tfit is None
    np.testing.assert_array_equal(path, _path(without, _strong_lobe, 12))


def test_the_path_does_not_depend_on_how_often_the_estimate_is_read():
    """The hand-over from the template to the quadratic happens in ``tell``, not in
    ``recommend()``: reading the estimate any number of times leaves the path alone."""

    def build() -> ModelBased:
        return ModelBased(
            (0.0, 0.0),
            lobe_template=lambda: _gaussian(0.35),
            noise_model=lambda: (1.0, 0.05),
            rng=0,
        )

    quiet, chatty = build(), build()
    path = _path(quiet, _strong_lobe, 20)
    np.testing.assert_array_equal(path, _path(chatty, _strong_lobe, 20, recommend_calls=3))
    assert quiet._quadratic_on_top  # the hand-over happened within the 20


def test_a_template_must_be_one_normalised_lobe():
    from echocal.errors import EchocalValueError

    good = _gaussian(0.35)
    with pytest.raises(EchocalValueError, match="shape"):
        LobeTemplate(good.angles, good.directions, good.values[:, :-1])
    with pytest.raises(EchocalValueError, match="1 at the peak"):
        LobeTemplate(good.angles, good.directions, 2.0 * good.values)
    with pytest.raises(EchocalValueError, match="evenly spaced"):
        LobeTemplate(good.angles, good.directions + 0.1, good.values)
