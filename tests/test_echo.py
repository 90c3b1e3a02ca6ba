"""echo_arrays (the simulator's fast ray stage) against ray_echoes, closed forms and chunking."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from echocal import MM, SOUND_SPEED_WATER, EchocalValueError
from echocal.echo import echo_arrays, ray_echoes
from echocal.geometry import orientation_frame
from echocal.specimen import builtin_specimen
from echocal.transducer import Transducer

PROBE = Transducer(width=10 * MM, height=10 * MM, n_h=16, n_v=16, pinhole_distance=20 * MM)


def poses(n: int, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """n poses 15-25 mm above the plate, tilted up to 10°, as (n, 3) and (n, 3, 3) arrays."""
    rng = np.random.default_rng(seed)
    positions = np.column_stack(
        [rng.uniform(-3, 3, n) * MM, rng.uniform(-3, 3, n) * MM, rng.uniform(15, 25, n) * MM]
    )
    return positions, orientation_frame(rng.uniform(-180, 180, n), rng.uniform(0, 10, n))


@pytest.mark.parametrize("model", ["lambertian", "specular"])
@pytest.mark.parametrize("specimen", ["flat-plate", "sphere", "thesis-block"])
def test_echo_arrays_matches_ray_echoes(model, specimen):
    positions, frames = poses(5)
    shape = builtin_specimen(specimen)
    amp, tof = echo_arrays(PROBE, shape, positions, frames, model=model)
    full = ray_echoes(PROBE, shape, positions, frames, model=model)
    # Same arithmetic on the same rays: bit-for-bit, including inf for the misses.
    assert_array_equal(amp, full.amplitude)
    assert_array_equal(tof, full.tof)
    assert np.any(amp > 0)  # the comparison is not between two empty results


def test_flat_plate_closed_form():
    """Lambertian echo off z = 0 from height h: τ = 2h/(c·|d_z|), amplitude = weight·|d_z|."""
    positions, frames = poses(4)
    amp, tof = echo_arrays(PROBE, builtin_specimen("flat-plate"), positions, frames)
    rays = PROBE.rays(positions, frames)
    dz = -rays.directions[..., 2]
    t = rays.origins[..., 2] / dz
    # rtol 1e-12: a few roundings of O(1) quantities (the casting solves the same plane).
    assert_allclose(tof, 2.0 * t / SOUND_SPEED_WATER, rtol=1e-12)
    assert_allclose(amp, PROBE.weights * dz, rtol=1e-12)


@pytest.mark.parametrize("model", ["lambertian", "specular"])
def test_results_do_not_depend_on_chunking(model):
    """9 poses × 64² rays span several 16k-ray chunks; each pose alone is one chunk."""
    probe = Transducer(width=10 * MM, height=10 * MM, n_h=64, n_v=64, pinhole_distance=20 * MM)
    positions, frames = poses(9, seed=11)
    shape = builtin_specimen("sphere")
    amp, tof = echo_arrays(probe, shape, positions, frames, model=model)
    for i in range(9):
        a1, t1 = echo_arrays(probe, shape, positions[i : i + 1], frames[i : i + 1], model=model)
        assert_array_equal(a1[0], amp[i])
        assert_array_equal(t1[0], tof[i])


def test_skewed_frame_directions_are_normalised():
    """A frame with a scaled and sheared normal column: the rays' directions are the frame's
    images of the local directions, normalised to unit length (as cast() does)."""
    positions = np.array([[0.5 * MM, -0.3 * MM, 20 * MM]])
    frame = orientation_frame(0.0, 0.0)[None].copy()
    frame[0, :, 2] = 2.5 * frame[0, :, 2] + 0.2 * frame[0, :, 0]  # n scaled and sheared
    amp, tof = echo_arrays(PROBE, builtin_specimen("flat-plate"), positions, frame)
    raw = PROBE.rays(positions, frame)  # origins and unnormalised directions
    d = raw.directions / np.linalg.norm(raw.directions, axis=-1, keepdims=True)
    dz = -d[..., 2]
    assert_allclose(tof, 2.0 * raw.origins[..., 2] / dz / SOUND_SPEED_WATER, rtol=1e-12)
    assert_allclose(amp, PROBE.weights * dz, rtol=1e-12)
    # and differently from the orthonormal frame (the test would pass vacuously otherwise)
    upright = orientation_frame(0.0, 0.0)[None]
    _, tof0 = echo_arrays(PROBE, builtin_specimen("flat-plate"), positions, upright)
    assert np.max(np.abs(tof - tof0)) > 1e-9


def test_degenerate_frame_is_rejected():
    positions = np.array([[0.0, 0.0, 20 * MM]])
    with pytest.raises(EchocalValueError, match="zero vector"):
        echo_arrays(PROBE, builtin_specimen("flat-plate"), positions, np.zeros((1, 3, 3)))


def test_bad_inputs_name_the_field():
    positions, frames = poses(2)
    plate = builtin_specimen("flat-plate")
    with pytest.raises(EchocalValueError, match="same number of poses"):
        echo_arrays(PROBE, plate, positions, frames[:1])
    with pytest.raises(EchocalValueError, match="positions"):
        echo_arrays(PROBE, plate, np.full((2, 3), np.nan), frames)
    with pytest.raises(KeyError, match="lambertian, specular"):
        echo_arrays(PROBE, plate, positions, frames, model="mirror")
