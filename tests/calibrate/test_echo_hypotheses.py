"""The posterior search over an echo of unknown amplitude (and lobe width):
:mod:`echocal.calibrate.posterior_search` and its use in
:class:`~echocal.calibrate.posterior_search.PosteriorSearch`.

Independent truth: the mixture's posterior, evidence and detection chances are what Bayes'
rule makes of one single-hypothesis search per hypothesis (each the plain, separately
tested :class:`PosteriorSearch`), combined here by hand; the Lorentzian lobes by their
closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import logsumexp, ndtr

from echocal.calibrate.posterior_search import (
    AMPLITUDE_DB,
    WIDTHS,
    EchoHypotheses,
    EchoLikelihood,
    PosteriorSearch,
    lorentzian_lobes,
    scaled_lobe,
)
from echocal.errors import EchocalValueError

M = 300.0
"""Rice's level-crossing constant of a synthetic window."""
THRESHOLD = float(brentq(lambda t: np.exp(-M * t * np.exp(-0.5 * t * t)) - ndtr(4.5), 1.0, 20.0))
BOUNDS = np.array([[-30.0, 30.0], [-30.0, 30.0]])  # wider than the prior: every cell counts
ANGLES = np.arange(0.0, 6.0 + 1e-9, 0.05)


def _like(peak: float, width: float) -> EchoLikelihood:
    echo = peak / (1.0 + (ANGLES / width) ** 2)
    return EchoLikelihood(angles=ANGLES, echo=echo, n_cells=M, threshold=THRESHOLD)


def _measure(searches: list[PosteriorSearch]) -> None:
    """The same significances at the same points into every search: noise everywhere but
    a weak echo near (3, -2) deg."""
    rng = np.random.default_rng(7)
    points = rng.uniform(-6.0, 6.0, size=(25, 2))
    g = rng.normal(size=25)
    g[np.hypot(*(points - (3.0, -2.0)).T) < 1.5] += 3.0
    for search in searches:
        search.update(points, g)


def test_hypotheses_are_bayes_rule_over_single_hypothesis_searches():
    likes = [_like(30.0, 0.6), _like(12.0, 1.5), _like(30.0, 1.5)]
    log_w = np.log([0.5, 0.3, 0.2])
    mixed = PosteriorSearch(
        np.zeros(2), 8.0, EchoHypotheses(tuple(likes), log_w, label="test"), BOUNDS
    )
    singles = [PosteriorSearch(np.zeros(2), 8.0, like, BOUNDS) for like in likes]
    assert {s.cell for s in singles} == {mixed.cell}  # one grid: the sums compare cell by cell
    _measure([mixed, *singles])
    evidence = np.array([s.log_evidence() for s in singles])
    # the evidence of the mixture: Σ_h w_h Z_h
    assert mixed.log_evidence() == pytest.approx(logsumexp(log_w + evidence), abs=1e-10)
    # the posterior over the optimum: Σ_h P(h | data) post_h, P(h | data) ∝ w_h Z_h
    p_h = np.exp(log_w + evidence - logsumexp(log_w + evidence))
    assert p_h.min() > 1e-3  # every hypothesis still matters: the test can tell them apart
    expected = sum(p * np.exp(s.log_posterior()) for p, s in zip(p_h, singles, strict=True))
    np.testing.assert_allclose(np.exp(mixed.log_posterior()), expected, rtol=1e-9, atol=1e-15)
    # the chance of a detection: the same weights over each hypothesis's chances
    chances = sum(p * s.detection_chances() for p, s in zip(p_h, singles, strict=True))
    np.testing.assert_allclose(mixed.detection_chances(), chances, rtol=1e-9, atol=1e-12)


def test_one_hypothesis_is_the_plain_likelihood():
    like = _like(30.0, 0.6)
    plain = PosteriorSearch(np.zeros(2), 8.0, like, BOUNDS)
    one = PosteriorSearch(np.zeros(2), 8.0, EchoHypotheses((like,), np.zeros(1)), BOUNDS)
    _measure([plain, one])
    np.testing.assert_array_equal(one.log_posterior(), plain.log_posterior())
    np.testing.assert_array_equal(one.next_point(), plain.next_point())
    assert one.log_evidence() == plain.log_evidence()


def test_lorentzian_lobes_are_the_closed_form_at_each_width_and_amplitude():
    family = lorentzian_lobes(M, THRESHOLD)
    assert len(family.likelihoods) == len(WIDTHS) * len(AMPLITUDE_DB)
    np.testing.assert_allclose(np.exp(family.log_weights), 1.0 / len(family.likelihoods))
    theta = family.angles
    for i, like in enumerate(family.likelihoods):
        w, a_db = WIDTHS[i // len(AMPLITUDE_DB)], AMPLITUDE_DB[i % len(AMPLITUDE_DB)]
        np.testing.assert_allclose(
            like.echo, 10.0 ** (a_db / 20.0) / (1.0 + (theta / w) ** 2), rtol=1e-12
        )
        assert (like.n_cells, like.threshold) == (M, THRESHOLD)


def test_a_scaled_lobe_keeps_its_shape_at_every_amplitude():
    shape = 4.0 * np.exp(-ANGLES)  # not normalized: the hypotheses normalize it
    family = scaled_lobe(ANGLES, shape, M, THRESHOLD, amplitudes_db=(20.0, 40.0))
    np.testing.assert_allclose(family.likelihoods[0].echo, 10.0 * np.exp(-ANGLES), rtol=1e-12)
    np.testing.assert_allclose(family.likelihoods[1].echo, 100.0 * np.exp(-ANGLES), rtol=1e-12)


def test_hypotheses_of_another_detector_are_refused():
    other = EchoLikelihood(angles=ANGLES, echo=ANGLES * 0 + 1, n_cells=2 * M, threshold=THRESHOLD)
    with pytest.raises(EchocalValueError, match="share the angles, n_cells and threshold"):
        EchoHypotheses((_like(30.0, 0.6), other), np.zeros(2))
    with pytest.raises(EchocalValueError, match="one per likelihood"):
        EchoHypotheses((_like(30.0, 0.6),), np.zeros(2))
