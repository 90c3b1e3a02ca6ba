"""Materials, attenuation and interface coefficients, checked against truth computed here.

References the tests compute themselves:
- impedances and normal-incidence coefficients by hand from the table's ρ and c;
- the fluid–fluid oblique formula (Z/cos θ, Snell's law, evanescent branch +i);
- an independent 3×3 solve of the boundary conditions (continuity of normal velocity,
  normal stress = −pressure, no shear stress) built from Lamé constants and plane-wave
  gradients, for fluid → solid and solid → fluid, in every angular regime;
- energy-flux balance with the propagating waves only.
Tolerances: 1e-12 relative for exact algebra, 1e-9 for the linear solves.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from tests.cli_helpers import run_main, tiny_setup_toml

from echocal import (
    MATERIALS,
    WATER,
    Attenuation,
    EchocalValueError,
    Material,
    UnknownNameError,
    critical_angles,
    material,
    material_names,
    reflection_fluid_solid,
    reflection_normal,
    reflection_solid_fluid,
    transmission_fluid_solid,
    transmission_normal,
    transmission_solid_fluid,
    water,
)
from echocal.coefficients import snell_angle
from echocal.setups import load_setup, validate_setup_file

STEEL = material("steel")
GLYCEROL = Material(name="glycerol", density=1260.0, longitudinal_speed=1920.0)
ANGLES = np.array([0.0, 1e-7, 5.0, 10.0, 14.0, 14.6, 16.0, 20.0, 27.0, 27.4, 30.0, 60.0, 89.0])


# ---------------------------------------------------------------- independent references
def _stress(lam: float, mu: float, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Stress tensor of the plane wave u = d·exp(i k·x) (unit displacement amplitude)."""
    grad = 1j * np.outer(k, d)  # ∂_i u_j
    return lam * np.trace(grad) * np.eye(3) + mu * (grad + grad.T)


def _wavevector(omega: float, c: float, kx: float, sign: float) -> np.ndarray:
    kz = np.sqrt((omega / c) ** 2 - kx**2 + 0j)  # +i branch: decays along +z
    return np.array([kx, 0.0, sign * kz])


def _solve_fluid_solid(theta: float, fluid: Material, solid: Material):
    """(R, T_L, T_T) by a linear solve; stress amplitudes ρ·c·V, shear polarised k̂ × ŷ."""
    omega = 2 * np.pi * 1e6
    rho1, c1 = fluid.density, fluid.longitudinal_speed
    rho2, cl, ct = solid.density, solid.longitudinal_speed, solid.shear_speed
    mu, lam = rho2 * ct**2, rho2 * (cl**2 - 2 * ct**2)
    kx = omega / c1 * math.sin(math.radians(theta))
    kz1 = _wavevector(omega, c1, kx, 1)[2]
    kl, kt = _wavevector(omega, cl, kx, 1), _wavevector(omega, ct, kx, 1)
    dl = kl / (omega / cl)
    dt = np.cross(kt / (omega / ct), [0.0, 1.0, 0.0])
    sl, st = _stress(lam, mu, kl, dl), _stress(lam, mu, kt, dt)
    # unknowns: R (pressure), U_L, U_T (displacements); p = 1 + R at z = 0
    a = np.array(
        [
            [-kz1 / (omega * rho1), 1j * omega * dl[2], 1j * omega * dt[2]],  # v_z continuous
            [1.0, sl[2, 2], st[2, 2]],  # σ_zz = −p
            [0.0, sl[0, 2], st[0, 2]],  # σ_xz = 0
        ]
    )
    b = np.array([-kz1 / (omega * rho1), -1.0, 0.0])
    r, ul, ut = np.linalg.solve(a, b)
    return r, rho2 * cl * (-1j * omega * ul), rho2 * ct * (-1j * omega * ut)


