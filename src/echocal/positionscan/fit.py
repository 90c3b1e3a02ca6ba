"""Time-of-flight surface fit of a position scan: a plane, a sphere or a cylinder.

Each trace's front-wall time of flight τᵢ (:func:`~echocal.positionscan.front_wall_tof`)
minus the zero offset τ₀ gives the water path dᵢ = c₀(τᵢ − τ₀)/2 from the probe position
pᵢ = (xᵢ, yᵢ, z₀).  The model is the echo of a small probe: it returns along the surface
normal through the probe, so dᵢ is the shortest distance from pᵢ to the surface —

* plane with unit normal n (gimbal tilts ``tilt_x``, ``tilt_y``; the beam of a level probe
  meets it at normal incidence for tilts 0, 0): dᵢ = n·(pᵢ − p_c) + D, where p_c is the
  scan's centre and D its distance from the plane;
* sphere (centre c, radius R): dᵢ = |pᵢ − c| − R;
* cylinder (axis through a with direction u, radius R): dᵢ = |(pᵢ − a) × u| − R.

The fit is robust (``scipy.optimize.least_squares``, ``soft_l1`` loss scaled by the
residuals' robust spread), then repeated without the loss on the traces within 4 robust σ
of it; the 1-σ uncertainties are the diagonal of s²(JᵀJ)⁻¹ at that solution, with s² the
residual variance (Σr²/(n − p)); the distance's and the radius's also hold the error of
the time origin common to all traces (the template's, c₀σ₀/2).  Derived angles (azimuth,
co-elevation) carry the propagated σ (delta method, numerical derivatives).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from echocal.errors import EchocalValueError
from echocal.geometry import normal_to_orientation, tilt_normal
from echocal.positionscan.dataset import PositionScan
from echocal.positionscan.tof import (
    front_wall_tof,
    stacked_template,
    template_origin_sigma,
    tof_noise,
)
from echocal.signal.gates import TimeGate

__all__ = ["SHAPES", "SurfaceFit", "fit_surface", "scan_distances"]

SHAPES = ("plane", "sphere", "cylinder")
"""The shapes :func:`fit_surface` fits."""

FloatArray = NDArray[np.float64]

_INLIER_SIGMAS = 4.0
"""Traces farther than this many robust σ from the robust fit are outliers."""


@dataclass(frozen=True)
class SurfaceFit:
    """A fitted surface (plain data).

    Attributes
    ----------
    shape : ``plane``, ``sphere`` or ``cylinder``.
    parameters : the estimates: lengths [m], angles [deg] (see :func:`fit_surface`).
    sigma : their 1-σ uncertainties, same keys and units.
    residuals : [m] measured minus fitted water path per trace, shape ``(n_y, n_x)``
        (NaN where a trace had no echo).
    inliers : traces the final fit used, shape ``(n_y, n_x)``.
    tof : [s] the front-wall times of flight, shape ``(n_y, n_x)``.
    rms : [m] root-mean-square residual of the inliers.
    """

    shape: str
    parameters: dict[str, float]
    sigma: dict[str, float]
    residuals: FloatArray
    inliers: NDArray[np.bool_]
    tof: FloatArray
    rms: float
    facts: dict[str, Any] = field(default_factory=dict)

    @property
    def noise(self) -> float:
        """[m] the water path's expected noise: the median over the inliers of each
        trace's time-of-flight bound (``echocal.positionscan.tof.tof_noise``) × c₀/2."""
        return float(self.facts.get("water_path_noise_m", math.nan))

    @property
    def misfit(self) -> bool:
        """The residuals are larger than the noise explains (rms > 2 × :attr:`noise`): the
        model does not describe these echoes, and the σ (which assume it does) are too
        small.  A probe whose aperture is large for the part's curvature does this."""
        return bool(math.isfinite(self.noise) and self.rms > 2.0 * self.noise)

    def summary(self) -> dict[str, Any]:
        """JSON-ready: shape, estimates with σ, residual statistics and the facts used."""
        return {
            "shape": self.shape,
            "parameters": dict(self.parameters),
            "sigma": dict(self.sigma),
            "rms_m": self.rms,
            "noise_m": self.noise,
            "misfit": self.misfit,
            "traces": int(np.isfinite(self.tof).sum()),
            "inliers": int(self.inliers.sum()),
            "outliers": int(np.isfinite(self.tof).sum() - self.inliers.sum()),
            **self.facts,
        }

    def dataset(self, scan: PositionScan) -> Any:
        """The residual and time-of-flight maps as an ``xarray.Dataset`` on the scan's
        positions (dims (y, x)), with the summary in ``attrs``."""
        import xarray as xr

        dims = ("y", "x")
        ds = xr.Dataset(
            {
                "residual": (dims, self.residuals),
                "tof": (dims, self.tof),
                "inlier": (dims, self.inliers.astype(np.int8)),
            },
            coords={"x": ("x", scan.x), "y": ("y", scan.y)},
        )
        ds["residual"].attrs.update(units="m", long_name="measured minus fitted water path")
        ds["tof"].attrs.update(units="s", long_name="front-wall time of flight")
        ds["inlier"].attrs.update(units="1", long_name="1 where the trace was used by the fit")
        ds["x"].attrs.update(units="m", long_name="probe position x")
        ds["y"].attrs.update(units="m", long_name="probe position y")
        ds.attrs["summary"] = json.dumps(self.summary())
        return ds


