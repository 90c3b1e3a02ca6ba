"""``calibrate_plan`` under Bluesky's pause/resume contract, in a real RunEngine.

Pauses are injected into the plan's message stream (a ``pause`` message after the n-th
message of a kind, as a plan's own ``bps.pause`` or ``RE.request_pause`` would do), so
each test interrupts at a known point: during the move, after the trigger, inside the
event bundle, between an event's save and the next checkpoint, and a deferred pause (one
Ctrl-C); one run pauses after every message of the calibration.  Whatever the point, a
resumed run has one ``primary`` event per measurement, unique ``seq_num``, and the
uninterrupted run's result; ``stop``, ``abort`` and ``halt`` end the run and the
optimizer's thread, with every measurement saved once.
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import tiny_setup_toml
from echocal.setups import load_setup

pytest.importorskip("ophyd")
pytest.importorskip("bluesky")
from bluesky import Msg, RunEngine
from bluesky.preprocessors import plan_mutator
from bluesky.utils import FailedStatus, RunEngineInterrupted, single_gen

from echocal.rigs.ophyd_devices import simulated_devices
from echocal.rigs.plans import calibrate_plan

POSITION = (0.0, 0.0, 0.016)  # [m] the tiny setup's reference position
PLAN = {"position": POSITION, "x0": (2.0, 1.0), "method": "model-based", "budget": 14}


@pytest.fixture(scope="module")
def virtual(tmp_path_factory: pytest.TempPathFactory):
    path: Path = tmp_path_factory.mktemp("setup") / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return load_setup(path)


def _pause_after(plan, command: str, nth: int, *, defer: bool = False, obj_name: str = ""):
    """``plan`` with a ``pause`` message after its ``nth`` (1-based) ``command`` message
    (on the object named ``obj_name``, if given)."""
    seen = {"n": 0}

    def insert(msg):
        name = getattr(msg.obj, "name", "")
        if msg.command == command and (not obj_name or name == obj_name):
            seen["n"] += 1
            if seen["n"] == nth:
                return None, single_gen(Msg("pause", None, defer=defer))
        return None, None

    return plan_mutator(plan, insert)


def _streams(docs):
    """{stream name: [event, ...]} of a run's documents."""
    names = {d["uid"]: d["name"] for n, d in docs if n == "descriptor"}
    out: dict[str, list[dict]] = {}
    for n, d in docs:
        if n == "event":
            out.setdefault(names[d["descriptor"]], []).append(d)
    return out


def _pause_after_every_message(plan):
    """``plan`` with an immediate ``pause`` after each of its messages."""

    def insert(msg):
        if msg.command == "pause":
            return None, None
        return None, single_gen(Msg("pause", None, defer=False))

    return plan_mutator(plan, insert)


def _drive(virtual, wrap=None, then: str = "resume", *, record_interruptions: bool = False):
    """Run the plan (``wrap``-ped), resuming every pause (or ending the run with
    ``then``); returns (the plan's result or None, documents, number of pauses)."""
    probe, detector = simulated_devices(virtual, gimbal=True, seed=7)
    plan = calibrate_plan(probe, detector, **PLAN)
    docs: list[tuple[str, dict]] = []
    engine = RunEngine({}, call_returns_result=True)
    engine.record_interruptions = record_interruptions
    engine.subscribe(lambda name, doc: docs.append((name, doc)))
    call = lambda: engine(wrap(plan) if wrap else plan)  # noqa: E731
    pauses = 0
    while True:
        try:
            outcome = call()
        except RunEngineInterrupted:
            pauses += 1
            call = getattr(engine, then)
            continue
        return outcome, docs, pauses


@pytest.fixture(scope="module")
def uninterrupted(virtual):
    outcome, docs, pauses = _drive(virtual)
    assert pauses == 0 and outcome.exit_status == "success"
    return outcome.plan_result, docs


def _check_documents(docs, n_measurements: int) -> None:
    primary = _streams(docs)["primary"]
    seq_nums = [e["seq_num"] for e in primary]
    assert seq_nums == list(range(1, n_measurements + 1))  # one event each, unique, in order
    # the detector's seq (the index the plan set before the trigger) is the event's
    assert [e["data"]["ascan_seq"] for e in primary] == seq_nums


