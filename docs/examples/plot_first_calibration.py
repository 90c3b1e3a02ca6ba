"""
Your first calibration
======================

Find the orientation of maximum echo of a simulated 5 MHz immersion probe over a tilted
plate, from noisy measurements, with echocal's default method ``auto``.

The calibration never sees the simulator's truth: it only asks for A-scans at poses
through a :class:`~echocal.measurement.SourceObjective`. Afterwards,
:func:`~echocal.evaluation.evaluate_run` judges the estimate against the simulator's true
optimum.
"""

# %%
# The setup: a built-in simulator (a :class:`~echocal.measurement.VirtualSetup`) — 12.7 mm probe,
# 50 mm water path, a plate whose normal points to (azimuth 30°, co-elevation 4°), and
# receiver noise at 30 dB SNR. ``seed`` makes the noise reproducible.
from echocal import SourceObjective, evaluate_run, load_setup
from echocal.calibrate import calibrate

setup = load_setup("immersion-5mhz", seed=0)
print(setup.description)

# %%
# The objective measures the pseudo-energy of the echo (thesis eq. 79) at an
# orientation, here in the pole-free gimbal tilts (degrees), and counts every
# measurement.
objective = SourceObjective(setup, setup.reference_position, parameterization="tilt")
result = calibrate(objective, method="auto", x0=(0.0, 0.0), rng=0, settle=(0.01, 8))
print(f"estimate (tilt x, tilt y) = ({result.x[0]:.3f}°, {result.x[1]:.3f}°)")
print(f"{result.n_measurements} measurements; stopped because: {result.message}")

# %%
# Judge it against the simulator's truth (only possible on a simulator).
evaluation = evaluate_run(setup, setup.reference_position, result)
print(f"true optimum ({evaluation.truth[0]:.3f}°, {evaluation.truth[1]:.3f}°)")
print(f"angular error of the estimate: {evaluation.error:.4f}°")

# %%
# How the estimate's (noiseless) pseudo-energy rose, per iteration and per measurement.
from echocal.plots.calibration import convergence_figure

fig = convergence_figure(
    {"auto": result},
    {"auto": evaluation.iterate_values / evaluation.optimum_value},
    optimum_value=1.0,
    title="auto: pseudo-energy of the estimate",
)