def _solve_solid_fluid(theta: float, solid: Material, fluid: Material):
    """(R_LL, R_LT, T) for a unit-stress longitudinal wave in the solid (z < 0) on a fluid."""
    omega = 2 * np.pi * 1e6
    rho1, c1 = fluid.density, fluid.longitudinal_speed
    rho2, cl, ct = solid.density, solid.longitudinal_speed, solid.shear_speed
    mu, lam = rho2 * ct**2, rho2 * (cl**2 - 2 * ct**2)
    kx = omega / cl * math.sin(math.radians(theta))
    ki, kr = _wavevector(omega, cl, kx, 1), _wavevector(omega, cl, kx, -1)
    kt = _wavevector(omega, ct, kx, -1)
    kz1 = _wavevector(omega, c1, kx, 1)[2]
    di, dr = ki / (omega / cl), kr / (omega / cl)
    dt = np.cross(kt / (omega / ct), [0.0, 1.0, 0.0])
    ui = 1.0 / (rho2 * cl * (-1j * omega))  # unit stress amplitude
    si, sr, st = (_stress(lam, mu, k, d) for k, d in ((ki, di), (kr, dr), (kt, dt)))
    # unknowns U_R, U_T (displacements), P (fluid pressure)
    a = np.array(
        [
            [-1j * omega * dr[2], -1j * omega * dt[2], -kz1 / (omega * rho1)],
            [sr[2, 2], st[2, 2], 1.0],
            [sr[0, 2], st[0, 2], 0.0],
        ]
    )
    b = -ui * np.array([-1j * omega * di[2], si[2, 2], si[0, 2]])
    ur, ut, p = np.linalg.solve(a, b)
    return rho2 * cl * (-1j * omega * ur), rho2 * ct * (-1j * omega * ut), p


def _oblique_z(rho: float, c: float, sin: np.ndarray) -> np.ndarray:
    return rho * c / np.sqrt(1 - sin.astype(complex) ** 2)


# ---------------------------------------------------------------- impedances, normal incidence
def test_normal_incidence_water_steel_by_hand():
    z_water, z_steel = 998.2 * 1482.3, 7850.0 * 5900.0  # 1.480 MRayl, 46.32 MRayl
    assert WATER.impedance == pytest.approx(1.4796e6, rel=1e-4)
    assert STEEL.impedance == pytest.approx(46.315e6, rel=1e-12)
    r = (z_steel - z_water) / (z_steel + z_water)
    assert r == pytest.approx(0.93808, abs=1e-5)
    assert reflection_normal(WATER.impedance, STEEL.impedance) == pytest.approx(r, rel=1e-12)
    t = transmission_normal(WATER.impedance, STEEL.impedance)
    assert t == pytest.approx(2 * z_steel / (z_steel + z_water), rel=1e-12)
    assert r**2 + (z_water / z_steel) * t**2 == pytest.approx(1.0, rel=1e-12)  # energy
    assert complex(reflection_fluid_solid(0.0, WATER, STEEL)) == pytest.approx(r, rel=1e-12)
    # the way back: 2 Z_water / (Z_water + Z_steel); back-wall round trip = 1 − R²
    back = transmission_solid_fluid(0.0, STEEL, WATER)
    assert complex(back) == pytest.approx(2 * z_water / (z_water + z_steel), rel=1e-12)
    r_back = reflection_solid_fluid(0.0, STEEL, WATER).longitudinal
    assert complex(r_back) == pytest.approx(-r, rel=1e-12)
    t_in = transmission_fluid_solid(0.0, WATER, STEEL).longitudinal
    assert complex(t_in * back) == pytest.approx(1 - r**2, rel=1e-12)


def test_normal_coefficients_vectorised_and_refuse_bad_impedances():
    z2 = np.array([1e6, 2e6, 4e6])
    np.testing.assert_allclose(reflection_normal(1e6, z2), (z2 - 1e6) / (z2 + 1e6))
    with pytest.raises(EchocalValueError, match="z2"):
        reflection_normal(1e6, -3.0)
    with pytest.raises(EchocalValueError, match="z1"):
        transmission_normal(float("nan"), 1e6)


def test_theta_to_zero_is_the_normal_formula():
    r0 = reflection_normal(WATER.impedance, STEEL.impedance)
    for theta in (1e-9, 1e-6, 1e-4):
        assert abs(reflection_fluid_solid(theta, WATER, STEEL) - r0) < 1e-7
        assert abs(transmission_fluid_solid(theta, WATER, STEEL).shear) < 1e-5


