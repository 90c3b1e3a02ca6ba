"""A plate's interior in setup files: thickness, back-wall echoes, flaws, and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.signal
from typer.testing import CliRunner

from echocal import load_setup
from echocal.cli import app
from echocal.geometry import Pose
from echocal.setups import validate_setup_file
from echocal.specimen.interior import Flaw, Interior

PLATE = """
name = "plate"
[specimen]
builtin = "flat-plate"
material = "steel"
thickness = "20 mm"
{flaws}
[transducer]
width = "12.7 mm"
aperture = "circular"
[echo]
reflection = "{model}"
[window]
fs = "100 MHz"
start = "60 us"
n_samples = 4096
[positioner]
reference_position = ["0 mm", "0 mm", "50 mm"]
"""

PIPE = """
[[specimen.shapes]]
kind = "cylinder"
center = [0, 0, "-{radius} mm"]
radius = "{radius} mm"
length = "200 mm"
azimuth = 90
coelevation = 90
surface = "{surface}"
"""


def _pipe(text: str, radius: float, surface: str = "outside") -> str:
    """``text`` with its plate replaced by a pipe along y, its top at z = 0."""
    pipe = PIPE.format(radius=radius, surface=surface)
    return text.replace('builtin = "flat-plate"\n', "").replace(
        'thickness = "20 mm"\n', 'thickness = "20 mm"\n' + pipe
    )


SDH = """
[[specimen.flaws]]
name = "{name}"
kind = "{kind}"
position = ["{x} mm", "0 mm", "{z} mm"]
diameter = "{diameter}"
{extra}
"""


def _problems(tmp_path: Path, text: str) -> list[str]:
    path = tmp_path / "plate.toml"
    path.write_text(text)
    return validate_setup_file(path)


def _flaw(
    name="sdh", kind="side-drilled-hole", x=0, z=-10, diameter="2 mm", extra='length = "30 mm"'
):
    return SDH.format(name=name, kind=kind, x=x, z=z, diameter=diameter, extra=extra)


def test_a_plate_with_flaws_loads(tmp_path: Path) -> None:
    assert _problems(tmp_path, PLATE.format(flaws=_flaw(), model="wave")) == []
    setup = load_setup(tmp_path / "plate.toml")
    assert setup.thickness == pytest.approx(0.02)
    assert [f.name for f in setup.interior.flaws] == ["sdh"]


@pytest.mark.parametrize(
    ("edit", "field", "fix"),
    [
        (lambda t: t.replace('"20 mm"', '"-5 mm"'), "specimen.thickness", "greater than 0"),
        (lambda t: t.replace('"20 mm"', "true"), "specimen.thickness", "number"),
        (
            lambda t: t.replace('"20 mm"', "nan"),
            "specimen.thickness",
            "must be a finite number > 0 [mm], got nan",
        ),
        (
            lambda t: t.replace('reflection = "wave"', 'reflection = "lambertian"'),
            "specimen.thickness",
            "wave",
        ),
        (lambda t: t.replace('material = "steel"\n', ""), "specimen.thickness", "material"),
        (
            lambda t: t.replace('material = "steel"', 'material = "water"'),
            "specimen.thickness",
            "solid",
        ),
        (  # the built-in rod (radius 20 mm) as a 20 mm wall
            lambda t: t.replace('builtin = "flat-plate"', 'builtin = "cylinder"'),
            "specimen.thickness",
            "thinner than its radius",
        ),
        (  # a 25 mm ball under a 12.7 mm probe: beyond the shell model's paraxial limit
            lambda t: t.replace('builtin = "flat-plate"', 'builtin = "sphere"'),
            "specimen.thickness",
            "smaller probe or a larger part",
        ),
        (  # a pipe of radius 40 mm under a 12.7 mm probe: a/R = 0.16 > 0.065
            lambda t: _pipe(t, radius=40),
            "specimen.thickness",
            "smaller probe or a larger part",
        ),
        (
            lambda t: _pipe(t, radius=100, surface="inside"),
            "specimen.thickness",
            "bores are not modelled",
        ),
        (
            lambda t: t.replace('builtin = "flat-plate"', 'builtin = "wavy-surface"'),
            "specimen.thickness",
            "meshes",
        ),
    ],
    ids=[
        "negative",
        "bool",
        "nan",
        "ray-model",
        "no-material",
        "fluid",
        "rod",
        "ball",
        "pipe",
        "bore",
        "mesh",
    ],
)
def test_an_impossible_interior_is_refused_naming_the_field(tmp_path, edit, field, fix) -> None:
    problems = _problems(tmp_path, edit(PLATE.format(flaws="", model="wave")))
    assert any(field in p and fix in p for p in problems), problems


@pytest.mark.parametrize(
    ("flaw", "field", "fix"),
    [
        (_flaw(z=-30), "specimen.flaws.sdh.position", "inside the part"),
        (_flaw(z=-0.5), "specimen.flaws.sdh.position", "inside the part"),
        (_flaw(x=80), "specimen.flaws.sdh.position", "outside the plate"),
        (_flaw(kind="crack"), "specimen.flaws", "kind"),
        (_flaw(extra=""), "specimen.flaws.sdh.length", "length"),
        (_flaw(diameter="0 mm"), "specimen.flaws.sdh.diameter", "greater than 0"),
        (_flaw() + _flaw(), "specimen.flaws", "twice"),
    ],
    ids=[
        "below-back-wall",
        "through-front",
        "beside",
        "unknown-kind",
        "sdh-no-length",
        "zero-diameter",
        "duplicate-name",
    ],
)
def test_a_bad_flaw_is_refused_naming_the_field(tmp_path, flaw, field, fix) -> None:
    problems = _problems(tmp_path, PLATE.format(flaws=flaw, model="wave"))
    assert any(field in p and fix in p for p in problems), problems
    assert all("Traceback" not in p for p in problems)


def test_flaw_geometry_is_checked_in_the_library_too() -> None:
    with pytest.raises(Exception, match="diameter"):
        Flaw("p", "pore", np.zeros(3), -1.0)
    with pytest.raises(Exception, match="back_wall_echoes"):
        Interior(0.02, back_wall_echoes=99)
    with pytest.raises(Exception, match="thickness"):
        Interior(True)  # type: ignore[arg-type]


def test_flaw_surface_samples_cover_their_area() -> None:
    normal = np.array([0.0, 0.0, 1.0])
    sdh = Flaw("s", "side-drilled-hole", np.zeros(3), 0.002, 0.03)
    pore = Flaw("p", "pore", np.zeros(3), 0.004)
    fbh = Flaw("f", "flat-bottom-hole", np.zeros(3), 0.003)
    for flaw, area in [
        (sdh, np.pi * 0.002 * 0.03),
        (pore, 4 * np.pi * 0.002**2),
        (fbh, np.pi * 0.0015**2),
    ]:
        samples = flaw.surface_samples(2e-4, normal)
        assert samples.areas.sum() == pytest.approx(area, rel=1e-9)
        radial = samples.points - samples.normals * flaw.radius
        if flaw.kind == "pore":  # the points lie on the sphere, normals outward
            np.testing.assert_allclose(radial, 0.0, atol=1e-12)


def test_simulate_lists_every_echo_of_the_steel_plate(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app,
        [
            "simulate",
            "--setup",
            "immersion-steel-plate",
            "--pose",
            "0,0,50",
            "--json",
            "--out",
            str(tmp_path / "out"),
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    labels = [e["label"] for e in summary["echoes"]]
    assert labels == ["front-wall", "back-wall", "back-wall-2", "back-wall-3"]
    times = np.array([e["tof_s"] for e in summary["echoes"]])
    want = 2 * 0.05 / 1480 + np.arange(4) * 2 * 0.02 / 5900  # the plate's round trips
    np.testing.assert_allclose(times, want, rtol=1e-3)
    amplitudes = [e["amplitude"] for e in summary["echoes"]]
    assert amplitudes[0] > amplitudes[1] > amplitudes[2] > amplitudes[3] > 0


def test_the_shell_setup_lists_its_walls_at_their_round_trips() -> None:
    """immersion-steel-shell: 50 mm of water over a 10 mm spherical steel wall (outer
    radius 120 mm).  Each back-wall echo 2T/c_L after the last, within 1 % (the curved
    echoes' envelope peaks; tests/physics/test_shell.py), each weaker than the one before."""
    setup = load_setup("immersion-steel-shell")
    assert setup.thickness == pytest.approx(0.01)
    echoes = setup.labelled_echoes(Pose(0.0, 0.0, 0.05, 0.0, 0.0))
    assert list(echoes) == ["front-wall", "back-wall", "back-wall-2", "back-wall-3"]
    envelopes = [np.abs(scipy.signal.hilbert(v)) for v in echoes.values()]
    t = np.array([np.argmax(e) for e in envelopes]) / 100e6
    np.testing.assert_allclose(np.diff(t), 2 * 0.01 / 5900, rtol=0.01)
    peaks = [e.max() for e in envelopes]
    assert peaks == sorted(peaks, reverse=True) and peaks[-1] > 0


def test_the_side_drilled_hole_setup_shows_its_hole_between_the_walls() -> None:
    setup = load_setup("immersion-steel-sdh")
    echoes = setup.labelled_echoes(Pose(0.0, 0.0, 0.05, 0.0, 0.0))
    assert list(echoes) == ["front-wall", "back-wall", "back-wall-2", "sdh"]
    t = setup.window.start + np.array([np.argmax(np.abs(v)) for v in echoes.values()]) / 100e6
    assert t[0] < t[3] < t[1]  # the hole (9 mm deep) between front and back wall


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("diameter", "true"),
        ("diameter", "nan"),
        ("diameter", "1e300"),
        ("length", "false"),
        ("position", "[true, 0, 0]"),
        ("axis", "[0, 0, 0]"),
    ],
)
def test_a_flaw_field_takes_no_bool_nan_or_huge_value(tmp_path, field, value) -> None:
    flaw = _flaw(extra='length = "30 mm"\naxis = [0, 1, 0]')
    lines = [
        f"{field} = {value}" if line.startswith(f"{field} =") else line
        for line in flaw.splitlines()
    ]
    problems = _problems(tmp_path, PLATE.format(flaws="\n".join(lines), model="wave"))
    # named by the flaw's name, as the interior's own checks name it (not flaws.0)
    assert any(p.startswith(f"specimen.flaws.sdh.{field}") for p in problems), problems
