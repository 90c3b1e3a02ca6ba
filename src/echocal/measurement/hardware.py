"""Real hardware behind the measurement interface: a positioner and a receiver.

Two small interfaces describe a rig:

* :class:`Positioner` — ``move_to(pose) -> Pose`` (the pose reached) and
  ``position() -> Pose``, plus its ``limits``;
* :class:`Receiver` — ``acquire() -> AScan`` (samples, fs, start time; no pose).

:class:`HardwareSource` composes one of each into a
:class:`~echocal.measurement.base.MeasurementSource`.  :class:`TcpInstrument`
speaks the line protocol of :mod:`echocal.measurement.protocol` over TCP, and
:class:`TcpPositioner` / :class:`TcpReceiver` share one such connection.

Fault policy of :class:`TcpInstrument` (what "raise or retry" means here):

* **Transport faults** — connection refused, reset or closed by the instrument,
  or no complete answer within ``timeout`` [s] — are retried: the connection
  is closed, the client waits ``backoff * 2**k`` [s] (k = 0, 1, ...), reconnects
  and sends the same command again, up to ``retries`` more times.  Every
  command of the protocol is idempotent (``MOVE`` is absolute), so a repeat is
  safe.  When the retries are used up :class:`~echocal.errors.InstrumentError`
  names the command and the last fault.
* **Nonsense** — a malformed number, a wrong sample count, a payload that is not
  base64, an unknown reply — is not retried: the connection is reset (so no
  stale bytes are read by the next command) and ``InstrumentError`` is raised
  at once, naming the command.  The caller decides whether to measure again.
* ``ERR LIMIT ...`` raises :class:`~echocal.errors.LimitError`; any other
  ``ERR`` raises ``InstrumentError`` with the instrument's message.

A fault never changes what was returned before: A-scans are immutable, and the
source holds no partial state between ``move_to`` and ``acquire``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import socket
import time
from collections.abc import Callable
from typing import Protocol, TypeVar, runtime_checkable

from echocal._signals import checkpoint
from echocal._validate import capped_float, nonnegative_float
from echocal.ascan import AScan
from echocal.errors import EchocalValueError, InstrumentError, LimitError
from echocal.geometry import Pose
from echocal.measurement import protocol
from echocal.measurement.base import BaseSource
from echocal.measurement.limits import PositionerLimits

__all__ = [
    "HardwareSource",
    "Positioner",
    "Receiver",
    "TcpInstrument",
    "TcpPositioner",
    "TcpReceiver",
]

T = TypeVar("T")


@runtime_checkable
class Positioner(Protocol):
    """Moves the transducer.  Poses in [m] and [deg]."""

    @property
    def limits(self) -> PositionerLimits:
        """The reachable poses."""
        ...

    def move_to(self, pose: Pose) -> Pose:
        """Move to ``pose`` and return the pose actually reached (after the move is done)."""
        ...

    def position(self) -> Pose:
        """The current pose."""
        ...

    def close(self) -> None:
        """Release the device."""
        ...


@runtime_checkable
class Receiver(Protocol):
    """Fires the transducer and records one A-scan."""

    def acquire(self) -> AScan:
        """Return one A-scan (samples, ``fs`` [Hz], ``start_time`` [s]; ``pose`` is None)."""
        ...

    def close(self) -> None:
        """Release the device."""
        ...


class _LineReader:
    """Reads ``\\n``-terminated lines from a socket, raising on EOF and on overlong lines."""

    def __init__(self, sock: socket.socket) -> None:
        self._file = sock.makefile("rb")

    def readline(self) -> str:
        line = self._file.readline(protocol.MAX_LINE_BYTES + 1)
        if not line:
            raise ConnectionError("connection closed by the instrument")
        if not line.endswith(b"\n"):
            if len(line) > protocol.MAX_LINE_BYTES:
                raise protocol.ProtocolError("reply line is too long")
            raise ConnectionError("connection closed in the middle of a reply")
        try:
            return line.decode(protocol.ENCODING).rstrip("\r\n")
        except UnicodeDecodeError:
            raise protocol.ProtocolError("reply is not UTF-8 text") from None

    def close(self) -> None:
        self._file.close()


MAX_TIMEOUT = 600.0
"""[s] the longest wait allowed for one reply (a move included): a larger timeout would
leave a dead rig unnoticed for hours."""
_TIMEOUT_WHY = "s (the longest one reply may take, a move included; a dead rig must be noticed)"


class TcpInstrument:
    """One TCP connection to an instrument speaking the echocal line protocol.

    Parameters
    ----------
    host, port : the instrument's address.
    timeout : [s] for connecting and for each complete reply (> 0).
    retries : how many times a command is sent again after a transport fault (>= 0).
    backoff : [s] wait before the first retry; doubled for each further retry (>= 0).
    token : the instrument's shared secret: sent as ``AUTH <token>`` on every (re)connection;
        a refusal raises :class:`~echocal.errors.InstrumentError` at once (no retry).

    The connection is opened lazily by the first command and re-opened after a fault.
    See the module docstring for the fault policy.
    """

    def __init__(
        self,
        host: str,
        port: int,
        *,
        timeout: float = 2.0,
        retries: int = 3,
        backoff: float = 0.05,
        token: str | None = None,
    ) -> None:
        self.token = protocol.check_token(token)
        self.host = str(host)
        self.port = int(port)
        self.timeout = capped_float("timeout", timeout, MAX_TIMEOUT, _TIMEOUT_WHY)
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise EchocalValueError(f"retries must be an integer >= 0; got {retries!r}")
        self.retries = retries
        self.backoff = nonnegative_float("backoff", backoff)
        self._sock: socket.socket | None = None
        self._reader: _LineReader | None = None
        self._closed = False
        self.n_reconnects = 0
        """How many times the connection was re-opened after a fault."""

    @property
    def address(self) -> str:
        """``host:port``."""
        return f"{self.host}:{self.port}"

    # -- connection -------------------------------------------------------------------------
    def _connect(self) -> _LineReader:
        if self._closed:
            raise InstrumentError(f"connection to instrument at {self.address} is closed")
        if self._reader is None:
            sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
            sock.settimeout(self.timeout)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._sock, self._reader = sock, _LineReader(sock)
            if self.token is not None:
                sock.sendall(protocol.encode_line(f"AUTH {self.token}"))
                reply = self._reader.readline()
                if reply != "OK":
                    _check_err(reply)  # ERR AUTH: refused
                    raise _AuthRefused(f"answered {reply[:60]!r} to AUTH (no token expected?)")
        return self._reader

    def _drop(self) -> None:
        if self._reader is not None:
            with contextlib.suppress(OSError):
                self._reader.close()
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
        self._sock, self._reader = None, None

    def close(self) -> None:
        """Say ``BYE`` (best effort) and close; later commands raise ``InstrumentError``."""
        if self._closed:
            return
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.sendall(protocol.encode_line("BYE"))
        self._drop()
        self._closed = True

    # -- exchange ---------------------------------------------------------------------------
    def request(self, command: str, parse: Callable[[_LineReader], T]) -> T:
        """Send ``command``, parse the reply with ``parse(reader)``; applies the fault policy."""
        name = command.split(" ", 1)[0]
        line = protocol.encode_line(command)
        last: BaseException | None = None
        for attempt in range(self.retries + 1):
            if attempt:
                time.sleep(self.backoff * 2 ** (attempt - 1))
                self.n_reconnects += 1
            try:
                reader = self._connect()
                assert self._sock is not None
                self._sock.sendall(line)
                return parse(reader)
            except LimitError:
                raise
            except _AuthRefused as exc:  # a wrong token stays wrong: no retry
                self._drop()
                raise InstrumentError(f"{name}: instrument at {self.address} {exc}") from None
            except _InstrumentReported as exc:  # ERR reply: the connection is still in step
                raise InstrumentError(f"{name}: instrument at {self.address} {exc}") from None
            except InstrumentError as exc:  # nonsense (ProtocolError): reset, no retry
                self._drop()
                if self._closed:
                    raise
                raise InstrumentError(
                    f"{name}: instrument at {self.address} answered nonsense: {exc}"
                ) from None
            except (TimeoutError, OSError) as exc:  # transport fault: retry
                self._drop()
                last = exc
        reason = "timed out" if isinstance(last, TimeoutError) else f"{last}"
        raise InstrumentError(
            f"{name}: instrument at {self.address} failed after {self.retries + 1} attempts "
            f"(last: {reason or type(last).__name__})"
        )

    def query_line(self, command: str) -> str:
        """Send ``command`` and return its one-line reply (an ``ERR`` reply raises)."""
        return self.request(command, _one_line)

    def identify(self) -> str:
        """The ``*IDN?`` answer."""
        return self.query_line("*IDN?")


class _AuthRefused(InstrumentError):
    """The instrument refused the token (private; not retried)."""


class _InstrumentReported(InstrumentError):
    """The instrument answered ``ERR`` (private: re-raised as InstrumentError)."""


def _check_err(reply: str) -> str:
    if reply.startswith("ERR"):
        parts = reply.split(" ", 2)
        code = parts[1] if len(parts) > 1 else ""
        message = parts[2] if len(parts) > 2 else reply
        if code == "LIMIT":
            raise LimitError(f"instrument refused: {message}")
        if code == "AUTH":
            raise _AuthRefused(
                f"refused the connection: {message} (echocal: --token SECRET or "
                "$ECHOCAL_INSTRUMENT_TOKEN)"
            )
        raise _InstrumentReported(f"reported error {code or '?'}: {message}")
    return reply


def _one_line(reader: _LineReader) -> str:
    return _check_err(reader.readline())


def _ok(reader: _LineReader) -> None:
    reply = _check_err(reader.readline())
    if reply != "OK":
        raise protocol.ProtocolError(f"expected 'OK'; got {reply[:80]!r}")


def _ascan(reader: _LineReader) -> AScan:
    header = _check_err(reader.readline())
    fs, start, n = protocol.decode_ascan_header(header)
    samples = protocol.decode_samples(reader.readline(), n, crc=protocol.payload_crc(header))
    return AScan(samples=samples, fs=fs, start_time=start)


class TcpPositioner:
    """:class:`Positioner` over a :class:`TcpInstrument` (``MOVE``, ``POS?``, ``LIMITS?``)."""

    def __init__(self, instrument: TcpInstrument) -> None:
        self.instrument = instrument
        self._limits: PositionerLimits | None = None

    @property
    def limits(self) -> PositionerLimits:
        """Asked once with ``LIMITS?``, then cached."""
        if self._limits is None:
            self._limits = self.instrument.request(
                "LIMITS?", lambda r: protocol.decode_limits(_one_line(r))
            )
        return self._limits

    def move_to(self, pose: Pose) -> Pose:
        """``MOVE`` then ``POS?``; returns the pose reached."""
        self.instrument.request(f"MOVE {protocol.encode_pose(pose)}", _ok)
        return self.position()

    def position(self) -> Pose:
        """``POS?``."""
        return self.instrument.request(
            "POS?", lambda r: protocol.decode_pose(_one_line(r), "POS? reply")
        )

    def close(self) -> None:
        """Close the shared connection."""
        self.instrument.close()


class TcpReceiver:
    """:class:`Receiver` over a :class:`TcpInstrument` (``ACQ?``)."""

    def __init__(self, instrument: TcpInstrument) -> None:
        self.instrument = instrument

    def acquire(self) -> AScan:
        """``ACQ?``: header and base64 samples, checked for count and finiteness."""
        return self.instrument.request("ACQ?", _ascan)

    def close(self) -> None:
        """Close the shared connection."""
        self.instrument.close()


class HardwareSource(BaseSource):
    """A positioner and a receiver composed into a measurement source.

    ``measure(pose)`` checks ``pose`` against ``limits`` (raising
    :class:`~echocal.errors.LimitError` before anything moves), moves, waits
    ``settle_time`` [s], acquires, and returns the A-scan carrying the pose the
    positioner reports having reached, and in its metadata what the measurement cost,
    measured by the clock (:func:`time.perf_counter`): ``bench_time`` [s], the sum of
    ``motion_time``, ``settling_time`` and ``acquisition_time``.  Faults are those of the
    positioner and receiver (for TCP see :class:`TcpInstrument`); they propagate unchanged.

    Parameters
    ----------
    positioner, receiver : the two devices (may share one connection).
    limits : defaults to ``positioner.limits``.
    description : defaults to a line naming the two devices.
    settle_time : [s] wait after each move before acquiring (>= 0).
    """

    def __init__(
        self,
        positioner: Positioner,
        receiver: Receiver,
        *,
        limits: PositionerLimits | None = None,
        description: str | None = None,
        settle_time: float = 0.0,
    ) -> None:
        self.positioner = positioner
        self.receiver = receiver
        self.limits = positioner.limits if limits is None else limits
        self.description = description or (
            f"hardware: {type(positioner).__name__} + {type(receiver).__name__}"
        )
        self.settle_time = nonnegative_float("settle_time", settle_time)
        self.n_measurements = 0
        """A-scans returned so far."""
        self._closed = False

    @classmethod
    def connect(
        cls,
        host: str,
        port: int,
        *,
        timeout: float = 2.0,
        retries: int = 3,
        backoff: float = 0.05,
        settle_time: float = 0.0,
        token: str | None = None,
    ) -> HardwareSource:
        """Connect to an instrument speaking the echocal protocol (one shared TCP connection).

        Asks ``*IDN?`` (the description) and ``LIMITS?`` at once, so a wrong
        address (or ``token``) fails here with :class:`~echocal.errors.InstrumentError`.
        """
        instrument = TcpInstrument(
            host, port, timeout=timeout, retries=retries, backoff=backoff, token=token
        )
        try:
            idn = instrument.identify()
            positioner = TcpPositioner(instrument)
            limits = positioner.limits
        except BaseException:
            instrument.close()
            raise
        return cls(
            positioner,
            TcpReceiver(instrument),
            limits=limits,
            description=f"hardware at {instrument.address}: {idn}",
            settle_time=settle_time,
        )

    def measure(self, pose: Pose) -> AScan:
        """Move to ``pose``, acquire, and return the A-scan with the pose reached."""
        if self._closed:
            raise InstrumentError(f"{self.description}: source is closed")
        # every command's rig measurement passes here: a stop signal whose exception was
        # lost (in a finalizer) stops before the next move
        checkpoint()
        self.limits.check(pose)
        clock = [time.perf_counter()]
        reached = self.positioner.move_to(pose)
        clock.append(time.perf_counter())
        if self.settle_time:
            time.sleep(self.settle_time)
        clock.append(time.perf_counter())
        ascan = self.receiver.acquire()
        clock.append(time.perf_counter())
        self.n_measurements += 1
        metadata = {
            **ascan.metadata,
            "source": "hardware",
            "requested_pose": pose.as_array(),
            "bench_time": clock[3] - clock[0],
            "motion_time": clock[1] - clock[0],
            "settling_time": clock[2] - clock[1],
            "acquisition_time": clock[3] - clock[2],
        }
        return dataclasses.replace(ascan, pose=reached, metadata=metadata)

    def close(self) -> None:
        """Close both devices (once each, even if they share a connection)."""
        if self._closed:
            return
        self._closed = True
        self.positioner.close()
        if self.receiver is not self.positioner:
            self.receiver.close()
