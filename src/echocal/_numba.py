"""Lazy numba (the package's ``fast`` extra): compile a plain-Python kernel on first use.

Kernels are written as plain Python loops over numpy arrays and compiled with
``numba.njit(cache=True, nogil=True)`` the first time they are needed; without numba (or
with :data:`USE_NUMBA` set False, as the tests do to check the fallbacks) :func:`compiled`
returns None and the caller takes its numpy path, which gives the same results to
round-off.

The compiled machine code is cached on disk: in a ``__pycache__`` folder beside the
source when that is writable, else in numba's per-user cache folder (``NUMBA_CACHE_DIR``
chooses another), so only the first process after an install compiles (a minute or two
on a 2-core machine) and later ones load the kernels in about a second.  That first
process says so once on stderr, so a pause is not mistaken for a hang.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable
from functools import cache
from typing import Any

__all__ = ["HAVE_NUMBA", "USE_NUMBA", "compiled", "jit"]

HAVE_NUMBA = importlib.util.find_spec("numba") is not None
"""Whether numba is installed; it is imported only when a kernel is first compiled."""

USE_NUMBA = HAVE_NUMBA
"""Use compiled kernels (set False to force the numpy fallbacks)."""

_listening = False


def _listen_for_compiles() -> None:
    """Say once per process (stderr) when numba compiles one of echocal's kernels.

    numba's ``numba:compile`` event fires only on a real compile, not when a kernel is
    loaded from the on-disk cache, so a process with every kernel cached prints nothing."""
    global _listening
    if _listening:
        return
    _listening = True
    from numba.core import event

    event.register("numba:compile", _announcer())


def _announcer() -> Any:
    """A numba event listener that prints the compile notice at its first echocal kernel."""
    from numba.core import event

    class _Announce(event.Listener):
        said = False

        def on_start(self, ev: Any) -> None:
            dispatcher = ev.data.get("dispatcher") if isinstance(ev.data, dict) else None
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            if self.said or not module.startswith("echocal"):
                return
            self.said = True
            where = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
            print(
                "echocal: compiling numba kernels (once after an install, a minute or two; "
                f"then cached on disk{f' in {where}' if where else ''})",
                file=sys.stderr,
                flush=True,
            )

        def on_end(self, ev: Any) -> None:
            pass

    return _Announce()


def jit(func: Callable[..., Any], **options: Any) -> Callable[..., Any]:
    """``numba.njit(cache=True, nogil=True, **options)(func)``; its first compile in a
    process (a cache miss) is announced on stderr.

    Requires numba (callers check :data:`HAVE_NUMBA` and :data:`USE_NUMBA`)."""
    from numba import njit

    _listen_for_compiles()
    return njit(cache=True, nogil=True, **options)(func)


@cache
def _njit(func: Callable[..., Any]) -> Callable[..., Any] | None:
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - depends on the environment
        return None
    return jit(func)


def compiled(func: Callable[..., Any]) -> Callable[..., Any] | None:
    """The numba-compiled ``func`` (compiled once, cached on disk), or None without numba."""
    if not (USE_NUMBA and HAVE_NUMBA):
        return None
    return _njit(func)
