"""The calibrate() driver: stopping rules, bad input, NaN policy, result round-trip, presets."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import OPT, gaussian
from echocal.calibrate import (
    STATUS_MESSAGES,
    CalibrationResult,
    FunctionObjective,
    calibrate,
    method_options,
    preset_names,
    presets,
)
from echocal.errors import DataFileError, EchocalValueError, LimitError, UnknownNameError

X0 = (1.5, 1.0)


@pytest.mark.parametrize(("method", "per_iter"), [("gradient", 4), ("newton", 9), ("spsa", 2)])
def test_budget_stops_cleanly_and_is_never_exceeded(method, per_iter, gauss_objective):
    obj = gauss_objective()
    opts = {"eps": 1.0} if method == "spsa" else {}
    res = calibrate(obj, method, x0=X0, budget=31, max_iter=1000, rng=0, **opts)
    # the budget ran out: an estimate, but not a converged one (scipy's ``success``)
    assert res.status == 2 and not res.success
    assert res.message == STATUS_MESSAGES[2]
    # the final measurement at the estimate was kept out of the method's budget
    assert res.n_measurements <= 31 and res.n_measurements > 31 - per_iter
    np.testing.assert_array_equal(res.points[-1], res.x)
    assert res.final_value == res.values[-1] == res.fun
    assert res.n_measurements == obj.n_measurements == len(res.points)


def test_objective_budget_is_respected_too(gauss_objective):
    obj = gauss_objective(budget=20)  # no settle stop: the run goes on to the budget
    res = calibrate(obj, "model-based", x0=X0, max_iter=1000, settle=None)
    assert res.status == 2 and obj.n_measurements == 20


def test_calibrate_settles_by_default_as_the_command_line_does(gauss_objective):
    from echocal.constants import DEFAULT_SETTLE

    assert DEFAULT_SETTLE == (0.01, 8)
    res = calibrate(gauss_objective(budget=200), "model-based", x0=X0, max_iter=1000)
    assert res.status == 7 and res.success and res.n_measurements < 200


def test_budget_smaller_than_one_iteration_raises_before_measuring(gauss_objective):
    obj = gauss_objective()
    with pytest.raises(EchocalValueError, match="budget=8 is smaller.*newton.*9"):
        calibrate(obj, "newton", x0=X0, budget=8)
    with pytest.raises(EchocalValueError, match="spsa"):  # 4 gain estimates + 1 iteration
        calibrate(obj, "spsa", x0=X0, budget=9)
    assert obj.n_measurements == 0


def test_x0_outside_bounds_raises_limit_error_naming_x0():
    obj = FunctionObjective(gaussian, bounds=[[-5, 5], [-5, 5]])
    with pytest.raises(LimitError, match=r"x0 \(azimuth=9"):
        calibrate(obj, "gradient", x0=(9.0, 0.0))


def test_unknown_method_and_unknown_options(gauss_objective):
    with pytest.raises(UnknownNameError, match="model-based"):
        calibrate(gauss_objective(), "bobyqa", x0=X0)
    with pytest.raises(UnknownNameError, match=r"method .gradient.: stepsize; accepted: delta"):
        calibrate(gauss_objective(), "gradient", x0=X0, max_iter=3, stepsize=0.1)


def test_iteration_limit_xtol_and_callback(gauss_objective):
    res = calibrate(gauss_objective(), "gradient", x0=X0, max_iter=5, final_check=0)
    assert res.status == 1 and res.n_iterations == 5 and res.n_measurements == 20
    assert not res.success and res.final_value is None
    assert res.iterates.shape == (6, 2)
    np.testing.assert_array_equal(res.iteration_measurements, [0, 4, 8, 12, 16, 20])
    res = calibrate(gauss_objective(), "newton", x0=X0, max_iter=50, xtol=1e-6)
    assert res.status == 0 and res.n_iterations < 50
    np.testing.assert_allclose(res.x, OPT, atol=1e-5)
    seen = []

    def stop_at_three(state):
        seen.append(state.iteration)
        return state.iteration == 3

    res = calibrate(gauss_objective(), "spsa", x0=X0, callback=stop_at_three, rng=0, eps=1.0)
    assert res.status == 3 and seen == [1, 2, 3] and res.n_iterations == 3


def test_nan_measurements_are_counted_reported_and_not_used_as_numbers():
    # NaN in a half-plane next to the start: the failed measurements are counted, reported,
    # and the method still converges (they act as "no echo", the worst value seen)
    def f(p):
        return np.where(p[:, 0] > 2.0, np.nan, gaussian(p))

    obj = FunctionObjective(f)
    res = calibrate(obj, "model-based", x0=(1.6, 1.0), max_iter=40)
    assert res.n_nan > 0 and res.n_nan == int(np.isnan(res.values).sum())
    assert "NaN" in res.message
    np.testing.assert_allclose(res.x, OPT, atol=1e-3)
    res = calibrate(FunctionObjective(f), "gradient", x0=(1.9, 1.0), max_iter=60)
    assert res.n_nan > 0
    assert np.hypot(*(res.x - OPT)) < 1e-2


def test_all_nan_objective_reports_failure():
    obj = FunctionObjective(lambda p: np.full(len(p), np.nan))
    res = calibrate(obj, "gradient", x0=(0.0, 0.0), max_iter=3)
    assert res.status == 6 and not res.success and res.n_nan == 12


def test_final_check_is_counted(gauss_objective):
    res = calibrate(gauss_objective(), "newton", x0=X0, max_iter=4, final_check=3)
    assert res.n_measurements == 4 * 9 + 3
    # noiseless: fun is the mean of 3 exact measurements at x
    np.testing.assert_allclose(res.fun, gaussian(res.x)[0], rtol=1e-12)


def test_result_json_round_trip(tmp_path, gauss_objective):
    obj = FunctionObjective(lambda p: np.where(p[:, 1] > 1.2, np.nan, gaussian(p)))
    res = calibrate(obj, "auto", x0=X0, max_iter=10, rng=3)
    path = tmp_path / "sub" / "result.json"
    res.save_json(path)
    back = CalibrationResult.load_json(path)
    for name in ("x", "points", "values", "iterates", "iteration_measurements", "times"):
        np.testing.assert_array_equal(getattr(back, name), getattr(res, name))
    assert back.to_dict() == res.to_dict()
    assert back.message == res.message and back.names == res.names
    assert not list(tmp_path.glob("sub/.*partial*"))


@pytest.mark.parametrize(
    "damage",
    [
        {"search_passes": ["wide"]},
        {"values": ["nan-ish"]},
        {"search_passes": 4.2},
        {"search_snr_db": "loud"},
    ],
)
def test_a_damaged_result_file_is_one_clear_error(tmp_path, damage):
    res = calibrate(FunctionObjective(gaussian), "auto", x0=X0, max_iter=3, rng=3)
    path = tmp_path / "result.json"
    res.save_json(path)
    data = json.loads(path.read_text())
    path.write_text(json.dumps({**data, **damage}))
    with pytest.raises(DataFileError, match="cannot read calibration result"):
        CalibrationResult.load_json(path)


def test_presets_hold_the_thesis_tables():
    assert "thesis" in preset_names() and "thesis-table-7" in preset_names()
    t7 = presets("thesis-table-7")
    assert t7.max_iter == 30 and t7.x0 == (0.0, 0.0)
    assert method_options("momentum") == {"mu": 0.05, "momentum": 0.7, "normalize": "max"}
    assert method_options("quasi-newton")["lam"] == 0.9
    spsa = method_options("spsa", preset="thesis-table-4")
    assert (spsa["c"], spsa["A"], spsa["eps"], spsa["rho"], spsa["gamma"]) == (
        1.0,
        5.0,
        0.1,
        0.602,
        0.101,
    )
    with pytest.raises(UnknownNameError, match="thesis-table-1"):
        presets("thesis-table-9")


def test_thesis_preset_is_scale_free_through_normalization():
    # normalize="max": the same run on energies scaled by 1e-6 and 1e6 moves identically
    runs = [
        calibrate(
            FunctionObjective(lambda p, s=s: s * gaussian(p, width=3.0)),
            "momentum",
            x0=(0.0, 0.0),
            preset="thesis",
        )
        for s in (1e-6, 1e6)
    ]
    assert runs[0].n_iterations == 30
    np.testing.assert_allclose(runs[0].iterates, runs[1].iterates, rtol=1e-9, atol=1e-12)
    f = gaussian(runs[0].iterates, width=3.0)
    assert f[-1] > f[0]  # it ascends


@pytest.mark.parametrize("normalize", ["first", "max"])
def test_normalize_makes_fixed_gains_scale_free(normalize):
    runs = [
        calibrate(
            FunctionObjective(lambda p, s=s: s * gaussian(p)),
            "gradient",
            x0=X0,
            mu=0.5,
            normalize=normalize,
            max_iter=10,
        )
        for s in (1e-3, 1e3)
    ]
    np.testing.assert_allclose(runs[0].iterates, runs[1].iterates, rtol=1e-9, atol=1e-12)


# -- option types, names and the options recorded in the result -----------------------------
@pytest.mark.parametrize(
    ("method", "options", "match"),
    [
        ("auto", {"confirm": "False"}, "'confirm' of method 'auto' must be true or false"),
        ("auto", {"confirm": "maybe"}, "'confirm' .* true or false; got 'maybe'"),
        ("auto", {"confirm": 0}, "'confirm' .* true or false; got 0"),
        ("auto", {"local_options": "abc"}, "'local_options' .* must be a dict"),
        ("auto", {"spacing": "1"}, "'spacing' of method 'auto' must be a number; got '1'"),
        ("gradient", {"mu": "0.05"}, "'mu' of method 'gradient' must be a number or none"),
        ("gradient", {"mu": True}, "'mu' .* a number or none; got True"),
        ("spsa", {"n_gain_estimates": 2.5}, "'n_gain_estimates' .* an integer"),
        ("model-based", {"space": 1}, "'space' .* a name"),
        ("acquisition", {"local": 3}, "'local' .* a name"),
    ],
)
def test_an_option_of_the_wrong_type_is_refused_before_measuring(
    method, options, match, gauss_objective
):
    # bool("False") is True: a string must never reach a boolean option
    obj = gauss_objective()
    with pytest.raises(EchocalValueError, match=match):
        calibrate(obj, method, x0=X0, max_iter=2, **options)
    assert obj.n_measurements == 0


def test_acquisition_options_and_local_options_are_checked_when_built(gauss_objective):
    from echocal.calibrate import Acquisition

    with pytest.raises(EchocalValueError, match="confirm must be true or false; got 'no'"):
        Acquisition(np.zeros(2), confirm="no")
    with pytest.raises(EchocalValueError, match=r"'raduis' .*did you mean radius\?"):
        Acquisition(np.zeros(2), local_options={"raduis": 1.0})
    with pytest.raises(EchocalValueError, match="'radius' of method 'model-based'.*a number"):
        Acquisition(np.zeros(2), local_options={"radius": "1"})
    with pytest.raises(
        EchocalValueError, match="'threshold' of the acquisition phase must be a number"
    ):
        calibrate(gauss_objective(), "gradient", x0=X0, acquire={"threshold": "4"})
    with pytest.raises(EchocalValueError, match="acquire must be true, false or a dict"):
        calibrate(gauss_objective(), "gradient", x0=X0, acquire="yes")
    with pytest.raises(EchocalValueError, match="final_check must be an integer"):
        calibrate(gauss_objective(), "gradient", x0=X0, final_check="2")


def test_an_unknown_option_is_an_error_naming_the_nearest_name(gauss_objective):
    # Python refuses a misspelt option as the command line does, before measuring
    obj = gauss_objective()
    with pytest.raises(UnknownNameError, match=r"fine_raduis \(did you mean fine_radius\?\)"):
        calibrate(obj, "auto", x0=X0, max_iter=1, fine_raduis=1.0)
    assert obj.n_measurements == 0


def test_a_grid_too_large_to_measure_is_refused_before_it_is_built():
    from echocal.calibrate import GridSearch
    from echocal.calibrate.grid import MAX_GRID_POINTS

    # unbounded, span 1e9 at step 0.5: 4e9 nodes per axis (the old code allocated 30 GiB)
    with pytest.raises(EchocalValueError, match=r"span=1e\+09 deg with step=0.5 deg"):
        GridSearch(np.zeros(2), span=1e9)
    with pytest.raises(EchocalValueError, match=f"at most {MAX_GRID_POINTS}"):
        GridSearch(np.zeros(2), span=5.0, step=1e-3)
    # within bounds the same span is clipped to them: nodes -21, -20.5, ..., 21 per axis
    grid = GridSearch(np.zeros(2), span=1e9, bounds=[[-21, 21], [-21, 21]])
    assert grid.n_points == 85 * 85
    np.testing.assert_array_equal(grid.axes[0], np.arange(-42, 43) * 0.5)


@pytest.mark.parametrize(
    ("x0", "span", "step", "bounds"),
    [((0.3, -1.7), 2.0, 0.3, None), ((4.9, -4.9), 3.0, 0.5, [[-5, 5], [-5, 5]])],
)
def test_grid_axes_are_the_clipped_lattice(x0, span, step, bounds):
    from echocal.calibrate import GridSearch

    # independent construction: every node x0 ± k·step, clipped to the bounds, deduplicated
    lim = np.array([[-np.inf, np.inf]] * 2) if bounds is None else np.array(bounds, float)
    n = int(np.floor(span / step + 1e-9))
    grid = GridSearch(np.array(x0), span=span, step=step, bounds=bounds)
    for axis, c, (lo, hi) in zip(grid.axes, x0, lim, strict=True):
        expected = np.unique(np.clip(c + np.arange(-n, n + 1) * step, lo, hi))
        np.testing.assert_array_equal(axis, expected)


def test_a_grid_larger_than_the_budget_warns(gauss_objective):
    with pytest.warns(UserWarning, match="441 points to measure but the budget allows 100"):
        res = calibrate(gauss_objective(), "grid", x0=X0, budget=100, final_check=0)
    assert res.status == 2


def test_the_recorded_options_are_the_effective_ones_and_plain_json(gauss_objective):
    import json

    def my_noise_model():
        return None, None

    res = calibrate(gauss_objective(noise_sigma=0.05, rng=1), "auto", x0=X0, max_iter=2, rng=0)
    opts = res.options
    # defaults included (auto's search geometry), objective-supplied inputs named
    assert opts["fine_radius"] == 3.0 and opts["threshold"] == 4.5 and opts["confirm"] is True
    assert opts["noise_model"] == "objective" and opts["detector"] == "objective"
    assert opts["noise_sigma"] == 0.05
    local = opts["local_options"]
    assert local["radius"] == 1.0 and local["history"] == "acquisition"
    assert local["noise_model"] == "objective"
    res = calibrate(gauss_objective(), "model-based", x0=X0, max_iter=2, noise_model=my_noise_model)
    # a None default the method resolves (max_radius = 4 x radius) is recorded resolved
    assert res.options["max_radius"] == 4.0 and res.options["min_radius"] == 0.1
    text = json.dumps(res.to_dict()["options"])
    assert "0x" not in text and "bound method" not in text
    assert "my_noise_model" in text
    res = calibrate(gauss_objective(), "gradient", x0=X0, max_iter=1, acquire={"spacing": 0.5})
    assert res.options["delta"] == 0.25 and res.options["acquire"]["spacing"] == 0.5
    assert res.options["acquire"]["detector"] == "objective"
    json.dumps(res.to_dict())  # every entry serializable


def test_the_objectives_resolution_reaches_the_local_method(gauss_objective, monkeypatch):
    """A replay's grid step (:meth:`Objective.resolution`) reaches model-based however it
    runs — alone, behind an acquisition phase, inside ``auto`` — unless given; a method
    that has no such option never sees it."""
    monkeypatch.setattr(FunctionObjective, "resolution", lambda self: 0.5)
    run = {"max_iter": 2, "rng": 0}
    assert calibrate(gauss_objective(), "model-based", x0=X0, **run).options["resolution"] == 0.5
    wrapped = calibrate(gauss_objective(), "model-based", x0=X0, acquire=True, **run)
    assert wrapped.options["resolution"] == 0.5
    auto = calibrate(gauss_objective(), "auto", x0=X0, **run)
    assert auto.options["local_options"]["resolution"] == 0.5
    given = calibrate(gauss_objective(), "auto", x0=X0, local_options={"resolution": 2.0}, **run)
    assert given.options["local_options"]["resolution"] == 2.0
    assert "resolution" not in calibrate(gauss_objective(), "gradient", x0=X0, **run).options


@pytest.mark.parametrize(
    ("method", "option"),
    [
        ("gradient", "mu"),
        ("momentum", "momentum"),
        ("spsa", "c"),
        ("newton", "delta"),
        ("quasi-newton", "lam"),
        ("model-based", "radius"),
        ("grid", "step"),
        ("acquisition", "spacing"),
        ("auto", "threshold"),
    ],
)
def test_methods_built_directly_refuse_numbers_given_as_text(method, option):
    from echocal.calibrate import get_method

    cls = get_method(method)
    with pytest.raises(EchocalValueError, match=f"{option} must be a number; got '0.5'"):
        cls(np.zeros(2), **{option: "0.5"})
    with pytest.raises(EchocalValueError, match=f"{option} must be a number; got True"):
        cls(np.zeros(2), **{option: True})
    cls(np.zeros(2), **{option: 0.5})  # the number itself is fine
