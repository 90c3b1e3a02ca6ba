"""Bad input, as a table: every numeric field of a setup file against a boolean, NaN, ±inf,
a huge and a negative value (issue 15, "TOML booleans become numbers").

The table is built from the schema itself (every int/float field of :class:`SetupConfig`,
tuples element-wise), so a numeric field added later is covered too.  Each case is a
whole TOML file, validated as ``echocal setup validate`` does; a refused value must be
reported with its field path, never read as another number (``width = true`` is not a
1 m probe).  Values a field legitimately takes — a negative position or angle, an
infinite positioner limit, a negative SNR — must be accepted.
"""

from __future__ import annotations

import json
import math
import tomllib
import types
import typing
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from pydantic import BaseModel
from typer.testing import CliRunner

from cli_helpers import run_main, tiny_setup_toml
from echocal.cli import app
from echocal.errors import (
    ConfigError,
    DataFileError,
    EchocalValueError,
    GeometryError,
    LimitError,
)
from echocal.geometry import Pose
from echocal.measurement.limits import PositionerLimits, limit_problems
from echocal.measurement.virtual import MAX_SIMULATED_SAMPLES, VirtualSetup
from echocal.setups import SetupConfig, builtin_setup_names, load_setup, validate_setup_file
from echocal.signal import GaborPulse, RecordingWindow
from echocal.specimen import Cylinder, Specimen, Sphere, TriangleMesh, builtin_specimen
from echocal.transducer import Transducer
from echocal.units import parse_quantity, plausible_frequency

VALUES = {
    "true": "true",
    "false": "false",
    "nan": "nan",
    "inf": "inf",
    "-inf": "-inf",
    "huge": "1e300",
    "negative": "-1.5",
}
"""The bad values, as TOML literals."""

SKIP = {"pulse"}
"""The pulse table is free-form (its options depend on the pulse): checked separately."""


def _bare(annotation: object) -> object:
    """``annotation`` without ``Annotated`` and an optional's None; None for a union of
    several types."""
    args = typing.get_args(annotation)
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _bare(args[0])
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return _bare(inner[0]) if len(inner) == 1 else None
    return annotation


def _numeric(annotation: object) -> tuple[str, int] | None:
    """('scalar'|'tuple', n) if ``annotation`` is an int/float field (optional or a tuple of
    them), else None."""
    bare = _bare(annotation)
    args = typing.get_args(bare)
    if (
        typing.get_origin(bare) is tuple
        and args
        and all(_numeric(a) == ("scalar", 1) for a in args)
    ):
        return "tuple", len(args)
    return ("scalar", 1) if bare in (int, float) else None


def _switch(annotation: object) -> tuple[str, int] | None:
    """('switch', 1) if ``annotation`` is a bool field (optional or not), else None."""
    return ("switch", 1) if _bare(annotation) is bool else None


def _model(annotation: object) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model(arg)
        if found is not None:
            return found
    return None


RENDERED_LISTS = {"specimen.shapes"}
"""Arrays of tables this table renders (one shape); the others (flaws) have their own tests."""


def _is_list(annotation: object) -> bool:
    """A list (optional or not): an array of tables, checked by its own tests (flaws:
    tests/specimen/test_specimen_interior.py)."""
    if typing.get_origin(annotation) is list:
        return True
    return any(_is_list(arg) for arg in typing.get_args(annotation))


def schema_fields(
    kind_of: typing.Callable[[object], tuple[str, int] | None] = _numeric,
    model: type[BaseModel] = SetupConfig,
    prefix: str = "",
) -> list[tuple]:
    """(table path, field name, kind, length) of every field ``kind_of`` names (numeric
    ones by default), recursively."""
    out = []
    for name, info in model.model_fields.items():
        path = f"{prefix}{name}"
        if path in SKIP:
            continue
        annotation = info.rebuild_annotation()
        kind = kind_of(annotation)
        if kind is not None:
            out.append((prefix.rstrip("."), name, *kind))
            continue
        sub = _model(annotation)
        if sub is not None and (path in RENDERED_LISTS or not _is_list(annotation)):
            out.extend(schema_fields(kind_of, sub, f"{path}."))
    return out


