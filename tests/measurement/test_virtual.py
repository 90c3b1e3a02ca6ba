"""The simulator as a source: physics invariants and the truth it knows."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from echocal import MM, SOUND_SPEED_WATER, EchocalValueError, LimitError, Pose
from echocal.echo import ray_echoes
from echocal.errors import GeometryError
from echocal.geometry import angle_between, orientation_frame, orientation_normal, tilt_normal
from echocal.measurement import PositionerLimits, ReceiverSettings, VirtualSetup
from echocal.signal import RecordingWindow, make_pulse, pseudo_energy, time_of_flight
from echocal.specimen import TILTED_PLATE_ORIENTATION, Cylinder, Specimen, Sphere, builtin_specimen
from echocal.transducer import Transducer

WINDOW = RecordingWindow(fs=100e6, start=20e-6, n_samples=2048)
PULSE = make_pulse("gabor", center_frequency=5e6, bandwidth=60)


def setup(specimen="flat-plate", snr_db=30.0, rng=7, **kwargs):
    return VirtualSetup(
        specimen=builtin_specimen(specimen),
        transducer=kwargs.pop("transducer", Transducer(n_h=24, n_v=24)),
        pulse=PULSE,
        window=WINDOW,
        receiver=ReceiverSettings(snr_db=snr_db),
        rng=rng,
        **kwargs,
    )


def test_time_of_flight_at_normal_incidence_is_two_d_over_c():
    # A single ray straight down from 20 mm above the plate: τ = 2d/c₀ exactly.
    one_ray = Transducer(n_h=1, n_v=1)
    echoes = ray_echoes(
        one_ray,
        builtin_specimen("flat-plate"),
        np.array([[0.0, 0.0, 20 * MM]]),
        orientation_frame(0.0, 0.0)[None],
    )
    expected = 2 * 20 * MM / SOUND_SPEED_WATER
    assert echoes.tof[0, 0] == pytest.approx(expected, rel=1e-12)
    assert echoes.amplitude[0, 0] == pytest.approx(1.0)
    # ... and the A-scan's matched-filter peak finds it to a small fraction of a sample.
    sim = setup(snr_db=None, transducer=one_ray)
    scan = sim.measure(Pose(0, 0, 20 * MM))
    tof = time_of_flight(scan.samples, WINDOW, PULSE)
    assert abs(tof - expected) < 0.05 / WINDOW.fs


@pytest.mark.parametrize("model", ["lambertian", "specular"])
def test_energy_peaks_at_normal_incidence_and_is_symmetric(model):
    sim = setup(snr_db=None, reflection=model)
    coel = np.array([-4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0])
    energy = sim.metric_values([0, 0, 20 * MM], 0.0, coel)
    assert np.argmax(energy) == 3
    # Symmetric about normal incidence: mirror-image poses see mirror-image geometry
    # (the pixel grid is symmetric), so energies agree to synthesis accuracy (1e-4 L2).
    assert_allclose(energy[:3], energy[4:][::-1], rtol=1e-3)
    assert np.all(np.diff(energy[3:]) < 0)


def test_noise_is_the_instruments_and_gives_the_requested_snr():
    sim = setup(snr_db=20.0)
    sigma = sim.noise_sigma
    # SNR definition: mean reference power inside the pseudo-energy window over σ².
    ref = sim.reference_samples
    power = pseudo_energy(ref, WINDOW, PULSE)
    count = round(2 * PULSE.duration * WINDOW.fs) + 1
    assert 10 * np.log10(power / count / sigma**2) == pytest.approx(20.0, abs=0.2)
    # Off-peak measurements carry the same absolute noise (fixed σ), so their SNR is lower.
    far = sim.simulate([Pose(0, 0, 20 * MM, 0, 30)] * 50)
    quiet = far[:, :200]  # before any echo
    assert np.std(quiet) == pytest.approx(sigma, rel=0.05)  # 10k samples: ±3 % at 3σ


def test_seed_reproduces_bit_for_bit_and_differs_otherwise():
    pose = Pose(0, 0, 20 * MM, 10, 2)
    a = setup(rng=3).measure(pose).samples
    b = setup(rng=3).measure(pose).samples
    c = setup(rng=4).measure(pose).samples
    assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_batch_equals_single_measurements_noiseless():
    sim = setup(snr_db=None)
    poses = [Pose(0, 0, 20 * MM, az, co) for az, co in [(0, 0), (30, 2), (-60, 5)]]
    batch = sim.measure_many(poses)
    for pose, scan in zip(poses, batch, strict=True):
        assert_allclose(scan.samples, sim.measure(pose).samples, atol=1e-15)
        assert scan.pose == pose


def test_true_optimum_of_tilted_plate_is_its_normal():
    sim = setup("tilted-plate", snr_db=None)
    az, coel = sim.true_optimum([0.0, 0.0, 20 * MM])
    plate = orientation_normal(*TILTED_PLATE_ORIENTATION)
    # Nelder–Mead to 1e-5° on a smooth noiseless lobe: 1e-3° is a safe bound.
    assert angle_between(orientation_normal(az, coel), plate) < 1e-3
    tx, ty = sim.true_optimum([0.0, 0.0, 20 * MM], parameterization="tilt")
    assert_allclose(sim.true_pose([0, 0, 20 * MM]).tilt, (tx, ty), atol=1e-9)


def test_limits_and_closing():
    sim = setup(limits=PositionerLimits(coelevation=(-10.0, 10.0)))
    with pytest.raises(LimitError, match="coelevation"):
        sim.measure(Pose(0, 0, 20 * MM, 0, 20))
    sim.close()
    with pytest.raises(EchocalValueError, match="closed"):
        sim.measure(Pose(0, 0, 20 * MM))


def test_bad_settings_name_the_field():
    with pytest.raises(EchocalValueError, match="snr_db"):
        ReceiverSettings(snr_db=float("nan"))
    with pytest.raises(KeyError, match="lambertian, specular"):
        setup(reflection="diffuse")


def test_true_optimum_over_a_sphere_points_at_its_centre():
    # Off-centre over a sphere the beam of maximum echo meets the surface at normal
    # incidence: along the line from the probe to the sphere's centre (0, 0, −25 mm).
    # 64 × 64 rays: with 24 × 24 the ray model aliases over the sphere, and spikes 3° off
    # the normal rise above its hump (the truth is the global maximum, spikes included).
    sim = setup("sphere", snr_db=None, transducer=Transducer(n_h=64, n_v=64))
    position = np.array([10 * MM, 0.0, 25 * MM])
    az, coel = sim.true_optimum(position)
    expected = position - np.array([0.0, 0.0, -25 * MM])
    # Symmetric beam on a sphere: the echo peaks exactly there (search tol 1e-5°).
    assert angle_between(orientation_normal(az, coel), expected) < 1e-3


def test_perpendicular_start_aims_at_the_nearest_surface_point():
    # Over a sphere the nearest surface point lies on the line to its centre (0, 0, −25 mm):
    # from (10, 0, 25) mm the beam tilts by atan(10 / 50) = 11.3° towards −x.  The search
    # fan has 1° steps, so the start is within half a step (0.5°) of that, per axis.
    sim = setup("sphere", snr_db=None)
    tx, ty = sim.perpendicular_start(np.array([10 * MM, 0.0, 25 * MM]))
    start = tilt_normal(tx, ty)
    assert angle_between(start, np.array([10.0, 0.0, 50.0])) <= np.hypot(0.5, 0.5)


def test_setup_is_frozen_so_its_cached_noise_cannot_go_stale():
    import dataclasses

    sim = setup(snr_db=20.0)
    sigma = sim.noise_sigma
    with pytest.raises(dataclasses.FrozenInstanceError):
        sim.receiver = ReceiverSettings(snr_db=40.0)
    quieter = dataclasses.replace(sim, receiver=ReceiverSettings(snr_db=40.0))
    # 20 dB more SNR = 10x smaller noise amplitude (same reference echo).
    assert quieter.noise_sigma == pytest.approx(sigma / 10.0, rel=1e-9)


BORE = 40 * MM


# the bore wall is 40 mm below the axis: round trip 2 * 40 mm / c ~ 54 us
BORE_WINDOW = RecordingWindow(fs=100e6, start=40e-6, n_samples=2048)


def pipe() -> Specimen:
    # horizontal pipe (axis along x): a solid rod of radius 50 mm with a 40 mm bore
    common = {"center": (0.0, 0.0, 0.0), "length": 0.2, "coelevation": 90.0}
    outer = Cylinder(radius=50 * MM, surface="outside", name="wall", **common)
    bore = Cylinder(radius=BORE, surface="inside", name="bore", **common)
    return Specimen([outer, bore], name="pipe")


def virtual(specimen: Specimen, at=(0.0, 0.0, 0.0)) -> VirtualSetup:
    return VirtualSetup(
        specimen=specimen,
        transducer=Transducer(n_h=8, n_v=8),
        pulse=PULSE,
        window=BORE_WINDOW,
        receiver=ReceiverSettings(snr_db=60.0),
        reference_position=at,
        rng=3,
    )


def test_probe_in_the_bore_builds_and_hears_the_bore_wall():
    setup = virtual(pipe())
    scan = setup.measure(Pose(0.0, 0.0, 0.0, 0.0, 0.0))
    envelope = np.abs(scan.samples)
    peak_time = scan.times[int(np.argmax(envelope))]
    # the echo peak lies within a few pulse periods (5 MHz: 0.2 us) of 2 r / c; the finite
    # aperture on the curved wall and the pulse shape shift it by well under 1 us
    assert peak_time == pytest.approx(2 * BORE / SOUND_SPEED_WATER, abs=1e-6)
    assert envelope.max() > 10 * np.median(envelope)


def test_containing_excludes_the_bore_but_not_the_wall():
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 45 * MM], [0.0, 0.0, 60 * MM]])
    # axis in the bore: medium; between bore and outer wall: material; outside: medium
    assert pipe().containing(points).tolist() == [-1, 0, -1]
    with pytest.raises(GeometryError, match="inside cylinder 'wall'"):
        virtual(pipe(), at=(0.0, 0.0, 45 * MM))
    # beyond the bore's length the rod is solid again
    short = Specimen(
        [
            Cylinder(center=(0, 0, 0), radius=50 * MM, length=0.2, coelevation=90.0),
            Cylinder(
                center=(0, 0, 0), radius=BORE, length=0.05, coelevation=90.0, surface="inside"
            ),
        ]
    )
    assert short.containing([[0.09, 0.0, 0.0], [0.0, 0.0, 0.0]]).tolist() == [0, -1]


@pytest.mark.parametrize(
    "shape",
    [
        Cylinder(center=(0, 0, 0), radius=50 * MM, length=0.2, coelevation=90.0),
        Sphere(center=(0, 0, 0), radius=50 * MM),
    ],
)
def test_probe_inside_a_plain_solid_is_still_refused(shape):
    with pytest.raises(GeometryError, match="probe must be outside the part"):
        virtual(Specimen([shape]))
    assert Specimen([shape]).containing([[0.0, 0.0, 0.0]]).tolist() == [0]
