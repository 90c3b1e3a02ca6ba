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
    assert code == 2 and "--overwrite" in err  # the folder holds the first run's files
    code, text, err = run_main([*args, "--overwrite"], capsys, monkeypatch)
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


def test_the_mechanical_axis_is_the_tilted_plates_normal(tmp_path, capsys, monkeypatch):
    setup = write_setup(tmp_path, FLAT.replace('"flat-plate"', '"tilted-plate"'))
    args = ["characterize", "--setup", str(setup), "--snr", "none", "--coarse-points", "7"]
    code, text, err = run_main([*args, "--json"], capsys, monkeypatch)
    assert code == 0, err
    axis = json.loads(text)["beam_axis"]
    # the plate's normal (azimuth 30°, co-elevation 4°) as gimbal tilts, computed here:
    # n = (sin 4° cos 30°, sin 4° sin 30°, cos 4°) = R_y(t_y) R_x(t_x) ẑ
    n = np.array([np.sin(np.radians(4)) * np.cos(np.radians(30)), 0.0, np.cos(np.radians(4))])
    n[1] = np.sin(np.radians(4)) * np.sin(np.radians(30))
    t_x = np.degrees(np.arcsin(-n[1]))
    t_y = np.degrees(np.arctan2(n[0], n[2]))
    assert np.allclose(axis["reflector_tilts_deg"], [t_x, t_y], atol=1e-6)
    # an ideal bench has no squint: within the 0.05° (the fit lands within 0.005°)
    assert np.allclose(axis["squint_deg"], 0.0, atol=0.05)


def test_characterize_on_a_rig_file(tmp_path, capsys, monkeypatch):
    """The emulated rig (the simulator behind an instrument server on loopback, as in
    tests/rigs) measures the squint of the probe it serves."""
    pytest.importorskip("pyvisa_sim")
    from echocal.geometry import Pose
    from echocal.measurement import InstrumentServer
    from echocal.setups import load_setup

    setup = write_setup(tmp_path, FLAT + BENCH)
    with InstrumentServer(load_setup(setup), initial_pose=Pose(0.0, 0.0, 0.05)) as server:
        host, port = server.address
        lines = ["[rig]", 'name = "emulated"']
        for part in ("positioner", "receiver"):
            lines += [f"[rig.{part}]", 'driver = "tcp"', f'address = "{host}:{port}"']
            lines += ["timeout = 30"]
        rig = tmp_path / "rig.toml"
        rig.write_text("\n".join(lines) + "\n")
        args = ["characterize", "--rig", str(rig), "--coarse-points", "7", "--averages", "4"]
        code, _, err = run_main([*args, "--snr", "20"], capsys, monkeypatch)
        assert code != 0 and "--snr" in err
        code, text, err = run_main([*args, "--position", "0,0,50", "--json"], capsys, monkeypatch)
    assert code == 0, err
    assert np.allclose(json.loads(text)["beam_axis"]["squint_deg"], SQUINT, atol=0.05)
