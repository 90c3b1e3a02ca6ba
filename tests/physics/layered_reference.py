"""Plane-wave reflection of a stack of elastic layers immersed in a fluid (issue 46).

Pure numpy; never imports echocal: the yard-stick for the layered echo train.

Method: global matrix (Lowe, IEEE UFFC 42, 525 (1995)).  Displacement potentials φ
(longitudinal) and ψ (SV shear), u = ∇φ + ∇×(ψŷ), time dependence e^{−iωt}.  Fluid above
(incident and reflected waves, unknown R) and below (transmitted, unknown T); in each
solid layer four partial waves, the down-going ones referenced to the layer's top and the
up-going ones to its bottom so that every exponential is bounded.  At a fluid–solid
interface u_z and σ_zz are continuous and σ_xz = 0; between two solids (welded) u_x,
u_z, σ_zz and σ_xz are continuous.  For a partial wave e^{i(k_x x + s k_z z)}:

    φ (amplitude a):  u_x = i k_x a,  u_z = i s k_zL a,  σ_zz = −μ(k_T² − 2k_x²) a,
                      σ_xz = −2μ k_x s k_zL a
    ψ (amplitude b):  u_x = −i s k_zT b,  u_z = i k_x b,  σ_zz = −2μ k_x s k_zT b,
                      σ_xz = μ(k_zT² − k_x²) b
    fluid φ:          u_z = i s k_z a,  σ_zz = −ρω² a  (= −p).

At k_x = 0 the shear waves decouple and are dropped (their thickness resonances would
make the system singular).  R is the pressure reflection coefficient referred to the
front face z = 0.
"""

from __future__ import annotations

import numpy as np


def _kz(k, kx):
    kz = np.sqrt(np.asarray(k * k - kx * kx, dtype=complex))
    return np.where(kz.imag < 0, -kz, kz)


def _waves(omega, kx, rho, c_l, c_t, sign):
    """(n, 4, m) columns (u_x, u_z, σ_zz, σ_xz) of the P (and SV) partial waves going
    along sign·z; m = 1 in a fluid, 2 in a solid."""
    kzl = sign * _kz(omega / c_l, kx)
    if c_t == 0.0:
        p = np.stack([1j * kx, 1j * kzl, -rho * omega**2 + 0 * kx, 0 * kx], axis=-1)
        return p[..., None]
    mu = rho * c_t * c_t
    kt = omega / c_t
    kzt = sign * _kz(kt, kx)
    p = np.stack([1j * kx, 1j * kzl, -mu * (kt * kt - 2 * kx * kx), -2 * mu * kx * kzl], axis=-1)
    s = np.stack([-1j * kzt, 1j * kx, -2 * mu * kx * kzt, mu * (kzt * kzt - kx * kx)], axis=-1)
    return np.stack([p, s], axis=-1), kzl, kzt