FIELDS = schema_fields()
SWITCHES = schema_fields(_switch)
SHAPE_FIELDS = [f for f in FIELDS if f[0] == "specimen.shapes"]

# values a field may legitimately take (everything else must be refused)
ALLOWED: dict[str, set[str]] = {
    "reference_position": set(),  # -1.5 m: not above the part (refused, naming it)
    "center": {"negative"},
    "azimuth": {"negative"},  # angles [deg]
    "coelevation": {"negative"},
    "opening_angle": set(),
    "start": set(),  # -1.5 s: an implausible bare time (refused with a unit hint)
    "snr_db": {"negative"},  # a weak echo: -1.5 dB is a (poor) SNR
    "x": {"negative", "inf", "-inf"},  # positioner limits [m]: inf is unlimited
    "y": {"negative", "inf", "-inf"},
    "z": {"negative", "inf", "-inf"},
    "squint": {"negative"},  # [bench]: angles [deg] and offsets [m] have a sign
    "pivot_offset": {"negative"},
    "speed": {"inf", "huge"},  # an axis's speed: inf (or nearly) is instantaneous
    "temperature_drift": {"negative"},  # [°C/h]: the water may cool
    "level_db": {"negative"},  # grain noise below the reference echo
}


def _toml(table: str, name: str, literal: str, length: int) -> str:
    """A tiny valid setup with ``table.name`` set to ``literal`` (each tuple element)."""
    value = literal if length == 1 else "[" + ", ".join([literal] * length) + "]"
    base = tomllib.loads(tiny_setup_toml())
    if table == "specimen.shapes":  # a shape list (of the kind the field applies to)
        shape = dict(SHAPES["cylinder" if name in ("radius", "length", "caps") else "plane"])
        shape[name] = _Raw(value)
        rows = "\n".join(f"{k} = {_literal(v)}" for k, v in shape.items())
        return _render(base, skip=("specimen",)) + f"[[specimen.shapes]]\n{rows}\n"
    section = base
    for part in table.split(".") if table else []:
        section = section.setdefault(part, {})
    section[name] = _Raw(value)
    return _render(base)


SHAPES = {
    "plane": {"kind": "plane", "center": [0, 0, 0], "width": "40 mm", "height": "40 mm"},
    "cylinder": {
        "kind": "cylinder",
        "center": [0, 0, "-5 mm"],
        "radius": "5 mm",
        "length": "40 mm",
        "azimuth": 0,
        "coelevation": 90,
    },
}
"""A valid shape of each kind the table sets a field of."""


class _Raw(str):
    """A TOML literal written as is."""


def _literal(value: object) -> str:
    if isinstance(value, _Raw):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    return repr(value)


def _render(data: dict, prefix: str = "", skip: tuple[str, ...] = ()) -> str:
    lines, tables = [], []
    for key, value in data.items():
        if key in skip:
            continue
        if isinstance(value, dict):
            tables.append((key, value))
        else:
            lines.append(f"{key} = {_literal(value)}")
    text = "\n".join(lines) + "\n"
    for key, value in tables:
        name = f"{prefix}{key}"
        text += f"[{name}]\n" + _render(value, f"{name}.")
    return text


CASES = [
    pytest.param(
        table,
        name,
        length,
        label,
        id=f"{table + '.' if table else ''}{name}={label}",
    )
    for table, name, _, length in FIELDS
    for label in VALUES
]


def test_the_table_covers_every_numeric_field():
    names = {f"{t}.{n}" if t else n for t, n, _, _ in FIELDS}
    expected = {
        "seed",
        "medium.sound_speed",
        "transducer.width",
        "transducer.n_h",
        "transducer.pinhole_distance",
        "transducer.directivity.opening_angle",
        "window.fs",
        "window.n_samples",
        "noise.snr_db",
        "positioner.z",
        "specimen.mesh_scale",
        "specimen.shapes.radius",
    }
    assert expected <= names, expected - names
    assert len(CASES) == len(FIELDS) * len(VALUES) >= 50 * 7


def test_every_switch_of_a_setup_file_is_listed():
    """The switches the test below covers (a new bool field joins it by itself)."""
    assert {f"{t}.{n}" for t, n, _, _ in SWITCHES} >= {"specimen.shapes.caps"}


