"""Sweep files: methods × parameter grid × SNRs × initial guesses × seeds, as TOML.

A sweep file names one setup and position and crosses everything else::

    name = "snr-study"
    setup = "thesis"                      # built-in or a setup file (relative to this file)
    position = ["10 mm", 0, "22 mm"]      # default: the setup's reference position
    parameterization = "tilt"
    budget = 120                          # measurements per run
    max_iter = 100
    xtol = 0.01                           # [deg] stop when a step is shorter (optional)
    settle = [0.01, 8]                    # [deg, iterations] stop once settled (optional)
    tolerance = 0.1                       # [deg] success threshold
    seeds = 20                            # seeds 0..19, or a list
    snr_db = [30, 20, 10]                 # default: the setup's SNR; "none" = noiseless
    [x0]
    points = [[0, 0]]                     # [deg] explicit initial guesses, and/or
    offset = [2, 5]                       # [deg] a random start 2..5 deg from the truth
    [[methods]]
    name = "spsa"
    preset = "thesis"                     # optional: start from a preset's options
    options = { eps = [0.05, 0.1] }       # a list is a grid axis; lists are crossed

:func:`load_sweep` validates the file (every problem at once, each with its field
path, like setup files) and resolves every default, so the returned
:class:`SweepSpec` says exactly what runs.  :func:`expand` turns it into
:class:`RunCase` s — one per run, each a complete, hashable description from which
:func:`echocal.experiments.runner.run_case` computes the same result in any process.
"""

from __future__ import annotations

import hashlib
import importlib.resources
import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from pydantic import ValidationError

from echocal.errors import ConfigError, DataFileError, EchocalError, UnknownNameError
from echocal.experiments.sweep_checks import run_problems
from echocal.experiments.sweep_schema import (
    MAX_SWEEP_RUNS,
    MethodSpec,
    SweepSalvage,
    SweepSpec,
    X0Spec,
)
from echocal.experiments.sweep_values import (
    _derive_seed,
    _grid,
    _num,
    _plain,
    _x0_seed,
    offset_start,
)
from echocal.setups import builtin_setup_names, load_setup_config
from echocal.setups.schema import _format_errors

__all__ = [
    "MAX_SWEEP_RUNS",
    "MethodSpec",
    "RunCase",
    "SweepSpec",
    "X0Spec",
    "builtin_sweep_names",
    "expand",
    "load_sweep",
    "offset_start",
    "run_problems",
    "spec_hash",
]


@dataclass(frozen=True, kw_only=True)
class RunCase:
    """Everything one run needs: a pure function of this (and nothing else) gives its result.

    setup : built-in setup name or absolute path; position : [m] (3,);
    xtol : [deg] convergence stop of :func:`~echocal.calibrate.calibrate` (None: off);
    settle : (tol [deg], patience) settle stop of ``calibrate`` (None: off);
    tolerance : [deg]; snr_db : [dB] or None (noiseless); params : sorted (option, value)
    pairs; x0 : [deg] the start (``x0_kind="point"``) or the ``(lo, hi)`` distance range
    from the truth (``"offset"``); x0_index : which entry of the sweep's x0 list;
    seed : the sweep seed of this run; sweep_seed : the sweep's base seed.
    """

    sweep: str
    setup: str
    position: tuple[float, float, float]
    parameterization: str
    budget: int | None
    max_iter: int
    xtol: float | None
    settle: tuple[float, int] | None
    tolerance: float
    sweep_seed: int
    method: str
    preset: str | None
    label: str
    params: tuple[tuple[str, Any], ...]
    snr_db: float | None
    x0_kind: str
    x0: tuple[float, float]
    x0_index: int
    seed: int
    gate: str | None = None

    @property
    def params_json(self) -> str:
        """The method options of the grid as compact JSON (sorted keys)."""
        return json.dumps(_plain(dict(self.params)), sort_keys=True, separators=(",", ":"))

    @property
    def x0_label(self) -> str:
        """``"(a,b)"`` for an explicit start, ``"offset(lo,hi)"`` for a random one [deg]."""
        a, b = (_num(v) for v in self.x0)
        return f"({a},{b})" if self.x0_kind == "point" else f"offset({a},{b})"

    @property
    def snr_label(self) -> str:
        """``"30"`` [dB] or ``"none"``."""
        return "none" if self.snr_db is None else _num(self.snr_db)

    @property
    def case_id(self) -> str:
        """Stable, readable identifier, unique within a sweep.

        ``label@preset{options}/snr=S/x0=X/seed=N``, e.g.
        ``spsa@thesis{"eps":0.05}/snr=30/x0=(0,0)/seed=3``.
        """
        method = self.label + (f"@{self.preset}" if self.preset else "")
        return (
            f"{method}{self.params_json}/snr={self.snr_label}/x0={self.x0_label}/seed={self.seed}"
        )

    @property
    def run_seed(self) -> int:
        """Seed of this run (noise and method), derived from the sweep seed and the case id."""
        return _derive_seed(self.sweep_seed, self.case_id)

    @property
    def x0_seed(self) -> int:
        """Seed of a random start: the sweep seed, the run's seed and the x0 entry only, so
        every method and SNR of a seed starts from the same point (paired comparison)."""
        return _x0_seed(self.sweep_seed, self.x0_index, self.seed)


