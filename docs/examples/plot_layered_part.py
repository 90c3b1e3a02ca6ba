"""
A layered part: acrylic on aluminium, echo by echo
==================================================

The built-in ``immersion-layered``: 30 mm of acrylic bonded on 50 mm of aluminium, two
flat-bottom holes in the aluminium, a 6 mm 2.25 MHz probe at 50 mm water path.  Every echo
of the train is a path through the layers (which interfaces it turns at), listed with its
time and amplitude; the A-scan's envelope, in dB, is labelled echo by echo.
"""

# %%
# Every echo, noiseless: its label (``interface-K`` the primary echo of interface K,
# ``interface-2.1.2`` the one that rang once in layer 2, ``interface-1.0.1`` once in the
# acrylic under the front face), time and amplitude.  The same list, with each path's
# layers and wave modes, is ``echoes`` in ``echocal simulate --json``.
import matplotlib.pyplot as plt
import numpy as np
import scipy.signal

from echocal import Pose, load_setup
from echocal.wave.interior import echo_list

setup = load_setup("immersion-layered")
pose = Pose(0.0, 0.0, 0.05, 0.0, 0.0)  # 50 mm above the part, beam straight down
echoes = setup.labelled_echoes(pose)
listed = [e for e in echo_list(echoes, setup.window) if e.amplitude > 1e-6]
for echo in listed:
    print(f"{echo.label:16s} {echo.tof_s * 1e6:7.2f} µs   amplitude {echo.amplitude:.2e}")

# %%
# The noiseless A-scan's envelope in dB of the front wall, each echo labelled at its
# peak: the acrylic takes 17 dB on its 60 mm round trip at 2.25 MHz, the bond line
# (interface 1) returns 59 % of what reaches it, the holes sit between it and the back wall.
scan = sum(echoes.values())
t_us = 1e6 * (setup.window.start + np.arange(setup.window.n_samples) / setup.window.fs)
envelope = np.abs(scipy.signal.hilbert(scan))
top = envelope.max()
fig, ax = plt.subplots(figsize=(9, 3.8))
ax.plot(t_us, 20 * np.log10(np.maximum(envelope / top, 1e-5)), lw=0.8, color="0.3")
for i, echo in enumerate(sorted(listed, key=lambda e: e.tof_s)):
    level = 20 * np.log10(echo.amplitude / top)
    ax.annotate(
        echo.label,
        (echo.tof_s * 1e6, level),
        xytext=(0, 10 + 12 * (i % 2)),
        textcoords="offset points",
        ha="center",
        fontsize=8,
        arrowprops={"arrowstyle": "-", "lw": 0.5, "color": "0.5"},
    )
ax.set_ylim(-90, 15)
ax.set_xlabel("time [µs]")
ax.set_ylabel("envelope [dB of the peak]")
ax.set_title("water / acrylic 30 mm / aluminium 50 mm, two flat-bottom holes, 2.25 MHz")
fig.tight_layout()
