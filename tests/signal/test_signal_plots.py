"""Figures read data only and are written atomically as PNG + SVG."""

from __future__ import annotations

import numpy as np
import pytest
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
    assert labels[:2] == ["A-scan", "envelope"] and "detection gate" in labels
    assert any(label.startswith("τ = 24.0000") for label in labels)
    assert len(fig2.axes) == 2  # the zoom panel on the echo: τ ± 3 pulse durations
    lo, hi = fig2.axes[1].get_xlim()
    np.testing.assert_allclose([lo, hi], 24.0 + np.array([-3, 3]) * p.duration * 1e6, rtol=1e-9)
    written = save_figure(fig2, tmp_path / "a.png")
    assert [q.name for q in written] == ["a.png", "a.svg"]
    assert all(q.stat().st_size > 0 for q in written)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.png", "a.svg"]  # no temp files


def test_a_noise_ascan_is_drawn_at_the_scale_of_the_expected_echo():
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=1024)
    noise = np.random.default_rng(1).normal(0.0, 0.01, w.n_samples)
    fig = plot_ascan(noise, w, expected_amplitude=0.8, noise_sigma=0.01)
    assert len(fig.axes) == 1  # no echo: no zoom panel
    np.testing.assert_allclose(fig.axes[0].get_ylim(), (-0.88, 0.88))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "sample noise ±σ (σ = 0.01)" in labels


def test_a_no_echo_ascan_draws_the_threshold_the_noise_stays_below_off_the_trace():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from echocal.signal.detection import EchoDetector

    p = GaborPulse()
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=1024)
    noise = np.random.default_rng(1).normal(0.0, 0.01, w.n_samples)
    fig = plot_ascan(noise, w, pulse=p, echo=False, expected_amplitude=0.8, noise_sigma=0.01)
    assert len(fig.axes) == 1  # no echo: no zoom panel, no time of flight
    ax = fig.axes[0]
    np.testing.assert_allclose(ax.get_ylim(), (-0.88, 0.88))  # the expected echo's scale
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert not [s for s in labels if s.startswith("τ")]
    threshold = next(ln for ln in ax.get_lines() if ln.get_label().startswith("detection"))
    want = EchoDetector(p, w.fs, w.n_samples).threshold_amplitude(0.01, 4.5)
    assert threshold.get_ydata()[0] == pytest.approx(want, rel=1e-9)
    # the legend says what g counts: the matched filter's σ, so the level is not g x the
    # samples' σ (here it is below it: filtering gains SNR), and the legend does not claim it
    assert want < 4.5 * 0.01
    assert "g = 4.5 matched-filter σ" in threshold.get_label()
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    box = ax.get_legend().get_window_extent(canvas.get_renderer())
    assert not box.overlaps(ax.get_window_extent(canvas.get_renderer()))  # beside the trace


def test_the_ascan_draws_the_detectors_threshold():
    from echocal.signal.detection import EchoDetector

    p = GaborPulse()
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=1024)
    rng = np.random.default_rng(3)
    x = synthesize([1.0], [24e-6], p, w, normalize="peak") + rng.normal(0.0, 0.02, w.n_samples)
    fig = plot_ascan(x, w, pulse=p, noise_sigma=0.02)
    want = EchoDetector(p, w.fs, w.n_samples).threshold_amplitude(0.02, 4.5)
    for ax in fig.axes:  # both panels: the whole window and the zoom
        lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("detection threshold")]
        assert len(lines) == 1
        assert lines[0].get_ydata()[0] == pytest.approx(want, rel=1e-9)
        assert 0.02 < want < 1.0  # above the noise σ, below the echo
    fig = plot_ascan(x, w, pulse=p, noise_sigma=0.0)  # no noise level: no threshold
    assert not [ln for ln in fig.axes[0].get_lines() if "threshold" in str(ln.get_label())]


def test_the_scenarios_overlay_draws_noise_threshold_and_distinct_styles():
    from echocal.experiments._ascan import ascan_overlay_figure
    from echocal.signal.detection import EchoDetector

    p = GaborPulse()
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=1024)
    rng = np.random.default_rng(4)
    rows = np.stack([synthesize([1.0], [t], p, w, normalize="peak") for t in (24e-6, 26e-6)])
    rows += rng.normal(0.0, 0.02, rows.shape)
    fig = ascan_overlay_figure(w.times, rows, ["a", "b"], [24e-6, 26e-6], title="t", pulse=p)
    full = fig.axes[0]
    labels = [t.get_text() for t in full.get_legend().get_texts()]
    assert labels[:2] == ["a", "b"] and any(s.startswith("sample noise ±σ") for s in labels)
    threshold = next(ln for ln in full.get_lines() if ln.get_label().startswith("detection"))
    sigma = float(labels[2].split("σ = ")[1].rstrip(")"))
    assert sigma == pytest.approx(0.02, rel=0.1)  # the MAD estimate of the noise drawn
    want = EchoDetector(p, w.fs, w.n_samples).threshold_amplitude(sigma, 4.5)
    assert threshold.get_ydata()[0] == pytest.approx(want, rel=1e-2)
    traces = [ln for ln in full.get_lines() if ln.get_label() in ("a", "b")]
    assert traces[0].get_linestyle() != traces[1].get_linestyle()  # not by colour alone
