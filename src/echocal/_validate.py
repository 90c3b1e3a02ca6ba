"""Small argument checks shared by every module (private).

Each check names the offending field in its message so the user knows what
to fix, and returns the value converted to the type the caller needs.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal.errors import EchocalValueError, UnknownNameError

T = TypeVar("T")


def finite_float(name: str, value: Any) -> float:
    """Return ``value`` as a float, refusing NaN, inf, booleans and non-numbers."""
    if isinstance(value, bool | np.bool_):
        raise EchocalValueError(f"{name} must be a number, not the boolean {value}")
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise EchocalValueError(f"{name} must be a real number; got {value!r}") from None
    if not math.isfinite(out):
        raise EchocalValueError(f"{name} must be finite; got {out}")
    return out


def positive_float(name: str, value: Any) -> float:
    """Return ``value`` as a finite float > 0."""
    out = finite_float(name, value)
    if out <= 0.0:
        raise EchocalValueError(f"{name} must be > 0; got {out:g}")
    return out


def nonnegative_float(name: str, value: Any) -> float:
    """Return ``value`` as a finite float >= 0."""
    out = finite_float(name, value)
    if out < 0.0:
        raise EchocalValueError(f"{name} must be >= 0; got {out:g}")
    return out


def positive_int(name: str, value: Any) -> int:
    """Return ``value`` as an int >= 1 (bools and non-integral floats refused)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise EchocalValueError(f"{name} must be a positive integer; got {value!r}")
    if value < 1:
        raise EchocalValueError(f"{name} must be >= 1; got {value}")
    return int(value)


def capped_float(name: str, value: Any, cap: float, why: str) -> float:
    """Return ``value`` as a float with ``0 < value <= cap``; ``why`` (the unit and the
    reason for the cap) completes the message of a larger value."""
    out = positive_float(name, value)
    if out > cap:
        raise EchocalValueError(f"{name} must be at most {cap:g} {why}; got {out:g}")
    return out


def in_range(name: str, value: Any, low: float, high: float) -> float:
    """Return ``value`` as a finite float with ``low <= value <= high``."""
    out = finite_float(name, value)
    if not low <= out <= high:
        raise EchocalValueError(f"{name} must lie in [{low:g}, {high:g}]; got {out:g}")
    return out


def finite_array(
    name: str, value: ArrayLike, *, shape_tail: tuple[int, ...] = ()
) -> NDArray[np.float64]:
    """Return ``value`` as a float64 array with all entries finite.

    ``shape_tail`` fixes the trailing axes, e.g. ``(3,)`` for arrays of points.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise EchocalValueError(f"{name} must be numeric; got {value!r}") from None
    if shape_tail and arr.shape[arr.ndim - len(shape_tail) :] != shape_tail:
        raise EchocalValueError(
            f"{name} must have trailing shape {shape_tail}; got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise EchocalValueError(f"{name} must be finite everywhere; got NaN or inf")
    return arr


def one_of(name: str, value: str, allowed: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``allowed``; otherwise list the allowed names."""
    allowed = list(allowed)
    if value not in allowed:
        raise UnknownNameError(
            f"unknown {name} {value!r}; choose one of: {', '.join(sorted(allowed))}"
        )
    return value


def lookup(kind: str, name: str, registry: Mapping[str, T]) -> T:
    """Return ``registry[name]``; an unknown name raises with the valid names listed."""
    one_of(kind, name, registry.keys())
    return registry[name]
