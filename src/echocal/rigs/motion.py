"""A SCPI-style motion controller as echocal's positioner (PyVISA, serial or TCP).

:class:`VisaPositioner` drives five axes — x, y, z [m] and azimuth, co-elevation
[deg] — each mapped to one controller axis with a scale (controller units per SI
unit: 1000 for a linear axis counted in mm, 1 for a rotation in degrees), or held
at a fixed value when the rig has no such axis.  Per move it sends, for each axis,
the *move* command (absolute), asks the *error* query (a refused move raises
:class:`~echocal.errors.LimitError` when the controller names a limit, else
:class:`~echocal.errors.InstrumentError`), then polls the *done* query until every
axis has stopped (at most ``motion_timeout`` [s]) and reads the positions back.
Limits come from the controller's *limits* queries, intersected with those given
in the rig file.  Command templates come from :data:`MOTION_PRESETS` and may be
overridden one by one; they may use ``{axis}`` and (move only) ``{value}``, e.g.
``{value:.4f}``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any

from echocal._validate import lookup, positive_float
from echocal.errors import EchocalValueError, InstrumentError, LimitError
from echocal.geometry import Pose
from echocal.measurement.limits import PositionerLimits
from echocal.rigs.visa_io import Nonsense, VisaInstrument, parse_float

__all__ = ["AXES", "MOTION_PRESETS", "Axis", "MotionPreset", "VisaPositioner", "motion_preset"]

AXES = ("x", "y", "z", "azimuth", "coelevation")
"""echocal's five positioner axes, in :class:`~echocal.geometry.Pose` order."""

LINEAR_AXES = ("x", "y", "z")


@dataclass(frozen=True, slots=True)
class MotionPreset:
    """Command templates of one motion-controller family.

    Attributes
    ----------
    name, family : the preset's name and the controllers it is written for.
    move : absolute move of ``{axis}`` to ``{value}`` (controller units).
    position : query answering the position of ``{axis}``.
    limits : query answering ``low,high`` of ``{axis}``; or empty and ...
    limits_low, limits_high : ... one query per bound (empty: no limits query).
    done : query answering ``done_value`` once ``{axis}`` has stopped.
    error : query answering ``code,message`` (code 0: no error); empty: not asked.
    limit_codes : error codes meaning "out of the travel limits" (besides messages that
        say LIMIT or OUT OF RANGE).
    setup : commands sent once on connecting (e.g. motors on).
    """

    name: str
    family: str
    move: str
    position: str
    done: str
    limits: str = ""
    limits_low: str = ""
    limits_high: str = ""
    done_value: str = "1"
    error: str = ""
    limit_codes: tuple[str, ...] = ()
    setup: tuple[str, ...] = ()


MOTION_PRESETS: dict[str, MotionPreset] = {
    p.name: p
    for p in (
        MotionPreset(
            name="scpi",
            family="SCPI-style controllers (MOVE:ABS, POS?, LIM?, MOVE:DONE?, SYST:ERR?); "
            "the simulated controller shipped with echocal",
            move="MOVE:ABS {axis},{value:.6f}",
            position="POS? {axis}",
            limits="LIM? {axis}",
            done="MOVE:DONE? {axis}",
            error="SYST:ERR?",
            limit_codes=("-222",),  # SCPI: data out of range
        ),
        MotionPreset(
            name="newport-esp",
            family="Newport ESP300/ESP301 (PA, TP?, SL?/SR?, MD?, TB?)",
            move="{axis}PA{value:.6f}",
            position="{axis}TP?",
            limits_low="{axis}SL?",
            limits_high="{axis}SR?",
            done="{axis}MD?",
            error="TB?",
            setup=("{axis}MO",),
        ),
    )
}
"""Command templates per motion-controller family (see :class:`MotionPreset`)."""


