"""ReplaySource: file format, the three modes, tolerances, and bad files."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from fake_sources import GaussianEchoSource

from echocal.errors import DataFileError, LimitError, UnknownNameError
from echocal.geometry import Pose
from echocal.measurement.recording import RecordingGrid, record, recording_dataset
from echocal.measurement.replay import ReplaySource
from echocal.netcdf import ENCODING

# azimuth step 10 deg, co-elevation step 5 deg; positions 4 mm apart
GRID = RecordingGrid.regular(
    azimuth=(0.0, 40.0, 5), coelevation=(-10.0, 10.0, 5), positions=[(0, 0, 0.02), (0.004, 0, 0.02)]
)
REPEATS = 3


@pytest.fixture(scope="module")
def clean_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("replay") / "clean.nc"
    return record(GaussianEchoSource(), GRID, path, repeats=REPEATS, progress=False)


@pytest.fixture(scope="module")
def noisy_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("replay") / "noisy.nc"
    fake = GaussianEchoSource(noise_std=0.05, seed=2)
    return record(fake, GRID, path, repeats=REPEATS, progress=False, setup={"name": "fake"})


def test_file_layout_units_and_attributes(noisy_file: Path) -> None:
    with xr.open_dataset(noisy_file, engine="h5netcdf") as ds:
        assert ds["samples"].dims == ("position", "azimuth", "coelevation", "repeat", "time")
        assert ds["samples"].shape == (2, 5, 5, REPEATS, 256)
        assert ds.attrs["echocal_format"] == "replay/2"
        assert ds.attrs["Conventions"] == "CF-1.10"
        assert ds.attrs["sampling_rate_hz"] == 50e6
        assert ds.attrs["start_time_s"] == 20e-6
        units = {n: ds[n].attrs["units"] for n in ("azimuth", "coelevation", "time", "position_x")}
        assert units == {
            "azimuth": "degree",
            "coelevation": "degree",
            "time": "s",
            "position_x": "m",
        }
        np.testing.assert_allclose(np.diff(ds["time"].values), 1 / 50e6, rtol=1e-9)
        source = json.loads(ds.attrs["source_info"])
        assert source["setup"] == {"name": "fake"}
        assert "gaussian echo fake" in source["description"]
        assert RecordingGrid.from_dict(json.loads(ds.attrs["grid"])) == GRID


def test_nearest_returns_the_recording_at_the_nearest_grid_pose(clean_file: Path) -> None:
    fake = GaussianEchoSource()
    with ReplaySource.open(clean_file) as replay:
        # 13 deg -> 10 (nearest), 3.0 -> 5, position 0.1 mm off -> (0, 0, 0.02)
        scan = replay.measure(Pose(0.0001, 0.0, 0.02, 13.0, 3.0))
        grid_pose = Pose(0.0, 0.0, 0.02, 10.0, 5.0)
        assert scan.pose == grid_pose
        np.testing.assert_array_equal(scan.samples, fake.clean_samples(grid_pose))
        assert (scan.fs, scan.start_time) == (50e6, 20e-6)
        assert replay.measure(Pose(0.004, 0.0, 0.02, 40.0, -10.0)).metadata["grid_index"] == (
            1,
            4,
            0,
        )


def test_limits_are_the_grid_extent(clean_file: Path) -> None:
    with ReplaySource.open(clean_file) as replay:
        limits = replay.limits
    assert (limits.azimuth, limits.coelevation) == ((0.0, 40.0), (-10.0, 10.0))
    assert (limits.x, limits.y, limits.z) == ((0.0, 0.004), (0.0, 0.0), (0.02, 0.02))


def test_tolerance_is_half_a_step_beyond_the_grid(clean_file: Path) -> None:
    with ReplaySource.open(clean_file) as replay:
        assert replay.measure(Pose(0, 0, 0.02, 44.9, 12.4)).pose == Pose(0, 0, 0.02, 40.0, 10.0)
        with pytest.raises(LimitError, match="azimuth=45.1"):
            replay.measure(Pose(0, 0, 0.02, 45.1, 0.0))
        with pytest.raises(LimitError, match="coelevation=-12.6"):
            replay.measure(Pose(0, 0, 0.02, 0.0, -12.6))
        # positions: default tolerance is half the 4 mm spacing
        assert replay.position_tolerance == pytest.approx(0.002)
        with pytest.raises(LimitError, match="nearest recorded position"):
            replay.measure(Pose(0.0, 0.0021, 0.02, 0.0, 0.0))


def test_azimuth_is_also_tried_modulo_360(clean_file: Path) -> None:
    with ReplaySource.open(clean_file) as replay:
        assert replay.measure(Pose(0, 0, 0.02, 378.0, 0.0)).pose.azimuth == 20.0
        assert replay.measure(Pose(0, 0, 0.02, -356.0, 0.0)).pose.azimuth == 0.0


def test_random_repeat_is_seeded_and_covers_all_repeats(noisy_file: Path) -> None:
    pose = Pose(0, 0, 0.02, 20.0, 5.0)
    with ReplaySource.open(noisy_file, mode="random-repeat", rng=4) as a:
        draws_a = [a.measure(pose) for _ in range(30)]
    with ReplaySource.open(noisy_file, mode="random-repeat", rng=4) as b:
        draws_b = [b.measure(pose) for _ in range(30)]
    assert [d.metadata["repeat"] for d in draws_a] == [d.metadata["repeat"] for d in draws_b]
    counts = Counter(d.metadata["repeat"] for d in draws_a)
    # P(some repeat never drawn in 30 uniform draws of 3) = 3 (2/3)^30 < 2e-5
    assert set(counts) == {0, 1, 2}
    with xr.open_dataset(noisy_file, engine="h5netcdf") as ds:
        for d in draws_a[:5]:
            recorded = ds["samples"].values[0, 2, 3, d.metadata["repeat"]]
            np.testing.assert_array_equal(d.samples, recorded)


def test_interpolate_at_grid_points_and_midpoints(noisy_file: Path) -> None:
    with xr.open_dataset(noisy_file, engine="h5netcdf") as ds:
        recorded = ds["samples"].values[0]  # (azimuth, coelevation, repeat, time)
    mean = recorded.mean(axis=2)
    n = REPEATS
    with ReplaySource.open(noisy_file, mode="interpolate", rng=1) as replay:
        # at a grid pose the weights are (1, 0, 0, 0): the drawn recorded A-scan itself
        on_grid = replay.measure(Pose(0, 0, 0.02, 20.0, 5.0))
        r = on_grid.metadata["repeat"]
        np.testing.assert_allclose(on_grid.samples, recorded[2, 3, r], rtol=0, atol=1e-14)
        # midway in azimuth (weights 1/2, 1/2): the average of the two neighbours' means
        # plus the drawn repeat's deviation at the first (the nearest on a tie), scaled by
        # sqrt((n - 1/2) / (n - 1))
        mid = replay.measure(Pose(0, 0, 0.02, 25.0, 5.0))
        r = mid.metadata["repeat"]
        noise = np.sqrt((n - 0.5) / (n - 1)) * (recorded[2, 3, r] - mean[2, 3])
        expected = 0.5 * (mean[2, 3] + mean[3, 3]) + noise
        np.testing.assert_allclose(mid.samples, expected, atol=1e-14)
        # cell centre (weights 1/4): the average of the four corners' means plus noise
        centre = replay.measure(Pose(0, 0, 0.02, 25.0, 7.5))
        r = centre.metadata["repeat"]
        corners = mean[2, 3] + mean[3, 3] + mean[2, 4] + mean[3, 4]
        noise = np.sqrt((n - 0.25) / (n - 1)) * (recorded[2, 3, r] - mean[2, 3])
        np.testing.assert_allclose(centre.samples, corners / 4 + noise, atol=1e-14)
        assert centre.pose == Pose(0, 0, 0.02, 25.0, 7.5)
        with pytest.raises(LimitError, match="azimuth=40.5"):
            replay.measure(Pose(0, 0, 0.02, 40.5, 0.0))  # no extrapolation


@pytest.mark.parametrize(
    ("azimuth", "coelevation"), [(20.0, 5.0), (25.0, 5.0), (25.0, 7.5), (22.5, 6.25)]
)
def test_interpolate_replays_the_recorded_noise_at_every_pose(
    tmp_path: Path, azimuth: float, coelevation: float
) -> None:
    """The replayed noise has the recorded A-scans' variance wherever the pose lies in a
    cell, and a re-measurement draws again.  The truth is the fake's own noise σ and its
    noiseless A-scans (bilinear over the 4 corners, computed here).  Averaging the repeats
    and blending them alone would give σ²·Σw²/n: σ²/16 at a cell's centre with n = 4."""
    sigma, n = 0.05, 4
    grid = RecordingGrid.regular(
        azimuth=(20.0, 30.0, 3), coelevation=(5.0, 10.0, 3), positions=[(0, 0, 0.02)]
    )
    fake = GaussianEchoSource(noise_std=sigma, seed=5)
    path = record(fake, grid, tmp_path / "r.nc", repeats=n, progress=False)
    u, v = (azimuth - 20.0) / 5.0, (coelevation - 5.0) / 2.5  # inside the first cell
    weights = [(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v]
    corners = [(20.0, 5.0), (25.0, 5.0), (20.0, 7.5), (25.0, 7.5)]
    clean = sum(
        w * fake.clean_samples(Pose(0, 0, 0.02, a, c))
        for w, (a, c) in zip(weights, corners, strict=True)
    )
    with ReplaySource.open(path, mode="interpolate", rng=7) as replay:
        scans = [replay.measure(Pose(0, 0, 0.02, azimuth, coelevation)) for _ in range(40)]
    noise = np.array([s.samples - clean for s in scans])  # (40, 256)
    # 40 draws of 4 recorded deviations plus one fixed blend of 4 x 4 recorded noises, over
    # 256 samples: the variance estimate's relative standard error is below 10 %; ±25 %
    assert np.mean(noise**2) == pytest.approx(sigma**2, rel=0.25)
    # a re-measurement draws again: 4 different A-scans (P(a repeat never drawn) < 1e-4)
    assert len({s.samples.tobytes() for s in scans}) == n


def test_interpolated_metric_reproduces_bilinear_functions(clean_file: Path) -> None:
    # a metric that is bilinear in the grid angles is reproduced exactly by bilinear
    # interpolation (to round-off) — the independent truth here
    def metric(scan) -> float:
        return (
            2.0 * scan.pose.azimuth
            - 3.0 * scan.pose.coelevation
            + 0.1 * scan.pose.azimuth * (scan.pose.coelevation)
        )

    with ReplaySource.open(clean_file, mode="nearest") as replay:
        for az, coel in [(3.0, -7.0), (17.5, 2.5), (40.0, 10.0), (0.0, -10.0)]:
            got = replay.interpolated_metric(Pose(0, 0, 0.02, az, coel), metric)
            assert got == pytest.approx(2 * az - 3 * coel + 0.1 * az * coel, abs=1e-12)
        assert replay.metric_grid(metric).shape == (5, 5)


def test_interpolated_energy_peaks_near_the_true_normal(clean_file: Path) -> None:
    # the fake's optimum is at (30, 4) deg; on a 10 x 5 deg grid the best grid point is (30, 5)
    def energy(scan) -> float:
        return float(np.sum(scan.samples**2))

    with ReplaySource.open(clean_file) as replay:
        grid = replay.metric_grid(energy)
        assert np.unravel_index(np.argmax(grid), grid.shape) == (3, 3)


def _great_circle(az0, co0, az1, co1) -> np.ndarray:
    """[deg] the angle between the beams (az0, co0) and (az1, co1) (spherical law of
    cosines, written here independently of echocal.geometry)."""
    a0, c0, a1, c1 = np.deg2rad([az0, co0, az1, co1])
    cos = np.cos(c0) * np.cos(c1) + np.sin(c0) * np.sin(c1) * np.cos(a1 - a0)
    return np.rad2deg(np.arccos(np.clip(cos, -1.0, 1.0)))


def test_grid_step_is_the_largest_step_between_neighbouring_beams(clean_file: Path) -> None:
    """In (azimuth, co-elevation) the step is the larger axis step (10°); in tilt angles
    — a gimbal's, close to the angle between beams — the largest angle between
    neighbouring recorded beams: the 5° co-elevation step (an azimuth step of 10° at
    |co-elevation| ≤ 10° is ≤ 1.74° apart).  2 % covers the tilt angles' departure from
    arc length within 10° of the axis."""
    with ReplaySource.open(clean_file) as replay:
        assert replay.grid_step("azimuth-coelevation") == 10.0
        az, co = np.meshgrid(replay.azimuths, replay.coelevations, indexing="ij")
        along_az = _great_circle(az[:-1], co[:-1], az[1:], co[1:])
        along_co = _great_circle(az[:, :-1], co[:, :-1], az[:, 1:], co[:, 1:])
        widest = max(along_az.max(), along_co.max())
        assert widest == pytest.approx(5.0)
        assert replay.grid_step("tilt") == pytest.approx(widest, rel=0.02)
        with pytest.raises(UnknownNameError, match="parameterization"):
            replay.grid_step("polar")


def test_a_single_orientation_has_no_grid_step(tmp_path: Path) -> None:
    grid = RecordingGrid.regular(
        azimuth=(0.0, 0.0, 1), coelevation=(5.0, 5.0, 1), positions=[(0, 0, 0.02)]
    )
    path = record(GaussianEchoSource(), grid, tmp_path / "one.nc", progress=False)
    with ReplaySource.open(path) as replay:
        assert replay.grid_step("tilt") is None


def test_closed_source_refuses(clean_file: Path) -> None:
    replay = ReplaySource.open(clean_file)
    replay.close()
    with pytest.raises(DataFileError, match="closed"):
        replay.measure(Pose(0, 0, 0.02, 0.0, 0.0))


def test_unknown_mode_lists_the_modes(clean_file: Path) -> None:
    with pytest.raises(UnknownNameError, match="interpolate, nearest, random-repeat"):
        ReplaySource.open(clean_file, mode="cubic")


# -- bad files ---------------------------------------------------------------------------------
def _write(ds: xr.Dataset, path: Path) -> Path:
    """Write ``ds`` as it is (no schema attributes added), with checksums."""
    encoding = {n: ENCODING for n, v in ds.variables.items() if v.dtype.kind in "if" and v.ndim}
    ds.to_netcdf(path, engine="h5netcdf", encoding=encoding)
    return path


def _good_dataset() -> xr.Dataset:
    samples = np.zeros((1, 2, 2, 1, 8))
    grid = RecordingGrid(azimuth=(0.0, 10.0), coelevation=(0.0, 5.0), positions=((0, 0, 0.02),))
    return recording_dataset(samples, grid, fs=1e6, start_time=0.0, source_info={"d": 1})


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(DataFileError, match=r"not found: .*nope\.nc"):
        ReplaySource.open(tmp_path / "nope.nc")


@pytest.mark.foreign_netcdf
def test_unreadable_file(tmp_path: Path) -> None:
    path = tmp_path / "text.nc"
    path.write_text("this is not HDF5")
    with pytest.raises(DataFileError, match=r"cannot read replay file .*text\.nc"):
        ReplaySource.open(path)


@pytest.mark.foreign_netcdf
def test_good_handmade_file_opens(tmp_path: Path) -> None:
    with ReplaySource.open(_write(_good_dataset(), tmp_path / "ok.nc")) as replay:
        assert replay.measure(Pose(0, 0, 0.02, 10.0, 5.0)).n_samples == 8


@pytest.mark.foreign_netcdf
@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda ds: ds.drop_attrs(deep=False), "not an echocal replay recording.*echocal_format"),
        (lambda ds: ds.assign_attrs(echocal_format="replay/9"), "unsupported echocal_format"),
        (lambda ds: ds.drop_vars("samples"), "variable 'samples' is missing"),
        (lambda ds: ds.drop_vars("coelevation"), "coordinate 'coelevation' is missing"),
        (lambda ds: _drop_units(ds, "azimuth"), "'azimuth' has no 'units' attribute"),
        (lambda ds: _set_units(ds, "azimuth", "rad"), "'azimuth' must be in 'degree'; got 'rad'"),
        (lambda ds: _set_units(ds, "position_z", "mm"), "'position_z' must be in 'm'"),
        (lambda ds: _drop_attr(ds, "sampling_rate_hz"), "attribute 'sampling_rate_hz' is missing"),
        (lambda ds: ds.assign_attrs(sampling_rate_hz=-1.0), "'sampling_rate_hz' must be > 0"),
        (lambda ds: ds.transpose("time", ...), "must have dims"),
    ],
)
def test_mislabelled_files_name_file_and_item(tmp_path: Path, mutate, message: str) -> None:
    path = _write(mutate(_good_dataset()), tmp_path / "bad.nc")
    with pytest.raises(DataFileError, match=message) as info:
        ReplaySource.open(path)
    assert "bad.nc" in str(info.value)


