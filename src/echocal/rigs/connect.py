"""From a rig file to a connected :class:`~echocal.measurement.HardwareSource`, and the
wiring check of ``echocal rig check``.

Drivers (``driver = ...`` in ``[rig.positioner]`` / ``[rig.receiver]``):

* ``tcp`` — an instrument speaking echocal's line protocol (the emulated rig of
  ``echocal instrument-server``, for tests and demos); a positioner and a receiver
  at the same address share one connection;
* ``visa`` — a SCPI motion controller (:class:`~echocal.rigs.motion.VisaPositioner`)
  or oscilloscope (:class:`~echocal.rigs.scope.VisaReceiver`) through PyVISA;
* ``python`` — any class given as ``module:Class``, built with ``options`` as keyword
  arguments, that implements :class:`~echocal.measurement.hardware.Positioner` or
  :class:`~echocal.measurement.hardware.Receiver`.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.resources
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from echocal.ascan import AScan
from echocal.errors import ConfigError, EchocalError, EchocalValueError, InstrumentError
from echocal.measurement.hardware import (
    HardwareSource,
    Positioner,
    Receiver,
    TcpInstrument,
    TcpPositioner,
    TcpReceiver,
)
from echocal.measurement.limits import PositionerLimits
from echocal.rigs.config import (
    AXIS_NAMES,
    PythonDriver,
    RigConfig,
    TcpDriver,
    VisaMotionDriver,
    VisaScopeDriver,
    axis_values,
    load_rig_config,
)

__all__ = ["SIM_LIBRARY", "Rig", "RigCheck", "check_rig", "connect_rig", "identify", "sim_library"]

SIM_LIBRARY = "@echocal-sim"
"""``library`` value naming the simulated instruments shipped with echocal (pyvisa-sim)."""


def sim_library() -> str:
    """PyVISA's library string for the shipped simulated instruments (``FILE.yaml@sim``)."""
    path = importlib.resources.files("echocal") / "data" / "visa" / "echocal-sim.yaml"
    return f"{path}@sim"


def _library(text: str, base_dir: Path) -> str:
    if text == SIM_LIBRARY:
        return sim_library()
    head, sep, tail = text.rpartition("@")
    if sep and head and tail == "sim" and not Path(head).is_absolute():
        return f"{base_dir / head}@sim"  # a simulation file next to the rig file
    return text


def _address(text: str, where: str) -> tuple[str, int]:
    host, sep, port = text.strip().rpartition(":")
    host = host.strip().removeprefix("[").removesuffix("]")
    if not sep or not host or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ConfigError(f"{where}.address: takes HOST:PORT (e.g. 127.0.0.1:5025); got {text!r}")
    return host, int(port)


def _python_device(config: PythonDriver, where: str, protocol: type) -> Any:
    module_name, sep, name = config.class_.replace(":", ".").rpartition(".")
    if not sep or not module_name:
        raise ConfigError(f"{where}.class: give module:Class; got {config.class_!r}")
    try:
        cls = getattr(importlib.import_module(module_name), name)
    except (ImportError, AttributeError) as exc:
        raise ConfigError(f"{where}.class: cannot import {config.class_!r}: {exc}") from None
    try:
        device = cls(**config.options)
    except TypeError as exc:
        raise ConfigError(f"{where}.options: {config.class_} refused them: {exc}") from None
    except EchocalError:
        raise
    except Exception as exc:  # the lab's own code: its failure, in one line
        raise InstrumentError(
            f"{where}: {config.class_}(...) failed: {type(exc).__name__}: {exc}"
        ) from None
    if not isinstance(device, protocol):
        raise ConfigError(
            f"{where}.class: {config.class_} is not a {protocol.__name__} (it needs "
            f"{', '.join(sorted(_protocol_members(protocol)))})"
        )
    return _Guarded(device, config.class_)


class _Guarded:
    """A lab's own device whose non-echocal exceptions become one-line InstrumentErrors
    naming the class and the call (echocal's own errors, e.g. LimitError, pass as they are)."""

    def __init__(self, device: Any, name: str) -> None:
        self._device = device
        self._name = name

    def _call(self, what: str, *args: Any) -> Any:
        try:
            member = getattr(self._device, what)
            return member(*args) if callable(member) else member
        except EchocalError:
            raise
        except Exception as exc:
            raise InstrumentError(f"{self._name}.{what}: {type(exc).__name__}: {exc}") from None

    @property
    def limits(self) -> PositionerLimits:
        return self._call("limits")

    def move_to(self, pose: Any) -> Any:
        return self._call("move_to", pose)

    def position(self) -> Any:
        return self._call("position")

    def acquire(self) -> AScan:
        return self._call("acquire")

    def identify(self) -> str:
        if callable(getattr(self._device, "identify", None)):
            return self._call("identify")
        return type(self._device).__name__

    def close(self) -> None:
        self._call("close")


def _protocol_members(protocol: type) -> set[str]:
    return {n for n in vars(protocol) if not n.startswith("_")}


def _visa(config: Any, base_dir: Path) -> Any:
    from echocal.rigs.visa_io import VisaInstrument

    return VisaInstrument(
        config.resource,
        library=_library(config.library, base_dir),
        timeout=config.timeout,
        retries=config.retries,
        read_termination=config.read_termination,
        write_termination=config.write_termination,
        baud_rate=config.baud_rate,
    )