# ---------------------------------------------------------------- oblique incidence
def test_fluid_solid_matches_an_independent_boundary_value_solve():
    r = reflection_fluid_solid(ANGLES, WATER, STEEL)
    t = transmission_fluid_solid(ANGLES, WATER, STEEL)
    for i, theta in enumerate(ANGLES):
        ref = _solve_fluid_solid(float(theta), WATER, STEEL)
        got = (r[i], t.longitudinal[i], t.shear[i])
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12, err_msg=f"{theta} deg")


def test_solid_fluid_matches_an_independent_boundary_value_solve():
    angles = np.array([0.0, 10.0, 30.0, 45.0, 60.0, 80.0, 89.0])
    for solid in (STEEL, material("aluminium"), material("pmma")):
        refl = reflection_solid_fluid(angles, solid, WATER)
        t = transmission_solid_fluid(angles, solid, WATER)
        for i, theta in enumerate(angles):
            ref = _solve_solid_fluid(float(theta), solid, WATER)
            got = (refl.longitudinal[i], refl.shear[i], t[i])
            np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12, err_msg=solid.name)


def test_fluid_solid_reduces_to_the_fluid_fluid_formula():
    # water → glycerol (1920 m/s): critical angle 50.5°; beyond it R is complex, |R| = 1
    theta = np.linspace(0.0, 89.0, 90)
    sin1 = np.sin(np.radians(theta))
    z1 = _oblique_z(WATER.density, WATER.longitudinal_speed, sin1)
    z2 = _oblique_z(GLYCEROL.density, GLYCEROL.longitudinal_speed, sin1 * 1920.0 / 1482.3)
    expected = (z2 - z1) / (z2 + z1)
    np.testing.assert_allclose(reflection_fluid_solid(theta, WATER, GLYCEROL), expected, 1e-12)
    t = transmission_fluid_solid(theta, WATER, GLYCEROL)
    np.testing.assert_allclose(t.longitudinal, 2 * z2 / (z2 + z1), rtol=1e-12)
    assert np.all(t.shear == 0) and np.all(np.isnan(t.angle_shear))
    beyond = theta > math.degrees(math.asin(1482.3 / 1920.0))
    np.testing.assert_allclose(np.abs(expected[beyond]), 1.0, rtol=1e-12)
    assert critical_angles(WATER, GLYCEROL).shear is None


def test_critical_angles_snell_and_total_reflection_water_steel():
    first, second = critical_angles(WATER, STEEL)
    assert first == pytest.approx(math.degrees(math.asin(1482.3 / 5900.0)), rel=1e-12)
    assert second == pytest.approx(math.degrees(math.asin(1482.3 / 3230.0)), rel=1e-12)
    assert (first, second) == pytest.approx((14.55, 27.32), abs=0.01)
    theta = np.linspace(0.0, 89.9, 500)
    t = transmission_fluid_solid(theta, WATER, STEEL)
    below1, below2 = theta < first, theta < second
    sin = np.sin(np.radians(theta))
    np.testing.assert_allclose(np.sin(np.radians(t.angle_longitudinal[below1])) / 5900.0,
                               sin[below1] / 1482.3, rtol=1e-12)  # fmt: skip
    np.testing.assert_allclose(np.sin(np.radians(t.angle_shear[below2])) / 3230.0,
                               sin[below2] / 1482.3, rtol=1e-12)  # fmt: skip
    assert np.all(np.isnan(t.angle_longitudinal[~below1]))
    assert np.all(np.isnan(t.angle_shear[~below2]))
    np.testing.assert_allclose(snell_angle(theta[below1], 1482.3, 5900.0),
                               t.angle_longitudinal[below1], rtol=1e-12)  # fmt: skip
    r = reflection_fluid_solid(theta, WATER, STEEL)
    np.testing.assert_allclose(np.abs(r[~below2]), 1.0, rtol=1e-12)
    assert np.all(np.abs(r[below2]) < 1.0 - 1e-6)  # energy goes into the part
    assert abs(reflection_fluid_solid(90.0, WATER, STEEL) + 1) < 1e-12  # grazing: R = −1


