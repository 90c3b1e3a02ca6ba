"""The calibration driver: loop ask → measure → tell with every stopping rule, return a result."""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal._blas import one_blas_thread
from echocal._rng import RngLike, as_generator
from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import (
    accepted_options,
    check_option_types,
    nonnegative_float,
    option_defaults,
    positive_float,
    positive_int,
    suggestion,
)
from echocal.calibrate.acquisition import LOCAL_INPUTS, Acquisition
from echocal.calibrate.base import Optimizer
from echocal.calibrate.evidence import UNCERTAINTY_LEVEL, estimate_radius, judge
from echocal.calibrate.objective import Objective
from echocal.calibrate.presets import method_options, presets
from echocal.calibrate.registry import get_method
from echocal.calibrate.result import (
    NO_ECHO_STATUSES,
    STATUS_MESSAGES,
    SUCCESS_STATUSES,
    UNSUPPORTED_STATUSES,
    CalibrationResult,
)
from echocal.constants import DEFAULT_SETTLE
from echocal.errors import BudgetExhaustedError, EchocalValueError, UnknownNameError
from echocal.geometry import angle_between, convert_angles, orientation_normal

__all__ = ["SEARCH_GEOMETRY", "CalibrationState", "build_optimizer", "calibrate"]


@dataclass(frozen=True, slots=True)
class CalibrationState:
    """What a callback sees after each iteration.

    iteration : completed iterations; n_measurements : measurements so far;
    iterate, recommendation : [deg] (2,); points : [deg] (k, 2) and values (k,) of the last batch.
    """

    iteration: int
    n_measurements: int
    iterate: FloatArray
    recommendation: FloatArray
    points: FloatArray
    values: FloatArray


def _split(cls: type[Optimizer], options: Mapping[str, Any]) -> tuple[dict, list[str]]:
    ok = accepted_options(cls)
    known = {k: v for k, v in options.items() if k in ok}
    return known, sorted(set(options) - ok)


def build_optimizer(
    objective: Objective,
    method: str,
    x0: FloatArray,
    *,
    rng: np.random.Generator,
    acquire: bool | Mapping[str, Any] = False,
    options: Mapping[str, Any] | None = None,
) -> tuple[Optimizer, dict[str, Any]]:
    """Instantiate ``method`` (optionally behind an acquisition phase) for ``objective``.

    An unknown option raises UnknownNameError naming it, the closest valid name and the
    accepted ones; an option of the wrong type (a string for a number or a boolean, ...) raises
    EchocalValueError naming it.  Returns the optimizer and the options it runs with, as
    recorded in the result: every option of the method with its effective value,
    defaults included, and ``"objective"`` for the inputs the objective supplies (its
    live noise estimate and its echo detector).
    """
    cls = get_method(method)
    options = dict(options or {})
    if not isinstance(acquire, bool | np.bool_ | Mapping):
        raise EchocalValueError(
            f"acquire must be true, false or a dict of acquisition options; got {acquire!r}"
        )
    acq_opts = dict(acquire) if isinstance(acquire, Mapping) else {}
    wrap = bool(acquire) and not issubclass(cls, Acquisition)
    known, unknown = _split(cls, options)
    check_option_types(cls, known, where=f"method {method!r}")
    if wrap:
        aknown, aunknown = _split(Acquisition, acq_opts)
        for key in ("local", "local_options", "normalize"):  # these come from the method
            if key in aknown:
                del aknown[key]
                aunknown.append(key)
        check_option_types(Acquisition, aknown, where="the acquisition phase")
        unknown += [f"acquire.{k}" for k in aunknown]
    elif issubclass(cls, Acquisition):
        acq_opts, aunknown = _split(cls, acq_opts)
        check_option_types(cls, acq_opts, where=f"method {method!r}")
        unknown += [f"acquire.{k}" for k in aunknown]
    if unknown:
        hints = "; ".join(
            f"{k}{suggestion(k.removeprefix('acquire.'), accepted_options(cls))}" for k in unknown
        )
        raise UnknownNameError(
            f"unknown option(s) for method {method!r}: {hints}; "
            f"accepted: {', '.join(sorted(accepted_options(cls)))} "
            f"(see `echocal methods {method}`)"
        )
    if wrap:
        aknown = {**_search_inputs(objective), **aknown}
        opt: Optimizer = Acquisition(
            x0, local=method, local_options=known, bounds=objective.bounds, rng=rng, **aknown
        )
        record = _record(opt, {"local": method, "local_options": known, **aknown}, objective)
        local = record.pop("local_options")
        del record["local"]
        return opt, {**local, "acquire": record}
    if issubclass(cls, Acquisition):
        given = {**known, **acq_opts}
        known = {**_search_inputs(objective), **_search_plan(cls, objective, given), **given}
    else:
        inputs = _search_inputs(objective)
        for name in LOCAL_INPUTS:
            if name in accepted_options(cls):
                known.setdefault(name, inputs[name])
    opt = cls(x0, bounds=objective.bounds, rng=rng, **known)
    return opt, _record(opt, known, objective)


