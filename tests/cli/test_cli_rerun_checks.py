"""``calibrate --from result.json`` refuses a result that lacks what a rerun needs, in one
line, instead of silently running the default calibration."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cli_helpers import flat, run_main, tiny_setup_toml

CALIBRATE = ["calibrate", "--setup", "tiny.toml", "--position", "0,0,16", "--x0", "2,-1"]
CALIBRATE += ["--method", "model-based", "--budget", "8", "--settle", "none", "--no-plots"]


@pytest.fixture(scope="module")
def result(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("rerun")
    (folder / "tiny.toml").write_text(tiny_setup_toml(), encoding="utf-8")
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(folder)
        code, _, err = run_main([*CALIBRATE, "--out", "first"], _Capsys(), patch)
    assert code in (0, 1, 3), err
    return folder / "first" / "result.json"


class _Capsys:
    """run_main's capture for a module fixture (capsys is per test)."""

    def readouterr(self) -> tuple[str, str]:
        return "", ""


def _edited(result: Path, tmp_path: Path, edit) -> Path:
    data = json.loads(result.read_text(encoding="utf-8"))
    edit(data["provenance"])
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (lambda p: p.pop("parameters"), "holds no parameters"),
        (lambda p: p.update(parameters={}), "holds no parameters"),
        (lambda p: p["parameters"].pop("method"), "lacks method"),
        (lambda p: p["parameters"].pop("position"), "lacks position"),
    ],
    ids=["removed", "empty", "no-method", "no-position"],
)
def test_from_refuses_a_result_without_its_parameters(
    result, edit, expected, tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(result.parent.parent)
    edited = _edited(result, tmp_path, edit)
    out = tmp_path / "again"
    code, _, err = run_main(
        ["calibrate", "--from", str(edited), "--out", str(out)], capsys, monkeypatch
    )
    assert code == 2 and err.count("error:") == 1 and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert expected in flat(err) and str(edited) in flat(err)
    assert not out.exists()  # nothing ran, nothing written


@pytest.fixture
def own_result(tmp_path, monkeypatch) -> Path:
    """A result of its own (its setup file is edited by the test)."""
    (tmp_path / "tiny.toml").write_text(tiny_setup_toml(), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    code, _, err = run_main([*CALIBRATE, "--out", "first"], _Capsys(), monkeypatch)
    assert code in (0, 1, 3), err
    return tmp_path / "first" / "result.json"


def test_from_on_a_changed_setup_needs_current_setup_and_records_it(
    own_result, capsys, monkeypatch
):
    folder = own_result.parent.parent
    first = json.loads(own_result.read_text(encoding="utf-8"))
    code, _, _ = run_main(
        ["calibrate", "--from", str(own_result), "--out", "same"], capsys, monkeypatch
    )
    assert code in (0, 1, 3)
    same = json.loads((folder / "same" / "result.json").read_text(encoding="utf-8"))
    assert same["provenance"]["rerun"]["setup"] == "recorded"
    assert same["points"] == first["points"]  # the rerun repeats the run
    setup = folder / "tiny.toml"
    setup.write_text(tiny_setup_toml().replace('width = "6 mm"', 'width = "6.5 mm"'))
    code, _, err = run_main(
        ["calibrate", "--from", str(own_result), "--out", "refused"], capsys, monkeypatch
    )
    assert code == 2 and "has changed since the run" in err and "--current-setup" in flat(err)
    assert not (folder / "refused").exists()
    code, _, err = run_main(
        ["calibrate", "--from", str(own_result), "--out", "current", "--current-setup"],
        capsys,
        monkeypatch,
    )
    assert code in (0, 1, 3), err
    record = json.loads((folder / "current" / "result.json").read_text(encoding="utf-8"))
    rerun = record["provenance"]["rerun"]
    assert rerun["setup"] == "current" and rerun["from"] == str(own_result.resolve())
    assert rerun["recorded_sha256"] == first["provenance"]["setup"]["sha256"]
    # the new result's setup digest is the current file's: what it really ran on
    assert rerun["current_sha256"] == record["provenance"]["setup"]["sha256"]
    assert rerun["current_sha256"] != rerun["recorded_sha256"]


def test_from_refuses_a_missing_setup_file_and_current_setup_alone(own_result, capsys, monkeypatch):
    folder = own_result.parent.parent
    (folder / "tiny.toml").rename(folder / "moved.toml")
    for extra in ([], ["--current-setup"]):
        code, _, err = run_main(
            ["calibrate", "--from", str(own_result), "--out", "again", *extra],
            capsys,
            monkeypatch,
        )
        assert code == 2 and err.count("error:") == 1
        assert "setup file" in flat(err) and "is missing" in flat(err)
    code, _, err = run_main([*CALIBRATE, "--current-setup", "--out", "x"], capsys, monkeypatch)
    assert code == 2 and "only with --from" in flat(err)
    assert not (folder / "again").exists() and not (folder / "x").exists()