def motion_preset(name: str, **overrides: Any) -> MotionPreset:
    """The preset ``name`` with some templates replaced; unknown names list the valid ones."""
    preset = lookup("motion preset", name, MOTION_PRESETS)
    fields = {f.name for f in dataclasses.fields(MotionPreset)} - {"name", "family"}
    unknown = sorted(set(overrides) - fields)
    if unknown:
        raise EchocalValueError(
            f"unknown motion command {unknown[0]!r}; known: {', '.join(sorted(fields))}"
        )
    clean: dict[str, Any] = {
        k: tuple(v) if k in ("setup", "limit_codes") else v for k, v in overrides.items()
    }
    return dataclasses.replace(preset, **clean)


@dataclass(frozen=True, slots=True)
class Axis:
    """One of echocal's axes on the controller.

    Attributes
    ----------
    name : one of :data:`AXES`.
    id : the controller's axis name (``{axis}`` in the templates); None for a fixed axis.
    scale : controller units per SI unit ([1/m] for x, y, z; [1/deg] for angles).
    fixed : [m] or [deg] the value of an axis the rig does not move (``id`` is None).
    limits : [m] or [deg] travel limits from the rig file (intersected with the
        controller's); None to take the controller's alone.
    """

    name: str
    id: str | None = None
    scale: float = 1.0
    fixed: float | None = None
    limits: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.name not in AXES:
            raise EchocalValueError(f"unknown axis {self.name!r}; axes: {', '.join(AXES)}")
        if (self.id is None) == (self.fixed is None):
            raise EchocalValueError(
                f"axis {self.name}: give either the controller's axis id or a fixed value"
            )
        positive_float(f"axis {self.name} scale", self.scale)


