"""``calibrate_plan``: any echocal optimizer as a Bluesky plan over ophyd motors and a
detector (``bluesky`` extra).

The plan runs :func:`echocal.calibrate.calibrate` — the very driver the command line
and the Python API use, with its stopping rules, acquisition search, counting and
result — and lets Bluesky do every measurement: each pose the optimizer asks for is
moved to with ``mv`` (the five motors together) and measured with ``trigger_and_read``
(the detector and the motors), so each measurement is one event of the run's
``primary`` stream and the user's data store records all of them.  The A-scan the
detector read is handed back to the optimizer (a worker thread runs the driver and
waits for each A-scan; the plan waits for each request, so exactly one of them works
at a time).  The plan returns the :class:`~echocal.calibrate.CalibrationResult`.

Pause and resume follow Bluesky's contract: the plan yields a ``checkpoint`` before and
right after each measurement, so a deferred pause (one Ctrl-C) stops after the
measurement in progress, and an immediate pause before the event is saved rewinds to
the measurement's start and takes it again on ``RE.resume()``.  A suspender
(``RE.install_suspender``) suspends the run the same way and resumes it on its own once
its signal is back; the plan also checkpoints after the ``result`` event, so a suspender
tripped by that event's save suspends inside the run.  An immediate pause (or a
suspension) that lands after the event is saved and before the next checkpoint must not
rewind: the RunEngine would replay the saved event (a second event with the same
``seq_num``).  The plan holds a :class:`~bluesky.protocols.Pausable` guard that sees
each event document of its run and, when the RunEngine pauses in that window, raises
:class:`bluesky.utils.NoReplayAllowed` from ``pause()`` (Bluesky's way for a device to
refuse a replay): the RunEngine drops the messages since the checkpoint and resumes
after the save.  The optimizer is told each measurement once, with the A-scan of its
event (read back after the event is saved), so a resumed run has one event per
measurement, unique ``seq_num``, and the result of an uninterrupted run when the
detector's retake is the same A-scan (echocal's simulated detector draws the noise of
measurement ``seq`` from a seed).  ``stop``, ``abort`` and ``halt`` end the optimizer's
thread with the run.

The estimate, the metric of every measurement and the outcome go into the run's
``result`` stream (one event after the last measurement); the start document carries
``plan_name``, ``plan_args``, ``hints`` and the method's settings, and the stop
document's ``reason`` is the outcome's message.

The detector may be the user's own: it must read its A-scan samples (an array signal),
and its sampling frequency [Hz] and first-sample time [s] as signals or as numbers
given to the plan.  A detector with a ``seq`` signal is given each measurement's index
(the event's ``seq_num``) before its trigger.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Generator, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal import __version__
from echocal.ascan import AScan
from echocal.calibrate import CalibrationResult, calibrate
from echocal.errors import EchocalValueError
from echocal.geometry import Pose
from echocal.measurement.base import BaseSource
from echocal.measurement.limits import PositionerLimits
from echocal.measurement.objective import SourceObjective
from echocal.signal import Pulse

try:
    import bluesky.plan_stubs as bps
    from bluesky import Msg
    from bluesky.utils import NoReplayAllowed
except ImportError:  # without the bluesky extra
    raise ImportError(
        "echocal's Bluesky plans need bluesky: pip install 'echocal[bluesky]' (bluesky, ophyd)"
    ) from None

__all__ = ["calibrate_plan"]

AXES = ("x", "y", "z", "azimuth", "coelevation")
_DONE = object()


class _Bridge(BaseSource):
    """The measurement source the driver's objective measures: each ``measure(pose)``
    is a request to the plan, answered with the A-scan the plan's detector read."""

    def __init__(self, limits: PositionerLimits, description: str) -> None:
        self.limits = limits
        self.description = description
        self.requests: queue.Queue[Any] = queue.Queue()
        self.replies: queue.Queue[Any] = queue.Queue()

    def measure(self, pose: Pose) -> AScan:
        self.requests.put(pose)
        reply = self.replies.get()
        if isinstance(reply, BaseException):
            raise reply
        return reply


