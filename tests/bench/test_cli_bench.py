"""`echocal calibrate` on a bench: the truth is the mechanical optimum (the squint taken
off), the calibration finds it, and the bench time is reported."""

from __future__ import annotations

import json
import time

import numpy as np

from cli_helpers import run_main, tiny_setup_toml
from echocal.ascan import AScan
from echocal.calibrate import CalibrationResult
from echocal.cli._calibrate_common import _bench_line

BENCH = """
[bench.probe]
squint = [1.0, -0.5]
pivot_offset = [0, 0, "-20 mm"]
[bench.positioner]
acquisition_time = "1 ms"
[bench.positioner.tilt_x]
backlash = 0.01
speed = 20
settling = "20 ms"
[bench.positioner.tilt_y]
backlash = 0.01
speed = 20
settling = "20 ms"
[bench.receiver]
noise_ar = [0.5]
"""


def test_calibrate_on_a_bench_finds_the_squinted_optimum_and_reports_bench_time(
    tmp_path, capsys, monkeypatch
):
    setup = tmp_path / "bench.toml"
    setup.write_text(tiny_setup_toml() + BENCH)
    args = ["calibrate", "--setup", str(setup), "--out", str(tmp_path / "out"), "--no-plots"]
    code, out, _ = run_main([*args, "--json"], capsys, monkeypatch)
    summary = json.loads(out)
    assert code == 0, summary["message"]
    # the plate is flat and level: the acoustic optimum is (0, 0), so the mechanical one
    # is minus the squint (second order: 1.0 × 0.5 × π/180 / 2 ≈ 0.004°)
    np.testing.assert_allclose(summary["truth_deg"], [-1.0, 0.5], atol=0.02)
    # 30 dB, coloured noise, 0.01° backlash: the estimate within 0.05° of the truth
    assert summary["error_deg"] < 0.05
    # every measurement cost at least its 1 ms acquisition, and the search moved
    bench_time = summary["bench_time_s"]
    assert bench_time > 0.001 * summary["n_measurements"] + 0.02
    # the positioner's error: 0.01° backlash on both tilt axes, √(2 × 0.01²/2) = 0.01° RMS
    np.testing.assert_allclose(summary["bench_uncertainty_deg"], 0.01, rtol=1e-9)
    assert "the positioner's error (0.01° RMS)" in summary["message"]
    saved = json.loads((tmp_path / "out" / "result.json").read_text())
    assert saved["bench_time"] == bench_time
    # the human-readable report prints it beside the counts
    result = CalibrationResult.load_json(tmp_path / "out" / "result.json")
    assert _bench_line(result) == f"   bench time {bench_time:.3g} s"


def test_a_positioner_error_above_the_tolerance_is_said_to_limit_the_estimate():
    from echocal.calibrate.driver import _unresolved

    assert _unresolved(None, (0.01, 8), None) == ""
    within = _unresolved(0.008, (0.01, 8), None)
    assert "0.008° RMS" in within and "not resolved" not in within
    assert "convergence tolerance (0.01°): not resolved below it" in _unresolved(0.05, (0.01, 8), 1)
    assert "convergence tolerance (0.02°)" in _unresolved(0.05, None, 0.02)


def test_a_rig_reports_the_time_each_measurement_took_by_the_clock():
    from echocal.geometry import Pose
    from echocal.measurement.hardware import HardwareSource
    from echocal.measurement.limits import PositionerLimits

    class SlowPositioner:
        limits = PositionerLimits()

        def move_to(self, pose: Pose) -> Pose:
            time.sleep(0.02)
            return pose

        def close(self) -> None:
            pass

    class Receiver:
        def acquire(self) -> AScan:
            return AScan(np.zeros(64), fs=50e6)

        def close(self) -> None:
            pass

    source = HardwareSource(SlowPositioner(), Receiver(), settle_time=0.01)
    facts = source.measure(Pose(0.0, 0.0, 0.02)).metadata
    # lower bounds only (the clock may run longer on a busy machine, never shorter)
    assert facts["motion_time"] >= 0.02 and facts["settling_time"] >= 0.01
    parts = facts["motion_time"] + facts["settling_time"] + facts["acquisition_time"]
    np.testing.assert_allclose(facts["bench_time"], parts, rtol=1e-9)


def test_an_estimate_whose_echo_is_below_the_floor_is_not_a_convergence():
    from types import SimpleNamespace

    from echocal.calibrate import FunctionObjective
    from echocal.calibrate.evidence import judge

    class GrainyObjective(FunctionObjective):
        def echo_floor(self) -> float:
            return 1.0  # half a normal-incidence echo of 2.0

    objective = GrainyObjective(lambda p: np.zeros(len(p)), noise_sigma=0.0)
    points = np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]])
    searched = (points, np.array([0.2, 0.25, 0.2]))
    opt = SimpleNamespace(concave=None)
    x = np.array([0.5, 0.0])
    status, detail = judge(7, x, opt, objective, searched, np.array([0.3]))
    assert status == 10 and "not the surface's" in detail and "(2)" in detail
    # a strong echo at the estimate keeps the claim
    searched = (points, np.array([1.9, 2.0, 1.9]))
    assert judge(7, x, opt, objective, searched, np.array([2.0]))[0] == 7
