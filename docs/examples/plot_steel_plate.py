"""
Inside a steel plate: front wall, back wall, multiples and a side-drilled hole
==============================================================================

Simulate the echo train of a 20 mm steel plate under a 12.7 mm 5 MHz probe at 50 mm water
path (the built-in ``immersion-steel-sdh``: the plate of ``immersion-steel-plate`` with a
2 mm side-drilled hole 10 mm deep), label every echo, and see how the front-wall and
back-wall echoes fall off as the probe tilts.
"""

# %%
# Every echo of the train, noiseless, with its label, time of flight and amplitude (the
# envelope peak). The same list is ``echoes`` in ``echocal simulate --json``.
import matplotlib.pyplot as plt
import numpy as np
import scipy.signal

from echocal import Pose, load_setup
from echocal.wave.interior import echo_list

setup = load_setup("immersion-steel-sdh", seed=1)
pose = Pose(0.0, 0.0, 0.05, 0.0, 0.0)  # 50 mm above the plate, beam straight down
echoes = setup.labelled_echoes(pose)
for echo in echo_list(echoes, setup.window):
    print(f"{echo.label:12s} {echo.tof_s * 1e6:7.2f} µs   amplitude {echo.amplitude:.4f}")

# %%
# The A-scan as recorded (30 dB SNR on the front wall), each echo labelled.
scan = setup.measure(pose)
t_us = 1e6 * (setup.window.start + np.arange(setup.window.n_samples) / setup.window.fs)
fig, ax = plt.subplots(figsize=(9, 3.5))
ax.plot(t_us, scan.samples, lw=0.6, color="0.3", label="A-scan (30 dB SNR)")
for echo in echo_list(echoes, setup.window):
    ax.annotate(
        echo.label,
        (echo.tof_s * 1e6, echo.amplitude),
        xytext=(0, 8),
        textcoords="offset points",
        ha="center",
        fontsize=8,
    )
ax.set_xlim(64, 90)
low, high = ax.get_ylim()
ax.set_ylim(low, 1.25 * high)  # room for the front wall's label below the title
ax.set_xlabel("time [µs]")
ax.set_ylabel("amplitude [a.u.]")
ax.set_title("20 mm steel plate with a 2 mm side-drilled hole, 50 mm water path")
ax.legend(loc="upper right")
fig.tight_layout()

# %%
# Tilt the probe: the back-wall echo's lobe is that of a mirror at the *equivalent water
# path* d + T·c_L/c_w = 50 + 80 mm, slightly wider than the front wall's at 50 mm, and
# both are far narrower than a degree.
tilts = np.linspace(0.0, 1.5, 13)
peaks = {"front-wall": [], "back-wall": []}
for tilt in tilts:
    labelled = setup.labelled_echoes(Pose.from_tilt(0.0, 0.0, 0.05, float(tilt), 0.0))
    for label in peaks:
        peaks[label].append(np.abs(scipy.signal.hilbert(labelled[label])).max())
fig, ax = plt.subplots(figsize=(6, 3.5))
for (label, values), style in zip(peaks.items(), ("-", "--"), strict=True):
    values = np.asarray(values)
    ax.plot(tilts, 20 * np.log10(values / values[0]), style, marker="o", ms=3, label=label)
ax.axhline(-6, color="0.6", lw=0.8, ls=":")
ax.set_xlabel("tilt [deg]")
ax.set_ylabel("echo relative to normal incidence [dB]")
ax.set_ylim(-30, 1)
ax.legend()
fig.tight_layout()
