"""``method="auto"``: acquisition phase + the best local method we measured (model-based).

Evidence (``benchmarks/bench_calibration.py``; the tables are in README.md and
docs/benchmarks/): every method through the same SourceObjective and counter, budget 80,
tilt parameterization, common random numbers.  On ``immersion-5mhz`` (12.7 mm 5 MHz
probe, 50 mm water path, tilted plate, the **wave** model), 100 seeded runs per cell for
``auto`` alone: from 1–3°, the share of runs within 0.1° after 20 / 40 / 60 / 80
measurements; from 5–20°, the measurements to 0.1° (median / p90 / p99;
docs/benchmarks/lower-bound.md, budget 80 at 30 dB, 400 at 20 dB, 1200 at 10 dB):

==================  ================  ======================
start band          1–3°              5–20°
==================  ================  ======================
30 dB               100/100/100/100   17 / 20 / 24
20 dB               100/100/100/100   27 / 40 / 59
10 dB               79/100/100/100    262 / 441 / 535
==================  ================  ======================

From 5–20° at 10 dB no search that acts on detections can be sure of the echo within 80
(it needs 457 measurements to reach 0.1° from 99 % of these starts,
docs/benchmarks/lower-bound.md); with a budget of 1200 ``auto`` needs a median 262, p99
535: **1.17×** that bound.  Before the search below 20 dB was sized for the predicted
echo (item 3) it gave up after about 146 measurements whatever the budget.

From 1–3° at 30 dB, 100 % of runs are within 0.05° after 15 measurements (median 9;
91 % before the local method followed the probe's lobe from its tail, 64 % before it
fitted its warm start before its first step).  From 5–20° at 30 dB the median is 17
measurements to 0.1° (p90 20, p99 24 with the posterior search of item 9; 21 and 26 with
the passes; every run gets there; 18, 23 and 29 before the seek
of item 8, 22, 25 and 31 before a warm
start that the template fits skipped its hexagon, 29, 35 and 50 before the lobe's
template) since the search is sized for the echo the probe's model predicts
against the noise the first ring measures (before: 3/11/66/97 %, median 58.5; with
hand-sized passes 0/12/56/99, before the passes 0/12/27/77 %) and the local model's
log-space noise is capped once its incumbent is a significant echo (before, 4/95/99/99 %:
one run in 100 circled 4° out).
From 1–3° ``auto`` needs a median 8, 9 and 12 measurements to 0.1° at 30, 20 and
10 dB (14, 13 and 15 before the lobe's template); the best peer of the full benchmark
(10 runs per cell) needed 17.5 (Py-BOBYQA), 21.5 (Py-BOBYQA) and 43.5 (scikit-optimize's
GP, 80 % of runs).  Over curved parts, probe off axis, 1–3° at 10 dB, within 0.1° after
60: a ball 100 % with the 6.35 mm probe and with the 12.7 mm one (whose near-field lobe
has a ring, which the lobe's template keeps), a rod 100 % and 95 % (12.7 mm, 100 runs:
two equal humps 3° apart along the ridge with a dip to 0.79 between them, 5 % before a
ridge's local fit that lacks fit shrank to one hump, 73 % before it was fitted around
the hump's own maximum, 92 % before a side lobe was tested after two refinement steps;
20 runs per cell otherwise);
the best peer 50 % and 10 % on the ball, 40 % and 40 % on the rod
(docs/benchmarks/curved.md).

Why each part:

1. the model-based fit subtracts the objective's live noise floor (``noise_estimate()``)
   before taking logs — at 10 dB the floor is ~10 % of the peak, and left in it made the
   lobe look broader than it is;
2. the acquisition phase tests each A-scan's matched-filter peak significance
   (:class:`~echocal.signal.detection.EchoDetector`; a first threshold, then a
   confirming re-measurement of a marginal detection), so a false find on noise is not
   handed to the local method;
3. inside 3° of x0 the search keeps a 1° lattice, which a 10 dB echo needs (visible only
   within about 0.55–0.7°) — unless x0's first ring saw nothing and the objective predicts
   an echo of ≥ 20 dB against the noise those 7 A-scans measured
   (:meth:`~echocal.calibrate.Objective.passes_for_measured_noise`, the ``replan``
   option: a simulated probe's noiseless best echo against the A-scans' robust σ), which
   the passes alone detect from 99 % of the plane: then the 1° lattice is dropped and the
   first pass is the coarsest for that SNR (below 20 dB the 1° lattice stays and one
   pass sized for that SNR follows it, 1.33° at 10 dB, in place of the two below, which
   cannot see such an echo: a 10 dB far start used to give up after them); beyond, two
   passes out to ``max_radius``, coarse to fine, sized from the probe when the objective
   knows it (:meth:`~echocal.calibrate.Objective.search_passes`: the simulator, or a rig's setup):
   the coarsest hexagonal lattices that detect a 30 dB, then a 20 dB echo from 99 % of
   the plane, computed from the probe's noiseless diffraction lobe before anything is
   measured (:mod:`echocal.measurement.detection_radius`) — 8.62° and 4.17° for the
   5 MHz probe on the wave model, 4.18° and 1.97° on the ray model, whose lobe has no
   tails.  Without a known probe, :data:`AUTO_SEARCH`'s 7.27° and 4.2°, sized by hand for
   the 5 MHz probe;
4. the local method fits what the acquisition hands it before its first step (it used
   to step in a random direction from x0 first, ignoring the 7 measurements around it:
   the 30 dB near start within 0.05° after 15 went from 64 to 91 %);
5. the local model refutes itself when a measurement stands clearly above its maximum,
   or the strongest measurement stands twice above the model's own value there (a fit to
   a lobe's flat tail), and refits a smaller neighbourhood (a near-field ring over a
   ball), and searches once across a ridge — and along both axes of a peak refined
   twice below 0.4 of the echo at normal incidence, where the objective knows that echo
   (:meth:`~echocal.calibrate.Objective.normal_echo`, the simulator): the optimum's is
   at least as strong, so that peak is a side lobe (the 12.7 mm probe over a rod: 0.17
   of it, 1.6° across; 30 dB, 20 runs, within 0.1° after 60: 90 → 95 %; tested after
   two refinement steps instead of six, the 10 of 60 runs at 10 dB that climbed it
   need a median 47 measurements to 0.1°, not 56);
6. the local model's log-space noise, the tolerance of its trust-region test, is capped
   at a factor e once its incumbent is a significant echo: a refuted fit's residuals
   gave 40, every step passed, and a far run circled 4° out for 36 measurements;
7. from the lobe's tail the local method follows the probe's lobe
   (:meth:`~echocal.calibrate.Objective.lobe_template`, the simulated probe's
   pseudo-energy versus misalignment; :mod:`echocal.calibrate.lobe_template`): fitted
   to every measurement, with the peak's energy known to 25 % on the simulator, its
   fitted peak is the next point until one lies on the lobe's top — a quadratic reads the
   tail as a lobe twice as broad.  Near 30 dB within 0.05° after 15: 91 → 100 %; far
   30 dB median 29 → 22, p99 50 → 31; a detection 3.7° out stepped to 0.44° in one
   measurement;
8. from a detection deep in the tail, which the template's fit does not yet show as an
   echo (4–7° out at 30 dB, 1.2–1.7 × the noise floor), the local method seeks the peak
   (:mod:`echocal.calibrate.template_seek`): every candidate peak is weighted by how well
   the template fits the measurements with it, and the next point is where their
   predicted echoes disagree most — on the arc the tail value implies, away from the
   directions the search already measured empty — instead of a 1° hexagon around the
   detection, whose 6 values lie within a few noise σ of each other.  Far 30 dB, 100
   runs: p90 to 0.1° 23 → 21, p99 29 → 26, no run slower; 100 other seeds: 25 → 21 and
   30 → 26;
9. beyond x0's first ring, on a simulated probe whose echo the first ring's noise puts
   at 15 dB or more, the search follows the posterior over the optimum
   (:mod:`echocal.calibrate.posterior_search`, the ``posterior`` option): how each
   A-scan's matched-filter peak is distributed wherever the optimum is comes from the
   probe's noiseless lobe and the detector's own noise model
   (:meth:`~echocal.calibrate.Objective.echo_likelihood`), every significance — below the
   threshold too — updates the posterior, and the next point is where a detection is most
   likely (among near-ties, the one nearest to x0), instead of the passes of item 3, which
   act only on detections.  Far starts, 100 runs: at 20 dB (budget 400) p99 to 0.1°
   99 → 59, median 50 → 27 — below the 62 that any search acting on detections needs
   (docs/benchmarks/lower-bound.md); at 30 dB p99 26 → 24 (100 other seeds: 26 → 26,
   median 16 → 15).  Below 15 dB the passes stay (with the posterior, near starts at
   10 dB reached 0.1° within 40 in 97 % of runs instead of 100 %: a prior uniform in
   distance out to 20° sends a search with a 0.6° kernel outward before it has covered
   the 1–3° around x0); without a probe model (a recording, a rig) too.

Issue 19's targets (README.md, docs/benchmarks/lower-bound.md, curved.md): the
lower-bound ratio is met in every far cell — 30 dB 1.20 (p99 24 against 20), 20 dB
0.95 (p99 59 against 62: below a bound that holds only for searches acting on
detections, which the posterior search is not), 10 dB 1.17 (p99 535 against 457, the
passes).  The 12.7 mm probe over a rod at 10 dB meets its target only just (95 of 100
runs; its lobe peaks off normal incidence in two humps, flat along the rod, with no
template; 2 of 100 runs reach 0.1° only after 68–71 measurements, three end 0.10–0.47°
off).  Without a probe model (a recording, a rig) the far search still spends the 1°
lattice first (a fixed order cannot serve both a 10 dB near start and a 30 dB far one
without knowing the SNR); ``fine_radius=1.0`` drops it when the SNR is known to be
≥ 20 dB. When
the start is known to be near the echo, ``method="model-based"`` saves the acquisition.
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
"""[deg] the second pass: the 4.2° lattice (points within 2.4°, the 20 dB echo's detection
radius), of which the first pass is a part (turned by 30°): it adds only its other two
thirds."""
AUTO_SEARCH: dict[str, Any] = {
    "fine_radius": 3.0,
    "passes": (STRONG_ECHO_SPACING, WEAK_ECHO_SPACING),
    "posterior": True,
}
"""auto's search [deg] — its only difference from ``acquisition``: the 1° lattice
within 3° of x0, then two passes over the disc of ``max_radius``, coarse to fine (see the
evidence above and :func:`~echocal.calibrate.search_pattern.search_rings`), or, on a
simulated probe with an echo of 15 dB or more, the posterior search (item 9), unless the
caller sets where to search (``passes``, ``growth``, ``max_spacing`` or ``fine_radius``
without ``posterior=True``).  The passes are
the default for an objective that cannot size them from its probe
(:meth:`~echocal.calibrate.Objective.search_passes` returns None); the driver puts the
probe's own in their place unless the caller sets ``passes``, ``growth`` or
``max_spacing``."""


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