def builtin_sweep_names() -> tuple[str, ...]:
    """Names of the sweeps shipped with echocal (``echocal/data/sweeps/*.toml``)."""
    folder = importlib.resources.files("echocal") / "data" / "sweeps"
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


def _read(source: str | Path) -> tuple[dict[str, Any], Path, str]:
    text = str(source)
    if text in builtin_sweep_names():
        resource = importlib.resources.files("echocal") / "data" / "sweeps" / f"{text}.toml"
        raw, where = resource.read_text(encoding="utf-8"), f"built-in sweep {text!r}"
        base = Path.cwd()
    else:
        path = Path(text)
        if not path.is_file():
            if path.suffix != ".toml":
                raise UnknownNameError(
                    f"unknown sweep {text!r}: not a built-in "
                    f"({', '.join(builtin_sweep_names())}) and no such .toml file"
                )
            raise DataFileError(f"sweep file not found: {path}")
        try:
            raw = path.read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            raise ConfigError(f"{path}: not valid TOML: {exc}") from None
        where, base = str(path), path.resolve().parent
    try:
        return tomllib.loads(raw), base, where
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML: {exc}") from None


def load_sweep(
    source: str | Path | dict[str, Any] | SweepSpec,
    *,
    base_dir: str | Path | None = None,
    check_runs: bool = True,
) -> SweepSpec:
    """Read, validate and resolve a sweep: a built-in name, a TOML path, a dict or a spec.

    Relative setup paths resolve against the sweep file's folder (``base_dir`` for a
    dict or spec, default the working directory).  Defaults are filled in from the setup:
    ``position`` (its reference position) and ``snr_db`` (its SNR).  ``check_runs=False``
    skips the dry run of every run configuration (:func:`run_problems`; ≈ 1 s) when only
    the sweep's description is wanted.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field
    path: ``methods.0.options.epsilon: unknown option of method 'spsa'; accepted: ...``.
    """
    where = "sweep"
    if isinstance(source, SweepSpec):
        raw: dict[str, Any] = source.model_dump()
    elif isinstance(source, dict):
        raw = source
    else:
        raw, file_base, where = _read(source)
        base_dir = file_base if base_dir is None else base_dir
    base = Path.cwd() if base_dir is None else Path(base_dir)
    problems: list[str] = []
    try:
        spec: SweepSpec | None = SweepSpec.model_validate(raw)
        part = SweepSalvage(index=list(range(len(spec.methods))))  # type: ignore[union-attr]
    except ValidationError as exc:
        problems += _format_errors(exc, hint="see docs/sweeps.md")
        spec, part = _salvage(raw, exc)
    if spec is None:  # nothing more can be checked
        _raise(where, problems)
    found, bad_methods = _check(spec, part)
    problems += found
    resolved = None
    if "setup" not in part.dropped:
        try:
            resolved = _resolve(spec, base)
        except EchocalError as exc:
            problems.append(f"setup: {exc}")
    if resolved is not None and check_runs:
        problems += run_problems(resolved, _part=part, _skip=bad_methods)
    if problems:
        _raise(where, problems)
    assert resolved is not None
    return resolved