def test_energy_flux_balance_with_the_propagating_waves():
    theta = np.linspace(0.0, 89.0, 400)
    r = reflection_fluid_solid(theta, WATER, STEEL)
    t = transmission_fluid_solid(theta, WATER, STEEL)
    sin = np.sin(np.radians(theta))
    z1 = _oblique_z(WATER.density, 1482.3, sin)
    zl = _oblique_z(STEEL.density, 5900.0, sin * 5900.0 / 1482.3)
    zt = _oblique_z(STEEL.density, 3230.0, sin * 3230.0 / 1482.3)
    first, second = critical_angles(WATER, STEEL)
    flux = np.abs(r) ** 2
    flux = flux + np.where(theta < first, (z1 / zl).real * np.abs(t.longitudinal) ** 2, 0.0)
    flux = flux + np.where(theta < second, (z1 / zt).real * np.abs(t.shear) ** 2, 0.0)
    np.testing.assert_allclose(flux, 1.0, rtol=1e-10)
    # between the critical angles the shear wave carries energy away
    between = (theta > first) & (theta < second)
    assert np.all(np.abs(r[between]) < 1.0) and np.any(np.abs(r[between]) < 0.95)
    # from the solid side: |R_LL|² + (Z_L/Z_T)|R_LT|² + (Z_L/Z_1)|T|² = 1
    th = np.linspace(0.0, 89.0, 200)
    refl, tout = (
        reflection_solid_fluid(th, STEEL, WATER),
        transmission_solid_fluid(th, STEEL, WATER),
    )
    s = np.sin(np.radians(th))
    zl2 = _oblique_z(STEEL.density, 5900.0, s)
    zt2 = _oblique_z(STEEL.density, 3230.0, s * 3230.0 / 5900.0)
    z12 = _oblique_z(WATER.density, 1482.3, s * 1482.3 / 5900.0)
    flux2 = (np.abs(refl.longitudinal) ** 2 + (zl2 / zt2).real * np.abs(refl.shear) ** 2
             + (zl2 / z12).real * np.abs(tout) ** 2)  # fmt: skip
    np.testing.assert_allclose(flux2, 1.0, rtol=1e-10)


def test_coefficients_refuse_bad_angles_and_a_solid_incident_medium():
    with pytest.raises(EchocalValueError, match=r"theta_deg must lie in \[0, 90\]"):
        reflection_fluid_solid(95.0, WATER, STEEL)
    with pytest.raises(EchocalValueError, match="theta_deg"):
        reflection_fluid_solid(float("nan"), WATER, STEEL)
    with pytest.raises(EchocalValueError, match="fluid: 'steel'"):
        reflection_fluid_solid(0.0, STEEL, WATER)
    with pytest.raises(EchocalValueError, match="solid must be a Material"):
        transmission_fluid_solid(0.0, WATER, "steel")


# ---------------------------------------------------------------- attenuation
def test_attenuation_power_law_and_factor():
    water = WATER.attenuation
    assert water.alpha(1e6) == pytest.approx(0.0253, rel=1e-12)  # Pinkerton: 25.3e-15 s²/m
    f = np.array([-5e6, 0.0, 2e6, 5e6])
    np.testing.assert_allclose(water.alpha(f), 25.3e-15 * f**2, rtol=1e-12)
    d = np.array([[0.0], [0.1], [0.2]])  # (3, 1) distances × (4,) frequencies → (3, 4)
    np.testing.assert_allclose(water.factor(f, d), np.exp(-25.3e-15 * f**2 * d), rtol=1e-12)
    # spectrum ratio of two water paths: exp(−2α(f)Δd) (issue #13, must show 5)
    ratio = water.factor(f, 2 * 0.15) / water.factor(f, 2 * 0.05)
    np.testing.assert_allclose(ratio, np.exp(-2 * water.alpha(f) * 0.1), rtol=1e-12)
    twenty_db = Attenuation.from_db(20.0, f_ref=5e6, exponent=1.0)  # 20 dB/m at 5 MHz
    assert twenty_db.factor(5e6, 1.0) == pytest.approx(0.1, rel=1e-12)
    assert twenty_db.factor(10e6, 0.5) == pytest.approx(0.1, rel=1e-12)  # α ∝ f
    assert Attenuation().factor(5e6, 1.0) == 1.0  # lossless default


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"alpha0": -0.1}, "alpha0 must be >= 0"),
        ({"alpha0": float("nan")}, "alpha0 must be finite"),
        ({"alpha0": True}, "alpha0 must be a number"),
        ({"f_ref": 0.0}, "f_ref must be > 0"),
        ({"exponent": 5.0}, r"exponent must lie in \[0, 4\]"),
        ({"exponent": float("inf")}, "exponent must be finite"),
    ],
)
def test_attenuation_refuses_bad_values_naming_the_field(kwargs, match):
    with pytest.raises(EchocalValueError, match=match):
        Attenuation(**kwargs)