def scan_distances(
    scan: PositionScan,
    *,
    gate: TimeGate | None = None,
    sound_speed: float | None = None,
    zero_offset: float | None = None,
) -> tuple[FloatArray, FloatArray, float, float, float]:
    """(tof [s], water path [m], c₀ [m/s], τ₀ [s], σ₀ [s]) of every trace, shapes
    ``(n_y, n_x)``; σ₀ is the 1-σ of the time origin common to all traces
    (:func:`~echocal.positionscan.tof.template_origin_sigma`).

    ``sound_speed`` and ``zero_offset`` default to the scan's ``sound_speed_m_s`` and
    ``zero_offset_s`` (0 if it has none); a scan without a speed needs ``sound_speed``.
    """
    c = sound_speed if sound_speed is not None else scan.sound_speed
    if c is None or not c > 0:
        raise EchocalValueError(
            "sound_speed: the scan does not say the medium's speed; give it (--sound-speed 1480)"
        )
    t0 = zero_offset
    if t0 is None:
        t0 = float(scan.dataset.attrs.get("zero_offset_s", 0.0))
    tof = front_wall_tof(scan.samples, scan.window, gate=gate)
    tof = np.where(scan.valid, tof, np.nan)
    common = template_origin_sigma(scan.samples, scan.window, tof, gate)
    return tof, c * (tof - t0) / 2.0, float(c), float(t0), common


def water_path_noise(scan: PositionScan, tof: FloatArray, sound_speed: float) -> FloatArray:
    """[m] each trace's expected water-path noise c₀/2 × :func:`tof_noise`, shape
    ``(n_y, n_x)`` (NaN where there is no echo)."""
    ok = np.isfinite(tof)
    out = np.full(tof.shape, np.nan)
    if np.any(ok):
        template = stacked_template(scan.samples[ok], scan.window, tof[ok])
        out[ok] = sound_speed / 2.0 * tof_noise(scan.samples[ok], template, scan.fs)
    return out


# ------------------------------------------------------------------ the models
# Each model: parameter names, residual r(θ; P, d) = model(θ, P) - d, and a first guess.


def _plane_model(line: bool) -> tuple[tuple[str, ...], Callable[..., FloatArray]]:
    if line:  # a line along x sees the slope along x only: tilt_y
        names: tuple[str, ...] = ("tilt_y", "distance")

        def model(theta: FloatArray, p: FloatArray) -> FloatArray:
            n = tilt_normal(0.0, theta[0])
            return p[:, :2] @ n[:2] + theta[1]

        return names, model

    def model3(theta: FloatArray, p: FloatArray) -> FloatArray:
        n = tilt_normal(theta[0], theta[1])
        return p[:, :2] @ n[:2] + theta[2]

    return ("tilt_x", "tilt_y", "distance"), model3


