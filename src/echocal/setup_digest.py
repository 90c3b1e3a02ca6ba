"""The digest of a setup's resolved content, for provenance records.

Kept out of :mod:`echocal.provenance` (a low floor that every writer imports) because it
loads setups, which import most of the package.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from echocal.setups import load_setup_config
from echocal.setups.reading import resolved_data

__all__ = ["setup_digest"]


def setup_digest(setup: str) -> dict[str, str]:
    """``{"name": setup, "sha256": …}``: the digest of the setup's *resolved* content (its
    validated configuration in SI units, as JSON with sorted keys) — the same for a
    built-in name and a copy of its file, different as soon as any value differs."""
    config, _ = load_setup_config(setup)
    text = json.dumps(resolved_data(config), sort_keys=True)
    name = str(Path(setup).resolve()) if Path(setup).is_file() else setup
    return {"name": name, "sha256": hashlib.sha256(text.encode()).hexdigest()}
