"""SourceObjective: a measurement source + a metric as a calibration objective."""

from __future__ import annotations

import numpy as np
import pytest

from echocal import MM, EchocalValueError, Pose
from echocal.ascan import AScan
from echocal.measurement import BaseSource, PositionerLimits
from echocal.measurement.objective import SourceObjective, default_bounds
from echocal.measurement.virtual import ReceiverSettings, VirtualSetup
from echocal.signal import RecordingWindow, make_pulse, pseudo_energy
from echocal.specimen import builtin_specimen
from echocal.transducer import Transducer

POSITION = [0.0, 0.0, 20 * MM]


@pytest.fixture(scope="module")
def sim():
    return VirtualSetup(
        specimen=builtin_specimen("tilted-plate"),
        transducer=Transducer(n_h=16, n_v=16),
        pulse=make_pulse("gabor", center_frequency=5e6),
        window=RecordingWindow(fs=100e6, start=20e-6, n_samples=2048),
        receiver=ReceiverSettings(snr_db=None),
        limits=PositionerLimits(coelevation=(-20.0, 20.0)),
        rng=0,
    )


def test_values_are_the_metric_of_the_measured_ascans(sim):
    objective = SourceObjective(sim, POSITION)
    values = objective(np.array([[30.0, 4.0], [0.0, 0.0]]))
    expected = pseudo_energy(
        sim.simulate([Pose(*POSITION, 30.0, 4.0), Pose(*POSITION, 0.0, 0.0)], noise=False),
        sim.window,
        sim.pulse,
    )
    np.testing.assert_allclose(values, expected, rtol=1e-12)
    assert objective.n_measurements == 2
    assert objective.log.points.shape == (2, 2)


def test_tilt_parameterization_measures_the_same_beam(sim):
    by_angles = SourceObjective(sim, POSITION)
    by_tilt = SourceObjective(sim, POSITION, parameterization="tilt")
    tilt = Pose(*POSITION, 30.0, 4.0).tilt
    # Same beam, frames differ only by a roll of the square aperture: energies agree to 2 %.
    assert by_tilt(np.array([tilt]))[0] == pytest.approx(by_angles([[30.0, 4.0]])[0], rel=0.02)


def test_default_bounds_follow_the_limits(sim):
    np.testing.assert_allclose(default_bounds(sim, "azimuth-coelevation"), [[-180, 180], [-20, 20]])
    half = default_bounds(sim, "tilt")[0, 1]
    assert default_bounds(sim, "tilt").tolist() == [[-half, half], [-half, half]]
    # The box's corner lies exactly on the 20° co-elevation cone (every tilt reachable).
    corner = Pose.from_tilt(*POSITION, half, half)
    assert corner.coelevation == pytest.approx(20.0, abs=1e-9)
    assert sim.limits.contains(corner.with_orientation(corner.azimuth, corner.coelevation - 1e-9))


class _NaNSource(BaseSource):
    description = "broken receiver"
    pulse = make_pulse("gabor")

    def measure(self, pose):
        return AScan(samples=np.full(64, np.nan), fs=100e6, pose=pose)


def test_nan_ascans_become_counted_nan_values():
    objective = SourceObjective(_NaNSource(), POSITION)
    values = objective([[0.0, 0.0]])
    assert np.isnan(values[0]) and objective.n_nan == 1 and objective.n_measurements == 1


def test_source_without_pulse_needs_one():
    class NoPulse(BaseSource):
        description = "rig"

    with pytest.raises(EchocalValueError, match="pulse is required"):
        SourceObjective(NoPulse(), POSITION)
    with pytest.raises(KeyError, match="pseudo-energy"):
        SourceObjective(_NaNSource(), POSITION, metric="loudness")