def _sphere(theta: FloatArray, p: FloatArray) -> FloatArray:
    return np.linalg.norm(p - theta[:3], axis=-1) - theta[3]


def _cylinder_axis(phi: float, eps: float) -> tuple[FloatArray, FloatArray]:
    """Unit axis u (azimuth ``phi``, elevation ``eps`` [deg]) and a horizontal unit w ⟂ u."""
    a, e = math.radians(phi), math.radians(eps)
    u = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    w = np.array([-math.sin(a), math.cos(a), 0.0])
    return u, w


def _cylinder(theta: FloatArray, p: FloatArray) -> FloatArray:
    phi, eps, s, za, radius = theta
    u, w = _cylinder_axis(phi, eps)
    a = s * w + np.array([0.0, 0.0, za])
    rel = p - a
    return np.linalg.norm(np.cross(rel, u), axis=-1) - radius


def _cylinder_line(theta: FloatArray, p: FloatArray) -> FloatArray:
    s, za, radius = theta  # axis along y through (s, ·, za)
    return np.hypot(p[:, 0] - s, p[:, 2] - za) - radius


def _quadratic_guess(p: FloatArray, d: FloatArray, line: bool) -> tuple[FloatArray, FloatArray]:
    """Least-squares d ≈ c₀ + g·(x, y) + ½ (x, y)ᵀ H (x, y): (g, H) (H 2×2, zeros on a line)."""
    x, y = p[:, 0], p[:, 1]
    if line:
        coef = np.polyfit(x, d, 2)
        return np.array([coef[1], 0.0]), np.array([[2.0 * coef[0], 0.0], [0.0, 0.0]])
    a = np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=1)
    c = np.asarray(np.linalg.lstsq(a, d, rcond=None)[0], dtype=np.float64)
    return c[1:3], np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]])


def _curved_guess(shape: str, p: FloatArray, d: FloatArray, line: bool) -> FloatArray:
    """First guess of a sphere or cylinder from the paraboloid through the distances."""
    g, h = _quadratic_guess(p, d, line)
    vals, vecs = np.linalg.eigh(h)
    k = float(vals[-1])  # the largest curvature [1/m]: across a cylinder's axis
    if not k > 0:
        raise EchocalValueError(
            f"shape: the times of flight do not curve as a convex {shape} would (the water "
            "path is not smallest inside the scan); fit a plane, or scan across the part"
        )
    depth = 1.0 / k  # distance from the probe plane to the centre / axis [m]
    if shape == "sphere" or line:
        hk = h if not line else np.array([[h[0, 0], 0.0], [0.0, h[0, 0]]])
        apex = -np.linalg.solve(hk, g) if not line else np.array([-g[0] / h[0, 0], 0.0])
    else:
        across = vecs[:, -1]
        apex = -across * float(across @ g) / k
    rho2 = np.sum((p[:, :2] - apex) ** 2, axis=1)
    d_apex = float(np.median(d - 0.5 * k * rho2))
    radius = depth - d_apex
    za = float(p[0, 2]) - depth
    if shape == "sphere":
        return np.array([apex[0], apex[1], za, radius])
    if line:
        return np.array([apex[0], za, radius])
    along = vecs[:, 0]
    phi = math.degrees(math.atan2(along[1], along[0]))
    _, w = _cylinder_axis(phi, 0.0)
    return np.array([phi, 0.0, float(w[:2] @ apex), za, radius])


# ------------------------------------------------------------------ the fit


def _solve(
    model: Callable[..., FloatArray],
    theta0: FloatArray,
    p: FloatArray,
    d: FloatArray,
    loss: str,
    f_scale: float,
) -> Any:
    return scipy.optimize.least_squares(
        lambda th: model(th, p) - d,
        theta0,
        loss=loss,
        f_scale=f_scale,
        x_scale="jac",
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
        max_nfev=2000,
    )


