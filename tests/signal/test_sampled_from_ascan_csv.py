"""A sampled pulse reads echocal's own A-scan CSV (``echocal simulate``'s ``ascan.csv``)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from echocal.cli.simulate import _save_ascan
from echocal.errors import DataFileError
from echocal.signal import SampledPulse


def test_a_sampled_pulse_reads_the_ascan_csv_that_simulate_writes(tmp_path):
    fs, t0 = 100e6, 60e-6
    times = t0 + np.arange(256) / fs
    samples = np.exp(-(((times - t0 - 1.28e-6) / 0.2e-6) ** 2)) * np.cos(
        2 * np.pi * 5e6 * (times - t0 - 1.28e-6)
    )
    path = tmp_path / "ascan.csv"  # a '# {summary}' line, a header, then the numbers
    _save_ascan(path, SimpleNamespace(times=times, samples=samples), {"setup": "x", "a": 1})
    assert path.read_text().splitlines()[1] == "time_s,amplitude"
    pulse = SampledPulse.from_file(path)
    assert pulse.fs == pytest.approx(fs, rel=1e-6)  # from the time column's step
    assert pulse.start_time == pytest.approx(t0, rel=1e-9)
    np.testing.assert_allclose(pulse.samples, samples, rtol=1e-8, atol=1e-9)  # 10 digits
    # a header in the middle is not a header: a file with text among its rows is refused
    path.write_text("time_s,amplitude\n0,1\nx,y\n0.2,3\n")
    with pytest.raises(DataFileError, match="is not a numeric .npy or CSV file"):
        SampledPulse.from_file(path)
