"""Unbounded inputs are bounded with one clear line (issue 15): a search radius of 1e9 deg
grew memory to 10 GB, ``seeds = 100000000`` hung ``sweep check``, ``--timeout 1e9`` was
accepted and ``--snr 1e308`` ended in an OverflowError traceback."""

from __future__ import annotations

import pytest

from cli_helpers import flat, run_main
from echocal.calibrate.acquisition import MAX_SEARCH_RADIUS, Acquisition
from echocal.errors import ConfigError, EchocalValueError
from echocal.experiments.sweep import MAX_SWEEP_RUNS, load_sweep
from echocal.measurement.hardware import MAX_TIMEOUT, TcpInstrument
from echocal.signal.noise import SNR_DB_RANGE, check_snr_db

CASES = [
    (["calibrate", "--search-radius", "1e9"], "--search-radius must be at most 180 deg"),
    (["calibrate", "--option", "max_radius=1e9"], "max_radius must be at most 180 deg"),
    (["calibrate", "--method", "gradient", "--search-radius", "1e9"], "at most 180 deg"),
    (
        [
            "calibrate",
            "--instrument",
            "127.0.0.1:9",
            "--setup",
            "thesis",
            "--position",
            "0,0,20",
            "--timeout",
            "1e9",
        ],
        "--timeout must be at most 600 s",
    ),
    (["calibrate", "--snr", "1e308"], "--snr must lie in [-100, 200] dB"),
    (["simulate", "--pose", "0,0,20", "--snr", "4000"], "--snr must lie in [-100, 200] dB"),
    (["simulate", "--pose", "0,0,20", "--snr", "-1e308"], "--snr must lie in [-100, 200] dB"),
]


@pytest.mark.parametrize(("args", "message"), CASES, ids=[" ".join(c[0][:3]) for c in CASES])
def test_a_huge_value_is_one_line_naming_the_option(args, message, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    code, stdout, err = run_main([*args, "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and stdout == "", err
    assert err.count("error:") == 1 and "Traceback" not in err and message in flat(err)
    assert not out.exists()  # refused before anything was written


def test_the_bounds_hold_in_the_python_api():
    with pytest.raises(EchocalValueError, match="max_radius must be at most 180"):
        Acquisition((0.0, 0.0), max_radius=1e9)
    Acquisition((0.0, 0.0), max_radius=MAX_SEARCH_RADIUS)  # the bound itself is allowed
    with pytest.raises(EchocalValueError, match="timeout must be at most 600"):
        TcpInstrument("127.0.0.1", 9, timeout=1e9)
    TcpInstrument("127.0.0.1", 9, timeout=MAX_TIMEOUT)
    for snr in (4000.0, 1e308, -1e308):
        with pytest.raises(EchocalValueError, match="snr_db must lie in"):
            check_snr_db("snr_db", snr)
    assert check_snr_db("snr_db", SNR_DB_RANGE[1]) == 200.0


@pytest.mark.parametrize("seeds", [100_000_000, MAX_SWEEP_RUNS + 1])
def test_a_sweep_of_a_hundred_million_seeds_is_refused_at_once(seeds):
    spec = {"name": "huge", "setup": "thesis", "seeds": seeds, "methods": [{"name": "spsa"}]}
    with pytest.raises(ConfigError, match=r"seeds: .* exceed the cap of 100,000 runs"):
        load_sweep(spec, check_runs=False)


def test_a_sweep_whose_grid_exceeds_the_cap_is_refused_before_expanding():
    from echocal.experiments import expand

    spec = {
        "name": "grid",
        "setup": "thesis",
        "seeds": 60_000,
        "snr_db": [10, 20],
        "methods": [{"name": "spsa"}],
    }
    with pytest.raises(ConfigError, match="120,000 runs exceed the cap"):
        expand(load_sweep(spec, check_runs=False))


@pytest.mark.parametrize("phase", ["1e308", "-361", "720"])
def test_a_pulse_phase_beyond_360_deg_is_refused(phase, tmp_path, capsys, monkeypatch):
    """The documented bound of angles (±360°) holds for the pulse's carrier phase too."""
    from cli_helpers import tiny_setup_toml
    from echocal.signal.pulses.analytic import GaborPulse

    text = tiny_setup_toml().replace(
        'center_frequency = "5 MHz"', f'center_frequency = "5 MHz"\nphase = {phase}'
    )
    path = tmp_path / "phase.toml"
    path.write_text(text, encoding="utf-8")
    code, out, err = run_main(["setup", "validate", str(path)], capsys, monkeypatch)
    assert code == 1 and "Traceback" not in err  # validate: 1 = the file has problems
    assert "pulse.phase: must lie in [-360, 360]" in flat(out + err)
    with pytest.raises(EchocalValueError, match=r"phase must lie in \[-360, 360\]"):
        GaborPulse(center_frequency=5e6, bandwidth=50.0, phase=float(phase))
    assert GaborPulse(center_frequency=5e6, bandwidth=50.0, phase=-360.0).phase == -360.0
