"""``method="auto"``: find the echo, then refine its peak, from as few A-scans as possible.

A run has two phases that share every measurement:

1. **Find the echo.** From ``x0`` outward, each A-scan is asked whether it shows the echo
   (its matched-filter peak's significance, :class:`~echocal.signal.detection.EchoDetector`;
   a marginal detection is confirmed by a second A-scan). First ``x0`` and its 1° ring.
   Beyond, where the echo's likelihood is known — a simulated probe, or a recording or a rig
   in tilt angles, its unknown amplitude averaged over — it follows a posterior over the
   optimum (:mod:`echocal.calibrate.posterior_search`) at every SNR: every A-scan, below the
   detection threshold too, updates it, and the next point is where a detection is most
   likely. Elsewhere it keeps a 1° lattice within 3° of ``x0``, then hexagonal passes sized
   for the probe (:data:`AUTO_SEARCH`).
2. **Refine the peak** with :class:`~echocal.calibrate.model_based.ModelBased`: a
   log-quadratic fitted to every measurement so far, in a trust region, with the live noise
   floor subtracted; from the lobe's tail it follows the probe's lobe template
   (:mod:`echocal.calibrate.lobe_template`). A detection it cannot confirm within
   :data:`~echocal.calibrate.acquisition.CONFIRM_WITHIN` (8) measurements is a false alarm:
   the search resumes where it stood (``result.false_alarms``); so it does when the local
   phase's echo stays weaker than the echo's likelihood allows
   (:data:`~echocal.calibrate.acquisition.ECHO_WITHIN`).

The run stops when its recommendation has settled (or the budget is spent) and reports
``uncertainty``, a radius [deg] around the estimate that holds the optimum with 90 %
probability (``echocal.calibrate.evidence.estimate_radius``). When the start is known to be near the
echo, ``method="model-based"`` saves the search. Every rule of both phases, in the order a
run meets it, with the measurement that keeps it: the documentation's ``auto`` benchmark
page.

Evidence (``benchmarks/bench_calibration.py``, ``benchmarks/bench_tails.py``): on
``immersion-5mhz`` (wave model, budget 80, tilt angles) every start 1–3° off reaches 0.1°
within 40 measurements at 30, 20 and 10 dB; from 5–20° off the median / p99 to 0.1° are
17 / 24 at 30 dB, 27 / 59 at 20 dB, at 10 dB a median 108; on 300 hold-out seeds per far
cell 100 % (30 dB) and 99 % (20 dB) reach 0.1° within 60, and the 90 % radius covers the
truth in 94–98 % of runs.
"""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate.acquisition import Acquisition
from echocal.calibrate.registry import register_method

__all__ = ["AUTO_SEARCH", "Auto"]

STRONG_ECHO_SPACING = float(4.2 * np.sqrt(3.0))
"""[deg] the first pass beyond 3°: a hexagonal lattice of 7.27° leaves no point farther
than 4.2° from a measurement, where the 5 MHz probe's echo at 30 dB is still detected in
98 % of A-scans (docs/benchmarks/detection-wave.md)."""
WEAK_ECHO_SPACING = 4.2
"""[deg] the second pass: points within 2.4°, the 20 dB echo's detection radius; the first
pass, turned by 30°, is a third of it."""
AUTO_SEARCH: dict[str, Any] = {
    "fine_radius": 3.0,
    "passes": (STRONG_ECHO_SPACING, WEAK_ECHO_SPACING),
    "posterior": True,
}
"""auto's search geometry [deg], its only difference from ``acquisition``: the 1° lattice
within 3° of x0, then the passes (:func:`~echocal.calibrate.acquisition.search_rings`)
where the objective cannot size its own (the driver's ``_search_plan``), or the posterior
search where the echo's likelihood is known — unless the caller sets where to search
(``passes``, ``growth``, ``max_spacing`` or ``fine_radius`` without ``posterior=True``)."""


@register_method("auto")
class Auto(Acquisition):
    """Acquisition (only spends measurements beyond x0's hexagon when the echo is not
    there) followed by the model-based local method, which reuses every measurement.

    Takes every :class:`Acquisition` option; only the search geometry defaults differ
    (:data:`AUTO_SEARCH`).
    """

    def __init__(self, x0: ArrayLike, **options: Any) -> None:
        super().__init__(x0, **{**AUTO_SEARCH, **options})


# The driver and the CLI read a method's options and defaults from its signature.
Auto.__init__.__signature__ = inspect.signature(Acquisition.__init__).replace(  # type: ignore[attr-defined]
    parameters=[
        p.replace(default=AUTO_SEARCH.get(name, p.default))
        for name, p in inspect.signature(Acquisition.__init__).parameters.items()
    ]
)