# ---------------------------------------------------------------- materials
def test_table_lookup_aliases_and_values():
    assert material("Aluminum") is material("aluminium") is MATERIALS["aluminium"]
    assert material(" PMMA ") is material("acrylic")
    assert material("stainless steel") is material("stainless-steel")
    assert material_names() == tuple(sorted(MATERIALS))
    assert {"water", "steel", "aluminium", "titanium", "acrylic", "copper", "glass"} <= set(
        material_names()
    )
    assert (STEEL.density, STEEL.longitudinal_speed, STEEL.shear_speed) == (7850, 5900, 3230)
    for m in MATERIALS.values():  # every built-in solid: 0 < ν < 0.5, attenuation stated
        assert m.is_fluid == (m.name == "water")
        assert 0.0 < m.poisson_ratio <= 0.5
        assert m.attenuation.alpha0 > 0
    assert WATER.is_fluid and not STEEL.is_fluid


def test_unknown_material_lists_the_valid_names():
    with pytest.raises(UnknownNameError) as info:
        material("unobtainium")
    message = str(info.value)
    assert "unknown material 'unobtainium'" in message
    assert all(name in message for name in material_names())


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"density": 0.0}, "density must be > 0"),
        ({"density": -7850.0}, "density must be > 0"),
        ({"density": float("nan")}, "density must be finite"),
        ({"density": True}, "density must be a number"),
        ({"longitudinal_speed": float("inf")}, "longitudinal_speed must be finite"),
        ({"longitudinal_speed": -1.0}, "longitudinal_speed must be > 0"),
        ({"shear_speed": 5900.0}, "shear_speed must be below longitudinal_speed"),
        ({"shear_speed": 7000.0}, "shear_speed must be below longitudinal_speed"),
        ({"shear_speed": 5500.0}, "bulk modulus is negative"),
        ({"shear_speed": -1.0}, "shear_speed must be >= 0"),
        ({"shear_speed": False}, "shear_speed must be a number"),
        ({"attenuation": 0.02}, "attenuation must be an Attenuation"),
    ],
)
def test_material_refuses_impossible_values_naming_the_field(change, match):
    with pytest.raises(EchocalValueError, match=match):
        dataclasses.replace(STEEL, **change)


def test_doubtful_material_warns_and_fluid_takes_no_shear_attenuation():
    with pytest.warns(UserWarning, match="negative Poisson ratio"):
        Material(density=1000.0, longitudinal_speed=1000.0, shear_speed=800.0)
    with pytest.raises(EchocalValueError, match="shear_attenuation: a fluid"):
        Material(density=1000.0, longitudinal_speed=1480.0, shear_attenuation=Attenuation())


def test_water_at_a_temperature_matches_the_tables():
    # Del Grosso & Mader 1972 (speed) and Kell 1975 / CRC (density), independent tables
    speeds = {0: 1402.39, 10: 1447.27, 20: 1482.34, 30: 1509.13, 40: 1528.89}
    densities = {0: 999.84, 10: 999.70, 25: 997.05, 40: 992.22, 60: 983.20}
    for t, c in speeds.items():
        assert water(t).longitudinal_speed == pytest.approx(c, abs=0.06)
    for t, rho in densities.items():
        assert water(t).density == pytest.approx(rho, abs=0.01)
    assert water().longitudinal_speed == pytest.approx(WATER.longitudinal_speed, abs=0.1)
    with pytest.raises(EchocalValueError, match=r"temperature must lie in \[0, 95\]"):
        water(-5)
    with pytest.raises(EchocalValueError, match="temperature must be a number"):
        water(True)