def _robust_sigma(r: FloatArray) -> float:
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def fit_surface(
    scan: PositionScan,
    shape: str = "plane",
    *,
    gate: TimeGate | None = None,
    sound_speed: float | None = None,
    zero_offset: float | None = None,
    probe_z: float | None = None,
) -> SurfaceFit:
    """Fit a plane, sphere or cylinder to the front-wall times of flight of ``scan``.

    Parameters
    ----------
    shape : ``plane``, ``sphere`` or ``cylinder`` (on a line scan: a cylinder whose axis
        is along y; a sphere needs a raster).
    gate : where the front-wall echo is looked for (default: the interface-triggered
        ``front-wall`` gate).
    sound_speed : [m/s] c₀ (default: the scan's).
    zero_offset : [s] τ₀, the delay a calibration block measures (default: the scan's
        ``zero_offset_s``, else 0).
    probe_z : [m] the probe's height z₀ (default: the scan's, else 0: heights are then
        relative to the probe).

    Returns
    -------
    :class:`SurfaceFit` with parameters (σ alike):

    * plane: ``tilt_x``, ``tilt_y`` [deg] (its normal as gimbal tilts; a line scan gives
      ``tilt_y`` only), ``azimuth``, ``coelevation`` [deg] of the normal, ``distance`` [m]
      from the scan's centre;
    * sphere: ``center_x``, ``center_y``, ``center_z``, ``radius``, ``distance`` [m];
    * cylinder: ``axis_azimuth``, ``axis_elevation`` [deg], ``axis_offset`` (horizontal,
      from the scan's centre), ``axis_z``, ``radius``, ``distance`` [m] (a line scan:
      ``axis_x``, ``axis_z``, ``radius``, ``distance``).

    Raises
    ------
    EchocalValueError : an unknown shape, too few traces with an echo, no speed.
    """
    if shape not in SHAPES:
        raise EchocalValueError(f"shape must be one of {', '.join(SHAPES)}; got {shape!r}")
    line = not scan.is_raster
    if shape == "sphere" and line:
        raise EchocalValueError("shape sphere needs a raster scan (y, x); a line fits a cylinder")
    tof, dist, c, t0, common = scan_distances(
        scan, gate=gate, sound_speed=sound_speed, zero_offset=zero_offset
    )
    z0 = probe_z if probe_z is not None else (scan.probe_z or 0.0)
    xx, yy = np.meshgrid(scan.x, scan.y)
    centre = np.array([0.5 * (scan.x.min() + scan.x.max()), 0.5 * (scan.y.min() + scan.y.max())])
    ok = np.isfinite(dist)
    p = np.stack([xx[ok] - centre[0], yy[ok] - centre[1], np.full(int(ok.sum()), z0)], axis=1)
    d = dist[ok]
    if shape == "plane":
        names, model = _plane_model(line)
        g, _ = _quadratic_guess(p, d, line) if d.size >= 6 else (np.zeros(2), None)
        tx = -math.degrees(math.asin(float(np.clip(g[1], -1, 1))))
        ty = math.degrees(math.asin(float(np.clip(g[0], -1, 1))))
        theta0 = np.array([ty, 0.0]) if line else np.array([tx, ty, 0.0])
        theta0[-1] = float(np.median(d - model(theta0, p)))
    else:
        if shape == "sphere":
            names, model = ("center_x", "center_y", "center_z", "radius"), _sphere
        elif line:
            names, model = ("axis_x", "axis_z", "radius"), _cylinder_line
        else:
            names = ("axis_azimuth", "axis_elevation", "axis_offset", "axis_z", "radius")
            model = _cylinder
        theta0 = _curved_guess(shape, p, d, line)
    n_par = len(names)
    if d.size < n_par + 2:
        raise EchocalValueError(
            f"only {d.size} traces hold a front-wall echo; a {shape} fit needs at least "
            f"{n_par + 2}: check the gate and the scan"
        )
    first = _solve(model, theta0, p, d, "linear", 1.0)
    scale = max(_robust_sigma(first.fun), 1e-9)
    robust = _solve(model, first.x, p, d, "soft_l1", scale)
    r = model(robust.x, p) - d
    keep = np.abs(r - np.median(r)) <= _INLIER_SIGMAS * max(_robust_sigma(r), 1e-12)
    final = _solve(model, robust.x, p[keep], d[keep], "linear", 1.0)
    theta = final.x
    jac = final.jac
    dof = int(keep.sum()) - n_par
    s2 = float(np.sum(final.fun**2) / dof) if dof > 0 else math.nan
    try:
        cov = s2 * np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        cov = np.full((n_par, n_par), np.nan)
    estimates = dict(zip(names, (float(v) for v in theta), strict=True))
    sigma = dict(zip(names, (float(math.sqrt(max(v, 0.0))) for v in np.diag(cov)), strict=True))
    _derived(shape, line, theta, cov, estimates, sigma, z0, centre)
    shift = c * common / 2.0 if math.isfinite(common) else 0.0  # [m] common to every trace
    for key in ("distance", "radius"):
        if key in sigma:
            sigma[key] = math.hypot(sigma[key], shift)
    residuals = np.full(dist.shape, np.nan)
    residuals[ok] = -(model(theta, p) - d)
    inliers = np.zeros(dist.shape, dtype=bool)
    inliers[ok] = keep
    facts = {
        "sound_speed_m_s": c,
        "zero_offset_s": t0,
        "time_origin_sigma_s": common,
        "water_path_noise_m": float(np.nanmedian(water_path_noise(scan, tof, c)[inliers]))
        if np.any(inliers)
        else math.nan,
        "probe_z_m": z0,
        "scan_centre_m": [float(centre[0]), float(centre[1])],
    }
    return SurfaceFit(
        shape=shape,
        parameters=estimates,
        sigma=sigma,
        residuals=residuals,
        inliers=inliers,
        tof=tof,
        rms=float(np.sqrt(np.mean(final.fun**2))),
        facts=facts,
    )


