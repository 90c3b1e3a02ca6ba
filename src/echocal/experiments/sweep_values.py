"""Seeds and option values of sweep runs: how each run's seeds derive from the sweep's,
the random start of an ``x0.offset`` run, and the frozen (hashable) form of option values
and its grid (see :mod:`echocal.experiments.sweep`)."""

from __future__ import annotations

import hashlib
import itertools
import json
from typing import Any

from echocal.experiments.sweep_schema import _as_list

__all__ = ["offset_start"]


def _x0_seed(sweep_seed: int, x0_index: int, seed: int) -> int:
    return _derive_seed(sweep_seed, f"x0/{x0_index}/seed={seed}")


def offset_start(x0_seed: int, offset: tuple[float, float], truth: Any) -> Any:
    """[deg] shape (2,): the random start of an ``x0.offset`` run, not clipped — a distance
    drawn uniformly from ``offset`` [deg] ``(lo, hi)`` in a uniform direction from ``truth``
    [deg] shape (2,), with the run's ``x0_seed``."""
    import numpy as np

    rng = np.random.default_rng(x0_seed)
    distance = rng.uniform(*offset)
    direction = rng.uniform(0.0, 2.0 * np.pi)
    return np.asarray(truth, dtype=np.float64) + distance * np.array(
        [np.cos(direction), np.sin(direction)]
    )


def _derive_seed(base: int, text: str) -> int:
    digest = hashlib.sha256(f"{base}|{text}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1  # 63 bits: fits int64 columns


def _num(value: float) -> str:
    return json.dumps(int(value) if float(value).is_integer() else float(value))


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _frozen(value: Any) -> Any:
    return tuple(_frozen(v) for v in value) if isinstance(value, list | tuple) else value


# ---------------------------------------------------------------- reading and checking
def _thawed(value: Any) -> Any:
    return [_thawed(v) for v in value] if isinstance(value, tuple) else value


def _grid(options: dict[str, Any]) -> list[tuple[tuple[str, Any], ...]]:
    keys = sorted(options)
    axes = [_as_list(options[k]) for k in keys]
    return [
        tuple((k, _frozen(v)) for k, v in zip(keys, combo, strict=True))
        for combo in itertools.product(*axes)
    ]