def _drop_units(ds: xr.Dataset, name: str) -> xr.Dataset:
    ds[name].attrs.pop("units")
    return ds


def _set_units(ds: xr.Dataset, name: str, unit: str) -> xr.Dataset:
    ds[name].attrs["units"] = unit
    return ds


def _drop_attr(ds: xr.Dataset, name: str) -> xr.Dataset:
    ds.attrs.pop(name)
    return ds


def test_auto_on_an_interpolated_replay_reaches_a_tenth_of_a_degree(tmp_path: Path) -> None:
    """``auto`` on a replay (``interpolate``, 4 repeats) of a small recorded grid lands
    within 0.1° of the fake's analytic optimum, which lies off the grid's nodes (30.4°,
    4.05°): the replay answers between nodes, with the recorded noise."""
    from echocal.calibrate import calibrate
    from echocal.geometry import convert_angles
    from echocal.measurement import SourceObjective
    from echocal.signal import make_pulse

    position = (0.0, 0.0, 0.016)  # the echo at 2 z / c = 21.6 µs, inside the 20–25 µs window
    fake = GaussianEchoSource(true_azimuth=30.4, true_coelevation=4.05, noise_std=0.01, seed=3)
    grid = RecordingGrid.regular(
        azimuth=(0.0, 60.0, 31), coelevation=(2.0, 6.0, 41), positions=[position]
    )
    path = record(fake, grid, tmp_path / "small.nc", repeats=4, progress=False)
    truth = np.array(convert_angles(30.4, 4.05, "azimuth-coelevation", "tilt"))
    bounds = np.array([truth - 1.2, truth + 1.2]).T  # inside the grid (co-elevation 2.5–5.6°)
    pulse = make_pulse("gabor", center_frequency=5e6, bandwidth=60)
    with ReplaySource.open(path, mode="interpolate", rng=0) as replay:
        objective = SourceObjective(
            replay, position, parameterization="tilt", pulse=pulse, bounds=bounds, budget=40
        )
        result = calibrate(
            objective, method="auto", x0=truth + np.array([0.9, -0.6]), budget=40, rng=0
        )
    assert float(np.hypot(*(result.x - truth))) < 0.1
