"""The bench's receiver: coloured noise and its detector, grain noise that does not average
away, the water's temperature, the gain curve."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _bench_setups import bench_setup
from scipy.special import ndtr

from echocal.bench import ar_noise, water_sound_speed
from echocal.geometry import Pose
from echocal.measurement import ReceiverSettings, SourceObjective
from echocal.setups import load_setup
from echocal.setups.bench_schema import BenchConfig, build_bench
from echocal.signal import make_pulse
from echocal.signal.detection import EchoDetector
from echocal.signal.processing import pseudo_energy


def test_ar_noise_has_unit_variance_and_the_ar1_autocorrelation():
    n = ar_noise((400, 2048), (0.8,), np.random.default_rng(3))
    # AR(1): ρ(k) = a^k; 819,200 samples, correlated over ~10: σ² within 2 %
    np.testing.assert_allclose(n.var(), 1.0, rtol=0.02)
    lag1 = np.mean(n[:, 1:] * n[:, :-1]) / n.var()
    np.testing.assert_allclose(lag1, 0.8, atol=0.01)
    lag3 = np.mean(n[:, 3:] * n[:, :-3]) / n.var()
    np.testing.assert_allclose(lag3, 0.8**3, atol=0.015)


@pytest.mark.parametrize("ar", [(0.9,), (1.2, -0.5)])
def test_the_detector_keeps_its_false_alarm_rate_under_coloured_noise(ar):
    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
    fs, n = 50e6, 512
    coloured = EchoDetector(pulse, fs, n, noise_ar=ar)
    noise = ar_noise((10000, n), ar, np.random.default_rng(7)) * 2.5  # σ = 2.5 per sample
    g = coloured.significance(noise, 2.5)
    # design: P(g > t) = 1 − Φ(t); over 10,000 A-scans the rate at t = 2 (2.3 %) is known
    # to ±0.15 % (1 σ): within 0.6 % absolute (4 σ) of the design
    for t in (1.0, 2.0):
        np.testing.assert_allclose(np.mean(g > t), 1.0 - ndtr(t), atol=0.006 if t == 2 else 0.02)
    # the white-noise detector on the same noise is off its design (why the colour matters)
    white = EchoDetector(pulse, fs, n).significance(noise, 2.5)
    assert abs(np.mean(white > 2.0) - (1.0 - ndtr(2.0))) > 0.02


GRAIN = """
[bench.grain]
level_db = -12
depth = "1.5 mm"
width = "10 mm"
scatterers = 300
"""


def test_grain_noise_does_not_average_away_but_white_noise_does(tmp_path):
    noisy, _ = bench_setup(tmp_path, GRAIN, noise="snr_db = 20")
    clean, _ = bench_setup(tmp_path, GRAIN, noise="snr_db = 'none'")
    plain, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    x, y, z = noisy.reference_position
    pose = Pose.from_tilt(x, y, z, 1.0, 0.5)
    echo = plain.measure(pose).samples
    grain = clean.measure(pose).samples - echo  # the grain signal at this pose
    assert np.sqrt(np.mean(grain**2)) > 0.0
    # a fixed pose sees the same grains every time, and another pose other ones
    np.testing.assert_array_equal(clean.measure(pose).samples - echo, grain)
    other = Pose.from_tilt(x + 0.002, y, z, 1.0, 0.5)
    assert not np.allclose(clean.measure(other).samples - plain.measure(other).samples, grain)
    # mean of N repeated A-scans minus the echo: the grain stays, the noise falls as 1/√N
    sigma = noisy.noise_sigma
    for count in (16, 256):
        mean = np.mean([s.samples for s in noisy.measure_many([pose] * count)], axis=0) - echo
        residual = mean - grain
        # the residual's RMS is σ/√N to within 15 % (256 samples per A-scan)
        np.testing.assert_allclose(np.sqrt(np.mean(residual**2)), sigma / np.sqrt(count), rtol=0.15)
        np.testing.assert_allclose(mean, grain, atol=6 * sigma / np.sqrt(count))
    assert np.max(np.abs(grain)) > 10 * sigma / np.sqrt(256)  # it did not average away


def test_water_temperature_gives_the_published_speed():
    # Del Grosso & Mader (1972), J. Acoust. Soc. Am. 52, 1442: 1482.343 m/s at 20 °C;
    # Marczak (1997) agrees within 0.02 m/s; the tolerance is 0.05 m/s
    np.testing.assert_allclose(water_sound_speed(20.0), 1482.343, atol=0.05)
    # 0 °C: 1402.39 m/s (Del Grosso & Mader 1972)
    np.testing.assert_allclose(water_sound_speed(0.0), 1402.39, atol=0.05)


def test_a_drifting_temperature_delays_the_echo_as_the_sound_speed_says(tmp_path):
    # 36 °C/h = 0.01 °C/s; each A-scan costs 100 s: the water warms 1 °C per A-scan
    drift = """
