"""Over curved parts the wave model's echo peaks at the surface normal (physical optics),
and ``true_optimum`` finds the global maximum from any probe position.

Truth is geometric: the normal of a sphere through the probe is the line to its centre;
in a bore the beam through the axis meets the far wall at normal incidence.  A maximum
"at the normal within STEP" is checked as: the noiseless echo at the normal exceeds the
echo STEP away in each of the four gimbal directions.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from echocal.geometry import convert_angles, tilt_normal
from echocal.setups import setup_with_overrides
from echocal.specimen import Cylinder, Specimen, Sphere

MM = 1e-3


STEP = 0.05
"""[deg] The precision these tests hold the maximum to (the issue's 0.05°).  It needs the
finer sampling of curved surfaces (1.35 λ; at 2.7 λ the sampling, which moves with the
probe, rippled the lobe's top by 1e-4–4e-2 and moved the maximum by 0.06–0.4°)."""

FLAT = 2e-3
"""Across a cylinder's axis the lobe can be flat-topped: within ±0.2° of the normal no echo
exceeds the normal's by more than this fraction (measured: up to 1.3e-3 above it, 12.7 mm
over the rod and 6.35 mm in the bore; the 3 mm probe's falls off) — below any
measurement's noise, so no echo can place the maximum finer there."""


def _wave_setup(width: float, specimen: Specimen | None = None, aperture: str = "circular"):
    base = setup_with_overrides("scan-5mhz", specimen="sphere")
    probe = dataclasses.replace(base.transducer, width=width, height=width, aperture=aperture)
    receiver = dataclasses.replace(base.receiver, snr_db=None)
    setup = dataclasses.replace(base, reflection="wave", transducer=probe, receiver=receiver)
    return setup if specimen is None else dataclasses.replace(setup, specimen=specimen)


def _tilts(n: np.ndarray) -> tuple[float, float]:
    """Gimbal tilts [deg] of the orientation normal n = (sinβ cosα, −sinα, cosβ cosα)."""
    n = n / np.linalg.norm(n)
    return math.degrees(math.asin(-n[1])), math.degrees(math.atan2(n[0], n[2]))


def _check_cylinder(setup, position, tilts) -> None:
    """Along the axis (tilt a) the maximum is at the normal within STEP.  Across it
    (tilt b) the cylinder is mirror-symmetric about the plane through its axis and the
    probe, so the echo is even in b — stationary at the normal — and nowhere within ±0.2°
    more than FLAT above the normal's."""
    a0, b0 = tilts
    along = setup.metric_values(position, a0 + np.array([0.0, STEP, -STEP]), np.full(3, b0),
                                parameterization="tilt")  # fmt: skip
    assert np.all(along[0] >= along[1:]), along
    across = setup.metric_values(position, np.full(5, a0),
                                 b0 + np.array([0.0, STEP, -STEP, 0.2, -0.2]),
                                 parameterization="tilt")  # fmt: skip
    np.testing.assert_allclose(across[1::2], across[2::2], rtol=1e-9)  # even in b
    assert np.all(across[1:] / across[0] <= 1.0 + FLAT), across / across[0]


def _is_local_max(setup, position, tilts, step=STEP) -> tuple[bool, np.ndarray]:
    a0, b0 = tilts
    a = np.array([a0, a0 + step, a0 - step, a0, a0])
    b = np.array([b0, b0, b0, b0 + step, b0 - step])
    values = setup.metric_values(position, a, b, parameterization="tilt")
    return bool(np.all(values[0] >= values[1:])), values


BORE = Specimen(
    [
        Cylinder(
            center=(0.0, 0.0, 0.0),
            radius=15 * MM,
            length=100 * MM,
            azimuth=90.0,
            coelevation=90.0,
            surface="inside",
            name="bore",
        )
    ],
    name="bore",
)


@pytest.mark.parametrize("width_mm", [3.0, 6.35, 12.7])
@pytest.mark.parametrize("position_mm", [(0.0, 0.0, 25.0), (4.0, 2.0, 22.0), (-6.0, 3.0, 20.0)])
def test_echo_over_a_sphere_peaks_at_its_normal(width_mm, position_mm) -> None:
    setup = _wave_setup(width_mm * MM)
    position = np.array(position_mm) * MM
    centre = np.asarray(setup.specimen[0].center)
    ok, values = _is_local_max(setup, position, _tilts(position - centre))
    assert ok, values


@pytest.mark.parametrize("width_mm", [3.0, 6.35])
def test_square_probe_echo_over_a_sphere_and_a_rod_peaks_at_the_normal(width_mm) -> None:
    """A flat square probe (the rectangle's closed-form SIR and the Kirchhoff sum): the
    beam through the sphere's centre keeps the square's mirror symmetries, so the echo
    peaks at the normal within STEP; along a rod's axis too, and across it it is even."""
    setup = _wave_setup(width_mm * MM, aperture="rectangular")
    position = np.array([4.0, 2.0, 22.0]) * MM
    centre = np.asarray(setup.specimen[0].center)
    ok, values = _is_local_max(setup, position, _tilts(position - centre))
    assert ok, values
    rod = Cylinder(
        center=(0.0, 0.0, -20 * MM), radius=20 * MM, length=100 * MM, azimuth=90.0,
        coelevation=90.0, surface="outside", name="rod",
    )  # fmt: skip
    setup = _wave_setup(width_mm * MM, Specimen([rod], name="cylinder"), aperture="rectangular")
    position = np.array([5.0, 3.0, 24.0]) * MM
    _check_cylinder(setup, position, _tilts(position - np.array([0.0, position[1], -20 * MM])))


@pytest.mark.parametrize("width_mm", [3.0, 12.7])
def test_echo_over_a_cylinder_peaks_at_its_normal(width_mm) -> None:
    rod = Cylinder(
        center=(0.0, 0.0, -20 * MM), radius=20 * MM, length=100 * MM, azimuth=90.0,
        coelevation=90.0, surface="outside", name="rod",
    )  # fmt: skip
    setup = _wave_setup(width_mm * MM, Specimen([rod], name="cylinder"))
    position = np.array([5.0, 3.0, 24.0]) * MM
    radial = position - np.array([0.0, position[1], -20 * MM])
    _check_cylinder(setup, position, _tilts(radial))


@pytest.mark.parametrize("width_mm", [3.0, 6.35])
def test_echo_in_a_bore_peaks_at_its_normal(width_mm) -> None:
    setup = _wave_setup(width_mm * MM, BORE)
    position = np.array([4.0, 2.0, 8.0]) * MM
    radial = np.array([position[0], 0.0, position[2]])  # the beam goes down through the axis
    _check_cylinder(setup, position, _tilts(radial))


def test_true_optimum_in_a_bore_is_global() -> None:
    """From (4, 2, 8) mm in a bore the optimum was 24.9° off the normal (a side lobe)."""
    setup = dataclasses.replace(_wave_setup(3 * MM, BORE), reflection="lambertian")
    position = np.array([4.0, 2.0, 8.0]) * MM
    a, b = setup.true_optimum(position, parameterization="tilt")
    found = tilt_normal(np.array([a]), np.array([b])).reshape(3)
    want = np.array([4.0, 0.0, 8.0]) / math.hypot(4.0, 8.0)
    assert math.degrees(math.acos(min(1.0, float(found @ want)))) < 1.0


@pytest.mark.slow
@pytest.mark.parametrize("width_mm", [3.0, 6.35, 12.7])
def test_wave_true_optimum_over_a_sphere_is_its_normal_within_0_05_deg(width_mm) -> None:
    setup = _wave_setup(width_mm * MM)
    position = np.array([4.0, 2.0, 22.0]) * MM
    az, coel = setup.true_optimum(position)
    a, b = convert_angles(az, coel, "azimuth-coelevation", "tilt")
    found = tilt_normal(np.array([a]), np.array([b])).reshape(3)
    want = position - np.asarray(setup.specimen[0].center)
    want /= np.linalg.norm(want)
    # measured 0.000°, 0.008°, 0.002° (0.058° for 3 mm at the planes' 2.7 λ sampling)
    assert math.degrees(math.acos(min(1.0, float(found @ want)))) < 0.05


def test_sphere_centre_attribute_is_what_the_tests_assume() -> None:
    sphere = setup_with_overrides("scan-5mhz", specimen="sphere").specimen[0]
    assert isinstance(sphere, Sphere)
