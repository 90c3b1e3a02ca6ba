"""Where to measure when the lobe's tail says the echo is near but not where: the point whose
value the possible peaks disagree on most.

A far search hands over its first detection, often deep in the lobe's tail (4–7° out at
30 dB, 1.2–1.7 × the noise floor).  One tail value with the peak's known energy says how
far the peak is, not in which direction: the peaks that fit the measurements lie on an arc
around the detection, minus the directions the search already measured empty.  There the
template's least-squares fit is not significant, and the design hexagon of 1° around the
detection that measured instead tells little (6 values within a few noise σ of each other).

:func:`seek_point` weighs every candidate peak c on a grid by its likelihood
exp(−χ²(c)/2) (the template fit's χ², the prior on the peak's energy included) and
measures next where the echo predicted by those candidates varies most — in units of the
noise σ, capped at :data:`SEEK_CAP` σ (a predicted echo that far above the noise is
unmistakable, whatever its size).  On an arc of candidates that is a point on the arc,
where half of them predict a clear echo and half predict noise; at the detection itself,
where the candidates predict about the value measured there, it is least.  Each
measurement there either finds the echo (the fit becomes significant and the template's
steps take over) or removes the candidates near it.
"""

from __future__ import annotations

import numpy as np

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.lobe_template import (
    COARSE_STEP,
    LobeTemplate,
    disc_grid,
    energy_prior,
    peak_scores,
)

__all__ = ["SEEK_CAP", "seek_point", "tail_reach"]

SEEK_CAP = 10.0
"""[σ] a predicted echo this far above the noise counts as seen, however strong."""
_KEEP_LIKELIHOOD = 1e-4
"""Candidate peaks less likely than this fraction of the best are left out."""


def tail_reach(template: LobeTemplate, peak: float, sigma: float, level: float = 3.0) -> float:
    """[deg] the largest misalignment at which the lobe of peak metric ``peak`` is still
    ``level`` × ``sigma`` (same units) above the noise in its strongest direction: how far
    from a detection its peak can be."""
    strongest = template.values.max(axis=0)
    seen = template.angles[peak * strongest >= level * sigma]
    return float(seen.max()) if seen.size else 0.0


def seek_point(
    template: LobeTemplate,
    points: FloatArray,
    values: FloatArray,
    sigmas: FloatArray,
    sigma: float,
    peak: float,
    around: FloatArray,
    radius: float,
) -> FloatArray | None:
    """The next point [deg] (2,) of the seek, within ``radius`` [deg] of ``around`` (2,).

    ``points`` [deg] (n, 2), ``values`` (n,) the echo's metric (noise floor removed) and
    ``sigmas`` (n,) their noise σ (> 0), as for
    :func:`~echocal.calibrate.lobe_template.fit_template`; ``sigma`` the noise σ of a
    measurement of no echo and ``peak`` the metric at the lobe's peak (same units).  The
    candidate peaks are a 0.2° grid within ``radius`` of ``around``, the candidate points
    a 0.4° grid.  None when no candidate peak gives a positive energy."""
    if not (sigma > 0.0 and peak > 0.0):
        from echocal.errors import EchocalValueError

        raise EchocalValueError(
            f"seek_point needs a noise sigma > 0 and a peak metric > 0; got {sigma!r}, {peak!r}"
        )
    ok = np.isfinite(values) & (sigmas > 0.0)
    x, y, w = points[ok], values[ok], 1.0 / sigmas[ok] ** 2
    centres = disc_grid(around, radius, COARSE_STEP)
    chi2, energy, *_ = peak_scores(template, centres, x, y, w, energy_prior(peak))
    usable = energy > 0.0
    if not usable.any():
        return None
    log_like = np.where(usable, -0.5 * (chi2 - chi2[usable].min()), -np.inf)
    keep = log_like >= np.log(_KEEP_LIKELIHOOD)
    weight = np.exp(log_like[keep])
    weight /= weight.sum()
    probes = disc_grid(around, radius, 2.0 * COARSE_STEP)
    predicted = energy[keep] * template(probes[:, None, :] - centres[None, keep, :])
    z = np.minimum(predicted / sigma, SEEK_CAP)  # (probes, candidates)
    mean = z @ weight
    spread = (z * z) @ weight - mean * mean
    return probes[int(np.argmax(spread))].copy()
