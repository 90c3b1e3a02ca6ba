"""Sweeps that cannot run are refused before anything runs, every problem at once; a sweep
whose runs failed ends with exit code 1 and names the most common error."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import echocal.cli
import echocal.evaluation
from cli_helpers import run_main
from echocal.errors import ConfigError, EchocalValueError
from echocal.experiments import (
    builtin_sweep_names,
    expand,
    load_sweep,
    run_case,
    run_problems,
    run_sweep,
)
from echocal.setups import load_setup

OK = {
    "name": "ok",
    "setup": "thesis",
    "budget": 12,
    "max_iter": 3,
    "seeds": 1,
    "snr_db": [30],
    "methods": [{"name": "model-based"}],
}


def _problems(data: dict) -> list[str]:
    with pytest.raises(ConfigError) as info:
        load_sweep(data)
    return [line.strip() for line in str(info.value).splitlines()[1:]]


def test_runs_that_cannot_run_are_refused_with_every_reason():
    # each of these passed `sweep check` and failed every run before
    problems = _problems(
        {
            **OK,
            "position": [0, 0, "500 mm"],  # thesis positioner: z in [5, 100] mm
            "budget": 3,  # newton needs 9 measurements per iteration
            "x0": {"points": [[100, 0]]},  # the tilt bounds are about ±32.8°
            "methods": [{"name": "newton"}, {"name": "auto", "options": {"fine_radius": "abc"}}],
        }
    )
    assert len(problems) == 4, problems
    position, x0, newton, auto = problems
    assert position.startswith("position:") and "z=500 mm outside [5, 100] mm" in position
    assert x0.startswith("x0.points.0:") and "tilt_x" in x0 and "100" in x0
    assert newton.startswith("methods.0 (newton):") and "budget >= 10" in newton
    assert auto.startswith("methods.1 (auto") and "fine_radius" in auto and "'abc'" in auto


def test_schema_and_method_problems_are_reported_together():
    problems = _problems(
        {
            **OK,
            "budget": 0,
            "tolerance": -1,
            "snr_db": ["abc"],
            "x0": {"offset": [5, 2]},
            "methods": [{"name": "spsaa"}, {"name": "spsa", "options": {"epsilon": 1}}],
        }
    )
    fields = [p.split(":")[0] for p in problems]
    assert fields == [
        "budget",
        "tolerance",
        "snr_db.0",
        "x0.offset",
        "methods.0.name",
        "methods.1.options.epsilon",
    ]


def test_a_malformed_method_entry_keeps_the_other_methods_checked():
    problems = _problems({**OK, "methods": [{"name": "spsa", "options": "eps"}, {"name": "nope"}]})
    assert [p.split(":")[0] for p in problems] == ["methods.0.options", "methods.1.name"]


def test_the_budget_at_the_methods_minimum_passes_and_runs():
    # the check's bound is calibrate's own: one short of it is refused, at it the run works
    # (newton: 9 per iteration + the final measurement at the estimate)
    (problem,) = _problems({**OK, "budget": 9, "methods": [{"name": "newton"}]})
    assert "budget >= 10" in problem
    spec = load_sweep({**OK, "budget": 10, "methods": [{"name": "newton"}]})
    assert run_problems(spec) == []
    row, _ = run_case(expand(spec)[0])
    assert row["status"] >= 0, row["message"]
    assert 0 < row["n_measurements"] <= 10


def test_check_cli_lists_the_problems_and_exits_2(tmp_path, capsys, monkeypatch):
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'setup = "thesis"\nbudget = 3\n[[methods]]\nname = "newton"\n', encoding="utf-8"
    )
    code, out, err = run_main(["sweep", "check", str(sweep)], capsys, monkeypatch)
    assert code == 2 and out == ""
    assert "Traceback" not in err and "budget >= 10" in err


@pytest.mark.parametrize(
    ("sweep", "options", "expected"),
    [
        ("quick", ["--workers", "0"], "workers must be >= 1"),
        ("quick", ["--scheduler", "localhost:8786"], "tcp://HOST:PORT"),
        ("bad", [], "budget >= 10"),
    ],
)
def test_run_refuses_before_writing_anything(
    tmp_path, capsys, monkeypatch, sweep, options, expected
):
    if sweep == "bad":
        sweep = str(tmp_path / "bad.toml")
        Path(sweep).write_text(
            'setup = "thesis"\nbudget = 3\n[[methods]]\nname = "newton"\n', encoding="utf-8"
        )
    out = tmp_path / "out"
    code, _, err = run_main(
        ["sweep", "run", sweep, "--out", str(out), *options], capsys, monkeypatch
    )
    assert code == 2, err
    assert expected in err and "Traceback" not in err
    assert not out.exists()  # no sweep.json, no parts/


def _break_judging(monkeypatch) -> None:
    def broken(*args, **kwargs):
        raise EchocalValueError("judging failed")

    monkeypatch.setattr(echocal.evaluation, "evaluate_run", broken)


def test_run_with_failed_runs_exits_1_and_names_the_error(tmp_path, capsys, monkeypatch):
    sweep = tmp_path / "ok.toml"
    sweep.write_text(
        'setup = "thesis"\nbudget = 12\nmax_iter = 2\nseeds = 2\n[[methods]]\nname = "spsa"\n',
        encoding="utf-8",
    )
    args = ["sweep", "run", str(sweep), "--workers", "1", "--no-progress"]
    code, _, err = run_main([*args, "--out", str(tmp_path / "good")], capsys, monkeypatch)
    assert code == 0, err
    _break_judging(monkeypatch)
    code, _, err = run_main([*args, "--out", str(tmp_path / "bad")], capsys, monkeypatch)
    assert code == 1
    text = " ".join(err.split())
    assert "2 of 2 run(s) failed" in text and "(2 run(s)): judging failed" in text
    code, out, _ = run_main(
        ["sweep", "run", str(sweep), "--out", str(tmp_path / "bad2"), "--workers", "1", "--json"],
        capsys,
        monkeypatch,
    )
    data = json.loads(out)
    assert code == 1
    assert data["n_failed"] == 2
    assert data["most_common_failure"] == {"message": "judging failed", "runs": 2}


def test_run_help_documents_the_exit_codes():
    from typer.testing import CliRunner

    result = CliRunner().invoke(echocal.cli.app, ["sweep", "run", "--help"])
    text = " ".join(result.output.split())
    assert "Exit codes: 0" in text and "1 some runs failed" in text and "2 the sweep" in text


def test_run_sweep_library_checks_workers_before_writing(tmp_path):
    with pytest.raises(EchocalValueError, match="workers"):
        run_sweep(OK, tmp_path / "x", workers=0, progress=False)
    assert not (tmp_path / "x").exists()


# -- random starts outside the angle bounds -------------------------------------------------------
THESIS_AT_10 = {**OK, "position": ["10 mm", 0, "22 mm"], "parameterization": "tilt"}
# the thesis positioner's co-elevation cone is 45 deg; the tilt box inside it has the
# half-width arccos(sqrt(cos 45 deg)) = 32.765 deg (see default_bounds)
TILT_BOUND = float(np.rad2deg(np.arccos(np.sqrt(np.cos(np.deg2rad(45.0))))))


def _numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", text)]


def test_an_offset_putting_starts_outside_the_bounds_is_refused_with_the_rest():
    # passed `sweep check` before and started both runs from the clipped corner
    problems = _problems(
        {
            **THESIS_AT_10,
            "seeds": 2,
            "x0": {"offset": [60, 70]},
            "methods": [{"name": "auto", "options": {"fine_radius": "abc"}}],
        }
    )
    assert len(problems) == 2, problems
    offset, method = problems
    assert method.startswith("methods.0 (auto") and "fine_radius" in method
    assert offset.startswith("x0.offset: [60, 70] deg from the truth")
    assert "2 of 2 start(s)" in offset
    assert f"tilt_x in [{-TILT_BOUND:.2f}, {TILT_BOUND:.2f}]" in offset
    truth = np.array(load_setup("thesis").true_optimum([0.01, 0, 0.022], parameterization="tilt"))
    head, tail = offset.split(" deg: ")
    np.testing.assert_allclose(_numbers(head.split("truth")[1])[:2], truth, atol=0.005)
    starts = re.findall(r"seed (\d+) x0=\((\S+), (\S+)\)", tail)
    assert [int(s) for s, _, _ in starts] == [0, 1]
    for _, a, b in starts:
        x0 = np.array([float(a), float(b)])
        # each start as drawn: 60..70 deg from the truth (0.02 deg: the 2-decimal rounding
        # of the start and the truth), beyond the bound on some axis
        assert 60 - 0.02 <= np.hypot(*(x0 - truth)) <= 70 + 0.02
        assert np.max(np.abs(x0)) > TILT_BOUND
    # the largest offset whose every start is inside: the truth's distance to the box edge
    assert f"offsets up to {TILT_BOUND - np.max(np.abs(truth)):.2f} deg" in tail


def test_an_offset_inside_the_bounds_passes_and_runs_from_the_drawn_start():
    spec = load_sweep({**THESIS_AT_10, "seeds": 3, "x0": {"offset": [20, 26]}})
    assert run_problems(spec) == []
    row, _ = run_case(expand(spec)[2])
    assert row["status"] >= 0, row["message"]
    # the run starts at the drawn distance from the truth (not clipped), 1e-9 deg: round-off
    distance = np.hypot(
        row["x0_tilt_x_deg"] - row["truth_tilt_x_deg"],
        row["x0_tilt_y_deg"] - row["truth_tilt_y_deg"],
    )
    assert 20 - 1e-9 <= distance <= 26 + 1e-9


def test_sweep_check_names_the_offset_and_exits_2(tmp_path, capsys, monkeypatch):
    sweep = tmp_path / "far.toml"
    sweep.write_text(
        'setup = "thesis"\nposition = ["10 mm", 0, "22 mm"]\nseeds = 2\n'
        '[x0]\noffset = [60, 70]\n[[methods]]\nname = "auto"\n',
        encoding="utf-8",
    )
    for command in ("check", "run"):
        out = tmp_path / "out"
        args = ["sweep", command, str(sweep)] + (["--out", str(out)] if command == "run" else [])
        code, stdout, err = run_main(args, capsys, monkeypatch)
        assert code == 2 and stdout == "", err
        assert "x0.offset: [60, 70]" in err and "outside the bounds" in err
        assert "Traceback" not in err and not out.exists()


@pytest.mark.parametrize("name", builtin_sweep_names())
def test_the_builtin_sweeps_pass_the_check(name, capsys, monkeypatch):
    code, _, err = run_main(["sweep", "check", name], capsys, monkeypatch)
    assert code == 0, err


def test_sweep_check_refuses_a_window_that_cannot_hold_the_echo():
    # thesis: z limits [5, 100] mm, window [20, 71.2] us; the echo from 100 mm comes at 135 us
    with pytest.raises(ConfigError) as info:
        load_sweep({**OK, "position": [0, 0, "100 mm"]})
    (problem,) = [line.strip() for line in str(info.value).splitlines()[1:]]
    assert problem.startswith("position:") and "cannot contain any echo" in problem
    assert load_sweep({**OK, "position": [0, 0, "22 mm"]}).name == "ok"  # a valid one passes
