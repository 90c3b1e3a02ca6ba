"""Every result file records its origin, and a calibration reruns from it (issue 15,
"Provenance"): result.json, scan.nc, a recording and a sweep's runs.parquet carry the setup
and its digest, the source, position, seed, method with every option, the versions, the
command line and the start and end times; ``echocal calibrate --from result.json`` gives
the same numbers, and refuses when the setup or the recording changed.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import importlib.metadata
import json
import subprocess
import sys
from pathlib import Path

import pytest

from cli_helpers import run_main, tiny_setup_toml
from echocal.errors import DataFileError
from echocal.provenance import FORMAT, file_digest, read_provenance
from echocal.setups import load_setup_config

pytestmark = pytest.mark.slow  # fresh processes: a rerun is compared across processes

CALIBRATE = ["calibrate", "--setup", "tiny.toml", "--position", "0,0,16", "--x0", "2,-1"]
CALIBRATE += ["--method", "model-based", "--budget", "14", "--settle", "none", "--no-plots"]


def echocal(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``echocal ARGS`` in a fresh process (a rerun is compared across processes)."""
    return subprocess.run(
        [sys.executable, "-m", "echocal.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("prov")
    (path / "tiny.toml").write_text(tiny_setup_toml())
    return path


@pytest.fixture(scope="module")
def first(folder) -> dict:
    done = echocal([*CALIBRATE, "--seed", "5", "--out", "first"], folder)
    assert done.returncode in (0, 1, 3), done.stderr  # 3: budget ran out (no convergence claim)
    return json.loads((folder / "first" / "result.json").read_text())


def _utc(text: str) -> dt.datetime:
    assert text.endswith("Z")
    return dt.datetime.fromisoformat(text[:-1] + "+00:00")


def test_result_json_records_its_origin(folder, first):
    record = first["provenance"]
    assert record["format"] == FORMAT and record["command"] == "calibrate"
    assert record["argv"][1:] == [*CALIBRATE, "--seed", "5", "--out", "first"]
    assert record["cwd"] == str(folder)
    # the setup digest: SHA-256 of the resolved configuration, recomputed here
    config, _ = load_setup_config(folder / "tiny.toml")
    data = config.model_dump(mode="json")
    # tables a setup leaves out by default are left out of the digest (an ideal bench,
    # one solid, longitudinal paths only, the listed paths): a setup written before they
    # existed keeps its digest
    assert data.pop("bench") is None and data["specimen"].pop("layers") is None
    assert data["specimen"].pop("shear_legs") == 0
    assert data["specimen"].pop("exact_stack") is False
    text = json.dumps(data, sort_keys=True)
    assert record["setup"] == {
        "name": str(folder / "tiny.toml"),
        "sha256": hashlib.sha256(text.encode()).hexdigest(),
    }
    assert record["source"]["kind"] == "simulator"
    assert record["position_m"] == [0.0, 0.0, 0.016] and record["seed"] == 5
    method = record["method"]
    assert method["name"] == "model-based" and method["budget"] == 14
    assert method["options"] == first["options"]  # every option the method ran with
    assert method["x0"] == [2.0, -1.0] and method["parameterization"] == "tilt"
    for name in ("numpy", "scipy", "xarray", "pandas", "h5py"):
        assert record["versions"][name] == importlib.metadata.version(name)
    assert record["versions"]["echocal"] == importlib.metadata.version("echocal")
    started, finished = _utc(record["started"]), _utc(record["finished"])
    assert started <= finished <= dt.datetime.now(dt.UTC)
    assert (finished - started).total_seconds() >= first["wall_time"] * 0.5


def test_calibrate_from_result_json_gives_the_same_numbers(folder, first):
    done = echocal(["calibrate", "--from", "first/result.json", "--out", "again"], folder)
    assert done.returncode in (0, 1, 3), done.stderr  # 3: budget ran out (no convergence claim)
    again = json.loads((folder / "again" / "result.json").read_text())
    for key in ("x", "points", "values", "iterates", "status", "n_measurements", "options"):
        assert again[key] == first[key], key
    assert again["provenance"]["parameters"] == first["provenance"]["parameters"]
    assert again["provenance"]["argv"][1:] == [
        "calibrate",
        "--from",
        "first/result.json",
        "--out",
        "again",
    ]


def test_from_refuses_other_options_a_changed_setup_and_no_provenance(
    folder, first, capsys, monkeypatch
):
    monkeypatch.chdir(folder)
    code, _, err = run_main(
        ["calibrate", "--from", "first/result.json", "--seed", "6", "--out", "x"],
        capsys,
        monkeypatch,
    )
    assert code == 2 and err.count("error:") == 1 and "drop --seed" in err
    changed = folder / "changed"
    changed.mkdir()
    setup = folder / "tiny.toml"
    original = setup.read_text()
    try:
        setup.write_text(original.replace('width = "6 mm"', 'width = "6.5 mm"'))
        code, _, err = run_main(
            ["calibrate", "--from", "first/result.json", "--out", "y"], capsys, monkeypatch
        )
    finally:
        setup.write_text(original)
    assert code == 2 and "has changed since the run" in err and "tiny.toml" in err
    plain = folder / "plain.json"
    plain.write_text(json.dumps({"x": [0, 0]}))
    code, _, err = run_main(["calibrate", "--from", str(plain), "--out", "z"], capsys, monkeypatch)
    assert code == 2 and "records no provenance" in err
    assert not any((folder / name).exists() for name in ("x", "y", "z"))


def test_a_replay_calibration_records_the_recording_digest(folder, capsys, monkeypatch):
    monkeypatch.chdir(folder)
    args = ["record", "--setup", "tiny.toml", "--out", "grid.nc", "--azimuth", "-6:6:7"]
    args += ["--coelevation", "-6:6:7", "--position", "0,0,16", "--no-progress"]
    assert run_main(args, capsys, monkeypatch)[0] == 0
    recorded = read_provenance(folder / "grid.nc")  # the recording's own provenance
    assert recorded["command"] == "record" and recorded["method"]["grid"]["azimuth"][0] == -6
    code, _, err = run_main(
        ["calibrate", "--replay", "grid.nc", "--out", "onreplay", "--no-plots"],
        capsys,
        monkeypatch,
    )
    assert code in (0, 1), err
    source = read_provenance(folder / "onreplay" / "result.json")["source"]
    assert source["kind"] == "replay" and source["file"] == str(folder / "grid.nc")
    assert source["sha256"] == hashlib.sha256((folder / "grid.nc").read_bytes()).hexdigest()
    assert source["sha256"] == file_digest(folder / "grid.nc")
    with (folder / "grid.nc").open("ab") as fh:  # the recording changes
        fh.write(b"\0")
    code, _, err = run_main(
        ["calibrate", "--from", "onreplay/result.json", "--out", "rerun"], capsys, monkeypatch
    )
    assert code == 2 and "recording" in err and "has changed since the run" in err


def test_scan_and_sweep_files_record_their_origin(folder, capsys, monkeypatch):
    monkeypatch.chdir(folder)
    args = ["scan", "--setup", "tiny.toml", "--grid", "0:0:1,0:0:1", "--z", "16"]
    assert run_main([*args, "--out", "scan", "--no-figures"], capsys, monkeypatch)[0] == 0
    record = read_provenance(folder / "scan" / "scan.nc")
    assert record["command"] == "scan" and record["setup"]["sha256"]
    assert record["method"]["name"] == "auto" and record["seed"] == 4  # the setup's seed
    assert _utc(record["started"]) <= _utc(record["finished"])

    from echocal.experiments import run_sweep

    spec = {
        "name": "one",
        "setup": str(folder / "tiny.toml"),
        "position": [0.0, 0.0, 0.016],
        "budget": 14,
        "max_iter": 20,
        "snr_db": [30],
        "methods": [{"name": "model-based"}],
    }
    results = run_sweep(spec, folder / "sweep", workers=1, progress=False)
    for where in (folder / "sweep", results.runs_path):
        record = read_provenance(where)
        assert record["command"] == "sweep run" and record["runs"]["total"] == 1
        assert record["method"]["hash"] == results.hash
        assert record["position_m"] == [0.0, 0.0, 0.016]


def test_a_file_without_provenance_is_refused(tmp_path):
    path = tmp_path / "old.json"
    path.write_text("{}")
    with pytest.raises(DataFileError, match="records no provenance"):
        read_provenance(path)


SWEEP_TOML = """
name = "one"
setup = "tiny.toml"
position = [0.0, 0.0, 0.016]
budget = 14
max_iter = 20
snr_db = [30]
[[methods]]
name = "model-based"
"""

RECORD = ["record", "--setup", "tiny.toml", "--out", "grid.nc", "--azimuth", "-3:3:3"]
RECORD += ["--coelevation", "-3:3:3", "--position", "0,0,16", "--no-progress"]
SCAN = ["scan", "--setup", "tiny.toml", "--grid", "0:0:1,0:0:1", "--z", "16"]
SCAN += ["--out", "scan", "--no-figures"]
FILE_KINDS = {
    "result.json": ([*CALIBRATE, "--seed", "5", "--out", "cal"], "cal/result.json"),
    "recording": (RECORD, "grid.nc"),
    "scan.nc": (SCAN, "scan/scan.nc"),
    "runs.parquet": (
        ["sweep", "run", "one.toml", "--out", "sweep", "--workers", "1", "--no-progress"],
        "sweep/runs.parquet",
    ),
}


@pytest.mark.parametrize("kind", list(FILE_KINDS))
def test_every_file_kind_carries_the_whole_record(kind, tmp_path, capsys, monkeypatch):
    """Each item of the issue's provenance list, in each kind of result file."""
    from echocal.provenance import git_commit
    from echocal.setup_digest import setup_digest

    (tmp_path / "tiny.toml").write_text(tiny_setup_toml())
    (tmp_path / "one.toml").write_text(SWEEP_TOML)
    monkeypatch.chdir(tmp_path)
    args, target = FILE_KINDS[kind]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code in (0, 1, 3), err  # 1/3: no convergence claim; the file is written
    record = read_provenance(tmp_path / target)
    assert record["format"] == FORMAT
    # the command line as typed, where it ran, and when (UTC, start before end)
    assert record["argv"] == ["echocal", *args] and record["cwd"] == str(tmp_path)
    assert _utc(record["started"]) <= _utc(record["finished"]) <= dt.datetime.now(dt.UTC)
    # the setup: its path and the digest of its resolved content, recomputed here
    setup = setup_digest(str(tmp_path / "tiny.toml"))
    assert record["setup"] == setup and len(setup["sha256"]) == 64
    # the source, the seed, the method and its options
    assert record["source"]["kind"] == "simulator"
    assert isinstance(record["seed"], int)
    assert record["method"] and isinstance(record["method"], dict)
    if kind == "result.json":
        assert record["seed"] == 5 and record["position_m"] == [0.0, 0.0, 0.016]
        assert record["method"]["options"]  # every option the method ran with
    if kind == "recording":
        assert record["method"]["grid"]["positions"] == [[0.0, 0.0, 0.016]]
    if kind == "scan.nc":
        assert record["method"]["name"] == "auto" and record["method"]["budget_per_point"]
    if kind == "runs.parquet":
        assert record["position_m"] == [0.0, 0.0, 0.016]
        assert record["method"]["spec"]["methods"][0]["name"] == "model-based"
    # echocal's version (and its git commit when run from a checkout) and its dependencies'
    versions = record["versions"]
    assert versions["echocal"] == importlib.metadata.version("echocal")
    for name in ("numpy", "scipy", "xarray", "pandas", "h5py"):
        assert versions[name] == importlib.metadata.version(name)
    assert versions.get("echocal_git") == git_commit()


def test_the_git_commit_is_the_checkouts_when_there_is_one():
    import echocal
    from echocal.provenance import git_commit

    where = Path(echocal.__file__).resolve().parent
    done = subprocess.run(
        ["git", "-C", str(where), "rev-parse", "HEAD"], capture_output=True, text=True
    )
    if done.returncode != 0:
        assert git_commit() is None  # installed from a wheel: no commit claimed
    else:
        assert git_commit().removesuffix("-dirty") == done.stdout.strip()


def test_python_dash_m_echocal_is_recorded_as_echocal(monkeypatch):
    from echocal.provenance import start

    monkeypatch.setattr("sys.argv", ["/venv/lib/echocal/__main__.py", "calibrate", "--x0", "1,2"])
    assert start("calibrate").argv == ["echocal", "calibrate", "--x0", "1,2"]
