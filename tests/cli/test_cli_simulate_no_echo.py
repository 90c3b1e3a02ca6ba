"""``echocal simulate``: an echo only when the matched filter sees one; the setup's seed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import echocal
from cli_helpers import flat, run_main
from echocal.cli import app

runner = CliRunner()
C0 = 1480.0  # [m/s] water, both setups used here


def run(*args, code=0):
    result = runner.invoke(app, ["simulate", *args])
    assert result.exit_code == code, result.output
    return result


def summary_of(tmp_path, *args):
    return json.loads(run(*args, "--json", "--out", str(tmp_path)).stdout)


def test_pure_noise_reports_no_echo_with_its_significance(tmp_path):
    # the 5 MHz probe 25 deg off its plate's normal (lobe sigma ~0.3 deg): only noise returns
    args = ("--setup", "immersion-5mhz", "--pose", "0,0,50,0,25")
    data = summary_of(tmp_path, *args)
    assert data["detected"] is False
    assert data["tof_s"] is None and data["distance_m"] is None
    # a significance of pure noise is ~N(0, 1): far below the threshold (P(g > 4.5) ~ 3e-6)
    assert data["significance"] < data["detection_threshold"] == 4.5
    human = run(*args, "--out", str(tmp_path), "--overwrite")
    assert "no echo detected" in human.output and "significance g =" in human.output
    assert "distance" in human.output and " mm" not in human.output  # no distance printed


def test_an_echo_is_detected_and_its_time_of_flight_reported(tmp_path):
    # thesis block, straight down from 20 mm at 30 dB: tau = 2 * 20 mm / c0
    data = summary_of(tmp_path, "--pose", "0,0,20")
    assert data["detected"] is True and data["significance"] > 4.5
    # tolerance: a fraction of a sample at 20 MHz plus the facet's slight slope
    assert data["tof_s"] == pytest.approx(2 * 0.02 / C0, abs=0.5e-6)
    assert data["distance_m"] == pytest.approx(0.02, abs=0.4e-3)


def test_the_noiseless_path_is_unchanged(tmp_path):
    data = summary_of(tmp_path, "--pose", "0,0,20", "--specimen", "flat-plate", "--snr", "none")
    assert data["detected"] is True and data["significance"] is None
    assert data["tof_s"] == pytest.approx(2 * 0.02 / C0, abs=0.05 / 20e6)


def test_no_gate_key_or_legend_without_a_gate(tmp_path, monkeypatch):
    import echocal.plots

    figures = []
    real = echocal.plots.save_figure

    def keep(fig, *args, **kwargs):
        figures.append(fig)
        return real(fig, *args, **kwargs)

    monkeypatch.setattr(echocal.plots, "save_figure", keep)
    base = ("--pose", "0,0,20", "--specimen", "flat-plate", "--snr", "none")
    data = summary_of(tmp_path / "a", *base)
    assert "gate_s" not in data
    # the shaded window is the pseudo-energy's: two pulse durations centred on the echo
    start, width = data["energy_window_s"]
    assert start + width / 2 == pytest.approx(data["tof_s"], abs=1e-12)
    labels = [t.get_text() for t in figures[-1].axes[0].get_legend().get_texts()]
    assert "gate" not in labels and "pseudo-energy window" in labels
    gated = summary_of(tmp_path / "b", *base, "--gate", "20,15")
    assert gated["gate_s"] == pytest.approx([20e-6, 15e-6])
    labels = [t.get_text() for t in figures[-1].axes[0].get_legend().get_texts()]
    assert any(label.startswith("gate 20us,15us") for label in labels)


def test_a_gate_that_never_sees_an_echo_is_refused_before_anything_is_written(
    tmp_path, capsys, monkeypatch
):
    # issue #14: the echo is at ~27 us; [40, 45] us holds only noise -> one line, exit 2
    out = tmp_path / "new" / "sim"
    args = ["simulate", "--pose", "0,0,20", "--gate", "40,5", "--out", str(out)]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2, err
    assert "--gate 40us,5us: never sees an echo" in flat(err) and "put it on an echo" in flat(err)
    assert err.count("error:") == 1 and "Traceback" not in err
    assert not (tmp_path / "new").exists()  # no folder, no A-scan files


def _samples(path: Path) -> np.ndarray:
    return np.loadtxt(path / "ascan.csv", delimiter=",", comments="#", skiprows=2)


def test_the_setup_files_seed_is_used_unless_seed_is_given(tmp_path):
    source = Path(echocal.__file__).parent / "data" / "setups" / "thesis.toml"
    text = source.read_text(encoding="utf-8").replace("seed = 0", "seed = 5")
    assert "seed = 5" in text
    (tmp_path / "seeded.toml").write_text(text, encoding="utf-8")
    pose = ("--pose", "0,0,20")
    run(*pose, "--setup", str(tmp_path / "seeded.toml"), "--out", str(tmp_path / "file"))
    run(*pose, "--seed", "5", "--out", str(tmp_path / "five"))
    run(*pose, "--seed", "0", "--out", str(tmp_path / "zero"))
    from_file = _samples(tmp_path / "file")
    np.testing.assert_array_equal(from_file, _samples(tmp_path / "five"))
    assert not np.array_equal(from_file, _samples(tmp_path / "zero"))
