"""The matched filter's template for measured data (private to the CLI): the pulse of
``--setup``, or of the setup a recording was made with (``echocal record`` stores it)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from rich.markup import escape

from echocal.cli._common import console

__all__ = ["_replay_pulse", "_setup_pulse"]


def _setup_pulse(setup: str) -> Any:
    """The pulse of ``--setup`` (a built-in or a TOML file); nothing else of it is used."""
    from echocal.setups import build_pulse, load_setup_config

    config, base_dir = load_setup_config(setup)
    return build_pulse(config.pulse, base_dir, where=setup)


def _recorded_pulse(recording: Any) -> tuple[Any, str]:
    """The pulse of the setup a recording was made with (``echocal record`` stores its
    config in the file's ``source`` attribute) and where it came from; (None, why not)."""
    from echocal.errors import EchocalError
    from echocal.setups import PulseConfig, build_pulse

    stored = recording.source_info.get("setup")
    config = stored.get("config") if isinstance(stored, dict) else None
    table = config.get("pulse") if isinstance(config, dict) else None
    if not isinstance(config, dict) or not isinstance(table, dict):
        return None, (
            "the recording does not say which pulse was transmitted (only `echocal record` "
            "stores its setup in the file)"
        )
    name = stored.get("setup")
    # a setup file's relative paths (a sampled pulse's samples) are relative to its folder
    base = Path(name).parent if isinstance(name, str) and name.endswith(".toml") else Path.cwd()
    try:
        pulse = build_pulse(PulseConfig.model_validate(table), base, where="pulse")
    except (EchocalError, ValueError) as exc:
        return None, f"the recorded setup's pulse cannot be rebuilt ({exc})"
    return pulse, f"the recording's setup {name or config.get('name', '')}".rstrip()


def _same_pulse(a: Any, b: Any) -> bool:
    if type(a) is not type(b):
        return False
    pa, pb = a.parameters(), b.parameters()
    return pa.keys() == pb.keys() and all(np.array_equal(pa[k], pb[k]) for k in pa)


def _replay_pulse(recording: Any, setup: str | None) -> tuple[Any, str]:
    """The matched filter's template for a recording: ``--setup``'s pulse when given (with a
    warning if the recording was made with another), else the recorded setup's."""
    from echocal.errors import ConfigError

    recorded, origin = _recorded_pulse(recording)
    if setup is not None:
        pulse = _setup_pulse(setup)
        if recorded is not None and not _same_pulse(pulse, recorded):
            console.print(
                f"[yellow]warning:[/] the pulse of --setup {escape(setup)} ({pulse.name} "
                f"{pulse.center_frequency / 1e6:g} MHz) differs from the one {recording.path} "
                f"was recorded with ({recorded.name} {recorded.center_frequency / 1e6:g} MHz); "
                "the matched filter uses --setup's",
                highlight=False,
                soft_wrap=True,
            )
        return pulse, f"--setup {setup}"
    if recorded is None:
        raise ConfigError(
            f"{recording.path}: no pulse for the matched filter: {origin}; pass --setup "
            "NAME|FILE whose [pulse] is the transmitted one"
        )
    return recorded, origin
