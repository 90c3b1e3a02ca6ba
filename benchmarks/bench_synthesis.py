"""Time A-scan synthesis (not a test): fast (NUFFT) vs direct, and how fast scales.

Run: ``python benchmarks/bench_synthesis.py``.  Prints median wall times on one core of
``synthesize`` alone (no ray tracing): 5 MHz Gabor, 60 % bandwidth, fs = 100 MHz, τ spread
over ~30 µs, pseudo-energy timed separately.
"""

from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

from echocal.signal import (
    GaborPulse,
    RecordingWindow,
    pseudo_energy,
    synthesize,
)


def median_time(fn, repeat: int) -> float:
    fn()  # warm caches (the plan: kernel transform × pulse spectrum)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def setup(n_rays: int, n_samples: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    window = RecordingWindow(fs=100e6, start=20e-6, n_samples=n_samples)
    tau = rng.uniform(
        window.start + 0.1 * window.duration, window.end - 0.1 * window.duration, n_rays
    )
    return rng.uniform(0.2, 1.0, n_rays), tau, window


def main() -> None:
    pulse = GaborPulse(center_frequency=5e6, bandwidth=60.0)
    a, tau, w = setup(4096, 4096)
    fast = median_time(lambda: synthesize(a, tau, pulse, w), 200)
    direct = median_time(lambda: synthesize(a, tau, pulse, w, method="direct"), 3)
    x = synthesize(a, tau, pulse, w)
    energy = median_time(lambda: pseudo_energy(x, w, pulse), 200)
    err = np.linalg.norm(x - synthesize(a, tau, pulse, w, method="direct")) / np.linalg.norm(x)
    print("defaults: 4096 rays (64×64), 4096 samples, 5 MHz Gabor 60 %, fs 100 MHz")
    print(f"  direct            {direct * 1e3:10.2f} ms")
    print(f"  fast              {fast * 1e3:10.3f} ms")
    print(f"  ratio             {direct / fast:10.0f} ×")
    print(f"  relative L2 error {err:10.1e}")
    print(f"  pseudo-energy     {energy * 1e3:10.3f} ms")
    print("\nfast path vs rays (4096 samples):")
    for side in (16, 32, 64, 128, 256):
        a, tau, w = setup(side * side, 4096)
        t = median_time(lambda a=a, tau=tau, w=w: synthesize(a, tau, pulse, w), 50)
        print(f"  {side:4d}² = {side * side:6d} rays  {t * 1e3:8.3f} ms")
    print("\nfast path vs samples (4096 rays):")
    for n in (1024, 4096, 16384, 65536):
        a, tau, w = setup(4096, n)
        t = median_time(lambda a=a, tau=tau, w=w: synthesize(a, tau, pulse, w), 50)
        print(f"  {n:6d} samples  {t * 1e3:8.3f} ms")
    print("\nbatch of 64 poses × 4096 rays × 4096 samples:")
    rng = np.random.default_rng(1)
    a = rng.uniform(0.2, 1.0, (64, 4096))
    tau = rng.uniform(25e-6, 55e-6, (64, 4096))
    w = RecordingWindow(fs=100e6, start=20e-6, n_samples=4096)
    t = median_time(lambda: synthesize(a, tau, pulse, w), 5)
    print(f"  {t * 1e3:8.2f} ms total, {t / 64 * 1e3:.3f} ms per A-scan")


if __name__ == "__main__":
    main()
