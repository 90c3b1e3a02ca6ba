"""The seek from a detection in the lobe's tail (``echocal.calibrate.lobe_template.seek_point``).

Independent truth: the far-field piston lobe with a broadband tail that the lobe template's
tests build (``_piston``: 0.09·e^(−θ/0.8°) beyond the main lobe), whose tail the tests
invert by hand; the peak's position, which the tests choose.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests.calibrate.test_lobe_template import ANGLES, _measurements_to_stay_within, _piston

from echocal.calibrate import FunctionObjective, calibrate
from echocal.calibrate.lobe_template import LobeTemplate, TemplateSteps, seek_point, tail_reach

PEAK, SIGMA = 100.0, 0.05
"""The echo at the lobe's peak and the noise σ (objective units): the tail is 3 σ up to
0.8°·ln(0.09 · 100 / 0.15) = 3.28° out."""


@pytest.fixture(scope="module")
def template() -> LobeTemplate:
    return LobeTemplate(ANGLES, np.zeros(1), _piston(135.0)[None, :], peak=PEAK)


def test_the_tail_reaches_where_it_falls_to_three_sigma(template):
    # 100 · 0.09 e^(−θ/0.8) ≥ 3 · 0.05  ⇔  θ ≤ 0.8 ln 60 = 3.275°: 3.2 on the 0.1° grid
    assert tail_reach(template, PEAK, SIGMA) == pytest.approx(3.2)
    assert tail_reach(template, PEAK, 1e3) == 0.0  # a peak below the noise is seen nowhere


def _seek(template, points: np.ndarray, truth: np.ndarray) -> np.ndarray:
    values = PEAK * template(points - truth)  # noiseless: what the seek makes of them
    point = seek_point(
        template, points, values, np.full(len(values), SIGMA), SIGMA, PEAK, np.zeros(2), 6.0
    )
    assert point is not None
    return point


def test_one_tail_value_sends_the_seek_onto_the_arc_it_implies(template):
    """The tail value 3° out (0.21, 4 σ) says how far the peak is, not where: the seek
    measures 1.5–4.5° from the detection, where the candidates on the arc disagree, never
    at the detection, where they all predict the value measured there."""
    point = _seek(template, np.zeros((1, 2)), truth=np.array([3.0, 0.0]))
    assert 1.5 <= math.hypot(*point) <= 4.5


def test_directions_measured_empty_are_not_sought_again(template):
    """With the arc's other three quarters measured (3° out at 90°, 180° and 270°: a peak
    within about 3° of those points would have shown there), the seek goes toward the
    remaining quarter, where the peak is (0°)."""
    points = np.array([[0.0, 0.0], [-3.0, 0.0], [0.0, 3.0], [0.0, -3.0]])
    point = _seek(template, points, truth=np.array([3.0, 0.0]))
    assert abs(math.degrees(math.atan2(point[1], point[0]))) <= 60.0


def _from_the_tail(template, seed: int, seek: bool, monkeypatch) -> int | None:
    """``model-based`` warm-started at a detection 3.8° out in the tail (measured twice,
    0.08 each: 1.6 σ) with five points of the search around it, 3.8° out, all at the noise:
    the measurements after which it stays within 0.1° of the peak."""
    truth = np.array([1.3, -0.6])
    x0 = truth + 3.8 * np.array([-math.sqrt(0.75), -0.5])
    dirs = np.deg2rad([150.0, 210.0, 270.0, 90.0, 330.0])
    history = np.vstack([x0, x0, x0 + 3.8 * np.column_stack([np.cos(dirs), np.sin(dirs)])])

    def echo(points: np.ndarray) -> np.ndarray:
        return PEAK * template(np.atleast_2d(points) - truth) + 1.0

    noise = np.random.default_rng(100 + seed).standard_normal(len(history))
    objective = FunctionObjective(echo, noise_sigma=SIGMA, noise_floor=1.0, budget=30, rng=seed)
    if not seek:
        monkeypatch.setattr(TemplateSteps, "_start_seek", lambda self: False)
    result = calibrate(
        objective,
        method="model-based",
        x0=x0,
        budget=30,
        rng=seed,
        settle=None,
        history=(history, echo(history) + SIGMA * noise),
        lobe_template=lambda: template,
    )
    monkeypatch.undo()
    return _measurements_to_stay_within(result, truth, 0.1)


def test_the_seek_climbs_from_deep_in_the_tail_faster_than_the_design(template, monkeypatch):
    """Twelve seeds: with the seek every run stays within 0.1° after at most 5 measurements
    (2–4 measured); with the 1° design hexagon around the detection instead (the method
    before the seek), after 3–10 (median 8.5)."""
    counts = {
        seek: [_from_the_tail(template, seed, seek, monkeypatch) for seed in range(12)]
        for seek in (True, False)
    }
    assert None not in counts[True] and None not in counts[False], counts
    assert max(counts[True]) <= 5, counts  # type: ignore[type-var]  # measured 4, +1
    assert np.median(counts[True]) + 3 <= np.median(counts[False]), counts  # type: ignore[arg-type]


def test_a_seek_on_noise_ends_after_its_eight_measurements(template):
    """A false alarm handed on (every value pure noise): the seek measures at most
    ``_SEEK_MAX`` points, then the usual steps go on; each seek point lies within the
    candidates' reach of the detection."""
    from echocal.calibrate.lobe_template import _SEEK_MAX
    from echocal.calibrate.model_based import ModelBased

    rng = np.random.default_rng(7)
    history = np.vstack([np.zeros(2), 3.0 * np.eye(2), -3.0 * np.eye(2)])
    opt = ModelBased(
        np.zeros(2),
        history=(history, 1.0 + SIGMA * rng.standard_normal(len(history))),
        noise_model=lambda: (1.0, SIGMA),
        lobe_template=lambda: template,
        rng=0,
    )
    assert opt._seeks_left == _SEEK_MAX
    reach = max(opt.max_radius, tail_reach(template, PEAK, SIGMA))  # 4°: the design's 4 × 1°
    for n in range(_SEEK_MAX + 4):
        point = opt.ask()
        assert n >= _SEEK_MAX or np.hypot(*point[0]) <= reach + 1e-9
        opt.tell(1.0 + SIGMA * rng.standard_normal(1))
    assert opt._seeks_left == 0


def test_no_seek_without_a_noise_or_a_peak(template):
    """A noise σ or a peak of 0 is refused in one line (the spread would be NaN, the
    prior infinite); a template whose peak is 0 starts no seek."""
    from echocal.calibrate.model_based import ModelBased
    from echocal.errors import EchocalValueError

    points, values = np.zeros((1, 2)), np.array([0.2])
    for sigma, peak in ((0.0, PEAK), (SIGMA, 0.0)):
        with pytest.raises(EchocalValueError, match="sigma > 0 and a peak metric > 0"):
            seek_point(template, points, values, np.ones(1), sigma, peak, np.zeros(2), 4.0)
    flat = LobeTemplate(template.angles, template.directions, template.values, peak=0.0)
    opt = ModelBased(
        np.zeros(2),
        history=(points, 1.0 + values),
        noise_model=lambda: (1.0, SIGMA),
        lobe_template=lambda: flat,
    )
    assert opt._seeks_left == 0
