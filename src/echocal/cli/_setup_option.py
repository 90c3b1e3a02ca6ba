"""The ``--setup``/``--specimen``/``--snr``/``--seed`` options shared by simulation commands."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from echocal.errors import EchocalValueError

if TYPE_CHECKING:
    from echocal.measurement.virtual import VirtualSetup

__all__ = ["SETUP_HELP", "SNR_HELP", "SPECIMEN_HELP", "resolve_setup"]

SETUP_HELP = "Built-in setup name (see `echocal setup list`) or a setup TOML file."
SPECIMEN_HELP = "Replace the setup's specimen by this built-in one (e.g. thesis-block, sphere)."
SNR_HELP = (
    "Override the receiver SNR [dB] (reference echo at normal incidence); 'none' = noiseless."
)


def resolve_setup(
    setup: str, *, specimen: str | None = None, snr: str | None = None, seed: int | None = None
) -> VirtualSetup:
    """Load ``setup`` with the command-line overrides (``snr`` as typed: dB or 'none').

    Without ``seed`` the setup file's seed is used, and without that 0, so a command
    repeated as typed gives the same noise; ``virtual.rng`` is then that seed.
    """
    from echocal.setups import setup_with_overrides  # the simulator loads on first use

    noise = {} if snr is None else {"snr_db": _parse_snr(snr)}  # absent: the setup's own SNR
    virtual = setup_with_overrides(setup, specimen=specimen, seed=seed, **noise)
    return virtual if virtual.rng is not None else dataclasses.replace(virtual, rng=0)


def _parse_snr(text: str) -> float | None:
    if text.strip().lower() in ("none", "inf", "off"):
        return None
    from echocal.signal.noise import check_snr_db

    try:
        value = float(text)
    except ValueError:
        raise EchocalValueError(f"--snr must be a number in dB or 'none'; got {text!r}") from None
    return check_snr_db("--snr", value)
