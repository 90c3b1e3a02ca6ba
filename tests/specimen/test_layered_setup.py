"""Layered plates in setup files, on the CLI and in gates (issue 46)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from echocal import Pose, load_setup
from echocal.cli import app
from echocal.errors import GeometryError
from echocal.materials import material
from echocal.setups import validate_setup_file
from echocal.signal.gates import plate_layers, resolve_gate
from echocal.specimen.interior import Interior
from echocal.wave.interior import echo_list

C = 1480.0
LAYERED = """
name = "layered"
[specimen]
builtin = "flat-plate"
back_wall_echoes = {order}
{top}
[[specimen.layers]]
material = "acrylic"
thickness = "4 mm"
[[specimen.layers]]
material = {second}
thickness = "{second_thickness}"
{flaws}
[transducer]
width = "12.7 mm"
aperture = "circular"
[echo]
reflection = "wave"
[window]
fs = "100 MHz"
start = "60 us"
n_samples = 2000
[noise]
snr_db = "none"
[positioner]
reference_position = ["0 mm", "0 mm", "50 mm"]
"""


def _text(
    *,
    order: int = 2,
    top: str = "",
    second: str = '"steel"',
    second_thickness: str = "6 mm",
    flaws: str = "",
) -> str:
    return LAYERED.format(
        order=order, top=top, second=second, second_thickness=second_thickness, flaws=flaws
    )


def _problems(tmp_path: Path, text: str) -> list[str]:
    path = tmp_path / "layered.toml"
    path.write_text(text)
    return validate_setup_file(path)


def test_a_layered_plate_loads_with_its_layers_and_paths(tmp_path: Path) -> None:
    path = tmp_path / "layered.toml"
    path.write_text(_text())
    setup = load_setup(path)
    assert [layer.material.name for layer in setup.interior.layers] == ["acrylic", "steel"]
    assert setup.thickness == pytest.approx(0.010)
    assert setup.material.name == "acrylic"  # the front face's reflection
    labels = setup.interior_echoes.labels
    assert labels[:3] == ("front-wall", "interface-1", "interface-2")
    # order 2: the primaries and every path with three reflections
    assert set(labels[3:]) == {
        "interface-1.0.1",
        "interface-1.0.2",
        "interface-2.0.1",
        "interface-2.0.2",
        "interface-2.1.2",
    }


@pytest.mark.parametrize(
    ("edit", "field", "fix"),
    [
        ({"top": 'material = "steel"'}, "specimen.material", "[[specimen.layers]]"),
        ({"top": 'thickness = "3 mm"'}, "specimen.thickness", "[[specimen.layers]]"),
        ({"second": '"unobtainium"'}, "specimen.layers.1.material", "steel"),
        ({"second": '"water"'}, "specimen.layers.1", "solid"),
        ({"second_thickness": "-2 mm"}, "specimen.layers.1.thickness", ""),
        ({"order": 9}, "specimen.back_wall_echoes", "lower the order"),
    ],
)
def test_a_bad_layer_is_refused_naming_the_field(
    tmp_path: Path, edit: dict[str, object], field: str, fix: str
) -> None:
    problems = _problems(tmp_path, _text(**edit))  # type: ignore[arg-type]
    assert any(p.startswith(field) and fix in p for p in problems), problems


def test_exact_stack_adds_a_remainder_echo_and_is_refused_without_layers(
    tmp_path: Path,
) -> None:
    """``specimen.exact_stack``: the paths keep their labels and a ``stack-remainder``
    echo holds what the exact stack adds to them (the physics: tests/physics/
    test_layered.py); on a plate without layers it is refused in one line naming the
    field."""
    path = tmp_path / "layered.toml"
    path.write_text(_text(top="exact_stack = true"))
    labels = load_setup(path).interior_echoes.labels
    assert labels[:3] == ("front-wall", "interface-1", "interface-2")
    assert labels[-1] == "stack-remainder" and labels.count("stack-remainder") == 1
    plain = tmp_path / "plain.toml"
    plain.write_text(_text())
    assert "stack-remainder" not in load_setup(plain).interior_echoes.labels
    with pytest.raises(GeometryError, match=r"^specimen\.exact_stack: needs \[\[specimen\.layers"):
        Interior(5e-3, 2, (), (), 0, True)


@pytest.mark.parametrize(("value", "got"), [('"yes"', "'yes'"), ("1", "1")])
def test_exact_stack_is_true_or_false_only(tmp_path: Path, value: str, got: str) -> None:
    """A word or a number is not read as a switch: one line naming the field and the fix."""
    problems = _problems(tmp_path, _text(top=f"exact_stack = {value}"))
    fix = "must be true or false (unquoted: exact_stack = true)"
    assert problems == [f"specimen.exact_stack: {fix}, got {got}"]


def test_a_flaw_across_an_interface_is_refused(tmp_path: Path) -> None:
    flaw = """
