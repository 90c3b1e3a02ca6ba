"""``calibrate_plan`` in a Bluesky RunEngine on echocal's simulated ophyd devices: every
measurement is an event of the run (its motor positions the pose measured, its A-scan
giving the value the optimizer was told), the plan returns the CalibrationResult, a
user's own detector and motors work, and a failing detector fails the run cleanly."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import tiny_setup_toml
from echocal.calibrate import CalibrationResult
from echocal.geometry import pose_from_angles
from echocal.measurement.objective import ascan_metric
from echocal.setups import load_setup

pytest.importorskip("ophyd")
bluesky = pytest.importorskip("bluesky")
from bluesky import RunEngine  # noqa: E402

from echocal.rigs.ophyd_devices import AScanDetector, probe_positioner, simulated_devices  # noqa: E402
from echocal.rigs.plans import calibrate_plan  # noqa: E402

POSITION = (0.0, 0.0, 0.016)  # [m] the tiny setup's reference position
X0 = (2.0, 1.0)  # [deg] tilts


@pytest.fixture
def virtual(tmp_path: Path):
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return load_setup(path)


def _stream_events(docs, stream: str = "primary") -> list[dict]:
    """The events of one stream, in order."""
    descriptors = {d["uid"] for n, d in docs if n == "descriptor" and d["name"] == stream}
    return [d for n, d in docs if n == "event" and d["descriptor"] in descriptors]


def _run(plan):
    documents: list[tuple[str, dict]] = []
    engine = RunEngine({}, call_returns_result=True)
    outcome = engine(plan, lambda name, doc: documents.append((name, doc)))
    return outcome, documents


def test_every_measurement_is_an_event_and_the_plan_returns_the_result(virtual):
    probe, detector = simulated_devices(virtual, gimbal=True)
    outcome, docs = _run(calibrate_plan(probe, detector, position=POSITION, x0=X0))
    result = outcome.plan_result
    assert isinstance(result, CalibrationResult) and result.success
    assert np.hypot(*result.x) < 0.5  # a flat plate: the echo is strongest straight down
    names = [name for name, _ in docs]
    assert names[0] == "start" and names[-1] == "stop"
    start, stop = docs[0][1], docs[-1][1]
    assert start["plan_name"] == "calibrate_plan" and start["method"] == "auto"
    assert stop["exit_status"] == "success"
    events = _stream_events(docs)
    assert len(events) == result.n_measurements == detector.n_measurements
    assert stop["num_events"]["primary"] == result.n_measurements
    for event, point, value in zip(events, result.points, result.values, strict=True):
        data = event["data"]
        pose = pose_from_angles(POSITION, *point, "tilt")
        measured = [data[f"probe_{axis}"] for axis in ("x", "y", "z", "azimuth", "coelevation")]
        np.testing.assert_allclose(measured, pose.as_array(), rtol=0, atol=1e-12)
        # the event's A-scan gives exactly the value the optimizer was told
        scan = virtual.measure(pose)  # same window; the noise differs, so compare via metric
        recomputed = ascan_metric(
            type(scan)(
                samples=np.asarray(data["ascan_samples"]),
                fs=data["ascan_fs"],
                start_time=data["ascan_start_time"],
            ),
            "pseudo-energy",
            virtual.pulse,
        )
        assert recomputed == pytest.approx(value, rel=1e-12, abs=1e-300)


def test_a_users_own_detector_and_motors(virtual):
    """Motors given as a mapping; a detector reading only samples (fs, start as numbers)."""
    from ophyd import Component, Device, Signal
    from ophyd.status import DeviceStatus

    probe = probe_positioner(virtual.limits, name="stage")

    class Scope(Device):
        trace = Component(Signal, value=np.zeros(1))

        def trigger(self):
            pose = pose_from_angles(
                [probe.x.position, probe.y.position, probe.z.position],
                probe.azimuth.position,
                probe.coelevation.position,
                "azimuth-coelevation",
            )
            self.trace.put(virtual.measure(pose).samples)
            status = DeviceStatus(self)
            status.set_finished()
            return status

    scope = Scope(name="scope")
    motors = {a: getattr(probe, a) for a in ("x", "y", "z", "azimuth", "coelevation")}
    window = virtual.window
    outcome, docs = _run(
        calibrate_plan(
            motors,
            scope,
            position=POSITION,
            method="model-based",
            x0=(45.0, 1.0),
            parameterization="azimuth-coelevation",
            pulse=virtual.pulse,
            samples="scope_trace",
            fs=window.fs,
            start_time=window.start,
            budget=12,
        )
    )
    result = outcome.plan_result
    assert result.n_measurements == 12
    assert len(_stream_events(docs)) == 12


def test_a_failing_detector_fails_the_run_and_stops_the_optimizer(virtual):
    probe, detector = simulated_devices(virtual, gimbal=True)
    calls = {"n": 0}
    trigger = detector.trigger

    def flaky():
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError("scope unplugged")
        return trigger()

    detector.trigger = flaky
    engine = RunEngine({}, call_returns_result=True)
    docs: list[tuple[str, dict]] = []
    with pytest.raises(OSError, match="scope unplugged"):
        engine(
            calibrate_plan(probe, detector, position=POSITION, x0=X0),
            lambda n, d: docs.append((n, d)),
        )
    assert docs[-1][0] == "stop" and docs[-1][1]["exit_status"] == "fail"
    assert sum(name == "event" for name, _ in docs) == 2
    # the optimizer's thread ended
    assert not [t for t in threading.enumerate() if t.name == "echocal-calibrate-plan"]


def test_motors_missing_an_axis_are_refused(virtual):
    probe, detector = simulated_devices(virtual)
    with pytest.raises(ValueError, match="missing coelevation"):
        next(
            calibrate_plan(
                {"x": probe.x, "y": probe.y, "z": probe.z, "azimuth": probe.azimuth},
                detector,
                position=POSITION,
            )
        )


def test_the_detector_refuses_nothing_the_positioner_refuses(virtual):
    """ophyd refuses a move outside the setup's limits before anything moves."""
    probe = probe_positioner(virtual.limits)
    with pytest.raises(ValueError):
        probe.coelevation.move(45.0)  # the tiny setup allows [-30, 30]
    assert probe.coelevation.position == 0.0
    detector = AScanDetector(source=virtual, positioner=probe)
    assert detector.pose().z == pytest.approx(0.01)  # the origin clipped to z >= 10 mm
