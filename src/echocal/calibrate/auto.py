"""``method="auto"``: acquisition phase + the best local method we measured (model-based).

Evidence: ``benchmarks/bench_calibration.py`` (docs/benchmarks/calibration.md), full run
of 50 seeded runs per cell and method, budget 80, every method through the same
SourceObjective; realistic setup immersion-5mhz-ray (5 MHz, 12.7 mm probe, tilted plate,
ray model: energy lobe σ ≈ 0.28°, half-energy at 0.33°), tilt parameterization.  "@n" = fraction
of runs whose estimate is within the tolerance after n measurements:

==================  ============  ============  ============  ==========================
immersion-5mhz-ray  near 30 dB    near 20 dB    near 10 dB    far (5-20°) 30 dB
                    ≤0.05° @20    ≤0.1° @80     ≤0.1° @60     ≤0.1° @60 / @80
==================  ============  ============  ============  ==========================
auto                100 %         100 %         100 %         24 % / 68 %
model-based         100 %         96 %          64 %          4 % / 6 %
Py-BOBYQA (noisy)   54 %          92 %          28 %          0 % / 2 %
Nelder-Mead         22 %          66 %          26 %          0 % / 0 %
scikit-optimize GP  4 %           98 %          42 %          26 % / 40 %
NGOpt (noisy)       0 %           0 %           0 %           0 % / 0 %
==================  ============  ============  ============  ==========================

Median measurements to 0.1° from 1-3°: auto 14 / 15 / 18 at 30 / 20 / 10 dB against the
best peer's 18 (Py-BOBYQA) / 28.5 / 64.5 (GP).  On the thesis's broad lobe from 1-3° at
30 dB: auto 11, no peer's median run within 80; the six thesis methods reach 0.1° within
80 in at most 48 % of the runs of any cell.

Why each part:

1. the model-based fit subtracts the objective's live noise floor (``noise_estimate()``)
   before taking logs — at 10 dB the floor is ~10 % of the peak, and left in it made the
   lobe look broader than it is (10 dB near: 50 % → 100 % within 0.1° @60);
2. the acquisition phase (model-based alone: 6 % from 5-20° @80) tests each A-scan's
   matched-filter peak significance (:class:`~echocal.signal.detection.EchoDetector`),
   which sees the echo 2.4° from the peak at 30 dB (90 % of the time) where the
   pseudo-energy loses it at 2.0°, and re-measures a marginal detection once (false
   hand-overs to a local method on noise were 2 of 40 far starts without it);
3. beyond 3° from x0 the search runs on circles of point spacing up to 4.2° (gaps of at
   most ≈ 2.75°, where one measurement still sees the echo half of the time) out to
   ``max_radius``; inside 3° it keeps the 1° lattice that a 10 dB echo (detection radius
   ≈ 0.55°) needs.  Far starts at 30 dB (40-run check, budget 150): 25 % within 60, 65 %
   within 80, 97 % within 100, 100 % within 120 — before this detector and search, 7 / 15
   / 43 / 80 % at 60 / 80 / 100 / 120.

Targets: ≥ 99 % within 0.05° @20 at 30 dB from 1-3°: met (100 %).  ≥ 95 % within 0.1°
@60 at 10 dB from 1-3°: met (100 %).  ≥ 99 % within 60 from 5-20° at 30 dB: NOT met
(24 %), and out of reach for any blind search on this probe
(``benchmarks/detection_range.py``): covering the 5-20° band with the 2.4° radius at
which one A-scan sees the echo 90 % of the time takes 2π/(3√3)·(20² − 5²)/2.4² ≈ 81
measurements before refinement; even granting every measurement the 2.7° radius of 50 %
detection, at most ≈ 85 % of starts could be found and refined within 60.  Deferring the
1° lattice's outer ring behind the first coarse circle would trade 10 points of far
success at 60 for 15 of near success at 10 dB by 40; auto keeps the near-start cases
first.  When the SNR is known to be ≥ 20 dB, ``fine_radius=1.0`` drops the lattice
beyond x0's hexagon: from 5-20° at 30 dB 70 % within 60, 100 % within 80 (40 runs); 1-3°
starts at 30 and 20 dB stay at 100 %; 1-3° starts at 10 dB would be missed.

When the start is known to be near the echo, ``method="model-based"`` saves the
acquisition.
"""

from __future__ import annotations

import inspect
from typing import Any

from numpy.typing import ArrayLike

from echocal.calibrate.acquisition import Acquisition
from echocal.calibrate.registry import register_method

__all__ = ["AUTO_SEARCH", "Auto"]

AUTO_SEARCH: dict[str, float] = {"fine_radius": 3.0, "growth": 2.0, "max_spacing": 4.2}
"""auto's search geometry [deg, -, deg] — its only difference from ``acquisition``: the 1°
lattice within 3° of x0, then circles of spacing up to 4.2° (see the evidence above)."""


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