@pytest.mark.parametrize(("value", "got"), [('"yes"', "'yes'"), ("1", "1"), ('"true"', "'true'")])
@pytest.mark.parametrize(("table", "name"), [(t, n) for t, n, _, _ in SWITCHES])
def test_a_switch_takes_true_or_false_only(table, name, value, got, tmp_path):
    """A word or a number is not read as a switch (pydantic's lax bool took "yes" and 1):
    one line naming the field and the fix; true still loads."""
    path = write(tmp_path, _toml(table, name, value, 1))
    fix = f"must be true or false (unquoted: {name} = true)"
    where = f"{table}.0.{name}" if table == "specimen.shapes" else f"{table}.{name}"
    assert validate_setup_file(path) == [f"{where}: {fix}, got {got}"]
    problems = validate_setup_file(write(tmp_path, _toml(table, name, "true", 1)))
    assert not [p for p in problems if "true or false" in p]  # (exact_stack needs layers)


@pytest.mark.parametrize(
    ("key", "line"),
    [
        ("flaws", 'flaws = [{ name = "p", kind = "pore", position = [0, 0, "-5 mm"], '
         'diameter = "1 mm" }]'),
        ("shear_legs", "shear_legs = 1"),
        ("exact_stack", "exact_stack = true"),
    ],
)  # fmt: skip
def test_the_inside_of_a_part_without_one_is_refused(tmp_path, key, line):
    """Flaws, shear legs or the exact stack on a part without a thickness or layers were
    dropped without a word ("valid"): one line naming the field and the fix."""
    path = write(tmp_path, TINY + f'[specimen]\nbuiltin = "flat-plate"\n{line}\n')
    assert validate_setup_file(path) == [
        f"specimen.{key}: the part has no inside (no specimen.thickness or "
        "[[specimen.layers]]); give one or leave it out"
    ]


def test_back_wall_echoes_without_an_inside_is_warned_about(tmp_path):
    path = write(tmp_path, TINY + '[specimen]\nbuiltin = "flat-plate"\nback_wall_echoes = 2\n')
    with pytest.warns(UserWarning, match=r"^specimen.back_wall_echoes is ignored: the part "):
        assert validate_setup_file(path) == []


@pytest.mark.parametrize(("table", "name", "length", "label"), CASES)
def test_bad_number_is_refused_naming_the_field(table, name, length, label, tmp_path, recwarn):
    path = tmp_path / "setup.toml"
    path.write_text(_toml(table, name, VALUES[label], length))
    problems = validate_setup_file(path)
    allowed = label in ALLOWED.get(name, set())
    if table == "positioner" and name in ("x", "y", "z") and label in ("inf", "-inf"):
        # [inf, inf] or [-inf, -inf] is an empty range: refused as such, naming the field
        assert problems and any(f"positioner.{name}" in p for p in problems), problems
        return
    if allowed:
        assert not any(f".{name}" in p or p.startswith(f"{name}") for p in problems), problems
        return
    assert problems, f"{table}.{name} = {VALUES[label]} was accepted"
    # the problem names the field: its table and its name ("transducer.directivity:
    # directivity.opening_angle must be < 90 deg", "specimen.shapes.0.width: ...")
    section = table.split(".")[-1]
    assert any(name in p and section in p for p in problems), problems
    if label in ("true", "false"):
        assert any("boolean" in p or "must be a number" in p for p in problems), problems
    assert all("Traceback" not in p for p in problems)


@pytest.mark.parametrize("label", ["true", "nan", "inf", "huge", "negative"])
def test_pulse_numbers_are_checked_too(label, tmp_path, recwarn):
    text = tiny_setup_toml().replace(
        'center_frequency = "5 MHz"', f"center_frequency = {VALUES[label]}"
    )
    path = tmp_path / "setup.toml"
    path.write_text(text)
    problems = validate_setup_file(path)
    assert problems and any("center_frequency" in p for p in problems), problems


def test_cli_refuses_a_boolean_width_in_one_line(tmp_path, capsys, monkeypatch):
    from cli_helpers import run_main

    path = tmp_path / "bool.toml"
    path.write_text(tiny_setup_toml().replace('width = "6 mm"', "width = true"))
    code, out, err = run_main(["setup", "validate", str(path)], capsys, monkeypatch)
    assert code == 1, (out, err)
    assert "transducer.width" in out + err
    assert "boolean" in out + err or "must be a number" in out + err
    assert "valid" not in (out + err).replace("invalid", "")
    assert "Traceback" not in err


