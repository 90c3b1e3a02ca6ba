"""Compiled (numba) kernels of the simulator against their numpy fallbacks.

The fused lambertian ray kernel (``echocal.echo._lambertian_loops``) and the compiled
pseudo-energy window (``echocal.signal.processing._peak_window_loops``) must give what the
numpy path gives.  Tolerance 1e-12 relative: the two paths do the same arithmetic in a
different order (a BLAS matrix product vs. scalar sums), so they differ by a few ulps of
the ray coordinates; hit/miss decisions only flip for rays exactly on an edge, which these
random poses do not produce (asserted by the exact equality of the miss masks).
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from echocal import MM, EchocalValueError
from echocal import _numba as N
from echocal.echo import _kernel_table, echo_arrays
from echocal.geometry import orientation_frame
from echocal.signal import GaborPulse, RecordingWindow, pseudo_energy
from echocal.specimen import Cylinder, FinitePlane, Specimen, Sphere, builtin_specimen
from echocal.transducer import Transducer

pytestmark = pytest.mark.skipif(not N.HAVE_NUMBA, reason="numba not installed")

PROBE = Transducer(width=10 * MM, height=10 * MM, n_h=24, n_v=20, pinhole_distance=20 * MM)


def poses(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    positions = np.column_stack(
        [rng.uniform(-8, 8, n) * MM, rng.uniform(-8, 8, n) * MM, rng.uniform(10, 30, n) * MM]
    )
    return positions, orientation_frame(rng.uniform(-180, 180, n), rng.uniform(0, 40, n))


def both_paths(monkeypatch, specimen, positions, frames):
    fused = echo_arrays(PROBE, specimen, positions, frames)
    monkeypatch.setattr(N, "USE_NUMBA", False)
    numpy = echo_arrays(PROBE, specimen, positions, frames)
    monkeypatch.setattr(N, "USE_NUMBA", True)
    return fused, numpy


MIXED = Specimen(
    [
        FinitePlane(center=(0, 0, 0), width=12 * MM, height=9 * MM, azimuth=30, coelevation=8),
        Sphere(center=(4 * MM, -3 * MM, 2 * MM), radius=3 * MM),
        FinitePlane(center=(0, 0, -2 * MM), width=60 * MM, height=60 * MM),
    ],
    name="mixed",
)


@pytest.mark.parametrize(
    "specimen", [builtin_specimen("flat-plate"), MIXED], ids=["plate", "mixed"]
)
def test_fused_kernel_matches_numpy_path(monkeypatch, specimen):
    positions, frames = poses(7, seed=5)
    (amp, tof), (amp_np, tof_np) = both_paths(monkeypatch, specimen, positions, frames)
    assert_array_equal(np.isinf(tof), np.isinf(tof_np))  # same rays miss
    assert np.any(amp > 0)  # the comparison is not between two empty results
    if specimen is MIXED:  # small shapes: misses and shape-to-shape switches are exercised
        assert np.any(np.isinf(tof))
    assert_allclose(amp, amp_np, rtol=1e-12, atol=1e-15)
    assert_allclose(tof, tof_np, rtol=1e-12)


def test_fused_kernel_sphere_from_inside_and_outside(monkeypatch):
    ball = Specimen([Sphere(center=(0, 0, 0), radius=20 * MM)], name="ball")
    positions, frames = poses(4, seed=6)
    positions[:2] *= 0.2  # two poses inside the ball: rays hit its far side
    (amp, tof), (amp_np, tof_np) = both_paths(monkeypatch, ball, positions, frames)
    assert_array_equal(np.isinf(tof), np.isinf(tof_np))
    assert_allclose(amp, amp_np, rtol=1e-12, atol=1e-15)
    assert_allclose(tof, tof_np, rtol=1e-12)


def test_fused_kernel_normalizes_sheared_frames(monkeypatch):
    positions, frames = poses(3, seed=7)
    frames = frames * np.array([1.3, 0.8, 1.1])  # scaled columns: not orthonormal
    specimen = builtin_specimen("flat-plate")
    (amp, tof), (amp_np, tof_np) = both_paths(monkeypatch, specimen, positions, frames)
    assert_allclose(amp, amp_np, rtol=1e-12, atol=1e-15)
    assert_allclose(tof, tof_np, rtol=1e-12)


def test_fused_kernel_rejects_a_zero_direction():
    positions, _ = poses(1, seed=8)
    with pytest.raises(EchocalValueError, match="zero vector"):
        echo_arrays(PROBE, builtin_specimen("flat-plate"), positions, np.zeros((1, 3, 3)))


def test_shapes_without_kernel_take_the_generic_path():
    rod = Cylinder(center=(0, 0, 0), radius=5 * MM, length=40 * MM, azimuth=0, coelevation=90)
    plate = FinitePlane(center=(0, 0, 0), width=10 * MM, height=10 * MM)
    assert _kernel_table((plate, rod)) is None
    assert _kernel_table((plate,)) is not None


def test_specimens_without_kernel_are_not_kept_alive_by_the_table_cache():
    # The table cache holds its keys; a mesh (or any generic-path) specimen must not be one
    # of them, or each mesh simulated would stay in memory for the life of the process.
    import gc
    import weakref

    from echocal.specimen import TriangleMesh

    mesh = TriangleMesh(
        [[-0.02, -0.02, 0.0], [0.02, -0.02, 0.0], [0.0, 0.02, 0.0]], [[0, 1, 2]], engine="numpy"
    )
    gone = weakref.ref(mesh)
    positions, frames = poses(2, seed=5)
    echo_arrays(PROBE, Specimen([mesh]), positions, frames)
    del mesh
    gc.collect()
    assert gone() is None


def test_compiled_pseudo_energy_matches_numpy(monkeypatch):
    pulse = GaborPulse(center_frequency=5e6, bandwidth=60.0)
    window = RecordingWindow(fs=100e6, start=20e-6, n_samples=2048)
    rng = np.random.default_rng(9)
    t = window.times
    x = pulse.waveform(t[None, :] - rng.uniform(21e-6, 39e-6, (5, 1)))
    x += 0.05 * rng.standard_normal(x.shape)
    x[0] = 0.0  # silence: the window starts at sample 0, as argmax of zeros does
    compiled = pseudo_energy(x, window, pulse)
    monkeypatch.setattr(N, "USE_NUMBA", False)
    fallback = pseudo_energy(x, window, pulse)
    # same window (same argmax), sums of a few dozen squares in another order: 1e-13
    assert_allclose(compiled, fallback, rtol=1e-13, atol=0.0)
    assert compiled[0] == 0.0
