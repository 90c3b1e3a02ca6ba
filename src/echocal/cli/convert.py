"""``echocal convert OLD NEW``: rewrite an older echocal NetCDF file in the current schema."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from echocal.cli._common import console


def register(app: typer.Typer) -> None:
    """Add ``echocal convert`` to ``app``."""

    @app.command("convert")
    def convert_command(
        source: Annotated[Path, typer.Argument(help="The file to convert (.nc).")],
        target: Annotated[Path, typer.Argument(help="The file to write (.nc).")],
        overwrite: Annotated[bool, typer.Option(help="Replace an existing TARGET.")] = False,
    ) -> None:
        """Rewrite a replay, scan or A-scan file of an older echocal in the current NetCDF
        schema (CF-1.10, compressed, Fletcher-32 checksums; docs/netcdf-schema.md)."""
        from echocal.cli._common import check_out_file
        from echocal.conversion import convert
        from echocal.errors import DataFileError

        check_out_file(target, suffix=".nc", option="TARGET", what="a NetCDF file")
        if target.exists() and not overwrite:
            raise DataFileError(f"TARGET {target} exists; choose another path or pass --overwrite")
        if target.resolve() == source.resolve():
            raise DataFileError("TARGET must differ from SOURCE (the original is kept)")
        fmt = convert(source, target)
        console.print(f"{source} → {target} ({fmt})")
