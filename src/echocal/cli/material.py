"""``echocal material list|show``: the built-in materials and their interface coefficients."""

from __future__ import annotations

from typing import Any

import typer

_F_SHOWN = 5.0e6
"""[Hz] the frequency at which ``material list`` states each attenuation."""


def _row(m: Any) -> dict[str, Any]:
    from echocal.materials import NEPER_TO_DB

    return {
        "name": m.name,
        "density_kg_m3": m.density,
        "longitudinal_speed_m_s": m.longitudinal_speed,
        "shear_speed_m_s": m.shear_speed,
        "impedance_mrayl": m.impedance / 1e6,
        "attenuation_db_per_mm_5mhz": float(m.attenuation.alpha(_F_SHOWN)) * NEPER_TO_DB / 1e3,
    }


def _parse_angles(text: str) -> list[float]:
    from echocal.errors import EchocalValueError
    from echocal.units import parse_angle

    angles = [parse_angle("--angles", part) for part in text.split(",") if part.strip()]
    bad = [a for a in angles if not 0.0 <= a <= 90.0]
    if bad:
        raise EchocalValueError(
            f"--angles: incidence angles lie in [0, 90] deg from the normal; got {bad[0]:g}"
        )
    return angles


def material_report(name: str, medium: str = "water", angles: list[float] | None = None) -> dict:
    """Properties of material ``name`` and its coefficients against the fluid ``medium``:
    critical angles [deg], normal-incidence R, T in and out, the back-wall round trip
    T_in·R_back·T_out and, at each of ``angles`` [deg], R, T_L and T_T (magnitude, phase)."""
    import numpy as np

    from echocal.errors import EchocalValueError
    from echocal.materials import (
        critical_angles,
        material,
        reflection_fluid_solid,
        reflection_solid_fluid,
        transmission_fluid_solid,
        transmission_solid_fluid,
    )

    part, fluid = material(name), material(medium)
    if not fluid.is_fluid:
        raise EchocalValueError(
            f"--medium: {fluid.name!r} is a solid; the coupling medium must be a fluid (water)"
        )
    report: dict[str, Any] = {**_row(part), "poisson_ratio": part.poisson_ratio}
    report["medium"] = _row(fluid)
    r0 = complex(reflection_fluid_solid(0.0, fluid, part))
    t_in = complex(transmission_fluid_solid(0.0, fluid, part).longitudinal)
    t_out = complex(transmission_solid_fluid(0.0, part, fluid))
    r_back = complex(reflection_solid_fluid(0.0, part, fluid).longitudinal)
    first, second = critical_angles(fluid, part)
    report["normal_incidence"] = {
        "reflection": r0.real,
        "transmission_in": t_in.real,
        "transmission_out": t_out.real,
        "back_wall_round_trip": (t_in * r_back * t_out).real,
    }
    report["critical_angles_deg"] = {"longitudinal": first, "shear": second}
    if angles:
        theta = np.asarray(angles, dtype=np.float64)
        r = reflection_fluid_solid(theta, fluid, part)
        t = transmission_fluid_solid(theta, fluid, part)
        report["oblique"] = [
            {
                "angle_deg": float(theta[i]),
                "reflection_abs": float(abs(r[i])),
                "reflection_phase_deg": float(np.degrees(np.angle(r[i]))),
                "transmission_longitudinal_abs": float(abs(t.longitudinal[i])),
                "transmission_shear_abs": float(abs(t.shear[i])),
                "refraction_longitudinal_deg": float(t.angle_longitudinal[i]),
                "refraction_shear_deg": float(t.angle_shear[i]),
                "longitudinal_wave": _wave_kind(float(theta[i]), first),
                "shear_wave": _wave_kind(float(theta[i]), second),
            }
            for i in range(theta.size)
        ]
    return report


def _wave_kind(angle: float, critical: float | None) -> str:
    """ "evanescent" past the critical angle [deg] of a transmitted wave, else
    "propagating" (no critical angle: the wave always propagates)."""
    return "evanescent" if critical is not None and angle > critical else "propagating"


