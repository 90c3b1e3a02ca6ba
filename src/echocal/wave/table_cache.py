"""Echo-table nodes kept on disk between processes (``echocal.wave.echo_table``).

A table's node is the exact form at one point of its grid: it depends only on what the
table's owner says it depends on (the probe, the pulse's spectrum on the time grid's bins,
the sound speed, the grid's axes; see ``echocal.wave.plane_table``) and on the package's
code, so it can be kept between processes: a Monte-Carlo study, a sweep's workers or the
next ``echocal calibrate`` read the nodes an earlier run computed.

Like ``echocal.signal.detector_cache`` (and in its folder: ``$ECHOCAL_CACHE_DIR``, else
``$XDG_CACHE_HOME/echocal``, else ``~/.cache/echocal``; here its ``tables`` subfolder), each
node is one small ``.npy`` file named by a SHA-256 of the table's identity, the package's
source code (``echocal._code_digest.code_digest``) and the node's indices, written
atomically, so that parallel workers never clash (the same node written twice is the same
bytes).  A missing, unreadable or damaged file is a miss; a folder that cannot be written
is skipped: the cache can only save time, never change a result.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.signal.detector_cache import cache_dir

__all__ = ["DiskNodes", "array_digest"]


class DiskNodes:
    """The on-disk store of one table's nodes (``EchoTable``'s ``store``).

    Parameters
    ----------
    name : the table's kind, the files' prefix (``plane``, say).
    identity : everything a node's value depends on besides its indices and the code
        (JSON-ready values; arrays by their digest).
    """

    def __init__(self, name: str, identity: dict[str, Any]) -> None:
        from echocal._code_digest import code_digest

        text = json.dumps(
            {"table": name, "identity": identity, "code": code_digest()},
            sort_keys=True,
            default=str,
        )
        self._name = name
        self._digest = hashlib.sha256(text.encode()).hexdigest()

    def _path(self, i: int, j: int) -> Path:
        key = hashlib.sha256(f"{self._digest}:{i}:{j}".encode()).hexdigest()
        return cache_dir() / "tables" / f"{self._name}-{key}.npy"

    def load(self, i: int, j: int, size: int) -> tuple[NDArray[np.complex128], float] | None:
        """Node (i, j)'s kept bins ``(size,)`` and side value, or None (a miss, or a file
        of the wrong shape, type or with non-finite values)."""
        try:
            data = np.load(self._path(i, j), allow_pickle=False)
        except (OSError, ValueError, EOFError):
            return None
        if data.dtype != np.complex128 or data.shape != (size + 1,):
            return None
        if not np.all(np.isfinite(data)):
            return None
        return np.ascontiguousarray(data[:size]), float(data[size].real)

    def save(self, i: int, j: int, spectrum: NDArray[np.complex128], side: float) -> None:
        """Keep node (i, j): its kept bins and side value (the last element); silently
        skipped when the folder cannot be written."""
        from echocal.io import atomic_write_bytes

        buffer = io.BytesIO()
        np.save(buffer, np.append(spectrum, complex(side)).astype(np.complex128))
        path = self._path(i, j)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(path, buffer.getvalue())
        except OSError:
            return


def array_digest(values: NDArray[Any]) -> str:
    """SHA-256 (hex) of an array's bytes, for a table's identity."""
    return hashlib.sha256(np.ascontiguousarray(values).tobytes()).hexdigest()
