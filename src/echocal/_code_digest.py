"""The digest of echocal's own source code, for the on-disk caches' keys.

A cached lobe profile or detector calibration is valid only for the code that computed it;
the package version alone does not change when the physics does between releases (an
editable install, a branch).  :func:`code_digest` hashes every ``.py`` file of the installed
package (about 2 MB, read once per process), so any change of the code is a cache miss.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

__all__ = ["code_digest"]


@lru_cache(maxsize=1)
def code_digest() -> str:
    """SHA-256 (hex) of the package's ``.py`` files: their paths relative to the package and
    their bytes, in sorted order."""
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()
