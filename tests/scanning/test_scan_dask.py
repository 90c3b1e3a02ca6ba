"""A scan on a Dask cluster (a LocalCluster: scheduler and two worker processes on
127.0.0.1) equals the local scan bit for bit: through the API (``client=``) and the
command line (``--scheduler``), warm and cold, and a resumed distributed scan too."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cli_helpers import run_main, tiny_setup_toml
from echocal.scanning import ScanGrid, scan_surface
from echocal.setups import load_setup

distributed = pytest.importorskip("distributed")
pytestmark = pytest.mark.slow  # a LocalCluster of two worker processes: about 60 s

MM = 1e-3
GRID = ScanGrid.regular(x=(-2 * MM, 2 * MM, 2 * MM), y=(0.0, 2 * MM, 2 * MM), z=16 * MM)


@pytest.fixture(scope="module")
def cluster():
    with (
        distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        ) as local,
        distributed.Client(local, set_as_default=False) as client,
    ):
        yield local, client


@pytest.fixture(scope="module")
def setup_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scan-dask") / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return path


def _same(a: xr.Dataset, b: xr.Dataset) -> None:
    assert set(a.data_vars) == set(b.data_vars)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


@pytest.mark.parametrize("warm", [True, False], ids=["warm", "cold"])
def test_a_scan_on_a_cluster_equals_the_local_scan(cluster, setup_file, warm):
    _, client = cluster
    options = {"rng": 3, "progress": False, "budget_per_point": 40, "warm_start": warm}
    local = scan_surface(load_setup(setup_file), GRID, **options)
    remote = scan_surface(load_setup(setup_file), GRID, client=client, **options)
    assert local.summary["found"] == GRID.size  # a real scan: every point found
    _same(local.dataset, remote.dataset)


def test_scan_scheduler_on_the_command_line_resumes_and_equals_a_local_scan(
    cluster, setup_file, tmp_path, capsys, monkeypatch
):
    local_cluster, _ = cluster
    args = ["scan", "--setup", str(setup_file), "--grid", "-2:2:2,0:2:2", "--z", "16"]
    args += ["--budget-per-point", "40", "--seed", "3", "--no-figures", "--no-progress"]
    code, _, err = run_main([*args, "--out", str(tmp_path / "here")], capsys, monkeypatch)
    assert code == 0, err
    # the distributed scan is interrupted after its second point, then resumed
    from echocal import scanning

    real = scanning.scan.scan_surface

    def stop_after_two(*a, **k):
        def on_point(done, total):
            if done == 2:
                raise KeyboardInterrupt

        return real(*a, on_point=on_point, **k)

    there = [
        *args,
        "--out",
        str(tmp_path / "there"),
        "--scheduler",
        local_cluster.scheduler_address,
    ]
    monkeypatch.setattr("echocal.scanning.scan_surface", stop_after_two)
    code, _, err = run_main(there, capsys, monkeypatch)
    assert code == 130, err
    monkeypatch.setattr("echocal.scanning.scan_surface", real)
    code, _, err = run_main(there, capsys, monkeypatch)
    assert code == 0 and "resuming" in err, err
    with (
        xr.open_dataset(tmp_path / "here" / "scan.nc", engine="h5netcdf") as here,
        xr.open_dataset(tmp_path / "there" / "scan.nc", engine="h5netcdf") as there_ds,
    ):
        _same(here, there_ds)
        assert (
            json.loads(there_ds.attrs["provenance"])["argv"][-1] == local_cluster.scheduler_address
        )


def test_scheduler_is_refused_with_a_rig_and_for_a_bad_address(
    setup_file, tmp_path, capsys, monkeypatch
):
    args = [
        "scan",
        "--setup",
        str(setup_file),
        "--grid",
        "0:0:1,0:0:1",
        "--out",
        str(tmp_path / "o"),
    ]
    code, _, err = run_main([*args, "--scheduler", "10.0.0.5:8786"], capsys, monkeypatch)
    assert code == 2 and "tcp://HOST:PORT" in err
    rig = tmp_path / "rig.toml"
    rig.write_text(
        "[rig]\n"
        + "".join(
            f'[rig.{part}]\ndriver = "tcp"\naddress = "127.0.0.1:9"\n'
            for part in ("positioner", "receiver")
        )
    )
    code, _, err = run_main(
        [
            "scan",
            "--rig",
            str(rig),
            "--setup",
            str(setup_file),
            "--grid",
            "0:0:1,0:0:1",
            "--out",
            str(tmp_path / "r"),
            "--scheduler",
            "tcp://127.0.0.1:9",
        ],
        capsys,
        monkeypatch,
    )
    assert code == 2 and "not on a cluster" in err
