"""``echocal info --json``: the versions and engines as one JSON object."""

from __future__ import annotations

import json
from importlib.metadata import version

from typer.testing import CliRunner

import echocal
from echocal._numba import USE_NUMBA
from echocal.cli import app


def test_info_json_reports_versions_and_engines():
    result = CliRunner().invoke(app, ["info", "--json"])
    assert result.exit_code == 0
    data = json.loads(result.output)
    assert data["echocal"] == echocal.__version__
    assert data["packages"]["numpy"] == version("numpy")
    assert set(data["packages"]) >= {"numpy", "scipy", "numba", "embreex"}
    assert data["engines"] == {
        "numba": USE_NUMBA,
        "embree": data["packages"]["embreex"] is not None,
    }
    text = CliRunner().invoke(app, ["info"]).output  # the text form says the same
    assert f"numba {'active' if USE_NUMBA else 'off'}" in text
