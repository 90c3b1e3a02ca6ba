"""The Bayesian search of a lost echo (:mod:`echocal.calibrate.posterior_search`).

Independent truths: the detector's own significance (inverted), the likelihood as the
numerical derivative of the CDF P(max(R, N) ≤ t) = F_Rice(t; ν) · exp(−M t e^{−t²/2})
(not the module's scaled closed form), noisy A-scans of the simulated probe through the
detector, a prior's annulus masses by hand, and the next point by a direct double sum.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ndtr
from scipy.stats import rice

from echocal.calibrate.posterior_search import EchoLikelihood, PosteriorSearch
from echocal.errors import EchocalValueError

M = 300.0
"""Rice's level-crossing constant of a synthetic window."""


def _threshold(g: float = 4.5) -> float:
    """The normalized peak t with exp(−M t e^{−t²/2}) = Φ(g), by hand."""
    return float(brentq(lambda t: np.exp(-M * t * np.exp(-0.5 * t * t)) - ndtr(g), 1.0, 20.0))


def _likelihood(peak: float = 12.0, width: float = 1.0) -> EchoLikelihood:
    angles = np.arange(0.0, 5.0 + 1e-9, 0.05)
    echo = peak * np.exp(-(angles**2) / (2.0 * width**2))
    return EchoLikelihood(angles=angles, echo=echo, n_cells=M, threshold=_threshold())


def _cdf(t: float, nu: float) -> float:
    """P(max(R, N) ≤ t) = F_Rice(t; ν) F_N(t)."""
    return float(rice.cdf(t, nu) * np.exp(-M * t * np.exp(-0.5 * t * t)))


def _sf(t: float, nu: float) -> float:
    """P(max(R, N) > t), as S_R + F_R · S_N (no cancellation near F = 1)."""
    return float(rice.sf(t, nu) + rice.cdf(t, nu) * -np.expm1(-M * t * np.exp(-0.5 * t * t)))


def _density(t: float, nu: float, h: float = 1e-3) -> float:
    """The density of max(R, N) at t: the five-point derivative (error ~h⁴) of whichever of
    the CDF and the survival function is the smaller there (the other is 1 − tiny)."""
    sign, f = (1.0, _cdf) if _cdf(t, nu) < 0.5 else (-1.0, _sf)
    return (
        sign
        * (-f(t + 2 * h, nu) + 8 * f(t + h, nu) - 8 * f(t - h, nu) + f(t - 2 * h, nu))
        / (12 * h)
    )


def test_the_peak_is_recovered_from_the_detectors_significance():
    from echocal.signal import make_pulse
    from echocal.signal.detection import shared_detector

    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
    detector = shared_detector(pulse, 100e6, 1024)
    sigma = 0.3
    like = EchoLikelihood(
        angles=np.array([0.0, 1.0]), echo=np.zeros(2), n_cells=detector.n_cells, threshold=5.0
    )
    for t in (2.0, 3.5, 5.0, 8.0, 14.0):
        g = float(detector.significance_of_peak(t * sigma * detector.noise_gain, sigma))
        # the table's step is 0.015 in t; linear interpolation of a smooth curve: 1e-3
        assert like.peak_of_significance(g) == pytest.approx(t, rel=1e-3)


def test_a_significance_beyond_double_precision_is_the_tables_largest_peak():
    like = _likelihood()
    assert like.peak_of_significance(45.0) == like.peak_of_significance(np.inf) == 64.0
    assert like.peak_of_significance(-30.0) == 1.0  # below the least peak of Rice's law (t = 1)


@pytest.mark.parametrize("t", [2.5, 3.5, 5.0, 7.0])
@pytest.mark.parametrize("nu", [0.5, 2.0, 4.0, 7.0])
def test_the_log_ratio_is_the_derivative_of_the_max_of_echo_and_noise(t, nu):
    like = EchoLikelihood(
        angles=np.array([0.0, 1.0]), echo=np.array([nu, 0.0]), n_cells=M, threshold=4.0
    )
    ratio = like.log_ratio(t)
    assert ratio[0] == pytest.approx(np.log(_density(t, nu) / _density(t, 0.0)), abs=1e-6)
    assert ratio[1] == pytest.approx(0.0, abs=1e-12)  # no echo: no evidence


def test_a_peak_far_in_the_tail_stays_finite():
    # t = 40: every unscaled density underflows (e^{−800}); the scaled form does not
    ratio = _likelihood().log_ratio(40.0)
    assert np.all(np.isfinite(ratio)) and ratio[0] > 100.0 and ratio[-1] < ratio[0]


