"""Shared test configuration: derandomized hypothesis, headless matplotlib."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).parent))  # tests/cli_helpers.py, from any folder
matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")
# the detector calibrations the suite makes are cached in its own folder, not the user's
# (subprocesses of CLI tests inherit it)
if "ECHOCAL_CACHE_DIR" not in os.environ:
    import atexit
    import shutil
    import tempfile

    _CACHE = tempfile.mkdtemp(prefix="echocal-test-cache-")
    os.environ["ECHOCAL_CACHE_DIR"] = _CACHE
    atexit.register(shutil.rmtree, _CACHE, ignore_errors=True)  # by the process that made it

settings.register_profile("echocal", derandomize=True, max_examples=60, deadline=None)
settings.load_profile("echocal")


@pytest.fixture(autouse=True)
def _netcdf_files_follow_the_schema(request: pytest.FixtureRequest) -> Iterator[None]:
    """Every NetCDF file a test writes into its ``tmp_path`` follows echocal's schema
    (CF attributes, UDUNITS units, compression, verified Fletcher-32 checksums).

    Tests that write foreign, legacy or damaged files on purpose are marked
    ``@pytest.mark.foreign_netcdf``.
    """
    checked = "tmp_path" in request.fixturenames and not request.node.get_closest_marker(
        "foreign_netcdf"
    )
    root = request.getfixturevalue("tmp_path") if checked else None
    yield
    if root is None:
        return
    from echocal.netcdf import schema_problems

    problems = {
        str(p.relative_to(root)): found
        for p in sorted(root.rglob("*.nc"))
        if p.is_file() and (found := schema_problems(p))
    }
    assert not problems, f"NetCDF files outside echocal's schema: {problems}"
