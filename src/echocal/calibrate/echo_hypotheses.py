"""The echo's likelihood when its amplitude, and perhaps its lobe's width, are not known.

A simulated probe measured in its own units says exactly how strong its echo is against
the noise it measures (:class:`~echocal.calibrate.posterior_search.EchoLikelihood`).  A
recording or a rig does not: the receiver's gain, the coupling and the part's
reflectivity set the echo's amplitude, and without a setup even the lobe's shape is
unknown.  :class:`EchoHypotheses` keeps one
:class:`~echocal.calibrate.posterior_search.EchoLikelihood` per hypothesis on these
nuisance parameters, with prior weights; the posterior search carries a posterior
over (optimum, hypothesis) and marginalizes the hypotheses
(:class:`~echocal.calibrate.posterior_search.PosteriorSearch`).

Model (what both constructors assume):

* the noise is what the detector is calibrated on: its σ is measured from the A-scans
  themselves (the significance each measurement reports is against it), so the peak t is
  in units of σ · the detector's noise gain and needs no further nuisance parameter;
* the noiseless matched-filter peak at misalignment θ from the optimum is ν(θ) = A·s(θ),
  s(0) = 1, isotropic (one profile for every direction), peaking at the optimum;
* A, the peak at the optimum in units of the noise's Rayleigh scale, is unknown: a prior
  uniform in 20·log10 A over :data:`AMPLITUDE_DB` (30–60 dB: the 12.7 mm 5 MHz probe's
  echo at a peak SNR of 10 to 40 dB on the wave model, whose matched filter gains about
  20 dB), on a 3 dB grid — a weaker echo is not searched for (a hypothesis that sees
  nothing would keep the search from ever giving up);
* the lobe's shape s: from the setup's physics where the source names one
  (:func:`scaled_lobe`: a rig file's ``setup``, a recording's stored setup), else a
  Lorentzian s(θ) = 1 / (1 + (θ/w)²) whose width w is unknown too, uniform in log w over
  :data:`WIDTHS` (:func:`lorentzian_lobes`).  The Lorentzian follows a piston probe's
  diffraction lobe, tails included: the 12.7 mm 5 MHz probe's matched-filter peak on the
  wave model falls to 0.5 / 0.1 / 0.03 / 0.01 at 0.6 / 1.6 / 3.7 / 6.3°, a Lorentzian of
  w = 0.6° to 0.5 / 0.12 / 0.026 / 0.009 (a Gaussian of the same half width to
  0.5 / 0.007 / 4·10⁻¹² / 10⁻³³: no tail, where a far search sees the echo first).  A lobe
  without tails (the ray model) is broader under this model than it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.posterior_search import EchoLikelihood
from echocal.errors import EchocalValueError

__all__ = ["AMPLITUDE_DB", "WIDTHS", "EchoHypotheses", "lorentzian_lobes", "scaled_lobe"]

AMPLITUDE_DB = tuple(float(a) for a in np.arange(30.0, 60.5, 3.0))
"""[dB] 20·log10 A of the echo's matched-filter peak at the optimum (in units of the
noise's Rayleigh scale) under each hypothesis, equally likely a priori (module docstring)."""
WIDTHS = (0.3, 0.6, 1.2, 2.4)
"""[deg] the Lorentzian lobe's half width w under each hypothesis, equally likely a priori."""
_LORENTZ_ANGLES = np.arange(0.0, 15.05, 0.1)
"""[deg] misalignments the Lorentzian lobes are tabulated at (beyond: no echo)."""


