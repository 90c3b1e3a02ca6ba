"""An emulated rig: any measurement source served over the instrument line protocol.

:class:`InstrumentServer` listens on TCP (loopback by default) and answers the
commands of :mod:`echocal.measurement.protocol` from a
:class:`~echocal.measurement.base.MeasurementSource` — usually the simulator —
so the whole hardware path (:class:`~echocal.measurement.hardware.HardwareSource`
over :class:`~echocal.measurement.hardware.TcpInstrument`) runs for real over a
socket.  The emulated positioner is perfect (it reaches the requested pose) and
optionally slow (``move_time`` [s] per ``MOVE``); ``ACQ?`` measures the source at
the current pose.  :class:`Faults` injects the failures a real rig shows.

One instrument, several connections: each connection is served by its own
thread, and commands are executed one at a time under a lock, as a real
instrument would.
"""

from __future__ import annotations

import contextlib
import hmac
import threading
import time
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from echocal._validate import nonnegative_float, one_of, positive_int
from echocal.errors import LimitError
from echocal.geometry import Pose
from echocal.measurement import protocol
from echocal.measurement.base import MeasurementSource
from echocal.measurement.line_server import LineServer

AUTH_CODE = "AUTH"
"""Error code of a connection refused for a missing or wrong token."""

__all__ = ["MALFORMED_KINDS", "Faults", "InstrumentServer", "serve_forever"]

MALFORMED_KINDS = ("count", "number", "base64", "nan", "reply")
"""Ways to garble an A-scan: header announces one sample more than sent (``count``), a
header that is not a number (``number``), a payload that is not base64 (``base64``), a NaN
sample (``nan``), an unknown reply line instead of the header (``reply``)."""


@dataclass(frozen=True, slots=True)
class Faults:
    """Failures to inject, each happening once (for tests and demos).

    Attributes
    ----------
    drop_after : after this many commands (counted over all connections), the next
        command is not answered: the connection is closed under the client.
    drop_forever : with ``drop_after``, the instrument then stays gone — every later
        connection is closed at once (the client's retries run out).
    late_acquisition : the k-th ``ACQ?`` (1-based) is answered ``late_delay`` late.
    late_delay : [s] delay of that late answer (make it longer than the client timeout).
    malformed_acquisition : the k-th ``ACQ?`` (1-based) gets a malformed answer.
    malformed_kind : how it is malformed, one of :data:`MALFORMED_KINDS`.
    """

    drop_after: int | None = None
    drop_forever: bool = False
    late_acquisition: int | None = None
    late_delay: float = 1.0
    malformed_acquisition: int | None = None
    malformed_kind: str = "count"

    def __post_init__(self) -> None:
        for name in ("drop_after", "late_acquisition", "malformed_acquisition"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, positive_int(f"faults.{name}", value))
        object.__setattr__(self, "late_delay", nonnegative_float("late_delay", self.late_delay))
        one_of("faults.malformed_kind", self.malformed_kind, MALFORMED_KINDS)


