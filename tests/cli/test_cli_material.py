"""``echocal material show --angles``: past a critical angle the wave is called evanescent."""

from __future__ import annotations

import json
import math

from typer.testing import CliRunner

from echocal.cli import app


def test_material_show_marks_evanescent_waves_past_the_critical_angles():
    res = CliRunner().invoke(app, ["material", "show", "steel", "--angles", "10,20,30", "--json"])
    assert res.exit_code == 0, res.output
    report = json.loads(res.output)
    # Snell: sin θc = c_water / c_wave, computed here from the speeds the report gives
    c_w = report["medium"]["longitudinal_speed_m_s"]
    crit_l = math.degrees(math.asin(c_w / report["longitudinal_speed_m_s"]))
    crit_t = math.degrees(math.asin(c_w / report["shear_speed_m_s"]))
    assert 10 < crit_l < 20 < crit_t < 30  # steel in water: about 14.5° and 27.3°
    kinds = [(r["longitudinal_wave"], r["shear_wave"]) for r in report["oblique"]]
    assert kinds == [
        ("propagating", "propagating"),
        ("evanescent", "propagating"),
        ("evanescent", "evanescent"),
    ]
    text = CliRunner().invoke(app, ["material", "show", "steel", "--angles", "30"]).output
    row = next(line for line in text.splitlines() if line.strip().startswith("30.00°"))
    assert row.count("(evanescent)") == 2
    assert "carries no energy into the part" in text
    below = CliRunner().invoke(app, ["material", "show", "steel", "--angles", "10"]).output
    assert "evanescent" not in below
