"""The uncertainty of a calibration's estimate: a confidence radius [deg] from the
measurements around it (private to the driver).

Model: near its peak the echo energy (noise floor removed) is f(x) = exp(m(x)), m a
quadratic (:func:`~echocal.calibrate.local_model.fit_quadratic`, fitted here to the
measurements on the lobe's top: within twice the farthest half-maximum measurement of the
estimate), measured with independent Gaussian noise of the σ an energy has at its level
(:func:`~echocal.calibrate.evidence.energy_sigma`).  The fitted parameters' covariance is
the Gauss–Newton one, (Jᵀ W J)⁻¹ with W = 1/σ², inflated by the reduced χ² when the
quadratic fits worse than the noise explains; the peak x̂ = centre − H⁻¹ b carries it by the
delta method.  The radius at ``level`` is that of the covariance's long axis, √(χ²₂(level)
λ_max), plus the distance from the estimate to x̂ (the recommendation may be another model's
peak, e.g. the lobe template's), so it bounds the estimate's error, not only x̂'s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.evidence import energy_sigma
from echocal.calibrate.local_model import QuadraticModel, fit_quadratic

__all__ = ["UNCERTAINTY_LEVEL", "coverage", "estimate_radius", "peak_covariance"]

UNCERTAINTY_LEVEL = 0.9
"""The confidence level of the radius a calibration reports."""
_TOP = 0.5
"""The lobe's top: measurements above this fraction of the strongest of the estimate's 7
nearest, connected to them (each within :data:`_REACH` times the farthest so far)."""
_REACH = 2.0
"""The fit takes the measurements within this many times the top's reach of the estimate."""
_MIN_POINTS = 7
"""A quadratic has 6 parameters: fewer measurements on the lobe's top say nothing."""


def _features(d: FloatArray) -> FloatArray:
    """∂m/∂(c, b₁, b₂, H₁₁, H₁₂, H₂₂) at offsets ``d`` (k, 2) [deg]: shape (k, 6)."""
    u, v = d.T
    return np.stack([np.ones(len(d)), u, v, 0.5 * u * u, u * v, 0.5 * v * v], axis=1)


def peak_covariance(
    model: QuadraticModel, points: FloatArray, energies: FloatArray, sigmas: FloatArray
) -> FloatArray | None:
    """[deg²] (2, 2) covariance of the peak of the log-quadratic ``model`` fitted to
    ``energies`` (k,) (floor removed) measured at ``points`` (k, 2) [deg] with noise σ
    ``sigmas`` (k,); None when the model is not concave or the fit is singular."""
    if model.space != "log" or not model.concave:
        return None
    d = points - model.center
    f = model.energy(points)
    jac = f[:, None] * _features(d)  # ∂f/∂θ
    w = 1.0 / np.maximum(sigmas, 1e-300) ** 2
    info = jac.T @ (w[:, None] * jac)
    try:
        cov = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        return None
    dof = len(points) - 6
    chi2 = float(np.sum(w * (energies - f) ** 2))
    cov *= max(1.0, chi2 / dof) if dof > 0 else 1.0
    h_inv = np.linalg.inv(model.H)
    delta = -h_inv @ model.b  # the peak's offset from the centre
    # ∂x̂/∂θ: db → −H⁻¹ db; dH → −H⁻¹ dH δ
    g = np.zeros((2, 6))
    g[:, 1:3] = -h_inv
    g[:, 3] = -h_inv @ np.array([delta[0], 0.0])
    g[:, 4] = -h_inv @ np.array([delta[1], delta[0]])
    g[:, 5] = -h_inv @ np.array([0.0, delta[1]])
    out = g @ cov @ g.T
    return out if np.all(np.isfinite(out)) else None


def estimate_radius(
    x: FloatArray,
    points: FloatArray,
    values: FloatArray,
    noise: tuple[float | None, float | None],
    level: float = UNCERTAINTY_LEVEL,
) -> float | None:
    """[deg] the radius around the estimate ``x`` (2,) [deg] that holds the optimum with
    probability ``level`` (see the module doc), from the run's ``points`` (n, 2) [deg] and
    ``values`` (n,); None when the noise ``(floor, σ)`` is unknown or the measurements on
    the lobe's top do not show a peak."""
    floor, sigma = noise
    ok = np.isfinite(values)
    if floor is None or sigma is None or not sigma > 0.0 or np.count_nonzero(ok) < _MIN_POINTS:
        return None
    pts, y = points[ok], values[ok] - floor
    dist = np.hypot(*(pts - x).T)
    nearest = np.argsort(dist)[:_MIN_POINTS]
    top = float(y[nearest].max())
    if top <= 0.0:
        return None
    strong = y >= _TOP * top
    reach = float(dist[nearest][strong[nearest]].max())
    for _ in range(8):  # the lobe's top: strong measurements connected to the estimate's
        grown = float(dist[strong & (dist <= _REACH * reach)].max())
        if grown <= reach:
            break
        reach = grown
    fit = dist <= _REACH * reach
    if np.count_nonzero(fit) < _MIN_POINTS:
        return None
    model = fit_quadratic(pts[fit], y[fit], x, space="log", scale=max(reach, 1e-6), floor=0.05)
    if model is None:
        return None
    sig = energy_sigma(values[ok][fit], floor, sigma)
    cov = peak_covariance(model, pts[fit], y[fit], sig)
    if cov is None:
        return None
    peak = model.argmax()
    q = -2.0 * np.log1p(-level)  # χ² with 2 degrees of freedom at ``level``
    spread = float(np.sqrt(q * max(float(np.linalg.eigvalsh(cov)[-1]), 0.0)))
    return float(np.hypot(*(x - peak))) + spread


def coverage(errors: ArrayLike, radii: Sequence[float | None]) -> tuple[float, float]:
    """(the fraction of runs whose error [deg] (n,) lies within the radius [deg] they
    reported, the fraction that reported one): a run without a radius counts as not
    covered."""
    r = np.array([np.nan if v is None else float(v) for v in radii])
    covered = np.isfinite(r) & (np.asarray(errors, dtype=np.float64) <= np.nan_to_num(r, nan=-1.0))
    n = max(len(r), 1)
    return float(covered.sum() / n), float(np.isfinite(r).sum() / n)
