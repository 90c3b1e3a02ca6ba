"""``echocal pulse``: figure files, summary, JSON, and clean errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.signal import GaborPulse

runner = CliRunner()


def test_pulse_gabor_writes_png_and_svg(tmp_path):
    out = tmp_path / "tmp.png"
    result = runner.invoke(app, ["pulse", "gabor", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.with_suffix(".svg").stat().st_size > 0
    assert "gabor: fc 5 MHz" in result.stdout


def test_pulse_json_summary_with_units(tmp_path):
    out = tmp_path / "p.png"
    result = runner.invoke(
        app,
        [
            "pulse",
            "gabor",
            "--fc",
            "2.25MHz",
            "--bandwidth",
            "50%",
            "--phase",
            "90",
            "--out",
            str(out),
            "--json",
            "--no-svg",
        ],
    )
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["parameters"] == {"center_frequency": 2.25e6, "bandwidth": 50.0, "phase": 90.0}
    # −6 dB width of the Gaussian spectrum = 50 % of fc (crossings interpolated linearly on a
    # ~2 kHz scan grid: error ≪ 1e-4)
    assert data["bandwidth_6db_hz"] == pytest.approx(0.5 * 2.25e6, rel=1e-4)
    assert not data["aliased"]
    assert not out.with_suffix(".svg").exists()


def test_pulse_sinc_and_sampled_file(tmp_path):
    r = runner.invoke(
        app,
        [
            "pulse",
            "sinc",
            "--bandwidth",
            "1MHz",
            "--window",
            "blackman",
            "--out",
            str(tmp_path / "s.png"),
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["parameters"]["window"] == "blackman"
    t = np.arange(-100, 101) / 100e6
    np.save(tmp_path / "ref.npy", GaborPulse().waveform(t))
    r = runner.invoke(
        app,
        [
            "pulse",
            "sampled",
            "--file",
            str(tmp_path / "ref.npy"),
            "--fs",
            "100MHz",
            "--out",
            str(tmp_path / "m.png"),
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["center_frequency_hz"] == pytest.approx(5e6, rel=0.01)


def test_sampled_time_amplitude_file_keeps_its_own_rate(tmp_path):
    # The same 5 MHz Gabor sampled at 50 MHz in a (time, amplitude) CSV.  The default
    # --fs (100 MHz, the plotting rate) must not re-time it: at 100 MHz the pulse would be
    # squeezed to half its duration and read as 10 MHz.  Tolerance 1 %: the centre
    # frequency of 101 samples of a smooth pulse.
    t = np.arange(-50, 51) / 50e6
    data = np.column_stack([t, GaborPulse().waveform(t)])
    np.savetxt(tmp_path / "p.csv", data, delimiter=",", header="time_s,amplitude")
    r = runner.invoke(
        app,
        [
            "pulse",
            "sampled",
            "--file",
            str(tmp_path / "p.csv"),
            "--out",
            str(tmp_path / "p.png"),
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout)
    assert summary["center_frequency_hz"] == pytest.approx(5e6, rel=0.01)


def test_unknown_pulse_is_a_clean_error(tmp_path):
    result = runner.invoke(app, ["pulse", "triangle", "--out", str(tmp_path / "x.png")])
    assert result.exit_code != 0
    assert "gabor, gaussian, ricker, sampled, sinc" in result.output
    assert "Traceback" not in result.output
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit)


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["gabor", "--fc", "0MHz"], "--fc"),
        (["gabor", "--bandwidth", "-5%"], "bandwidth"),
        (["ricker", "--window", "hann"], "--window"),
        (["gabor", "--fc", "5 mm"], "--fc"),
    ],
)
def test_bad_options_name_the_field(tmp_path, args, field):
    result = runner.invoke(app, ["pulse", *args, "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert field in result.output
    assert "Traceback" not in result.output
