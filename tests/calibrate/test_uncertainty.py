"""The 90 % radius a calibration reports: it covers the optimum at its stated level on a
peak whose truth the test knows, and the benchmark's coverage count is exact."""

from __future__ import annotations

import numpy as np

from echocal.calibrate import FunctionObjective, calibrate
from echocal.calibrate.evidence import UNCERTAINTY_LEVEL, coverage, estimate_radius
from echocal.calibrate.local_model import hexagon

PEAK = np.array([0.23, -0.11])
"""[deg] the true optimum."""
WIDTH = 0.6
"""[deg] the Gaussian lobe's width."""


def _lobe(points: np.ndarray, amplitude: float) -> np.ndarray:
    r2 = np.sum((np.atleast_2d(points) - PEAK) ** 2, axis=1)
    return amplitude * np.exp(-r2 / (2.0 * WIDTH**2))


def _design(rng: np.random.Generator) -> np.ndarray:
    """What a refined run leaves around its estimate: two hexagons (0.3°, 0.6°) and a few
    scattered points, centred up to 0.1° off the peak."""
    centre = PEAK + rng.uniform(-0.1, 0.1, 2)
    extra = centre + rng.uniform(-0.8, 0.8, (6, 2))
    return np.vstack([hexagon(centre, 0.3), hexagon(centre, 0.6)[1:], extra])


def test_the_radius_covers_the_optimum_at_its_level():
    # 300 seeded designs with noise σ = 1 on a peak of 30 (a ~30 dB echo's energy), floor
    # 2: the exact truth PEAK is known.  The estimate is the best measured point (a crude
    # one: the radius must cover its own distance to the fitted peak too).  With 300 runs
    # a true coverage of 0.90 is measured within ±0.035 (2 binomial σ); the radius must not
    # be vacuous either: its median stays below the lobe's width.
    rng = np.random.default_rng(44)
    covered, radii = [], []
    for _ in range(300):
        pts = _design(rng)
        vals = 2.0 + _lobe(pts, 30.0) + rng.standard_normal(len(pts))
        x = pts[int(np.argmax(vals))]
        r = estimate_radius(x, pts, vals, (2.0, 1.0))
        assert r is not None
        radii.append(r)
        covered.append(np.hypot(*(x - PEAK)) <= r)
    assert UNCERTAINTY_LEVEL == 0.9
    assert np.mean(covered) >= UNCERTAINTY_LEVEL - 0.035, np.mean(covered)
    assert np.median(radii) < WIDTH


def test_no_radius_without_a_noise_model_or_a_peak():
    rng = np.random.default_rng(1)
    pts = _design(rng)
    vals = 2.0 + _lobe(pts, 30.0)
    assert estimate_radius(PEAK, pts, vals, (None, 1.0)) is None
    assert estimate_radius(PEAK, pts, vals, (2.0, None)) is None
    flat = 2.0 + rng.standard_normal(len(pts))  # noise only: no lobe's top to fit
    r = estimate_radius(PEAK, pts, np.minimum(flat, 2.0), (2.0, 1.0))
    assert r is None


def test_a_calibration_reports_its_radius_and_level():
    obj = FunctionObjective(lambda p: 2.0 + _lobe(p, 30.0), noise_sigma=1.0, noise_floor=2.0, rng=7)
    res = calibrate(obj, "auto", x0=(0.8, 0.5), budget=60, rng=7)
    assert res.uncertainty is not None and res.uncertainty_level == UNCERTAINTY_LEVEL
    assert 0.0 < res.uncertainty < WIDTH
    back = type(res).from_dict(res.to_dict())
    assert back.uncertainty == res.uncertainty


def test_the_coverage_count_is_exact():
    errors = np.array([0.01, 0.05, 0.2, 0.03])
    radii = [0.02, 0.04, None, 0.03]  # covered, not, none reported, covered (on the edge)
    cov, reported = coverage(errors, radii)
    assert cov == 0.5 and reported == 0.75