@pytest.mark.parametrize(
    ("command", "nth", "obj_name", "defer"),
    [
        ("set", 7, "probe_azimuth", False),  # during a move
        ("trigger", 4, "", False),  # after the detector's trigger, before the event
        ("read", 9, "ascan", False),  # inside the event bundle (the 5th measurement's)
        ("read", 8, "ascan", False),  # after the 4th event: the plan reads its values back
        ("create", 11, "", False),  # the bundle opened, nothing read
        ("save", 4, "", False),  # the 4th event saved, before the checkpoint after it
        ("save", 1, "", False),  # the same, after the first event of the run
        ("trigger", 2, "", True),  # one Ctrl-C: pause at the next checkpoint
        ("save", 5, "", True),  # one Ctrl-C after a save: pause at the checkpoint after it
        ("create", 11, "", True),  # one Ctrl-C inside a bundle: pause after its save
        ("read", 8, "ascan", True),  # one Ctrl-C after a checkpoint: pause at the next one
    ],
)
def test_a_paused_and_resumed_run_equals_an_uninterrupted_one(
    virtual, uninterrupted, command, nth, obj_name, defer
):
    wrap = lambda plan: _pause_after(plan, command, nth, defer=defer, obj_name=obj_name)  # noqa: E731
    outcome, docs, pauses = _drive(virtual, wrap)
    assert pauses == 1
    _check_resumed_run(outcome, docs, *uninterrupted)


def test_a_pause_after_every_message_resumes_to_the_uninterrupted_run(virtual, uninterrupted):
    """An immediate pause at every point of the calibration, one after another (each
    resumed): the save of each event and of the result, the checkpoints, the moves,
    the reads.  The RunEngine's own ``interruptions`` stream records each pause."""
    outcome, docs, pauses = _drive(virtual, _pause_after_every_message, record_interruptions=True)
    reference, _ = uninterrupted
    # every message of the run paused once: at least ~20 per measurement
    assert pauses > 20 * reference.n_measurements
    _check_resumed_run(outcome, docs, *uninterrupted)
    interruptions = _streams(docs)["interruptions"]
    # each pause inside the run, and its resume (the last pause, after close_run, is
    # outside the run)
    assert [e["data"]["interruption"] for e in interruptions] == ["pause", "resume"] * (pauses - 1)


def test_a_pause_between_the_result_and_the_stop_document_keeps_one_result(virtual, uninterrupted):
    """The last save of the run is the ``result`` stream's: a pause after it resumes to
    one result event."""
    reference, _ = uninterrupted
    last_save = reference.n_measurements + 1
    outcome, docs, pauses = _drive(virtual, lambda plan: _pause_after(plan, "save", last_save))
    assert pauses == 1
    _check_resumed_run(outcome, docs, *uninterrupted)


def _check_resumed_run(outcome, docs, reference, reference_docs) -> None:
    """The resumed run's documents and result are the uninterrupted run's."""
    assert outcome.exit_status == "success"
    result = outcome.plan_result
    _check_documents(docs, result.n_measurements)
    # the same measurements, values and estimate: the retake is the same A-scan and the
    # optimizer was told each measurement once
    assert result.n_measurements == reference.n_measurements
    np.testing.assert_array_equal(result.points, reference.points)
    np.testing.assert_array_equal(result.values, reference.values)
    np.testing.assert_array_equal(result.x, reference.x)
    events = _streams(docs)["primary"]
    for ours, theirs in zip(events, _streams(reference_docs)["primary"], strict=True):
        np.testing.assert_array_equal(
            ours["data"]["ascan_samples"], theirs["data"]["ascan_samples"]
        )
    # the result stream: one event with the estimate, every measurement's metric and
    # the outcome; the stop document's reason is the outcome's message
    (final,) = _streams(docs)["result"]
    np.testing.assert_array_equal(final["data"]["result_x"], result.x)
    np.testing.assert_array_equal(final["data"]["result_values"], result.values)
    assert final["data"]["result_n_measurements"] == result.n_measurements
    assert final["data"]["result_message"] == result.message
    stop = [d for n, d in docs if n == "stop"][-1]
    assert stop["reason"] == result.message and stop["num_events"]["primary"] == len(events)


def test_a_deferred_pause_takes_effect_after_the_measurement_in_progress(virtual):
    """One Ctrl-C during measurement 3 pauses at the checkpoint after its event."""
    probe, detector = simulated_devices(virtual, gimbal=True, seed=7)
    docs: list[tuple[str, dict]] = []
    engine = RunEngine({}, call_returns_result=True)
    engine.subscribe(lambda name, doc: docs.append((name, doc)))
    plan = _pause_after(calibrate_plan(probe, detector, **PLAN), "trigger", 3, defer=True)
    with pytest.raises(RunEngineInterrupted):
        engine(plan)
    assert engine.state == "paused" and len(_streams(docs)["primary"]) == 3
    engine.abort()
    assert not [t for t in threading.enumerate() if t.name == "echocal-calibrate-plan"]


