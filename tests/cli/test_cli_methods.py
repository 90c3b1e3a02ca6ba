"""``echocal methods NAME``: every option with its default, meaning and unit."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from echocal.calibrate import get_method, method_names
from echocal.calibrate._options import accepted_options
from echocal.cli import app
from echocal.cli.methods import option_docs


@pytest.mark.parametrize("name", method_names())
def test_every_option_of_every_method_is_described(name):
    docs = option_docs(get_method(name))
    missing = sorted(k for k in accepted_options(get_method(name)) if not docs.get(k))
    assert not missing, f"{name}: options without a description: {missing}"


def test_methods_name_prints_meaning_and_unit():
    res = CliRunner().invoke(app, ["methods", "spsa", "--json"])
    assert res.exit_code == 0
    data = json.loads(res.output)
    assert set(data["descriptions"]) == set(data["options"])
    assert "[deg]" in data["descriptions"]["c"]  # the perturbation size, in degrees
    text = CliRunner().invoke(app, ["methods", "gradient"]).output
    lines = text.splitlines()
    at = next(i for i, line in enumerate(lines) if line.split()[:1] == ["delta"])
    assert "default 0.25" in lines[at] and "[deg] finite-difference step" in lines[at + 1]
