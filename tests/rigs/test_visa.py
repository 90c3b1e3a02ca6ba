"""The VISA receiver and positioner against pyvisa-sim instruments.

Each test writes its own pyvisa-sim YAML (with :mod:`echocal.rigs.simfile`) holding ADC
codes it chose, and checks what the driver returns against volts and times it computes
itself from the codes and the preamble it wrote: the driver's conversion is not reused.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from echocal.errors import EchocalError, InstrumentError, LimitError
from echocal.geometry import Pose
from echocal.measurement import HardwareSource
from echocal.rigs import (
    Axis,
    VisaInstrument,
    VisaPositioner,
    VisaReceiver,
    motion_preset,
    scope_preset,
    sim_library,
)
from echocal.rigs.simfile import (
    encodable,
    ieee_block,
    motion_device,
    scope_device,
    sim_definition,
)

pytest.importorskip("pyvisa_sim")
yaml = pytest.importorskip("yaml")

SCOPE = "TCPIP0::scope.test::INSTR"
STAGE = "ASRL3::INSTR"


def _library(tmp_path: Path, devices: dict) -> str:
    resources = {name: {"device": f"d{i}"} for i, name in enumerate(devices)}
    definition = {
        "spec": "1.1",
        "devices": {f"d{i}": d for i, d in enumerate(devices.values())},
        "resources": resources,
    }
    path = tmp_path / f"sim-{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(definition), encoding="utf-8")
    return f"{path}@sim"


def _instrument(library: str, resource: str, **kw) -> VisaInstrument:
    return VisaInstrument(resource, library=library, timeout=kw.pop("timeout", 0.5), **kw)


def _keysight_with(codes: np.ndarray, preamble: str) -> dict:
    device = scope_device("keysight")
    for d in device["dialogues"]:
        if d["q"] == ":WAVeform:DATA?":
            d["r"] = ieee_block(codes, "h")
        if d["q"] == ":WAVeform:PREamble?":
            d["r"] = preamble
    return device


def test_keysight_receiver_converts_the_block_with_the_preamble(tmp_path):
    # a ramp of codes whose bytes pyvisa-sim can send, 300 samples
    candidates = np.arange(1000, 40000, 97)
    codes = candidates[encodable(candidates, "h")][:300]
    dt, x0, xref, dy, y0, yref = 4e-9, 12e-6, 7.0, 3e-5, -0.02, 1500.0
    preamble = f"1,0,{codes.size},1,{dt!r},{x0!r},{xref!r},{dy!r},{y0!r},{yref!r}"
    library = _library(tmp_path, {SCOPE: _keysight_with(codes, preamble)})
    receiver = VisaReceiver(_instrument(library, SCOPE), scope_preset("keysight"), averages=8)
    scan = receiver.acquire()
    expected = (codes - yref) * dy + y0  # the Keysight programmer's guide's formula
    np.testing.assert_allclose(scan.samples, expected, rtol=0, atol=1e-12)
    assert scan.fs == pytest.approx(1 / dt, rel=1e-12)
    assert scan.start_time == pytest.approx(x0 - xref * dt, rel=1e-12)
    # the averaging was set on the instrument, and it kept it
    assert receiver.instrument.query(":ACQuire:COUNt?") == "8"
    receiver.close()


@pytest.mark.parametrize("preset", ["keysight", "tektronix", "rigol"])
def test_every_preset_reads_the_same_echo_from_the_shipped_instruments(preset):
    receiver = VisaReceiver(
        _instrument(sim_library(), f"TCPIP0::{preset}.sim::INSTR"), scope_preset(preset)
    )
    scan = receiver.acquire()
    assert scan.n_samples == 1000 and scan.fs == pytest.approx(100e6)
    assert scan.start_time == pytest.approx(60e-6, abs=1e-15)
    # the echo arrives at 66.5 us: the envelope's peak is there within one period (0.2 us)
    peak_time = scan.start_time + np.argmax(np.abs(scan.samples)) / scan.fs
    assert peak_time == pytest.approx(66.5e-6, abs=0.2e-6)
    receiver.close()


def test_the_shipped_sim_file_is_the_generators_output():
    shipped = Path(sim_library().removesuffix("@sim"))
    assert yaml.safe_load(shipped.read_text(encoding="utf-8")) == sim_definition()


def test_a_scope_that_never_answers_times_out_after_its_retries(tmp_path):
    library = _library(tmp_path, {SCOPE: scope_device("keysight", data="")})
    instrument = _instrument(library, SCOPE, timeout=0.05, retries=2, backoff=0.0)
    receiver = VisaReceiver(instrument, scope_preset("keysight"))
    with pytest.raises(InstrumentError) as info:
        receiver.acquire()
    message = str(info.value)
    assert SCOPE in message and ":WAVeform:DATA?" in message and "timed out" in message
    assert "3 attempts" in message and instrument.n_reconnects == 2
    # the next command works: nothing stale was left to read
    assert receiver.identify().startswith("KEYSIGHT")


@pytest.mark.parametrize("block", ["#9" + "A" * 30, "no block at all", "#13ABC"])
def test_a_garbled_block_is_nonsense_at_once(tmp_path, block):
    # length digits that are not digits; no '#' header; 3 bytes of 2-byte int16 samples
    library = _library(tmp_path, {SCOPE: scope_device("keysight", data=block)})
    instrument = _instrument(library, SCOPE, timeout=0.1, retries=3, backoff=0.0)
    receiver = VisaReceiver(instrument, scope_preset("keysight"))
    with pytest.raises(InstrumentError) as info:
        receiver.acquire()
    message = str(info.value)
    assert ":WAVeform:DATA?" in message and SCOPE in message and "nonsense" in message
    assert "\n" not in message and instrument.n_reconnects == 0  # not retried


def test_a_block_cut_short_is_a_transport_fault_retried(tmp_path):
    # announces 4 bytes, sends 2: as a slow transfer would, so it is retried, then reported
    library = _library(tmp_path, {SCOPE: scope_device("keysight", data="#14AB")})
    instrument = _instrument(library, SCOPE, timeout=0.05, retries=1, backoff=0.0)
    with pytest.raises(InstrumentError, match=r":WAVeform:DATA\?.*2 attempts.*timed out"):
        VisaReceiver(instrument, scope_preset("keysight")).acquire()
    assert instrument.n_reconnects == 1


def test_a_garbled_preamble_names_the_query(tmp_path):
    device = _keysight_with(np.array([4112, 4113]), "1,0,2,1,abc,0,0,1e-3,0,0")
    library = _library(tmp_path, {SCOPE: device})
    receiver = VisaReceiver(_instrument(library, SCOPE, retries=0), scope_preset("keysight"))
    with pytest.raises(InstrumentError, match=r":WAVeform:PREamble\?.*nonsense.*'abc'"):
        receiver.acquire()


def test_an_unknown_preset_lists_the_valid_ones():
    with pytest.raises(EchocalError, match="keysight, rigol, tektronix"):
        scope_preset("lecroy")
    with pytest.raises(EchocalError, match="newport-esp, scpi"):
        motion_preset("zaber")
    with pytest.raises(EchocalError, match="unknown scope command 'fetch'"):
        scope_preset("keysight", fetch="CURV?")


def test_an_unreachable_resource_is_one_line_naming_it():
    # pyvisa-py, a TCP socket on a closed loopback port: connection refused
    instrument = VisaInstrument(
        "TCPIP0::127.0.0.1::1::SOCKET", library="@py", timeout=0.3, retries=1, backoff=0.0
    )
    with pytest.raises(InstrumentError) as info:
        instrument.identify()
    assert "TCPIP0::127.0.0.1::1::SOCKET" in str(info.value) and "\n" not in str(info.value)


def _stage(library: str, **kw) -> VisaPositioner:
    axes = [
        Axis("x", "X", 1e3),
        Axis("y", "Y", 1e3),
        Axis("z", "Z", 1e3),
        Axis("azimuth", "AZ"),
        Axis("coelevation", "COEL"),
    ]
    return VisaPositioner(_instrument(library, STAGE), motion_preset("scpi"), axes, **kw)


def test_positioner_moves_reads_back_and_reports_limits(tmp_path):
    library = _library(tmp_path, {STAGE: motion_device()})
    stage = _stage(library)
    limits = stage.limits
    assert limits.x == pytest.approx((-0.05, 0.05)) and limits.z == pytest.approx((0.005, 0.08))
    assert limits.coelevation == (-30.0, 30.0)
    target = Pose(0.0123, -0.004, 0.031, -45.5, 12.25)
    reached = stage.move_to(target)
    np.testing.assert_allclose(reached.as_array(), target.as_array(), rtol=0, atol=1e-9)
    # the controller holds the positions in its own units (mm, deg)
    assert float(stage.instrument.query("POS? X")) == pytest.approx(12.3)


def test_a_move_beyond_the_controllers_limits_is_a_limit_error(tmp_path):
    library = _library(tmp_path, {STAGE: motion_device()})
    stage = _stage(library)
    stage.move_to(Pose(0.0, 0.0, 0.02, 0.0, 5.0))
    with pytest.raises(LimitError, match=r"MOVE:ABS COEL,45.*-222"):
        stage.move_to(Pose(0.0, 0.0, 0.02, 0.0, 45.0))
    # the refused axis did not move; the error queue is empty again
    assert stage.position().coelevation == pytest.approx(5.0)
    assert stage.instrument.query("SYST:ERR?").startswith("0")


def test_rig_limits_refuse_a_pose_before_anything_moves(tmp_path):
    library = _library(tmp_path, {STAGE: motion_device(), SCOPE: scope_device("keysight")})
    rig = HardwareSource(
        _stage(library), VisaReceiver(_instrument(library, SCOPE), scope_preset("keysight"))
    )
    before = rig.positioner.position()
    with pytest.raises(LimitError, match="coelevation = 40 deg outside"):
        rig.measure(Pose(0.0, 0.0, 0.02, 0.0, 40.0))
    assert rig.positioner.position() == before
    scan = rig.measure(Pose(0.001, 0.0, 0.02, 10.0, 3.0))
    assert scan.pose is not None and scan.pose.azimuth == pytest.approx(10.0)
    rig.close()


def test_a_fixed_axis_and_rig_file_limits(tmp_path):
    device = motion_device()
    library = _library(tmp_path, {STAGE: device})
    axes = [
        Axis("x", "X", 1e3, limits=(-0.01, 0.2)),  # narrower below, wider above
        Axis("y", "Y", 1e3),
        Axis("z", "Z", 1e3),
        Axis("azimuth", fixed=0.0),
        Axis("coelevation", "COEL"),
    ]
    stage = VisaPositioner(_instrument(library, STAGE), motion_preset("scpi"), axes)
    assert stage.limits.x == pytest.approx((-0.01, 0.05))  # the intersection
    assert stage.limits.azimuth == (0.0, 0.0)
    assert stage.move_to(Pose(0.0, 0.0, 0.02, 0.0, 2.0)).azimuth == 0.0


def test_a_positioner_missing_an_axis_is_refused():
    with pytest.raises(EchocalError, match="missing coelevation"):
        VisaPositioner(
            VisaInstrument(STAGE, library="@sim"),
            motion_preset("scpi"),
            [Axis("x", "X"), Axis("y", "Y"), Axis("z", "Z"), Axis("azimuth", "AZ")],
        )


def test_a_move_that_never_finishes_times_out(tmp_path):
    device = motion_device()
    for d in device["dialogues"]:
        if d["q"] == "MOVE:DONE? Z":
            d["r"] = "0"
    library = _library(tmp_path, {STAGE: device})
    stage = _stage(library, motion_timeout=0.1, poll_interval=0.01)
    with pytest.raises(InstrumentError, match="axes z did not stop within 0.1 s"):
        stage.move_to(Pose(0.0, 0.0, 0.03, 0.0, 0.0))


def test_a_rig_file_sets_the_serial_line(tmp_path):
    from echocal.rigs import connect_rig

    rig_file = tmp_path / "rig.toml"
    axes = "".join(
        f'{a} = {{ id = "{i}" }}\n'
        for a, i in zip(
            ("x", "y", "z", "azimuth", "coelevation"), ("X", "Y", "Z", "AZ", "COEL"), strict=True
        )
    )
    rig_file.write_text(
        '[rig]\n[rig.positioner]\ndriver = "visa"\nresource = "ASRL1::INSTR"\n'
        'library = "@echocal-sim"\nbaud_rate = 19200\n[rig.positioner.axes]\n'
        + axes
        + '[rig.receiver]\ndriver = "visa"\nresource = "TCPIP0::rigol.sim::INSTR"\n'
        'library = "@echocal-sim"\npreset = "rigol"\n',
        encoding="utf-8",
    )
    with connect_rig(rig_file) as rig:
        assert rig.positioner.instrument._handle.baud_rate == 19200
        assert rig.identities["receiver"].startswith("RIGOL")
