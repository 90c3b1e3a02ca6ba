"""
An A-scan of a setup
====================

Simulate the A-scan that the thesis's probe records over the thesis block, once at the
orientation of maximum echo and once 6° away from it, and read the time of flight and
pseudo-energy of each.
"""

# %%
# The thesis setup: a 4 mm square probe with 32 × 32 rays, a 1 MHz Gabor pulse, the
# Lambertian reflection of the thesis, 30 dB SNR.
from echocal import Pose, load_setup, pseudo_energy, time_of_flight
from echocal.constants import SOUND_SPEED_WATER

setup = load_setup("thesis", seed=1)
x, y, z = setup.reference_position
azimuth, coelevation = setup.true_optimum(setup.reference_position)
print(f"probe at ({x * 1e3:g}, {y * 1e3:g}, {z * 1e3:g}) mm")
print(f"orientation of maximum echo: azimuth {azimuth:.2f}°, co-elevation {coelevation:.2f}°")

# %%
# Measure at the optimum and 6° off it. ``measure`` returns an :class:`~echocal.ascan.AScan`
# with its time axis, samples and the pose reached.
best = setup.measure(Pose(x, y, z, azimuth, coelevation))
off = setup.measure(Pose(x, y, z, azimuth, coelevation + 6.0))
for name, scan in (("optimum", best), ("6° off", off)):
    tof = float(time_of_flight(scan.samples, setup.window, setup.pulse))
    energy = float(pseudo_energy(scan.samples, setup.window, setup.pulse))
    print(
        f"{name:8s} time of flight {tof * 1e6:.3f} µs "
        f"(distance {tof * SOUND_SPEED_WATER / 2 * 1e3:.2f} mm), pseudo-energy {energy:.3g}"
    )

# %%
# The A-scan at the optimum: raw samples, envelope and the time of flight.
from echocal.plots.ascan import plot_ascan

fig = plot_ascan(best.samples, setup.window, pulse=setup.pulse, title="at the optimum")
print(
    f"{best.samples.size} samples at {setup.window.fs / 1e6:g} MHz: "
    f"{best.samples.size / setup.window.fs * 1e6:.1f} µs recorded"
)
