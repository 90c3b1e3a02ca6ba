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

import tomllib
import types
import typing

import pytest
from pydantic import BaseModel

from cli_helpers import tiny_setup_toml
from echocal.setups import SetupConfig, validate_setup_file

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


def _numeric(annotation: object) -> tuple[str, int] | None:
    """('scalar'|'tuple', n) if ``annotation`` is an int/float field (optional or a tuple of
    them), else None."""
    args = typing.get_args(annotation)
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _numeric(args[0])
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return _numeric(inner[0]) if len(inner) == 1 else None
    if origin is tuple and args and all(_numeric(a) == ("scalar", 1) for a in args):
        return "tuple", len(args)
    if annotation in (int, float):
        return "scalar", 1
    return None


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


def numeric_fields(model: type[BaseModel] = SetupConfig, prefix: str = "") -> list[tuple]:
    """(table path, field name, kind, length) of every numeric field, recursively."""
    out = []
    for name, info in model.model_fields.items():
        path = f"{prefix}{name}"
        if path in SKIP:
            continue
        annotation = info.rebuild_annotation()
        kind = _numeric(annotation)
        if kind is not None:
            out.append((prefix.rstrip("."), name, *kind))
            continue
        sub = _model(annotation)
        if sub is not None and (path in RENDERED_LISTS or not _is_list(annotation)):
            out.extend(numeric_fields(sub, f"{path}."))
    return out


FIELDS = numeric_fields()
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
}


def _toml(table: str, name: str, literal: str, length: int) -> str:
    """A tiny valid setup with ``table.name`` set to ``literal`` (each tuple element)."""
    value = literal if length == 1 else "[" + ", ".join([literal] * length) + "]"
    base = tomllib.loads(tiny_setup_toml())
    if table == "specimen.shapes":  # a shape list (of the kind the field applies to)
        shape = dict(SHAPES["cylinder" if name in ("radius", "length") else "plane"])
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
