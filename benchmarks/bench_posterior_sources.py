"""``auto``'s posterior search on a recording and on the emulated rig, against the
simulator on the same seeds (issue 44).

Run from the repository root (record the grid first: 16,762 A-scans, a 0.49 GB file,
11 minutes on a busy 2-core machine)::

    echocal record --setup immersion-5mhz --snr 30 --seed 30 \\
        --azimuth -180:180:289 --coelevation 0:14.25:58 --out rec30.nc
    nice -n 10 python benchmarks/bench_posterior_sources.py --replay30 rec30.nc \\
        --runs 50 --jsonl sources.jsonl
    python benchmarks/bench_posterior_sources.py --summarize sources.jsonl

Cells: ``immersion-5mhz`` (wave model) at its reference position, tilt parameterization,
far (5–20°) and near (1–3°) starts from the true optimum, 30 and 20 dB, with
:mod:`bench_calibration`'s seeding rule (run indices 0..N−1).  Each run is made on

* ``simulator``: the setup itself (its probe's lobe at its known amplitude);
* ``rig``: the same setup behind :class:`~echocal.measurement.InstrumentServer` (the
  emulated rig, over TCP), measured through a :class:`~echocal.measurement.HardwareSource`
  whose objective knows the setup only as its ``twin`` (the lobe's shape; the amplitude
  unknown); ``rig-no-setup``: the same without a twin (Lorentzian lobes of unknown
  width);
* ``replay``: a recording of the setup (``--replay-mode``, default ``random-repeat``;
  its draws seeded by the run), whose objective's twin is the setup the file stores
  (:meth:`~echocal.measurement.ReplaySource.recorded_setup`).

Hold-out runs: ``--first 10000000`` (run indices from 10,000,000).  A smaller recording
with repeats, replayed interpolated in a ±6° box (docs/benchmarks/auto.md, "On a
recording with repeats, interpolated")::

    echocal record --setup immersion-5mhz --snr 30 --seed 30 --azimuth -180:180:145 \\
        --coelevation 0:8.5:35 --repeats 4 --out rec30.nc
    nice -n 10 python benchmarks/bench_posterior_sources.py --sources simulator-box,replay \\
        --box 6 --replay-mode interpolate --replay30 rec30.nc --first 10000000

The simulator and the rig use :mod:`bench_calibration`'s tilt box (±21.5°); the replay
and its own ``simulator-box`` runs use a tilt box of ±``--box`` (default 10°) the
recording must cover (the first recording's grid:
co-elevation 0–14.25° in 0.25° steps, azimuth in 1.25° steps — 0.09° of arc at the
optimum's 4°, 0.31° at the box's corner — one A-scan per pose, the nearest grid pose
answers).
Per cell: share within 0.1° at the budget and in at most 60 measurements, measurements to
0.1° (median / p90 / max), the measurements until the acquisition handed an echo to the
local method (``echo found after``: the search's own count), the final error, and the
share of runs the posterior search ran in (``posterior``; the others saw the echo from
x0's first ring).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy is imported

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from contextlib import ExitStack  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402
from _calibration_cases import PARAM  # noqa: E402
from _common import add_cell_arguments, append_jsonl, cell_runs  # noqa: E402
from bench_calibration import (  # noqa: E402
    auto_errors,
    case_setup,
    measurements_to,
    rounded,
    seeded_run,
)

from echocal.geometry import Pose  # noqa: E402
from echocal.measurement import (  # noqa: E402
    HardwareSource,
    InstrumentServer,
    ReplaySource,
    SourceObjective,
)
from echocal.measurement.replay import MODES  # noqa: E402

CASE = "immersion-5mhz"
BUDGET = 100
"""Measurements per run (the estimate is read after each)."""
BOX = np.array([[-10.0, 10.0], [-10.0, 10.0]])
"""[deg] the tilt box the recording covers (co-elevation up to 14.1°)."""
SOURCES = ("simulator", "rig", "rig-no-setup", "simulator-box", "replay")
_ORDER = (*SOURCES, "rig-before")  # the table also shows runs of an earlier version


_REPLAYS: dict[tuple[str, str], tuple[ReplaySource, Any]] = {}


def _replay(path: str, mode: str) -> tuple[ReplaySource, Any]:
    """The recording at ``path`` in ``mode``, opened once per process (its A-scans are
    read into memory at the first measurement), and the setup it stores."""
    if (path, mode) not in _REPLAYS:
        recording = ReplaySource.open(path, mode=mode)
        _REPLAYS[path, mode] = (recording, recording.recorded_setup())
    return _REPLAYS[path, mode]


def run_one(
    source: str,
    start: str,
    snr: float,
    run: int,
    replay: str | None,
    *,
    mode: str = "random-repeat",
    half_box: float = float(BOX[0, 1]),
) -> dict[str, Any]:
    """One seeded run of ``auto`` on ``source``; its error after each measurement.
    ``mode``: the replay's (:data:`~echocal.measurement.replay.MODES`); ``half_box``
    [deg]: the tilt box of ``simulator-box`` and ``replay`` is ±``half_box``."""
    in_box = source in ("simulator-box", "replay")
    box = np.array([[-half_box, half_box]] * 2) if in_box else None
    ready = seeded_run(CASE, start, snr, run, box)
    setup, pos = ready.setup, ready.position
    t0 = time.process_time()
    kw: dict[str, Any] = {"parameterization": PARAM, "budget": BUDGET, "bounds": ready.bounds}
    with ExitStack() as connected:
        if source in ("simulator", "simulator-box"):
            objective = SourceObjective(setup, pos, **kw)
        elif source in ("rig", "rig-no-setup"):
            twin = case_setup(CASE, snr, 0) if source == "rig" else None
            server = connected.enter_context(InstrumentServer(setup, initial_pose=Pose(*pos)))
            rig = connected.enter_context(HardwareSource.connect(*server.address))
            objective = SourceObjective(rig, pos, pulse=setup.pulse, twin=twin, **kw)
        else:
            assert replay is not None
            recording, twin = _replay(replay, mode)
            recording.reseed(ready.seed)
            objective = SourceObjective(recording, pos, pulse=setup.pulse, twin=twin, **kw)
        res, errors = auto_errors(objective, ready, BUDGET)
    return {
        "source": source,
        "start": start,
        "snr": snr,
        "run": run,
        "errors": rounded(errors),
        "posterior": bool(res.posterior_search),
        "found_at": res.acquisition_measurements,
        "status": int(res.status),
        "false_alarms": int(res.false_alarms),
        "cpu_s": time.process_time() - t0,
        **({"mode": mode} if source == "replay" else {}),
        **({"box": half_box} if in_box else {}),
    }


def _label(run: dict[str, Any]) -> str:
    """The source column of ``run``'s row: the source, the replay's mode, the tilt box
    (runs stored before these options: ``random-repeat``, ±10°)."""
    label = run["source"]
    if label == "replay":
        label += f" {run.get('mode', 'random-repeat')}"
    if "box" in run or label.startswith(("replay", "simulator-box")):
        label += f" ±{run.get('box', 10.0):g}°"
    return label


def summarize(runs: list[dict[str, Any]]) -> str:
    """The Markdown table of the runs, one row per (source, start, SNR)."""

    def spread(values: np.ndarray, *more: float) -> str:
        """``median/p90[/more]``, ∞ for a run that never got there."""
        p90 = np.percentile(values, 90, method="higher")
        return "/".join(
            "∞" if not np.isfinite(v) else f"{v:g}" for v in (np.median(values), p90, *more)
        )

    def row(cell: tuple[Any, ...], rs: list[dict[str, Any]]) -> list[str]:
        label, start, snr = cell
        errs = np.array([r["errors"] for r in rs])
        n_to = np.array([measurements_to(e, 0.1) for e in errs])
        found = np.array([np.inf if r["found_at"] is None else r["found_at"] for r in rs])
        return [
            label, start, f"{snr:g} dB", f"{len(rs)}",
            f"{np.mean([r['posterior'] for r in rs]):.0%}",
            f"{np.mean(errs[:, -1] <= 0.1):.1%}", f"{np.mean(n_to <= 60):.1%}",
            spread(n_to, n_to.max()), spread(found),
            f"{np.median(errs[:, -1]):.3f}° / {np.percentile(errs[:, -1], 90):.3f}°",
            f"{np.mean([r['cpu_s'] for r in rs]):.1f}",
        ]  # fmt: skip

    header = [
        "source", "start", "SNR", "runs", "posterior", "within 0.1° at 100", "in ≤ 60",
        "median / p90 / max to 0.1°", "echo found after (median / p90)",
        "final error (median / p90)", "CPU-s/run",
    ]  # fmt: skip
    order = {s: i for i, s in enumerate(_ORDER)}
    labelled = [{**r, "label": _label(r)} for r in runs]
    return _common.cell_table(
        labelled,
        ("label", "start", "snr"),
        header,
        row,
        order=lambda c: (c[1], -c[2], order[c[0].split()[0]], c[0]),
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_cell_arguments(parser, runs=50, starts="far,near")
    parser.add_argument("--first", type=int, default=0, help="first run index")
    parser.add_argument("--sources", default=",".join(SOURCES))
    parser.add_argument("--replay30", help="the recording at 30 dB (for source replay)")
    parser.add_argument("--replay20", help="the recording at 20 dB (for source replay)")
    parser.add_argument(
        "--replay-mode", default="random-repeat", choices=MODES, help="the replay's mode"
    )
    parser.add_argument(
        "--box", type=float, default=float(BOX[0, 1]),
        help="[deg] half-width of the tilt box of simulator-box and replay",
    )  # fmt: skip
    args = _common.parse_cell_arguments(parser, argv, summarize)
    if args is None:
        return 0
    replays = {30.0: args.replay30, 20.0: args.replay20}
    runs = []
    for start, snr, run in cell_runs(args, args.first):
        for source in args.sources.split(","):
            if source == "replay" and replays.get(snr) is None:
                continue
            r = run_one(
                source, start, snr, run, replays.get(snr), mode=args.replay_mode, half_box=args.box
            )
            runs.append(r)
            append_jsonl(args.jsonl, r)
    print(summarize(runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
