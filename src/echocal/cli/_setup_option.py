"""The ``--setup``/``--specimen``/``--snr``/``--seed`` options shared by simulation commands."""

from __future__ import annotations

import dataclasses

from echocal.measurement.virtual import VirtualSetup
from echocal.setups import load_setup
from echocal.specimen import builtin_specimen

SETUP_HELP = "Built-in setup name (see `echocal setup list`) or a setup TOML file."
SPECIMEN_HELP = "Replace the setup's specimen by this built-in one (e.g. thesis-block, sphere)."
SNR_HELP = (
    "Override the receiver SNR [dB] (reference echo at normal incidence); 'none' = noiseless."
)


def resolve_setup(
    setup: str, *, specimen: str | None = None, snr: str | None = None, seed: int | None = None
) -> VirtualSetup:
    """Load ``setup`` and apply the common command-line overrides."""
    virtual = load_setup(setup, seed=seed)
    changes: dict[str, object] = {}
    if specimen is not None:
        changes["specimen"] = builtin_specimen(specimen)
    if snr is not None:
        snr_db = None if snr.strip().lower() in ("none", "inf", "off") else _float("--snr", snr)
        changes["receiver"] = dataclasses.replace(virtual.receiver, snr_db=snr_db)
    if changes:
        changes["rng"] = seed if seed is not None else virtual.rng
        virtual = dataclasses.replace(virtual, **changes)
    return virtual


def _float(option: str, text: str) -> float:
    from echocal.errors import EchocalValueError

    try:
        return float(text)
    except ValueError:
        raise EchocalValueError(
            f"{option} must be a number in dB or 'none'; got {text!r}"
        ) from None


__all__ = ["SETUP_HELP", "SNR_HELP", "SPECIMEN_HELP", "resolve_setup"]