def _build(config: RigConfig, base_dir: Path) -> tuple[Positioner, Receiver]:
    """The two devices of a validated rig file (nothing is connected yet)."""
    from echocal.rigs.motion import Axis, VisaPositioner, motion_preset
    from echocal.rigs.scope import VisaReceiver, scope_preset

    p, r = config.rig.positioner, config.rig.receiver
    shared: dict[tuple[str, int], TcpInstrument] = {}

    def tcp(driver: TcpDriver, where: str) -> TcpInstrument:
        host, port = _address(driver.address, where)
        if (host, port) not in shared:
            shared[host, port] = TcpInstrument(
                host, port, timeout=driver.timeout, retries=driver.retries
            )
        return shared[host, port]

    positioner: Any
    if isinstance(p, TcpDriver):
        positioner = TcpPositioner(tcp(p, "rig.positioner"))
    elif isinstance(p, VisaMotionDriver):
        preset = _checked("rig.positioner", lambda: motion_preset(p.preset, **p.commands))
        axes = [Axis(**axis_values(a, getattr(p.axes, a))) for a in AXIS_NAMES]
        positioner = _checked(
            "rig.positioner",
            lambda: VisaPositioner(
                _visa(p, base_dir), preset, axes, motion_timeout=p.motion_timeout
            ),
        )
    else:
        positioner = _python_device(p, "rig.positioner", Positioner)
    receiver: Any
    if isinstance(r, TcpDriver):
        receiver = TcpReceiver(tcp(r, "rig.receiver"))
    elif isinstance(r, VisaScopeDriver):
        scope = _checked("rig.receiver", lambda: scope_preset(r.preset, **r.commands))
        receiver = VisaReceiver(
            _visa(r, base_dir),
            scope,
            channel=r.channel,
            averages=r.averages,
            time_offset=r.time_offset,
        )
    else:
        receiver = _python_device(r, "rig.receiver", Receiver)
    return positioner, receiver


def _checked(where: str, build: Any) -> Any:
    """``build()``; a bad preset name or template becomes a ConfigError naming ``where``."""
    try:
        return build()
    except EchocalValueError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    except KeyError as exc:  # an unknown preset (UnknownNameError)
        raise ConfigError(f"{where}.preset: {exc}") from None


def identify(device: Any) -> str:
    """A device's identification: its ``identify()`` (``*IDN?``), else its class name."""
    for target in (device, getattr(device, "instrument", None)):
        ask = getattr(target, "identify", None)
        if callable(ask):
            return " ".join(str(ask()).split())
    return type(device).__name__


def connect_rig(rig: str | Path | RigConfig, *, base_dir: Path | None = None) -> Rig:
    """Connect the rig of a rig file (or a validated :class:`RigConfig`).

    Identifies both devices (``*IDN?``) and reads the positioner's limits at once, so a
    wrong address or resource fails here, in one line naming it
    (:class:`~echocal.errors.InstrumentError`); nothing moves.
    """
    if isinstance(rig, RigConfig):
        config, folder = rig, base_dir or Path.cwd()
    else:
        config, folder = load_rig_config(rig)
    positioner, receiver = _build(config, folder)
    try:
        names = (identify(positioner), identify(receiver))
        limits = positioner.limits
    except BaseException:
        _close(positioner, receiver)
        raise
    section = config.rig
    who = names[0] if names[0] == names[1] else f"{names[0]} + {names[1]}"
    return Rig(
        positioner,
        receiver,
        config=config,
        identities={"positioner": names[0], "receiver": names[1]},
        limits=limits,
        description=f"rig {section.name}: {who}",
        settle_time=section.settle_time,
    )


class Rig(HardwareSource):
    """A :class:`HardwareSource` made from a rig file: also its ``config`` and the
    ``identities`` (``*IDN?``) of its ``positioner`` and ``receiver``."""

    def __init__(
        self,
        positioner: Positioner,
        receiver: Receiver,
        *,
        config: RigConfig,
        identities: dict[str, str],
        **kwargs: Any,
    ) -> None:
        super().__init__(positioner, receiver, **kwargs)
        self.config = config
        self.identities = identities

    def close(self) -> None:
        """Close both devices, once each (a shared connection once)."""
        if not self._closed:
            self._closed = True
            _close(self.positioner, self.receiver)


def _close(*devices: Any) -> None:
    seen: list[Any] = []
    for device in devices:
        target = getattr(device, "instrument", device)
        if any(target is s for s in seen):
            continue
        seen.append(target)
        with contextlib.suppress(Exception):
            device.close()


@dataclass(frozen=True)
class RigCheck:
    """What ``echocal rig check`` found: identities, limits, the pose and one A-scan."""

    name: str
    positioner: str
    receiver: str
    limits: PositionerLimits
    pose: Any
    ascan: AScan

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON)."""
        scan = self.ascan
        return {
            "name": self.name,
            "positioner": self.positioner,
            "receiver": self.receiver,
            "limits": self.limits.as_dict(),
            "pose": [float(v) for v in self.pose.as_array()],
            "ascan": {
                "n_samples": scan.n_samples,
                "fs_hz": scan.fs,
                "start_time_s": scan.start_time,
                "peak_abs": float(np.max(np.abs(scan.samples))),
                "finite": bool(scan.is_finite),
            },
        }


def check_rig(rig: str | Path) -> RigCheck:
    """Validate the rig file (a missing axis is refused here, before anything moves),
    connect, identify both devices, read the limits, and take one A-scan where the
    positioner stands (no move)."""
    source = connect_rig(rig)
    with source:
        pose = source.positioner.position()
        scan = source.receiver.acquire()
        ids = source.identities
        return RigCheck(
            name=source.config.rig.name,
            positioner=ids["positioner"],
            receiver=ids["receiver"],
            limits=source.limits,
            pose=pose,
            ascan=scan,
        )