[bench.positioner]
acquisition_time = "100 s"
[bench.receiver]
temperature_drift = 36
"""
    setup, _ = bench_setup(
        tmp_path, drift + "[medium]\ntemperature = 20\n", noise="snr_db = 'none'"
    )
    x, y, z = setup.reference_position
    first, second = setup.measure_many([Pose.from_tilt(x, y, z, 0, 0)] * 2)
    assert second.metadata["bench_clock"] == pytest.approx(200.0)
    # the echo's time of flight scales by c(T₀)/c(T): warmer water is faster, the echo earlier.
    # c from Marczak (1997)'s polynomial written out here: T₀ = 20 °C at t = 0, so the first
    # A-scan (at 100 s) is at 21 °C, the second at 22 °C
    coefficients = [1402.385, 5.038813, -5.799136e-2, 3.287156e-4, -1.398845e-6, 2.787860e-9]

    def speed(t):
        return sum(c * t**i for i, c in enumerate(coefficients))

    times = first.times
    peak_first = times[np.argmax(np.abs(first.samples))]
    peak_second = times[np.argmax(np.abs(second.samples))]
    expected = 2 * z / setup.sound_speed  # the echo at T₀ (the plate at z = 0 below)
    # argmax is good to a sample (20 ns at 50 MHz); the shift per °C is ~2 ns × 21.6 us/1 us
    shift = expected * (speed(20) / speed(22) - speed(20) / speed(21))
    assert shift < 0
    weights = np.abs(first.samples) ** 2, np.abs(second.samples) ** 2
    centre = [np.sum(w * times) / np.sum(w) for w in weights]
    np.testing.assert_allclose(centre[1] - centre[0], shift, rtol=0.02)
    assert peak_second <= peak_first


def test_the_gain_curve_multiplies_the_scan_by_its_interpolated_gain(tmp_path):
    setup, _ = bench_setup(
        tmp_path,
        '[bench.receiver]\ngain_curve = [["20 us", 0], ["25 us", 12]]\n',
        noise="snr_db = 'none'",
    )
    plain, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    x, y, z = setup.reference_position
    pose = Pose.from_tilt(x, y, z, 0.5, 0)
    scan, reference = setup.measure(pose), plain.measure(pose)
    t_us = scan.times * 1e6
    gain = 10 ** (np.clip((t_us - 20) / 5, 0, 1) * 12 / 20)
    np.testing.assert_allclose(scan.samples, reference.samples * gain, rtol=1e-12, atol=1e-300)


def test_jitter_delays_each_scan_by_a_normal_time_of_its_sigma(tmp_path):
    setup, _ = bench_setup(tmp_path, '[bench.receiver]\njitter = "2 ns"\n', noise="snr_db = 'none'")
    x, y, z = setup.reference_position
    scans = setup.measure_many([Pose.from_tilt(x, y, z, 0.0, 0.0)] * 400)
    times = scans[0].times
    power = np.array([s.samples for s in scans]) ** 2
    centroid = power @ times / power.sum(axis=1)
    # 400 draws: the sample σ within 10 % (3.5 σ of its own scatter, 1/√800 ≈ 3.5 %)
    np.testing.assert_allclose(np.std(centroid), 2e-9, rtol=0.1)
    # centred on the unjittered echo: the mean of 400 draws within 4 × 2 ns / √400
    plain, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    still = plain.measure(Pose.from_tilt(x, y, z, 0.0, 0.0)).samples ** 2
    np.testing.assert_allclose(np.mean(centroid), still @ times / still.sum(), atol=0.4e-9)


def test_the_noise_floor_of_the_metric_is_that_of_the_receivers_colour():
    """The pseudo-energy of pure noise (the floor a local model subtracts and an echo must
    clear) against AR(1) noise of coefficient 0.6 written out here: the objective's live
    estimate draws noise of the bench's colour, not white noise of the same σ (the 5 MHz
    probe at 100 MHz sampling, where the colour puts 2.9 times the power into its band)."""
    setup = load_setup("immersion-5mhz-ray", seed=3)
    bench = build_bench(BenchConfig.model_validate({"receiver": {"noise_ar": [0.6]}}), None)
    setup = dataclasses.replace(setup, bench=bench, receiver=ReceiverSettings(snr_db=20.0))
    objective = SourceObjective(setup, setup.reference_position, parameterization="tilt")
    objective(np.array([[3.0, 2.0], [-2.0, 4.0], [1.0, -3.0]]))
    floor, spread = objective.noise_estimate()
    sigma = objective._receiver_sigma()  # the per-sample σ it measured
    # the truth: 2,000 A-scans of n[k] = 0.6 n[k-1] + e[k], started stationary and scaled
    # to σ per sample, and of white noise of the same σ, through the same metric
    window, count, a = setup.window, 2000, 0.6
    rng = np.random.default_rng(11)
    e = rng.standard_normal((count, window.n_samples))
    ar = np.empty_like(e)
    ar[:, 0] = e[:, 0] / np.sqrt(1.0 - a * a)
    for k in range(1, window.n_samples):
        ar[:, k] = a * ar[:, k - 1] + e[:, k]
    ar *= np.sqrt(1.0 - a * a) * sigma
    coloured = pseudo_energy(ar, window, setup.pulse)
    white = pseudo_energy(rng.standard_normal(ar.shape) * sigma, window, setup.pulse)
    # the estimate's 64 A-scans: the mean to ~2 % (1 σ), the spread to ~9 %: 3 σ each;
    # white noise of the same σ is off by more than that (−14 % and −31 %)
    np.testing.assert_allclose(floor, coloured.mean(), rtol=0.06)
    np.testing.assert_allclose(spread, coloured.std(), rtol=0.27)
    assert white.mean() < 0.9 * coloured.mean()
    assert white.std() < 0.73 * coloured.std()