[[specimen.flaws]]
name = "pore"
kind = "pore"
position = ["0 mm", "0 mm", "-4 mm"]
diameter = "2 mm"
"""
    problems = _problems(tmp_path, _text(flaws=flaw))
    assert any("specimen.flaws.pore.position" in p and "interface" in p for p in problems)


def test_interface_gates_sit_on_each_interface_echo(tmp_path: Path) -> None:
    """``interface-K`` is the front-wall gate moved by the round trips of the layers above
    interface K; ``back-wall`` is the last interface."""
    path = tmp_path / "layered.toml"
    path.write_text(_text())
    setup = load_setup(path)
    layers = plate_layers(setup)
    c_acrylic, c_steel = (material(n).longitudinal_speed for n in ("acrylic", "steel"))
    assert layers == ((0.004, c_acrylic), (0.006, c_steel))
    front = resolve_gate("front-wall", pulse=setup.pulse)

    def gate(name: str):
        return resolve_gate(name, pulse=setup.pulse, layers=layers)

    assert gate("interface-1").delay - front.delay == pytest.approx(2 * 0.004 / c_acrylic)
    step = 2 * 0.004 / c_acrylic + 2 * 0.006 / c_steel
    assert gate("interface-2").delay - front.delay == pytest.approx(step)
    assert gate("back-wall").delay == gate("interface-2").delay
    with pytest.raises(KeyError, match="interface-1…2"):
        gate("interface-3")


def test_simulate_json_lists_each_echo_with_its_path_time_and_amplitude(tmp_path: Path) -> None:
    path = tmp_path / "layered.toml"
    path.write_text(_text(order=1))
    result = CliRunner().invoke(
        app,
        [
            *("simulate", "--setup", str(path), "--pose", "0,0,50", "--json"),
            *("--gate", "interface-2", "--out", str(tmp_path / "out")),
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    echoes = {e["label"]: e for e in summary["echoes"]}
    assert list(echoes) == ["front-wall", "interface-1", "interface-2"]
    assert echoes["interface-2"]["path"] == {
        "reflections": [2],
        "legs": [
            {"layer": 1, "material": "acrylic", "mode": "L"},
            {"layer": 2, "material": "steel", "mode": "L"},
            {"layer": 2, "material": "steel", "mode": "L"},
            {"layer": 1, "material": "acrylic", "mode": "L"},
        ],
    }
    c_acrylic, c_steel = (material(n).longitudinal_speed for n in ("acrylic", "steel"))
    want = 2 * 0.05 / C + np.array([0.0, 2 * 0.004 / c_acrylic, 2 * 0.006 / c_steel]).cumsum()
    got = [echoes[k]["tof_s"] for k in echoes]
    np.testing.assert_allclose(got, want, atol=2e-8)  # two samples
    # the gate on interface 2: its time and its depth through both layers (10 mm)
    assert summary["tof_s"] == pytest.approx(want[2], abs=2e-8)
    assert summary["depth_m"] == pytest.approx(0.010, abs=1e-4)


def test_the_built_in_layered_setup_shows_its_holes_in_the_aluminium() -> None:
    setup = load_setup("immersion-layered")
    assert [(layer.material.name, layer.thickness) for layer in setup.interior.layers] == [
        ("acrylic", 0.03),
        ("aluminium", 0.05),
    ]
    assert setup.interior_echoes.describe()["fbh-3mm"] == {"layer": 2, "material": "aluminium"}
    pose = Pose(0.0, 0.0, 0.05)
    listed = {e.label: e for e in echo_list(setup.labelled_echoes(pose), setup.window)}
    # interface-2.0.2 arrives at 143 µs, after the window's end (140 µs): absent
    assert listed["interface-2.0.2"].amplitude == 0.0
    assert math.isnan(listed["interface-2.0.2"].tof_s)
    assert listed["interface-2.1.2"].tof_s < setup.window.end


RESIN = '{ name = "resin", density = 1200, longitudinal_speed = "2600 m/s", shear_speed = 1100 }'
SDH_IN_RESIN = (
    'flaws = [{ name = "sdh", kind = "side-drilled-hole", position = ["1 mm", "0 mm", "-7 mm"], '
    'diameter = "1 mm", length = "20 mm", axis = [1, 0, 0] }]'
)
"""A side-drilled hole in the second layer (an inline array of ``[specimen]``)."""


def test_setup_show_prints_the_layers_flaws_and_exact_stack(tmp_path: Path) -> None:
    """``setup show`` (TOML and ``--json``) gives each layer's material and thickness [m],
    the flaws' geometry [m] and the stack settings, and its TOML loads back the same part."""
    path = tmp_path / "layered.toml"
    top = f"shear_legs = 1\nexact_stack = true\n{SDH_IN_RESIN}"
    path.write_text(_text(top=top, second=RESIN))
    runner = CliRunner()
    shown = runner.invoke(app, ["setup", "show", str(path)])
    assert shown.exit_code == 0, shown.output
    lines = [" ".join(line.split()) for line in shown.stdout.splitlines()]
    for line in (
        "exact_stack = true",
        "shear_legs = 1",
        "[[specimen.layers]]",
        'material = "acrylic"',
        "thickness = 0.004 # m",
        "[specimen.layers.material]",
        'name = "resin"',
        "longitudinal_speed = 2600.0 # m/s",
        "thickness = 0.006 # m",
        "[[specimen.flaws]]",
        'kind = "side-drilled-hole"',
        "position = [0.001, 0.0, -0.007] # m",
        "diameter = 0.001 # m",
        "length = 0.02 # m",
        "axis = [1.0, 0.0, 0.0]",
    ):
        assert line in lines, line
    copy = tmp_path / "copy.toml"
    copy.write_text(shown.stdout)
    original, again = load_setup(path).interior, load_setup(copy).interior
    assert (again.thickness, again.back_wall_echoes) == (original.thickness, 2)
    assert (again.shear_legs, again.exact_stack) == (1, True)
    assert again.layers == original.layers
    assert [(f.name, f.kind, f.diameter, f.length) for f in again.flaws] == [
        ("sdh", "side-drilled-hole", 0.001, 0.02)
    ]
    np.testing.assert_array_equal(again.flaws[0].position, original.flaws[0].position)
    np.testing.assert_array_equal(again.flaws[0].axis, original.flaws[0].axis)
    data = json.loads(runner.invoke(app, ["setup", "show", str(path), "--json"]).stdout)
    specimen = data["config"]["specimen"]
    assert (specimen["shear_legs"], specimen["exact_stack"]) == (1, True)
    assert [layer["thickness"] for layer in specimen["layers"]] == [0.004, 0.006]
    assert specimen["layers"][1]["material"]["longitudinal_speed"] == 2600.0
    assert specimen["flaws"] == [
        {
            "name": "sdh",
            "kind": "side-drilled-hole",
            "position": [0.001, 0.0, -0.007],
            "diameter": 0.001,
            "length": 0.02,
            "axis": [1.0, 0.0, 0.0],
        }
    ]
