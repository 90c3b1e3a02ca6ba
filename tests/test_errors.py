"""The error hierarchy: one base, builtin-compatible subclasses."""

from __future__ import annotations

import pytest

from echocal import errors


@pytest.mark.parametrize(
    ("cls", "builtin"),
    [
        (errors.EchocalValueError, ValueError),
        (errors.GeometryError, ValueError),
        (errors.ConfigError, ValueError),
        (errors.LimitError, ValueError),
        (errors.UnknownNameError, KeyError),
        (errors.BudgetExhaustedError, RuntimeError),
        (errors.DataFileError, OSError),
        (errors.InstrumentError, OSError),
    ],
)
def test_subclasses_inherit_base_and_builtin(cls, builtin):
    assert issubclass(cls, errors.EchocalError)
    assert issubclass(cls, builtin)


def test_unknown_name_prints_plain_message():
    assert str(errors.UnknownNameError("unknown pulse 'x'; choose one of: a, b")) == (
        "unknown pulse 'x'; choose one of: a, b"
    )
