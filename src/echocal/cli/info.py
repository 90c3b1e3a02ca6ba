"""``echocal version`` and ``echocal info``: what is installed and which engines are active."""

from __future__ import annotations

import importlib.metadata
import platform

import typer

import echocal


def register(app: typer.Typer) -> None:
    """Add the commands of this module to ``app``."""

    @app.command("version")
    def version() -> None:
        """Print the echocal version."""
        typer.echo(echocal.__version__)

    @app.command("info")
    def info() -> None:
        """Print versions and which optional fast engines (embreex, numba) are available."""
        typer.echo(f"echocal {echocal.__version__} on Python {platform.python_version()}")
        for module in ("numpy", "scipy", "trimesh", "embreex", "numba", "dask"):
            typer.echo(f"  {module:10s} {_installed_version(module)}")


def _installed_version(distribution: str) -> str:
    """The installed version of ``distribution``, or 'not installed'."""
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def version_callback(value: bool) -> None:
    """``echocal --version``: print the version and exit."""
    if value:
        typer.echo(echocal.__version__)
        raise typer.Exit()