def _salvage(raw: Any, exc: ValidationError) -> tuple[SweepSpec | None, SweepSalvage]:
    """The sweep without its invalid values, so that the checks beyond the schema can report
    their problems in the same error (a bad budget does not hide a misspelt method)."""
    part = SweepSalvage(index=[])
    if not isinstance(raw, dict):
        return None, part
    data = dict(raw)
    bad_methods: set[int] = set()
    x0 = dict(raw["x0"]) if isinstance(raw.get("x0"), dict) else None
    for error in exc.errors():
        loc = error["loc"]
        if not loc:
            return None, part
        top = str(loc[0])
        if top == "methods" and len(loc) > 1 and isinstance(loc[1], int):
            bad_methods.add(loc[1])
        elif top == "x0" and x0 is not None and len(loc) > 1 and isinstance(loc[1], str):
            x0.pop(loc[1], None)
            part.dropped.add(f"x0.{loc[1]}")
        else:
            data.pop(top, None)
            part.dropped.add(top)
    if x0 is not None and "x0" not in part.dropped:
        data["x0"] = x0
    methods = data.get("methods")
    if isinstance(methods, list):
        part.index = [i for i in range(len(methods)) if i not in bad_methods]
        data["methods"] = [methods[i] for i in part.index]
        if bad_methods:
            part.dropped.add("methods.*")
    try:
        return SweepSpec.model_validate(data), part
    except ValidationError:
        return None, part


def _raise(where: str, problems: list[str]) -> NoReturn:
    raise ConfigError(f"{where}: {len(problems)} problem(s):\n  " + "\n  ".join(problems))


def _check(spec: SweepSpec, part: SweepSalvage) -> tuple[list[str], set[int]]:
    """Problems pydantic cannot see: methods, options, presets and empty grids.

    Returns the problems and the positions (in ``spec.methods``) of the methods with one.
    """
    from echocal.calibrate import get_method, preset_names
    from echocal.calibrate._options import accepted_options

    problems = []
    bad: set[int] = set()
    if not spec.methods and not part.touched("methods"):
        problems.append("methods: at least one [[methods]] entry is needed (empty grid)")
    if isinstance(spec.seeds, int) and spec.seeds < 1:
        problems.append(f"seeds: must be >= 1 (empty grid), got {spec.seeds}")
    if isinstance(spec.seeds, list) and not spec.seeds:
        problems.append("seeds: empty list (empty grid)")
    if isinstance(spec.seeds, list) and len(set(spec.seeds)) != len(spec.seeds):
        problems.append(f"seeds: duplicate seeds in {spec.seeds}")
    if spec.snr_db is not None and not spec.snr_db:
        problems.append("snr_db: empty list (empty grid)")
    if spec.snr_db is not None and len(set(spec.snr_db)) != len(spec.snr_db):
        problems.append(f"snr_db: duplicate values in {spec.snr_db}")
    if not spec.x0.points and spec.x0.offset is None and not part.touched("x0"):
        problems.append("x0: give points and/or offset (empty grid)")
    if spec.x0.offset is not None and not 0 <= spec.x0.offset[0] <= spec.x0.offset[1]:
        problems.append(
            f"x0.offset: must be [lo, hi] with 0 <= lo <= hi [deg], got {spec.x0.offset}"
        )
    labels: dict[str, int] = {}
    for i, method in enumerate(spec.methods):
        at = f"methods.{part.index[i]}"
        n_before = len(problems)
        try:
            cls = get_method(method.name)
        except UnknownNameError as exc:
            problems.append(f"{at}.name: {exc}")
            bad.add(i)
            continue
        if method.preset is not None and method.preset not in preset_names():
            problems.append(
                f"{at}.preset: unknown preset {method.preset!r}; "
                f"choose one of: {', '.join(preset_names())}"
            )
        accepted = sorted(accepted_options(cls))
        for key, value in method.options.items():
            if key not in accepted:
                problems.append(
                    f"{at}.options.{key}: unknown option of method {method.name!r}; "
                    f"accepted: {', '.join(accepted)}"
                )
            elif isinstance(value, list) and not value:
                problems.append(f"{at}.options.{key}: empty list (empty grid)")
            elif isinstance(value, list) and len(set(map(repr, value))) != len(value):
                problems.append(f"{at}.options.{key}: duplicate values in {value}")
        key = f"{method.label or method.name}@{method.preset}"
        if key in labels:
            problems.append(
                f"{at}: same method and preset as methods.{labels[key]}; give one a `label` "
                "or merge their options into one grid"
            )
        labels[key] = part.index[i]
        if len(problems) > n_before:
            bad.add(i)
    return problems, bad


