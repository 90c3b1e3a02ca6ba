"""A simulated SCPI bench on TCP: a motion controller and an oscilloscope whose echoes
come from a measurement source (usually the simulator) at the controller's pose.

:class:`ScpiBench` listens on loopback and answers, on one port, the commands of
echocal's ``scpi`` motion preset (``MOVE:ABS``, ``POS?``, ``LIM?``, ``MOVE:DONE?``,
``SYST:ERR?``) and of its ``keysight`` scope preset (``:WAVeform:...``, ``:DIGitize``,
``:ACQuire:TYPE``/``COUNt``, ``*OPC?``, ``:WAVeform:PREamble?``, ``:WAVeform:DATA?`` as
an IEEE 488.2 block of signed 16-bit codes), so PyVISA reaches it through pyvisa-py as
a ``TCPIP::127.0.0.1::PORT::SOCKET`` resource and the VISA drivers
(:class:`~echocal.rigs.motion.VisaPositioner`, :class:`~echocal.rigs.scope.VisaReceiver`)
run against pose-dependent echoes: each ``:DIGitize`` measures the source at the pose
the axes were moved to (averaged over ``:ACQuire:COUNt`` acquisitions in ``AVERage``
mode).  Controller units are mm (``X``, ``Y``, ``Z``) and degrees (``AZ``, ``COEL``); a
move beyond the source's limits is refused (``SYST:ERR?`` answers
``-222,"Data out of range"``) and the axis stays.  The vertical scale puts the
source's reference echo at a quarter of the 16-bit range.

The bench has no authentication (SCPI has none): it serves loopback only.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from echocal.errors import EchocalValueError
from echocal.geometry import Pose
from echocal.measurement.base import MeasurementSource
from echocal.measurement.line_server import LineServer

__all__ = ["AXIS_IDS", "ScpiBench", "rig_file_text"]

AXIS_IDS = {"X": "x", "Y": "y", "Z": "z", "AZ": "azimuth", "COEL": "coelevation"}
"""The controller's axis ids and echocal's axes they drive."""

_SCALE = {"x": 1e3, "y": 1e3, "z": 1e3, "azimuth": 1.0, "coelevation": 1.0}
"""Controller units per SI unit: mm for lengths, degrees for angles."""
_TRAVEL = 1e3
"""[controller units] the travel reported for an axis the source does not bound."""
_FULL_CODE = 32767


class ScpiBench(LineServer):
    """A motion controller and an oscilloscope over SCPI, backed by ``source``.

    Parameters
    ----------
    source : the measurement source (e.g. a :class:`~echocal.measurement.VirtualSetup`).
    host, port : where to listen (loopback; port 0 picks a free one: :attr:`address`).
    initial_pose : where the axes start (default: straight down over the source's
        ``reference_position``, else the origin clipped to the limits).
    gimbal : the controller's angles are a gimbal's (the probe's roll that of
        :meth:`~echocal.geometry.Pose.from_tilt`), as for calibrations in tilts.
    full_scale : [a.u.] the amplitude of the largest code; default four times the
        source's reference echo peak (1 when the source has none).
    """

    max_line = 4096
    thread_name = "echocal-scpi-bench"

    def __init__(
        self,
        source: MeasurementSource,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        initial_pose: Pose | None = None,
        gimbal: bool = True,
        full_scale: float | None = None,
    ) -> None:
        from echocal._net import is_loopback

        if not is_loopback(host):
            raise EchocalValueError(
                f"host {host}: the SCPI bench has no authentication; it listens on loopback "
                "only (use an SSH tunnel to reach it from elsewhere)"
            )
        self.source = source
        self.gimbal = bool(gimbal)
        if initial_pose is None:
            reference = getattr(source, "reference_position", None)
            x, y, z = (0.0, 0.0, 0.0) if reference is None else np.asarray(reference, float)
            initial_pose = source.limits.clip(Pose(float(x), float(y), float(z), 0.0, 0.0))
        self._axes = dict(zip(AXIS_IDS.values(), initial_pose.as_array(), strict=True))
        if full_scale is None:
            reference_samples = getattr(source, "reference_samples", None)
            peak = 0.0 if reference_samples is None else float(np.max(np.abs(reference_samples)))
            full_scale = 4.0 * peak if peak > 0.0 else 1.0
        if not (math.isfinite(full_scale) and full_scale > 0.0):
            raise EchocalValueError(f"full_scale must be finite and > 0; got {full_scale!r}")
        self.y_increment = float(full_scale) / _FULL_CODE
        """[a.u.] per code."""
        self._errors: list[str] = []
        self._averages = 1
        self._averaging = False
        self._trace: Any = None  # (codes, fs, start) of the last acquisition
        self._lock = threading.Lock()
        self.n_acquisitions = 0
        """A-scans measured (each averaged acquisition counts once per average)."""
        super().__init__(host=host, port=port)

    @property
    def resource(self) -> str:
        """The VISA resource name of the bench (pyvisa-py's raw TCP socket)."""
        host, port = self.address
        return f"TCPIP::{host}::{port}::SOCKET"

    def answer(self, raw: bytes, session: Any) -> tuple[bytes, bool]:
        """The reply to one command line (nothing for a command without one); the
        connection stays open."""
        return self.execute(raw.decode("ascii", "replace").strip()) or b"", False

    # -- state ------------------------------------------------------------------------------
    def pose(self) -> Pose:
        """The axes' pose [m, deg]."""
        a = self._axes
        return Pose(a["x"], a["y"], a["z"], a["azimuth"], a["coelevation"], gimbal=self.gimbal)

    # -- commands ---------------------------------------------------------------------------
    def execute(self, line: str) -> bytes | None:
        """Execute one command line; return the reply (with its line end) or None."""
        head, _, args = line.partition(" ")
        with self._lock:
            command = self._COMMANDS.get(head.upper())
            if command is None:
                self._errors.append(f'-113,"Undefined header; {head[:40]}"')
                return None
            try:
                reply = command(self, args.strip())
            except (ValueError, KeyError) as exc:
                self._errors.append(f'-224,"Illegal parameter value; {exc}"')
                return b"\n" if head.endswith("?") else None
        if reply is None:
            return None
        return reply if isinstance(reply, bytes) else f"{reply}\n".encode("ascii")

    def _axis(self, name: str) -> str:
        axis = AXIS_IDS.get(name.strip().upper())
        if axis is None:
            raise KeyError(f"unknown axis {name.strip()!r}; axes: {', '.join(AXIS_IDS)}")
        return axis

    def _idn(self, args: str) -> str:
        description = " ".join(self.source.description.split()).replace(",", ";")
        return f"ECHOCAL,SIMULATED-SCPI-BENCH,{description},1"

    def _move(self, args: str) -> None:
        name, _, value = args.partition(",")
        axis = self._axis(name)
        target = float(value) / _SCALE[axis]
        if not math.isfinite(target):
            raise ValueError(f"{value.strip()!r} is not finite")
        low, high = getattr(self.source.limits, axis)
        if not low <= target <= high:
            self._errors.append('-222,"Data out of range"')
            return None
        self._axes[axis] = target
        return None

    def _position(self, args: str) -> str:
        axis = self._axis(args)
        return f"{self._axes[axis] * _SCALE[axis]:.9g}"

    def _limits(self, args: str) -> str:
        axis = self._axis(args)
        low, high = (
            float(np.clip(v * _SCALE[axis], -_TRAVEL, _TRAVEL))
            for v in getattr(self.source.limits, axis)
        )
        return f"{low:.9g},{high:.9g}"

    def _done(self, args: str) -> str:
        self._axis(args)
        return "1"  # the simulated axes arrive at once

    def _error(self, args: str) -> str:
        return self._errors.pop(0) if self._errors else '+0,"No error"'

    def _ignore(self, args: str) -> None:
        return None  # source, format, byte order, sign: the bench always sends signed LE words

    def _acquire_type(self, args: str) -> None:
        kind = args.strip().upper()
        if kind not in ("NORM", "NORMAL", "AVER", "AVERAGE"):
            raise ValueError(f"acquisition type {args!r}")
        self._averaging = kind.startswith("AVER")
        return None

    def _count(self, args: str) -> None:
        count = int(args)
        if not 1 <= count <= 65536:
            raise ValueError(f"count {count} (1 to 65536)")
        self._averages = count
        return None

    def _digitize(self, args: str) -> None:
        n = self._averages if self._averaging else 1
        pose = self.pose()
        measure_many = getattr(self.source, "measure_many", None)
        if measure_many is not None:
            scans = measure_many([pose] * n)
        else:
            scans = [self.source.measure(pose) for _ in range(n)]
        self.n_acquisitions += n
        samples = np.mean([np.asarray(s.samples, dtype=np.float64) for s in scans], axis=0)
        codes = np.clip(np.rint(samples / self.y_increment), -_FULL_CODE - 1, _FULL_CODE)
        self._trace = (codes.astype("<i2"), float(scans[0].fs), float(scans[0].start_time))
        return None

    def _opc(self, args: str) -> str:
        return "1"

    def _preamble(self, args: str) -> str:
        if self._trace is None:
            raise ValueError("no waveform: :DIGitize first")
        codes, fs, start = self._trace
        count = self._averages if self._averaging else 1
        mode = 2 if self._averaging else 0
        return (
            f"1,{mode},{codes.size},{count},{1.0 / fs:.12e},{start:.12e},0,"
            f"{self.y_increment:.12e},0,0"
        )

    def _data(self, args: str) -> bytes:
        if self._trace is None:
            raise ValueError("no waveform: :DIGitize first")
        payload = self._trace[0].tobytes()
        size = str(len(payload))
        return f"#{len(size)}{size}".encode("ascii") + payload + b"\n"

    _COMMANDS: ClassVar[dict[str, Callable[[Any, str], Any]]] = {
        "*IDN?": _idn,
        "*OPC?": _opc,
        "MOVE:ABS": _move,
        "POS?": _position,
        "LIM?": _limits,
        "MOVE:DONE?": _done,
        "SYST:ERR?": _error,
        ":WAVEFORM:SOURCE": _ignore,
        ":WAVEFORM:FORMAT": _ignore,
        ":WAVEFORM:BYTEORDER": _ignore,
        ":WAVEFORM:UNSIGNED": _ignore,
        ":ACQUIRE:TYPE": _acquire_type,
        ":ACQUIRE:COUNT": _count,
        ":DIGITIZE": _digitize,
        ":WAVEFORM:PREAMBLE?": _preamble,
        ":WAVEFORM:DATA?": _data,
    }


def rig_file_text(bench_resource: str, *, setup: str | None = None, timeout: float = 30.0) -> str:
    """A rig file (TOML) for the bench at ``bench_resource``: the ``scpi`` controller and
    the ``keysight`` scope over pyvisa-py (``library = "@py"``); ``setup`` names the
    setup whose pulse the rig transmits."""
    head = ["[rig]", 'name = "scpi-bench"']
    if setup is not None:
        head.append(f'setup = "{setup}"')
    common = [f'resource = "{bench_resource}"', 'library = "@py"', f"timeout = {timeout:g}"]
    axes = "\n".join(f'{axis} = {{ id = "{ident}" }}' for ident, axis in AXIS_IDS.items())
    return "\n".join(
        [
            *head,
            "[rig.positioner]",
            'driver = "visa"',
            'preset = "scpi"',
            *common,
            "[rig.positioner.axes]",
            axes,
            "[rig.receiver]",
            'driver = "visa"',
            'preset = "keysight"',
            *common,
            "",
        ]
    )
