"""One page per probe: the orientation map with the fitted axis, the spectrum with its
−6 dB band (:mod:`echocal.characterize`)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from echocal.characterize.probe import ProbeCharacterization

__all__ = ["plot_characterization"]


def plot_characterization(result: ProbeCharacterization) -> Figure:
    """Left: the echo [dB re its largest] at every tilt measured, the reflector's normal
    (the mechanical axis) and the fitted beam axis with its 1-σ ellipse's axes.  Right:
    the averaged echo's amplitude spectrum [dB] with f_l, f_c, f_u and the −6 dB level."""
    axis, spec = result.axis, result.spectrum
    fig = Figure(figsize=(11.0, 4.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    db = 20.0 * np.log10(np.maximum(axis.amplitude / axis.amplitude.max(), 1e-3))
    dots = left.scatter(axis.grid_deg[:, 0], axis.grid_deg[:, 1], c=db, s=14, cmap="viridis")
    fig.colorbar(dots, ax=left, label="echo [dB re max]")
    left.plot(*axis.reflector_tilts_deg, "k+", ms=12, label="mechanical axis (reflector normal)")
    left.errorbar(
        *axis.tilts_deg,
        xerr=axis.tilts_sigma_deg[0],
        yerr=axis.tilts_sigma_deg[1],
        fmt="rx",
        ms=10,
        label="beam axis (fit)",
    )
    sx, sy = axis.squint_deg
    left.set_title(f"beam axis: squint ({sx:.3f}°, {sy:.3f}°)")
    left.set_xlabel("tilt_x [deg]")
    left.set_ylabel("tilt_y [deg]")
    left.set_aspect("equal")
    left.legend(loc="lower left", fontsize=8)
    mhz = spec.freqs / 1e6
    keep = mhz <= 3.0 * spec.upper_hz / 1e6
    right.plot(mhz[keep], 20 * np.log10(np.maximum(spec.amplitude[keep], 1e-4)), "C0")
    right.axhline(-6.02, color="0.5", ls="--", lw=0.8)
    for f, style in ((spec.lower_hz, ":"), (spec.center_hz, "-"), (spec.upper_hz, ":")):
        right.axvline(f / 1e6, color="C3", ls=style, lw=1)
    right.set_ylim(-40, 3)
    right.set_xlabel("frequency [MHz]")
    right.set_ylabel("amplitude [dB re peak]")
    right.set_title(
        f"f_c = {spec.center_hz / 1e6:.3f} MHz, −6 dB band {spec.bandwidth_hz / 1e6:.3f} MHz "
        f"({100 * spec.relative_bandwidth:.1f} %)"
    )
    fig.suptitle(result.source, fontsize=9)
    return fig
