"""Figures read data only and are written atomically as PNG + SVG."""

from __future__ import annotations

from matplotlib.figure import Figure

from echocal.plots import save_figure
from echocal.plots.ascan import plot_ascan
from echocal.plots.pulses import plot_pulse
from echocal.signal import GaborPulse, Gate, RecordingWindow, synthesize


def test_plot_pulse_and_ascan_save(tmp_path):
    p = GaborPulse()
    fig = plot_pulse(p, fs=100e6)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=1024)
    x = synthesize([1.0, 0.4], [24e-6, 26e-6], p, w, normalize="peak")
    fig2 = plot_ascan(x, w, pulse=p, gate=Gate(start=23e-6, width=4e-6, threshold=0.3))
    labels = [t.get_text() for t in fig2.axes[0].get_legend().get_texts()]
    assert labels[:3] == ["A-scan", "envelope", "gate"] and labels[3].startswith("τ = 24.0000")
    written = save_figure(fig2, tmp_path / "a.png")
    assert [q.name for q in written] == ["a.png", "a.svg"]
    assert all(q.stat().st_size > 0 for q in written)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.png", "a.svg"]  # no temp files
