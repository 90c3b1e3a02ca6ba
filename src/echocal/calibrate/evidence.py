"""What a calibration result may claim: the evidence behind ``success``, and its uncertainty.

A run *converged* only when its own stopping rule fired (``xtol`` or ``settle``, as in
scipy's ``success``) **and** the data support the estimate:

- it does not sit on the positioner's angle limits (the optimum may lie beyond reach:
  status 8, whatever the stopping rule said);
- the final measurement at the estimate shows an echo clearly above the noise floor (the
  matched-filter significance above :data:`~echocal.constants.ECHO_THRESHOLD` when the
  objective has a detector, else the value ``5 σ`` above the noise floor: status 9);
- a method with a model has a concave one there (:attr:`Optimizer.concave`);
- the estimate lies inside the region sampled (the convex hull of the measured points);
- no measured point is clearly stronger than the estimate's own final measurement (by
  ``5 σ`` of the difference, σ an energy's noise at that level, :func:`energy_sigma`, and
  by 0.1 %): a quadratic fitted over a double-humped lobe (a large probe over a cylinder)
  puts its maximum between the humps (status 10 otherwise);
- where the objective knows a floor the optimum's echo exceeds
  (:meth:`~echocal.calibrate.objective.Objective.echo_floor`: half a simulator's echo at
  normal incidence), the echo at the estimate is above it — not a side lobe's or the grains'
  (status 10 otherwise).

The uncertainty of the estimate (:func:`estimate_radius`): near its peak the echo energy
(noise floor removed) is f(x) = exp(m(x)), m a quadratic
(:func:`~echocal.calibrate.local_model.fit_quadratic`, fitted to the measurements on the
lobe's top: within twice the farthest half-maximum measurement of the estimate), with
independent Gaussian noise of the σ an energy has at its level (:func:`energy_sigma`).  The
parameters' covariance is the Gauss–Newton (Jᵀ W J)⁻¹, W = 1/σ², inflated by the reduced χ²
when the quadratic fits worse than the noise explains; the peak x̂ = centre − H⁻¹ b carries
it by the delta method.  The radius at ``level`` is the covariance's long axis,
√(χ²₂(level) λ_max), plus the distance from the estimate to x̂ (the recommendation may be
another model's peak), so it bounds the estimate's error, not only x̂'s.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import Delaunay, QhullError

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.base import Optimizer
from echocal.calibrate.local_model import QuadraticModel, fit_quadratic
from echocal.calibrate.objective import Objective
from echocal.constants import ECHO_THRESHOLD

__all__ = [
    "UNCERTAINTY_LEVEL",
    "at_limit",
    "coverage",
    "echo_at_estimate",
    "energy_sigma",
    "estimate_radius",
    "judge",
    "peak_covariance",
    "unsupported_claim",
]

_K = 5.0
"""Evidence margin in standard deviations."""
_RELATIVE = 1e-3
"""A measured point must beat the estimate by this fraction too (0.1 %: a lobe of width w
drops by that much 0.045 w from its peak, far below a settle tolerance's worth)."""


def at_limit(x: FloatArray, bounds: FloatArray, atol: float = 1e-6) -> bool:
    """True when ``x`` [deg] (2,) lies on a finite bound of ``bounds`` [deg] (2, 2)."""
    finite = np.isfinite(bounds)
    near = np.isclose(x[:, None], bounds, rtol=0.0, atol=atol) & finite
    return bool(np.any(near))


def energy_sigma(values: FloatArray, floor: float, sigma: float) -> FloatArray:
    """[energy units] noise σ of an energy-like metric measured at ``values`` (k,).

    For a windowed energy of W samples with per-sample noise σₙ, pure noise has mean
    ``floor`` = W σₙ² and σ = σₙ² √(2W); at an echo of energy E = value − floor the
    cross term adds 4 σₙ² E, i.e. σ² (1 + 2E / floor)."""
    echo = np.maximum(np.asarray(values, dtype=np.float64) - floor, 0.0)
    ratio = 2.0 * echo / floor if floor > 0.0 else np.zeros_like(echo)
    return sigma * np.sqrt(1.0 + ratio)


def echo_at_estimate(objective: Objective, final: FloatArray) -> bool | None:
    """Whether the final measurements ``final`` (n,) at the estimate show an echo clearly
    above the noise floor; None when the objective cannot tell (no detector, no noise)."""
    significance = objective.detections()
    if significance is not None and np.any(np.isfinite(significance)):
        g = significance[np.isfinite(significance)]
        return bool(g.sum() / np.sqrt(g.size) > ECHO_THRESHOLD)  # Stouffer over repeats
    floor, sigma = objective.noise_estimate()
    good = final[np.isfinite(final)]
    if floor is None or sigma is None or not good.size:
        return None
    return bool(good.mean() > floor + _K * sigma / np.sqrt(good.size))


def _inside_hull(x: FloatArray, points: FloatArray) -> bool:
    """True when ``x`` (2,) lies in the convex hull of ``points`` (n, 2) [deg] (its edge
    included, to 1e-9 relative)."""
    pts = np.unique(points[np.all(np.isfinite(points), axis=1)], axis=0)
    if len(pts) < 3:
        return bool(len(pts) and np.any(np.all(np.isclose(pts, x, atol=1e-9), axis=1)))
    try:
        hull = Delaunay(pts)
    except QhullError:  # all on one line: no area was sampled
        return False
    return bool(hull.find_simplex(x[None, :], tol=1e-9)[0] >= 0)


def unsupported_claim(
    x: FloatArray,
    points: FloatArray,
    values: FloatArray,
    final: FloatArray | None,
    *,
    concave: bool | None,
    noise: tuple[float | None, float | None],
) -> str | None:
    """Why a converged-looking run's estimate ``x`` [deg] (2,) is not supported by its
    measurements (``points`` (n, 2) [deg], ``values`` (n,)), or None when it is.

    final : the values measured at ``x`` at the end (None: not measured);
    concave : the method's model is concave at ``x`` (None: the method has no model);
    noise : the objective's ``(noise_floor, noise_sigma)``.
    """
    if concave is False:
        return "the method's model is not concave at the estimate"
    if not _inside_hull(x, points):
        return "the estimate lies outside the region sampled"
    good = None if final is None else final[np.isfinite(final)]
    if good is None or not good.size:
        return None
    floor, sigma = noise
    if floor is None or sigma is None:
        return None
    level = float(good.mean())
    mask = np.isfinite(values)
    spread = np.hypot(
        energy_sigma(values[mask], floor, sigma),
        energy_sigma(np.array([level]), floor, sigma)[0] / np.sqrt(good.size),
    )
    stronger = values[mask] - level > _K * spread + _RELATIVE * abs(level)
    if np.any(stronger):
        best = int(np.argmax(np.where(stronger, values[mask], -np.inf)))
        p = points[mask][best]
        return (
            f"a measured point ({p[0]:.3f}, {p[1]:.3f}) deg is clearly stronger than the "
            f"estimate ({values[mask][best]:.4g} against {level:.4g})"
        )
    return None


def judge(
    status: int,
    x: FloatArray,
    opt: Optimizer,
    objective: Objective,
    searched: tuple[FloatArray, FloatArray],
    final: FloatArray | None,
) -> tuple[int, str]:
    """The status a run may report, and a detail for its message ("" or "; ...").

    status : why the loop stopped; x : [deg] (2,) the estimate; searched : the points (n, 2)
    [deg] and values (n,) the run measured before its final measurement ``final`` (k,) at
    ``x`` (None if none).  Warns when the estimate is at the angle limits."""
    points, values = searched
    if len(values) and not np.any(np.isfinite(values)):
        return 6, ""
    if status == 4:
        return status, ""
    if at_limit(x, objective.bounds):
        names = objective.names
        warnings.warn(
            f"the estimate ({names[0]}={x[0]:.3f}, {names[1]}={x[1]:.3f}) deg lies on the "
            "positioner's angle limits: the optimum may be beyond reach; move the probe, "
            "widen the limits or start elsewhere (status 8, not a success)",
            UserWarning,
            stacklevel=3,
        )
        return 8, ""
    if final is not None and echo_at_estimate(objective, final) is False:
        return 9, " (measured there at the end)"
    floor = objective.echo_floor()
    if status in (0, 7) and floor is not None and final is not None:
        level = float(np.nanmean(final)) if np.any(np.isfinite(final)) else -np.inf
        if level < floor:
            return 10, (
                f" ({STATUS_CLAIMS[status]}, but the echo at the estimate ({level:.4g}) is "
                f"less than half the probe's echo at normal incidence ({2.0 * floor:.4g}): "
                "the peak found is not the surface's main lobe (a side lobe, grain noise); "
                "start nearer or gate the front-wall echo"
            )
    if status in (0, 7):
        reason = unsupported_claim(
            x,
            points,
            values,
            final,
            concave=opt.concave,
            noise=objective.noise_estimate(),
        )
        if reason is not None:
            return 10, f" ({STATUS_CLAIMS[status]}, but {reason})"
    return status, ""


STATUS_CLAIMS = {0: "the iterate stopped moving", 7: "the recommendation settled"}
"""What the stopping rule of a withdrawn convergence claim said."""


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
