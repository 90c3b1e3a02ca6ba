"""Shared test configuration: derandomized hypothesis, headless matplotlib, and a list of
the fast tier's tests that cost more CPU time than the tier allows."""

from __future__ import annotations

import os
import resource
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

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


FAST_TIER_CPU_S = 10.0
"""[CPU-s] a test not marked ``slow`` that costs more (setup, call and teardown: this
process's threads and the children it waited for) is listed at the end of the run: mark
it ``slow`` (``make test-slow``) or make it cheaper.  CPU time, not wall-clock time, so the
list does not depend on the machine's load; nothing fails on it."""
_CPU_START = pytest.StashKey[float]()


def _cpu_s() -> float:
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item: pytest.Item) -> Iterator[None]:
    item.stash[_CPU_START] = _cpu_s()
    yield


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    outcome = yield
    if call.when == "teardown" and _CPU_START in item.stash:
        report = outcome.get_result()  # type: ignore[attr-defined]
        report.user_properties.append(("cpu_s", _cpu_s() - item.stash[_CPU_START]))


def pytest_terminal_summary(terminalreporter: Any) -> None:
    costly = []
    for report in terminalreporter.getreports(""):
        if getattr(report, "when", None) != "teardown" or "slow" in report.keywords:
            continue
        spent = dict(report.user_properties).get("cpu_s", 0.0)
        if spent > FAST_TIER_CPU_S:
            costly.append((spent, report.nodeid))
    if costly:
        terminalreporter.section(f"fast-tier tests over {FAST_TIER_CPU_S:g} CPU-s")
        terminalreporter.write_line("mark them slow (make test-slow) or make them cheaper:")
        for spent, nodeid in sorted(costly, reverse=True):
            terminalreporter.write_line(f"{spent:8.1f} CPU-s  {nodeid}")
