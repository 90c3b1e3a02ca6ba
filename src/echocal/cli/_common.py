"""Helpers shared by the CLI commands (private): error display, pose parsing, output."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

from echocal.errors import DataFileError, EchocalError, EchocalValueError
from echocal.geometry import Pose
from echocal.io import atomic_write_text, file_in_the_way, json_ready
from echocal.units import parse_angle, parse_length, parse_quantity

try:  # recent typer vendors click as typer._click; older ones use click itself
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover - depends on the installed typer
    from click import exceptions as click_exceptions  # type: ignore[no-redef]
_NO_ARGS_IS_HELP = getattr(click_exceptions, "NoArgsIsHelpError", ())  # click >= 8.2

console = Console(stderr=True, emoji=False, soft_wrap=True)  # one message, one line; "1:-1:3" no 👎
"""Console for messages about the work — progress, warnings, errors (stderr)."""

output = Console(emoji=False, width=None if sys.stdout.isatty() else 200)
"""Console for a command's result when it is not printed as --json (stdout: pipe it, grep it —
200 columns when piped, so lines and table cells are not cut at 80)."""


def run_cli(app: typer.Typer) -> None:
    """Run ``app``; usage errors (a misspelt option, a missing value), echocal errors and
    paths the operating system refuses become one red line and exit code 2, not a traceback
    or a box.  Ctrl-C, SIGTERM and SIGHUP all interrupt the command the same way (what it
    measured is kept, see :mod:`echocal._signals`) and end it with "aborted" and the
    shell's code for the signal (130, 143, 129).  Output locks the command held
    (:func:`~echocal.locking.hold_output_lock`) are released when it ends.
    """
    from echocal._signals import INTERRUPTED, Terminated, exit_code, how, terminate_like_ctrl_c
    from echocal.locking import release_held_locks

    warnings.showwarning = _show_warning
    try:
        with terminate_like_ctrl_c() as stopped_by:
            try:
                code = app(standalone_mode=False)
            finally:
                release_held_locks()
        if stopped_by and code == INTERRUPTED:  # typer's code for any KeyboardInterrupt
            stop = Terminated(stopped_by[0])
            console.print(f"aborted: {how(stop)}", highlight=False)
            code = exit_code(stop)
    except _NO_ARGS_IS_HELP as exc:
        exc.show()  # a bare group (`echocal`, `echocal sweep`): its help
        sys.exit(exc.exit_code)
    except click_exceptions.UsageError as exc:
        hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
        _fail(exc.format_message() + hint)
    except click_exceptions.ClickException as exc:  # e.g. a file the parser could not open
        _fail(exc.format_message())
    except (typer.Abort, KeyboardInterrupt) as exc:  # Ctrl-C, SIGTERM, SIGHUP
        console.print(f"aborted: {how(exc)}", highlight=False)
        sys.exit(exit_code(exc))
    except EchocalError as exc:
        _fail(str(exc))
    except OSError as exc:  # a path the operating system refused (permissions, not a dir, ...)
        where = f" {exc.filename}" if exc.filename else ""
        _fail(f"cannot access{where}: {exc.strerror or exc}; check the path and its permissions")
    sys.exit(code if isinstance(code, int) else 0)


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    """Warnings as one yellow line on stderr ("warning: ..."), not Python's source excerpt."""
    console.print(f"[yellow]warning:[/] {escape(str(message))}", highlight=False, soft_wrap=True)


def _fail(message: str) -> None:
    console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    sys.exit(2)


def parse_pose(text: str, option: str = "--pose") -> Pose:
    """Parse ``"X,Y,Z,AZ,COEL"``; lengths in mm unless a unit is given, angles in degrees.

    ``"0,0,20"`` is a pose 20 mm above the origin pointing straight down;
    ``"-10mm,0,22mm,0,5"`` adds 5° of co-elevation.
    """
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (3, 5):
        raise typer.BadParameter(
            f"{option} takes X,Y,Z or X,Y,Z,AZIMUTH,COELEVATION "
            f"(lengths in mm unless a unit is given, angles in degrees); got {text!r}"
        )
    x, y, z = (parse_length(f"{option} {n}", v) for n, v in zip("xyz", parts[:3], strict=True))
    az, coel = (
        (parse_angle(f"{option} azimuth", parts[3]), parse_angle(f"{option} coelevation", parts[4]))
        if len(parts) == 5
        else (0.0, 0.0)
    )
    return Pose(x, y, z, az, coel)