def _propagate(
    fn: Callable[[FloatArray], FloatArray], theta: FloatArray, cov: FloatArray
) -> FloatArray:
    """1-σ of ``fn(theta)`` by the delta method (central differences)."""
    base = np.atleast_1d(fn(theta))
    jac = np.empty((base.size, theta.size))
    for k in range(theta.size):
        h = 1e-6 * max(abs(theta[k]), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[k] += h
        down[k] -= h
        jac[:, k] = (np.atleast_1d(fn(up)) - np.atleast_1d(fn(down))) / (2 * h)
    return np.sqrt(np.maximum(np.diag(jac @ cov @ jac.T), 0.0))


def _derived(
    shape: str,
    line: bool,
    theta: FloatArray,
    cov: FloatArray,
    est: dict[str, float],
    sig: dict[str, float],
    z0: float,
    centre: FloatArray,
) -> None:
    """Add the derived quantities (and their σ) to ``est``/``sig`` in place."""
    if shape == "plane":
        if line:
            return

        def angles(th: FloatArray) -> FloatArray:
            az, co = normal_to_orientation(tilt_normal(th[0], th[1]))
            return np.array([float(az), float(co)])

        az, co = angles(theta)
        s_az, s_co = _propagate(angles, theta, cov)
        est.update(azimuth=float(az), coelevation=float(co))
        sig.update(azimuth=float(s_az), coelevation=float(s_co))
        return
    p_c = np.array([[0.0, 0.0, z0]])
    model = _sphere if shape == "sphere" else (_cylinder_line if line else _cylinder)

    def distance(th: FloatArray) -> FloatArray:
        return model(th, p_c)

    est["distance"] = float(distance(theta)[0])
    sig["distance"] = float(_propagate(distance, theta, cov)[0])
    if shape == "sphere":  # back to the scan's coordinates
        est["center_x"] += float(centre[0])
        est["center_y"] += float(centre[1])
    elif line:
        est["axis_x"] += float(centre[0])
