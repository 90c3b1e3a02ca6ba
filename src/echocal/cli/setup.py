"""``echocal setup list|show|validate``: the built-in setups and setup files.

``show`` prints the *resolved* setup — every default filled in, every quantity in
SI units (m, s, Hz, m/s; angles in degrees) — as TOML that ``load_setup`` reads
back, or as one JSON object with ``--json``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import typer

_UNITS = {
    "sound_speed": "m/s",
    "center": "m",
    "width": "m",
    "height": "m",
    "radius": "m",
    "length": "m",
    "focal_length": "m",
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


def resolved_setup(name_or_path: str) -> tuple[dict[str, Any], str]:
    """The resolved setup as plain data (SI, degrees) and the built simulator's description.

    Defaults that depend on other fields (``transducer.height``, ``transducer.n_v``)
    and the pulse parameters (given with units in the file) are taken from the
    built :class:`~echocal.measurement.VirtualSetup`; a mesh path becomes absolute.
    """
    from echocal.setups import build_setup, load_setup_config

    config, base_dir = load_setup_config(name_or_path)
    setup = build_setup(config, base_dir=base_dir)
    data = config.model_dump(mode="python")
    data["pulse"] = {
        "name": setup.pulse.name,
        **{k: v for k, v in setup.pulse.parameters().items() if isinstance(v, int | float | str)},
    }
    data["transducer"]["height"] = setup.transducer.height
    data["transducer"]["n_v"] = setup.transducer.n_v
    mesh = data["specimen"].get("mesh")
    if mesh is not None and not Path(mesh).is_absolute():
        data["specimen"]["mesh"] = str((base_dir / mesh).resolve())
    return data, setup.description


# ---------------------------------------------------------------- TOML rendering
def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = f"{value:.15g}"  # 15 digits: 2e-05, not 1.9999999999999998e-05 (1 ulp apart)
        return text if any(c in text for c in ".en") else text + ".0"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _toml_table(data: dict[str, Any], prefix: str, out: list[str]) -> None:
    """Scalars of ``data`` first, then its sub-tables and arrays of tables."""
    for key, value in data.items():
        if isinstance(value, dict) or (
            isinstance(value, list) and value and isinstance(value[0], dict)
        ):
            continue
        if value is None:
            out.append(f"# {key} = (unset)")
            continue
        unit = _UNITS.get(key)
        line = f"{key} = {_toml_value(value)}"
        out.append(f"{line:<44s} # {unit}" if unit else line)
    for key, value in data.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            out.extend(["", f"[{name}]"])
            _toml_table(value, name, out)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for item in value:
                out.extend(["", f"[[{name}]]"])
                _toml_table(item, name, out)


def as_toml(data: dict[str, Any]) -> str:
    """``data`` (nested dicts of scalars and lists) as TOML text; None values become comments."""
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
            write_json({"setup": setup, "description": description, "config": data})  # inf -> null
            return
        header = [
            f"# {description}",
            f"# resolved from {setup!r}: SI units (m, s, Hz, m/s), angles in degrees,",
            "# inf = unlimited; load it back with `echocal setup validate FILE`",
            "",
        ]
        typer.echo("\n".join(header) + as_toml(data), nl=False)

    @group.command("validate")
    def validate(
        file: str = typer.Argument(..., help="TOML setup file (or a built-in name)."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """Report every problem of a setup file, one per line with its field path.

        Exit code 0 and "valid" when there is none, 1 otherwise.
        """
        from echocal.cli._common import console, write_json
        from echocal.setups import validate_setup_file

        problems = validate_setup_file(file)
        if as_json:
            write_json({"file": file, "valid": not problems, "problems": problems})
        elif problems:
            for line in problems:
                typer.echo(line)
            console.print(f"[red]{len(problems)} problem(s)[/] in {file}", soft_wrap=True)
        else:
            typer.echo("valid")
        if problems:
            raise typer.Exit(1)