def parse_position(text: str, option: str = "--position") -> np.ndarray:
    """Parse ``"X,Y,Z"`` as a point [m], shape ``(3,)`` (lengths in mm unless a unit is
    given): ``"0,0,50"`` is 50 mm above the origin."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3:
        raise EchocalValueError(f"{option} must be X,Y,Z (mm unless a unit is given); got {text!r}")
    return np.array([parse_quantity(option, p, "length", "mm") for p in parts])


def parse_pair(text: str, option: str) -> tuple[float, float]:
    """Parse ``"A,B"`` as two angles in degrees."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise typer.BadParameter(f"{option} takes two angles A,B in degrees; got {text!r}")
    return parse_angle(f"{option}[0]", parts[0]), parse_angle(f"{option}[1]", parts[1])


_WORDS: dict[str, bool | None] = {
    "true": True,
    "yes": True,
    "false": False,
    "no": False,
    "none": None,
    "null": None,
}
"""Option values read as booleans or None whatever their case (``False``, ``NO``, ``None``)."""


def parse_options(items: list[str] | None, option: str) -> dict[str, Any]:
    """Parse repeated ``KEY=VALUE`` options.

    ``true``/``yes`` and ``false``/``no`` (any case) are booleans and ``none``/``null``
    is None; a VALUE that reads as JSON (``1``, ``0.5``, ``[1, 2]``, ``{"radius": 0.5}``)
    is taken as such; anything else is a string (which the receiving function checks:
    a string is never taken for a number or a boolean).
    """
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key.isidentifier():
            raise typer.BadParameter(f"{option} takes KEY=VALUE (e.g. fine_radius=1); got {item!r}")
        if value.lower() in _WORDS:
            out[key] = _WORDS[value.lower()]
            continue
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out


def write_json(data: dict[str, Any], path: Path | None = None) -> None:
    """Print ``data`` as one JSON object on stdout, or write it atomically to ``path``.

    NaN and ±inf (no echo, an unlimited bound) become ``null``: JSON has no such numbers,
    and strict parsers (``jq``, browsers) refuse Python's ``NaN``/``Infinity`` tokens.
    """
    text = json.dumps(json_ready(data), indent=None if path is None else 2, allow_nan=False)
    if path is None:
        sys.stdout.write(text + "\n")
        return
    atomic_write_text(path, text + "\n")


def check_out_file(
    path: Path,
    *,
    suffix: str | None,
    option: str = "--out",
    what: str = "a file",
    example: str | None = None,
) -> None:
    """Refuse an output file path that cannot be right, before any work.

    ``path`` must end in ``suffix`` (e.g. ``".nc"``, unless None; ``what`` names the
    content, e.g. ``"a NetCDF replay file"``), must not be an existing directory, and
    every existing ancestor folder must be a directory.  ``example`` : a file name
    suggested inside a directory given by mistake (default ``out`` + ``suffix``).
    Raises :class:`~echocal.errors.DataFileError`
    naming ``option`` and the fix.
    """
    if path.is_dir():
        raise DataFileError(
            f"{option} {path} is a directory; give a file path, e.g. "
            f"{path / (example or 'out' + (suffix or ''))}"
        )
    if suffix is not None and path.suffix.lower() != suffix:
        given = f"ends in {path.suffix!r}" if path.suffix else "has no suffix"
        raise DataFileError(
            f"{option} {path} {given}: it is written as {what}; give a name ending in {suffix}, "
            f"e.g. {path.with_suffix(suffix)}"
        )
    blocker = file_in_the_way(path)
    if blocker is not None:
        raise DataFileError(
            f"{option} {path}: {blocker} is not a directory; choose a path in a folder"
        )
