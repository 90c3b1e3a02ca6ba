"""Position scans on the simulator: the same file kind as an imported scan.

:func:`simulate_position_scan` moves the probe of a :class:`~echocal.measurement.
VirtualSetup` over a line or a raster at one fixed orientation and records an A-scan
at every position, with the receiver's noise.  It also measures the setup's **zero
offset** as an operator does on a calibration block: the time of flight of a flat, level
reflector at the probe's height, noiseless, minus its true round trip 2h/c₀.  A surface
fit subtracts it (the wave model's diffraction delays the echo's envelope by a few ns in
the near field, as a real probe's does).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike, as_generator
from echocal._validate import finite_float, positive_float
from echocal.errors import EchocalValueError
from echocal.geometry import Pose
from echocal.positionscan.dataset import PositionScan, position_scan

__all__ = ["receiver_noise", "simulate_position_scan", "zero_offset"]

_BATCH = 64
"""Poses simulated at once."""


def zero_offset(setup: Any, height: float, *, tilt_x: float = 0.0, tilt_y: float = 0.0) -> float:
    """[s] the setup's zero offset at a water path ``height`` [m]: the front-wall time of
    flight (:func:`echocal.positionscan.front_wall_tof`, its own echo as the template)
    of a flat, level 100 × 100 mm reflector ``height`` below the probe at the orientation
    (``tilt_x``, ``tilt_y``) [deg], noiseless, minus 2·height/c₀."""
    from echocal.positionscan.tof import front_wall_tof
    from echocal.specimen import FinitePlane, Specimen

    h = positive_float("height", height)
    block = FinitePlane(center=(0.0, 0.0, 0.0), width=0.1, height=0.1, name="block")
    flat = dataclasses.replace(
        setup,
        specimen=Specimen([block], name="calibration-block"),
        interior=None,
        reference_position=(0.0, 0.0, h),
        rng=0,
    )
    samples = flat.simulate([Pose.from_tilt(0.0, 0.0, h, tilt_x, tilt_y)], noise=False)
    tof = front_wall_tof(samples, flat.window)
    return float(tof[0]) - 2.0 * h / flat.sound_speed


def simulate_position_scan(
    setup: Any,
    *,
    x: ArrayLike,
    y: ArrayLike | None = None,
    z: float | None = None,
    tilt_x: float = 0.0,
    tilt_y: float = 0.0,
    noise: bool = True,
    rng: RngLike = None,
) -> PositionScan:
    """Record a line (``y`` None) or raster scan on the simulator.

    Parameters
    ----------
    setup : a :class:`~echocal.measurement.VirtualSetup`.
    x, y : [m] probe positions, shapes ``(n_x,)`` and ``(n_y,)``.
    z : [m] probe height (default: the setup's reference position's).
    tilt_x, tilt_y : [deg] the fixed orientation as gimbal tilts (0, 0: straight down).
    noise : add the receiver's noise (the setup's SNR).
    rng : seed or Generator of the noise (default: the setup's own generator).

    Returns
    -------
    A :class:`PositionScan` with dims (y, x, time) or (x, time) and the attributes
    ``sound_speed_m_s``, ``probe_z_m``, ``tilt_x_deg``, ``tilt_y_deg``, ``zero_offset_s``,
    ``probe`` and ``setup``.
    """
    xs = np.asarray(x, dtype=np.float64).reshape(-1)
    ys = np.array([0.0]) if y is None else np.asarray(y, dtype=np.float64).reshape(-1)
    if xs.size == 0 or ys.size == 0:
        raise EchocalValueError("x and y need at least one position each")
    height = float(setup.reference_position[2]) if z is None else finite_float("z", z)
    tx, ty = finite_float("tilt_x", tilt_x), finite_float("tilt_y", tilt_y)
    poses = [Pose.from_tilt(float(px), float(py), height, tx, ty) for py in ys for px in xs]
    poses = [setup.limits.check(p) for p in poses]
    generator = as_generator(rng) if rng is not None else None
    rows = []
    for lo in range(0, len(poses), _BATCH):
        chunk = poses[lo : lo + _BATCH]
        rows.append(setup.simulate(chunk, noise=noise, rng=generator))
    samples = np.concatenate(rows).reshape(ys.size, xs.size, -1)
    window = setup.window
    probe = {
        "diameter_m": float(setup.transducer.width),
        "aperture": setup.transducer.aperture,
        "pulse": setup.pulse.name,
        "center_frequency_hz": float(setup.pulse.center_frequency),
    }
    attrs = {
        "source_format": "echocal simulator",
        "setup": setup.name,
        "setup_description": setup.description,
        "specimen": setup.specimen.name,
        "sound_speed_m_s": float(setup.sound_speed),
        "probe_z_m": height,
        "tilt_x_deg": tx,
        "tilt_y_deg": ty,
        "zero_offset_s": zero_offset(setup, height, tilt_x=tx, tilt_y=ty),
        "snr_db": setup.receiver.snr_db if noise else None,
        "probe": probe,
    }
    return position_scan(
        samples if y is not None else samples[0],
        fs=window.fs,
        start_time=window.start,
        x=xs,
        y=ys if y is not None else None,
        attrs=attrs,
    )


def receiver_noise(scan: PositionScan, setup: Any, rng: RngLike) -> PositionScan:
    """A noiseless simulated ``scan`` (``noise=False``) with the receiver of ``setup``
    applied (its noise at the setup's SNR, its ADC), drawn from ``rng``: the same A-scans
    :func:`simulate_position_scan` records with noise, for many noise draws of one
    (costly) noiseless simulation."""
    if scan.dataset.attrs.get("snr_db") is not None:
        raise EchocalValueError(
            "receiver_noise needs a noiseless scan (simulated with noise=False)"
        )
    noisy = setup._receiver._receive_unchecked(scan.samples, as_generator(rng))
    out = scan.with_samples(noisy)
    out.dataset.attrs["snr_db"] = setup.receiver.snr_db
    return out
