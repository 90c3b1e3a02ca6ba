"""
Gates on a steel plate: the back-wall gate follows the front wall
=================================================================

A flaw detector measures an echo inside a gate. On the 20 mm steel plate of
``immersion-steel-plate`` the ``front-wall`` gate sits around the first strong echo and
the ``back-wall`` gate 2T/c_L = 6.78 µs later, both triggered by the front wall's threshold
crossing (the interface trigger). Move the probe up by 10 mm: the water path grows, the
whole echo train arrives 13.5 µs later, and the gates move with it. See docs/gates.md.
"""

# %%
# The two gates, resolved for this setup (its pulse, thickness and material).
from echocal import Pose, load_setup
from echocal.plots import plot_ascan
from echocal.signal.gates import gated_metric, resolve_gate

setup = load_setup("immersion-steel-plate", seed=1)
gates = [
    resolve_gate(name, pulse=setup.pulse, thickness=setup.thickness, material=setup.material)
    for name in ("front-wall", "back-wall")
]
for gate in gates:
    print(gate.label())

# %%
# At 50 mm water path: the gates are shaded, the interface trigger is the triangle on the
# time axis.  The back-wall echo's envelope peak inside its gate is the labelled echo's.
for water_path in (0.050, 0.060):
    pose = Pose(0.0, 0.0, water_path, 0.0, 0.0)
    scan = setup.measure(pose)
    fig = plot_ascan(
        scan.samples,
        setup.window,
        pulse=setup.pulse,
        gates=gates,
        title=f"20 mm steel plate, {water_path * 1e3:g} mm water path",
    )
    back = gated_metric("peak-amplitude", scan.samples, setup.window, setup.pulse, gates[1])
    alone = gated_metric(
        "peak-amplitude", setup.labelled_echoes(pose)["back-wall"], setup.window, setup.pulse
    )
    starts = [float(g.starts(scan.samples, setup.window)) * 1e6 for g in gates]
    print(
        f"{water_path * 1e3:g} mm: gates start at {starts[0]:.2f} and {starts[1]:.2f} µs; "
        f"back wall in its gate {float(back):.4f} at 30 dB SNR "
        f"(noiseless, alone: {float(alone):.4f})"
    )
