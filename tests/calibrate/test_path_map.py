"""The path plot's cost map within its budget (:mod:`echocal.plots.path_map`).

Independent truth: the noiseless metric simulated directly at the same orientations
(``VirtualSetup.metric_values``, what the map drew before it had a budget).  Near the
optimum the map comes from the lobe profile (0.1° steps in 4 directions, interpolated
linearly in both).  The profile is centred on the setup's nearest normal-incidence
direction, 0.035° from the ray model's peak here, so around it the lobe varies with
direction as a first harmonic of amplitude A(r); linear interpolation between directions
90° apart errs by up to (1 − 1/√2)·A ≈ 0.3·A, 1.6 % of the peak at 0.2° (A ≈ 6 %, the
ray model's lobe being about 0.5° wide): the tolerance is 3 % of the peak.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.errors import EchocalValueError
from echocal.plots.path_map import path_cost_map
from echocal.setups import load_setup


@pytest.fixture(scope="module")
def ray():
    setup = load_setup("immersion-5mhz-ray", seed=0)
    pos = np.asarray(setup.reference_position, dtype=np.float64)
    truth = np.asarray(setup.true_optimum(pos, parameterization="tilt"))
    return setup, pos, truth


def test_near_the_optimum_the_map_is_the_lobe_and_costs_no_ascan(ray) -> None:
    setup, pos, truth = ray
    drawn = path_cost_map(setup, pos, truth, 8.0)  # by default nothing beyond the lobe
    assert drawn.from_lobe and drawn.simulated == drawn.planned == 0 and not drawn.stopped
    m = drawn.cost_map
    offsets = np.hypot(*np.meshgrid(m.a - truth[0], m.b - truth[1], indexing="ij"))
    inside = offsets <= drawn.reach - 0.1  # the profile's centre is 0.035° from the truth
    assert 0.5 < drawn.reach < 8.0
    assert np.all(np.isfinite(m.values[inside]))
    assert np.all(np.isnan(m.values[offsets > drawn.reach + 0.1]))
    # every 7th point inside the reach, against the metric simulated there
    ia, ib = np.nonzero(inside)
    ia, ib = ia[::7], ib[::7]
    direct = setup.metric_values(pos, m.a[ia], m.b[ib], parameterization="tilt")
    peak = float(setup.metric_values(pos, truth[0], truth[1], parameterization="tilt"))
    assert np.max(np.abs(m.values[ia, ib] - direct)) < 0.03 * peak
    assert float(np.nanmax(m.values)) == pytest.approx(peak, rel=0.03)


def test_beyond_the_lobe_a_coarse_grid_within_the_budget(ray) -> None:
    setup, pos, truth = ray
    drawn = path_cost_map(setup, pos, truth, 8.0, max_points=12)
    assert 0 < drawn.planned <= 12 and drawn.simulated == drawn.planned
    values = drawn.cost_map.values
    assert np.all(np.isfinite(values)) and np.all(values >= 0.0)
    info = drawn.to_dict()
    assert info["simulated"] == drawn.simulated and info["stopped"] is False
    # the time budget: spent before the first chunk, nothing simulated, the rest blank
    late = path_cost_map(setup, pos, truth, 8.0, max_points=12, max_seconds=1e-9)
    assert late.stopped and late.simulated == 0 and np.any(np.isnan(late.cost_map.values))


def test_without_a_lobe_profile_the_grid_is_sized_by_the_budget(ray) -> None:
    from echocal.signal.gates import resolve_gate

    setup, pos, truth = ray
    gate = resolve_gate("front-wall", pulse=setup.pulse)  # the profile is the whole window's
    drawn = path_cost_map(setup, pos, truth, 2.0, gate=gate, max_points=9)
    assert not drawn.from_lobe and drawn.simulated == drawn.planned == 9
    direct = setup.metric_values(
        pos, drawn.cost_map.a[:, None], drawn.cost_map.b[None, :], parameterization="tilt",
        gate=gate,
    )  # fmt: skip
    np.testing.assert_array_equal(drawn.cost_map.values, direct)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"max_points": -1}, "map points"), ({"max_seconds": 0.0}, "map seconds")],
)
def test_a_bad_budget_is_refused(ray, kwargs, message) -> None:
    setup, pos, truth = ray
    with pytest.raises(EchocalValueError, match=message):
        path_cost_map(setup, pos, truth, 2.0, **kwargs)


def test_calibrate_map_points(tmp_path) -> None:
    base = ["calibrate", "--setup", "immersion-5mhz-ray", "--x0", "-1,3", "--json"]
    done = CliRunner().invoke(app, [*base, "--map-points", "0", "--out", str(tmp_path / "a")])
    assert done.exit_code == 0, done.output
    assert json.loads(done.stdout)["files"]["path"].endswith("path.png")
    assert (tmp_path / "a" / "path.png").stat().st_size > 10_000
    refused = CliRunner().invoke(app, [*base, "--map-points", "-1", "--out", str(tmp_path / "b")])
    assert refused.exit_code == 2 and "--map-points" in refused.output
    # an output option, as --plots: a rerun may change it, and it is not recorded
    recorded = json.loads((tmp_path / "a" / "result.json").read_text())["provenance"]
    assert "map_points" not in recorded["parameters"]
    rerun = ["calibrate", "--from", str(tmp_path / "a" / "result.json"), "--map-points", "4"]
    again = CliRunner().invoke(app, [*rerun, "--out", str(tmp_path / "c"), "--json"])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)["n_measurements"] == json.loads(done.stdout)["n_measurements"]
