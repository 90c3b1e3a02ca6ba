"""Thesis defaults (Tables 1–7) as named presets.

The thesis's gains (step μ = 0.05, SPSA ε = 0.1, quasi-Newton λ ≤ 0.9) assume pseudo-energy
normalized to a peak of about 1, so every thesis preset sets ``normalize="max"`` (values
divided by the running maximum of |values|) and works on any energy scale.  The thesis does
not state the difference step δ; the presets keep echocal's defaults (0.25° for FD
gradients, 0.5° for the FD Hessian).  Values the thesis studied over a range are listed in
``studied``; the preset holds the Table 7 (comparison) value.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from echocal._validate import one_of

__all__ = ["Preset", "method_options", "preset_names", "presets"]

_N = {"normalize": "max"}
_GRAD = {"mu": 0.05, **_N}
_MOM = {"mu": 0.05, "momentum": 0.7, **_N}
_SPSA = {"eps": 0.1, "A": 5.0, "c": 1.0, "rho": 0.602, "gamma": 0.101, **_N}
_NEWTON = {"mu": 0.05, **_N}


@dataclass(frozen=True)
class Preset:
    """A named set of method options from the thesis.

    methods : method name -> options; x0 : [deg]; max_iter : iterations; snr_db : [dB]
    (the scenario's SNR, for experiment set-ups); studied : option -> values the thesis varied.
    """

    name: str
    description: str
    methods: dict[str, dict[str, Any]]
    x0: tuple[float, float] = (0.0, 0.0)
    max_iter: int = 30
    snr_db: float = 30.0
    studied: dict[str, tuple[float, ...]] = field(default_factory=dict)


_PRESETS: dict[str, Preset] = {
    p.name: p
    for p in (
        Preset("thesis-table-1", "FD gradient ascent, step sizes studied", {"gradient": _GRAD}),
        Preset(
            "thesis-table-2",
            "gradient ascent with momentum",
            {"momentum": _MOM},
            studied={"momentum": (0.65, 0.7, 0.8, 0.85)},
        ),
        Preset(
            "thesis-table-3",
            "Nesterov accelerated gradient",
            {"nesterov": _MOM},
            studied={"momentum": (0.65, 0.7, 0.8, 0.85)},
        ),
        Preset("thesis-table-4", "SPSA", {"spsa": _SPSA}),
        Preset("thesis-table-5", "Newton (initial guesses studied)", {"newton": _NEWTON}),
        Preset(
            "thesis-table-6",
            "quasi-Newton, scaling factors studied",
            {"quasi-newton": {"mu": 0.05, "lam": 0.1, **_N}},
            studied={"lam": (0.1, 0.5, 0.8)},
        ),
        Preset(
            "thesis-table-7",
            "comparison of all six methods",
            {
                "gradient": _GRAD,
                "momentum": _MOM,
                "nesterov": _MOM,
                "spsa": _SPSA,
                "newton": _NEWTON,
                "quasi-newton": {"mu": 0.05, "lam": 0.9, **_N},
            },
        ),
    )
}
_ALIASES = {"thesis": "thesis-table-7"}


def preset_names() -> list[str]:
    """Names of the presets (``"thesis"`` is an alias of ``"thesis-table-7"``)."""
    return sorted([*_PRESETS, *_ALIASES])


def presets(name: str) -> Preset:
    """The preset called ``name`` (unknown names list the valid ones)."""
    one_of("preset", name, preset_names())
    return _PRESETS[_ALIASES.get(name, name)]


def method_options(method: str, preset: str = "thesis") -> dict[str, Any]:
    """Options of ``method`` in ``preset`` (a copy); empty when the preset has none for it."""
    return dict(presets(preset).methods.get(method, {}))
