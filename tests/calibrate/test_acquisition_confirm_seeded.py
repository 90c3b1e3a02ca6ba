"""Issue 15, item 5: the acquisition phase confirms a find before the local method gets it.

A seeded 20 dB run on the 5 MHz probe's narrow lobe (ray model), started 2.5° from the
optimum, in which noise is the first thing to cross the detection threshold: x0's
neighbourhood scores above ``first_threshold`` (3σ) but below ``threshold`` + 2, and the
echo is in fact out of reach there.  Unconfirmed (``confirm=False``) the noise point goes
to the local method at 7 measurements (which used to end about 4.6° off; since the local
method fits what it is handed before its first step, it finds the echo from there on this
seed); confirmed, the one re-measurement drops it, the search goes on, finds the echo and
ends within 0.05°.
Measured over 100 such seeded runs (seeds 1000–1099 of the benchmark's scheme, ray model,
budget 80): 2 runs ended > 1° off unconfirmed, 1 confirmed (a confirmed noise point, which
the run then reports as status 9, "no echo at the estimate", not as a success).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from echocal.calibrate import calibrate
from echocal.evaluation import angular_error
from echocal.measurement import ReceiverSettings, SourceObjective
from echocal.setups import load_setup

SEED = 4069856663
"""np.random.SeedSequence([0, 0, 20, 1000]).generate_state(1)[0]: the benchmark's seed of
run 1000 of the near starts at 20 dB on its first case."""
DIRECTION = 341.6866405150541
"""[deg] the start's direction from the optimum (the benchmark's draw for that seed)."""


def _run(confirm: bool) -> tuple[float, object, np.ndarray]:
    base = load_setup("immersion-5mhz-ray", seed=0)
    pos = np.asarray(base.reference_position, float)
    truth = np.array(base.true_optimum(pos, parameterization="tilt"))
    setup = dataclasses.replace(base, receiver=ReceiverSettings(snr_db=20.0), rng=SEED)
    cone = np.radians(max(abs(v) for v in setup.limits.coelevation))
    half = float(np.degrees(np.arccos(np.sqrt(np.cos(cone))))) - 1e-6
    objective = SourceObjective(
        setup, pos, parameterization="tilt", budget=80, bounds=[[-half, half], [-half, half]]
    )
    x0 = truth + 2.5 * np.array([np.cos(np.radians(DIRECTION)), np.sin(np.radians(DIRECTION))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = calibrate(
            objective,
            "auto",
            x0=x0,
            budget=80,
            max_iter=10_000,
            rng=SEED,
            confirm=confirm,
            settle=None,
        )
    err = float(angular_error(np.asarray(res.x)[None], truth, "tilt")[0])
    first = angular_error(objective.log.points[:7], truth, "tilt")  # [deg]
    return err, res, first


@pytest.mark.slow
def test_a_noise_crossing_is_confirmed_away_before_the_local_method_gets_it():
    err, res, _ = _run(confirm=True)
    assert res.acquisition_measurements > 8  # the first crossing was not handed over
    assert err < 0.05, (err, res.status)


@pytest.mark.slow
def test_without_confirmation_the_same_run_hands_noise_on():
    # the control: the seed really is a noise-first case (else the test above proves
    # nothing): unconfirmed, the search hands over after x0 and its first ring, none of
    # which lies within 1.5° of the optimum (the ray model's 20 dB echo is detected within
    # 1.1°); the local phase then refutes that false alarm and the search resumes
    _, res, first = _run(confirm=False)
    assert res.false_alarms >= 1  # x0 and its first ring: noise crossed 3σ
    assert res.acquisition_measurements > 7  # the search resumed after it
    assert first.min() > 1.5  # the echo was out of reach of all 7
