"""One VISA resource behind echocal's fault policy (PyVISA, ``visa`` extra).

:class:`VisaInstrument` opens a PyVISA message-based resource lazily and wraps
``write``, ``query`` and ``query_binary_values`` with the fault policy of
:class:`echocal.measurement.hardware.TcpInstrument`:

* **Transport faults** — a VISA timeout, a lost connection, an I/O error, a
  resource that cannot be opened — are retried: the resource is closed and opened
  again (so a late answer is never read as the next one's), the client waits
  ``backoff * 2**k`` [s] and sends the same command again, up to ``retries`` more
  times.  Every command echocal sends is idempotent (moves are
  absolute, settings are set, queries only ask).  When the retries are used up
  :class:`~echocal.errors.InstrumentError` names the resource, the command and
  the last fault in one line.
* **Nonsense** — a garbled binary block, a number that does not parse, a reply of
  the wrong shape, no answer at all — is not retried: the resource is closed (and
  opened again by the next command) and ``InstrumentError`` is raised at once,
  naming the command.

PyVISA is imported on first use; without it the error names the ``visa`` extra.
"""

from __future__ import annotations

import contextlib
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from echocal._validate import nonnegative_float, positive_float
from echocal.errors import EchocalValueError, InstrumentError

__all__ = ["Nonsense", "VisaInstrument", "import_pyvisa", "resource_manager"]

_RESOURCE_MANAGERS: dict[str, Any] = {}


class Nonsense(InstrumentError):
    """A reply that does not parse (raised by the drivers' parsers; never retried)."""


def import_pyvisa() -> Any:
    """The ``pyvisa`` module, or an error naming the extra to install."""
    try:
        import pyvisa
    except ImportError:
        raise InstrumentError(
            "VISA instruments need PyVISA: pip install 'echocal[visa]' "
            "(pyvisa, pyvisa-py, pyvisa-sim)"
        ) from None
    return pyvisa


def resource_manager(library: str = "") -> Any:
    """A shared :class:`pyvisa.ResourceManager` for ``library``.

    ``library`` is PyVISA's: ``""`` (the system's VISA, else pyvisa-py), ``"@py"``
    (pyvisa-py), ``"@sim"`` (pyvisa-sim's default devices) or ``"FILE.yaml@sim"``
    (simulated devices defined in a YAML file).
    """
    pyvisa = import_pyvisa()
    if library not in _RESOURCE_MANAGERS:
        try:
            _RESOURCE_MANAGERS[library] = pyvisa.ResourceManager(library)
        except (OSError, ValueError, pyvisa.errors.Error) as exc:
            what = "" if not library else f" {library!r}"
            hint = (
                " (install the simulator: pip install 'echocal[visa]')"
                if library.endswith("@sim")
                else ""
            )
            raise InstrumentError(
                f"cannot load the VISA library{what}: {_one_line(exc)}{hint}"
            ) from None
    return _RESOURCE_MANAGERS[library]


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


