"""Pulses at the user boundary: implausible frequencies and bandwidths are refused with a
hint instead of hanging, output formats are checked before any work.

Each CLI case used to hang (> 60 s: a pulse of seconds sampled at MHz rates, or a sinc of
hundreds of thousands of cycles whose spectrum is integrated numerically); an alarm turns a
regression into a failure instead of a stuck test run.
"""

from __future__ import annotations

import signal
import warnings

import numpy as np
import pytest
from matplotlib.figure import Figure
from typer.testing import CliRunner

import echocal.cli.scene
import echocal.plots.pulses
from echocal.cli import app
from echocal.errors import EchocalValueError
from echocal.plots import figure_formats, save_figure, supported_formats
from echocal.signal import GaborPulse, SampledPulse, SincPulse, make_pulse, pulse_names
from echocal.signal.pulses import (
    MAX_PULSE_CYCLES,
    MAX_SAMPLED_PULSE_SAMPLES,
    parse_bandwidth,
    plausible_bandwidth,
    pulse_options,
)

runner = CliRunner()


@pytest.fixture(autouse=True)
def no_hang():
    """Fail a test that runs longer than 10 min: the hang these tests guard against never
    ends, while each test takes well under a second when fixed (the bound is generous for a
    loaded machine; it only turns a hang into a failure)."""

    def expire(*_):
        raise TimeoutError("still running after 10 min (each test takes < 1 s): the hang is back")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(600)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


def pulse_cli(tmp_path, *args: str):
    return runner.invoke(app, ["pulse", *args, "--out", str(tmp_path / "p.png")])


# -- the CLI: refused with a hint, exit 2 -------------------------------------------------
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["gabor", "--fc", "5"], "--fc: 5 Hz is implausible"),
        (["gaussian", "--fc", "5"], "did you mean '5 MHz'?"),
        (["ricker", "--fc", "5"], "did you mean '5 MHz'?"),
        (["sinc", "--fc", "5"], "did you mean '5 MHz'?"),
        (["sinc", "--fc", "5MHz", "--bandwidth", "60"], "did you mean '60%' (B = 1.5 MHz)?"),
        (["sinc", "--bandwidth", "1.5"], "did you mean '1.5 MHz' (B = 1.5 MHz)?"),
        (["sinc", "--bandwidth", "5kHz"], "bandwidth: B = 5 kHz makes the sinc pulse"),
        (["sinc", "--lobes", "1000"], "lobes: 1000 lobes make the sinc pulse"),
        (["gabor", "--fs", "100"], "--fs: 100 Hz is implausible for a sampling rate"),
        (["gabor", "--alpha", "5"], "would draw"),
        (["gabor", "--fc", "5 GHz"], "--fc: 5 GHz is implausible"),
    ],
)
def test_implausible_pulse_options_are_refused_not_hung(tmp_path, args, message):
    result = pulse_cli(tmp_path, *args)
    assert result.exit_code == 2, result.output
    assert message in " ".join(result.output.split())
    assert "Traceback" not in result.output
    assert not (tmp_path / "p.png").exists()


def test_sampled_pulse_at_a_slipped_rate_is_refused(tmp_path):
    # A one-column file sampled at --fs 100 (Hz, meant MHz)
    np.save(tmp_path / "w.npy", GaborPulse().waveform(np.arange(-100, 101) / 100e6))
    result = pulse_cli(tmp_path, "sampled", "--file", str(tmp_path / "w.npy"), "--fs", "100")
    assert result.exit_code == 2
    assert "did you mean '100 MHz'?" in result.output


def test_every_registered_pulse_refuses_a_frequency_slip(tmp_path):
    # No pulse of the registry may hang on a unit slip: each is refused at the boundary.
    for name in pulse_names():
        args = [name, "--fc", "5"] if name != "sampled" else [name, "--fs", "5"]
        if name == "sampled":
            np.save(tmp_path / "w.npy", GaborPulse().waveform(np.arange(-100, 101) / 100e6))
            args += ["--file", str(tmp_path / "w.npy")]
        result = pulse_cli(tmp_path, *args)
        assert result.exit_code == 2, (name, result.output)
        assert "implausible" in result.output, name


def test_sinc_percent_bandwidth_still_works(tmp_path):
    result = pulse_cli(tmp_path, "sinc", "--fc", "5MHz", "--bandwidth", "60%", "--json")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "p.png").exists()


# -- figure formats: checked before the work ----------------------------------------------
def test_pulse_to_an_unknown_format_fails_before_plotting(tmp_path, monkeypatch):
    def never(*_a, **_k):
        raise AssertionError("plotted before the output format was checked")

    monkeypatch.setattr(echocal.plots.pulses, "plot_pulse", never)
    result = runner.invoke(app, ["pulse", "gabor", "--out", str(tmp_path / "p.txt")])
    assert result.exit_code == 2
    text = " ".join(result.output.split())
    assert "--out: cannot write a figure as 'txt'" in text
    assert "png" in text and "svg" in text and "pdf" in text
    assert list(tmp_path.iterdir()) == []


