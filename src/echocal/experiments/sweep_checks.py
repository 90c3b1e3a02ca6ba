"""What would make a sweep's runs fail, found without measuring (:func:`run_problems`)."""

from __future__ import annotations

import json
import warnings
from typing import Any

from echocal.errors import EchocalError
from echocal.experiments.sweep_schema import SweepSalvage, SweepSpec
from echocal.experiments.sweep_values import _grid, _plain, _thawed, _x0_seed, offset_start

__all__ = ["run_problems"]


class _Reached(Exception):
    """A dry run got as far as its first measurement: the run's configuration is valid."""


def run_problems(
    spec: SweepSpec,
    *,
    _part: SweepSalvage | None = None,
    _skip: set[int] | frozenset[int] = frozenset(),
) -> list[str]:
    """Problems that would make runs of a resolved sweep fail, found without measuring.

    Builds the setup at every SNR of the sweep, checks the position against the
    positioner's limits and every start against the angle bounds (the explicit ones and
    every seed's random ``x0.offset`` start, drawn as the runs draw it), and runs
    :func:`~echocal.calibrate.calibrate` for every method and option combination up to
    (not including) its first measurement, so that what ``calibrate`` refuses before
    measuring — option values the method rejects, a budget below what one iteration of
    the method needs — is reported here, one line each with its field path.
    """
    import numpy as np

    from echocal.calibrate import calibrate
    from echocal.measurement.objective import SourceObjective
    from echocal.setups import setup_with_overrides

    part = _part or SweepSalvage(index=list(range(len(spec.methods))))
    problems: list[str] = []
    setups = []
    for k, snr in enumerate(spec.snr_db or [None]):
        try:
            setups.append(setup_with_overrides(spec.setup, snr_db=snr, seed=0))
        except EchocalError as exc:
            problems.append(f"snr_db.{k}: the setup at {snr} dB cannot be built: {exc}")
    if not setups:
        return problems
    virtual = setups[0]
    position = np.asarray(spec.position, dtype=np.float64)
    gate = None
    if spec.gate is not None:
        from echocal.signal.gates import setup_gate

        try:
            gate = setup_gate(spec.gate, virtual, field="gate")
        except EchocalError as exc:
            problems.append(str(exc))
    limits = virtual.limits
    outside = [
        f"{name}={value * 1e3:g} mm outside [{low * 1e3:g}, {high * 1e3:g}] mm"
        for name, value in zip("xyz", position, strict=True)
        for low, high in [getattr(limits, name)]
        if not low <= value <= high
    ]
    if outside and not part.touched("position"):
        problems.append(
            f"position: outside the positioner limits of setup {spec.setup!r}: "
            f"{'; '.join(outside)}; choose a reachable position"
        )
    if not outside and not part.touched("position"):
        if (problem := _echo_problem(virtual, position)) is not None:
            problems.append(f"position: {problem}")

    class DryRun(SourceObjective):
        def _evaluate(self, points: Any) -> Any:
            raise _Reached

    def objective() -> SourceObjective:
        return DryRun(virtual, position, parameterization=spec.parameterization, gate=gate)

    bounds = objective().bounds
    starts = []
    if not part.touched("parameterization"):
        for j, point in enumerate(spec.x0.points):
            try:
                starts.append(objective().check_point("x0", point))
            except EchocalError as exc:
                problems.append(f"x0.points.{j}: {exc}; choose a start inside the bounds")
    if spec.x0.offset is not None and not (outside or part.touched("parameterization")):
        names = objective().names
        if (problem := _offset_problem(spec, virtual, position, bounds, names)) is not None:
            problems.append(problem)
    start = starts[0] if starts else bounds.mean(axis=1)
    for i, method in enumerate(spec.methods):
        if i in _skip:
            continue
        seen: set[str] = set()
        for params in _grid(method.options):
            options = {k: _thawed(v) for k, v in params}
            label = method.label or method.name
            if params:
                label += " " + json.dumps(_plain(options), sort_keys=True)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    calibrate(
                        objective(),
                        method.name,
                        start,
                        budget=None if part.touched("budget") else spec.budget,
                        max_iter=spec.max_iter,
                        xtol=spec.xtol,
                        settle=spec.settle,
                        rng=0,
                        preset=method.preset,
                        **options,
                    )
            except _Reached:
                continue
            except EchocalError as exc:
                message = str(exc)
            except Exception as exc:  # a method's own check that is not an echocal error
                message = f"{type(exc).__name__}: {exc}"
            if message not in seen:
                seen.add(message)
                problems.append(f"methods.{part.index[i]} ({label}): {message}")
    return problems


