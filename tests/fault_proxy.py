"""A fault-injecting TCP proxy on 127.0.0.1 for tests (shared helper, not a test module).

``FaultProxy(upstream)`` listens on a free loopback port and forwards every connection to
``upstream`` (host, port).  The instrument's replies pass line by line; the ``at``-th reply
line (1-based, counted over every connection) is hit by the chosen fault, once:

* ``drop``     — the connection is closed instead of forwarding the line;
* ``delay``    — the line is held ``delay`` seconds (longer than the client's timeout);
* ``garble``   — bytes in the middle of the line are changed (printable, so the line still
  looks like a line: only a checksum can tell);
* ``truncate`` — only the first half of the line is sent, then the connection is closed.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time

FAULTS = ("drop", "delay", "garble", "truncate")


class FaultProxy:
    """Forward TCP connections to ``upstream``, injecting one fault (see module docstring)."""

    def __init__(self, upstream: tuple[str, int], fault: str, at: int, delay: float = 1.0) -> None:
        assert fault in FAULTS, fault
        self.upstream, self.fault, self.at, self.delay = upstream, fault, at, delay
        self.lines = 0  # reply lines seen (all connections)
        self.fired = False
        self.connections = 0
        self._lock = threading.Lock()
        self._listener = socket.create_server(("127.0.0.1", 0))
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._sockets: list[socket.socket] = []

    @property
    def address(self) -> tuple[str, int]:
        host, port = self._listener.getsockname()[:2]
        return str(host), int(port)

    def __enter__(self) -> FaultProxy:
        self._spawn(self._accept)
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        with contextlib.suppress(OSError):
            self._listener.close()
        for sock in self._sockets:
            with contextlib.suppress(OSError):
                sock.close()

    def _spawn(self, target, *args) -> None:
        thread = threading.Thread(target=target, args=args, daemon=True)
        thread.start()
        self._threads.append(thread)

    def _accept(self) -> None:
        self._listener.settimeout(0.1)
        while not self._stop.is_set():
            try:
                client, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            server = socket.create_connection(self.upstream)
            self._sockets += [client, server]
            self.connections += 1
            self._spawn(self._pump_up, client, server)
            self._spawn(self._pump_down, server, client)

    @staticmethod
    def _pump_up(client: socket.socket, server: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := client.recv(65536):
                server.sendall(data)
        with contextlib.suppress(OSError):
            server.shutdown(socket.SHUT_WR)

    def _hit(self) -> bool:
        with self._lock:
            self.lines += 1
            if not self.fired and self.lines == self.at:
                self.fired = True
                return True
            return False

    def _pump_down(self, server: socket.socket, client: socket.socket) -> None:
        reader = server.makefile("rb")
        try:
            while line := reader.readline():
                if self._hit():
                    if self.fault == "drop":
                        break
                    if self.fault == "delay":
                        time.sleep(self.delay)
                    elif self.fault == "garble":
                        middle = len(line) // 2
                        swap = b"A" if line[middle : middle + 1] != b"A" else b"B"
                        line = line[:middle] + swap * 4 + line[middle + 4 :]
                    elif self.fault == "truncate":
                        client.sendall(line[: len(line) // 2])
                        break
                client.sendall(line)
        except OSError:
            pass
        for sock in (client, server):
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                sock.close()
