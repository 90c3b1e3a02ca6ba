"""What a scan point's calibration is told rather than computing from its position."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from echocal.calibrate._options import accepted_options
from echocal.calibrate.auto import AUTO_SEARCH
from echocal.calibrate.driver import SEARCH_GEOMETRY
from echocal.calibrate.registry import get_method

__all__ = ["point_options"]

_FROM_LOBE_PROFILE = ("lobe_template", "normal_echo")
"""A calibration's inputs computed from the probe's lobe profile at its position."""


def point_options(method: str, options: Mapping[str, Any]) -> Mapping[str, Any]:
    """``options`` with a scan's defaults for what a calibration would otherwise compute
    from the probe's lobe at each position (a lobe profile: 2-8 s per position on the wave
    model, against ~1 s for a point's whole calibration): ``auto``'s default passes unless
    the search geometry is given, and neither the lobe's template nor its echo at normal
    incidence (``lobe_template=None``, ``normal_echo=None``) unless given.  A scan point
    starts near its neighbour's optimum, where the template adds little
    (:mod:`echocal.calibrate.lobe_template`: it is for steps from the lobe's tail) and
    no side lobe lies between it and the optimum (:mod:`echocal.calibrate.ridge_search`)."""
    out = dict(options)
    if method == "auto" and not any(k in options for k in SEARCH_GEOMETRY):
        out["passes"] = AUTO_SEARCH["passes"]
    accepted = accepted_options(get_method(method))
    for name in _FROM_LOBE_PROFILE:
        if name in accepted:
            out.setdefault(name, None)
    return out