def test_ascan_freezes_a_copy_not_the_callers_array():
    # AScan is frozen: its samples are read-only, but the caller's buffer stays writable and
    # a later write to it does not change the A-scan.
    buffer = np.zeros(8)
    scan = AScan(samples=buffer, fs=1e6)
    buffer[0] = 1.0
    assert scan.samples[0] == 0.0 and not scan.samples.flags.writeable
    frozen = np.zeros(8)
    frozen.setflags(write=False)
    assert AScan(samples=frozen, fs=1e6).samples is frozen  # read-only input: kept, no copy


def test_detections_are_significant_at_the_echo(sim):
    import dataclasses

    noisy = dataclasses.replace(sim, receiver=ReceiverSettings(snr_db=20.0), rng=3)
    objective = SourceObjective(noisy, POSITION)
    # the plate's optimum (30°, 4°), then 15° away (this small probe's broad lobe still
    # returns an echo there; pure noise is tested in tests/signal/test_signal_detection.py)
    objective(np.array([[30.0, 4.0], [30.0, 19.0]]))
    g = objective.detections()
    assert g.shape == (2,)
    # at the optimum the matched-filter SNR at 20 dB is ≈ 10·√(samples in the pulse) ≫ 10
    assert g[0] > 10.0 and g[0] > g[1]
    noiseless = SourceObjective(sim, POSITION)
    noiseless(np.array([[30.0, 4.0]]))
    assert noiseless.detections()[0] > 1e6  # σ from round-off only: enormous (or inf)


def test_scan_noise_sigma_from_gaussian_and_from_coarsely_quantized_noise():
    from echocal.measurement.objective import scan_noise_sigma

    rng = np.random.default_rng(0)
    noise = rng.standard_normal(4096)
    echo = np.zeros(4096)
    echo[2000:2100] = 50.0 * np.sin(np.arange(100))
    # robust to the echo: 1.4826 MAD of 4096 samples has a ~2 % standard error; 6 % allowed
    sigma, coarse = scan_noise_sigma(2.0 * noise + echo)
    assert abs(sigma - 2.0) < 0.12 and not coarse
    # noise of 0.3 ADC steps: most samples on one level (MAD 0); the estimate is the RMS of
    # the quantized noise itself, within 10 % (sampling error ~3 % on ~10 % non-zero samples)
    step = 1.0
    quantized = np.round((0.3 * noise) / step) * step
    sigma, coarse = scan_noise_sigma(quantized + np.round(echo))
    assert coarse and abs(sigma - quantized.std()) < 0.1 * quantized.std()
    # a noiseless float trace (zeros and an echo) is not "quantized"; a constant says nothing
    assert scan_noise_sigma(echo)[1] is False
    assert scan_noise_sigma(np.zeros(64)) == (None, False)


def test_energy_in_db_takes_one_matched_filter_per_ascan(sim, monkeypatch):
    """The dB metric is the pseudo-energy's, so the envelope peak the detector needs comes
    from the same matched filter: the detector's own filter is not run again."""
    import echocal.signal.detection as detection
    from echocal.signal import energy_db

    calls = []
    original = detection.EchoDetector.peak

    def counting(self, samples):
        calls.append(1)
        return original(self, samples)

    monkeypatch.setattr(detection.EchoDetector, "peak", counting)
    poses = np.array([[30.0, 4.0], [0.0, 0.0]])
    in_db = SourceObjective(sim, POSITION, metric="energy-db")
    values = in_db(poses)
    assert calls == []  # both numbers from one matched filter
    expected = energy_db(
        sim.simulate([Pose(*POSITION, 30.0, 4.0), Pose(*POSITION, 0.0, 0.0)], noise=False),
        sim.window,
        sim.pulse,
    )
    np.testing.assert_allclose(values, expected, rtol=1e-12)
    plain = SourceObjective(sim, POSITION)
    plain(poses)
    np.testing.assert_allclose(in_db._peaks, plain._peaks, rtol=1e-12)
    SourceObjective(sim, POSITION, metric="peak-amplitude")(poses)
    assert len(calls) == 2  # the envelope's peak is not the matched filter's: one each