# ---------------------------------------------------------------- setups
def _setup(tmp_path, medium: str = "", material_line: str = "", name: str = "s.toml"):
    text = tiny_setup_toml(specimen=f'builtin = "flat-plate"\n{material_line}')
    path = tmp_path / name
    path.write_text(f"{text}\n{medium}\n" if medium else text)
    return path


def test_setup_materials_and_the_sound_speed_in_effect(tmp_path):
    plain = load_setup(_setup(tmp_path))
    assert plain.material is None and plain.medium.name == "water"
    assert plain.sound_speed == plain.medium.longitudinal_speed == 1480.0  # thesis c₀ kept
    named = load_setup(_setup(tmp_path, '[medium]\nmaterial = "water"', 'material = "Steel"'))
    assert named.sound_speed == named.medium.longitudinal_speed == 1482.3  # the material's
    assert named.material is STEEL
    warm = load_setup(_setup(tmp_path, "[medium]\ntemperature = 30"))
    assert warm.sound_speed == warm.medium.longitudinal_speed == water(30).longitudinal_speed
    assert warm.medium.density == water(30).density
    explicit = load_setup(_setup(tmp_path, '[medium]\nmaterial = "water"\nsound_speed = 1490'))
    assert explicit.sound_speed == explicit.medium.longitudinal_speed == 1490.0  # given wins
    assert explicit.medium.density == WATER.density
    # the ray models are unchanged by the materials (the wave model uses them)
    np.testing.assert_array_equal(
        dataclasses.replace(plain, material=STEEL).reference_samples, plain.reference_samples
    )


def test_setup_inline_material_and_toml_round_trip(tmp_path, capsys, monkeypatch):
    inline = (
        'material = { name = "my steel", density = "7.85 g/cm3", longitudinal_speed = '
        '"5.9 mm/us", shear_speed = "3230 m/s", attenuation = { alpha0 = "0.02 dB/mm", '
        'f_ref = "5 MHz", exponent = 1 } }'
    )
    path = _setup(tmp_path, '[medium]\nmaterial = "water"', inline)
    setup = load_setup(path)
    m = setup.material
    assert (m.name, m.density, m.longitudinal_speed, m.shear_speed) == (
        "my steel", 7850.0, 5900.0, 3230.0,
    )  # fmt: skip
    assert m.attenuation.alpha0 == pytest.approx(20.0 * math.log(10) / 20, rel=1e-12)  # 20 dB/m
    code, out, _ = run_main(["setup", "show", str(path)], capsys, monkeypatch)
    assert code == 0
    again = tmp_path / "again.toml"
    again.write_text(out)
    back = load_setup(again)
    assert back.sound_speed == setup.sound_speed == 1482.3
    assert back.medium == setup.medium
    for key in ("name", "density", "longitudinal_speed", "shear_speed"):
        assert getattr(back.material, key) == getattr(m, key)
    assert back.material.attenuation.alpha0 == pytest.approx(m.attenuation.alpha0, rel=1e-14)


