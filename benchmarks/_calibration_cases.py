"""The calibration benchmark's cases, starts, SNRs, methods and targets (data only),
shared by :mod:`bench_calibration` and its report (:mod:`_calibration_report`)."""

from __future__ import annotations

from typing import Any

BUDGET = 80
FIXED_BUDGETS = (15, 20, 25, 40, 60, 80)
TOLERANCES = (0.05, 0.1)
PARAM = "tilt"

CASES: dict[str, dict[str, Any]] = {
    "immersion-5mhz": {
        "setup": "immersion-5mhz",
        "position": None,
        "lobe": "narrow (~1°), diffraction tails (the wave model)",
    },
    "immersion-5mhz-ray": {
        "setup": "immersion-5mhz-ray",
        "position": None,
        "lobe": "narrow (~1°), the ray model",
    },
    "thesis": {"setup": "thesis", "position": (0.010, 0.0, 0.022), "lobe": "broad (~±8°)"},
    # curved parts, probe 4 mm across / 2 mm along off the axis of the part (issue 19)
    "sphere-12.7": {
        "setup": "immersion-5mhz",
        "specimen": "sphere",
        "position": (0.004, 0.002, 0.05),
        "lobe": "ball r 25 mm, 12.7 mm probe: central peak, dip, near-field ring (wave)",
    },
    "sphere-6.35": {
        "setup": "immersion-5mhz",
        "specimen": "sphere",
        "probe_width": 0.00635,
        "position": (0.004, 0.002, 0.05),
        "lobe": "ball r 25 mm, 6.35 mm probe: one broad lobe (wave)",
    },
    "rod-12.7": {
        "setup": "immersion-5mhz",
        "specimen": "cylinder",
        "position": (0.004, 0.002, 0.05),
        "lobe": "rod r 20 mm, 12.7 mm probe: two equal humps across the rod (wave)",
    },
    "rod-6.35": {
        "setup": "immersion-5mhz",
        "specimen": "cylinder",
        "probe_width": 0.00635,
        "position": (0.004, 0.002, 0.05),
        "lobe": "rod r 20 mm, 6.35 mm probe: anisotropic lobe (wave)",
    },
    # the back-wall echo through the interface-triggered gate, as a flaw detector (issue 19)
    "plate-back-wall": {
        "setup": "immersion-steel-plate",
        "gate": "back-wall",
        "position": None,
        "lobe": "20 mm steel plate's back wall in its triggered gate, 12.7 mm probe (wave)",
    },
}
REAL_BENCH: dict[str, Any] = {
    "probe": {"squint": (1.5, -1.0), "pivot_offset": (0.002, -0.001, -0.004)},
    "positioner": {
        "acquisition_time": 0.005,
        "approach": "positive",
        **{
            axis: {"backlash": 0.05, "step": 0.001, "repeatability": 0.002, "speed": 10.0,
                   "settling": 0.05}
            for axis in ("tilt_x", "tilt_y")
        },
    },
    "receiver": {"noise_ar": [0.6]},
}  # fmt: skip
"""A realistic bench (the ``[bench]`` table as data; issue 47): squint 1.8°, pivot offset
4.6 mm, 0.05° backlash, 0.001° steps, 0.002° repeatability, 10°/s and 50 ms settling per
tilt axis, 5 ms per A-scan, AR(1) noise of coefficient 0.6; the controller compensates
the backlash (``approach = "positive"``: every point approached from below, at 4 × the
backlash of extra travel on a move down), as benches do."""
GRAIN_BENCH: dict[str, Any] = {
    **REAL_BENCH,
    "grain": {"level_db": -30.0, "depth": 0.005, "width": 0.02},
}
""":data:`REAL_BENCH` with grains at −30 dB re the front-wall echo, 5 mm deep under 20 mm
around the reference: their backscatter reaches the probe at any tilt (no gate)."""
CASES["immersion-5mhz-ray-bench"] = {
    "setup": "immersion-5mhz-ray",
    "bench": REAL_BENCH,
    "position": None,
    "lobe": "narrow (~1°), the ray model, on a real bench (squint, pivot, backlash, AR, grain)",
}
CASES["thesis-bench"] = {
    "setup": "thesis",
    "bench": REAL_BENCH,
    "position": (0.010, 0.0, 0.022),
    "lobe": "broad (~±8°), on a real bench",
}
CASES["immersion-5mhz-ray-grain"] = {
    "setup": "immersion-5mhz-ray",
    "bench": GRAIN_BENCH,
    "position": None,
    "lobe": "narrow (~1°), the ray model, on the real bench with grain noise at -30 dB",
}
BENCH_CASES = ("immersion-5mhz-ray-bench", "thesis-bench", "immersion-5mhz-ray-grain")
"""Cases on :data:`REAL_BENCH`; ``--cases`` only.  Their runs also report the bench time."""
CURVED_CASES = ("sphere-12.7", "sphere-6.35", "rod-12.7", "rod-6.35")
"""Selectable with ``--cases``; not in a default run (each costs minutes)."""
GATED_CASES = ("plate-back-wall",)
"""Cases whose metric is read in a gate (the ``gate`` of the case); ``--cases`` only."""
TWIN_RATIO = 0.98
"""A second maximum within this fraction of the first counts as the optimum too."""
DEFAULT_CASES = ("immersion-5mhz", "immersion-5mhz-ray", "thesis")
"""The cases of a run without ``--cases``: the same rig on both physics models, and the
thesis's block."""
STARTS: dict[str, tuple[float, float]] = {"near": (1.0, 3.0), "far": (5.0, 20.0)}
SNRS = (30.0, 20.0, 10.0)

MOTION_AWARE = "auto-motion-aware"
"""``auto`` on a motion-aware objective (``SourceObjective(motion_aware=True)``): its
batches measured along short paths, and its posterior search told each candidate's move
time (on a bench whose tilts take time; elsewhere it is ``auto``)."""
FRONT_FIRST = "auto-front-first"
"""A workflow, not a method, for a gated case: ``auto`` on the whole recording (the
interface echo, which keeps the gate's trigger) until it settles (the CLI's default
0.01°, 8), then ``auto`` in the case's gate from that estimate, on one budget."""
SETTLE = (0.01, 8)

OURS: dict[str, dict[str, Any]] = {
    "auto": {},
    "model-based": {},
    "newton": {},
    "quasi-newton": {},
    "spsa": {},
    "gradient": {},
    "momentum": {},
    "nesterov": {},
}


AUTO_TARGETS: dict[str, tuple[tuple[str, float, float, int, float], ...]] = {
    "immersion-5mhz": (
        ("near", 30.0, 0.05, 15, 0.99),
        ("near", 10.0, 0.1, 40, 0.99),
        ("far", 30.0, 0.1, 60, 0.99),
    ),
    "immersion-5mhz-ray": (
        ("near", 30.0, 0.05, 20, 0.99),
        ("near", 10.0, 0.1, 60, 0.95),
        ("far", 30.0, 0.1, 60, 0.99),
    ),
}
AUTO_TARGETS["immersion-5mhz-ray-bench"] = (
    ("near", 20.0, 0.1, 25, 0.99),
    ("far", 30.0, 0.1, 80, 0.99),
)
"""Targets for auto per case: (start, SNR [dB], tolerance [deg], measurements, fraction of
runs) — issue 19's on the wave model (``immersion-5mhz``), issue 5's on the ray model,
issue 47's on the real bench (``immersion-5mhz-ray-bench``)."""
