"""The local model of ``model-based``: a quadratic of log-energy, its fit and its maximum
in a trust region (see ``echocal.calibrate.model_based`` for why and how it is used).

- :func:`fit_quadratic`: m(x) = c + bᵀd + ½ dᵀHd (d = x − centre), weighted least squares of
  log f (weights ∝ f², as var(log f) ≈ σ²/f²) or of f itself, with a weak prior on the
  curvature and a final exp-fit of f (:func:`_refine_exp_fit`);
- :class:`QuadraticModel`: its value, maximum, widths and energy;
- :func:`trust_region_max`: the model's maximizer in a ball (Levenberg shift);
- :func:`hexagon`: the rotatable 7-point design.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray

__all__ = [
    "REFUTE",
    "REFUTE_RELATIVE",
    "QuadraticModel",
    "fit_quadratic",
    "hexagon",
    "trust_region_max",
]

REFUTE = 4.0
"""A measurement this many of its noise σ above the model's maximum refutes the model."""
REFUTE_RELATIVE = 0.05
"""... and by this fraction of that maximum (a smooth peak's top is fitted within a few %;
the central peak over a ball stands 25 % above the ring around it)."""


def hexagon(center: FloatArray, radius: float) -> FloatArray:
    """``center`` and 6 points on a circle of ``radius`` [deg], shape (7, 2)."""
    ang = np.arange(6) * np.pi / 3.0
    ring = center[None, :] + radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    return np.vstack([center[None, :], ring])


@dataclass(frozen=True, slots=True)
class QuadraticModel:
    """m(x) = c + bᵀ(x − center) + ½ (x − center)ᵀ H (x − center).

    center : [deg] (2,); c : model value at centre; b : (2,); H : (2, 2).
    space : ``"log"`` (m models log f) or ``"linear"``.
    """

    center: FloatArray
    c: float
    b: FloatArray
    H: FloatArray
    space: str

    def __call__(self, x: ArrayLike) -> FloatArray:
        """Model values at points [deg], shape (k, 2) -> (k,)."""
        d = np.atleast_2d(np.asarray(x, dtype=np.float64)) - self.center
        return self.c + d @ self.b + 0.5 * np.einsum("ki,ij,kj->k", d, self.H, d)

    @property
    def concave(self) -> bool:
        """True when H is negative definite."""
        return bool(np.linalg.eigvalsh(self.H)[-1] < 0.0)

    def argmax(self) -> FloatArray:
        """Stationary point x* = centre − H⁻¹ b [deg] (the maximum when concave)."""
        return self.center - np.linalg.solve(self.H, self.b)

    def width(self) -> FloatArray:
        """(−H)^{−1/2}, shape (2, 2) [deg]: the peak's 1-σ ellipse (log space, concave only)."""
        eig, vec = np.linalg.eigh(-self.H)
        return vec @ np.diag(1.0 / np.sqrt(eig)) @ vec.T

    def energy(self, x: ArrayLike) -> FloatArray:
        """Model of f itself at points (k, 2): exp(m) in log space."""
        m = self(x)
        return np.exp(np.minimum(m, 700.0)) if self.space == "log" else m


def fit_quadratic(
    points: FloatArray,
    values: FloatArray,
    center: FloatArray,
    *,
    space: str,
    scale: float,
    locality: float | None = None,
    floor: float = 0.0,
    refine: bool = True,
) -> QuadraticModel | None:
    """Weighted least-squares quadratic fit (see the module doc); None if underdetermined.

    Parameters
    ----------
    points : [deg] ``(n, 2)``.
    values : ``(n,)``, finite.
    center : [deg] ``(2,)``, the model's centre.
    space : ``"log"`` or ``"linear"``.
    scale : [deg] length for conditioning.
    locality : [deg] only points within this distance of ``center`` are fitted (None: all).
    floor : log space only — points below ``floor`` × the largest fitted value are left
        out (at the noise floor log y says nothing about log f, and its residual would grow
        with the squared distance from the peak); if fewer than 8 remain, the 8 largest
        positive values are used.
    refine : log space only — starting from that weighted log fit, fit f = exp(m) to *all*
        local values (noise-floor and negative ones included) by nonlinear least squares
        with equal weights, the maximum-likelihood fit for additive noise of fixed σ.
    """
    if locality is not None:
        near = np.hypot(*(points - center).T) <= locality
        points, values = points[near], values[near]
    d_all, y_all = (points - center) / scale, values
    d = d_all
    if space == "log":
        keep = values > 0.0
        if np.any(keep) and floor > 0.0:
            strong = values > floor * values.max()
            if np.count_nonzero(strong) >= 8:
                keep &= strong
            else:
                top = np.argsort(values)[::-1][:8]
                keep &= np.isin(np.arange(len(values)), top)
        d, y = d[keep], values[keep]
        if len(y) < 6:
            return None
        z = np.log(y)
        w = (y / y.max()) ** 2
    else:
        if len(values) < 6:
            return None
        z, w = values, np.ones(len(values))
    if np.count_nonzero(w > 1e-8) < 6:
        return None
    phi = _features(d)
    sw = np.sqrt(w)
    ridge = np.sqrt(1e-12 * w.sum()) * np.eye(6)[1:]
    a = np.vstack([phi * sw[:, None], ridge])
    rhs = np.concatenate([z * sw, np.zeros(5)])
    coef, *_ = np.linalg.lstsq(a, rhs, rcond=None)
    if not np.all(np.isfinite(coef)):
        return None
    if space == "log" and refine and len(y_all) >= 7:
        coef = _refine_exp_fit(d_all, y_all, coef)
    b = coef[1:3] / scale
    h = np.array([[2.0 * coef[3], coef[4]], [coef[4], 2.0 * coef[5]]]) / scale**2
    return QuadraticModel(center=center.copy(), c=float(coef[0]), b=b, H=h, space=space)


