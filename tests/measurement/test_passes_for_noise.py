"""The search sized for the echo the probe's model predicts against the measured noise
(:func:`echocal.measurement.detection_radius.passes_for_noise`, the acquisition's
``replan``).

Independent truth: the SNR definition (P_signal / σ², :mod:`echocal.signal.noise`) and
the lattice spacings of :meth:`LobeProfile.lattice_spacing` (checked against closed forms
and random points in test_detection_radius.py); the acquisition's queue against
:func:`search_rings` built directly.
"""

from __future__ import annotations

import numpy as np
import pytest

from echocal.calibrate import Acquisition, CalibrationResult, FunctionObjective, calibrate
from echocal.calibrate.acquisition import search_rings
from echocal.errors import EchocalValueError
from echocal.measurement import SourceObjective
from echocal.measurement import detection_radius as dr
from echocal.setups import load_setup, setup_with_overrides
from echocal.signal.gates import resolve_gate
from echocal.signal.noise import noise_sigma_for_snr, signal_power, snr_for_noise_sigma


@pytest.fixture(scope="module")
def ray():
    setup = load_setup("immersion-5mhz-ray", seed=0)
    pos = np.asarray(setup.reference_position, float)
    return setup, pos, dr.cached_lobe_profile(setup, pos)


def _sigma(setup, profile, snr):
    return float(noise_sigma_for_snr(profile.reference, snr, setup.window, setup.pulse))


@pytest.mark.parametrize("snr", [-5.0, 10.0, 30.0, 57.3])
def test_the_snr_of_a_noise_level_inverts_the_noise_level_of_an_snr(ray, snr):
    setup, _, profile = ray
    sigma = _sigma(setup, profile, snr)
    measured = snr_for_noise_sigma(profile.reference, sigma, setup.window, setup.pulse)
    assert measured == pytest.approx(snr, abs=1e-9)
    power = float(signal_power(profile.reference, setup.window, setup.pulse))
    assert 10 ** (measured / 10) == pytest.approx(power / sigma**2, rel=1e-9)  # the definition


def test_a_noiseless_receiver_has_infinite_snr_and_bad_sigmas_are_refused(ray):
    setup, _, profile = ray
    assert snr_for_noise_sigma(profile.reference, 0.0, setup.window, setup.pulse) == np.inf
    for bad in (-1.0, float("nan"), True):
        with pytest.raises(EchocalValueError, match="noise_sigma"):
            snr_for_noise_sigma(profile.reference, bad, setup.window, setup.pulse)


@pytest.mark.parametrize("snr", [10.0, 23.5])
def test_the_predicted_echo_snr_is_the_snr_whose_noise_was_measured(ray, snr):
    """ŝ inverts the noise level of an SNR (the definition, P / σ²), and the passes are
    those of that SNR."""
    setup, pos, profile = ray
    sigma = _sigma(setup, profile, snr)
    assert dr.echo_snr_for_noise(setup, pos, sigma) == pytest.approx(snr, abs=1e-9)
    assert dr.passes_for_noise(setup, pos, sigma) == dr.passes_for_snr(setup, pos, snr)
    assert dr.passes_for_snr(setup, pos, float("nan")) is None


def test_passes_start_at_the_predicted_echo_and_keep_the_finer_ones(ray):
    setup, pos, profile = ray
    ladder = dr.search_passes(setup, pos)  # sized for 30 then 20 dB

    def passes(snr):
        return dr.passes_for_noise(setup, pos, _sigma(setup, profile, snr))

    assert passes(30.0) == ladder  # the 30 dB echo: the ladder itself
    assert passes(20.0) == ladder[1:]  # the 20 dB echo: its own pass only
    strong = passes(40.0)
    assert strong[0] > ladder[0] and strong[1:] == ladder  # seen from farther: coarser first
    assert strong[0] == pytest.approx(profile.lattice_spacing(40.0), abs=0.01)
    middle = passes(25.0)
    assert ladder[1] < middle[0] < ladder[0] and middle[1:] == ladder[1:]
    weak = passes(10.0)  # one pass, finer than the ladder, which cannot see it
    assert len(weak) == 1 and weak[0] == pytest.approx(profile.lattice_spacing(10.0), abs=0.01)
    assert weak[0] < passes(19.0)[0] < ladder[1]
    assert passes(-10.0) is None  # no pass of at least MIN_PASS_SPACING sees it: the plan stays
    assert profile.lattice_spacing(-3.0) < dr.MIN_PASS_SPACING