@pytest.mark.parametrize(
    ("medium", "material_line", "expected"),
    [
        ("", 'material = "unobtainium"', "specimen.material: unknown material 'unobtainium'; "
         "choose one of: acrylic, aluminium"),
        ('[medium]\nmaterial = "steel"', "", "medium.material: 'steel' is a solid"),
        ("", 'material = { density = -1, longitudinal_speed = 5900 }',
         "specimen.material.density: must be greater than 0"),
        ("", 'material = { density = 7850, longitudinal_speed = 5900, shear_speed = 6000 }',
         "specimen.material.shear_speed: must be below longitudinal_speed"),
        ("", 'material = { density = 7850, longitudinal_speed = 5900, shear_speed = true }',
         "specimen.material.shear_speed: must be a number; got true"),
        ("", 'material = { density = "7850 m/s", longitudinal_speed = 5900 }',
         "specimen.material.density: value: unit 'm/s' is not a density unit"),
        ("", 'material = { density = 7850, longitudinal_speed = 5900, attenuation = '
         '{ alpha0 = "-1 dB/mm" } }', "specimen.material.attenuation.alpha0: must be greater"),
        ("", "material = 3", "specimen.material: must be a material name"),
        ("[medium]\ntemperature = 120", "", "medium.temperature: must be less than or equal"),
        (
            "[medium]\nmaterial = { density = 1260, longitudinal_speed = 1920 }\ntemperature = 20",
            "",
            "medium.temperature: applies to the built-in water only",
        ),
        ("", "material = { density = 7850, longitudinal_speed = 5.9 }",
         "specimen.material.longitudinal_speed: 5.9 m/s is implausible"),
        ("[noise]\nsnr_db = true", "", "noise.snr_db: must be a number; got true"),
        ("[noise]\nadc_bits = false", "", "noise.adc_bits: must be a number; got false"),
    ],
)  # fmt: skip
def test_setup_validate_names_the_material_field(tmp_path, capsys, monkeypatch, medium,
                                                 material_line, expected):  # fmt: skip
    path = _setup(tmp_path, medium, material_line)
    problems = validate_setup_file(path)
    assert any(p.startswith(expected) for p in problems), problems
    code, out, _ = run_main(["setup", "validate", str(path)], capsys, monkeypatch)
    assert code == 1 and expected in out


def test_virtual_setup_refuses_a_solid_medium():
    setup = load_setup("thesis")
    with pytest.raises(EchocalValueError, match="medium: 'steel' has a shear speed"):
        dataclasses.replace(setup, medium=STEEL)
    with pytest.raises(EchocalValueError, match="material must be a Material or None"):
        dataclasses.replace(setup, material="steel")


# ---------------------------------------------------------------- command line
def test_cli_material_list_and_show(capsys, monkeypatch):
    import json

    code, out, _ = run_main(["material", "list", "--json"], capsys, monkeypatch)
    assert code == 0
    rows = {row["name"]: row for row in json.loads(out)["materials"]}
    assert set(rows) == set(material_names())
    assert rows["steel"]["impedance_mrayl"] == pytest.approx(46.315, rel=1e-12)
    assert rows["water"]["attenuation_db_per_mm_5mhz"] == pytest.approx(
        0.0253 * 25 * 20 / math.log(10) / 1e3, rel=1e-12
    )
    code, out, _ = run_main(
        ["material", "show", "STEEL", "--angles", "0,20,40", "--json"], capsys, monkeypatch
    )
    assert code == 0
    report = json.loads(out)
    r = (46.315e6 - 998.2 * 1482.3) / (46.315e6 + 998.2 * 1482.3)
    assert report["normal_incidence"]["reflection"] == pytest.approx(r, rel=1e-12)
    assert report["normal_incidence"]["back_wall_round_trip"] == pytest.approx(-r * (1 - r * r))
    assert report["critical_angles_deg"]["shear"] == pytest.approx(27.317, abs=1e-3)
    assert [row["angle_deg"] for row in report["oblique"]] == [0.0, 20.0, 40.0]
    assert report["oblique"][2]["reflection_abs"] == pytest.approx(1.0, rel=1e-12)
    assert report["oblique"][2]["refraction_shear_deg"] is None  # evanescent: NaN → null
    code, out, _ = run_main(["material", "show", "aluminum"], capsys, monkeypatch)
    assert code == 0 and "aluminium: ρ 2700 kg/m³" in out and "critical angles" in out


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["unobtainium"], "unknown material 'unobtainium'; choose one of: acrylic"),
        (["steel", "--medium", "steel"], "--medium: 'steel' is a solid"),
        (["steel", "--angles", "10,95"], "--angles: incidence angles lie in [0, 90]"),
    ],
)
def test_cli_material_show_refuses_bad_input_in_one_line(capsys, monkeypatch, args, expected):
    code, _, err = run_main(["material", "show", *args], capsys, monkeypatch)
    assert code == 2 and expected in " ".join(err.split()) and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
