"""An on-disk cache of lobe profiles (:func:`~echocal.measurement.detection_radius.lobe_profile`).

A lobe profile is a few hundred noiseless A-scans of the probe tilted away from its best
direction of normal incidence (2–50 s on the wave model); it depends only on the setup's
physics (specimen, probe, pulse, window, medium, model), the position and the profile's
own constants, so its four arrays can be kept between processes like the detector's
calibration (:mod:`echocal.signal.detector_cache`): every ``echocal calibrate`` of the
same setup otherwise paid for it again.

Files live in the same folder as the detector cache (``$ECHOCAL_CACHE_DIR``, else
``$XDG_CACHE_HOME/echocal``, else ``~/.cache/echocal``), one ``.npz`` per key (a SHA-256
of the pickled physics objects, the position, the constants and the digest of echocal's
source code, ``echocal._code_digest.code_digest``),
written atomically.  A physics object that cannot be pickled is not cached; a missing,
unreadable, damaged or inconsistent file is a miss; a folder that cannot be written is
skipped: the cache can only save time, never change a result.
"""

from __future__ import annotations

import hashlib
import io
import pickle
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from echocal.signal.detector_cache import cache_dir

__all__ = ["load", "profile_key", "store"]

_ARRAYS = ("angles", "peaks", "reference", "energies", "centre")
"""The arrays a profile is made of (:class:`~echocal.measurement.detection_radius.LobeProfile`)."""


def profile_key(
    parts: tuple[Any, ...], position: np.ndarray, constants: dict[str, Any]
) -> str | None:
    """SHA-256 of the physics objects ``parts`` (pickled), ``position`` [m] (3,), the
    profile's ``constants`` and the package's source code; None when an object cannot be
    pickled (it is then not cached)."""
    from echocal._code_digest import code_digest

    try:
        physics = pickle.dumps(parts, protocol=5)
    except Exception:  # whatever an object's pickling raises: no cache
        return None
    digest = hashlib.sha256(physics)
    digest.update(np.ascontiguousarray(position, dtype=np.float64).tobytes())
    digest.update(repr(sorted(constants.items())).encode())
    digest.update(code_digest().encode())
    return digest.hexdigest()


def _path(key: str) -> Path:
    return cache_dir() / f"lobe-{key}.npz"


def load(key: str) -> dict[str, np.ndarray] | None:
    """The cached arrays of ``key`` (``angles``, ``peaks``, ``reference``, ``energies``,
    ``centre``), or None (a miss, or a damaged or inconsistent file)."""
    try:
        with np.load(_path(key), allow_pickle=False) as data:
            if str(data["key"]) != key:
                return None
            arrays = {name: np.array(data[name], dtype=np.float64) for name in _ARRAYS}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None
    angles, peaks, energies = arrays["angles"], arrays["peaks"], arrays["energies"]
    if angles.ndim != 1 or peaks.ndim != 2 or peaks.shape != energies.shape:
        return None
    if peaks.shape[1] != angles.size or arrays["reference"].ndim != 1:
        return None
    if arrays["centre"].shape != (2,):
        return None
    if not all(np.all(np.isfinite(a)) for a in arrays.values()):
        return None
    return arrays


def store(key: str, arrays: dict[str, np.ndarray]) -> None:
    """Keep ``arrays`` (those :func:`load` returns) under ``key``; silently skipped when
    the folder cannot be written."""
    from echocal.io import atomic_write_bytes

    buffer = io.BytesIO()
    payload: dict[str, Any] = {"key": np.array(key)} | {name: arrays[name] for name in _ARRAYS}
    np.savez(buffer, **payload)
    try:
        cache_dir().mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(_path(key), buffer.getvalue())
    except OSError:
        return
