"""``echocal characterize`` end to end: the summary, the JSON, the report page, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _probe_setups import BENCH, FLAT, SQUINT, pore_setup, write_setup

from cli_helpers import flat, run_main


def test_characterize_prints_writes_json_and_the_report(tmp_path, capsys, monkeypatch):
    setup = write_setup(tmp_path, FLAT + BENCH)
    out = tmp_path / "out"
    args = ["characterize", "--setup", str(setup), "--coarse-points", "7", "--out", str(out)]
    code, text, err = run_main([*args, "--json"], capsys, monkeypatch)
    assert code == 0, err
    data = json.loads(text)
    # the bound on the squint: 0.05 deg
    assert np.allclose(data["beam_axis"]["squint_deg"], SQUINT, atol=0.05)
    assert data["spectrum"]["center_frequency_hz"] == pytest.approx(5e6, rel=0.02)
    assert (
        json.loads((out / "characterize.json").read_text())["measurements"] == data["measurements"]
    )
    assert (out / "characterize.png").stat().st_size > 0
    code, text, err = run_main(args, capsys, monkeypatch)
    assert code == 0, err
    assert "squint (0.5" in flat(text) and "centre frequency" in text


def test_characterize_measures_beam_widths_and_focus_over_the_point_setup(
    tmp_path, capsys, monkeypatch
):
    flat_probe = write_setup(tmp_path, FLAT.replace('"12.7 mm"', '"2 mm"'), "flat.toml")
    point = write_setup(tmp_path, pore_setup(start="40 us") + BENCH, "point.toml")
    args = ["characterize", "--setup", str(flat_probe), "--coarse-points", "5", "--span", "4"]
    args += ["--point-setup", str(point), "--distances", "40,55", "--line-points", "21"]
    args += ["--half-span", "8", "--focus-distances", "30,35,40", "--json"]
    code, text, err = run_main(args, capsys, monkeypatch)
    assert code == 0, err
    data = json.loads(text)
    widths = np.array(data["beam_profile"]["width_6db_m"])
    assert widths.shape == (2, 2) and np.all(widths[1] > widths[0])  # the beam spreads
    # a flat 2 mm probe has no focus beyond its 3.4 mm near field: no maximum inside
    assert data["focus"]["focal_distance_m"] is None


@pytest.mark.parametrize(
    ("option", "value", "field"),
    [
        ("--span", "-2", "span"),
        ("--position", "1,2", "--position"),
        ("--reflector-tilts", "a,b", "--reflector-tilts"),
        ("--averages", "0", "n_ascans"),
        ("--distances", "40", "--point-setup"),
    ],
)
def test_bad_input_is_one_line_naming_the_field(
    tmp_path, capsys, monkeypatch, option, value, field
):
    setup = write_setup(tmp_path, FLAT)
    code, _, err = run_main(
        ["characterize", "--setup", str(setup), option, value], capsys, monkeypatch
    )
    assert code != 0
    assert field in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
