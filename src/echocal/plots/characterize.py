"""One page per probe: the orientation map with the fitted axis, the spectrum with its
−6 dB band, the beam widths and the on-axis echo against distance
(:mod:`echocal.characterize`)."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from echocal.characterize.probe import ProbeCharacterization

__all__ = ["plot_characterization"]


def plot_characterization(result: ProbeCharacterization) -> Figure:
    """Left: the echo [dB re its largest] at every tilt measured, the reflector's normal
    (the mechanical axis) and the fitted beam axis with its 1-σ ellipse's axes.  Right:
    the averaged echo's amplitude spectrum [dB] with f_l, f_c, f_u and the −6 dB level.
    Third, when measured: the −6 dB beam width [mm] per scanned axis against distance
    with 1-σ bars, and the on-axis echo against distance with the focal distance."""
    axis, spec = result.axis, result.spectrum
    extra = result.profile is not None or result.focus is not None
    fig = Figure(figsize=(16.0 if extra else 11.0, 4.6), layout="constrained")
    panels = fig.subplots(1, 3 if extra else 2)
    left, right = panels[0], panels[1]
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
    if extra:
        _plot_distances(result, panels[2])
    fig.suptitle(result.source, fontsize=9)
    return fig


def _plot_distances(result: ProbeCharacterization, ax: Axes) -> None:
    profile, focus = result.profile, result.focus
    if profile is not None:
        for k, name in enumerate(profile.axes):
            ax.errorbar(
                1e3 * profile.distances,
                1e3 * profile.width[:, k],
                yerr=1e3 * profile.width_sigma[:, k],
                fmt="o-",
                capsize=3,
                label=f"−6 dB width along {name}'",
            )
        ax.set_ylabel("−6 dB beam width [mm]")
        ax.legend(loc="upper left", fontsize=8)
    ax.set_xlabel("distance to the point target [mm]")
    if focus is not None:
        echo = ax.twinx() if profile is not None else ax
        echo.plot(1e3 * focus.distances, focus.amplitude / focus.amplitude.max(), "k.:")
        echo.set_ylabel("on-axis echo [re max]")
        if np.isfinite(focus.focal_distance):
            echo.axvline(1e3 * focus.focal_distance, color="C3", lw=1)
            ax.set_title(f"focal distance {1e3 * focus.focal_distance:.2f} mm")
