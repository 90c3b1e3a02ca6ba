"""Calibration methods by name: one registry that refuses duplicates and lists valid names."""

from __future__ import annotations

import importlib
from collections.abc import Callable

from echocal._validate import lookup
from echocal.calibrate.base import Optimizer
from echocal.errors import EchocalValueError

__all__ = ["get_method", "method_names", "register_method"]

_METHODS: dict[str, type[Optimizer]] = {}
_MODULES = (
    "gradient",
    "spsa",
    "newton",
    "quasi_newton",
    "model_based",
    "grid",
    "acquisition",
    "auto",
)
_loaded = False


def register_method(name: str) -> Callable[[type[Optimizer]], type[Optimizer]]:
    """Class decorator adding an :class:`Optimizer` subclass under ``name`` (no duplicates)."""

    def deco(cls: type[Optimizer]) -> type[Optimizer]:
        if name in _METHODS:
            raise EchocalValueError(f"calibration method {name!r} is already registered")
        cls.name = name
        _METHODS[name] = cls
        return cls

    return deco


def _load() -> None:
    global _loaded
    if not _loaded:
        _loaded = True
        for mod in _MODULES:
            importlib.import_module(f"echocal.calibrate.{mod}")


def method_names() -> list[str]:
    """The registered method names, sorted."""
    _load()
    return sorted(_METHODS)


def get_method(name: str) -> type[Optimizer]:
    """The optimizer class registered as ``name`` (unknown names list the valid ones)."""
    _load()
    return lookup("calibration method", name, _METHODS)