class VisaInstrument:
    """One VISA resource with retries, timeouts and one-line errors.

    Parameters
    ----------
    resource : the VISA resource name, e.g. ``"TCPIP0::192.168.1.20::INSTR"``.
    library : PyVISA's library string (see :func:`resource_manager`).
    timeout : [s] for each reply (> 0).
    retries : how many times a command is sent again after a transport fault (>= 0).
    backoff : [s] wait before the first retry; doubled for each further retry (>= 0).
    read_termination, write_termination : line endings of the instrument's messages.
    baud_rate : [bit/s] of a serial line (ASRL resources); None leaves the VISA default.
    """

    def __init__(
        self,
        resource: str,
        *,
        library: str = "",
        timeout: float = 2.0,
        retries: int = 2,
        backoff: float = 0.05,
        read_termination: str = "\n",
        write_termination: str = "\n",
        baud_rate: int | None = None,
    ) -> None:
        if not isinstance(resource, str) or not resource.strip():
            raise EchocalValueError(f"resource must be a VISA resource name; got {resource!r}")
        self.resource = resource.strip()
        self.library = library
        self.timeout = positive_float("timeout", timeout)
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise EchocalValueError(f"retries must be an integer >= 0; got {retries!r}")
        self.retries = retries
        self.backoff = nonnegative_float("backoff", backoff)
        self.read_termination = read_termination
        self.write_termination = write_termination
        self.baud_rate = baud_rate
        self._handle: Any = None
        self._closed = False
        self.n_reconnects = 0
        """How many times a command was sent again after a transport fault."""

    # -- connection -------------------------------------------------------------------------
    def _open(self) -> Any:
        if self._closed:
            raise InstrumentError(f"VISA resource {self.resource} is closed")
        if self._handle is None:
            handle = resource_manager(self.library).open_resource(
                self.resource, open_timeout=int(self.timeout * 1e3)
            )
            handle.timeout = self.timeout * 1e3  # PyVISA counts milliseconds
            handle.read_termination = self.read_termination
            handle.write_termination = self.write_termination
            if self.baud_rate is not None:  # a serial line (ASRL resources)
                handle.baud_rate = int(self.baud_rate)
            self._handle = handle
        return self._handle

    def _drop(self) -> None:
        if self._handle is not None:
            with contextlib.suppress(Exception):
                self._handle.close()
        self._handle = None

    def close(self) -> None:
        """Close the resource; later commands raise ``InstrumentError``."""
        self._drop()
        self._closed = True

    # -- exchange ---------------------------------------------------------------------------
    def call(self, command: str, action: Callable[[Any], Any]) -> Any:
        """Run ``action(resource)`` for ``command`` under the fault policy."""
        pyvisa = import_pyvisa()
        last: BaseException | None = None
        for attempt in range(self.retries + 1):
            if attempt:
                time.sleep(self.backoff * 2 ** (attempt - 1))
                self.n_reconnects += 1
            try:
                return action(self._open())
            except InstrumentError as exc:
                if self._closed:
                    raise
                self._drop()
                if isinstance(exc, Nonsense):
                    raise InstrumentError(
                        f"{command}: VISA resource {self.resource} answered nonsense: {exc}"
                    ) from None
                raise
            except (ValueError, TypeError, pyvisa.errors.InvalidBinaryFormat) as exc:
                self._drop()
                raise InstrumentError(
                    f"{command}: VISA resource {self.resource} answered nonsense: {_one_line(exc)}"
                ) from None
            except (pyvisa.errors.VisaIOError, OSError) as exc:  # transport: retry
                self._drop()
                last = exc
        timed_out = isinstance(last, pyvisa.errors.VisaIOError) and (
            last.error_code == pyvisa.constants.StatusCode.error_timeout
        )
        reason = "timed out" if timed_out else _one_line(last) if last else "?"
        raise InstrumentError(
            f"{command}: VISA resource {self.resource} failed after {self.retries + 1} "
            f"attempts (last: {reason})"
        )

    def write(self, command: str) -> None:
        """Send one command (no answer expected)."""
        self.call(command, lambda r: r.write(command))

    def query(self, command: str) -> str:
        """Send ``command`` and return its one-line answer, stripped."""
        return self.call(command, lambda r: _answer(r, command))

    def query_float(self, command: str) -> float:
        """Send ``command`` and parse its answer as one finite number."""
        return self.call(command, lambda r: parse_float(_answer(r, command), command))

    def query_block(self, command: str, datatype: str, big_endian: bool) -> np.ndarray:
        """Send ``command`` and read an IEEE 488.2 definite-length binary block of
        ``datatype`` (a :mod:`struct` code: ``b``, ``B``, ``h``, ``H``, ``f``, ...)."""

        def read(r: Any) -> np.ndarray:
            values = r.query_binary_values(
                command,
                datatype=datatype,
                is_big_endian=big_endian,
                container=np.array,
                header_fmt="ieee",
                expect_termination=True,
            )
            return np.asarray(values, dtype=np.float64)

        return self.call(command, read)

    def identify(self) -> str:
        """The ``*IDN?`` answer."""
        return self.query("*IDN?")


def _answer(resource: Any, command: str) -> str:
    """The stripped one-line answer to ``command``; :class:`Nonsense` when empty (what a
    resource that is not there answers on some VISA libraries)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "doesn't end with termination"
        text = str(resource.query(command)).strip()
    if not text:
        raise Nonsense("no answer (is the instrument at this resource name?)")
    return text


def parse_float(text: str, what: str) -> float:
    """One finite number from ``text`` (an instrument's answer); :class:`Nonsense` otherwise."""
    try:
        value = float(text.strip().strip('"'))
    except ValueError:
        raise Nonsense(f"{what}: {text.strip()[:40]!r} is not a number") from None
    if not np.isfinite(value):
        raise Nonsense(f"{what}: {text.strip()!r} is not a finite number")
    return value
