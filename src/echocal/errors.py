"""The one error hierarchy of echocal.

Every error echocal raises on purpose derives from :class:`EchocalError`, so a
caller can catch them all at once.  Each subclass also derives from the
builtin exception a Python user would expect (``ValueError`` for bad values,
``KeyError`` for unknown names, ``OSError`` for instruments and files), so
code that catches builtins keeps working.

Messages follow one rule: name the field, say what was wrong, say what is
allowed — ``"snr_db must be finite; got nan"``.
"""

from __future__ import annotations

__all__ = [
    "BudgetExhaustedError",
    "ConfigError",
    "DataFileError",
    "EchocalError",
    "EchocalValueError",
    "GeometryError",
    "InstrumentError",
    "LimitError",
    "UnknownNameError",
]


class EchocalError(Exception):
    """Base class of every error raised deliberately by echocal."""


class EchocalValueError(EchocalError, ValueError):
    """A value is out of its allowed domain (NaN, non-positive size, wrong shape, ...)."""


class GeometryError(EchocalValueError):
    """Impossible or degenerate geometry: a zero-area plane, an empty mesh, ..."""


class ConfigError(EchocalValueError):
    """A setup, sweep or scenario file is malformed or holds invalid values."""


class LimitError(EchocalValueError):
    """A pose lies outside the positioner's reachable limits."""


class UnknownNameError(EchocalError, KeyError):
    """A name (pulse, specimen, model, method, ...) is not in its registry.

    ``KeyError`` quotes its argument when printed; this class prints the plain
    message instead, which lists the valid names.
    """

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class BudgetExhaustedError(EchocalError, RuntimeError):
    """The measurement budget of an objective is used up."""


class DataFileError(EchocalError, OSError):
    """A data file (replay recording, mesh, pulse file, results) is missing or unreadable."""


class InstrumentError(EchocalError, OSError):
    """A hardware instrument disconnected, timed out or answered nonsense."""
