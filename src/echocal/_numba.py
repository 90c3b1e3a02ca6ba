"""Lazy numba (the package's ``fast`` extra): compile a plain-Python kernel on first use.

Kernels are written as plain Python loops over numpy arrays and compiled with
``numba.njit(cache=True, nogil=True)`` the first time they are needed; without numba (or
with :data:`USE_NUMBA` set False, as the tests do to check the fallbacks) :func:`compiled`
returns None and the caller takes its numpy path, which gives the same results to
round-off.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from functools import cache
from typing import Any

__all__ = ["HAVE_NUMBA", "USE_NUMBA", "compiled"]

HAVE_NUMBA = importlib.util.find_spec("numba") is not None
"""Whether numba is installed; it is imported only when a kernel is first compiled."""

USE_NUMBA = HAVE_NUMBA
"""Use compiled kernels (set False to force the numpy fallbacks)."""


@cache
def _njit(func: Callable[..., Any]) -> Callable[..., Any] | None:
    try:
        from numba import njit
    except ImportError:  # pragma: no cover - depends on the environment
        return None
    return njit(cache=True, nogil=True)(func)


def compiled(func: Callable[..., Any]) -> Callable[..., Any] | None:
    """The numba-compiled ``func`` (compiled once, cached on disk), or None without numba."""
    if not (USE_NUMBA and HAVE_NUMBA):
        return None
    return _njit(func)