def test_the_likelihood_against_noisy_ascans_of_the_simulated_probe():
    """The model's CDF of the peak at 2.5° from the optimum (the lobe's edge at 20 dB)
    against 600 noisy A-scans through the detector: Kolmogorov–Smirnov distance ≤ 0.08
    (the 1 % critical value of 600 draws is 0.067; the model counts one cell of the echo)."""
    from echocal.geometry import tilt_frame
    from echocal.measurement import detection_radius as dr
    from echocal.setups import load_setup
    from echocal.signal.detection import shared_detector
    from echocal.signal.noise import noise_sigma_for_snr

    setup = load_setup("immersion-5mhz", seed=0)
    pos = np.asarray(setup.reference_position, float)
    profile = dr.cached_lobe_profile(setup, pos)
    sigma = float(noise_sigma_for_snr(profile.reference, 20.0, setup.window, setup.pulse))
    like = profile.echo_likelihood(sigma)
    centre = setup.normal_incidence_directions(pos)[0]
    scan = setup.ideal_samples(pos[None, :], tilt_frame(centre[0] + 2.5, centre[1]))[0]
    rng = np.random.default_rng(3)
    noisy = scan + sigma * rng.standard_normal((600, scan.size))
    detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
    t = np.sort(detector.peak(noisy) / (sigma * detector.noise_gain))
    nu = float(np.interp(2.5, like.angles, like.echo))
    model = rice.cdf(t, nu) * np.exp(-like.n_cells * t * np.exp(-0.5 * t * t))
    empirical = np.arange(1, len(t) + 1) / len(t)
    assert np.max(np.abs(model - empirical)) <= 0.08


def _search(bounds=((-30.0, 30.0), (-30.0, 30.0)), like=None) -> PosteriorSearch:
    like = _likelihood() if like is None else like
    return PosteriorSearch(np.zeros(2), 20.0, like, np.array(bounds))


def _prior_mass_within(r: float, radius: float = 20.0, near: float = 3.0) -> float:
    """P(ρ ≤ r) of the prior, by hand: a uniform distance, half within ``near`` of x0, half
    within ``radius``."""
    return 0.5 * min(r, near) / near + 0.5 * min(r, radius) / radius


@pytest.mark.parametrize("near", [3.0, 6.0])
def test_the_prior_is_uniform_in_distance_half_near_x0_half_anywhere(near):
    search = PosteriorSearch(
        np.zeros(2), 20.0, _likelihood(), np.array([[-30.0, 30.0], [-30.0, 30.0]]),
        near_radius=near,
    )  # fmt: skip
    post = np.exp(search.log_posterior())
    x, y = np.meshgrid(search._x[0], search._y[:, 0])
    rho = np.hypot(x, y)
    # annuli by hand (uniform in distance out to 20° alone, before: 5 % per 1° annulus).
    # Cells (0.25°) straddle the edges, and within 1° of x0 a 1/ρ density is integrated
    # over 4 cells per radius, the first capped at 1/cell: 2.5 % absolute there, 1.2 %
    # beyond (measured), so 3 % bounds both and a prior off by a third of a 1° annulus fails
    # (0.19 expected in the first degree with near=3°; the old prior had 0.05)
    for lo, hi in ((0.0, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 6.0), (6.0, 10.0), (10.0, 20.0)):
        inside = (rho >= lo) & (rho < hi)
        expected = _prior_mass_within(hi, near=near) - _prior_mass_within(lo, near=near)
        assert post[inside].sum() == pytest.approx(expected, abs=0.03)


def test_a_strong_detection_concentrates_and_a_quiet_value_thins_the_posterior():
    search = _search()
    x, y = np.meshgrid(search._x[0], search._y[:, 0])
    near = np.hypot(x - 8.0, y) < 1.5
    before = np.exp(search.log_posterior())[near].sum()
    search.update(np.array([[8.0, 0.0]]), np.array([-1.0]))  # a quiet value at (8, 0)
    assert np.exp(search.log_posterior())[near].sum() < 0.5 * before
    search.update(np.array([[-8.0, 0.0]]), np.array([9.0]))  # a clear echo at (−8, 0)
    around = np.hypot(x + 8.0, y) < 2.0
    assert np.exp(search.log_posterior())[around].sum() > 0.99


def test_quiet_measurements_lower_the_evidence_and_nan_is_no_evidence():
    search = _search()
    assert search.log_evidence() == pytest.approx(0.0, abs=1e-9)  # no data: prior odds
    search.update(np.array([[3.0, 0.0]]), np.array([np.nan]))
    assert search.log_evidence() == pytest.approx(0.0, abs=1e-9)
    last = 0.0
    for x in (3.0, 6.0, 9.0):
        search.update(np.array([[x, 0.0]]), np.array([-0.5]))
        assert search.log_evidence() < last
        last = search.log_evidence()