def _record(opt: Optimizer, given: Mapping[str, Any], objective: Objective) -> dict[str, Any]:
    """Every option of ``opt``'s method with its effective value (defaults included, a
    None default the method resolved to a number — e.g. a radius derived from another —
    as that number); the objective's own callables named ``"objective"``; an
    acquisition's ``local_options`` expanded the same way (its warm-start ``history``
    named ``"acquisition"``)."""
    supplied = [v for v in _search_inputs(objective).values() if callable(v)]
    supplied.append(objective.passes_for_measured_noise)

    def name(value: Any) -> Any:
        if callable(value) and not isinstance(value, type) and any(value == f for f in supplied):
            return "objective"
        return value

    out = {k: name(v) for k, v in {**option_defaults(type(opt)), **given}.items()}
    for key, value in out.items():  # a None default the method resolved to a number
        resolved = getattr(opt, key, None) if value is None else None
        if isinstance(resolved, int | float) and not isinstance(resolved, bool):
            out[key] = resolved if np.isfinite(resolved) else None
    if isinstance(opt, Acquisition):
        local = {**option_defaults(opt.local_class), **opt.local_setup()}
        if "history" in local and "history" not in opt.local_options:
            local["history"] = "acquisition"
        out["local_options"] = {k: name(v) for k, v in local.items()}
    return out


OBJECTIVE_INPUTS: dict[str, Callable[[Objective], Any]] = {
    "noise_sigma": lambda o: o.noise_sigma,
    "noise_floor": lambda o: o.noise_floor,
    "noise_model": lambda o: o.noise_estimate,
    "lobe_template": lambda o: o.lobe_template,
    "normal_echo": lambda o: o.normal_echo,
    "resolution": lambda o: o.resolution(),
    "detector": lambda o: o.detections,
    "echo_likelihood": lambda o: o.echo_likelihood,
    "move_time": lambda o: o.move_times,
    "measurement_price": lambda o: o.measurement_price(),
}
"""Acquisition options the driver takes from the objective unless they are given, and how:
its noise level and floor, the live noise estimate, the probe's lobe and best echo, a
replay's grid step, the echo detector and likelihood, a motion-aware objective's moves."""


def _search_inputs(objective: Objective) -> dict[str, Any]:
    """The :data:`OBJECTIVE_INPUTS` of ``objective``."""
    return {name: get(objective) for name, get in OBJECTIVE_INPUTS.items()}


CALLABLE_INPUTS = (
    "noise_model",
    "lobe_template",
    "normal_echo",
    "detector",
    "replan",
    "echo_likelihood",
    "move_time",
)
"""Options the objective supplies as callables (the live noise estimate, the probe's lobe
and best echo, the echo detector, the search replanned for the measured noise): set only
through the Python API."""

SEARCH_GEOMETRY = ("passes", "growth", "max_spacing")
"""Options that set where a blind search looks beyond the fine lattice."""


def _search_plan(
    cls: type[Optimizer], objective: Objective, given: Mapping[str, Any]
) -> dict[str, Any]:
    """For a method that searches in passes by default (``auto``), unless the caller set
    the search geometry: ``passes`` from the objective's probe
    (:meth:`Objective.search_passes`), and ``replan``, the objective's passes for the echo
    it predicts against the noise the first ring measures
    (:meth:`Objective.passes_for_measured_noise`), unless the caller set ``fine_radius``;
    else ``{}``.  When the caller set where to search (the geometry or ``fine_radius``)
    and not ``posterior``, ``posterior`` is off: the posterior search would ignore it."""
    if not option_defaults(cls).get("passes"):
        return {}
    placed = any(k in given for k in (*SEARCH_GEOMETRY, "fine_radius"))
    plan: dict[str, Any] = {"posterior": False} if placed and "posterior" not in given else {}
    if any(k in given for k in SEARCH_GEOMETRY):
        return plan
    passes = objective.search_passes()
    if passes is not None:
        plan["passes"] = passes
    if "fine_radius" not in given and "replan" not in given:
        plan["replan"] = objective.passes_for_measured_noise
    return plan