@pytest.mark.parametrize(
    ("then", "exit_status"), [("stop", "success"), ("abort", "abort"), ("halt", "abort")]
)
@pytest.mark.parametrize(
    ("command", "nth", "obj_name", "n_saved"),
    [
        ("create", 5, "", 4),  # the 5th measurement's bundle opened: never saved
        ("save", 4, "", 4),  # the 4th event saved, before the checkpoint after it
        ("set", 3, "probe_x", 2),  # the 3rd measurement's move
        ("read", 8, "ascan", 4),  # after the 4th event's checkpoint
    ],
)
def test_stop_abort_and_halt_after_a_pause_end_the_run(
    virtual, uninterrupted, then, exit_status, command, nth, obj_name, n_saved
):
    wrap = lambda plan: _pause_after(plan, command, nth, obj_name=obj_name)  # noqa: E731
    _, docs, pauses = _drive(virtual, wrap, then=then)
    assert pauses == 1
    stop = [d for n, d in docs if n == "stop"]
    assert len(stop) == 1 and stop[0]["exit_status"] == exit_status
    primary = _streams(docs)["primary"]
    # each measurement taken before the pause is saved once; the one interrupted
    # before its save never is
    assert [e["seq_num"] for e in primary] == list(range(1, n_saved + 1))
    assert stop[0]["num_events"]["primary"] == n_saved
    for ours, theirs in zip(primary, _streams(uninterrupted[1])["primary"], strict=False):
        np.testing.assert_array_equal(
            ours["data"]["ascan_samples"], theirs["data"]["ascan_samples"]
        )
    assert "result" not in _streams(docs)
    assert not [t for t in threading.enumerate() if t.name == "echocal-calibrate-plan"]


def test_the_plan_documents_follow_the_conventions(virtual, uninterrupted):
    _, docs = uninterrupted
    start = docs[0][1]
    assert start["plan_name"] == "calibrate_plan"
    assert start["plan_args"]["method"] == "model-based" and start["plan_args"]["budget"] == 14
    assert start["hints"] == {"dimensions": [(["ascan_seq"], "primary")]}
    descriptor = next(d for n, d in docs if n == "descriptor" and d["name"] == "primary")
    keys = descriptor["data_keys"]
    assert keys["ascan_samples"]["units"] == "a.u." and keys["ascan_samples"]["dtype"] == "array"
    assert keys["ascan_fs"]["units"] == "Hz" and keys["ascan_start_time"]["units"] == "s"
    assert keys["probe_z"]["units"] == "m" and keys["probe_azimuth"]["units"] == "deg"
    assert descriptor["hints"]["ascan"] == {"fields": ["ascan_peak"]}


def test_a_failing_trigger_finishes_its_status_with_the_exception(virtual):
    probe, detector = simulated_devices(virtual, gimbal=True)

    class Unplugged:
        limits = virtual.limits

        def measure(self, pose):
            raise OSError("scope unplugged")

    detector.source = Unplugged()
    status = detector.trigger()  # does not raise
    assert status.done and not status.success
    assert isinstance(status.exception(), OSError)
    engine = RunEngine({})
    with pytest.raises(FailedStatus) as failed:  # the RunEngine's way to report it
        engine(calibrate_plan(probe, detector, **PLAN))
    assert "scope unplugged" in repr(failed.value.__cause__) + repr(failed.value.args)
    assert not [t for t in threading.enumerate() if t.name == "echocal-calibrate-plan"]


def test_the_simulated_devices_start_at_the_reference_pose(virtual):
    _, detector = simulated_devices(virtual)
    pose = detector.pose()
    np.testing.assert_allclose([pose.x, pose.y, pose.z], virtual.reference_position)
    assert (pose.azimuth, pose.coelevation) == (0.0, 0.0)
    detector.trigger()
    assert detector.peak.get() > 0.0  # an echo: something is measured where it starts


# -- suspenders -------------------------------------------------------------------------
def _drive_suspended(virtual, trip):
    """Run the plan under a :class:`~bluesky.suspenders.SuspendBoolHigh` watching an ophyd
    ``Signal`` (a beam-loss interlock) that ``trip(engine, beam)`` sets high; the
    interlock is released 50 ms into the suspension.  Returns (outcome, documents, number
    of suspensions, of resumptions, of detector triggers)."""
    from bluesky.suspenders import SuspendBoolHigh
    from ophyd import Signal

    probe, detector = simulated_devices(virtual, gimbal=True, seed=7)
    beam = Signal(name="beam_lost", value=0)
    counts = {"suspended": 0, "resumed": 0, "triggers": 0}

    def pre_plan():
        counts["suspended"] += 1
        threading.Timer(0.05, beam.put, (0,)).start()  # the beam comes back
        return iter(())

    def post_plan():
        counts["resumed"] += 1
        return iter(())

    trigger = detector.trigger

    def counted_trigger():
        counts["triggers"] += 1
        return trigger()

    detector.trigger = counted_trigger
    docs: list[tuple[str, dict]] = []
    engine = RunEngine({}, call_returns_result=True)
    engine.subscribe(lambda name, doc: docs.append((name, doc)))
    engine.install_suspender(SuspendBoolHigh(beam, sleep=0, pre_plan=pre_plan, post_plan=post_plan))
    trip(engine, beam)
    outcome = engine(calibrate_plan(probe, detector, **PLAN))
    return outcome, docs, counts


