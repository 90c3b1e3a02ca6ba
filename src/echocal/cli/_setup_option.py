"""The ``--setup``/``--specimen``/``--snr``/``--seed`` options shared by simulation commands."""

from __future__ import annotations

from echocal.errors import EchocalValueError
from echocal.measurement.virtual import VirtualSetup
from echocal.setups import setup_with_overrides

__all__ = ["SETUP_HELP", "SNR_HELP", "SPECIMEN_HELP", "resolve_setup"]

SETUP_HELP = "Built-in setup name (see `echocal setup list`) or a setup TOML file."
SPECIMEN_HELP = "Replace the setup's specimen by this built-in one (e.g. thesis-block, sphere)."
SNR_HELP = (
    "Override the receiver SNR [dB] (reference echo at normal incidence); 'none' = noiseless."
)


def resolve_setup(
    setup: str, *, specimen: str | None = None, snr: str | None = None, seed: int | None = None
) -> VirtualSetup:
    """Load ``setup`` with the command-line overrides (``snr`` as typed: dB or 'none')."""
    if snr is None:
        return setup_with_overrides(setup, specimen=specimen, seed=seed)
    return setup_with_overrides(setup, specimen=specimen, snr_db=_parse_snr(snr), seed=seed)


def _parse_snr(text: str) -> float | None:
    if text.strip().lower() in ("none", "inf", "off"):
        return None
    try:
        return float(text)
    except ValueError:
        raise EchocalValueError(f"--snr must be a number in dB or 'none'; got {text!r}") from None