class VisaPositioner:
    """:class:`~echocal.measurement.hardware.Positioner` on a motion controller.

    Parameters
    ----------
    instrument : the VISA resource (owned: closed by :meth:`close`).
    preset : the controller family's commands (:func:`motion_preset`).
    axes : the five axes (:class:`Axis`), one per name of :data:`AXES`.
    motion_timeout : [s] the longest a move may take.
    poll_interval : [s] between two *done* queries.
    """

    def __init__(
        self,
        instrument: VisaInstrument,
        preset: MotionPreset,
        axes: dict[str, Axis] | list[Axis],
        *,
        motion_timeout: float = 60.0,
        poll_interval: float = 0.02,
    ) -> None:
        table = {a.name: a for a in axes} if isinstance(axes, list) else dict(axes)
        missing = [name for name in AXES if name not in table]
        if missing:
            raise EchocalValueError(
                f"positioner axes: missing {', '.join(missing)}; a positioner needs all of "
                f"{', '.join(AXES)} (map each to a controller axis, or give it a fixed value)"
            )
        if not (preset.limits or preset.limits_low or preset.limits_high):
            unlimited = [n for n in AXES if table[n].id is not None and table[n].limits is None]
            if unlimited:
                raise EchocalValueError(
                    f"positioner axes {', '.join(unlimited)}: the {preset.name} preset "
                    "cannot ask the controller's limits; give limits = [low, high] for each"
                )
        self.instrument = instrument
        self.preset = preset
        self.axes = {name: table[name] for name in AXES}
        self.motion_timeout = positive_float("motion_timeout", motion_timeout)
        self.poll_interval = positive_float("poll_interval", poll_interval)
        self._limits: PositionerLimits | None = None
        self._ready = False

    @property
    def description(self) -> str:
        """The preset and the resource."""
        return f"{self.preset.name} motion controller at {self.instrument.resource}"

    def identify(self) -> str:
        """The controller's ``*IDN?`` answer."""
        return self.instrument.identify()

    def _moving(self) -> list[Axis]:
        return [a for a in self.axes.values() if a.id is not None]

    def _setup(self) -> None:
        if not self._ready:
            for axis in self._moving():
                for template in self.preset.setup:
                    self.instrument.write(template.format(axis=axis.id))
            self._ready = True

    # -- limits -----------------------------------------------------------------------------
    def _controller_limits(self, axis: Axis) -> tuple[float, float]:
        p = self.preset
        if p.limits:
            command = p.limits.format(axis=axis.id)
            text = self.instrument.query(command)
            parts = text.replace(";", ",").split(",")
            if len(parts) != 2:
                raise InstrumentError(
                    f"{command}: VISA resource {self.instrument.resource} answered "
                    f"nonsense: expected 'low,high'; got {text[:80]!r}"
                )
            low, high = (self._parse(command, v) for v in parts)
        else:
            low = self.instrument.query_float(p.limits_low.format(axis=axis.id))
            high = self.instrument.query_float(p.limits_high.format(axis=axis.id))
        return low / axis.scale, high / axis.scale

    def _parse(self, command: str, text: str) -> float:
        try:
            return parse_float(text, command)
        except Nonsense as exc:
            raise InstrumentError(
                f"{command}: VISA resource {self.instrument.resource} answered nonsense: {exc}"
            ) from None

    @property
    def limits(self) -> PositionerLimits:
        """Asked once from the controller (intersected with the rig file's), then cached."""
        if self._limits is None:
            bounds: dict[str, tuple[float, float]] = {}
            asks = bool(self.preset.limits or self.preset.limits_low)
            for name, axis in self.axes.items():
                if axis.id is None:
                    assert axis.fixed is not None
                    bounds[name] = (axis.fixed, axis.fixed)
                    continue
                low, high = -math.inf, math.inf
                if asks:
                    low, high = self._controller_limits(axis)
                if axis.limits is not None:
                    low, high = max(low, axis.limits[0]), min(high, axis.limits[1])
                bounds[name] = (low, high)
            self._limits = PositionerLimits(**bounds)
        return self._limits

    # -- motion -----------------------------------------------------------------------------
    def _check_error(self, command: str) -> None:
        """Ask the error query; raise LimitError / InstrumentError for a refused command."""
        if not self.preset.error:
            return
        text = self.instrument.query(self.preset.error)
        code, _, message = text.partition(",")
        code = code.strip().lstrip("+")
        if code in ("0", "") or (code.lstrip("-").isdigit() and int(code) == 0):
            return
        words = message.upper()
        if code in self.preset.limit_codes or "LIMIT" in words or "OUT OF RANGE" in words:
            raise LimitError(f"{command}: the controller refused the move: {text.strip()}")
        raise InstrumentError(
            f"{command}: VISA resource {self.instrument.resource} reported error {text.strip()}"
        )

    def move_to(self, pose: Pose) -> Pose:
        """Move every axis (absolute), wait until all have stopped; return the pose reached."""
        self._setup()
        values = dict(zip(AXES, pose.as_array(), strict=True))
        for axis in self._moving():
            command = self.preset.move.format(axis=axis.id, value=values[axis.name] * axis.scale)
            self.instrument.write(command)
            self._check_error(command)
        self._wait()
        return self.position()

    def _wait(self) -> None:
        deadline = time.monotonic() + self.motion_timeout
        pending = self._moving()
        while pending:
            pending = [
                a
                for a in pending
                if self.instrument.query(self.preset.done.format(axis=a.id)).strip()
                != self.preset.done_value
            ]
            if not pending:
                return
            if time.monotonic() > deadline:
                names = ", ".join(a.name for a in pending)
                raise InstrumentError(
                    f"{self.description}: axes {names} did not stop within "
                    f"{self.motion_timeout:g} s (motion_timeout)"
                )
            time.sleep(self.poll_interval)

    def position(self) -> Pose:
        """Every axis's position, read from the controller."""
        self._setup()
        values = []
        for axis in self.axes.values():
            if axis.id is None:
                assert axis.fixed is not None
                values.append(axis.fixed)
                continue
            command = self.preset.position.format(axis=axis.id)
            values.append(self.instrument.query_float(command) / axis.scale)
        x, y, z, azimuth, coelevation = values
        return Pose(x, y, z, azimuth, coelevation)

    def close(self) -> None:
        """Close the VISA resource."""
        self.instrument.close()
