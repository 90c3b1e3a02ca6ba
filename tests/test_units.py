"""Unit parsing at the user boundary."""

from __future__ import annotations

import math

import pytest

from echocal import EchocalValueError
from echocal.units import parse_angle, parse_length, parse_quantity


@pytest.mark.parametrize(
    ("text", "metres"),
    [
        ("20", 0.02),
        ("20mm", 0.02),
        ("12.7 mm", 0.0127),
        ("0.5in", 0.0127),
        ("1e-3 m", 1e-3),
        (3, 0.003),
        ("5\u00b5m", 5e-6),  # micro sign
        ("5\u03bcm", 5e-6),  # Greek small letter mu: looks the same, means the same
    ],
)
def test_lengths(text, metres):
    assert parse_length("z", text) == pytest.approx(metres)


def test_frequency_and_angle():
    assert parse_quantity("f", "5MHz", "frequency", "Hz") == pytest.approx(5e6)
    assert parse_angle("a", "0.5rad") == pytest.approx(28.6478897565)
    assert parse_quantity("t", "2\u03bcs", "time", "us") == pytest.approx(2e-6)


@pytest.mark.parametrize("text", ["20 MHz", "abc", "nan mm", "1e400 mm"])
def test_bad_lengths_name_the_field(text):
    with pytest.raises(EchocalValueError, match="transducer.width"):
        parse_length("transducer.width", text)


@pytest.mark.parametrize(
    ("text", "want"),
    [
        ("infinity", math.inf),
        ("-Infinity", -math.inf),
        ("infinity mm", math.inf),
        ("inf", math.inf),
    ],
)
def test_infinity_spelled_out_is_infinite_not_inf_with_unit_inity(text: str, want: float) -> None:
    assert parse_quantity("positioner.x", text, "length", "mm", allow_infinite=True) == want


def test_a_word_that_only_starts_with_inf_is_refused() -> None:
    with pytest.raises(EchocalValueError, match="positioner.x must be a number"):
        parse_quantity("positioner.x", "infinite", "length", "mm", allow_infinite=True)