def _acquisition_cost(opt: Optimizer, objective: Objective) -> int | None:
    """Measurements the acquisition phase spent until it handed over (points x repeats)."""
    found = getattr(opt, "found_at", None)
    return None if found is None else objective.cost(found)


def _beam_spread(recent: FloatArray, parameterization: str) -> float:
    """[deg] the largest angle between the beams of ``recent`` orientations ``(n, 2)``
    [deg] and their mean beam: what the probe's direction still moves.  In degrees of the
    angles themselves the azimuth at the pole (co-elevation 0, where it does not move the
    beam) would keep a converged run from ever settling."""
    az, coel = convert_angles(recent[:, 0], recent[:, 1], parameterization, "azimuth-coelevation")
    beams = orientation_normal(az, coel)
    return float(angle_between(beams, beams.mean(axis=0)).max())


def _settle_test(
    settle: tuple[float, int], objective: Objective
) -> Callable[[ArrayLike, ArrayLike], bool]:
    """A stateful test: True once the last ``patience`` recommendations [deg] lie within
    ``tol`` [deg] of their mean — and, when the objective knows its noise, the values
    measured in those iterations rose clearly (5 σ) above the noise floor, so a method
    parked on pure noise is not taken for converged."""
    try:
        tol, patience = settle
    except (TypeError, ValueError):
        raise EchocalValueError(
            f"settle must be a pair (tol [deg], patience); got {settle!r}"
        ) from None
    tol = positive_float("settle tol", tol)
    patience = positive_int("settle patience", patience)
    history: list[FloatArray] = []
    peaks: list[float] = []
    parameterization = getattr(objective, "parameterization", "tilt")

    def test(recommendation: ArrayLike, values: ArrayLike) -> bool:
        history.append(np.asarray(recommendation, dtype=np.float64))
        finite = np.asarray(values, dtype=np.float64)
        finite = finite[np.isfinite(finite)]
        peaks.append(float(finite.max()) if finite.size else -np.inf)
        if len(history) < patience:
            return False
        if _beam_spread(np.array(history[-patience:]), parameterization) >= tol:
            return False
        floor, sigma = objective.noise_estimate()
        if floor is None or sigma is None:
            return True
        return max(peaks[-patience:]) > floor + 5.0 * sigma

    return test


