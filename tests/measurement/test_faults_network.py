"""Fault injection on the wire (issue 15, "Must show"): a TCP proxy on 127.0.0.1 between
``echocal calibrate --instrument`` and the emulated rig drops, delays, garbles or truncates
one reply.  Every run either survives (the client retries a transport fault and finishes
with the same number of logged measurements) or stops cleanly (one error line, exit 2,
every measurement made before the fault saved in partial_log.json) — never a silently
wrong A-scan, never a traceback.

Also the rig's network safety: a token handshake, and no listening beyond loopback
without --allow-remote.
"""

from __future__ import annotations

import json
import socket

import numpy as np
import pytest
from typer.testing import CliRunner

from cli_helpers import flat, run_main, tiny_setup_toml
from echocal.cli import app
from echocal.errors import InstrumentError
from echocal.geometry import Pose
from echocal.measurement import HardwareSource, InstrumentServer
from echocal.setups import load_setup
from fault_proxy import FaultProxy

# reply lines: *IDN? (1), LIMITS? (2), then per measured pose MOVE -> OK, POS? -> pose,
# ACQ? -> header + payload: the payload of the j-th A-scan is line 2 + 4 j
PAYLOAD_OF_THIRD = 2 + 4 * 3
TIMEOUT = "2"
RIG = ["--position", "0,0,16", "--x0", "2,-1", "--seed", "3", "--no-plots", "--json"]
RUN = [*RIG, "--method", "model-based", "--budget", "14", "--settle", "none"]

FINISHED = (0, 3)
"""Exit codes of a calibration that ran to its end (3: the budget ran out before the
convergence rule fired — a finished run that claims no convergence)."""

OUTCOME = {"drop": "survives", "delay": "survives", "truncate": "survives", "garble": "stops"}
"""What each fault must lead to: a transport fault is retried (the run survives); a garbled
A-scan fails its checksum and the run stops cleanly (nothing in it is trusted)."""


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("rig") / "tiny.toml"
    path.write_text(tiny_setup_toml())
    return path


def _calibrate(address, tiny, out, capsys, monkeypatch, *extra):
    host, port = address
    args = ["calibrate", "--instrument", f"{host}:{port}", "--setup", str(tiny), *RUN]
    return run_main([*args, "--timeout", TIMEOUT, "--out", str(out), *extra], capsys, monkeypatch)


@pytest.fixture(scope="module")
def clean_run(tiny, tmp_path_factory):
    """The run without a fault: its measurement count (and that it succeeds)."""
    out = tmp_path_factory.mktemp("clean")
    with InstrumentServer(load_setup(tiny, seed=3)) as server:
        host, port = server.address
        args = ["calibrate", "--instrument", f"{host}:{port}", "--setup", str(tiny), *RUN]
        result = CliRunner().invoke(app, [*args, "--timeout", TIMEOUT, "--out", str(out)])
        acquisitions = server.n_acquisitions
    assert result.exit_code in FINISHED, result.output
    summary = json.loads(result.stdout)
    assert summary["n_measurements"] == 14  # the budget, all used
    return {**summary, "acquisitions": acquisitions}


@pytest.mark.parametrize("fault", list(OUTCOME))
def test_a_fault_on_the_wire_is_survived_or_stops_cleanly(
    fault, tiny, clean_run, tmp_path, capsys, monkeypatch
):
    out = tmp_path / "run"
    with (
        InstrumentServer(load_setup(tiny, seed=3)) as server,
        FaultProxy(server.address, fault, at=PAYLOAD_OF_THIRD, delay=3.0) as proxy,
    ):
        code, stdout, err = _calibrate(proxy.address, tiny, out, capsys, monkeypatch)
        acquisitions = server.n_acquisitions
    assert proxy.fired and "Traceback" not in err
    if OUTCOME[fault] == "survives":
        assert code in FINISHED, err
        summary = json.loads(stdout)
        # the hit A-scan was measured again on a new connection: one more acquisition
        assert proxy.connections >= 2
        # the run finished as a clean one does: every measurement logged in result.json
        # (the re-measured A-scan has new noise, so the path may differ from clean_run's)
        result = json.loads((out / "result.json").read_text())
        assert 0 < summary["n_measurements"] == len(result["values"]) <= 14
        assert summary["n_measurements"] <= acquisitions
        assert clean_run["n_measurements"] == 14
        assert not (out / "partial_log.json").exists()
        return
    assert code == 2 and err.count("error:") == 1, err
    assert "CRC-32" in err and "saved" in flat(err), err
    log = json.loads((out / "partial_log.json").read_text())
    # every A-scan before the garbled one is kept, with its pose, value and time
    # (2 before the third A-scan; more only if a slow machine made the client retry one)
    assert 2 <= log["n_measurements"] <= acquisitions - 1
    n = log["n_measurements"]
    assert len(log["values"]) == len(log["poses"]) == len(log["times"]) == n
    assert np.all(np.isfinite(log["values"]))
    assert not (out / "result.json").exists()  # no result claims what was not measured


