"""The schema of sweep files: one pydantic model per table, its unit-aware and list-or-
scalar fields (see :mod:`echocal.experiments.sweep` for the file format)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from echocal.setups.fields import Angle, NotBool, Point

__all__ = ["MAX_SWEEP_RUNS", "MethodSpec", "SweepSalvage", "SweepSpec", "X0Spec"]

_NOISELESS = ("none", "off", "inf")


MAX_SWEEP_RUNS = 100_000
"""The most runs one sweep may hold: each takes seconds, so more is weeks on a workstation and
almost always a mistyped count (``seeds = 100000000``)."""


def _seed_count(value: Any) -> Any:
    """``seeds``: a count or list of at most :data:`MAX_SWEEP_RUNS` (checked before a range
    of a hundred million seeds is ever built); a boolean is refused, not read as 1 or 0."""
    items = value if isinstance(value, list) else [value]
    if any(isinstance(v, bool) for v in items):
        raise ValueError(f"must be a seed count or a list of seeds, not a boolean; got {value!r}")
    n = len(value) if isinstance(value, list) else value
    if isinstance(n, int) and not isinstance(n, bool) and n > MAX_SWEEP_RUNS:
        raise ValueError(
            f"{n:,} seeds exceed the cap of {MAX_SWEEP_RUNS:,} runs per sweep (a run takes "
            "seconds: split the study into several sweeps)"
        )
    return value


def _snr(value: Any) -> Any:
    if isinstance(value, str) and value.strip().lower() in _NOISELESS:
        return None
    return value


def _as_list(value: Any) -> Any:
    return value if isinstance(value, list | tuple) else [value]


def _offset(value: Any) -> Any:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return [value, value]
    return value


Snr = Annotated[Annotated[float, Field(allow_inf_nan=False)] | None, BeforeValidator(_snr), NotBool]
SnrList = Annotated[list[Snr] | None, BeforeValidator(lambda v: None if v is None else _as_list(v))]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class MethodSpec(_Model):
    """One calibration method of a sweep.

    Attributes
    ----------
    name : a method of :func:`echocal.calibrate.method_names`.
    preset : optional preset (``"thesis"``, ``"thesis-table-4"``, ...) giving default options.
    options : option -> value, or a list of values (a grid axis; axes are crossed).
        A literal list value is written as a list of one list: ``{ x = [[1, 2]] }``.
    label : optional display name (default: the method name).
    """

    name: str
    preset: str | None = None
    options: dict[str, Any] = Field(default_factory=dict)
    label: str | None = None


class X0Spec(_Model):
    """Initial guesses [deg]: explicit ``points`` and/or a random ``offset`` range from the truth.

    offset : [deg] ``[lo, hi]`` (or one number): each seed starts at a distance drawn
        uniformly from ``[lo, hi]`` from the true optimum, in a uniformly random direction
        (distances measured in the parameterization's two angles).
    """

    points: list[tuple[Angle, Angle]] = Field(default_factory=list)
    offset: Annotated[tuple[Angle, Angle] | None, BeforeValidator(_offset)] = None


class SweepSpec(_Model):
    """A sweep, as validated from a file; after :func:`load_sweep` every default is resolved.

    position : [m] shape (3,); xtol, tolerance : [deg]; snr_db : [dB], None = noiseless.
    """

    name: str = "sweep"
    description: str = ""
    setup: str = "thesis"
    position: Point | None = None
    parameterization: Literal["tilt", "azimuth-coelevation"] = "tilt"
    budget: Annotated[int | None, NotBool] = Field(default=None, ge=1)
    max_iter: Annotated[int, NotBool] = Field(default=100, ge=1)
    xtol: Annotated[float | None, NotBool] = Field(default=None, ge=0, allow_inf_nan=False)
    settle: (
        tuple[
            Annotated[float, NotBool, Field(gt=0)],
            Annotated[int, NotBool, Field(ge=1)],
        ]
        | None
    ) = None
    tolerance: Annotated[float, NotBool] = Field(default=0.1, gt=0, allow_inf_nan=False)
    seed: Annotated[int, NotBool] = Field(default=0, ge=0)
    seeds: Annotated[int | list[Annotated[int, Field(ge=0)]], BeforeValidator(_seed_count)] = 1
    snr_db: SnrList = None
    x0: X0Spec = X0Spec(points=[(0.0, 0.0)])
    methods: list[MethodSpec] = Field(default_factory=list)
    gate: str | None = None
    """The gate every run's metric is computed in (``--gate`` syntax, docs/gates.md):
    front-wall, back-wall, a gate of the setup or START,WIDTH; None: the whole recording."""

    @property
    def seed_list(self) -> list[int]:
        """The seeds of the sweep (``seeds = N`` means 0..N-1)."""
        return list(range(self.seeds)) if isinstance(self.seeds, int) else list(self.seeds)


@dataclass
class SweepSalvage:
    """What of a sweep file could be validated: ``index`` maps the kept methods to
    their entries in the file; ``dropped`` names the fields (``"x0.offset"`` for a
    sub-field) whose value was invalid and replaced by its default for the later checks."""

    index: list[int]
    dropped: set[str] = field(default_factory=set)

    def touched(self, name: str) -> bool:
        """True when ``name`` or one of its sub-fields was dropped."""
        return any(d == name or d.startswith(name + ".") for d in self.dropped)
