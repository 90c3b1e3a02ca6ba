"""Method options: which a method accepts, their types, and a "did you mean" for typos (private).

Every calibration method declares its options as keyword parameters of its constructor, with
type hints.  The driver and the command line check the options a user gives against those
declarations *before* anything is measured: a string where a number or a boolean belongs is
refused with the option's name (``bool("False")`` is True, so a boolean option must never
take a string), and an unknown name gets the nearest valid one suggested.  Ranges (> 0,
within [0, 1), ...) are each method's own checks, with the strict number checks below (text
and booleans refused) so that a method built directly is as strict as one built by the
driver.
"""

from __future__ import annotations

import collections.abc
import difflib
import inspect
import types
import typing
from collections.abc import Callable, Iterable, Mapping
from typing import Any, TypeVar

import numpy as np

from echocal import _validate
from echocal.errors import EchocalValueError

__all__ = [
    "RESERVED",
    "accepted_options",
    "check_option_types",
    "finite_float",
    "in_range",
    "nonnegative_float",
    "option_defaults",
    "optional",
    "optional_callable",
    "positive_float",
    "positive_int",
    "strict_bool",
    "suggestion",
]

_T = TypeVar("_T")

RESERVED = frozenset({"self", "x0", "bounds", "rng"})
"""Constructor parameters that are not options: the start, the objective's bounds, the rng."""

_DESCRIPTIONS = {
    "none": "none",
    "bool": "true or false",
    "int": "an integer",
    "float": "a number",
    "str": "a name (text)",
    "mapping": "a dict of options",
    "pair": "a pair (points, values)",
    "callable": "a callable",
}


def accepted_options(cls: type) -> set[str]:
    """Names of the options a method class accepts (its constructor's keywords)."""
    return set(inspect.signature(cls).parameters) - RESERVED


def option_defaults(cls: type) -> dict[str, Any]:
    """Each option of ``cls`` with its default value (None where it has none)."""
    params = inspect.signature(cls).parameters
    return {
        k: (None if p.default is inspect.Parameter.empty else p.default)
        for k, p in params.items()
        if k not in RESERVED and p.kind is not inspect.Parameter.VAR_KEYWORD
    }


def suggestion(name: str, valid: Iterable[str]) -> str:
    """``" (did you mean X?)"`` for the valid name closest to ``name``, else ``""``."""
    close = difflib.get_close_matches(name, sorted(valid), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def strict_bool(name: str, value: Any) -> bool:
    """Return ``value`` if it is a boolean; refuse strings, numbers and None, naming ``name``.

    (``bool("False")`` is True: converting would silently give the opposite.)
    """
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise EchocalValueError(f"{name} must be true or false; got {value!r}")


def _number(name: str, value: Any) -> Any:
    """``value`` unless it is text or a boolean, which a number option refuses (``float``
    would take ``"0.5"``, and ``True`` as 1)."""
    if isinstance(value, str | bytes | bool | np.bool_):
        raise EchocalValueError(f"{name} must be a number; got {value!r}")
    return value


def _strict(check: Callable[..., _T]) -> Callable[..., _T]:
    """``check`` (an :mod:`echocal._validate` number check) that refuses text and booleans."""

    def strict(name: str, value: Any, *args: float) -> _T:
        return check(name, _number(name, value), *args)

    strict.__doc__ = f"``echocal._validate.{check.__name__}`` that refuses text and booleans."
    return strict


finite_float = _strict(_validate.finite_float)
positive_float = _strict(_validate.positive_float)
nonnegative_float = _strict(_validate.nonnegative_float)
positive_int = _strict(_validate.positive_int)
in_range = _strict(_validate.in_range)


def optional(check: Callable[[str, Any], _T], name: str, value: Any) -> _T | None:
    """``check(name, value)``, or None for an option left unset (None)."""
    return None if value is None else check(name, value)


def optional_callable(name: str, value: Any) -> Any:
    """``value`` when it is None or callable, else EchocalValueError naming ``name``."""
    if value is not None and not callable(value):
        raise EchocalValueError(f"{name} must be a callable or None; got {value!r}")
    return value


def _hints(cls: type) -> dict[str, Any]:
    """The constructor type hints of ``cls`` and its bases (the most derived one wins)."""
    hints: dict[str, Any] = {}
    for klass in reversed(cls.__mro__):
        init = klass.__dict__.get("__init__")
        if init is None or klass is object:
            continue
        try:
            hints.update(typing.get_type_hints(init))
        except (NameError, TypeError):  # an unresolvable hint: no type check for it
            continue
    return hints


def _kinds(hint: Any) -> list[str] | None:
    """The kinds of value ``hint`` allows (keys of ``_DESCRIPTIONS``), or None when it
    allows anything this module cannot check (array-likes, Any, ...)."""
    arms = (
        typing.get_args(hint)
        if typing.get_origin(hint) in (typing.Union, types.UnionType)
        else (hint,)
    )
    kinds = []
    for arm in arms:
        origin = typing.get_origin(arm) or arm
        if arm is type(None):
            kinds.append("none")
        elif arm is bool:
            kinds.append("bool")
        elif arm is int:
            kinds.append("int")
        elif arm is float:
            kinds.append("float")
        elif arm is str:
            kinds.append("str")
        elif origin in (dict, Mapping, collections.abc.Mapping):
            kinds.append("mapping")
        elif origin is tuple:
            kinds.append("pair")
        elif origin is collections.abc.Callable:
            kinds.append("callable")
        else:
            return None
    return kinds


def _is(kind: str, value: Any) -> bool:
    boolean = isinstance(value, bool | np.bool_)
    if kind == "none":
        return value is None
    if kind == "bool":
        return boolean
    if kind == "int":
        if isinstance(value, float | np.floating):
            return bool(np.isfinite(value)) and float(value).is_integer()
        return isinstance(value, int | np.integer) and not boolean
    if kind == "float":
        return isinstance(value, int | float | np.integer | np.floating) and not boolean
    if kind == "str":
        return isinstance(value, str)
    if kind == "mapping":
        return isinstance(value, Mapping)
    if kind == "pair":
        return isinstance(value, tuple | list) and len(value) == 2
    return callable(value)  # "callable"


def check_option_types(cls: type, options: Mapping[str, Any], *, where: str) -> None:
    """Refuse an option whose value has the wrong type for ``cls``'s declaration.

    ``where`` names the owner in the message, e.g. ``"method 'auto'"``:
    ``option 'confirm' of method 'auto' must be true or false; got 'maybe'``.
    Options ``cls`` does not declare are left alone (the caller reports unknown names).
    """
    hints = _hints(cls)
    for name, value in options.items():
        if name not in hints:
            continue
        kinds = _kinds(hints[name])
        if kinds is None or any(_is(kind, value) for kind in kinds):
            continue
        allowed = " or ".join(_DESCRIPTIONS[k] for k in kinds)
        raise EchocalValueError(f"option {name!r} of {where} must be {allowed}; got {value!r}")