def _offset_problem(
    spec: SweepSpec, virtual: Any, position: Any, bounds: Any, names: tuple[str, str]
) -> str | None:
    """Why the random starts ``truth + offset`` of ``spec.x0.offset`` cannot all be run
    (None if every seed's start lies inside the angle ``bounds`` [deg], shape (2, 2)).

    The starts are the runs' own: the same truth and the same draws as
    :func:`~echocal.experiments.runner.run_case`, one per seed, so a sweep that passes runs
    exactly what it says (a start outside would be clipped to the nearest bound).
    """
    import numpy as np

    lo, hi = spec.x0.offset  # type: ignore[misc]
    if not 0 <= lo <= hi:
        return None  # reported by the schema check
    try:
        truth = np.array(virtual.true_optimum(position, parameterization=spec.parameterization))
    except EchocalError:
        return None  # every run fails there: the position's problem, reported as such
    index = len(spec.x0.points)  # the offset is the last start entry (see expand)
    seeds = spec.seed_list
    drawn = {
        seed: offset_start(_x0_seed(spec.seed, index, seed), (lo, hi), truth) for seed in seeds
    }
    bad = {
        seed: x0 for seed, x0 in drawn.items() if np.any((x0 < bounds[:, 0]) | (x0 > bounds[:, 1]))
    }
    if not bad:
        return None
    shown = ", ".join(
        f"seed {seed} x0=({x0[0]:.2f}, {x0[1]:.2f})" for seed, x0 in list(bad.items())[:3]
    )
    more = f" and {len(bad) - 3} more" if len(bad) > 3 else ""
    margin = float(np.min(np.abs(bounds - truth[:, None])))  # the truth to the nearest bound
    within = (
        f"offsets up to {margin:.2f} deg keep every start inside"
        if np.all((truth >= bounds[:, 0]) & (truth <= bounds[:, 1]))
        else "the truth itself is outside the bounds"
    )
    return (
        f"x0.offset: [{lo:g}, {hi:g}] deg from the truth ({names[0]}={truth[0]:.2f}, "
        f"{names[1]}={truth[1]:.2f}) puts {len(bad)} of {len(seeds)} start(s) (x0 = truth + "
        f"offset, one per seed) outside the bounds {names[0]} in [{bounds[0, 0]:.2f}, "
        f"{bounds[0, 1]:.2f}], {names[1]} in [{bounds[1, 0]:.2f}, {bounds[1, 1]:.2f}] "
        f"deg: {shown}{more}; {within}"
    )


def _echo_problem(virtual: Any, position: Any) -> str | None:
    """Why no run at ``position`` [m] can succeed on ``virtual`` (None if nothing is known).

    Every run computes the true optimum first, a search that starts by simulating the
    beam towards the nearest surface point (:meth:`VirtualSetup.true_optimum`): a probe
    inside the specimen, no surface within 60 deg of straight down, or a recording window
    that cannot contain the echo there fails every run — as ``calibrate`` refuses it.
    """
    from echocal.geometry import pose_from_angles
    from echocal.measurement.recording import simulation_errors

    x, y, z = (1e3 * float(v) for v in position)
    where = f"({x:g}, {y:g}, {z:g}) mm"
    try:
        tilt = virtual.perpendicular_start(position)
    except EchocalError as exc:
        return f"every run would fail at {where}: {exc}; choose another position"
    pose = pose_from_angles(position, float(tilt[0]), float(tilt[1]), "tilt")
    (error,) = simulation_errors(virtual, [pose])
    if error is None:
        return None
    return (
        f"every run would fail at {where}: {error}; choose another position or adjust the "
        "setup (its window or specimen)"
    )
