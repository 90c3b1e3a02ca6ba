"""``echocal version`` and ``echocal info``: what is installed and which engines are active."""

from __future__ import annotations

import importlib.metadata
import json
import platform
from typing import Annotated

import typer

import echocal


def register(app: typer.Typer) -> None:
    """Add the commands of this module to ``app``."""

    @app.command("version")
    def version() -> None:
        """Print the echocal version."""
        typer.echo(echocal.__version__)

    @app.command("info")
    def info(
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the same as one JSON object.")
        ] = False,
    ) -> None:
        """Print versions and which optional fast engines (embreex, numba) are available."""
        from echocal._numba import USE_NUMBA

        versions = {module: _installed_version(module) for module in PACKAGES}
        engines = {"numba": bool(USE_NUMBA), "embree": versions["embreex"] is not None}
        if json_output:
            typer.echo(
                json.dumps(
                    {
                        "echocal": echocal.__version__,
                        "python": platform.python_version(),
                        "packages": versions,
                        "engines": engines,
                    }
                )
            )
            return
        typer.echo(f"echocal {echocal.__version__} on Python {platform.python_version()}")
        for module, version in versions.items():
            typer.echo(f"  {module:10s} {version or 'not installed'}")
        typer.echo(
            "  engines    "
            + ", ".join(f"{name} {'active' if on else 'off'}" for name, on in engines.items())
        )


PACKAGES = ("numpy", "scipy", "trimesh", "embreex", "numba", "dask")
"""The packages ``echocal info`` reports: the numerical core and the optional engines."""


def _installed_version(distribution: str) -> str | None:
    """The installed version of ``distribution``, or None."""
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None


def version_callback(value: bool) -> None:
    """``echocal --version``: print the version and exit."""
    if value:
        typer.echo(echocal.__version__)
        raise typer.Exit()
