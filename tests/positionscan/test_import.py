"""Import of foreign scan files: each test writes a real-format file itself, imports it and
checks that every sample, the time axis and the positions come back exactly."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io

from echocal.errors import DataFileError, EchocalValueError
from echocal.netcdf import schema_problems
from echocal.positionscan import PositionScan, ScanFacts, import_scan, load_facts
from echocal.provenance import file_digest

FS = 50e6
T0 = 20e-6


@pytest.fixture()
def codes() -> np.ndarray:
    """int16 ADC codes of a 3 × 4 raster of 64-sample traces (a distinct value per sample)."""
    rng = np.random.default_rng(1)
    return rng.integers(-30000, 30000, size=(3, 4, 64)).astype(np.int16)


def _round_trip(scan: PositionScan, tmp_path: Path) -> PositionScan:
    out = tmp_path / "scan.nc"
    scan.save(out)
    assert schema_problems(out) == []
    return PositionScan.load(out)


def test_matlab_v5_raster_keeps_codes_scale_and_positions(codes, tmp_path):
    # MATLAB users store (y, x, time) with named vectors; the conventional names are read
    src = tmp_path / "scan.mat"
    x, y = np.arange(4) * 0.5e-3, 10e-3 + np.arange(3) * 1e-3
    t = T0 + np.arange(64) / FS
    scipy.io.savemat(src, {"ascans": codes, "x": x, "y": y, "t": t})
    scan = import_scan(src, ScanFacts(scale_factor=1 / 32768, sound_speed=1480.0))
    back = _round_trip(scan, tmp_path)
    assert back.raw.dtype == np.int16
    np.testing.assert_array_equal(back.raw, codes)  # every sample, bit for bit
    np.testing.assert_allclose(back.samples, codes / 32768)
    np.testing.assert_allclose(back.x, x)
    np.testing.assert_allclose(back.y, y)
    assert back.fs == pytest.approx(FS, rel=1e-9)
    assert back.start_time == pytest.approx(T0, abs=1e-15)
    attrs = back.dataset.attrs
    assert attrs["source_sha256"] == file_digest(src)
    assert attrs["source_format"] == "MATLAB v5"
    assert json.loads(attrs["user_facts"]) == {"scale_factor": 1 / 32768, "sound_speed": 1480.0}
    assert back.dataset["x"].attrs["standard_name"] == "projection_x_coordinate"
    assert back.dataset["samples"].attrs["scale_factor"] == pytest.approx(1 / 32768)


def test_matlab_v73_is_read_in_matlab_axis_order(codes, tmp_path):
    # a v7.3 file is HDF5 with every array stored transposed (MATLAB is column-major)
    src = tmp_path / "scan73.mat"
    with h5py.File(src, "w", userblock_size=512) as handle:
        handle["data"] = codes.T
        handle["fs"] = np.array([[FS]])
    scan = import_scan(src, ScanFacts(x_step=1e-3, y_step=2e-3, start_time=T0))
    back = _round_trip(scan, tmp_path)
    np.testing.assert_array_equal(back.raw, codes)
    np.testing.assert_allclose(back.y, [0.0, 2e-3, 4e-3])
    assert back.fs == FS and back.dataset.attrs["source_format"] == "MATLAB v7.3 (HDF5)"


def test_csv_with_time_column_one_trace_per_column(tmp_path):
    t = T0 + np.arange(40) / FS
    traces = np.sin(np.arange(40)[:, None] * 0.3 + np.arange(5)) * 0.25
    src = tmp_path / "scope.csv"
    header = "Time (s)," + ",".join(f"CH{k}" for k in range(5))
    rows = [",".join(repr(float(v)) for v in (t[i], *traces[i])) for i in range(40)]
    src.write_text(header + "\n" + "\n".join(rows) + "\n")
    scan = import_scan(src, ScanFacts(x_start=-2e-3, x_step=1e-3, x_end=2e-3))
    back = _round_trip(scan, tmp_path)
    np.testing.assert_array_equal(back.samples[0], traces.T)  # float64 text round trip
    np.testing.assert_allclose(back.x, [-2e-3, -1e-3, 0, 1e-3, 2e-3], atol=1e-15)
    assert back.fs == pytest.approx(FS, rel=1e-9) and not back.is_raster


def test_one_trace_per_file_npy_in_a_folder(tmp_path):
    traces = np.random.default_rng(2).normal(size=(3, 32))
    for k, trace in enumerate(traces):
        np.save(tmp_path / f"trace{k}.npy", trace)
    scan = import_scan(tmp_path, ScanFacts(sampling_rate=FS, x_step=2e-3))
    np.testing.assert_array_equal(_round_trip(scan, tmp_path).samples[0], traces)


def test_npz_and_generic_hdf5_with_a_mapping(codes, tmp_path):
    mapping = tmp_path / "map.toml"
    mapping.write_text(
        'dataset = "scan/ascans"\naxes = ["time", "y", "x"]\nsampling_rate = "50 MHz"\n'
        'start_time = "20 us"\nx_step = "0.5 mm"\ny_step = "1 mm"\nsound_speed = "1480 m/s"\n'
        'probe = { name = "V309", center_frequency = "5 MHz" }\n'
    )
    src = tmp_path / "scan.h5"
    with h5py.File(src, "w") as handle:
        handle["scan/ascans"] = np.moveaxis(codes, -1, 0)  # time first in this file
    scan = import_scan(src, load_facts(mapping))
    back = _round_trip(scan, tmp_path)
    np.testing.assert_array_equal(back.raw, codes)
    assert back.sound_speed == 1480.0 and back.start_time == pytest.approx(T0)
    assert back.attr_json("probe")["name"] == "V309"
    npz = tmp_path / "scan.npz"
    np.savez(npz, ascans=codes.astype(np.float32))
    again = import_scan(npz, ScanFacts(sampling_rate=FS, x_step=1e-3, y_step=1e-3))
    np.testing.assert_array_equal(_round_trip(again, tmp_path).raw, codes.astype(np.float32))


def _write_nde(path: Path, codes: np.ndarray, status: np.ndarray) -> None:
    """An NDE 4.0 file as its published layout describes: /Public/Setup (JSON), the
    A-scans at /Public/Groups/0/Datasets/0-AScanAmplitude with (U, V, Ultrasound) axes."""
    n_y, n_x, n_t = codes.shape
    setup = {
        "version": "4.0.0",
        "groups": [
            {
                "id": 0,
                "name": "GR-1",
                "datasets": [
                    {
                        "id": 0,
                        "dataClass": "AScanAmplitude",
                        "path": "/Public/Groups/0/Datasets/0-AScanAmplitude",
                        "dataValue": {
                            "min": 0,
                            "max": 32767,
                            "unitMin": 0.0,
                            "unitMax": 200.0,
                            "unit": "Percent",
                        },
                        "dimensions": [
                            {
                                "axis": "UCoordinate",
                                "offset": 0.01,
                                "quantity": n_x,
                                "resolution": 0.001,
                            },
                            {
                                "axis": "VCoordinate",
                                "offset": 0.0,
                                "quantity": n_y,
                                "resolution": 0.002,
                            },
                            {
                                "axis": "Ultrasound",
                                "offset": T0,
                                "quantity": n_t,
                                "resolution": 1 / FS,
                            },
                        ],
                    },
                    {
                        "id": 1,
                        "dataClass": "AScanStatus",
                        "path": "/Public/Groups/0/Datasets/1-AScanStatus",
                        "dataValue": {
                            "hasData": 1,
                            "saturated": 2,
                            "noSynchro": 4,
                            "unit": "Bitfield",
                        },
                        "dimensions": [],
                    },
                ],
            }
        ],
    }
    with h5py.File(path, "w") as handle:
        handle["Public/Setup"] = json.dumps(setup).encode()
        handle["Public/Groups/0/Datasets/0-AScanAmplitude"] = np.transpose(codes, (1, 0, 2))
        handle["Public/Groups/0/Datasets/1-AScanStatus"] = status.T


def test_nde_open_format_ut_raster(codes, tmp_path):
    unsigned = (codes.astype(np.int32) + 32768).astype(np.uint16) // 2  # 0..32767
    status = np.ones(codes.shape[:2], dtype=np.uint8)
    status[1, 2] = 0  # no data at one position
    src = tmp_path / "weld.nde"
    _write_nde(src, unsigned, status)
    back = _round_trip(import_scan(src), tmp_path)
    np.testing.assert_array_equal(back.raw, unsigned)
    np.testing.assert_allclose(back.samples, unsigned * (200.0 / 32767), rtol=1e-12)
    np.testing.assert_allclose(back.x, 0.01 + 0.001 * np.arange(4))
    np.testing.assert_allclose(back.y, [0.0, 0.002, 0.004])
    assert back.valid.sum() == 11 and not back.valid[1, 2]
    assert back.fs == pytest.approx(FS) and back.dataset.attrs["source_format"] == "NDE 4.0.0"


@pytest.mark.parametrize(
    ("facts", "field"),
    [
        (ScanFacts(sampling_rate=FS, x_step=1e-3, x_end=5e-3), "x_step"),  # 4 traces, not 6
        (ScanFacts(x_step=1e-3), "sampling_rate"),  # no time axis anywhere
        (ScanFacts(sampling_rate=FS), "x_step"),  # 4 traces, no positions
    ],
)
def test_missing_or_inconsistent_facts_name_the_field(tmp_path, facts, field):
    src = tmp_path / "a.npy"
    np.save(src, np.zeros((4, 16)))
    with pytest.raises(EchocalValueError, match=field):
        import_scan(src, ScanFacts(layout="rows").merged(**facts.given()))


def test_bad_files_are_one_line(tmp_path):
    ragged = tmp_path / "r.csv"
    ragged.write_text("1,2,3\n4,5\n")
    with pytest.raises(EchocalValueError, match="line 2: 2 fields, expected 3"):
        import_scan(ragged, ScanFacts(sampling_rate=FS, x_step=1e-3))
    nan = tmp_path / "n.csv"
    nan.write_text("1,2\nnan,3\n")
    with pytest.raises(EchocalValueError, match="line 2, column 1"):
        import_scan(nan, ScanFacts(sampling_rate=FS, x_step=1e-3))
    npy = tmp_path / "n.npy"
    np.save(npy, np.array([[0.0, np.nan, 1.0]]))
    with pytest.raises(EchocalValueError, match="NaN"):
        import_scan(npy, ScanFacts(sampling_rate=FS, layout="rows"))
    with pytest.raises(ValueError, match="sampling_rate must be > 0"):
        ScanFacts.from_mapping({"sampling_rate": -5})
    with pytest.raises(DataFileError, match="unknown scan file type"):
        (tmp_path / "x.xyz").write_text("")
        import_scan(tmp_path / "x.xyz")


def test_cli_import_writes_the_file_and_refuses_in_one_line(tmp_path, capsys, monkeypatch):
    from cli_helpers import run_main

    src = tmp_path / "scope.csv"
    src.write_text("t,a,b\n0,1,2\n2e-8,3,4\n4e-8,5,6\n")
    out = tmp_path / "s.nc"
    code, stdout, _ = run_main(
        ["import", str(src), "--out", str(out), "--x-step", "1", "--json"], capsys, monkeypatch
    )
    assert code == 0 and json.loads(stdout)["sampling_rate_hz"] == pytest.approx(50e6)
    scan = PositionScan.load(out)
    np.testing.assert_array_equal(scan.samples[0], [[1, 3, 5], [2, 4, 6]])
    assert json.loads(scan.dataset.attrs["provenance"])["command"] == "import"
    code, _, err = run_main(
        ["import", str(src), "--out", str(tmp_path / "t.nc"), "--x-step", "1", "--x-end", "3"],
        capsys,
        monkeypatch,
    )
    assert code != 0 and "x_step" in err and "Traceback" not in err
