"""Sweep files: validation errors with field paths, resolution of defaults, expansion."""

from __future__ import annotations

import shutil
from importlib.resources import files
from pathlib import Path

import pytest

from echocal.errors import ConfigError, DataFileError, UnknownNameError
from echocal.experiments import builtin_sweep_names, expand, load_sweep, spec_hash

BASE = {
    "name": "t",
    "setup": "thesis",
    "budget": 30,
    "seeds": 3,
    "snr_db": [30, 20],
    "x0": {"points": [[0, 0]], "offset": [1, 2]},
    "methods": [
        {"name": "spsa", "preset": "thesis", "options": {"eps": [0.05, 0.1], "A": [1, 5]}},
        {"name": "model-based"},
    ],
}


def _problems(data: dict) -> str:
    with pytest.raises(ConfigError) as info:
        load_sweep(data)
    return str(info.value)


def test_expansion_counts_and_order():
    spec = load_sweep(BASE)
    cases = expand(spec)
    # (2 × 2 spsa grid + 1 model-based) × 2 SNRs × (1 point + 1 offset) × 3 seeds
    assert len(cases) == (2 * 2 + 1) * 2 * 2 * 3
    assert len({c.case_id for c in cases}) == len(cases)
    assert len({c.run_seed for c in cases}) == len(cases)
    assert [c.seed for c in cases[:3]] == [0, 1, 2]  # seeds innermost
    grid = {c.params for c in cases if c.method == "spsa"}
    assert grid == {
        (("A", a), ("eps", e)) for a in (1, 5) for e in (0.05, 0.1)
    }  # keys sorted, values crossed
    assert {c.snr_db for c in cases} == {30.0, 20.0}


def test_case_ids_and_seeds_are_stable():
    first, second = expand(load_sweep(BASE)), expand(load_sweep(dict(BASE)))
    assert [c.case_id for c in first] == [c.case_id for c in second]
    assert [c.run_seed for c in first] == [c.run_seed for c in second]
    assert first[0].case_id == 'spsa@thesis{"A":1,"eps":0.05}/snr=30/x0=(0,0)/seed=0'
    # a random start depends on the seed and the x0 entry only: paired across methods
    offsets = [c for c in first if c.x0_kind == "offset" and c.seed == 1]
    assert len({c.x0_seed for c in offsets}) == 1
    other_base = expand(load_sweep({**BASE, "seed": 7}))
    assert first[0].run_seed != other_base[0].run_seed


def test_defaults_resolved_from_the_setup():
    spec = load_sweep({"methods": [{"name": "spsa"}]})
    assert spec.setup == "thesis"
    assert spec.position == pytest.approx((0.01, 0.0, 0.022))  # thesis reference position
    assert spec.snr_db == [30.0]  # thesis noise.snr_db
    assert spec.x0.points == [(0.0, 0.0)]
    assert len(expand(spec)) == 1


def test_units_and_noiseless():
    spec = load_sweep({**BASE, "position": ["-10 mm", 0, "2.2 cm"], "snr_db": ["none", 10]})
    assert spec.position == pytest.approx((-0.01, 0.0, 0.022))
    assert spec.snr_db == [None, 10.0]
    assert "snr=none" in expand(spec)[0].case_id


def test_builtin_quick_sweep():
    assert "quick" in builtin_sweep_names()
    spec = load_sweep("quick")
    assert len(expand(spec)) == 4 * 2 * 5  # 4 methods × 2 SNRs × 5 seeds, one start kind


def test_unknown_method_lists_valid_ones():
    text = _problems({**BASE, "methods": [{"name": "spsaa"}]})
    assert "methods.0.name: unknown calibration method 'spsaa'" in text
    assert "model-based" in text and "quasi-newton" in text


def test_unknown_option_names_method_and_accepted():
    text = _problems({**BASE, "methods": [{"name": "spsa", "options": {"epsilon": 0.1}}]})
    assert "methods.0.options.epsilon: unknown option of method 'spsa'" in text
    assert "accepted: A, c, eps" in text


def test_every_problem_reported_at_once_with_paths():
    data = {
        **BASE,
        "budget": 0,
        "snr_db": ["loud"],
        "methods": [{"name": "newton", "options": {"mu": []}}, {"name": "nope"}],
    }
    text = _problems(data)
    # schema problems and the method checks are reported together
    assert "4 problem(s)" in text
    assert "budget:" in text
    assert "snr_db.0" in text
    assert "methods.0.options.mu: empty list (empty grid)" in text
    assert "methods.1.name" in text


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"methods": []}, "methods: at least one"),
        ({"seeds": 0}, "seeds: must be >= 1"),
        ({"seeds": []}, "seeds: empty list"),
        ({"snr_db": []}, "snr_db: empty list"),
        ({"x0": {"points": []}}, "x0: give points and/or offset"),
        ({"x0": {"offset": [3, 1]}}, "x0.offset: must be [lo, hi]"),
        ({"tolerance": -1}, "tolerance:"),
        ({"parameterization": "euler"}, "parameterization:"),
        ({"colour": "red"}, "colour: unknown key"),
        ({"methods": [{"name": "spsa", "preset": "table-9"}]}, "methods.0.preset: unknown"),
        ({"methods": [{"name": "spsa"}, {"name": "spsa"}]}, "methods.1: same method"),
    ],
)
def test_invalid_fields(change, expected):
    assert expected in _problems({**BASE, **change})


def test_malformed_toml_and_missing_files(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[[methods]\nname = "spsa"\n', encoding="utf-8")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_sweep(bad)
    with pytest.raises(DataFileError, match="sweep file not found"):
        load_sweep(tmp_path / "missing.toml")
    with pytest.raises(UnknownNameError, match="not a built-in"):
        load_sweep("no-such-sweep")


def test_setup_path_relative_to_sweep_file_and_hashed(tmp_path, monkeypatch):
    thesis = files("echocal") / "data" / "setups" / "thesis.toml"
    (tmp_path / "rig").mkdir()
    setup = tmp_path / "rig" / "my-setup.toml"
    shutil.copyfile(str(thesis), setup)
    sweep = tmp_path / "rig" / "s.toml"
    sweep.write_text('setup = "my-setup.toml"\n[[methods]]\nname = "spsa"\n', encoding="utf-8")
    monkeypatch.chdir(tmp_path)  # the path resolves against the sweep file, not the cwd
    spec = load_sweep(sweep)
    assert Path(spec.setup) == setup.resolve()
    before = spec_hash(spec)
    assert spec_hash(spec.model_copy(update={"name": "renamed"})) == before
    setup.write_text(setup.read_text().replace("snr_db = 30", "snr_db = 31"), encoding="utf-8")
    assert spec_hash(spec) != before  # the results depend on the setup file's content
    sweep.write_text('setup = "missing.toml"\n[[methods]]\nname = "spsa"\n', encoding="utf-8")
    with pytest.raises(ConfigError, match="setup: setup file not found"):
        load_sweep(sweep)


def test_cli_check_prints_names_with_brackets_verbatim(tmp_path):
    # rich would read "[bold]" / "[deg]" in a name as markup and drop it; the CLI escapes
    from typer.testing import CliRunner

    from echocal.cli import app

    path = tmp_path / "s.toml"
    path.write_text(
        'name = "a[bold]b [deg]"\nsetup = "thesis"\nbudget = 30\n[[methods]]\nname = "spsa"\n'
    )
    result = CliRunner().invoke(app, ["sweep", "check", str(path)])
    assert result.exit_code == 0, result.output
    assert "a[bold]b [deg]" in result.output
