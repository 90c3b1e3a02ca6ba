"""Random-number handling (private): one normalizer for every random API."""

from __future__ import annotations

import numpy as np

from echocal.errors import EchocalValueError

RngLike = np.random.Generator | int | None
"""Anything accepted as ``rng``: a Generator (used as is), a seed, or None (fresh entropy)."""


def as_generator(rng: RngLike) -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` for ``rng``.

    A Generator is returned unchanged (so the caller's stream advances); an int
    seeds a new PCG64 generator; ``None`` draws fresh OS entropy.
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None:
        return np.random.default_rng()
    if isinstance(rng, bool) or not isinstance(rng, int | np.integer):
        raise EchocalValueError(
            f"rng must be a numpy.random.Generator, an int seed or None; got {type(rng).__name__}"
        )
    if rng < 0:
        raise EchocalValueError(f"rng seed must be >= 0; got {rng}")
    return np.random.default_rng(int(rng))