EVANESCENT_NOTE = (
    "evanescent: past its critical angle the transmitted wave decays away from the surface "
    "and carries no energy into the part; |T| is its amplitude at the surface"
)


def register(app: typer.Typer) -> None:
    """Add the ``material`` command group to ``app``."""
    group = typer.Typer(
        name="material",
        help="Built-in materials (density, sound speeds, attenuation) and the reflection and "
        "transmission coefficients at their interface with the coupling fluid.",
        no_args_is_help=True,
    )
    app.add_typer(group, name="material")

    @group.command("list")
    def list_materials(
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """List the built-in materials: ρ, c_L, c_T, Z and α at 5 MHz."""
        from echocal.cli._common import write_json
        from echocal.materials import MATERIALS

        rows = [_row(m) for m in MATERIALS.values()]
        if as_json:
            write_json({"materials": rows})
            return
        typer.echo(
            f"{'name':<16s} {'ρ kg/m³':>8s} {'c_L m/s':>8s} {'c_T m/s':>8s} {'Z MRayl':>8s} "
            f"{'α dB/mm @5MHz':>14s}"
        )
        for row in rows:
            typer.echo(
                f"{row['name']:<16s} {row['density_kg_m3']:8.6g} "
                f"{row['longitudinal_speed_m_s']:8.6g} {row['shear_speed_m_s']:8.6g} "
                f"{row['impedance_mrayl']:8.4g} {row['attenuation_db_per_mm_5mhz']:14.3g}"
            )

    @group.command("show")
    def show(
        name: str = typer.Argument(..., help="Material name (case-insensitive; aluminum, pmma)."),
        medium: str = typer.Option("water", "--medium", help="The coupling fluid."),
        angles: str = typer.Option(
            "", "--angles", help="Incidence angles [deg], comma-separated, e.g. 0,10,20,30."
        ),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """A material's properties and its coefficients against the coupling fluid."""
        from echocal.cli._common import write_json

        report = material_report(name, medium, _parse_angles(angles))
        if as_json:
            write_json(report)
            return
        n, c = report["normal_incidence"], report["critical_angles_deg"]
        typer.echo(
            f"{report['name']}: ρ {report['density_kg_m3']:g} kg/m³, c_L "
            f"{report['longitudinal_speed_m_s']:g} m/s, c_T {report['shear_speed_m_s']:g} m/s, "
            f"Z {report['impedance_mrayl']:.4g} MRayl, ν {report['poisson_ratio']:.3f}, "
            f"α {report['attenuation_db_per_mm_5mhz']:.3g} dB/mm at 5 MHz"
        )
        typer.echo(
            f"from {medium} at normal incidence: R {n['reflection']:.4f}, T in "
            f"{n['transmission_in']:.4f}, T out {n['transmission_out']:.4f}, back-wall round "
            f"trip {n['back_wall_round_trip']:.4f}"
        )
        shown = [f"{v:.2f}°" if v is not None else "none" for v in c.values()]
        typer.echo(f"critical angles: longitudinal {shown[0]}, shear {shown[1]}")
        rows = report.get("oblique", [])
        for row in rows:
            typer.echo(
                f"  {row['angle_deg']:6.2f}°  |R| {row['reflection_abs']:.4f} "
                f"({row['reflection_phase_deg']:+7.2f}°)  |T_L| "
                f"{row['transmission_longitudinal_abs']:.4f}{_mark(row['longitudinal_wave'])}"
                f"  |T_T| {row['transmission_shear_abs']:.4f}{_mark(row['shear_wave'])}"
            )
        if any("evanescent" in (r["longitudinal_wave"], r["shear_wave"]) for r in rows):
            typer.echo(f"  {EVANESCENT_NOTE}")


def _mark(kind: str) -> str:
    return " (evanescent)" if kind == "evanescent" else ""