@one_blas_thread  # bit-reproducible: a seeded run gives the same numbers in any process
def calibrate(
    objective: Objective,
    method: str = "auto",
    x0: ArrayLike = (0.0, 0.0),
    *,
    budget: int | None = None,
    max_iter: int | None = None,
    xtol: float | None = None,
    settle: tuple[float, int] | None = DEFAULT_SETTLE,
    rng: RngLike = None,
    callback: Callable[[CalibrationState], bool | None] | None = None,
    acquire: bool | Mapping[str, Any] = False,
    preset: str | None = None,
    final_check: int = 1,
    **options: Any,
) -> CalibrationResult:
    """Find the orientation [deg] maximizing ``objective`` with ``method``.

    Parameters
    ----------
    objective : the counted, bounded measurement (see :class:`Objective`).
    method : a name from :func:`method_names` (default ``"auto"``).
    x0 : [deg], shape (2,), inside the objective's bounds (else LimitError).
    budget : maximum measurements for this run (also limited by the objective's own
        budget); a budget below what the first iteration needs raises EchocalValueError
        before measuring.  The run never exceeds it: it stops with status 2.
    max_iter : iteration limit (default: the preset's, else 100; an exhaustive method —
        ``grid`` — runs all its rows, and ``xtol``/``settle`` do not stop it).
    xtol : [deg] stop when an iteration moves the estimate (or proposes a step) shorter
        than this (after at least 2 iterations).
    settle : ``(tol [deg], patience)``: stop once the last ``patience`` recommendations
        lie within ``tol`` of their mean — a convergence test that noise cannot fool the
        way a single short step can (status 7).  Default
        :data:`~echocal.constants.DEFAULT_SETTLE` ``(0.01, 8)``, the command line's
        ``--settle`` default; None disables it.
    rng : seed or Generator (randomized methods; reproducible runs).
    callback : called with a :class:`CalibrationState` after each iteration; True stops.
    acquire : True (or a dict of :class:`Acquisition` options) puts an acquisition phase
        in front of the method.
    preset : take the method's options from a preset (``"thesis"``, ``"thesis-table-4"``,
        ...); explicit ``options`` override them.
    final_check : the final step moves to the estimate and measures it this many times
        (default 1; counted, and kept out of the method's budget so the run still never
        exceeds ``budget``); their mean is reported as ``fun`` and ``final_value``, and
        the echo there is part of the evidence for ``success``.  0 disables it (the
        positioner is then left at the last point the method probed).  Not done when no
        echo was found (status 4 or 6).
    **options : method options (see ``echocal methods NAME``); an unknown name raises
        UnknownNameError naming the closest valid one, and a value of the wrong type (e.g.
        a string for a number or a boolean) raises EchocalValueError naming the option,
        both before anything is measured.
    """
    t0 = time.perf_counter()
    if not isinstance(objective, Objective):
        raise EchocalValueError(
            f"objective must be an echocal.calibrate.Objective; got {type(objective).__name__}"
        )
    x0 = objective.check_point("x0", x0)
    gen = as_generator(rng)
    opts: dict[str, Any] = {}
    default_iter = 100
    if preset is not None:
        opts.update(method_options(method, preset))
        default_iter = presets(preset).max_iter
    opts.update(options)
    max_iter_given = max_iter is not None
    max_iter = default_iter if max_iter is None else positive_int("max_iter", max_iter)
    xtol = None if xtol is None else nonnegative_float("xtol", xtol)
    settled = None if settle is None else _settle_test(settle, objective)
    if isinstance(final_check, bool) or not isinstance(final_check, int | np.integer):
        raise EchocalValueError(f"final_check must be an integer >= 0; got {final_check!r}")
    final_check = int(final_check)
    if final_check < 0:
        raise EchocalValueError(f"final_check must be >= 0; got {final_check}")
    opt, used = build_optimizer(objective, method, x0, rng=gen, acquire=acquire, options=opts)

    limit = objective.remaining
    if budget is not None:
        budget = positive_int("budget", budget)
        limit = budget if limit is None else min(limit, budget)
    need = objective.cost(opt.min_budget)
    reserve = objective.cost(final_check)  # the final measurements at the estimate
    if limit is not None and limit < need + reserve:
        raise EchocalValueError(
            f"budget={limit} is smaller than one iteration of method {method!r} needs "
            f"({need} measurements) plus the final measurement(s) at the estimate "
            f"(final_check={final_check}: {reserve}); allowed: budget >= {need + reserve}"
            + (" (or final_check=0)" if reserve and limit >= need else "")
        )
    limit = None if limit is None else limit - reserve
    rows = getattr(opt, "n_rows", None)  # an exhaustive method: its whole set, row by row
    wrapped = isinstance(opt, Acquisition) and hasattr(opt.local_class, "n_rows")
    if rows is not None or wrapped:  # (behind a search, its rows are known once it starts)
        settled = xtol = None  # a partial grid has not "converged": it is measured through
        if not max_iter_given:
            max_iter = np.iinfo(np.int64).max  # it ends itself, after its last row
        elif rows is not None and max_iter < rows:
            warnings.warn(
                f"method {method!r} measures {rows} rows but max_iter={max_iter} stops it "
                f"after {max_iter}: only part of the grid will be searched",
                UserWarning,
                stacklevel=2,
            )
    planned = getattr(opt, "n_points", None)  # a method that measures a fixed set (grid)
    if planned is not None and limit is not None and objective.cost(planned) > limit:
        warnings.warn(
            f"method {method!r} has {planned} points to measure but the budget allows "
            f"{limit} measurements: only part of it will be searched (use a smaller span "
            "or a larger step, or a larger budget)",
            UserWarning,
            stacklevel=2,
        )

    start = objective.n_measurements
    bench_start = objective.bench_time
    saved_start = getattr(objective, "bench_time_saved", None)
    objective.search_snr_db = None  # set by the objective's replan, should this run make one
    iterates = [x0.copy()]
    counts = [0]
    status = 1
    prev = x0.copy()
    while True:
        if opt.finished:  # first: a method that ends on its last allowed iteration says why
            status = opt.finish_status if opt.finish_status is not None else 5
            break
        if opt.n_iterations >= max_iter:
            status = 1
            break
        pts = opt.ask()
        used_so_far = objective.n_measurements - start
        if limit is not None and used_so_far + objective.cost(len(pts)) > limit:
            status = 2
            break
        try:
            vals = objective(pts)
        except BudgetExhaustedError:
            status = 2
            break
        done = opt.tell(vals)
        if not done:
            continue
        it = opt.iterate
        iterates.append(it)
        counts.append(objective.n_measurements - start)
        moved = getattr(opt, "proposed_step", None)
        moved = float(np.hypot(*(it - prev))) if moved is None else float(moved)
        prev = it
        if callback is not None:
            state = CalibrationState(
                iteration=opt.n_iterations,
                n_measurements=objective.n_measurements - start,
                iterate=it.copy(),
                recommendation=opt.recommend(),
                points=pts.copy(),
                values=np.asarray(vals, dtype=np.float64).copy(),
            )
            if callback(state):
                status = 3
                break
        if xtol is not None and opt.n_iterations >= 2 and moved < xtol:
            status = 0
            break
        if settled is not None and settled(opt.recommend(), vals):
            status = 7
            break

    x = opt.recommend()
    fun = opt.recommend_value()
    log = objective.log
    searched = log.points[start:], log.values[start:]
    final = final_value = None
    if final_check and status != 4 and np.any(np.isfinite(searched[1])):
        final = objective(np.repeat(x[None, :], final_check, axis=0))
        good = final[np.isfinite(final)]
        fun = final_value = float(good.mean()) if good.size else None
        log = objective.log
    pts_all, vals_all, times = log.points[start:], log.values[start:], log.times[start:]
    if fun is None:
        at = np.all(np.isclose(pts_all, x, rtol=0.0, atol=1e-12), axis=1) & np.isfinite(vals_all)
        fun = float(vals_all[at].mean()) if np.any(at) else None
    status, detail = judge(status, x, opt, objective, searched, final)
    n_nan = int(np.count_nonzero(np.isnan(vals_all)))
    message = STATUS_MESSAGES[status] + detail
    replanned = getattr(opt, "replanned", None)
    if n_nan:
        message += f"; {n_nan} measurement(s) returned NaN (treated as the worst value seen)"
    uncertainty = objective.bench_uncertainty()
    message += _unresolved(uncertainty, settle, xtol)
    radius = None
    if status not in NO_ECHO_STATUSES | UNSUPPORTED_STATUSES:
        radius = estimate_radius(x, pts_all, vals_all, objective.noise_estimate())
    return CalibrationResult(
        x=x,
        fun=fun,
        success=status in SUCCESS_STATUSES,
        status=status,
        message=message,
        n_measurements=len(vals_all),
        n_iterations=opt.n_iterations,
        points=pts_all,
        values=vals_all,
        iterates=np.array(iterates).reshape(-1, 2),
        iteration_measurements=np.array(counts, dtype=np.int64),
        method=method,
        options=used,
        wall_time=time.perf_counter() - t0,
        n_nan=n_nan,
        parameterization=objective.parameterization,
        names=objective.names,
        times=times,
        acquisition_measurements=_acquisition_cost(opt, objective),
        search_passes=replanned,
        posterior_search=getattr(opt, "search", None) is not None,
        search_snr_db=None if replanned is None else objective.search_snr_db,
        final_value=final_value,
        bench_time=_bench_time(objective.bench_time, bench_start),
        bench_time_saved=_bench_time(getattr(objective, "bench_time_saved", None), saved_start),
        bench_uncertainty=uncertainty,
        false_alarms=len(getattr(opt, "false_alarms", ())),
        uncertainty=radius,
        uncertainty_level=UNCERTAINTY_LEVEL,
    )


def _unresolved(uncertainty: float | None, settle: Any, xtol: float | None) -> str:
    """The message's note when the positioner's error [deg] exceeds the convergence
    tolerance [deg] the run was held to (``settle``'s, else ``xtol``): the run's settling
    then says nothing below the positioner's error."""
    if uncertainty is None:
        return ""
    tol = float(settle[0]) if settle is not None else xtol
    note = f"; the estimate carries the positioner's error ({uncertainty:.3g}° RMS)"
    if tol is not None and uncertainty > tol:
        note += f", more than the convergence tolerance ({tol:g}°): not resolved below it"
    return note


def _bench_time(total: float | None, start: float | None) -> float | None:
    """[s] a bench-time total's growth since it stood at ``start`` (None while there is
    none)."""
    return None if total is None else total - (start or 0.0)
