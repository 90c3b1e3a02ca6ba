"""Time-of-flight surface fit against the simulator's truth over many seeds.

Usage: ``python benchmarks/tof_surface_fit.py [--seeds 200]``

For each part (a plate tilted 0.5° under the 3 mm probe of ``scan-5mhz``, the ``sphere``
and the ``cylinder`` under a 1 mm disc), one noiseless position scan is simulated (wave
model) and the receiver's 30 dB noise drawn once per seed; the fit's errors against the
truth and the fraction of runs whose truth lies inside 3 σ (and 1 σ) are printed, with
the CPU time.  The unit tests run 10 seeds of the same cases.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time

import numpy as np

from echocal.positionscan import fit_surface, receiver_noise, simulate_position_scan
from echocal.setups import load_setup
from echocal.specimen import FinitePlane, Specimen, builtin_specimen


def _cases() -> list[tuple[str, object, np.ndarray, np.ndarray, dict[str, float]]]:
    setup = load_setup("scan-5mhz")
    az, co = math.radians(30.0), math.radians(0.5)
    n = np.array([math.sin(co) * math.cos(az), math.sin(co) * math.sin(az), math.cos(co)])
    plate = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1, azimuth=30.0, coelevation=0.5)
    flat = dataclasses.replace(setup, specimen=Specimen([plate], name="plate 0.5 deg"))
    truth_plate = {
        "tilt_x": -math.degrees(math.asin(n[1])),
        "tilt_y": math.degrees(math.atan2(n[0], n[2])),
        "distance": n[2] * 0.025,
    }
    small = dataclasses.replace(setup.transducer, width=1e-3, height=1e-3)
    xs = np.linspace(-5e-3, 5e-3, 9)
    cs = np.linspace(-4e-3, 4e-3, 7)
    return [
        ("plane", flat, xs, xs, truth_plate),
        (
            "sphere",
            dataclasses.replace(setup, specimen=builtin_specimen("sphere"), transducer=small),
            cs + 0.4e-3,
            cs,
            {"radius": 0.025},
        ),
        (
            "cylinder",
            dataclasses.replace(setup, specimen=builtin_specimen("cylinder"), transducer=small),
            cs + 0.4e-3,
            cs,
            {"radius": 0.020},
        ),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=200)
    args = parser.parse_args()
    for shape, virtual, x, y, truth in _cases():
        start = time.process_time()
        ideal = simulate_position_scan(virtual, x=x, y=y, noise=False)
        simulated = time.process_time() - start
        errors: dict[str, list[float]] = {k: [] for k in truth}
        z: dict[str, list[float]] = {k: [] for k in truth}
        for seed in range(args.seeds):
            fit = fit_surface(receiver_noise(ideal, virtual, seed), shape)
            for key, value in truth.items():
                errors[key].append(fit.parameters[key] - value)
                z[key].append((fit.parameters[key] - value) / fit.sigma[key])
        fitted = time.process_time() - start - simulated
        print(
            f"{shape}: {x.size} x {y.size} traces, simulation {simulated:.1f} CPU-s, "
            f"{args.seeds} fits {fitted:.1f} CPU-s"
        )
        for key in truth:
            e, zz = np.array(errors[key]), np.abs(np.array(z[key]))
            unit, scale = ("deg", 1.0) if key.startswith("tilt") else ("um", 1e6)
            print(
                f"  {key:<9} mean error {e.mean() * scale:+.4f} {unit}, max |error| "
                f"{np.abs(e).max() * scale:.4f} {unit}, inside 1 sigma {np.mean(zz <= 1):.1%}, "
                f"inside 3 sigma {np.mean(zz <= 3):.1%}"
            )


if __name__ == "__main__":
    main()