class InstrumentServer(LineServer):
    """Serve ``source`` as an instrument over TCP, in a background thread.

    Parameters
    ----------
    source : any measurement source (the caller keeps ownership; it is not closed here).
    host, port : where to listen; ``port=0`` picks a free port (see :attr:`address`).
    move_time : [s] each ``MOVE`` takes (the instrument is busy meanwhile).
    faults : failures to inject (default: none).
    initial_pose : where the positioner starts (default: the origin clipped to the limits).
    token : a shared secret: each connection must first send ``AUTH <token>`` (answered
        ``OK``; a wrong or missing token gets ``ERR AUTH`` and the connection is closed).
        None (the default) asks nothing — fine on loopback, not on a network.

    Use as a context manager: ``with InstrumentServer(src) as server: ...server.address``.
    """

    max_line = protocol.MAX_LINE_BYTES
    thread_name = "echocal-instrument-server"

    def __init__(
        self,
        source: MeasurementSource,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        move_time: float = 0.0,
        faults: Faults | None = None,
        initial_pose: Pose | None = None,
        token: str | None = None,
    ) -> None:
        self.source = source
        self.token = protocol.check_token(token)
        self.move_time = nonnegative_float("move_time", move_time)
        self.faults = faults or Faults()
        self.pose = initial_pose or source.limits.clip(Pose(0.0, 0.0, 0.0))
        self.n_commands = 0
        """Commands received so far (all connections)."""
        self.n_acquisitions = 0
        """``ACQ?`` commands received so far."""
        self._lock = threading.Lock()
        self._gone = False
        self._fired: set[str] = set()
        super().__init__(host=host, port=port)

    def open_session(self) -> dict[str, bool]:
        """A connection's state: whether it has authenticated (always, without a token)."""
        return {"authenticated": self.token is None}

    def answer(self, raw: bytes, session: dict[str, bool]) -> tuple[bytes, bool]:
        """The reply to one command line (the first line of a connection must be
        ``AUTH <token>`` when the server has a token), and whether to close after it."""
        if self._gone:
            return b"", True
        if len(raw) > protocol.MAX_LINE_BYTES:  # the rest of it would parse as commands
            return _err("SYNTAX", "command line is too long"), True
        if not session["authenticated"]:  # the first line must be AUTH <token>: else goodbye
            session["authenticated"] = self._authenticate(raw)
            if not session["authenticated"]:
                return _err(AUTH_CODE, "this instrument needs its token first: AUTH <token>"), True
            return protocol.encode_line("OK"), False
        reply = self._dispatch(raw)
        if reply is None:  # injected drop
            return b"", True
        lines, delay, close_after = reply
        if delay:
            time.sleep(delay)
        return b"".join(lines), close_after

    def _authenticate(self, raw: bytes) -> bool:
        """Whether ``raw`` is ``AUTH <token>`` with this server's token (constant time)."""
        name, _, given = raw.decode(protocol.ENCODING, errors="replace").strip().partition(" ")
        assert self.token is not None
        return name == "AUTH" and hmac.compare_digest(given.encode(), self.token.encode())

    # -- command execution ------------------------------------------------------------------
    def _once(self, name: str, due: bool) -> bool:
        if due and name not in self._fired:
            self._fired.add(name)
            return True
        return False

    def _dispatch(self, raw: bytes) -> tuple[list[bytes], float, bool] | None:
        """Execute one command line: (reply lines, delay [s], close after) or None to drop."""
        with self._lock:
            self.n_commands += 1
            f = self.faults
            if self._once("drop", f.drop_after is not None and self.n_commands > f.drop_after):
                self._gone = f.drop_forever
                return None
            try:
                text = raw.decode(protocol.ENCODING).strip()
            except UnicodeDecodeError:
                return [_err("SYNTAX", "command is not UTF-8 text")], 0.0, False
            name, _, args = text.partition(" ")
            handler = self._COMMANDS.get(name)
            if handler is None:
                return (
                    [
                        _err(
                            "SYNTAX",
                            f"unknown command {name!r}; known: {' '.join(protocol.COMMANDS)}",
                        )
                    ],
                    0.0,
                    False,
                )
            try:
                return handler(self, args)
            except LimitError as exc:
                return [_err("LIMIT", str(exc))], 0.0, False
            except protocol.ProtocolError as exc:
                return [_err("SYNTAX", str(exc))], 0.0, False
            except Exception as exc:  # the instrument failed: say so, and keep serving
                # (unanswered, the client would time out and resend the failing command)
                return [_err("FAULT", f"{type(exc).__name__}: {exc}")], 0.0, False

    def _idn(self, args: str) -> tuple[list[bytes], float, bool]:
        description = " ".join(self.source.description.split())
        return [protocol.encode_line(f"echocal,instrument-server,{description}")], 0.0, False

    def _move(self, args: str) -> tuple[list[bytes], float, bool]:
        pose = protocol.decode_pose(args, "MOVE arguments")
        self.source.limits.check(pose)
        if self.move_time:
            time.sleep(self.move_time)
        self.pose = pose
        return [protocol.encode_line("OK")], 0.0, False

    def _pos(self, args: str) -> tuple[list[bytes], float, bool]:
        return [protocol.encode_line(protocol.encode_pose(self.pose))], 0.0, False

    def _limits(self, args: str) -> tuple[list[bytes], float, bool]:
        return [protocol.encode_line(protocol.encode_limits(self.source.limits))], 0.0, False

    def _auth(self, args: str) -> tuple[list[bytes], float, bool]:
        return [protocol.encode_line("OK")], 0.0, False  # already authenticated (or no token)

    def _bye(self, args: str) -> tuple[list[bytes], float, bool]:
        return [protocol.encode_line("OK")], 0.0, True

    def _acq(self, args: str) -> tuple[list[bytes], float, bool]:
        self.n_acquisitions += 1
        k, f = self.n_acquisitions, self.faults
        ascan = self.source.measure(self.pose)
        header, payload = protocol.encode_ascan(ascan.samples, ascan.fs, ascan.start_time)
        if self._once("malformed", f.malformed_acquisition == k):
            header, payload = _garble(f.malformed_kind, header, payload, ascan.samples)
        delay = f.late_delay if self._once("late", f.late_acquisition == k) else 0.0
        return [protocol.encode_line(header), protocol.encode_line(payload)], delay, False

    _COMMANDS: ClassVar[dict[str, Callable[[Any, str], tuple[list[bytes], float, bool]]]] = {
        "*IDN?": _idn,
        "MOVE": _move,
        "POS?": _pos,
        "ACQ?": _acq,
        "LIMITS?": _limits,
        "BYE": _bye,
        "AUTH": _auth,
    }


def _err(code: str, message: str) -> bytes:
    return protocol.encode_line("ERR", code, " ".join(message.split()))


def _garble(kind: str, header: str, payload: str, samples: Any) -> tuple[str, str]:
    _, fs, start, n, crc = header.split()
    if kind == "count":
        return f"ASCAN {fs} {start} {int(n) + 1} {crc}", payload
    if kind == "number":
        return f"ASCAN fs=? {start} {n} {crc}", payload
    if kind == "base64":  # with the CRC of what is sent: the base64 check must catch it
        bad_payload = "!!not-base64!!" + payload[14:]
        crc = f"crc32={zlib.crc32(bad_payload.encode('ascii')):08x}"
        return f"ASCAN {fs} {start} {n} {crc}", bad_payload
    if kind == "nan":
        bad = samples.copy()
        bad[len(bad) // 2] = float("nan")
        return protocol.encode_ascan(bad, float(fs), float(start))  # a valid CRC of NaNs
    return "HELLO 42", payload  # "reply": an unknown reply


def serve_forever(
    source: MeasurementSource,
    host: str = "127.0.0.1",
    port: int = 5025,
    move_time: float = 0.0,
    *,
    on_ready: Callable[[tuple[str, int]], None] | None = None,
    token: str | None = None,
) -> None:
    """Serve ``source`` on ``host:port`` until interrupted (Ctrl-C); for the CLI.

    ``on_ready(address)`` is called once the socket listens (e.g. to print the address).
    Port 5025 is the customary port of SCPI instruments.
    """
    server = InstrumentServer(source, host=host, port=port, move_time=move_time, token=token)
    if on_ready is not None:
        on_ready(server.address)
    with contextlib.suppress(KeyboardInterrupt):
        server.serve_forever()
