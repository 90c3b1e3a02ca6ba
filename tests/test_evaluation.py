"""Judging calibration runs against the simulator's truth; the `echocal calibrate` command."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from echocal.calibrate import calibrate
from echocal.cli import app
from echocal.evaluation import angular_error, cost_map, evaluate_run, nearest_equivalent
from echocal.measurement.objective import SourceObjective
from echocal.setups import load_setup

POSITION = np.array([0.01, 0.0, 0.022])  # over the thesis block's right facet


@pytest.fixture(scope="module")
def thesis():
    return load_setup("thesis", seed=1)


def test_angular_error_is_parameterization_free():
    # (φ, θ) and (φ + 180°, −θ) are one beam; tilts of the same beam agree too.
    assert angular_error([195.0, -6.0], [15.0, 6.0], "azimuth-coelevation") < 1e-12
    assert angular_error([0.0, 1.0], [0.0, 0.0], "tilt") == pytest.approx(1.0, rel=1e-9)


def test_nearest_equivalent_picks_the_signed_form_near_the_start():
    np.testing.assert_allclose(
        nearest_equivalent([165.0, 6.0], [0.0, 0.0], "azimuth-coelevation"), [-15.0, -6.0]
    )
    np.testing.assert_allclose(nearest_equivalent([1.0, 2.0], [90.0, 0.0], "tilt"), [1.0, 2.0])


def test_evaluate_run_and_measurements_to_tolerance(thesis):
    objective = SourceObjective(thesis, POSITION, parameterization="tilt")
    result = calibrate(objective, method="gradient", x0=(0.0, 0.0), max_iter=25, rng=0, mu=2.0)
    ev = evaluate_run(thesis, POSITION, result)
    assert ev.iterate_errors.shape == (result.n_iterations + 1,)
    assert ev.iterate_errors[0] == pytest.approx(float(np.hypot(*ev.truth)), rel=0.05)
    assert ev.error == pytest.approx(ev.iterate_errors[-1])
    # The noiseless metric never exceeds its value at the true optimum (it is the maximum).
    assert np.all(ev.iterate_values <= ev.optimum_value * (1 + 1e-9))
    n = ev.measurements_to(10.0)  # x0 is within 10° of the truth: zero measurements needed
    assert n == 0
    assert ev.measurements_to(1e-9) is None


def test_cost_map_peaks_at_the_truth(thesis):
    truth = thesis.true_optimum(POSITION, parameterization="tilt")
    cmap = cost_map(thesis, POSITION, a_range=(-15, 15), b_range=(-15, 15), n=31)
    i, j = np.unravel_index(np.argmax(cmap.values), cmap.values.shape)
    # Grid step 1°: the best grid node is within one step of the truth in each angle.
    assert abs(cmap.a[i] - truth[0]) <= 1.0 and abs(cmap.b[j] - truth[1]) <= 1.0


def test_calibrate_command_prints_json_and_saves_files(tmp_path):
    result = CliRunner().invoke(
        app,
        [
            "calibrate",
            "--setup",
            "thesis",
            "--position",
            "10,0,22",
            "--method",
            "gradient",
            "--max-iter",
            "5",
            "--out",
            str(tmp_path),
            "--json",
            "--no-final-measure",
        ],
    )
    assert result.exit_code == 3, result.output  # --max-iter 5 stopped it: not converged
    summary = json.loads(result.stdout)
    assert summary["n_measurements"] == 20  # FD gradient: 4 measurements per iteration
    assert len(summary["truth_deg"]) == 2 and summary["error_deg"] >= 0
    for name in ("result.json", "convergence.png", "path.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_calibrate_command_bad_method_is_one_line(tmp_path):
    result = CliRunner().invoke(app, ["calibrate", "--method", "magic", "--out", str(tmp_path)])
    assert result.exit_code != 0
    assert "magic" in str(result.exception) or "magic" in result.output


def test_iterations_to_matches_the_iterate_errors(thesis):
    # independent truth: recount by hand from iterate_errors
    from echocal.calibrate import calibrate
    from echocal.evaluation import evaluate_run
    from echocal.measurement.objective import SourceObjective

    pos = thesis.reference_position
    res = calibrate(
        SourceObjective(thesis, pos, parameterization="tilt"),
        "newton",
        x0=(3.0, -2.0),
        max_iter=6,
        rng=0,
    )
    ev = evaluate_run(thesis, pos, res)
    for tol in (0.05, 0.5, 2.0, 10.0):
        if ev.error > tol:
            assert ev.iterations_to(tol) is None and ev.measurements_to(tol) is None
            continue
        inside = ev.iterate_errors <= tol
        first = next(i for i in range(len(inside) + 1) if inside[i:].all())
        assert ev.iterations_to(tol) == min(first, res.n_iterations)
        expected = res.n_measurements if first > res.n_iterations else first * 9
        assert ev.measurements_to(tol) == expected  # newton: 9 measurements per iteration


def test_calibrate_command_search_radius_bounds_the_search(tmp_path):
    # a start 16.6° from the realistic setup's optimum with a gradient method: a 2° search
    # radius puts an acquisition phase in front (auto's search) that gives up (status 4)
    # when the echo is not within it — after x0 and its first ring (7 measurements): at
    # 30 dB an echo anywhere within 2° would have shown in them, so the posterior search
    # finds the measurements over 1,000 times likelier without one (the 1° lattice to 2°
    # of the passes took 19)
    args = [
        "calibrate",
        "--setup",
        "immersion-5mhz",
        "--x0",
        "12,12",
        "--method",
        "gradient",
        "--search-radius",
        "2",
        "--out",
        str(tmp_path),
        "--no-plots",
        "--json",
    ]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, result.output  # no echo found: exit status 1
    summary = json.loads(result.stdout)
    assert summary["status"] == 4 and summary["n_measurements"] == 7
    assert summary["acquisition_measurements"] is None
    bad = CliRunner().invoke(app, [a if a != "2" else "nan" for a in args])
    assert bad.exit_code != 0 and "--search-radius" in (bad.output + str(bad.exception))


def test_calibrate_command_passes_method_options(tmp_path):
    base = ["calibrate", "--setup", "thesis", "--position", "10,0,22", "--max-iter", "3"]
    args = [*base, "--option", "fine_radius=1", "--option", "local=newton", "--out", str(tmp_path)]
    result = CliRunner().invoke(app, [*args, "--no-plots", "--json"])
    assert result.exit_code == 3, result.output  # --max-iter 3 stopped it: not converged
    saved = json.loads((tmp_path / "result.json").read_text(encoding="utf-8"))
    # a JSON number stays a number, anything else is a string
    assert saved["options"]["fine_radius"] == 1 and saved["options"]["local"] == "newton"
    for bad in ("budget=3", "no-equals-sign", "detector=x"):
        res = CliRunner().invoke(app, [*base, "--option", bad, "--out", str(tmp_path)])
        assert res.exit_code != 0 and "--option" in res.output + str(res.exception)


def test_methods_command_lists_the_registry_and_one_methods_defaults():
    from echocal.calibrate import method_names
    from echocal.calibrate.auto import AUTO_SEARCH

    listing = json.loads(CliRunner().invoke(app, ["methods", "--json"]).stdout)
    assert sorted(listing["methods"]) == sorted(method_names())
    auto = json.loads(CliRunner().invoke(app, ["methods", "auto", "--json"]).stdout)
    # auto differs from acquisition only by its search geometry defaults
    acquisition = json.loads(CliRunner().invoke(app, ["methods", "acquisition", "--json"]).stdout)
    assert {k: auto["options"][k] for k in AUTO_SEARCH} == json.loads(json.dumps(AUTO_SEARCH))
    assert set(auto["options"]) == set(acquisition["options"])
    bad = CliRunner().invoke(app, ["methods", "magic"])
    assert bad.exit_code != 0 and "magic" in (bad.output + str(bad.exception))


def test_cost_map_in_a_gate_is_the_metric_of_the_gated_trace(thesis):
    from echocal.geometry import tilt_frame
    from echocal.signal import get_metric
    from echocal.signal.gates import TimeGate

    window = thesis.window
    whole = TimeGate(name="whole", start=window.start, width=window.end - window.start)
    kwargs = {"a_range": (-4.0, 4.0), "b_range": (-4.0, 4.0), "n": 5}
    plain = cost_map(thesis, POSITION, **kwargs)
    assert np.array_equal(cost_map(thesis, POSITION, gate=whole, **kwargs).values, plain.values)
    # a gate on the first half of the echo: the metric of the trace zeroed outside it
    t0, t1 = thesis.true_optimum(POSITION, parameterization="tilt")
    samples = thesis.ideal_samples(POSITION[None], tilt_frame(np.array([t0]), np.array([t1])))[0]
    peak = window.start + np.argmax(np.abs(samples)) / window.fs
    half = TimeGate(name="half", start=window.start, width=peak - window.start)
    gated = thesis.metric_values(POSITION, t0, t1, parameterization="tilt", gate=half)
    by_hand = get_metric("pseudo-energy")(
        np.where(window.times <= peak, samples, 0.0), window, thesis.pulse
    )
    assert float(gated) == pytest.approx(float(by_hand), rel=1e-9)
    assert (
        0.0 < float(gated) < float(thesis.metric_values(POSITION, t0, t1, parameterization="tilt"))
    )
    # a gate holding no echo: a noiseless map of (Gabor-tail) zeros
    empty = TimeGate(name="empty", start=window.start, width=2e-7)
    nothing = cost_map(thesis, POSITION, gate=empty, **kwargs).values
    assert np.max(nothing) < 1e-12 * np.max(plain.values)


def test_map_resolution_follows_the_models_cost():
    from echocal.evaluation import map_resolution

    assert map_resolution(load_setup("thesis")) == 61  # ray model: < 1 ms per pose
    assert map_resolution(load_setup("immersion-5mhz-wave")) == 41
    assert map_resolution(load_setup("immersion-steel-plate")) == 25  # + back-wall echoes
    # far tilts cost more on the wave model: a wide map is coarser
    assert map_resolution(load_setup("immersion-5mhz-wave"), half_span=18.0) == 21
    assert map_resolution(load_setup("immersion-steel-plate"), half_span=18.0) == 15
    assert map_resolution(load_setup("thesis"), half_span=18.0) == 61
    assert map_resolution(load_setup("immersion-steel-pipe")) == 11  # 0.1–1 s per pose
    assert map_resolution(load_setup("immersion-steel-shell"), half_span=18.0) == 9


def test_gated_truth_of_the_plate_is_normal_incidence_on_the_back_wall():
    from echocal.signal.gates import resolve_gate

    plate = load_setup("immersion-steel-plate")
    gate = resolve_gate(
        "back-wall", pulse=plate.pulse, thickness=plate.thickness, material=plate.material
    )
    where = plate.reference_position
    a, b = plate.true_optimum(where, parameterization="tilt", gate=gate)
    assert np.hypot(a, b) < 0.01  # a level plate: the back wall is parallel to the front
    ungated = plate.metric_values(where, 0.0, 0.0, parameterization="tilt")
    in_gate = plate.metric_values(where, 0.0, 0.0, parameterization="tilt", gate=gate)
    assert 0.0 < float(in_gate) < 0.1 * float(ungated)  # the back wall is ~20 dB down
