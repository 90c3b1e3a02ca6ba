"""The ask/tell methods: convergence on known optima, measurement counts, contracts."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import OPT, gaussian, quadratic
from echocal.calibrate import calibrate, get_method, method_names
from echocal.calibrate.newton import newton_direction
from echocal.calibrate.quasi_newton import bfgs_update
from echocal.errors import EchocalValueError, UnknownNameError

LOCAL = ["gradient", "momentum", "nesterov", "spsa", "newton", "quasi-newton", "model-based"]
X0 = (1.5, 1.0)  # 1.6 deg from OPT


def test_registry_lists_every_method_and_refuses_unknown_names():
    assert set(method_names()) == {*LOCAL, "grid", "acquisition", "auto"}
    with pytest.raises(UnknownNameError, match="gradient.*quasi-newton"):
        get_method("simplex")


@pytest.mark.parametrize("method", [*LOCAL, "auto"])
@pytest.mark.parametrize("problem", ["quadratic", "gaussian"])
def test_converges_on_noiseless_concave_problem(method, problem, quad_objective, gauss_objective):
    obj = quad_objective() if problem == "quadratic" else gauss_objective()
    opts = {}
    if problem == "quadratic":  # log f of a quadratic is not quadratic: model f itself
        if method == "model-based":
            opts = {"space": "linear"}
        elif method == "auto":
            opts = {"local_options": {"space": "linear"}}
    # SPSA's decaying gains (mu_k ~ k^-0.602) need more iterations on the anisotropic
    # quadratic, whose cross term enters each SP estimate; 400 cost 800 measurements
    max_iter = 400 if method == "spsa" else 80
    # settle=None: the test is about the fixed point, not the settle stop (0.01°), which
    # would end the slow gradient methods before they reach 1e-3°
    res = calibrate(obj, method, x0=X0, rng=0, max_iter=max_iter, settle=None, **opts)
    # noiseless: every method's fixed point is the optimum; the iteration counts bring
    # the slowest (SPSA on the quadratic: 4e-4 deg) below 1e-3 deg
    np.testing.assert_allclose(res.x, OPT, atol=1e-3)


def test_grid_finds_the_optimum_to_its_resolution(gauss_objective):
    res = calibrate(gauss_objective(), "grid", x0=(0.0, 0.0), span=2.0, step=0.1)
    assert res.status == 5 and res.n_measurements == 41 * 41 + 1  # + the final measurement
    # a node of the grid lies within 0.1/sqrt(2) of OPT; the 3x3-mean argmax of a
    # symmetric peak is that node or a neighbour: error <= one diagonal step
    assert np.hypot(*(res.x - OPT)) <= 0.1 * np.sqrt(2) + 1e-9


@pytest.mark.parametrize(
    ("method", "per_iter"),
    [
        ("gradient", 4),
        ("momentum", 4),
        ("nesterov", 4),
        ("quasi-newton", 4),
        ("newton", 9),
        ("spsa", 2),
        ("model-based", 1),
    ],
)
def test_measurements_per_iteration_are_locked(method, per_iter, gauss_objective):
    opt_cls = get_method(method)
    opts = {"eps": 0.1} if method == "spsa" else {}
    opt = opt_cls(np.array(X0), rng=0, **opts)
    obj = gauss_objective()
    sizes = []
    for _ in range(6):
        pts = opt.ask()
        sizes.append(len(pts))
        opt.tell(obj(pts))
    start = 1 if method == "model-based" else 0  # model-based: 7-point design first
    assert sizes[start:] == [per_iter] * (6 - start)
    if method == "model-based":
        assert sizes[0] == 7


def test_spsa_gain_calibration_is_counted_and_uses_symmetric_perturbations(gauss_objective):
    obj = gauss_objective()
    res = calibrate(obj, "spsa", x0=X0, rng=1, max_iter=10, n_gain_estimates=4, final_check=0)
    # 4 calibration estimates x 2 + 10 iterations x 2
    assert res.n_measurements == 28 == obj.n_measurements
    assert res.iteration_measurements[1] == 10
    pts = res.points.reshape(-1, 2, 2)
    half = (pts[:, 0] - pts[:, 1]) / 2.0  # = c_k * Delta_k
    np.testing.assert_allclose(np.abs(half[:, 0]), np.abs(half[:, 1]))  # |Delta_i| = 1
    signs = np.sign(half).ravel()
    assert set(signs) == {-1.0, 1.0}


def test_spsa_first_step_has_the_calibrated_length_on_any_energy_scale():
    lengths = []
    for scale in (1e-6, 1.0, 1e6):
        from echocal.calibrate import FunctionObjective

        obj = FunctionObjective(lambda p, s=scale: s * gaussian(p), rng=0)
        res = calibrate(obj, "spsa", x0=X0, rng=5, max_iter=1, first_step=0.5)
        lengths.append(np.hypot(*(res.iterates[1] - res.iterates[0])))
    # same rng -> same perturbations; the gain absorbs the scale exactly
    np.testing.assert_allclose(lengths, lengths[0], rtol=1e-9)


class _Logger:
    """An objective stand-in that records the order of ask/tell calls."""

    def __init__(self):
        self.calls = []


@pytest.mark.parametrize("method", sorted(set(LOCAL) | {"grid", "auto"}))
def test_ask_tell_order_contract(method):
    opt = get_method(method)(np.array(X0), rng=0)
    with pytest.raises(EchocalValueError, match="without a pending ask"):
        opt.tell(np.zeros(4))
    pts = opt.ask()
    with pytest.raises(EchocalValueError, match="before tell"):
        opt.ask()
    with pytest.raises(EchocalValueError, match=f"expects {len(pts)} value"):
        opt.tell(np.zeros(len(pts) + 1))
    opt.tell(gaussian(pts))  # the pending ask survives a rejected tell
    log = _Logger()
    for _ in range(3):
        p = opt.ask()
        log.calls.append(("ask", len(p)))
        opt.tell(gaussian(p))
        log.calls.append(("tell", len(p)))
    assert [c[0] for c in log.calls] == ["ask", "tell"] * 3
    assert opt.n_asks == opt.n_tells == 4


@pytest.mark.parametrize("method", [*LOCAL, "auto"])
def test_seeded_runs_are_reproducible(method, gauss_objective):
    runs = [
        calibrate(gauss_objective(noise_sigma=0.1, rng=4), method, x0=X0, rng=9, max_iter=15)
        for _ in range(2)
    ]
    np.testing.assert_array_equal(runs[0].points, runs[1].points)
    np.testing.assert_array_equal(runs[0].values, runs[1].values)
    np.testing.assert_array_equal(runs[0].iterates, runs[1].iterates)
    np.testing.assert_array_equal(runs[0].x, runs[1].x)


@pytest.mark.parametrize("method", ["newton", "quasi-newton"])
@pytest.mark.parametrize("x0", [(1.5, 1.0), (-4.0, 3.0), (10.0, -8.0)])
@pytest.mark.parametrize("mu", [1.0, 0.05])
def test_newton_and_bfgs_never_step_downhill_on_a_concave_quadratic(method, x0, mu, quad_objective):
    res = calibrate(quad_objective(), method, x0=x0, rng=0, max_iter=25, mu=mu)
    f = quadratic(res.iterates)
    # noiseless and exact FD on a quadratic: f along the iterates is non-decreasing
    assert np.all(np.diff(f) >= -1e-9), f
    if mu == 1.0:
        np.testing.assert_allclose(res.x, OPT, atol=1e-6)


def test_newton_handles_an_indefinite_hessian_with_an_ascent_step():
    g = np.array([1.0, -2.0])
    for h in (np.diag([1.0, 2.0]), np.diag([-1.0, 3.0]), np.zeros((2, 2))):
        for damping in ("levenberg", "gradient"):
            d, nd = newton_direction(g, h, max_step=2.0, damping=damping)
            assert not nd and d @ g > 0 and np.hypot(*d) <= 2.0 + 1e-9
    d, nd = newton_direction(g, -np.eye(2), max_step=2.0)
    assert nd
    np.testing.assert_allclose(d, g)  # -H^-1 g with H = -I


def test_newton_uses_the_corrected_h22():
    from echocal.calibrate._fd import nine_gradient_hessian, nine_points

    c, delta = np.array([0.2, 0.1]), 0.3
    pts = nine_points(c, delta)
    _g, h = nine_gradient_hessian(quadratic(pts), pts)
    # the Hessian of the quadratic is -2Q exactly (central differences are exact)
    np.testing.assert_allclose(h, -2.0 * np.array([[1.0, 0.3], [0.3, 2.0]]), atol=1e-9)


def test_stencils_clipped_at_a_bound_use_the_real_spacing():
    from conftest import _Q
    from echocal.calibrate._fd import (
        cross_gradient,
        cross_points,
        nine_gradient_hessian,
        nine_points,
    )

    c, delta, hi = np.array([1.5, 0.9]), 0.4, np.array([1.7, 1.0])  # bounds cut + side
    pts = np.minimum(nine_points(c, delta), hi)
    assert not np.allclose(pts, nine_points(c, delta))
    g, h = nine_gradient_hessian(quadratic(pts), pts)
    # uneven 3-point differences are exact for a quadratic: ∇f = -2Q(c - x*), H = -2Q
    np.testing.assert_allclose(g, -2.0 * _Q @ (c - OPT), atol=1e-9)
    np.testing.assert_allclose(h, -2.0 * _Q, atol=1e-9)
    # the cross: a secant over the real distance, exact on a linear function
    cross = np.minimum(cross_points(c, delta), hi)
    slope = np.array([2.0, -3.0])
    np.testing.assert_allclose(cross_gradient(cross @ slope, cross), slope, atol=1e-12)
    # an axis clipped onto the centre: one-sided gradient, no curvature claimed on that
    # axis; the mixed term still spans a rectangle (δ × 2δ) and stays exact
    flat = np.minimum(nine_points(c, delta), [c[0], np.inf])
    g1, h1 = nine_gradient_hessian(quadratic(flat), flat)
    assert h1[0, 0] == 0.0 and np.isfinite(g1).all()
    np.testing.assert_allclose(h1[0, 1], -2.0 * _Q[0, 1], atol=1e-9)


def test_bfgs_skips_updates_that_violate_the_curvature_condition():
    b = np.eye(2)
    assert bfgs_update(b, np.array([1.0, 0.0]), np.array([-1.0, 0.0])) is None
    new = bfgs_update(b, np.array([1.0, 0.0]), np.array([2.0, 0.0]))
    np.testing.assert_allclose(new @ np.array([1.0, 0.0]), [2.0, 0.0])  # secant equation
    assert np.all(np.linalg.eigvalsh(new) > 0)


def test_grid_measures_its_whole_grid_whatever_the_iteration_and_settle_defaults(
    gauss_objective,
):
    # 121 rows: more than the default iteration limit (100), and the settle rule would stop
    # it once the recommendation stops moving; an exhaustive search must be cut short by
    # neither (a partial grid reported as "converged" is a wrong answer)
    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    result = calibrate(
        objective,
        method="grid",
        x0=(0.0, 0.0),
        span=15.0,
        step=0.25,
        settle=(0.01, 8),
        rng=0,
        final_check=0,
    )
    assert result.n_measurements == 121 * 121  # every node, once
    assert result.status == 5  # "grid finished", not 1 (iteration limit) or 7 (settled)
    np.testing.assert_allclose(result.x, [0.75, -0.5], atol=1e-12)  # the node nearest OPT


def test_grid_cut_short_by_an_explicit_iteration_limit_warns(gauss_objective):
    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    with pytest.warns(UserWarning, match="only part of the grid"):
        result = calibrate(objective, method="grid", x0=(0.0, 0.0), max_iter=3, rng=0)
    assert result.n_iterations == 3


def test_grid_warns_when_its_best_node_is_on_its_edge(gauss_objective):
    # OPT = (0.7, -0.4): a grid of span 0.5 around (-0.5, 0) cannot reach it; its best node
    # is on the +x edge.  Centred on OPT it is inside, and no warning is given.
    with pytest.warns(UserWarning, match="edge"):
        calibrate(gauss_objective(), "grid", x0=(-0.5, 0.0), span=0.5, step=0.25)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        calibrate(gauss_objective(), "grid", x0=(0.7, -0.4), span=0.5, step=0.25)


def test_grid_behind_an_acquisition_phase_is_measured_through(gauss_objective):
    # the search hands over to the grid; settle must not stop the half-measured grid then
    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    result = calibrate(
        objective,
        "grid",
        x0=(0.0, 0.0),
        span=3.0,
        step=0.5,
        settle=(0.01, 3),
        acquire={"max_radius": 20.0},
    )
    assert result.status == 5  # "search complete", not 7 (settled) after a few rows


def test_grid_does_not_ask_to_widen_a_grid_clipped_at_the_bounds(gauss_objective):
    # OPT = (0.7, -0.4) lies beyond the bound 0.5 in x: the best node sits on the bound,
    # which no larger span can move; the maximum is out of reach, not out of the grid
    import warnings

    objective = gauss_objective(bounds=[[-2.0, 0.5], [-2.0, 2.0]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = calibrate(objective, "grid", x0=(0.0, 0.0), span=1.0, step=0.25)
    assert result.x[0] == 0.5
    # the one warning is the estimate's: on the positioner's limits (status 8, no success)
    assert [str(w.message) for w in caught if "span" in str(w.message)] == []
    assert len(caught) == 1 and "angle limits" in str(caught[0].message)
    assert result.status == 8 and not result.success