def test_a_garbled_payload_is_refused_by_its_checksum_not_read_as_numbers(tiny):
    """Without the CRC, a garbled base64 payload decodes to other, finite numbers."""
    from echocal.measurement import protocol

    header, payload = protocol.encode_ascan(np.linspace(-1.0, 1.0, 64), 50e6, 2e-5)
    middle = len(payload) // 2
    garbled = payload[:middle] + "AAAA" + payload[middle + 4 :]
    _, _, n = protocol.decode_ascan_header(header)
    silent = protocol.decode_samples(garbled, n)  # base64 still valid: other numbers
    assert np.all(np.isfinite(silent)) and not np.array_equal(silent, np.linspace(-1, 1, 64))
    with pytest.raises(InstrumentError, match="CRC-32"):
        protocol.decode_samples(garbled, n, crc=protocol.payload_crc(header))


# -- token handshake, remote listening ----------------------------------------------------
TOKEN = "s3cret-token-42"


def test_a_server_with_a_token_serves_only_clients_that_send_it(tiny):
    with InstrumentServer(load_setup(tiny, seed=1), token=TOKEN) as server:
        host, port = server.address
        with HardwareSource.connect(host, port, token=TOKEN) as rig:
            assert "tiny" in rig.description
            assert rig.measure(Pose(0.0, 0.0, 0.016, 0.0, 0.0)).samples.size == 256
        with pytest.raises(InstrumentError, match="refused the connection.*--token"):
            HardwareSource.connect(host, port, token="wrong-token-xx", retries=3)
        with pytest.raises(InstrumentError):  # no token: the server hangs up at once
            HardwareSource.connect(host, port, retries=0)
        with socket.create_connection((host, port), timeout=2) as raw:  # by hand
            raw.sendall(b"ACQ?\n")
            assert raw.makefile("rb").readline().startswith(b"ERR AUTH")
        assert server.n_acquisitions == 1  # only the authenticated client measured


def test_cli_calibrate_passes_the_token(tiny, tmp_path, capsys, monkeypatch):
    with InstrumentServer(load_setup(tiny, seed=3), token=TOKEN) as server:
        code, _, err = _calibrate(server.address, tiny, tmp_path / "a", capsys, monkeypatch)
        assert code == 2 and "--token" in err and "Traceback" not in err
        code, stdout, err = _calibrate(
            server.address, tiny, tmp_path / "b", capsys, monkeypatch, "--token", TOKEN
        )
        assert code in FINISHED, err
    assert json.loads(stdout)["n_measurements"] > 0


@pytest.mark.parametrize("token", ["short", "with space in it", "tab\tinside!"])
def test_a_bad_token_is_refused_in_one_line(token, capsys, monkeypatch):
    code, _, err = run_main(
        ["instrument-server", "--port", "0", "--token", token], capsys, monkeypatch
    )
    assert code == 2 and err.count("error:") == 1 and "token must be" in err


def test_listening_beyond_loopback_needs_allow_remote(capsys, monkeypatch):
    code, _, err = run_main(["instrument-server", "--host", "0.0.0.0"], capsys, monkeypatch)
    assert code == 2 and err.count("error:") == 1
    assert "--allow-remote" in err and "--token" in err


def test_allow_remote_without_a_token_is_refused(capsys, monkeypatch):
    monkeypatch.delenv("ECHOCAL_INSTRUMENT_TOKEN", raising=False)
    code, _, err = run_main(
        ["instrument-server", "--host", "0.0.0.0", "--allow-remote", "--port", "0"],
        capsys,
        monkeypatch,
    )
    assert code == 2 and err.count("error:") == 1 and "Traceback" not in err
    assert "needs a token" in flat(err) and "--token" in err


TOKEN_ARGS = ("--token", "s3cret-token-42")


def test_allow_remote_with_a_token_warns_and_serves(capsys, monkeypatch):
    from echocal.cli import instrument

    served = {}

    def fake_serve(source, host, port, move_time, *, on_ready, token):
        served.update(host=host, token=token)

    monkeypatch.setattr("echocal.measurement.instrument_server.serve_forever", fake_serve)
    code, _, err = run_main(
        ["instrument-server", "--host", "0.0.0.0", "--allow-remote", "--port", "0", *TOKEN_ARGS],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    assert served == {"host": "0.0.0.0", "token": "s3cret-token-42"}
    assert "warning:" in err and "clients must send the --token first" in flat(err)
    assert instrument.is_loopback("127.0.0.1") and instrument.is_loopback("localhost")
    assert not instrument.is_loopback("0.0.0.0")