@pytest.mark.parametrize("keep", [0.5, 0.1, 40])
def test_a_truncated_binary_stl_is_one_line_naming_the_file(keep, tmp_path):
    import trimesh

    whole = tmp_path / "box.stl"
    trimesh.creation.box(extents=(0.01, 0.01, 0.01)).export(whole)
    data = whole.read_bytes()
    cut = tmp_path / "cut.stl"
    cut.write_bytes(data[: int(keep * len(data)) if keep < 1 else keep])
    path = tmp_path / "mesh.toml"
    path.write_text('name = "m"\n[specimen]\nmesh = "cut.stl"\nmesh_scale = 1.0\n')
    problems = validate_setup_file(path)
    assert len(problems) == 1 and "cut.stl" in problems[0] and "truncated" in problems[0]
    assert "charset" not in problems[0] and "No module" not in problems[0]


runner = CliRunner()


# 8 x 8 rays, 256 samples at 50 MHz from 20 us: the echo of the plate 16 mm below
# (2 x 16 mm / 1480 m/s = 21.6 us) lies inside the window.
TINY = """
name = "tiny"
seed = 1

[transducer]
width = "6 mm"
n_h = 8
pinhole_distance = "50 mm"

[pulse]
center_frequency = "5 MHz"

[window]
fs = "50 MHz"
start = "20 us"
n_samples = 256

[positioner]
reference_position = ["0 mm", "0 mm", "16 mm"]
"""