class _SavedEventGuard:
    """Refuses a rewind that would replay a saved event (a :class:`~bluesky.protocols.Pausable`).

    Subscribed to the run's documents, it notes each saved event of the plan's
    ``streams`` (not the RunEngine's own ``interruptions`` stream, whose events a pause
    emits); the plan clears the note after the checkpoint that follows.  The RunEngine
    calls ``pause()`` on every object of the run when it pauses or suspends; while an
    event is saved and no checkpoint has followed, ``pause()`` raises
    :class:`~bluesky.utils.NoReplayAllowed`, so the RunEngine forgets the messages since
    the last checkpoint instead of replaying them on resume."""

    def __init__(self, streams: Sequence[str]) -> None:
        self.streams = frozenset(streams)
        self.descriptors: set[str] = set()
        self.saved = False

    def __call__(self, name: str, doc: Mapping[str, Any]) -> None:
        if name == "descriptor" and doc.get("name") in self.streams:
            self.descriptors.add(doc["uid"])
        elif name == "event" and doc.get("descriptor") in self.descriptors:
            self.saved = True

    def pause(self) -> None:
        if self.saved:
            raise NoReplayAllowed("calibrate_plan: the event is saved; resume after it")

    def resume(self) -> None:
        """Nothing to do: the plan goes on from where it paused."""


class _Aborted(Exception):
    """The plan stopped (an error or an abort in the RunEngine): the driver stops too."""


def _motors(motors: Any) -> list[Any]:
    """The five motors, in :data:`AXES` order, from a device or a mapping."""
    get = motors.get if isinstance(motors, Mapping) else lambda a: getattr(motors, a, None)
    found = [get(axis) for axis in AXES]
    missing = [a for a, m in zip(AXES, found, strict=True) if m is None]
    if missing:
        raise EchocalValueError(
            f"motors: missing {', '.join(missing)}; give a device or a mapping with all of "
            f"{', '.join(AXES)}"
        )
    return found


def _limits_of(motors: list[Any]) -> PositionerLimits:
    """The motors' own limits (``motor.limits``; (0, 0) means none, as in ophyd)."""
    bounds = {}
    for axis, motor in zip(AXES, motors, strict=True):
        low, high = (float(v) for v in getattr(motor, "limits", (0.0, 0.0)))
        if low == high == 0.0:
            default = PositionerLimits()
            bounds[axis] = getattr(default, axis)
        else:
            bounds[axis] = (low, high)
    return PositionerLimits(**bounds)


def _value(reading: Mapping[str, Any], key: str, what: str) -> Any:
    if key not in reading:
        raise EchocalValueError(
            f"{what}: the detector read no {key!r}; it read {', '.join(sorted(reading))} "
            "(name the key, or give the number)"
        )
    return reading[key]["value"]


READ_ATTEMPTS = 3
"""How often :func:`_read` asks a device before it gives up."""


def _read(device: Any) -> Generator[Msg, Any, dict[str, Any]]:
    """A device's reading, outside an event bundle.  A suspension that lands on the read
    rewinds the RunEngine to the last checkpoint and replays the read; the replay's reply
    goes to the replay, and the plan's pending read is answered ``None``: it is asked
    again (at most :data:`READ_ATTEMPTS` times, then a one-line error naming the device)."""
    for _ in range(READ_ATTEMPTS):
        values = yield from bps.read(device)
        if values:
            return dict(values)
    name = getattr(device, "name", repr(device))
    raise EchocalValueError(
        f"{name}: the device's read returned nothing {READ_ATTEMPTS} times in a row "
        "(check that it is connected and has readable signals)"
    )


