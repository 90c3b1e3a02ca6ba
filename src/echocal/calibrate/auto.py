"""``method="auto"``: acquisition phase + the best local method we measured (model-based).

:class:`Auto` searches outward from ``x0`` until an A-scan shows the echo, then refines
with :class:`~echocal.calibrate.model_based.ModelBased`.  The parts, in the order a run
meets them:

1. the model-based fit subtracts the objective's live noise floor (``noise_estimate()``)
   before taking logs, so at low SNR the floor does not make the lobe look broader;
2. the acquisition phase tests each A-scan's matched-filter peak significance
   (:class:`~echocal.signal.detection.EchoDetector`; a first threshold, then a
   confirming re-measurement of a marginal detection), so a find on noise is not
   handed to the local method;
3. inside 3° of x0 the search keeps a 1° lattice, which a 10 dB echo needs (visible only
   within about 0.55–0.7°), unless x0's first ring saw nothing and the objective
   predicts an echo of ≥ 20 dB against the noise those 7 A-scans measured
   (:meth:`~echocal.calibrate.Objective.passes_for_measured_noise`, the ``replan``
   option): then the first pass is the coarsest for that SNR (below 20 dB one pass sized
   for that SNR follows the 1° lattice).  Beyond, two hexagonal passes out to
   ``max_radius``, coarse to fine, sized from the probe when the objective knows it
   (:meth:`~echocal.calibrate.Objective.search_passes`: the coarsest lattices that detect
   a 30 dB, then a 20 dB echo from 99 % of the plane, from the probe's noiseless lobe,
   :mod:`echocal.measurement.detection_radius`), else :data:`AUTO_SEARCH`'s 7.27° and
   4.2°, sized for the 5 MHz probe;
4. the local method fits the measurements the acquisition hands it before its first step;
5. the local model refutes itself when a measurement stands clearly above its maximum,
   or the strongest measurement stands twice above the model's value there (a fit to a
   lobe's flat tail), and refits a smaller neighbourhood; it searches once across a
   ridge, and along both axes of a peak refined twice below 0.4 of the echo at normal
   incidence where the objective knows that echo
   (:meth:`~echocal.calibrate.Objective.normal_echo`): such a peak is a side lobe;
6. the local model's log-space noise (the tolerance of its trust-region test) is capped
   at a factor e once its incumbent is a significant echo;
7. from the lobe's tail the local method follows the probe's lobe
   (:meth:`~echocal.calibrate.Objective.lobe_template`,
   :mod:`echocal.calibrate.lobe_template`): fitted to every measurement, its fitted peak
   is the next point until one lies on the lobe's top;
8. from a detection deep in the tail that the template's fit does not yet show as an
   echo, the local method seeks the peak (:mod:`echocal.calibrate.template_seek`): the
   next point is where the candidate peaks' predicted echoes disagree most;
9. beyond x0's first ring, on a simulated probe whose echo the first ring's noise puts
   at 15 dB or more, the search follows the posterior over the optimum
   (:mod:`echocal.calibrate.posterior_search`, the ``posterior`` option): every A-scan's
   significance updates it, and the next point is where a detection is most likely.
   On a recording or a rig, whose echo amplitude is unknown, at any SNR, over
   hypotheses on that amplitude (and on the lobe's width where no setup gives its shape:
   :mod:`echocal.calibrate.echo_hypotheses`).  Below 15 dB on the simulator, the
   passes of item 3;
10. a detection the local method does not confirm within its first
   :data:`~echocal.calibrate.acquisition.CONFIRM_WITHIN` (8) measurements — none of them,
   nor all together, significant at the detection threshold — is a false alarm: the
   search resumes where it stood (the lattice's next point, or the posterior, which
   keeps every measurement), the false alarm's neighbourhood no longer counting towards
   a detection (``result.false_alarms`` counts them).

The result reports ``uncertainty``, a radius [deg] around the estimate that holds the
optimum with 90 % probability (:mod:`echocal.calibrate.uncertainty`: the delta-method
spread of a log-quadratic's peak fitted to the measurements on the lobe's top, plus the
estimate's distance to that peak).

In tilt angles a recording or a rig is searched by the posterior too (item 9); in
(azimuth, co-elevation), or with ``posterior=False``, a search without a probe model spends
the 1° lattice first; ``fine_radius=1.0`` drops it when the SNR is known to be ≥ 20 dB.
When the start is known to be near the echo, ``method="model-based"`` saves the
acquisition.

Evidence: ``benchmarks/bench_calibration.py`` and the pages of the documentation's
benchmarks section (the summary, ``auto``, lower bound, curved parts), which also record
how each number changed with each part.  On ``immersion-5mhz`` (wave model, budget 80,
tilt parameterization), from 1–3° every run reaches 0.1° within 40 measurements at 30,
20 and 10 dB; from 5–20° the median / p99 measurements to 0.1° are 17 / 24 at 30 dB,
27 / 59 at 20 dB and 262 / 535 at 10 dB.  On hold-out seeds (``benchmarks/bench_tails.py``,
300 runs per far cell) 100 % of far starts at 30 dB and 99 % at 20 dB reach 0.1° within
60 measurements, and the 90 % radius covers the truth in 94–98 % of runs.
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
simulated probe with an echo of 15 dB or more, or a recording or a rig, the posterior
search (item 9), unless the
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
