"""Seeded regressions of ``auto`` on the wave model, with their measurement counts locked.

As scipy locks its optimizers' function-evaluation counts: a change to ``auto`` may make
these counts smaller, never larger, without updating this file and the benchmark pages.
The counts are the measurements after which the estimate stays within 0.1° of the true
optimum (every later iterate included).

One seed's count is not a stable lock: between two fresh installs of the same pinned
requirements, seed 5 went from 60 to 72 measurements and seed 3 from 64 to 54 (a last-bit
difference in a least-squares fit sends the search down another path).  The lock is
therefore on the median over twelve seeds, which moved by less than that; every run must
also reach 0.1° within the budget.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from tests.run_helpers import measurements_to_stay_within, tilt_errors

from echocal.calibrate import calibrate
from echocal.measurement import ReceiverSettings, SourceObjective, VirtualSetup
from echocal.setups import load_setup, setup_with_overrides

SEEDS = range(12)
LOCKED_MEDIAN = 17.5
"""Median measurements to stay within 0.1° over :data:`SEEDS` from the 30 dB start below
(measured 15.5 (17, 17, 12, 13, 16, 13, 15, 20, 13, 12, 16, 16) since the search beyond x0's
first ring follows the posterior over the optimum
(:mod:`echocal.calibrate.posterior_search`): this start, 9.4° out, lies on the first ring of
the 8.62° pass it searched before, and the posterior's first points go 10–11° out, where
a detection is as likely; over the benchmark's 100 far starts at 30 dB the p99 went from 26
to 24 and at 20 dB from 99 to 59 (the 20 dB lock below); 13 since a
detection the lobe template does not fit yet seeks the peak where the candidate peaks
disagree, not with a 1° hexagon (13, 18, 11, 13, 11, 10, 14, 13, 14, 15, 11, 14); 16.5
since the lobe template's fit keeps its previous peak unless the data clearly prefer
another (13, 22, 11, 21, 18, 10, 20, 20, 13, 15, 11, 19); 17 since a warm start whose
history the lobe template already fits steps to its peak without a hexagon (13, 22, 11,
21, 20, 10, 20, 20, 12, 15, 11, 19); 19.5 since the local method follows the probe's
lobe from its tail (18, 22, 16, 21, 20, 15, 20, 20, 17, 19, 15, 20), 25 since the search
is sized for the echo predicted against the measured noise — no 1° lattice out to 3° at
30 dB —, 54.5 with the search in passes before, 56 before that; 2 of margin for the
fresh-install jitter above; must not grow)."""
LOCKED_MEDIAN_20DB = 31
"""Median measurements to stay within 0.1° over :data:`SEEDS` from the 20 dB start below
(measured 29 since the posterior search: 31, 25, 28, 29, 18, 30, 39, 31, 29, 31, 22, 20;
with the 4.17° pass sized for the echo instead, ``posterior=False``, 73, 43, 62 and 37 on
the first four seeds; 2 of margin for the fresh-install jitter; must not grow)."""
BUDGET = 80
BUDGET_20DB = 120


@functools.cache
def _physics(specimen: str | None) -> VirtualSetup:
    """``immersion-5mhz`` (over the built-in ``specimen``), built once per process."""
    return setup_with_overrides("immersion-5mhz", specimen=specimen)


def _setup(specimen: str | None, snr: float, seed: int) -> VirtualSetup:
    """``setup_with_overrides("immersion-5mhz", specimen=..., snr_db=snr, seed=seed)`` with
    the physics objects shared: the lobe profile that sizes the search (48 s for this probe
    over the ball) is computed once per position, not once per case."""
    base = _physics(specimen)
    return dataclasses.replace(
        base, receiver=dataclasses.replace(base.receiver, snr_db=snr), rng=seed
    )


@functools.cache
def _truth(specimen: str | None, position: tuple[float, ...]) -> np.ndarray:
    """[deg] the noiseless optimum in tilt at ``position`` [m] (5 s over the ball)."""
    return np.array(_physics(specimen).true_optimum(np.array(position), parameterization="tilt"))


def _measurements_to_stay_within(
    seed: int, snr: float, offset: tuple[float, float], budget: int, tolerance: float = 0.1
) -> int | None:
    """``immersion-5mhz`` (12.7 mm, 5 MHz, wave model) at ``snr`` [dB], start ``offset``
    [deg] off the true optimum in tilt: the measurements after which every iterate is
    within ``tolerance`` [deg], or None."""
    setup = _setup(None, snr, seed)
    position = setup.reference_position
    truth = _truth(None, tuple(position))
    objective = SourceObjective(setup, position, parameterization="tilt")
    x0 = tuple(truth + np.array(offset))
    result = calibrate(objective, method="auto", x0=x0, budget=budget, rng=seed, settle=None)
    assert result.n_measurements == objective.n_measurements <= budget  # every one counted
    return measurements_to_stay_within(result, tilt_errors(result, truth), tolerance)


@pytest.mark.parametrize(
    ("snr", "offset", "budget", "locked"),
    [
        (30.0, (8.0, -5.0), BUDGET, LOCKED_MEDIAN),  # 9.4° out
        (20.0, (9.0, -9.0), BUDGET_20DB, LOCKED_MEDIAN_20DB),  # 12.7° out
    ],
)
@pytest.mark.slow  # 18 and 34 CPU-s: the slow tier
def test_auto_from_a_far_start_on_the_wave_model(snr, offset, budget, locked) -> None:
    reached = {s: _measurements_to_stay_within(s, snr, offset, budget) for s in SEEDS}
    missed = [seed for seed, n in reached.items() if n is None]
    assert not missed, f"seeds {missed} never stayed within 0.1° in {budget} measurements"
    median = float(np.median(list(reached.values())))
    assert median <= locked, f"median {median} measurements to 0.1°: {reached}"


# Over the built-in sphere (ball r = 25 mm) a 12.7 mm probe 50 mm above it is in its near
# field: the noiseless lobe is a central peak (0.3° to half energy), a dip to about 0.3
# of it at 0.8° and a ring at about 0.8 of it 1.6° out.  ``auto`` used to climb the ring
# (or fit a quadratic across peak and ring) and end 1.0–1.7° off from every such start.  The
# benchmark's ``sphere-12.7`` cell (docs/benchmarks/curved.md) measures the same on 20
# seeded starts per SNR.
# (position [mm], snr [dB], seed, start offset from the truth [deg]): the old code never
# stayed within 0.1° within 60 measurements from the two 10 dB cases, nor from starts 1.8°
# out on the ring above the ball's centre at 30 dB.  The 30 dB starts here lie on the ring
# too (its matched-filter peak, the largest of 4 directions, is 0.95–0.97 of the centre's
# 1.5–2° out), at the 10 dB cases' off-axis position: the test computes one lobe profile of
# the ball (≈ 70 s: 460 noiseless A-scans), not two.
SPHERE_CASES = (
    ((4.0, 2.0, 50.0), 30.0, 0, (1.8, 0.0)),
    ((4.0, 2.0, 50.0), 30.0, 2, (0.0, 1.8)),
    ((4.0, 2.0, 50.0), 10.0, 1, (2.214, 0.219)),
    ((4.0, 2.0, 50.0), 10.0, 5, (1.055, -0.492)),
)
SPHERE_LOCKED_MEDIAN = 12
"""Median measurements to stay within 0.1° over :data:`SPHERE_CASES` (must not grow; a
median, as for the far start above; 3.5 of margin, since a median of four moves with one
case).  Measured 8.5 (8, 8, 9, 12; the same with the 30 dB starts above the centre, before
they moved off-axis) since the local method fits the lobe's template with
its ring (the fit tells the ring from the central peak, only the main lobe counts as the
top, and a fitted peak is kept unless the data clearly prefer another); before, 32 (29,
29, 41, 35) with a log-quadratic refuted and refitted on a smaller neighbourhood, and
29.5 (30, 29, 30, 29) before the local method fitted what the acquisition handed it."""


def _sphere_measurements(case) -> int | None:
    """``immersion-5mhz`` with the ``sphere`` specimen, budget 60: the measurements after
    which every iterate stays within 0.1°, or None."""
    position_mm, snr, seed, offset = case
    setup = _setup("sphere", snr, seed)
    position = np.array(position_mm) * 1e-3
    truth = _truth("sphere", tuple(position))
    objective = SourceObjective(setup, position, parameterization="tilt")
    x0 = tuple(truth + np.array(offset))
    result = calibrate(objective, method="auto", x0=x0, budget=60, rng=seed, settle=None)
    assert result.n_measurements == objective.n_measurements <= 60  # every one counted
    return measurements_to_stay_within(result, tilt_errors(result, truth), 0.1)


@pytest.mark.slow  # 126 CPU-s (48 of them the lobe profile over the ball): the slow tier
def test_auto_over_the_sphere_finds_the_central_peak() -> None:
    reached = [_sphere_measurements(case) for case in SPHERE_CASES]
    missed = [case for case, n in zip(SPHERE_CASES, reached, strict=True) if n is None]
    assert not missed, f"never stayed within 0.1° in 60 measurements: {missed}"
    median = float(np.median([n for n in reached if n is not None]))
    assert median <= SPHERE_LOCKED_MEDIAN, f"median {median} measurements to 0.1°: {reached}"


def test_auto_does_not_circle_the_trust_circle_after_a_refuted_fit() -> None:
    """The benchmark's far start at 30 dB, run 16 (``bench_calibration``'s seed, start and
    tilt box, rebuilt here by the same formulas): the local model's fit was refuted by a
    lobe top 1.7× above its maximum, the fit's residuals put its log-space noise at 40,
    every trust-region step passed and the last 36 measurements circled 4° out — the run
    never stayed within 0.1°.  With the noise capped (a factor e) once the incumbent is a
    significant echo, and the search across a ridge ended where the lobe has fallen
    away, it stayed within 0.1° after 35, and after 21 since the local method follows the
    probe's lobe from its tail, after 15 since a detection the template does not fit yet
    seeks the peak; locked at 26 (the far cell's 99th percentile: one seed's count
    jitters between installs, see the module doc)."""
    seed = 887101703  # bench_calibration.run_seed("immersion-5mhz", "far", 30.0, 16)
    base = load_setup("immersion-5mhz", seed=0)
    setup = dataclasses.replace(base, receiver=ReceiverSettings(snr_db=30.0), rng=seed)
    position = setup.reference_position
    truth = np.array(setup.true_optimum(position, parameterization="tilt"))
    # bench_calibration.tilt_bounds: the objective's default tilt box, 1e-6° inside
    half = float(SourceObjective(setup, position, parameterization="tilt").bounds[0, 1]) - 1e-6
    # bench_calibration.start_point: uniform distance in 5–20°, uniform direction
    rng = np.random.default_rng(seed)
    dist, angle = rng.uniform(5.0, 20.0), rng.uniform(0.0, 2.0 * np.pi)
    x0 = truth + dist * np.array([np.cos(angle), np.sin(angle)])
    assert np.all(np.abs(x0) <= half)  # the benchmark's first draw: no redraw needed
    objective = SourceObjective(
        setup, position, parameterization="tilt", budget=BUDGET, bounds=[[-half, half]] * 2
    )
    result = calibrate(
        objective, method="auto", x0=x0, budget=BUDGET, max_iter=10_000, rng=seed, settle=None
    )
    assert result.n_measurements == objective.n_measurements <= BUDGET  # every one counted
    reached = measurements_to_stay_within(result, tilt_errors(result, truth), 0.1)
    assert reached is not None, "never stayed within 0.1°"
    assert reached <= 26, f"within 0.1° after {reached}"
