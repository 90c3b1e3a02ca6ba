"""The B-, C- and A-scan views of a position scan (a synthetic scan of Gabor echoes)."""

from __future__ import annotations

import numpy as np
import pytest

from cli_helpers import run_main
from echocal.plots.position_scan import ascan_figure, bscan_figure, cscan_figure, gated_values
from echocal.positionscan import position_scan
from echocal.signal import RecordingWindow, make_pulse, synthesize
from echocal.signal.gates import TimeGate

FS, T0, N = 50e6, 20e-6, 400


@pytest.fixture()
def scan():
    """A 5 × 6 raster over a plane whose echo arrives 2 ns later per mm of x."""
    x, y = np.arange(6) * 1e-3, np.arange(5) * 1e-3
    tau = 24e-6 + 2e-6 * x[None, :] + 0.0 * y[:, None]  # [s] 2 ns per mm
    amp = np.ones_like(tau)
    amp[2, 3] = 0.1  # a weak spot: -20 dB on the C-scan
    window = RecordingWindow(fs=FS, start=T0, n_samples=N)
    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
    samples = synthesize(amp[..., None], tau[..., None], pulse, window)
    return position_scan(samples, fs=FS, start_time=T0, x=x, y=y, attrs={"sound_speed_m_s": 1480.0})


def test_cscan_values_are_the_echoes(scan):
    gate = TimeGate(name="g", start=23e-6, width=2e-6)
    amp = gated_values(scan, gate, "amplitude")
    # the weak spot is 10x weaker than the traces of its column (same delay, scaled)
    assert amp[2, 3] == pytest.approx(0.1 * amp[3, 3], rel=1e-9)
    tof = gated_values(scan, gate, "tof")
    # the echo arrives 2 ns later per mm; sub-sample: well inside a sample (20 ns)
    np.testing.assert_allclose(
        tof - tof[:, :1], np.broadcast_to(2e-9 * np.arange(6), (5, 6)), atol=0.05e-9
    )


def test_figures_carry_units_and_db_colour_bars(scan):
    gate = TimeGate(name="g", start=23e-6, width=2e-6)
    b = bscan_figure(scan, depth=True)
    assert b.axes[0].get_ylabel() == "water path c₀t/2 [mm]"
    assert b.axes[1].get_ylabel() == "envelope [dB re max]"
    c = cscan_figure(scan, gate)
    assert c.axes[1].get_ylabel() == "gated peak [dB re max]"
    assert cscan_figure(scan, gate, value="tof").axes[1].get_ylabel() == "time of flight [µs]"
    a = ascan_figure(scan, 2e-3, 1e-3, gates=(gate,))
    assert a.axes[0].get_xlabel() == "time [µs]" and "x = 2 mm, y = 1 mm" in a.axes[0].get_title()


def test_cli_view_writes_each_figure(scan, tmp_path, capsys, monkeypatch):
    path = tmp_path / "s.nc"
    scan.save(path)
    for args in (["--bscan"], ["--cscan", "23us,2us", "--value", "tof"], ["--ascan", "1,2"]):
        out = tmp_path / f"{args[0].strip('-')}.png"
        code, _, err = run_main(["view", str(path), *args, "--out", str(out)], capsys, monkeypatch)
        assert code == 0, err
        assert out.stat().st_size > 10_000
    code, _, err = run_main(
        ["view", str(path), "--cscan", "90us,2us", "--out", str(tmp_path / "x.png")],
        capsys,
        monkeypatch,
    )
    assert code != 0 and "outside the recording window" in err and "Traceback" not in err


@pytest.mark.foreign_netcdf  # a damaged .nc on purpose
def test_report_of_a_position_scan_shows_its_views(scan, tmp_path, capsys, monkeypatch):
    path = tmp_path / "s.nc"
    scan.save(path)
    out = tmp_path / "report.html"
    code, _, err = run_main(["report", str(path), "--out", str(out)], capsys, monkeypatch)
    assert code == 0, err
    page = out.read_text()
    assert "position scan (raster of 5 × 6 traces)" in page
    assert page.count("data:image/png;base64,") == 3  # B-scan, C-scan, A-scan
    for view in ("B-scan", "C-scan", "A-scan"):
        assert view in page
    # a file that is not a position scan is refused in one line, nothing written
    other = tmp_path / "other.nc"
    other.write_bytes(b"not netcdf")
    code, _, err = run_main(
        ["report", str(other), "--out", str(tmp_path / "r2.html")], capsys, monkeypatch
    )
    assert code != 0 and "Traceback" not in err and "position scan's .nc file" in err
    assert not (tmp_path / "r2.html").exists()