def calibrate_plan(
    motors: Any,
    detector: Any,
    *,
    position: ArrayLike,
    method: str = "auto",
    x0: Sequence[float] = (0.0, 0.0),
    pulse: Pulse | None = None,
    parameterization: str = "tilt",
    limits: PositionerLimits | None = None,
    bounds: ArrayLike | None = None,
    metric: str = "pseudo-energy",
    budget: int | None = None,
    max_iter: int | None = None,
    settle: tuple[float, int] | None = (0.01, 8),
    rng: Any = 0,
    samples: str | None = None,
    fs: str | float | None = None,
    start_time: str | float | None = None,
    md: Mapping[str, Any] | None = None,
    **options: Any,
) -> Generator[Any, Any, CalibrationResult]:
    """Calibrate the probe's orientation at ``position`` with an echocal method, as a plan.

    Parameters
    ----------
    motors : an ophyd device with axes ``x``, ``y``, ``z`` [m], ``azimuth``, ``coelevation``
        [deg] (e.g. :func:`~echocal.rigs.ophyd_devices.probe_positioner`), or a mapping of
        those names to five movable devices.
    detector : a readable, triggerable device reading one A-scan per trigger
        (e.g. :class:`~echocal.rigs.ophyd_devices.AScanDetector`, or the user's own).
    position : [m] (3,) where the probe stays while its orientation is calibrated.
    method, x0, budget, max_iter, settle, rng, options : as :func:`echocal.calibrate.calibrate`
        (``x0`` [deg] in ``parameterization``).
    pulse : the transmitted pulse (matched-filter template); default ``detector.pulse``.
    parameterization : ``"tilt"`` or ``"azimuth-coelevation"``.
    limits : the reachable poses; default the motors' own ``limits``.
    bounds : [deg] (2, 2) angle bounds; default from ``limits``.
    metric : the objective's metric (pseudo-energy by default).
    samples : reading key of the A-scan samples; default ``<detector.name>_samples``.
    fs, start_time : [Hz], [s] numbers, or reading keys (default
        ``<detector.name>_fs`` and ``<detector.name>_start_time``).
    md : metadata for the run's start document.

    Returns
    -------
    The :class:`~echocal.calibrate.CalibrationResult` (the plan's return value; with
    ``RunEngine(call_returns_result=True)`` it is ``RE(plan).plan_result``).
    """
    axes = _motors(motors)
    pulse = pulse if pulse is not None else getattr(detector, "pulse", None)
    name = str(getattr(detector, "name", "detector"))
    keys = {
        "samples": samples or f"{name}_samples",
        "fs": fs if fs is not None else f"{name}_fs",
        "start_time": start_time if start_time is not None else f"{name}_start_time",
    }
    bridge = _Bridge(limits if limits is not None else _limits_of(axes), f"Bluesky detector {name}")
    objective = SourceObjective(
        bridge,
        position,
        pulse=pulse,
        parameterization=parameterization,
        bounds=bounds,
        metric=metric,
    )

    def drive() -> None:
        try:
            result = calibrate(
                objective,
                method,
                x0=x0,
                budget=budget,
                max_iter=max_iter,
                settle=settle,
                rng=rng,
                **options,
            )
        except BaseException as exc:  # handed to the plan, which raises it in the run
            bridge.requests.put((_DONE, exc))
        else:
            bridge.requests.put((_DONE, result))

    start_md = {
        "plan_name": "calibrate_plan",
        "method": method,
        "x0_deg": [float(v) for v in x0],
        "parameterization": parameterization,
        "position_m": [float(v) for v in objective.position],
        "detectors": [name],
        "motors": [str(getattr(m, "name", a)) for a, m in zip(AXES, axes, strict=True)],
        "plan_args": {
            "motors": repr(motors),
            "detector": repr(detector),
            "position": [float(v) for v in objective.position],
            "method": method,
            "x0": [float(v) for v in x0],
            "parameterization": parameterization,
            "metric": metric,
            "budget": budget,
            "max_iter": max_iter,
            "settle": None if settle is None else list(settle),
            "rng": repr(rng),
            "options": {k: repr(v) for k, v in options.items()},
        },
        "hints": {"dimensions": [([f"{name}_seq"], "primary")]}
        if getattr(detector, "seq", None) is not None
        else {"dimensions": [(["time"], "primary")]},
        "echocal_version": __version__,
        **dict(md or {}),
    }
    worker = threading.Thread(target=drive, name="echocal-calibrate-plan", daemon=True)
    guard = _SavedEventGuard(("primary", "result"))
    yield from bps.open_run(md=start_md)
    yield from bps.subscribe("all", guard)
    yield Msg("null", guard)  # a message naming the guard: the RunEngine will pause() it
    worker.start()
    seq = getattr(detector, "seq", None)
    n_measured = 0
    try:
        while True:
            request = bridge.requests.get()
            if isinstance(request, tuple) and request[0] is _DONE:
                outcome = request[1]
                break
            pose: Pose = request
            n_measured += 1
            # a pause from here to the save rewinds to this checkpoint and retakes the
            # measurement: the optimizer has not been told it yet
            yield from bps.checkpoint()
            targets = [v for m, x in zip(axes, pose.as_array(), strict=True) for v in (m, float(x))]
            if seq is not None:
                targets = [seq, n_measured, *targets]
            yield from bps.mv(*targets)
            yield from bps.trigger_and_read([detector, *axes])
            # the event is saved: no rewind may take it again (the guard refuses one
            # until this checkpoint, which empties the RunEngine's replay cache)
            yield from bps.checkpoint()
            guard.saved = False
            # the values the event recorded (a read outside the event bundle: the reply a
            # rewound message gives the plan may be incomplete)
            reading: dict[str, Any] = {}
            for device in (detector, *axes):
                reading.update((yield from _read(device)))
            bridge.replies.put(_ascan(reading, keys, _reached(reading, axes, pose)))
    except BaseException as exc:
        bridge.replies.put(_Aborted(f"calibrate_plan stopped: {type(exc).__name__}: {exc}"))
        worker.join(timeout=10.0)
        raise
    worker.join()
    if isinstance(outcome, BaseException):
        raise outcome
    yield from bps.checkpoint()
    yield from bps.trigger_and_read(_result_signals(outcome), name="result")
    # a suspender tripped by the result's save suspends here, inside the run (the
    # RunEngine cannot suspend a plan that has ended), and resumes after the save
    yield from bps.checkpoint()
    guard.saved = False
    yield from bps.close_run(exit_status="success", reason=outcome.message)
    return outcome


