"""Time-of-flight surface fits against the simulator's truth (wave model, 30 dB).

One noiseless simulation per part; the receiver's noise is then drawn per seed
(:func:`receiver_noise`, exactly what a noisy simulation adds).  The truth is written
here from the part's definition, without echocal's geometry.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from echocal.errors import EchocalValueError
from echocal.positionscan import fit_surface, receiver_noise, simulate_position_scan
from echocal.setups import load_setup
from echocal.specimen import FinitePlane, Specimen, builtin_specimen

SEEDS = range(10)
"""Seeded runs per part; the truth must lie inside 3 σ in at least 9 of them (a 95 %
coverage; a calibrated 1-σ misses 3 σ in 0.3 % of runs).  benchmarks/tof_surface_fit.py
runs more."""


@pytest.fixture(scope="module")
def setup():
    return load_setup("scan-5mhz")  # 3 mm 5 MHz disc, 25 mm water path, 30 dB


def _inside(errors: list[float], sigmas: list[float]) -> int:
    return sum(abs(e) <= 3 * s for e, s in zip(errors, sigmas, strict=True))


def test_tilted_plate_tilt_and_distance(setup):
    az, co = math.radians(30.0), math.radians(0.5)  # the plate's normal
    n = np.array([math.sin(co) * math.cos(az), math.sin(co) * math.sin(az), math.cos(co)])
    plate = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1, azimuth=30.0, coelevation=0.5)
    virtual = dataclasses.replace(setup, specimen=Specimen([plate], name="plate"))
    xs = np.linspace(-5e-3, 5e-3, 9)
    ideal = simulate_position_scan(virtual, x=xs, y=xs, noise=False)
    z0 = 0.025
    # gimbal tilts of n: n = (sin ty cos tx, -sin tx, cos ty cos tx)
    truth = {
        "tilt_x": -math.degrees(math.asin(n[1])),
        "tilt_y": math.degrees(math.atan2(n[0], n[2])),
        "distance": n[2] * z0,  # from the scan's centre (0, 0, z0) to the plane through 0
    }
    errors: dict[str, list[float]] = {k: [] for k in truth}
    sigmas: dict[str, list[float]] = {k: [] for k in truth}
    for seed in SEEDS:
        fit = fit_surface(receiver_noise(ideal, virtual, seed), "plane")
        for key, value in truth.items():
            errors[key].append(fit.parameters[key] - value)
            sigmas[key].append(fit.sigma[key])
    # the targets: tilt within 0.01 deg, distance within 10 um, at 30 dB
    assert max(abs(e) for e in errors["tilt_x"] + errors["tilt_y"]) < 0.01
    assert max(abs(e) for e in errors["distance"]) < 10e-6
    for key in truth:
        assert _inside(errors[key], sigmas[key]) >= 9, (key, errors[key], sigmas[key])
    assert not fit.misfit and fit.noise == pytest.approx(fit.rms, rel=0.3)  # white residuals


@pytest.mark.parametrize(("part", "radius"), [("sphere", 25e-3), ("cylinder", 20e-3)])
def test_curved_part_radius(setup, part, radius):
    # the model is a small probe's echo along the surface normal: a 1 mm disc
    probe = dataclasses.replace(setup.transducer, width=1e-3, height=1e-3)
    virtual = dataclasses.replace(setup, specimen=builtin_specimen(part), transducer=probe)
    xs = np.linspace(-4e-3, 4e-3, 7)
    ideal = simulate_position_scan(virtual, x=xs + 0.4e-3, y=xs, noise=False)
    errors, sigmas = [], []
    for seed in SEEDS:
        fit = fit_surface(receiver_noise(ideal, virtual, seed), part)
        errors.append(fit.parameters["radius"] - radius)
        sigmas.append(fit.sigma["radius"])
    assert max(abs(e) for e in errors) < 0.01 * radius  # within 1 %
    assert _inside(errors, sigmas) >= 9, (errors, sigmas)
    assert not fit.misfit
    if part == "cylinder":  # the rod lies along y (axis azimuth 90 deg, level)
        assert abs(abs(fit.parameters["axis_azimuth"]) - 90.0) < 1.0
        assert abs(fit.parameters["axis_elevation"]) < 0.5


def test_a_wide_probe_on_a_sphere_is_flagged_as_a_misfit(setup):
    # the 3 mm disc over the 25 mm ball, 4 mm off its top: its echoes do not follow the
    # small-probe model (the radius comes out near 14 mm); the fit must say so
    virtual = dataclasses.replace(setup, specimen=builtin_specimen("sphere"))
    xs = np.linspace(-4e-3, 4e-3, 7)
    fit = fit_surface(simulate_position_scan(virtual, x=xs, y=xs, rng=1), "sphere")
    assert fit.misfit and fit.rms > 2.5 * fit.noise
    assert fit.summary()["misfit"] is True


def test_outliers_are_set_aside_and_bad_requests_refused(setup):
    plate = FinitePlane(center=(0, 0, 0), width=0.1, height=0.1)
    virtual = dataclasses.replace(setup, specimen=Specimen([plate], name="plate"))
    ideal = simulate_position_scan(virtual, x=np.linspace(-2e-3, 2e-3, 6), noise=False)
    noisy = receiver_noise(ideal, virtual, 0)
    samples = noisy.samples.copy()
    k = np.argmax(np.abs(samples[0, 2]))
    samples[0, 2] = np.roll(samples[0, 2], 25)  # one trace 0.5 us late: an outlier
    assert samples[0, 2, k + 25] == noisy.samples[0, 2, k]
    fit = fit_surface(noisy.with_samples(samples), "plane")
    assert not fit.inliers[0, 2] and fit.inliers.sum() == 5
    assert abs(fit.parameters["tilt_y"]) < 0.05  # the outlier did not tilt the line
    with pytest.raises(EchocalValueError, match="raster"):
        fit_surface(noisy, "sphere")
    with pytest.raises(EchocalValueError, match="shape must be one of"):
        fit_surface(noisy, "cone")


def test_cli_record_scan_then_surface(tmp_path, capsys, monkeypatch):
    import json

    from cli_helpers import run_main
    from echocal.positionscan import PositionScan

    out = tmp_path / "line.nc"
    args = ["record-scan", "--setup", "scan-5mhz", "--specimen", "flat-plate"]
    code, _, err = run_main([*args, "--x=-2:2:5", "--out", str(out)], capsys, monkeypatch)
    assert code == 0, err
    scan = PositionScan.load(out)
    assert scan.dataset["samples"].dims == ("x", "time") and scan.probe_z == 0.025
    fig, maps = tmp_path / "res.png", tmp_path / "fit.nc"
    code, stdout, err = run_main(
        ["surface", str(out), "--json", "--figure", str(fig), "--out", str(maps)],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    fit = json.loads(stdout)
    # a level plate 25 mm below: tilt 0, distance 25 mm (3 sigma of a 5-trace line)
    assert abs(fit["parameters"]["distance"] - 0.025) < 3 * fit["sigma"]["distance"] + 1e-6
    assert fig.stat().st_size > 10_000 and maps.stat().st_size > 0
    code, _, err = run_main(["surface", str(out), "--shape", "cone"], capsys, monkeypatch)
    assert code != 0 and "shape must be one of" in err and "Traceback" not in err