def _resolve(spec: SweepSpec, base: Path) -> SweepSpec:
    setup = spec.setup
    if setup not in builtin_setup_names():
        path = Path(setup)
        setup = str((path if path.is_absolute() else base / path).resolve())
    config, _ = load_setup_config(setup)
    update: dict[str, Any] = {"setup": setup}
    if spec.position is None:
        update["position"] = tuple(float(v) for v in config.positioner.reference_position)
    if spec.snr_db is None:
        update["snr_db"] = [config.noise.snr_db]
    return spec.model_copy(update=update)


def spec_hash(spec: SweepSpec) -> str:
    """SHA-256 of the resolved spec and of the setup file's text (what the results depend on).

    ``name`` and ``description`` are excluded: renaming a sweep does not change its results.
    """
    data = spec.model_dump(mode="json", exclude={"name", "description"})
    data["setup_text"] = _setup_text(spec.setup)
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _setup_text(setup: str) -> str:
    if setup in builtin_setup_names():
        resource = importlib.resources.files("echocal") / "data" / "setups" / f"{setup}.toml"
        return resource.read_text(encoding="utf-8")
    return Path(setup).read_text(encoding="utf-8")


# ---------------------------------------------------------------- expansion
def expand(spec: SweepSpec) -> list[RunCase]:
    """Every run of a resolved sweep: methods × grid × SNRs × initial guesses × seeds.

    The order is the nesting order above (seeds innermost); case ids are unique.
    """
    if spec.position is None or spec.snr_db is None:
        spec = load_sweep(spec)
    position, snrs = spec.position, spec.snr_db
    assert position is not None and snrs is not None  # load_sweep resolved both
    starts: list[tuple[str, tuple[float, float]]] = [
        ("point", (float(a), float(b))) for a, b in spec.x0.points
    ]
    if spec.x0.offset is not None:
        starts.append(("offset", (float(spec.x0.offset[0]), float(spec.x0.offset[1]))))
    n_seeds = spec.seeds if isinstance(spec.seeds, int) else len(spec.seeds)
    count = sum(len(_grid(m.options)) for m in spec.methods) * len(spec.snr_db or [None])
    count *= len(starts) * n_seeds
    if count > MAX_SWEEP_RUNS:
        raise ConfigError(
            f"sweep {spec.name!r}: {count:,} runs exceed the cap of {MAX_SWEEP_RUNS:,} runs per "
            "sweep (methods x option grid x SNRs x starts x seeds); split it into smaller sweeps"
        )
    cases = [
        RunCase(
            sweep=spec.name,
            setup=spec.setup,
            position=(float(position[0]), float(position[1]), float(position[2])),
            parameterization=spec.parameterization,
            budget=spec.budget,
            max_iter=spec.max_iter,
            xtol=spec.xtol,
            settle=None if spec.settle is None else (float(spec.settle[0]), int(spec.settle[1])),
            tolerance=float(spec.tolerance),
            sweep_seed=spec.seed,
            method=method.name,
            preset=method.preset,
            label=method.label or method.name,
            params=params,
            snr_db=None if snr is None else float(snr),
            x0_kind=kind,
            x0=x0,
            x0_index=index,
            seed=seed,
            gate=spec.gate,
        )
        for method in spec.methods
        for params in _grid(method.options)
        for snr in snrs
        for index, (kind, x0) in enumerate(starts)
        for seed in spec.seed_list
    ]
    ids = [c.case_id for c in cases]
    if len(set(ids)) != len(ids):  # e.g. x0.points listing the same point twice
        dup = next(i for i in ids if ids.count(i) > 1)
        raise ConfigError(f"sweep {spec.name!r}: duplicate run {dup!r}; remove repeated values")
    if not cases:
        raise ConfigError(f"sweep {spec.name!r}: the grid is empty")
    return cases
