"""``echocal setup list|show|validate``: the built-in setups and setup files.

``show`` prints the *resolved* setup — every default filled in, every quantity in
SI units (m, s, Hz, m/s; angles in degrees) — as TOML that ``load_setup`` reads
back, or as one JSON object with ``--json``.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer

_UNITS = {
    "sound_speed": "m/s",
    "density": "kg/m3",
    "longitudinal_speed": "m/s",
    "shear_speed": "m/s",
    "alpha0": "Np/m",
    "f_ref": "Hz",
    "temperature": "°C",
    "center": "m",
    "width": "m",
    "height": "m",
    "radius": "m",
    "length": "m",
    "thickness": "m",
    "diameter": "m",
    "position": "m",
    "pinhole_distance": "m",
    "reference_position": "m",
    "x": "m",
    "y": "m",
    "z": "m",
    "azimuth": "deg",
    "coelevation": "deg",
    "opening_angle": "deg",
    "phase": "deg",
    "frequency": "Hz",
    "center_frequency": "Hz",
    "fs": "Hz",
    "start": "s",
    "snr_db": "dB",
    "bandwidth": "% at -6 dB",
}
"""Unit comments of ``setup show`` by field name (every setup quantity is SI)."""


@dataclass(frozen=True)
class Default:
    """A value in effect because the file leaves it out; ``value`` None stands for "none".

    ``setup show`` prints it as a comment (``# radius = 0.00635  # m (default: ...)``):
    uncommenting the line pins the value, leaving it commented keeps the default.
    """

    value: Any
    note: str = "default"


class _NoneWord:
    """None written as the word ``"none"`` (TOML has no null; the setup reads it back)."""


NONE_WORD = _NoneWord()


def resolved_setup(name_or_path: str) -> tuple[dict[str, Any], str]:
    """The resolved setup as plain data (SI, degrees) and the built simulator's description.

    Defaults that depend on other fields (``transducer.height``, ``transducer.n_v``)
    and the pulse parameters (given with units in the file) are taken from the
    built :class:`~echocal.measurement.VirtualSetup`; a mesh path becomes absolute.
    Defaults the file leaves out are :class:`Default` values (the value in effect);
    settings that do not apply (a piston's opening angle) are left out.
    """
    from echocal.setups import load_setup_with_config

    config, base_dir, setup = load_setup_with_config(name_or_path)
    data = config.model_dump(mode="python")
    data["medium"]["sound_speed"] = setup.sound_speed  # in effect (the material's or given)
    data["specimen"] = _specimen(config, base_dir, setup.specimen.name)
    data["transducer"]["height"] = setup.transducer.height
    data["transducer"]["n_v"] = setup.transducer.n_v
    data["transducer"]["directivity"] = _directivity(config, setup)
    data["pulse"] = _pulse(config, base_dir, setup)
    noise = data["noise"]
    if noise["snr_db"] is None:
        noise["snr_db"] = NONE_WORD  # noiseless: "none" in TOML, null in JSON
    for key, meaning in (("adc_bits", "no quantization"), ("full_scale", "no saturation")):
        if noise[key] is None:
            noise[key] = Default(None, f"default: {meaning}")
    return data, setup.description


def _specimen(config: Any, base_dir: Path, resolved_name: str) -> dict[str, Any]:
    from echocal.setups.schema import _SHAPE_FIELDS

    spec = config.specimen
    out: dict[str, Any] = {}
    if spec.builtin is not None:
        out["builtin"] = spec.builtin
    elif spec.mesh is not None:
        mesh = Path(spec.mesh)
        out["mesh"] = str(mesh if mesh.is_absolute() else (base_dir / mesh).resolve())
        out["mesh_scale"] = spec.mesh_scale
    out["name"] = spec.name if spec.name is not None else Default(resolved_name)
    if spec.material is not None:
        out["material"] = _material(spec.material)
    if spec.shapes is not None:
        out["shapes"] = []
        for i, shape in enumerate(spec.shapes):
            item: dict[str, Any] = {"kind": shape.kind, "center": list(shape.center)}
            item.update({key: getattr(shape, key) for key in _SHAPE_FIELDS[shape.kind]})
            item["name"] = shape.name if shape.name is not None else Default(f"{shape.kind}{i}")
            out["shapes"].append(item)
    if spec.thickness is not None or spec.layers:
        out.update(_interior(spec))
    return out


def _material(material: Any) -> Any:
    """A material as given: a built-in name, or its inline table as plain data."""
    return material if isinstance(material, str) else material.model_dump()


_FLAW_FIELDS = {"side-drilled-hole": ("length", "axis"), "flat-bottom-hole": (), "pore": ()}
"""The flaw fields besides name, kind, position and diameter that apply to each kind."""


def _interior(spec: Any) -> dict[str, Any]:
    """The plate's inside as given in ``[specimen]``: its thickness (one material) or its
    layers (material and thickness [m] each, top first), the echo settings (defaults the
    file leaves out as :class:`Default`; ``shear_legs`` and ``exact_stack`` only with
    layers) and its flaws (position and diameter [m]; a side-drilled hole's length [m] and
    axis)."""
    out: dict[str, Any] = {}
    if spec.thickness is not None:
        out["thickness"] = spec.thickness
    keys = ["back_wall_echoes"] + (["shear_legs", "exact_stack"] if spec.layers else [])
    for key in keys:
        value = getattr(spec, key)
        out[key] = value if key in spec.model_fields_set else Default(value)
    if spec.layers:
        out["layers"] = [
            {"material": _material(layer.material), "thickness": layer.thickness}
            for layer in spec.layers
        ]
    if spec.flaws:
        out["flaws"] = []
        for flaw in spec.flaws:
            item: dict[str, Any] = {
                "name": flaw.name,
                "kind": flaw.kind,
                "position": list(flaw.position),
                "diameter": flaw.diameter,
            }
            for key in _FLAW_FIELDS[flaw.kind]:
                value = getattr(flaw, key)
                item[key] = list(value) if isinstance(value, tuple) else value
            out["flaws"].append(item)
    return out


def _directivity(config: Any, setup: Any) -> dict[str, Any]:
    d = config.transducer.directivity
    used = setup.transducer.directivity
    out: dict[str, Any] = {"model": d.model}
    if d.model == "gaussian":
        given = d.opening_angle
        out["opening_angle"] = given if given is not None else Default(used.opening_angle)
    elif d.model == "piston":
        out["radius"] = (
            d.radius if d.radius is not None else Default(used.radius, "default: width / 2")
        )
        out["frequency"] = (
            d.frequency
            if d.frequency is not None
            else Default(used.frequency, "default: the pulse's centre frequency")
        )
    return out


def _pulse(config: Any, base_dir: Path, setup: Any) -> dict[str, Any]:
    pulse = setup.pulse
    if pulse.name == "sampled":  # its samples live in a file: show the table as given
        extra = dict(config.pulse.model_extra or {})
        if "file" in extra:
            extra["file"] = str((base_dir / Path(str(extra["file"]))).resolve())
        return {"name": config.pulse.name, **extra}
    params: dict[str, Any] = {
        k: v for k, v in pulse.parameters().items() if isinstance(v, int | float | str)
    }
    if pulse.name == "sinc" and pulse.length is None:
        params["length"] = Default(2 * pulse.half_length, "default: lobes / B")
    return {"name": config.pulse.name, **params}


# ---------------------------------------------------------------- TOML rendering
def _plain(value: Any) -> Any:
    """``value`` with every :class:`Default` replaced by the value in effect (for JSON)."""
    if isinstance(value, Default):
        return value.value
    if value is NONE_WORD:
        return None
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _toml_value(value: Any, unit: str | None = None) -> str:
    if value is NONE_WORD:
        return '"none"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = f"{value:.15g}"  # 15 digits: 2e-05, not 1.9999999999999998e-05 (1 ulp apart)
        if unit in ("m", "s") and abs(value) > 1.0:  # a bare 2.0 m would read as a slip of mm
            return json.dumps(f"{text} {unit}")
        return text if any(c in text for c in ".en") else text + ".0"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v, unit) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table(value: Any) -> bool:
    return isinstance(value, dict) or (
        isinstance(value, list) and bool(value) and isinstance(value[0], dict)
    )


def _toml_table(data: dict[str, Any], prefix: str, out: list[str]) -> None:
    """Scalars of ``data`` first, then its sub-tables and arrays of tables."""
    units = dict(_UNITS)
    if prefix == "pulse" and data.get("name") == "sinc":
        units["bandwidth"] = "Hz, one-sided B"
    for key, value in data.items():
        if _is_table(value) or value is None:
            continue
        unit = units.get(key)
        note: str | None
        if isinstance(value, Default):
            shown = '"none"' if value.value is None else _toml_value(value.value, unit)
            line = f"# {key} = {shown}"
            note = f"{unit} ({value.note})" if unit else f"({value.note})"
        else:
            line, note = f"{key} = {_toml_value(value, unit)}", unit
        out.append(f"{line:<44s} # {note}" if note else line)
    for key, value in data.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            out.extend(["", f"[{name}]"])
            _toml_table(value, name, out)
        elif _is_table(value):
            for item in value:
                out.extend(["", f"[[{name}]]"])
                _toml_table(item, name, out)


def as_toml(data: dict[str, Any]) -> str:
    """``data`` (nested dicts of scalars and lists) as TOML text.

    :class:`Default` values become comments showing the value in effect; None values
    are left out.
    """
    out: list[str] = []
    _toml_table(data, "", out)
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------- commands
def register(app: typer.Typer) -> None:
    """Add the ``setup`` command group to ``app``."""
    group = typer.Typer(
        name="setup",
        help="Built-in virtual setups and TOML setup files: list, show, validate.",
        no_args_is_help=True,
    )
    app.add_typer(group, name="setup")

    @group.command("list")
    def list_setups(
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """List the built-in setups with their descriptions."""
        from echocal.cli._common import write_json
        from echocal.setups import builtin_setup_names, load_setup_config

        rows = {name: load_setup_config(name)[0].description for name in builtin_setup_names()}
        if as_json:
            write_json({"setups": rows})
            return
        width = max(len(n) for n in rows)
        for name, description in rows.items():
            typer.echo(f"{name:<{width}s}  {description}")

    @group.command("show")
    def show(
        setup: str = typer.Argument(..., help="Built-in setup name or TOML file."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """Print the resolved setup (SI units, degrees) as TOML, or JSON with --json."""
        from echocal.cli._common import write_json

        data, description = resolved_setup(setup)
        if as_json:
            config = _plain(data)  # defaults in effect as values; inf -> null
            write_json({"setup": setup, "description": description, "config": config})
            return
        header = [
            f"# {description}",
            f"# resolved from {setup!r}: SI units (m, s, Hz, m/s), angles in degrees,",
            "# inf = unlimited; commented lines: defaults in effect (uncomment to pin them);",
            "# load it back with `echocal setup validate FILE`",
            "",
        ]
        typer.echo("\n".join(header) + as_toml(data), nl=False)

    @group.command("validate")
    def validate(
        file: str = typer.Argument(..., help="TOML setup file (or a built-in name)."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """Report every problem of a setup file, one per line with its field path.

        Exit code 0 and "valid" when there is none, 1 otherwise.  Settings that are
        ignored (a piston's opening angle, ...) are warned about on stderr.
        """
        from rich.markup import escape

        from echocal.cli._common import console, write_json
        from echocal.setups import validate_setup_file

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            problems = validate_setup_file(file)
        notes = list(dict.fromkeys(str(w.message) for w in caught))
        if as_json:
            write_json(
                {"file": file, "valid": not problems, "problems": problems, "warnings": notes}
            )
        else:
            for note in notes:
                console.print(f"[yellow]warning:[/] {escape(note)}", soft_wrap=True)
            for line in problems:
                typer.echo(line)
            if problems:
                console.print(f"[red]{len(problems)} problem(s)[/] in {file}", soft_wrap=True)
            else:
                typer.echo("valid")
        if problems:
            raise typer.Exit(1)