def test_the_next_point_is_the_direct_sum_of_posterior_times_detection():
    like = _likelihood(width=0.8)
    search = PosteriorSearch(np.zeros(2), 3.0, like, np.array([[-2.0, 10.0], [-10.0, 10.0]]))
    search.update(np.array([[1.0, 1.0], [-1.0, 0.5]]), np.array([2.5, -0.3]))
    post = np.exp(search.log_posterior())
    xs, ys = search._x[0], search._y[:, 0]
    gx, gy = np.meshgrid(xs, ys)
    detect = like.detection_probability()
    chance = np.zeros_like(post)
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            d = np.hypot(gx - x, gy - y)
            chance[i, j] = np.sum(post * np.interp(d, like.angles, detect, right=0.0))
    chance[:, xs < -2.0] = 0.0  # outside the bounds
    # the kernel leaves out detection probabilities below 1e-4 (≈ 1e-8 of a chance here)
    np.testing.assert_allclose(search.detection_chances(), chance, atol=1e-7)
    # the next point: of the cells within 5 % of the best chance, the nearest to x0
    good = chance >= 0.95 * chance.max()
    i, j = np.unravel_index(np.argmin(np.where(good, np.hypot(gx, gy), np.inf)), chance.shape)
    np.testing.assert_allclose(search.next_point(), [xs[j], ys[i]])


def test_the_evidence_counts_the_optima_inside_the_bounds_so_quiet_values_end_the_search():
    # the disc of 20° around x0 = (0, 0) half beyond tilt_x = 0: quiet values on a 2°
    # lattice of the other half bring the evidence below 1e-3 (before it counted the
    # mass beyond the bounds, which no measurement depletes: a search with no echo in reach
    # never gave up)
    search = _search(bounds=((0.0, 30.0), (-30.0, 30.0)))
    grid = np.arange(0.0, 21.0, 2.0)
    for x in grid:
        for y in np.arange(-20.0, 21.0, 2.0):
            if np.hypot(x, y) <= 21.0:
                search.update(np.array([[x, y]]), np.array([0.0]))
    assert search.log_evidence() < np.log(1e-3)


def test_a_start_whose_disc_misses_the_bounds_is_refused():
    with pytest.raises(EchocalValueError, match="move the start inside"):
        _search(bounds=((25.0, 30.0), (-30.0, 30.0)))


def test_the_next_point_stays_inside_the_bounds():
    search = _search(bounds=((2.0, 30.0), (-30.0, 30.0)))
    search.update(np.array([[-10.0, 0.0]]), np.array([6.0]))  # the echo is out of bounds
    assert search.next_point()[0] >= 2.0


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("echo", np.array([1.0, np.nan]), "echo must be finite"),
        ("angles", np.array([0.5, 1.0]), "angles must increase from 0"),
        ("n_cells", 0.0, "n_cells must be finite and > 0"),
        ("threshold", np.inf, "threshold must be finite and > 0"),
        ("echo", np.array([1.0]), "one length"),
    ],
)
def test_bad_likelihoods_are_refused(field, value, match):
    kw = {"angles": np.array([0.0, 1.0]), "echo": np.ones(2), "n_cells": M, "threshold": 4.0}
    kw[field] = value
    with pytest.raises(EchocalValueError, match=match):
        EchoLikelihood(**kw)


def test_a_cell_that_measured_nan_is_not_proposed_again():
    search = _search()
    first = search.next_point()
    search.exclude(first)
    assert not np.allclose(search.next_point(), first)


class _Scripted:
    """A detector whose significances the test sets before each tell."""

    def __init__(self) -> None:
        self.next: np.ndarray | None = None

    def __call__(self) -> np.ndarray | None:
        return self.next


def _acquisition(detector: _Scripted):
    from echocal.calibrate import Acquisition

    like = _likelihood()
    return Acquisition(
        np.zeros(2), detector=detector, echo_likelihood=lambda: like, posterior=True,
        noise_sigma=1.0, max_radius=10.0,
    )  # fmt: skip


def _tell(acq, detector: _Scripted, sig, values=None) -> np.ndarray:
    points = acq.ask()
    if sig is None or isinstance(sig, np.ndarray):
        detector.next = sig  # as given: None, or an array of any shape
    else:
        detector.next = np.full(len(points), sig, dtype=float)
    acq.tell(np.zeros(len(points)) if values is None else values(len(points)))
    return points


def test_the_acquisition_hands_a_quiet_first_ring_to_the_posterior_and_nan_is_no_evidence():
    detector = _Scripted()
    acq = _acquisition(detector)
    _tell(acq, detector, 0.0)  # x0 and its first ring: quiet
    assert acq.search is not None
    evidence = acq.search.log_evidence()
    _tell(acq, detector, np.nan)  # no noise estimate: no evidence either way
    assert acq.search.log_evidence() == pytest.approx(evidence)
    measured = _tell(acq, detector, 0.0, values=lambda k: np.full(k, np.nan))[0]
    assert not np.allclose(acq.ask()[0], measured)  # a NaN point is not asked again


def test_when_the_detector_stops_the_search_goes_back_to_the_lattice():
    detector = _Scripted()
    acq = _acquisition(detector)
    _tell(acq, detector, 0.0)
    assert acq.search is not None
    with pytest.warns(UserWarning, match="tests the values instead"):
        _tell(acq, detector, np.zeros(3))  # a wrong shape: the detector is dropped
    assert acq.search is None
    lattice = acq.ask()[0]
    np.testing.assert_allclose(lattice, acq._queue[acq._next])  # the lattice's next point
