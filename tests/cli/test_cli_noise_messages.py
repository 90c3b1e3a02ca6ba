"""Bad noise a user can give (a setup file's receiver gain, ``--snr``, a trace that
overflows, a scan file's missing position) is one line naming the file or the field and
the fix, never a bare "sigma must be finite" or "samples must be finite everywhere"."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import flat, run_main, tiny_setup_toml
from echocal.errors import EchocalValueError
from echocal.positionscan import ScanFacts, import_scan
from echocal.signal.noise import scan_noise_sigma


@pytest.mark.parametrize("gain_db", ["1e5", "-1e5", "121"])
def test_a_receiver_gain_beyond_its_range_names_the_file_and_the_field(
    gain_db, tmp_path: Path, capsys, monkeypatch
):
    """A gain of 1e5 dB overflowed every sample to inf, and ``simulate`` ended in
    "samples must be finite everywhere; got NaN or inf" while ``setup validate`` said
    the file was valid."""
    setup = tmp_path / "loud.toml"
    setup.write_text(
        tiny_setup_toml() + f'[bench.receiver]\ngain_curve = [["20 us", {gain_db}]]\n',
        encoding="utf-8",
    )
    out = tmp_path / "out"
    code, stdout, err = run_main(
        ["simulate", "--setup", str(setup), "--pose", "0,0,16", "--out", str(out)],
        capsys,
        monkeypatch,
    )
    said = flat(err)
    assert code == 2 and stdout == "" and "Traceback" not in err
    assert str(setup) in said
    assert "bench.receiver.gain_curve: gains must lie in [-120, 120] dB" in said
    assert not out.exists()
    code, stdout, _ = run_main(["setup", "validate", str(setup)], capsys, monkeypatch)
    assert code == 1 and "bench.receiver.gain_curve" in flat(stdout)


def test_a_gain_at_the_bound_is_allowed(tmp_path: Path, capsys, monkeypatch):
    setup = tmp_path / "quiet.toml"
    setup.write_text(
        tiny_setup_toml() + '[bench.receiver]\ngain_curve = [["20 us", -120], ["25 us", 120]]\n',
        encoding="utf-8",
    )
    code, stdout, err = run_main(["setup", "validate", str(setup)], capsys, monkeypatch)
    assert code == 0, stdout + err


@pytest.mark.parametrize("snr", ["nan", "-inf"])
def test_a_non_finite_snr_says_what_is_allowed(snr, tmp_path: Path, capsys, monkeypatch):
    out = tmp_path / "out"
    code, _, err = run_main(
        ["simulate", "--pose", "0,0,20", "--snr", snr, "--out", str(out)], capsys, monkeypatch
    )
    assert code == 2 and err.count("error:") == 1
    assert "--snr must be finite, a number of dB in [-100, 200]" in flat(err)
    assert "give 'none'" in flat(err)


def test_a_trace_whose_levels_overflow_has_no_noise_level():
    """Most samples at one level (the MAD is 0) and the rest 1e200 above: the RMS of the
    quantized noise overflowed to an infinite σ, which a detector then refused with
    "sigma must be finite"."""
    trace = np.zeros(256)
    trace[::4] = 1e200
    assert scan_noise_sigma(trace) == (None, False)
    quantized = np.round(np.random.default_rng(0).normal(scale=0.3, size=256))
    sigma, coarse = scan_noise_sigma(quantized)  # a real quantized trace still measures
    assert coarse and 0.1 < sigma < 1.0


def test_a_scan_file_with_a_missing_position_names_the_file_and_the_position(tmp_path: Path):
    src = tmp_path / "raster.npz"
    x = np.array([0.0, 1e-3, np.nan, 3e-3])
    np.savez(src, ascans=np.zeros((4, 32)), x=x)
    with pytest.raises(EchocalValueError, match=r"raster.npz: x position 3 of 4 is nan"):
        import_scan(src, ScanFacts(sampling_rate=50e6, layout="rows"))
