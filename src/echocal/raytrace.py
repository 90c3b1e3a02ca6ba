"""Closest-hit casting of a ray bundle against a specimen.

:func:`cast` is the one entry point: rays with any leading batch axes
``(..., N, 3)`` go in, a :class:`Hits` of the same batch shape comes out.
It is vectorized over rays; the only Python loop runs over the (few) shapes.
``cast`` validates and normalizes its input; the simulator, whose rays are valid
by construction, calls the unchecked structure-of-arrays kernel ``_cast_soa``.

The code lives in :mod:`echocal.specimen.casting`, beside the shapes it casts against, so
that imports run one way: this module (and the simulator) import the specimen package,
never the reverse.
"""

from __future__ import annotations

from echocal.specimen.casting import Hits, cast

__all__ = ["Hits", "cast"]