def write(tmp_path: Path, text: str, name: str = "setup.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def fields(problems: list[str]) -> list[str]:
    return sorted(p.split(":")[0] for p in problems)


# -- 1. frequencies are checked for plausibility ------------------------------------------
def test_bare_frequency_in_hz_is_refused_with_a_hint(tmp_path):
    # 5 (Hz) for 5 MHz used to make the reference echo allocate 89.7 GiB
    path = write(tmp_path, TINY.replace('center_frequency = "5 MHz"', "center_frequency = 5"))
    problems = validate_setup_file(path)
    assert len(problems) == 1
    assert problems[0].startswith("pulse.center_frequency: 5 Hz is implausible")
    assert "did you mean '5 MHz'?" in problems[0]


@pytest.mark.parametrize(
    ("old", "new", "field", "hint"),
    [
        ('fs = "50 MHz"', "fs = 50", "window.fs", "'50 MHz'"),
        ("[pulse]", "[medium]\nsound_speed = 1.48\n[pulse]", "medium.sound_speed", "mm/us"),
        (
            "[pulse]",
            '[transducer.directivity]\nmodel = "piston"\nfrequency = 2.25\n[pulse]',
            "transducer.directivity.frequency",
            "'2.25 MHz'",
        ),
    ],
)
def test_other_unit_slips_name_their_field(tmp_path, old, new, field, hint):
    problems = validate_setup_file(write(tmp_path, TINY.replace(old, new)))
    assert fields(problems) == [field]
    assert "implausible" in problems[0] and hint in problems[0]
    assert ", got" not in problems[0]  # the message quotes the value once


def test_simulate_with_a_frequency_slip_is_exit_2_not_a_memory_error(tmp_path, capsys, monkeypatch):
    path = write(tmp_path, TINY.replace('center_frequency = "5 MHz"', "center_frequency = 5"))
    code, _, err = run_main(
        ["simulate", "--setup", str(path), "--pose", "0,0,16"], capsys, monkeypatch
    )
    assert code == 2
    assert "Traceback" not in err and "MemoryError" not in err
    assert "pulse.center_frequency" in err and "5 MHz" in err


def test_a_pulse_of_seconds_is_refused_before_allocating():
    # Through the API (no setup file): 5 Hz is legal but doubtful (a warning); sampling its
    # ±0.7 s support at 100 MHz would need 1.4e8 samples, so the simulator refuses it.
    with pytest.warns(UserWarning, match="outside the ultrasonic range"):
        pulse = GaborPulse(center_frequency=5.0)
    with pytest.raises(EchocalValueError, match=r"pulse: an A-scan would need .* samples"):
        VirtualSetup(
            specimen=builtin_specimen("flat-plate"),
            transducer=Transducer(n_h=4, n_v=4),
            pulse=pulse,
            window=RecordingWindow(fs=100e6, n_samples=4096),
        )
    assert MAX_SIMULATED_SAMPLES == 1 << 20


def test_sinc_bandwidth_kept_from_gabor_is_refused_not_a_hang(tmp_path):
    # bandwidth = 60 means % for gabor but B = 60 Hz for sinc: a pulse of 333 000 cycles
    path = write(tmp_path, TINY.replace("[pulse]", '[pulse]\nname = "sinc"\nbandwidth = 60'))
    problems = validate_setup_file(path)
    assert fields(problems) == ["pulse.bandwidth"]
    assert "implausible" in problems[0] and "did you mean '60%' (B = 1.5 MHz)?" in problems[0]
    # "60%" means the same for sinc as on the command line: 2B = 60 % of the centre frequency
    ok = write(
        tmp_path, TINY.replace("[pulse]", '[pulse]\nname = "sinc"\nbandwidth = "60%"'), "ok.toml"
    )
    assert load_setup(ok).pulse.bandwidth == pytest.approx(1.5e6, rel=1e-12)


# -- 3. infinite limits and setup show round trips ----------------------------------------
@pytest.mark.parametrize("bounds", ["[-inf, inf]", '["-inf", "inf"]', '["-inf mm", "+inf"]'])
def test_infinite_position_limits_are_accepted(tmp_path, bounds):
    path = write(tmp_path, f"[positioner]\nz = {bounds}\n", "i.toml")
    assert validate_setup_file(path) == []
    assert load_setup(path).limits.z == (-math.inf, math.inf)


def test_nan_limit_is_refused(tmp_path):
    problems = validate_setup_file(write(tmp_path, "[positioner]\nz = [nan, 1]\n"))
    assert fields(problems) == ["positioner.z.0"]
    assert "NaN" in problems[0]


def test_no_unit_hints_on_infinity_and_no_repeated_got(tmp_path):
    path = write(tmp_path, '[transducer]\nwidth = inf\nheight = "inf"\n')
    problems = validate_setup_file(path)
    assert fields(problems) == ["transducer.height", "transducer.width"]
    text = "\n".join(problems)
    assert "inf mm" not in text
    for line in problems:
        assert line.count("got") <= 1, line


ROUND_TRIP_EXTRAS = {
    "noiseless-piston": TINY.replace(
        "[pulse]", '[transducer.directivity]\nmodel = "piston"\n[noise]\nsnr_db = "none"\n[pulse]'
    ),
    "sinc-shapes-unlimited": TINY.replace("[pulse]", '[pulse]\nname = "sinc"\nbandwidth = "1 MHz"')
    + '[specimen]\n[[specimen.shapes]]\nkind = "plane"\nwidth = "50 mm"\nheight = "50 mm"\n'
    + '[[specimen.shapes]]\nkind = "sphere"\ncenter = [0, "30 mm", "-30 mm"]\nradius = "5 mm"\n',
    "long-focus-adc": TINY.replace(
        'pinhole_distance = "50 mm"', 'pinhole_distance = "3 m"'
    ).replace("[window]", "[noise]\nadc_bits = 12\nfull_scale = 2\n[window]"),
}


@pytest.mark.parametrize("source", [*builtin_setup_names(), *ROUND_TRIP_EXTRAS])
def test_setup_show_output_validates_and_loads_back_the_same(tmp_path, source):
    if source in ROUND_TRIP_EXTRAS:
        source = str(write(tmp_path, ROUND_TRIP_EXTRAS[source], f"{source}.toml"))
    shown = runner.invoke(app, ["setup", "show", source])
    assert shown.exit_code == 0, shown.output
    assert "(unset)" not in shown.stdout
    copy = write(tmp_path, shown.stdout, "copy.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing shown may be an ignored setting
        assert validate_setup_file(copy) == []
        again = load_setup(copy)
    original = load_setup(source)
    assert again.limits == original.limits
    assert again.pulse.parameters() == original.pulse.parameters()
    assert again.receiver == original.receiver
    assert again.transducer.directivity == original.transducer.directivity
    assert again.transducer.pinhole_distance == original.transducer.pinhole_distance
    assert again.description == original.description
    assert _inside(again) == _inside(original)


def _inside(setup: VirtualSetup) -> tuple[object, ...] | None:
    """A setup's interior as comparable data, lengths [m] to the 15 digits ``setup show``
    writes (8.2 mm is 0.008199999999999999 parsed, 0.0082 shown: 1 ulp)."""
    interior = setup.interior
    if interior is None:
        return None

    def digits(*values: float) -> tuple[float, ...]:
        return tuple(float(f"{v:.15g}") for v in values)

    flaws = [
        (f.name, f.kind, digits(*f.position, f.diameter, f.length or 0.0), tuple(f.axis))
        for f in interior.flaws
    ]
    layers = [(layer.material, digits(layer.thickness)) for layer in interior.layers]
    settings = (interior.back_wall_echoes, interior.shear_legs, interior.exact_stack)
    return digits(interior.thickness), layers, settings, flaws


def test_setup_show_prints_the_defaults_in_effect(tmp_path):
    path = write(tmp_path, ROUND_TRIP_EXTRAS["noiseless-piston"])
    text = runner.invoke(app, ["setup", "show", str(path)]).stdout
    lines = {
        line.split("=")[0].strip("# ").strip(): line for line in text.splitlines() if "=" in line
    }
    # the piston's radius defaults to half the 6 mm width; its frequency to the pulse's
    assert lines["radius"].startswith("# radius = 0.003 ")
    assert "(default: width / 2)" in lines["radius"]
    assert "5000000.0" in lines["frequency"] and "default" in lines["frequency"]
    assert 'snr_db = "none"' in text  # noiseless stays noiseless when loaded back
    assert "opening_angle" not in text  # a piston has none
    assert "mesh_scale" not in text  # a built-in specimen has none
    assert tomllib.loads(text)["noise"]["snr_db"] == "none"
    data = json.loads(runner.invoke(app, ["setup", "show", str(path), "--json"]).stdout)
    directivity = data["config"]["transducer"]["directivity"]
    assert directivity == {"model": "piston", "radius": 0.003, "frequency": 5e6}
    assert data["config"]["noise"]["snr_db"] is None


# -- 4. every problem at once -------------------------------------------------------------
def test_schema_and_build_problems_are_reported_together(tmp_path, capsys, monkeypatch):
    path = write(
        tmp_path,
        'seed = -1\n[transducer]\nn_h = 0\naperture = "oval"\n[pulse]\nname = "nope"\n'
        '[echo]\nreflection = "mirror"\n[noise]\nadc_bits = 8\n'
        "[positioner]\ncoelevation = [-200, 200]\n",
    )
    assert fields(validate_setup_file(path)) == [
        "echo.reflection",
        "noise.adc_bits",
        "positioner.coelevation",
        "pulse.name",
        "seed",
        "transducer.aperture",
        "transducer.n_h",
    ]
    code, out, err = run_main(["setup", "validate", str(path)], capsys, monkeypatch)
    assert code == 1 and "7 problem(s)" in err and len(out.strip().splitlines()) == 7
    with pytest.raises(ConfigError, match=r"7 problem\(s\)"):
        load_setup(path)


def test_a_check_needing_a_broken_part_is_skipped_only(tmp_path):
    # The pulse is broken: the pulse x window checks are skipped, the rest still run.
    path = write(
        tmp_path,
        TINY.replace('center_frequency = "5 MHz"', 'center_frequency = "5 MHz"\ncolour = 1')
        + '[echo]\nreflection = "mirror"\n',
    )
    problems = validate_setup_file(path)
    assert fields(problems) == ["echo.reflection", "pulse.colour"]
    assert "pulse.colour: unknown option for gabor; valid: alpha, bandwidth, " in "".join(problems)


# -- 5. angle limits ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("axis", "bounds", "message"),
    [
        ("coelevation", (-200.0, 200.0), r"within \[-90, 90\] deg"),
        ("coelevation", (0.0, 150.0), r"within \[-90, 90\] deg"),
        ("azimuth", (-400.0, 0.0), r"within \[-360, 360\] deg"),
    ],
)
def test_angle_limits_must_be_meaningful(axis, bounds, message):
    with pytest.raises(EchocalValueError, match=f"limits.{axis}: limits must lie {message}"):
        PositionerLimits(**{axis: bounds})


def test_full_angle_ranges_are_allowed():
    assert limit_problems(azimuth=(0.0, 360.0), coelevation=(-90.0, 90.0)) == []
    # an endless azimuth axis (inf, as a rig's LIMITS? reply says) is one full turn
    assert PositionerLimits(azimuth=(-math.inf, math.inf)).azimuth == (-180.0, 180.0)


def test_simulating_a_pose_beyond_the_coelevation_limits_is_exit_2(tmp_path, capsys, monkeypatch):
    path = write(tmp_path, TINY + "coelevation = [-90, 90]\n")
    args = ["simulate", "--setup", str(path), "--pose", "0,0,16,0,150"]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert "coelevation = 150 deg outside [-90, 90] deg" in err


def test_limit_violations_are_shown_in_millimetres():
    limits = PositionerLimits(z=(0.005, 0.1))
    assert limits.violations(Pose(0.0, 0.0, -0.005, 0.0, 0.0)) == ["z = -5 mm outside [5, 100] mm"]
    with pytest.raises(LimitError, match=r"z = -5 mm outside \[5, 100\] mm"):
        limits.check(Pose(0.0, 0.0, -0.005, 0.0, 0.0))


# -- 6. a probe inside a closed specimen --------------------------------------------------
SPHERE_AROUND_PROBE = TINY + (
    '[specimen]\n[[specimen.shapes]]\nkind = "sphere"\nradius = "30 mm"\n'
    'center = [0, 0, "20 mm"]\nname = "ball"\n'
)


def test_reference_position_inside_a_sphere_is_a_problem(tmp_path):
    problems = validate_setup_file(write(tmp_path, SPHERE_AROUND_PROBE))
    assert fields(problems) == ["positioner.reference_position"]
    assert "(0, 0, 16) mm is inside sphere 'ball'" in problems[0]


def test_simulating_a_pose_inside_the_part_is_a_geometry_error(tmp_path, capsys, monkeypatch):
    # reference above the ball (top at 0), the requested pose 20 mm inside it
    path = write(
        tmp_path,
        TINY + '[specimen]\n[[specimen.shapes]]\nkind = "sphere"\nradius = "30 mm"\n'
        'center = [0, 0, "-30 mm"]\nname = "ball"\n',
    )
    setup = load_setup(path)
    with pytest.raises(GeometryError, match=r"pose \(0, 0, -20\) mm.* inside sphere 'ball'"):
        setup.measure(Pose(0.0, 0.0, -0.02, 0.0, 0.0))
    with pytest.raises(GeometryError, match="inside sphere 'ball'"):
        setup.true_optimum([0.0, 0.0, -0.02])
    code, _, err = run_main(
        ["simulate", "--setup", str(path), "--pose", "0,0,-20"], capsys, monkeypatch
    )
    assert code == 2 and "Traceback" not in err
    assert "inside sphere 'ball' of specimen 'custom'" in err


def test_which_shapes_are_closed():
    # Independent truth: a point at distance d from the centre is inside iff d < r.
    ball = Sphere(center=(0.0, 0.0, -0.03), radius=0.03)
    np.testing.assert_array_equal(
        ball.contains([[0, 0, -0.03], [0, 0, 0.001], [0.0299, 0, -0.03]]), [True, False, True]
    )
    rod = Cylinder(center=(0, 0, 0), radius=0.01, length=0.1, azimuth=90, coelevation=90)
    # axis along y: inside within radius 10 mm of the axis and |y| < 50 mm
    np.testing.assert_array_equal(
        rod.contains([[0, 0.04, 0.005], [0, 0.06, 0.0], [0.011, 0.0, 0.0]]), [True, False, False]
    )
    bore = Cylinder(center=(0, 0, 0), radius=0.01, length=0.1, surface="inside")
    assert not bore.closed and not bore.contains([[0, 0, 0]])[0]
    box = TriangleMesh.from_trimesh(trimesh.creation.box(extents=(0.02, 0.02, 0.02)))
    assert box.closed
    np.testing.assert_array_equal(
        box.contains([[0, 0, 0], [0.009, -0.009, 0.009], [0, 0, 0.011]]), [True, True, False]
    )
    sheet = builtin_specimen("wavy-surface")
    assert not sheet[0].closed  # an open height field bounds nothing
    both = Specimen([builtin_specimen("flat-plate")[0], ball])
    np.testing.assert_array_equal(both.containing([[0, 0, 0.02], [0, 0, -0.01]]), [-1, 1])


def test_scene_inside_the_part_is_drawn_with_a_warning(tmp_path):
    out = tmp_path / "s.png"
    result = runner.invoke(
        app, ["scene", "--specimen", "sphere", "--pose", "0,0,-10", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "is inside sphere 'ball'" in result.output


# -- 7. ignored settings, unknown options, wording ----------------------------------------
@pytest.mark.parametrize(
    ("extra", "key"),
    [
        (
            '[transducer.directivity]\nmodel = "piston"\nopening_angle = 5\n',
            "transducer.directivity.opening_angle",
        ),
        (
            '[transducer.directivity]\nmodel = "gaussian"\nradius = "3 mm"\n',
            "transducer.directivity.radius",
        ),
        ('[specimen]\nbuiltin = "flat-plate"\nmesh_scale = 0.001\n', "specimen.mesh_scale"),
        (
            '[specimen]\n[[specimen.shapes]]\nkind = "sphere"\nradius = "5 mm"\n'
            'center = [0, 0, "-5 mm"]\nwidth = "3 mm"\n',
            "specimen.shapes.0.width",
        ),
    ],
)
def test_ignored_settings_warn_naming_the_key(tmp_path, extra, key):
    path = write(tmp_path, TINY + extra)
    with pytest.warns(UserWarning, match=f"{key} is ignored"):
        assert validate_setup_file(path) == []


def test_setup_validate_prints_ignored_settings_as_warnings(tmp_path, capsys, monkeypatch):
    path = write(tmp_path, TINY + '[specimen]\nbuiltin = "flat-plate"\nmesh_scale = 0.001\n')
    code, out, err = run_main(["setup", "validate", str(path)], capsys, monkeypatch)
    assert (code, out) == (0, "valid\n")
    assert "warning: specimen.mesh_scale is ignored" in err
    code, out, _ = run_main(["setup", "validate", str(path), "--json"], capsys, monkeypatch)
    assert json.loads(out)["warnings"][0].startswith("specimen.mesh_scale is ignored")


def test_unknown_pulse_option_lists_the_valid_ones(tmp_path):
    path = write(tmp_path, TINY.replace("[pulse]", "[pulse]\nlobes = 3"))
    assert validate_setup_file(path) == [
        "pulse.lobes: unknown option for gabor; valid: alpha, bandwidth, center_frequency, phase"
    ]


def test_wording_of_unit_errors():
    with pytest.raises(EchocalValueError, match="'m' is not an angle unit"):
        parse_quantity("a", "5 m", "angle", "deg")
    with pytest.raises(EchocalValueError, match="'deg' is not a length unit"):
        parse_quantity("z", "5 deg", "length", "m")
    assert parse_quantity("z", "-inf mm", "length", "m", allow_infinite=True) == -math.inf
    with pytest.raises(EchocalValueError, match="must be finite"):
        parse_quantity("z", math.inf, "length", "m")
    with pytest.raises(EchocalValueError, match="did you mean '5 MHz'"):
        plausible_frequency("f", 5.0)
    with pytest.raises(EchocalValueError, match="did you mean '40 kHz'"):
        plausible_frequency("f", 40.0, plausible=(20e3, 100e3))
    assert plausible_frequency("f", 5e6) == 5e6


def test_a_missing_pulse_file_is_named_with_the_other_problems(tmp_path):
    path = write(tmp_path, '[pulse]\nname = "sampled"\nfile = "nope.csv"\n')
    problems = validate_setup_file(path)
    assert fields(problems) == ["pulse.file"] and "nope.csv" in problems[0]
    with pytest.raises(DataFileError, match="nope.csv"):  # the only problem: a file one
        load_setup(path)
    both = write(tmp_path, '[pulse]\nname = "sampled"\nfile = "nope.csv"\n[echo]\nreflection = 1\n')
    assert fields(validate_setup_file(both)) == ["echo.reflection", "pulse.file"]