def _result_signals(result: CalibrationResult) -> list[Any]:
    """ophyd signals holding the result: the ``result`` stream's one event.

    ``result_x`` [deg] (2,), ``result_fun`` (the metric at the estimate; NaN when not
    measured there), ``result_values`` (the metric of every measurement, in order),
    ``result_points`` [deg] (n_measurements, 2), ``result_success``,
    ``result_status``, ``result_message``, ``result_n_measurements``.
    """
    from ophyd import Signal

    fun = float("nan") if result.fun is None else float(result.fun)
    fields: dict[str, Any] = {
        "x": np.asarray(result.x, dtype=np.float64),
        "fun": fun,
        "values": np.asarray(result.values, dtype=np.float64),
        "points": np.asarray(result.points, dtype=np.float64),
        "success": int(bool(result.success)),
        "status": int(result.status),
        "message": str(result.message),
        "n_measurements": int(result.n_measurements),
    }
    return [Signal(name=f"result_{key}", value=value) for key, value in fields.items()]


def _reached(reading: Mapping[str, Any], axes: list[Any], requested: Pose) -> Pose:
    """The pose the motors read back (their readback is keyed by their name, as ophyd's
    motors do), else the one requested."""
    names = [str(getattr(motor, "name", "")) for motor in axes]
    if not all(name in reading for name in names):
        return requested
    x, y, z, az, coel = (float(reading[name]["value"]) for name in names)
    return Pose(x, y, z, az, coel, gimbal=requested.gimbal)


def _ascan(reading: Mapping[str, Any], keys: Mapping[str, Any], pose: Pose) -> AScan:
    """The A-scan of one ``trigger_and_read`` reading, measured at ``pose``."""
    samples = np.asarray(_value(reading, keys["samples"], "samples"), dtype=np.float64)
    numbers = {
        k: float(keys[k]) if not isinstance(keys[k], str) else float(_value(reading, keys[k], k))
        for k in ("fs", "start_time")
    }
    return AScan(samples=samples, fs=numbers["fs"], start_time=numbers["start_time"], pose=pose)
