"""``echocal methods [NAME]``: the calibration methods, and one method's options."""

from __future__ import annotations

import inspect
from typing import Annotated

import typer
from rich.markup import escape

from echocal.cli._common import output, write_json


def register(app: typer.Typer) -> None:
    """Add the command of this module to ``app``."""

    @app.command("methods")
    def methods(
        name: Annotated[
            str | None, typer.Argument(help="A method: list its options and defaults.")
        ] = None,
        json_output: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    ) -> None:
        """List the calibration methods, or one method's options (for --option KEY=VALUE)."""
        from echocal.calibrate import get_method, method_names
        from echocal.calibrate._options import accepted_options

        if name is None:
            summary = {m: _first_line(get_method(m)) for m in method_names()}
            if json_output:
                write_json({"methods": summary})
                return
            for m, line in summary.items():
                output.print(f"[bold]{m:14s}[/] {escape(line)}")
            return
        cls = get_method(name)  # unknown names list the valid ones
        params, accepted = inspect.signature(cls.__init__).parameters, accepted_options(cls)
        options = {k: params[k].default for k in params if k in accepted}
        docs = option_docs(cls)
        if json_output:
            write_json(
                {
                    "method": name,
                    "options": {k: _plain(v) for k, v in options.items()},
                    "descriptions": {k: docs.get(k, "") for k in options},
                }
            )
            return
        output.print(f"[bold]{escape(name)}[/]: {escape(_first_line(cls))}")
        for key, default in options.items():
            note = _note(key, cls)
            output.print(f"  {key:18s} default {escape(repr(default))}{note}")
            if docs.get(key):
                output.print(f"  {'':18s} {escape(docs[key])}", soft_wrap=True)


def _note(key: str, cls: type) -> str:
    """Where an option of method ``cls`` takes its value from when it is neither the
    default nor set by --option (the driver's rules: :func:`echocal.calibrate.calibrate`)."""
    from echocal.calibrate import Acquisition
    from echocal.calibrate._options import option_defaults
    from echocal.calibrate.acquisition import LOCAL_INPUTS
    from echocal.calibrate.driver import CALLABLE_INPUTS, OBJECTIVE_INPUTS

    searches = issubclass(cls, Acquisition)
    if key in CALLABLE_INPUTS:
        return "  (supplied by the objective; Python API only)"
    if key == "history":
        return "  (warm start from earlier measurements; Python API only)"
    if key in OBJECTIVE_INPUTS and (searches or key in LOCAL_INPUTS):
        return "  (default: the objective's)"
    if key == "passes" and searches and option_defaults(cls).get("passes"):
        return "  (sized from the objective's probe when it has one)"
    return ""


def option_docs(cls: type) -> dict[str, str]:
    """Each option's meaning and unit, from the ``Parameters`` sections of the docstrings
    of ``cls`` and its bases (NumPy style: ``name : text`` or ``a, b : text``, with
    indented continuation lines); the class's own text wins over a base's."""
    docs: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        docs.update(_parameters(inspect.getdoc(klass) or ""))
    return docs


def _parameters(doc: str) -> dict[str, str]:
    """``{name: text on one line}`` of the ``Parameters`` section of a docstring."""
    lines = doc.splitlines()
    try:
        start = next(i for i, ln in enumerate(lines) if ln.strip() == "Parameters") + 2
    except StopIteration:
        return {}
    found: dict[str, list[str]] = {}
    names: list[str] = []
    for line in lines[start:]:
        if not line.strip():
            if names:
                continue
            break
        if line.startswith(" ") and names:  # a continuation line
            for n in names:
                found[n].append(line.strip())
            continue
        if " : " not in line:  # the next section's heading
            break
        head, text = line.split(" : ", 1)
        names = [n.strip() for n in head.split(",")]
        for n in names:
            found[n] = [text.strip()]
    return {n: " ".join(parts) for n, parts in found.items()}


def _first_line(cls: type) -> str:
    """The first paragraph of the class docstring, on one line."""
    return " ".join((inspect.getdoc(cls) or "").split("\n\n")[0].split())


def _plain(value: object) -> object:
    """JSON-ready default: numbers, strings, booleans and None as they are, tuples and
    lists of them as lists, else repr."""
    if isinstance(value, tuple | list) and all(_plain(v) == v for v in value):
        return list(value)
    return value if value is None or isinstance(value, bool | int | float | str) else repr(value)