def test_the_source_objective_predicts_from_the_noise_its_a_scans_show(ray):
    """One A-scan's robust σ (1.4826 MAD of its samples) is within a few % of the
    receiver's: the first pass within 0.3° of the 30 dB ladder's (8 % in σ is 0.7 dB)."""
    setup, pos, _ = ray
    noisy = setup_with_overrides("immersion-5mhz-ray", snr_db=30.0, seed=4)
    objective = SourceObjective(noisy, pos, parameterization="tilt")
    assert objective.passes_for_measured_noise() is None  # nothing measured yet
    objective(np.array([[6.0, -4.0]]))  # no echo there: noise only
    passes = objective.passes_for_measured_noise()
    ladder = dr.search_passes(setup, pos)
    assert passes is not None and passes[0] == pytest.approx(ladder[0], abs=0.3)
    weak = setup_with_overrides("immersion-5mhz-ray", snr_db=10.0, seed=4)
    objective = SourceObjective(weak, pos, parameterization="tilt")
    objective(np.array([[6.0, -4.0]]))
    passes = objective.passes_for_measured_noise()  # 0.7 dB is 0.02 deg of the 10 dB pass
    assert passes is not None and len(passes) == 1
    assert passes[0] == pytest.approx(
        dr.cached_lobe_profile(setup, pos).lattice_spacing(10.0), abs=0.1
    )


def test_no_prediction_for_a_gated_metric_or_a_rigs_twin(ray):
    from tests.measurement.fake_sources import GaussianEchoSource

    setup, _, _ = ray
    plate = setup_with_overrides("immersion-steel-plate", snr_db=30.0, seed=0)
    gate = resolve_gate(
        "back-wall", pulse=plate.pulse, thickness=plate.thickness, material=plate.material
    )
    gated = SourceObjective(plate, plate.reference_position, gate=gate, parameterization="tilt")
    gated._scan_sigmas.append(1e-3)  # as if one A-scan had been measured
    assert gated.passes_for_measured_noise() is None
    rig = SourceObjective(GaussianEchoSource(), [0.0, 0.0, 0.02], pulse=setup.pulse, twin=setup)
    rig(np.array([[0.0, 0.0]]))
    assert rig.passes_for_measured_noise() is None  # its amplitude is not the setup's


def _no_echo(points: np.ndarray) -> np.ndarray:
    return np.zeros(len(points))


def _planned(replan, max_radius: float) -> Acquisition:
    """An acquisition planned as ``auto``'s: the 1° lattice to 3°, then 7° and 4° passes."""
    return Acquisition(
        np.zeros(2),
        spacing=1.0,
        noise_sigma=1.0,
        noise_floor=0.0,
        fine_radius=3.0,
        passes=(7.0, 4.0),
        replan=replan,
        max_radius=max_radius,
    )


def test_the_acquisition_replans_once_after_the_first_ring():
    calls = []

    def replan():
        calls.append(1)
        return (6.0, 3.0)

    acq = _planned(replan, max_radius=15.0)
    acq.tell(_no_echo(acq.ask()))
    assert acq.replanned == (6.0, 3.0) and len(calls) == 1
    expected = np.vstack(search_rings(np.zeros(2), 1.0, 15.0, fine_radius=1.0, passes=(6.0, 3.0)))
    assert len(acq._queue) == len(expected)
    np.testing.assert_allclose(np.sort(acq._queue[7:], axis=0), np.sort(expected[7:], axis=0))
    for _ in range(5):
        acq.tell(_no_echo(acq.ask()))
    assert len(calls) == 1
    assert np.all(np.hypot(*acq._x[7:].T) > 3.0)  # no 1° lattice beyond x0's hexagon


