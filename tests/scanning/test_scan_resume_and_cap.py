"""Scans (issue 15, items 7 and 9): a resumed scan measures the same numbers as an
uninterrupted one, and ``budget_per_point`` caps every point, second look included."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from echocal.scanning import ScanGrid, scan_surface
from echocal.setups import load_setup
from echocal.specimen import builtin_specimen

MM = 1e-3
VARIABLES = ("tilt_x", "tilt_y", "tof", "echo_snr", "n_measurements", "status", "warm")


def _setup(specimen: str, seed: int = 2):
    setup = load_setup("scan-5mhz", seed=seed)
    return dataclasses.replace(setup, specimen=builtin_specimen(specimen), rng=seed)


@pytest.mark.slow
def test_a_resumed_scan_equals_an_uninterrupted_one(tmp_path):
    grid = ScanGrid.regular(x=(-4 * MM, 4 * MM, 8 * MM), y=(0.0, 2 * MM, 2 * MM), z=25 * MM)
    whole = scan_surface(_setup("cylinder"), grid, rng=1, progress=False).dataset

    def stop_after_three(done, total):
        if done == 2:
            raise KeyboardInterrupt

    out = tmp_path / "scan.nc"
    with pytest.raises(KeyboardInterrupt):
        scan_surface(
            _setup("cylinder"), grid, rng=1, progress=False, out=out, on_point=stop_after_three
        )
    # a new process: the same setup, its noise stream from the start
    resumed = scan_surface(_setup("cylinder"), grid, rng=1, progress=False, out=out).dataset
    assert resumed.attrs["resumed_points"] == 2
    for name in VARIABLES:
        np.testing.assert_array_equal(resumed[name].values, whole[name].values, err_msg=name)


@pytest.mark.slow
def test_budget_per_point_caps_the_second_look_too():
    # a wavy part: side lobes and outliers that get a second look; before, the two
    # attempts were added up (10 of these 25 points used 31-58 measurements)
    grid = ScanGrid.regular(x=(-8 * MM, 8 * MM, 4 * MM), y=(-8 * MM, 8 * MM, 4 * MM), z=25 * MM)
    scan = scan_surface(_setup("wavy-surface"), grid, rng=3, progress=False, budget_per_point=30)
    used = scan.dataset["n_measurements"].values
    assert used.max() <= 30, used
