"""What every scenario shares: its record (:class:`Scenario`), its result
(:class:`ScenarioResult`), the registry of names, and :func:`_finish`, which writes
``findings.json`` and ``summary.md``.  The scenarios themselves live in
:mod:`echocal.experiments.scenarios` (the thesis's) and beside it (echocal's own)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from echocal._validate import lookup
from echocal.errors import EchocalValueError
from echocal.experiments._findings import Finding
from echocal.experiments._output import write_summary

__all__ = ["Progress", "Scenario", "ScenarioResult", "get_scenario", "scenario_names"]


@dataclass(frozen=True)
class ScenarioResult:
    """What :func:`run_scenario` wrote and found.

    name, out_dir : the scenario and its folder; findings : the checked thesis claims;
    runs : the tidy table of runs (scenarios 1–2: the per-point A-scan table);
    summary : medians per configuration (None for scenarios 1–2); files : every file written;
    wall_time : [s].
    """

    name: str
    out_dir: Path
    findings: tuple[Finding, ...]
    runs: pd.DataFrame
    summary: pd.DataFrame | None
    files: tuple[Path, ...]
    wall_time: float

    @property
    def agrees(self) -> bool:
        """True when every finding agrees with the thesis."""
        return all(f.agrees for f in self.findings)


Progress = Callable[[int, int], None]
"""Called as ``progress(done, total)`` after each unit of work."""


@dataclass(frozen=True)
class Scenario:
    """A named thesis scenario: what it reproduces, and how to run it."""

    name: str
    title: str
    thesis: str
    description: str
    run: Callable[..., ScenarioResult] = field(repr=False)


_SCENARIOS: dict[str, Scenario] = {}


def _register(scenario: Scenario) -> None:
    if scenario.name in _SCENARIOS:
        raise EchocalValueError(f"scenario {scenario.name!r} is already registered")
    _SCENARIOS[scenario.name] = scenario


def scenario_names() -> list[str]:
    """Names of the thesis scenarios, in thesis order."""
    return list(_SCENARIOS)


def get_scenario(name: str) -> Scenario:
    """The scenario called ``name`` (an unknown name lists the valid ones)."""
    return lookup("scenario", name, _SCENARIOS)


def _finish(
    scenario: Scenario,
    out: Path,
    *,
    t0: float,
    setup: str,
    quick: bool,
    seeds: Sequence[int],
    findings: Sequence[Finding],
    notes: Sequence[str],
    runs: pd.DataFrame,
    summary: pd.DataFrame | None,
    tables: dict[str, pd.DataFrame],
    files: list[Path],
    figures: dict[str, list[Path]],
) -> ScenarioResult:
    """Write ``findings.json`` and ``summary.md``; the result with every file written.

    t0 : [s] ``time.perf_counter()`` at the start (the wall time ends before the summary);
    files : the tables written so far; figures : the figures written, by caption.
    """
    wall = time.perf_counter() - t0
    files = files + write_summary(
        out,
        scenario=scenario.name,
        title=scenario.title,
        thesis=scenario.thesis,
        description=scenario.description,
        setup=setup,
        quick=quick,
        seeds=seeds,
        findings=findings,
        notes=notes,
        tables=tables,
        figures=figures,
        wall_time=wall,
    )
    return ScenarioResult(
        name=scenario.name,
        out_dir=out,
        findings=tuple(findings),
        runs=runs,
        summary=summary,
        files=tuple(files + [p for v in figures.values() for p in v]),
        wall_time=wall,
    )
