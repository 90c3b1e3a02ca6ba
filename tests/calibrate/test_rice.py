"""Rice's law on scipy.special (no scipy.stats import): checked against closed forms and
against scipy.stats.rice, which the calibration used before."""

from __future__ import annotations

import numpy as np
import scipy.stats

from echocal.calibrate.posterior_search import rice_cdf, rice_sf


def test_rice_with_no_echo_is_rayleigh():
    # b = 0: Rayleigh, P(R <= x) = 1 - exp(-x^2 / 2) (closed form); 1e-12: round-off
    x = np.linspace(0.0, 6.0, 61)
    np.testing.assert_allclose(rice_cdf(x, 0.0), 1.0 - np.exp(-(x**2) / 2.0), atol=1e-12)
    np.testing.assert_allclose(rice_sf(x, 0.0), np.exp(-(x**2) / 2.0), atol=1e-12)


def test_rice_agrees_with_scipy_stats():
    # the same non-central chi-square CDF underneath: agreement to round-off (1e-12)
    x = np.linspace(0.0, 12.0, 97)[:, None]
    b = np.array([0.0, 0.5, 2.0, 5.0, 9.0])[None, :]
    np.testing.assert_allclose(rice_cdf(x, b), scipy.stats.rice.cdf(x, b), atol=1e-12)
    np.testing.assert_allclose(rice_sf(x, b), scipy.stats.rice.sf(x, b), atol=1e-12)
