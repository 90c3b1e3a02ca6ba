"""One calibration, three ways, identical measurement for measurement: on the simulator
directly, through the emulated TCP rig (a rig file, ``connect_rig``), and as a Bluesky
plan on the simulated ophyd devices.

Each path gets its own simulator built from the same setup file (same seed, so the same
noise stream); ``auto`` in the tilt parameterization, the same x0 and seed.  The
simulator measures batches, the rig and the plan one pose at a time, the rig through a
socket: the number of measurements and the stopping reason must agree exactly, the points
measured, the values and the estimate to rounding.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import TILTED_PLATE as TILTED
from cli_helpers import tcp_rig_file, tiny_setup_toml
from echocal.calibrate import calibrate
from echocal.geometry import Pose, convert_angles
from echocal.measurement import InstrumentServer, SourceObjective
from echocal.rigs import connect_rig
from echocal.setups import load_setup

pytest.importorskip("bluesky")
from bluesky import RunEngine

from echocal.rigs.ophyd_devices import simulated_devices
from echocal.rigs.plans import calibrate_plan

POSITION = (0.001, -0.0005, 0.016)  # [m]
X0 = (0.0, 0.0)  # [deg] tilts: 4 deg from the optimum
RUN = {"method": "auto", "x0": X0, "settle": (0.01, 8), "rng": 11}


def test_simulator_tcp_rig_and_bluesky_calibrate_identically(tmp_path: Path):
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(specimen=TILTED), encoding="utf-8")

    direct = calibrate(SourceObjective(load_setup(setup), POSITION, parameterization="tilt"), **RUN)

    emulated = load_setup(setup)
    with InstrumentServer(emulated, initial_pose=Pose(*POSITION)) as server:
        host, port = server.address
        rig_file = tcp_rig_file(tmp_path / "rig.toml", f"{host}:{port}")
        with connect_rig(rig_file) as rig:
            on_rig = calibrate(
                SourceObjective(rig, POSITION, pulse=emulated.pulse, parameterization="tilt"),
                **RUN,
            )
        assert server.n_acquisitions == on_rig.n_measurements

    # seed=None: the detector draws from the setup's own noise stream, as the others do
    probe, detector = simulated_devices(load_setup(setup), gimbal=True, seed=None)
    events = []
    engine = RunEngine({}, call_returns_result=True)
    plan = calibrate_plan(probe, detector, position=POSITION, **RUN)
    planned = engine(plan, lambda name, doc: events.append(doc) if name == "event" else None)
    on_bluesky = planned.plan_result

    assert direct.success and direct.n_measurements > 10
    # the plate's normal (30, 4) deg as tilts: the estimate is within 0.5 deg of it
    truth = convert_angles(30.0, 4.0, "azimuth-coelevation", "tilt")
    assert np.hypot(*(np.asarray(direct.x) - np.asarray(truth))) < 0.5
    # the same measurements in the same order, with the same values and estimate; equal to
    # rounding only (1e-9 relative): the simulator's compiled kernels and BLAS may sum in a
    # different order from one run to the next (seen: 2e-14 under pytest-xdist)
    for other in (on_rig, on_bluesky):
        assert (other.n_measurements, other.status) == (direct.n_measurements, direct.status)
        np.testing.assert_allclose(other.points, direct.points, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(other.values, direct.values, rtol=1e-9, atol=0)
        np.testing.assert_allclose(other.x, direct.x, rtol=1e-9, atol=1e-12)
    assert len(events) == direct.n_measurements + 1  # and the result stream's one event
