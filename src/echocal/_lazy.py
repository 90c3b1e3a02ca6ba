"""Lazy package attributes (PEP 562): a package's public names imported on first use.

A package whose ``__init__`` imports every submodule makes ``import package.small``
pay for all of them (``echocal.measurement.limits`` once imported the calibration
methods, scipy.signal and scipy.stats).  :func:`lazy_attributes` builds the module-level
``__getattr__`` and ``__dir__`` that import a name's module only when the name is read.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import Any


def lazy_attributes(
    package: str, where: Mapping[str, str], public: Iterable[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package``.

    ``where`` maps a public name to the module that defines it, ``"module"`` or
    ``"module:attribute"`` when the package renames it.  A name read once is stored in the
    package's namespace, so later reads skip ``__getattr__``.  ``public`` (the package's
    ``__all__``) is listed by ``dir()``.
    """
    names = sorted(set(public))

    def __getattr__(name: str) -> Any:
        target = where.get(name)
        if target is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module, _, attribute = target.partition(":")
        value = getattr(importlib.import_module(module), attribute or name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