def _trip_at(command: str, nth: int, obj_name: str = ""):
    """Set the interlock high as the RunEngine takes the ``nth`` ``command`` message (on
    the object named ``obj_name``, if given)."""
    seen = {"n": 0}

    def trip(engine, beam):
        def hook(msg):
            if msg.command == command and (not obj_name or msg.obj.name == obj_name):
                seen["n"] += 1
                if seen["n"] == nth:
                    beam.put(1)

        engine.msg_hook = hook

    return trip


@pytest.mark.parametrize(
    ("command", "nth", "obj_name", "retakes"),
    [
        ("open_run", 1, "", 0),  # before the first measurement
        ("set", 7, "probe_azimuth", 0),  # during a move: moved again, nothing measured yet
        ("trigger", 3, "", 1),  # after the trigger, before the event: measured again
        ("create", 5, "", 1),  # the bundle opened, nothing read: measured again
        ("read", 9, "ascan", 1),  # inside the event bundle: measured again
        ("save", 4, "", 0),  # the event saved, before the checkpoint: not replayed
        ("save", 1, "", 0),  # the same, after the run's first event
        ("read", 8, "ascan", 0),  # after the checkpoint, the values read back
        ("save", 15, "", 0),  # the result's event (after the 14 measurements)
    ],
)
def test_a_suspender_tripped_mid_calibration_resumes_to_the_uninterrupted_run(
    virtual, uninterrupted, command, nth, obj_name, retakes
):
    """A suspender on an ophyd signal, tripped at each point of a measurement and released:
    the RunEngine suspends once (its pre- and post-plans run once), rewinds to the last
    checkpoint (a measurement whose event was not saved is taken again, one whose event
    was saved is not) and resumes on its own; the run has one event per measurement,
    unique seq_nums, and the uninterrupted run's result."""
    outcome, docs, counts = _drive_suspended(virtual, _trip_at(command, nth, obj_name))
    assert counts["suspended"] == counts["resumed"] == 1
    _check_resumed_run(outcome, docs, *uninterrupted)
    assert counts["triggers"] == outcome.plan_result.n_measurements + retakes


def test_a_suspender_tripped_from_another_thread_resumes_to_the_uninterrupted_run(
    virtual, uninterrupted
):
    """The interlock set high from another thread (as a control system's monitor does),
    at whatever point of the 4th measurement that lands."""

    def trip(engine, beam):
        seen = {"events": 0}

        def on_event(name, doc):
            seen["events"] += 1
            if seen["events"] == 3:
                threading.Thread(target=beam.put, args=(1,)).start()

        engine.subscribe(on_event, "event")

    outcome, docs, counts = _drive_suspended(virtual, trip)
    assert counts["suspended"] == counts["resumed"] == 1
    _check_resumed_run(outcome, docs, *uninterrupted)
    n = outcome.plan_result.n_measurements
    assert n <= counts["triggers"] <= n + 1


def test_a_read_answered_none_after_a_rewind_is_asked_again():
    """A suspension landing on the plan's read outside the event bundle: the RunEngine
    replays the read from its cache and answers the plan's pending read with None (seen
    in CI: the detector's fields were missing and the plan stopped).  The plan reads the
    device again; a device that never answers is a one-line error naming it."""
    from echocal.errors import EchocalValueError
    from echocal.rigs.plans import READ_ATTEMPTS, _read

    class Device:
        name = "ascan"

    reading = {"ascan_samples": {"value": [0.0], "timestamp": 0.0}}
    plan = _read(Device())
    messages = [next(plan)]
    messages.append(plan.send(None))  # the rewound read's reply: asked again
    with pytest.raises(StopIteration) as stop:
        plan.send(reading)
    assert stop.value.value == reading
    assert [m.command for m in messages] == ["read", "read"]
    assert all(m.obj is messages[0].obj for m in messages)

    plan = _read(Device())
    next(plan)
    with pytest.raises(EchocalValueError, match="ascan: the device's read returned nothing"):
        for _ in range(READ_ATTEMPTS):
            plan.send(None)