def test_scene_to_an_unknown_format_fails_before_loading_the_setup(tmp_path, monkeypatch):
    def never(*_a, **_k):
        raise AssertionError("the setup was loaded before the output format was checked")

    monkeypatch.setattr(echocal.cli.scene, "resolve_setup", never)
    out = tmp_path / "s.txt"
    result = runner.invoke(app, ["scene", "--pose", "0,0,20", "--out", str(out)])
    assert result.exit_code == 1  # CliRunner: the EchocalError itself (run_cli makes it 2)
    assert isinstance(result.exception, EchocalValueError)
    assert "cannot write a figure as 'txt'" in str(result.exception)
    assert list(tmp_path.iterdir()) == []


def test_figure_formats_and_save_figure():
    assert figure_formats("out/pulse") == ("png",)  # no suffix: png, as before
    assert figure_formats("out/pulse.svg", ("svg",)) == ("svg",)
    assert figure_formats("out/pulse.PDF", ("svg",)) == ("pdf", "svg")
    assert {"png", "svg", "pdf"} <= set(supported_formats())
    with pytest.raises(EchocalValueError, match="--out: cannot write a figure as 'txt'"):
        figure_formats("x.txt")
    with pytest.raises(EchocalValueError, match="format: cannot write a figure as 'doc'"):
        save_figure(Figure(), "x.png", formats=("png", "doc"))


# -- the library: guards and helpers ------------------------------------------------------
def test_sinc_guards_name_the_culprit():
    with pytest.raises(EchocalValueError, match=r"^bandwidth: B = 60 Hz makes the sinc pulse"):
        SincPulse(bandwidth=60.0)
    with pytest.raises(EchocalValueError, match=r"^lobes: 400 lobes"):
        SincPulse(lobes=400)
    with pytest.raises(EchocalValueError, match=r"^length: 2 s makes the sinc pulse"):
        SincPulse(length=2.0)
    # the limit: 2T (f_c + B) carrier cycles, with T = lobes / 2B
    lobes = int(MAX_PULSE_CYCLES * 1e6 / 6e6)  # f_c = 5 MHz, B = 1 MHz
    assert 2 * SincPulse(bandwidth=1e6, lobes=lobes).half_length * 6e6 <= MAX_PULSE_CYCLES


def test_sampled_pulse_length_is_bounded():
    w = np.hanning(MAX_SAMPLED_PULSE_SAMPLES + 1)
    with pytest.raises(EchocalValueError, match="samples: a sampled pulse holds at most 4096"):
        SampledPulse(samples=w, fs=100e6)
    SampledPulse(samples=w[:-1], fs=100e6)  # at the limit: fine


def test_a_centre_frequency_outside_the_ultrasonic_range_warns():
    with pytest.warns(UserWarning, match="center_frequency = 5 Hz lies outside"):
        GaborPulse(center_frequency=5.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        GaborPulse(center_frequency=20e3)  # the range is closed


def test_unknown_options_and_the_options_of_each_pulse():
    assert pulse_options("gabor") == ("alpha", "bandwidth", "center_frequency", "phase")
    assert "lobes" in pulse_options("sinc") and pulse_options("ricker") == ("center_frequency",)
    with pytest.raises(
        EchocalValueError,
        match="lobes: unknown option for gabor; valid: alpha, bandwidth, center_frequency, phase",
    ):
        make_pulse("gabor", lobes=3)


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("gabor", "60%", 60.0),
        ("gabor", "60", 60.0),  # bare: percent
        ("gabor", 60, 60.0),
        ("gabor", "3 MHz", 60.0),  # full −6 dB width: 3 MHz of 5 MHz
        ("sinc", "60%", 1.5e6),  # 2B = 60 % of 5 MHz
        ("sinc", "1.5 MHz", 1.5e6),
        ("sinc", "60", 60.0),  # bare: Hz (refused by plausible_bandwidth)
    ],
)
def test_parse_bandwidth_follows_each_pulse_unit(name, text, expected):
    assert parse_bandwidth(name, text, 5e6) == pytest.approx(expected, rel=1e-12)


def test_plausible_bandwidth_suggests_only_readings_that_work():
    with pytest.raises(EchocalValueError, match=r"did you mean '60%' \(B = 1.5 MHz\)\?$"):
        plausible_bandwidth("sinc", 60.0, 5e6, bare=True)
    with pytest.raises(EchocalValueError, match="at least 1 kHz; gabor's is in %\\)$"):
        plausible_bandwidth("sinc", 60.0, 5e6, bare=False)  # typed with a unit: no guess
    assert plausible_bandwidth("sinc", 1.5e6, 5e6) == 1.5e6
    assert plausible_bandwidth("gabor", 60.0, 5e6, bare=True) == 60.0
    assert parse_bandwidth("ricker", "60", 5e6) == "60"  # no bandwidth: the pulse refuses it