def stack_reflection(f, theta_deg, layers, rho_fluid, c_fluid):
    """R(f, θ) of ``layers`` = [(rho, c_L, c_T, h), …] (top first, solids) between two
    half-spaces of fluid (rho_fluid, c_fluid); ``f`` scalar [Hz], ``theta_deg`` any shape
    (incidence from the upper fluid, degrees).  Complex speeds c(1 − iη) add loss."""
    th = np.deg2rad(np.asarray(theta_deg, dtype=float)).ravel()
    shape = np.shape(theta_deg)
    omega = 2 * np.pi * f
    kx = omega / c_fluid * np.sin(th) + 0j
    n_layers = len(layers)
    n_unknown = 4 * n_layers + 2
    n = th.size
    matrix = np.zeros((n, n_unknown, n_unknown), dtype=complex)
    rhs = np.zeros((n, n_unknown), dtype=complex)
    scale_u, scale_s = omega / c_fluid, rho_fluid * omega**2

    def rows_for(upper_solid, lower_solid):
        if upper_solid and lower_solid:
            return [0, 1, 2, 3], None
        return [1, 2], 3  # u_z, σ_zz continuous; σ_xz = 0 on the solid side

    fluid_down = _waves(omega, kx, rho_fluid, c_fluid, 0.0, +1)[..., 0]  # (n, 4)
    fluid_up = _waves(omega, kx, rho_fluid, c_fluid, 0.0, -1)[..., 0]
    layer_waves = []
    for rho, c_l, c_t, h in layers:
        down, kzl, kzt = _waves(omega, kx, rho, c_l, c_t, +1)
        up, _, _ = _waves(omega, kx, rho, c_l, c_t, -1)
        phases = np.stack([np.exp(1j * kzl * h), np.exp(1j * kzt * h)], axis=-1)  # (n, 2)
        layer_waves.append((down, up, phases))
    row = 0
    for i in range(n_layers + 1):  # interface i: above is layer i (0: fluid), below i+1
        entries = []  # (column index, (n, 4) field at the interface, factor ±1)
        if i == 0:
            entries.append((0, fluid_up, 1.0))  # R (reflected, up-going at z = 0)
            incident = fluid_down
        else:
            down, up, phases = layer_waves[i - 1]
            base = 2 + 4 * (i - 1)
            for m in range(2):  # at the layer's bottom: down-going × e^{ik_z h}, up-going × 1
                entries.append((base + m, down[..., m] * phases[:, m, None], 1.0))
                entries.append((base + 2 + m, up[..., m], 1.0))
        if i == n_layers:
            entries.append((1, fluid_down, -1.0))  # T (transmitted, down-going at z = H)
        else:
            down, up, phases = layer_waves[i]
            base = 2 + 4 * i
            for m in range(2):  # at the layer's top: down-going × 1, up-going × e^{ik_z h}
                entries.append((base + m, down[..., m], -1.0))
                entries.append((base + 2 + m, up[..., m] * phases[:, m, None], -1.0))
        upper_solid, lower_solid = i > 0, i < n_layers
        continuous, free = rows_for(upper_solid, lower_solid)
        for comp in continuous:
            scale = scale_u if comp < 2 else scale_s
            for col, field, sign in entries:
                matrix[:, row, col] += sign * field[:, comp] / scale
            if i == 0:
                rhs[:, row] = -incident[:, comp] / scale
            row += 1
        if free is not None:  # σ_xz = 0 on the solid side only
            solid_above = upper_solid
            for col, field, sign in entries:
                is_above = sign > 0
                if is_above == solid_above:
                    matrix[:, row, col] += field[:, free] / scale_s
            row += 1
    assert row == n_unknown
    normal = np.abs(kx) == 0
    if np.any(normal):  # drop the shear unknowns: B = 0 replaces their equations
        shear_cols = [2 + 4 * j + m for j in range(n_layers) for m in (1, 3)]
        shear_rows = _shear_rows(n_layers)
        for r, col in zip(shear_rows, shear_cols, strict=True):
            matrix[normal, r, :] = 0.0
            matrix[normal, r, col] = 1.0
            rhs[normal, r] = 0.0
    x = np.linalg.solve(matrix, rhs[..., None])[..., 0]
    r = x[:, 0]
    return r.reshape(shape) if shape else r[0]


def _shear_rows(n_layers):
    """The equations that hold only shear terms at normal incidence (u_x and σ_xz rows,
    and σ_xz = 0 rows), one per shear unknown."""
    rows, row = [], 0
    for i in range(n_layers + 1):
        upper_solid, lower_solid = i > 0, i < n_layers
        if upper_solid and lower_solid:
            rows += [row, row + 3]  # u_x, σ_xz
            row += 4
        else:
            rows.append(row + 2)  # σ_xz = 0
            row += 3
    return rows


def normal_incidence_reflection(f, layers, rho_fluid, c_fluid):
    """R(f) at normal incidence by the impedance recursion (a second, one-dimensional
    check of :func:`stack_reflection`): Z_in = Z (Z_b − iZ tan kh)/(Z − iZ_b tan kh)
    from the bottom up (e^{−iωt})."""
    omega = 2 * np.pi * np.asarray(f, dtype=float)
    z_fluid = rho_fluid * c_fluid
    z_in = z_fluid + 0 * omega
    for rho, c_l, _c_t, h in reversed(layers):
        z = rho * c_l
        t = np.tan(omega / c_l * h)
        z_in = z * (z_in - 1j * z * t) / (z - 1j * z_in * t)
    return (z_in - z_fluid) / (z_in + z_fluid)