_PRIOR = np.array([-0.5, 0.0, -0.5])
_PRIOR_STD = 0.5


def _features(d: FloatArray) -> FloatArray:
    """The quadratic's 6 basis functions at scaled offsets ``d`` (n, 2): shape (n, 6)."""
    return np.stack(
        [np.ones(len(d)), d[:, 0], d[:, 1], d[:, 0] ** 2, d[:, 0] * d[:, 1], d[:, 1] ** 2], 1
    )


def _refine_exp_fit(d: FloatArray, y: FloatArray, coef: FloatArray) -> FloatArray:
    """Least squares of y ≈ exp(φ(d)·β) from ``coef``; the start is kept if not improved."""
    from scipy.optimize import least_squares

    phi = _features(d)
    ymax = float(np.max(np.abs(y)))
    if ymax <= 0.0:
        return coef
    yn = y / ymax
    start = coef.copy()
    start[0] -= np.log(ymax)

    def model(beta: FloatArray) -> FloatArray:
        return np.exp(np.minimum(phi @ beta, 50.0))

    def res(beta: FloatArray) -> FloatArray:
        return model(beta) - yn

    def jac(beta: FloatArray) -> FloatArray:
        return model(beta)[:, None] * phi

    r0 = res(start)
    try:
        out = least_squares(res, start, jac=jac, method="trf", max_nfev=200)
    except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - defensive
        return coef
    if not (np.all(np.isfinite(out.x)) and out.cost < 0.5 * float(r0 @ r0)):
        return coef
    n = len(y)
    if n > 6:
        # weak prior on the curvature: a peak about as wide as the design radius
        # (scaled coordinates: -1/2 on the diagonal), std _PRIOR_STD, weighed against
        # the data with their noise estimate (negligible at high SNR, stabilizing at low)
        sig = np.sqrt(2.0 * out.cost / (n - 6))
        wp = sig / _PRIOR_STD

        def res_p(beta: FloatArray) -> FloatArray:
            return np.concatenate([res(beta), wp * (beta[3:] - _PRIOR)])

        def jac_p(beta: FloatArray) -> FloatArray:
            return np.vstack([jac(beta), wp * np.eye(6)[3:]])

        try:
            out2 = least_squares(res_p, out.x, jac=jac_p, method="trf", max_nfev=200)
            if np.all(np.isfinite(out2.x)):
                out = out2
        except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - defensive
            pass
    beta = out.x.copy()
    beta[0] += np.log(ymax)
    return beta


def trust_region_max(model: QuadraticModel, radius: float) -> FloatArray:
    """Maximizer [deg] of ``model`` in the ball of ``radius`` around its centre (2-D, by
    bisection on the Levenberg shift λ ≥ max(0, λ_max(H)))."""
    h, b = model.H, model.b
    eig = np.linalg.eigvalsh(h)
    if eig[-1] < 0.0:
        d = -np.linalg.solve(h, b)
        if np.hypot(*d) <= radius:
            return model.center + d
    bnorm = float(np.hypot(*b))
    if bnorm == 0.0:
        vec = np.linalg.eigh(h)[1][:, -1]
        return model.center + radius * vec
    lo = max(eig[-1], 0.0)
    hi = lo + bnorm / radius + float(np.abs(eig).max()) + 1e-12
    for _ in range(100):
        lam = 0.5 * (lo + hi)
        d = -np.linalg.solve(h - lam * np.eye(2), b)
        if np.hypot(*d) > radius:
            lo = lam
        else:
            hi = lam
    d = -np.linalg.solve(h - hi * np.eye(2), b)
    return model.center + d
