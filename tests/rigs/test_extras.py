"""Without the optional extras, the error names the extra to install (one line)."""

from __future__ import annotations

import importlib
import sys

import pytest

from echocal.errors import InstrumentError


def test_without_pyvisa_the_error_names_the_visa_extra(monkeypatch):
    from echocal.rigs.visa_io import VisaInstrument

    monkeypatch.setitem(sys.modules, "pyvisa", None)  # as if not installed
    with pytest.raises(InstrumentError, match=r"pip install 'echocal\[visa\]'"):
        VisaInstrument("ASRL1::INSTR", library="@sim").identify()


@pytest.mark.parametrize(
    ("module", "missing"),
    [("echocal.rigs.ophyd_devices", "ophyd"), ("echocal.rigs.plans", "bluesky.plan_stubs")],
)
def test_without_bluesky_the_error_names_the_bluesky_extra(monkeypatch, module, missing):
    monkeypatch.setitem(sys.modules, missing, None)
    monkeypatch.delitem(sys.modules, module, raising=False)
    with pytest.raises(ImportError, match=r"pip install 'echocal\[bluesky\]'"):
        importlib.import_module(module)
