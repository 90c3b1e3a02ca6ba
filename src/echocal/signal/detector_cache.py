"""A small on-disk cache of :class:`~echocal.signal.detection.EchoDetector` calibrations.

A detector's calibration (1,024 noise A-scans through the matched filter: about 0.1 s for
4,096 samples) depends only on the pulse, the sampling rate, the A-scan length and the
calibration's own constants, and it is seeded, so its two numbers can be kept between
processes: every ``echocal simulate`` otherwise paid for it again.

Files live in ``$ECHOCAL_CACHE_DIR``, else ``$XDG_CACHE_HOME/echocal``, else
``~/.cache/echocal``, one small JSON file per key (a SHA-256 of everything the numbers
depend on, the digest of the package's source code included), written atomically.  A
missing, unreadable or damaged file is a miss; a folder that cannot be written is skipped:
the cache can only save time, never change a result.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["cache_dir", "cache_key", "load", "store"]

CACHE_ENV = "ECHOCAL_CACHE_DIR"


def cache_dir() -> Path:
    """Where the cache files live (see the module docstring)."""
    given = os.environ.get(CACHE_ENV)
    if given:
        return Path(given)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "echocal"


def _digestible(value: Any) -> Any:
    """JSON-ready form of a pulse parameter (arrays by their bytes' digest)."""
    if isinstance(value, np.ndarray):
        return {"sha256": hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def cache_key(pulse: Any, fs: float, n_samples: int, constants: dict[str, Any]) -> str:
    """SHA-256 of the pulse (name and parameters), the sampling rate [Hz], the A-scan length,
    the calibration's ``constants`` and the package's source code
    (``echocal._code_digest.code_digest``)."""
    from echocal._code_digest import code_digest

    data = {
        "pulse": pulse.name,
        "parameters": {k: _digestible(v) for k, v in sorted(pulse.parameters().items())},
        "fs": float(fs),
        "n_samples": int(n_samples),
        "constants": constants,
        "code": code_digest(),
    }
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _path(key: str) -> Path:
    return cache_dir() / f"detector-{key}.json"


def load(key: str) -> tuple[float, float] | None:
    """The cached ``(noise_gain, n_cells)`` of ``key``, or None (a miss, or a damaged file)."""
    try:
        data = json.loads(_path(key).read_text(encoding="utf-8"))
        gain, cells = float(data["noise_gain"]), float(data["n_cells"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if data.get("key") != key or not (math.isfinite(gain) and math.isfinite(cells)):
        return None
    if gain <= 0.0 or cells <= 0.0:
        return None
    return gain, cells


def store(key: str, noise_gain: float, n_cells: float) -> None:
    """Keep ``(noise_gain, n_cells)`` under ``key``; silently skipped when the folder
    cannot be written."""
    from echocal.io import atomic_write_text

    text = json.dumps({"key": key, "noise_gain": noise_gain, "n_cells": n_cells})
    try:
        cache_dir().mkdir(parents=True, exist_ok=True)
        atomic_write_text(_path(key), text)
    except OSError:
        return
