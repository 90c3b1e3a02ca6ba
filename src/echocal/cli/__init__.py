"""The ``echocal`` command: a thin layer over library calls.

Every command lives in its own module of this package and exposes
``register(app)``; this module only assembles them.  Everything a command does
is doable from Python through the public API.
"""

from __future__ import annotations

import importlib
from typing import Annotated

import typer

from echocal.cli._common import run_cli
from echocal.cli.info import version_callback

app = typer.Typer(
    name="echocal",
    help="Ultrasonic immersion simulator and transducer-orientation calibration.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=version_callback,
            is_eager=True,
            help="Print the version and exit.",
        ),
    ] = False,
) -> None:
    """Ultrasonic immersion simulator and transducer-orientation calibration."""


# Command modules, in the order their commands appear in --help.
_COMMAND_MODULES = (
    "echocal.cli.info",
    "echocal.cli.pulse",
    "echocal.cli.scene",
    "echocal.cli.simulate",
    "echocal.cli.lobe",
    "echocal.cli.characterize",
    "echocal.cli.calibrate",
    "echocal.cli.methods",
    "echocal.cli.setup",
    "echocal.cli.material",
    "echocal.cli.record",
    "echocal.cli.convert",
    "echocal.cli.instrument",
    "echocal.cli.rig",
    "echocal.cli.scan",
    "echocal.cli.positionscan",
    "echocal.cli.position_fit",
    "echocal.cli.sweep",
    "echocal.cli.experiments",
)

for _name in _COMMAND_MODULES:
    importlib.import_module(_name).register(app)


def main() -> None:
    """Entry point of the ``echocal`` console script."""
    run_cli(app)


__all__ = ["app", "main"]