def test_a_replan_finer_than_every_planned_pass_keeps_the_fine_lattice():
    """An echo weaker than the plan was sized for: the 1° lattice out to 3° stays, where a
    near start's echo is, and beyond it the replanned pass takes the planned ones' place."""
    acq = _planned(lambda: (1.5,), max_radius=10.0)
    acq.tell(_no_echo(acq.ask()))
    assert acq.replanned == (1.5,)
    expected = np.vstack(search_rings(np.zeros(2), 1.0, 10.0, fine_radius=3.0, passes=(1.5,)))
    assert len(acq._queue) == len(expected)  # the same points (a ring's order may differ)
    np.testing.assert_allclose(np.sort(acq._queue, axis=0), np.sort(expected, axis=0), atol=1e-12)
    # every point out to max_radius within 0.83 s of a search point (search_rings' bound)
    g = np.mgrid[-10:10:0.25, -10:10:0.25].reshape(2, -1).T
    g = g[np.hypot(*g.T) <= 10.0]
    nearest = np.min(np.hypot(*(g[:, None, :] - acq._queue[None]).transpose(2, 0, 1)), axis=1)
    assert nearest.max() <= 0.83 * 1.5


def test_a_replan_of_none_keeps_the_plan_and_bad_ones_are_refused():
    kwargs = dict(spacing=1.0, noise_sigma=1.0, noise_floor=0.0, fine_radius=3.0, passes=(7.0,))
    keep = Acquisition(np.zeros(2), replan=lambda: None, **kwargs)
    plain = Acquisition(np.zeros(2), **kwargs)
    keep.tell(_no_echo(keep.ask()))
    plain.tell(_no_echo(plain.ask()))
    assert keep.replanned is None
    np.testing.assert_allclose(keep._queue, plain._queue)
    with pytest.raises(EchocalValueError, match="replan must be a callable"):
        Acquisition(np.zeros(2), replan=(4.0,), **kwargs)
    bad = Acquisition(np.zeros(2), replan=lambda: "far", **kwargs)
    with pytest.raises(EchocalValueError, match="replan"):
        bad.tell(_no_echo(bad.ask()))


def test_auto_takes_the_objectives_replan_unless_told_where_to_search(ray):
    """Through the driver, with the passes (``posterior=False``; by default a simulated
    probe is searched by the posterior, which asks no replan): recorded as the objective's;
    off when the caller sets ``fine_radius`` or the passes; a far start on the ray model at
    30 dB searches without the 1° lattice out to 3° (30 measurements) and finds the echo."""
    _, pos, _ = ray
    noisy = setup_with_overrides("immersion-5mhz-ray", snr_db=30.0, seed=2)
    truth = np.array(noisy.true_optimum(pos, parameterization="tilt"))

    def run(**options):
        obj = SourceObjective(noisy, pos, parameterization="tilt", budget=60)
        return calibrate(obj, "auto", x0=truth + np.array([6.0, 4.0]), budget=60, rng=2, **options)

    default = run()
    assert default.posterior_search and default.search_passes is None
    assert np.hypot(*(np.asarray(default.x) - truth)) < 0.1
    res = run(posterior=False)
    assert res.options["replan"] == "objective" and not res.posterior_search
    # the result says what it searched: one pass sized for ~30 dB, then the 20 dB one
    assert (
        res.search_passes is not None and res.search_passes[-1] == dr.search_passes(noisy, pos)[-1]
    )
    # ... and the SNR it sized them for: the 30 dB setup's, from the first ring's σ
    # (7 A-scans; 8 % in σ is 0.7 dB)
    assert res.search_snr_db == pytest.approx(30.0, abs=1.0)
    back = CalibrationResult.from_dict(res.to_dict())
    assert back.search_passes == res.search_passes and back.search_snr_db == res.search_snr_db
    assert res.acquisition_measurements is not None and res.acquisition_measurements < 37
    assert np.hypot(*(np.asarray(res.x) - truth)) < 0.1
    kept = run(fine_radius=3.0, posterior=False)
    assert kept.options["replan"] is None and kept.search_passes is None
    assert kept.search_snr_db is None
    assert run(passes=[5.0]).options["replan"] is None
    analytic = FunctionObjective(lambda x: np.exp(-np.sum(x**2, axis=1)), budget=12)
    res = calibrate(analytic, "auto", x0=[0.5, 0.5], budget=12, rng=1)
    assert res.options["replan"] == "objective"  # asked, and it predicts nothing
    assert res.search_passes is None and res.search_snr_db is None
