"""Shared helpers of the benchmark scripts: timing, machine description, Markdown tables,
the run-cell arguments and JSONL logs of the seeded calibration benchmarks.

Not a package (no ``__init__.py``): the scripts run as ``python benchmarks/NAME.py`` and
import this module from their own directory.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class Timing:
    """Wall-clock times of repeated calls (``time.perf_counter``).

    Attributes
    ----------
    median : [s] median over the repeats (the reported number).
    best : [s] fastest repeat (least disturbed by other processes).
    repeats : number of timed calls (after the warm-up calls).
    """

    median: float
    best: float
    repeats: int

    def as_dict(self) -> dict[str, float | int]:
        return asdict(self)


def measure(fn: Callable[[], object], *, repeats: int, warmup: int = 1) -> Timing:
    """Time ``fn()``: ``warmup`` untimed calls, then ``repeats`` timed ones."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return Timing(median=statistics.median(times), best=min(times), repeats=len(times))


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info(packages: Sequence[str] = ()) -> dict[str, Any]:
    """echocal's git commit (``-dirty`` when its source differs from it; None outside a
    checkout), cores, CPU, Python and package versions, BLAS threads and the load when
    started."""
    from echocal.provenance import git_commit

    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        usable = os.cpu_count() or 1
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except OSError:
        load = []
    return {
        "echocal_git": git_commit(),
        "cpu": _cpu_model(),
        "cores": os.cpu_count(),
        "usable_cores": usable,
        "load_average_1_5_15min": load,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
        "versions": {name: _version(name) for name in ("numpy", "scipy", *packages)},
    }


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub Markdown table (cells formatted with ``str``)."""
    lines = [
        "| " + " | ".join(header) + " |",
        "| " + " | ".join("---" for _ in header) + " |",
    ]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def fmt_time(seconds: float) -> str:
    """Seconds in a readable unit: ``0.412 ms``, ``12.3 s``."""
    if seconds < 1e-3:
        return f"{seconds * 1e6:.1f} µs"
    if seconds < 1.0:
        return f"{seconds * 1e3:.3g} ms"
    return f"{seconds:.3g} s"


def fmt_rate(per_second: float) -> str:
    """A rate with thousands separators: ``1,234/s``."""
    return f"{per_second:,.0f}/s"


# ------------------------------------------------------- seeded cells of calibration runs
def add_cell_arguments(ap: argparse.ArgumentParser, *, runs: int, starts: str) -> None:
    """The options every seeded run-cell benchmark takes: ``--runs`` (per cell, default
    ``runs``), ``--snr`` (comma-separated [dB], default 30,20), ``--starts`` (comma-separated
    subset of far,near, default ``starts``), ``--jsonl`` (append every run there as it
    ends) and ``--summarize`` (only print a JSONL's table)."""
    ap.add_argument("--runs", type=int, default=runs, help="runs per cell")
    ap.add_argument("--snr", default="30,20", help="comma-separated SNRs [dB]")
    ap.add_argument("--starts", default=starts, help="comma-separated subset of far,near")
    ap.add_argument("--jsonl", type=Path, default=None, help="append every run here as it ends")
    ap.add_argument("--summarize", type=Path, default=None, help="only print a JSONL's table")


def parse_cell_arguments(
    ap: argparse.ArgumentParser,
    argv: list[str] | None,
    table: Callable[[list[dict[str, Any]]], str],
) -> argparse.Namespace | None:
    """``ap``'s arguments (with :func:`add_cell_arguments`'s); with ``--summarize`` the
    JSONL's ``table`` is printed instead and None returned (the benchmark is done)."""
    args = ap.parse_args(argv)
    if args.summarize is None:
        return args
    print(table(read_jsonl(args.summarize)))
    return None


def cell_table(
    runs: list[dict[str, Any]],
    keys: tuple[str, ...],
    header: Sequence[str],
    row: Callable[[tuple[Any, ...], list[dict[str, Any]]], Sequence[str]],
    order: Callable[[tuple[Any, ...]], Any],
) -> str:
    """A Markdown table (:func:`markdown_table`) of ``runs`` with one row per cell (the
    runs' values at ``keys``), cells sorted by ``order`` (of a cell's key values): the
    ``header`` columns, a cell's column texts ``row(cell, its runs)``."""
    cells: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for r in runs:
        cells.setdefault(tuple(r[k] for k in keys), []).append(r)
    return markdown_table(header, [row(c, cells[c]) for c in sorted(cells, key=order)])


def cell_runs(args: argparse.Namespace, first: int) -> Iterator[tuple[str, float, int]]:
    """``(start, snr, run)`` of :func:`add_cell_arguments`'s ``args`` for runs ``first`` ..
    ``first + args.runs - 1``, interleaved (run-major): a benchmark cut short has about as
    many runs in every cell."""
    starts = args.starts.split(",")
    snrs = [float(s) for s in args.snr.split(",")]
    for run in range(first, first + args.runs):
        for start in starts:
            for snr in snrs:
                yield start, snr, run


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    """The rows of a JSONL log (blank lines skipped)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return [json.loads(line) for line in lines if line.strip()]


def append_jsonl(path: Path | None, row: dict[str, Any]) -> None:
    """Append ``row`` to the JSONL log at ``path`` as one line (nothing when None)."""
    if path is not None:
        with path.open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(row) + "\n")
