"""A threaded TCP server of text lines: the scaffolding of echocal's emulated instruments.

:class:`LineServer` listens on ``host:port`` and serves each connection in its own
thread: it reads one line at a time (at most :attr:`LineServer.max_line` bytes) and
writes what :meth:`LineServer.answer` returns, until the client closes the connection
or ``answer`` says to close it.  It serves in a background thread
(:meth:`LineServer.start`, or as a context manager) or in the caller's
(:meth:`LineServer.serve_forever`); :meth:`LineServer.close` stops it and closes every
open connection.  Subclasses give the instrument: :meth:`LineServer.answer` and, for a
per-connection state (a login, say), :meth:`LineServer.open_session`.  The emulated rig
(:class:`~echocal.measurement.InstrumentServer`) and the simulated SCPI bench
(:class:`~echocal.rigs.scpi_bench.ScpiBench`) are line servers.
"""

from __future__ import annotations

import contextlib
import socket
import socketserver
import threading
from typing import Any, ClassVar, Self

__all__ = ["LineServer"]


class _Handler(socketserver.StreamRequestHandler):
    server: _TcpServer

    def handle(self) -> None:
        owner = self.server.owner
        owner._connections.add(self.request)
        try:
            session = owner.open_session()
            while True:
                raw = self.rfile.readline(owner.max_line + 1)
                if not raw:
                    return
                reply, close = owner.answer(raw, session)
                if reply:
                    self.wfile.write(reply)
                    self.wfile.flush()
                if close:
                    return
        except OSError:
            return
        finally:
            owner._connections.discard(self.request)
            with contextlib.suppress(OSError):
                self.request.shutdown(socket.SHUT_RDWR)


class _TcpServer(socketserver.ThreadingTCPServer):
    daemon_threads = True
    allow_reuse_address = True
    owner: LineServer


class LineServer:
    """A TCP server answering text lines, one thread per connection.

    Parameters
    ----------
    host, port : where to listen; ``port=0`` picks a free port (see :attr:`address`).
        The socket is bound when the object is made (an ``OSError`` if it cannot be).
    """

    max_line: ClassVar[int] = 4096
    """[bytes] the longest line read at once (a longer one arrives in pieces, and
    :meth:`answer` sees a piece of ``max_line + 1`` bytes, without its line end)."""
    thread_name: ClassVar[str] = "echocal-line-server"
    """The name of the background thread :meth:`start` runs."""
    poll_interval: ClassVar[float] = 0.05
    """[s] how often the serving loop looks for :meth:`close`."""

    def __init__(self, *, host: str, port: int) -> None:
        self._connections: set[socket.socket] = set()
        self._thread: threading.Thread | None = None
        self._server = _TcpServer((host, int(port)), _Handler, bind_and_activate=True)
        self._server.owner = self

    def open_session(self) -> Any:
        """The state of a new connection, handed to each :meth:`answer` on it (None)."""
        return None

    def answer(self, raw: bytes, session: Any) -> tuple[bytes, bool]:
        """(reply bytes, close the connection after them) for one line ``raw`` (with its
        line end) received on the connection of ``session``."""
        raise NotImplementedError

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) the server listens on."""
        host, port = self._server.server_address[:2]
        return str(host), int(port)

    def start(self) -> Self:
        """Serve in a daemon thread (once; a second call does nothing); returns self."""
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._server.serve_forever,
                kwargs={"poll_interval": self.poll_interval},
                name=self.thread_name,
                daemon=True,
            )
            self._thread.start()
        return self

    def serve_forever(self) -> None:
        """Serve in the calling thread until :meth:`close` or KeyboardInterrupt, then
        close the port."""
        try:
            self._server.serve_forever(poll_interval=self.poll_interval)
        finally:
            self._server.server_close()

    def close(self) -> None:
        """Stop serving, close the port and every open connection."""
        if self._thread is not None:
            self._server.shutdown()
            self._thread.join(timeout=5.0)
            self._thread = None
        self._server.server_close()
        for conn in list(self._connections):
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
