"""`auto` passes every acquisition option through (the driver reads options from signatures)."""

from __future__ import annotations

import inspect

from echocal.calibrate import Acquisition, Auto


def test_auto_accepts_exactly_the_acquisition_options():
    auto = inspect.signature(Auto.__init__).parameters
    acquisition = inspect.signature(Acquisition.__init__).parameters
    assert list(auto) == list(acquisition)