@dataclass(frozen=True, eq=False)
class EchoHypotheses:
    """One :class:`~echocal.calibrate.posterior_search.EchoLikelihood` per hypothesis on
    the echo's unknown amplitude (and lobe width), and the hypotheses' prior weights.

    Attributes
    ----------
    likelihoods : the hypotheses' likelihoods, shape ``(k,)``; all on the same
        ``angles``, ``n_cells`` and ``threshold`` (one detector).
    log_weights : ln of the prior weights, shape ``(k,)`` (normalized here).
    label : what the hypotheses are (reported with the result).
    """

    likelihoods: tuple[EchoLikelihood, ...]
    log_weights: FloatArray
    label: str = "hypotheses"

    def __post_init__(self) -> None:
        likes = tuple(self.likelihoods)
        weights = np.asarray(self.log_weights, dtype=np.float64)
        if not likes or weights.shape != (len(likes),) or not np.all(np.isfinite(weights)):
            raise EchocalValueError(
                f"log_weights must be finite, one per likelihood ({len(likes)}); got shape "
                f"{weights.shape}"
            )
        first = likes[0]
        for like in likes[1:]:
            same = (
                np.array_equal(like.angles, first.angles)
                and like.n_cells == first.n_cells
                and like.threshold == first.threshold
            )
            if not same:
                raise EchocalValueError(
                    "every hypothesis must share the angles, n_cells and threshold (one detector)"
                )
        weights = weights - np.logaddexp.reduce(weights)
        object.__setattr__(self, "likelihoods", likes)
        object.__setattr__(self, "log_weights", weights)

    @property
    def angles(self) -> FloatArray:
        """[deg] the misalignments every hypothesis is tabulated at, shape ``(n,)``."""
        return self.likelihoods[0].angles

    def detection_probability(self) -> FloatArray:
        """P(t > threshold) at the echo's cell under the prior, shape ``(n,)``: the
        hypotheses' Marcum Q weighted by their prior weights."""
        weights = np.exp(self.log_weights)
        return np.asarray(
            sum(
                w * like.detection_probability()
                for w, like in zip(weights, self.likelihoods, strict=True)
            ),
            dtype=np.float64,
        )


def _amplitudes(amplitudes_db: ArrayLike) -> FloatArray:
    """A for each 20·log10 A [dB] of ``amplitudes_db``, shape ``(k,)``."""
    db = np.asarray(amplitudes_db, dtype=np.float64).reshape(-1)
    if db.size == 0 or not np.all(np.isfinite(db)):
        raise EchocalValueError(f"amplitudes_db must be finite dB values; got {db!r}")
    return np.asarray(10.0 ** (db / 20.0), dtype=np.float64)


def scaled_lobe(
    angles: ArrayLike,
    shape: ArrayLike,
    n_cells: float,
    threshold: float,
    amplitudes_db: ArrayLike = AMPLITUDE_DB,
) -> EchoHypotheses:
    """The hypotheses for a known lobe shape ``shape`` (s(θ) at ``angles`` [deg], shape
    ``(n,)``, normalized here to 1 at θ = 0) of unknown amplitude: one per 20·log10 A in
    ``amplitudes_db`` [dB], equally likely; ``n_cells`` and ``threshold`` as
    :class:`~echocal.calibrate.posterior_search.EchoLikelihood`'s (the detector's)."""
    s = np.asarray(shape, dtype=np.float64)
    if s.ndim != 1 or not s.size or not s[0] > 0.0:
        raise EchocalValueError("shape must be 1-D and > 0 at 0 deg (the lobe's peak)")
    s = s / s[0]
    amps = _amplitudes(amplitudes_db)
    likes = tuple(
        EchoLikelihood(
            angles=np.asarray(angles, float), echo=a * s, n_cells=n_cells, threshold=threshold
        )
        for a in amps
    )
    return EchoHypotheses(likes, np.zeros(len(likes)), label="lobe-shape")


def lorentzian_lobes(
    n_cells: float,
    threshold: float,
    widths: ArrayLike = WIDTHS,
    amplitudes_db: ArrayLike = AMPLITUDE_DB,
) -> EchoHypotheses:
    """The hypotheses for a lobe of unknown shape: a Lorentzian 1 / (1 + (θ/w)²) for each
    width w of ``widths`` [deg] times each amplitude of ``amplitudes_db`` [dB], equally
    likely, tabulated out to 15° (module docstring)."""
    w = np.asarray(widths, dtype=np.float64).reshape(-1)
    if w.size == 0 or not np.all(np.isfinite(w) & (w > 0.0)):
        raise EchocalValueError(f"widths must be finite and > 0 deg; got {w!r}")
    amps = _amplitudes(amplitudes_db)
    theta = _LORENTZ_ANGLES
    likes = tuple(
        EchoLikelihood(
            angles=theta,
            echo=a / (1.0 + (theta / width) ** 2),
            n_cells=n_cells,
            threshold=threshold,
        )
        for width in w
        for a in amps
    )
    return EchoHypotheses(likes, np.zeros(len(likes)), label="lorentzian")
