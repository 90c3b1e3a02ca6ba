"""Property: every measurement is counted and no run ever exceeds its budget.

Whatever the method, repeats, acquisition phase, final check, objective budget
and noise, ``calibrate`` must (a) never measure more than ``min(budget,
objective.budget)``, (b) report exactly the measurements the objective made,
and (c) log each of them (points and values, in order).
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import gaussian
from echocal.calibrate import FunctionObjective, calibrate, method_names
from echocal.errors import EchocalValueError

METHODS = tuple(method_names())


@settings(max_examples=80)
@given(
    method=st.sampled_from(METHODS),
    budget=st.integers(8, 80),
    objective_budget=st.one_of(st.none(), st.integers(20, 80)),
    repeats=st.integers(1, 3),
    acquire=st.booleans(),
    final_check=st.integers(0, 4),
    noise=st.sampled_from([0.0, 0.05]),
    seed=st.integers(0, 3),
)
def test_budget_is_never_exceeded_and_every_measurement_counted(
    method, budget, objective_budget, repeats, acquire, final_check, noise, seed
):
    obj = FunctionObjective(
        gaussian,
        budget=objective_budget,
        repeats=repeats,
        noise_sigma=noise,
        rng=seed,
        bounds=[[-10, 10], [-10, 10]],
    )
    limit = budget if objective_budget is None else min(budget, objective_budget)
    try:
        res = calibrate(
            obj,
            method,
            x0=(1.5, 1.0),
            budget=budget,
            max_iter=200,
            rng=seed,
            acquire=acquire,
            final_check=final_check,
        )
    except EchocalValueError as exc:
        # only allowed refusal: the budget is below one iteration, and nothing was measured
        assert "smaller than one iteration" in str(exc)
        assert obj.n_measurements == 0
        return
    assert obj.n_measurements <= limit
    assert res.n_measurements == obj.n_measurements
    assert len(res.points) == len(res.values) == len(res.times) == res.n_measurements
    assert res.iteration_measurements[-1] <= res.n_measurements
    assert np.all(np.diff(res.iteration_measurements) >= 0)
