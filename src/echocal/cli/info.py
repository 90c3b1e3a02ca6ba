"""``echocal version`` and ``echocal info``: what is installed and which engines are active."""

from __future__ import annotations

import importlib.util
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
            spec = importlib.util.find_spec(module)
            typer.echo(f"  {module:10s} {'available' if spec else 'not installed'}")
