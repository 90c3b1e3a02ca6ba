"""The ``--rig FILE`` option shared by ``calibrate``, ``record`` and ``scan``: a rig file
(docs/rigs.md) instead of a simulated setup, with the checks every command makes."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from echocal.errors import EchocalValueError

if TYPE_CHECKING:
    from echocal.rigs import Rig

__all__ = ["RIG_HELP", "open_rig", "refuse_simulation_options", "require_position", "rig_setup"]

RIG_HELP = (
    "Measure on a rig described by a rig file ([rig] TOML: a positioner and a receiver "
    "from drivers, see docs/rigs.md; try it first with `echocal rig check FILE`)."
)


def open_rig(path: Path | str) -> Rig:
    """Validate the rig file and connect it (identification and limits read at once)."""
    from echocal.rigs import connect_rig

    return connect_rig(path)


def require_position(position: str | None, option: str) -> str:
    """``--position`` as typed; refused when missing (a rig has no reference position)."""
    if position is None:
        raise EchocalValueError(
            f"--position X,Y,Z is required with {option}: the rig is calibrated at "
            "one position (mm unless a unit is given)"
        )
    return position


def rig_setup(setup: str | None, rig: Path | str | None, option: str) -> str:
    """The setup whose ``[pulse]`` the rig transmits: ``--setup``, else the rig file's
    ``setup``; refused (naming both ways) when neither gives one."""
    if setup is None and rig is not None:
        from echocal.rigs import load_rig_config

        setup = load_rig_config(rig)[0].rig.setup
    if setup is None:
        where = " or setup = NAME in the rig file's [rig] table" if rig is not None else ""
        raise EchocalValueError(
            f"{option} needs the transmitted pulse for the matched filter: pass --setup "
            f"NAME|FILE whose [pulse] is the rig's{where} (see `echocal setup list`)"
        )
    return setup


def refuse_simulation_options(**given: object) -> None:
    """Refuse options that only a simulation honours (``snr="20"`` → ``--snr``)."""
    for name, value in given.items():
        if value is not None and value is not False:
            flag = "--" + name.replace("_", "-")
            raise EchocalValueError(
                f"{flag} applies to a simulated setup only: a rig (--rig) has its own; drop {flag}"
            )
