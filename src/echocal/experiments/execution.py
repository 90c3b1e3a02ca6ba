"""Running a sweep: local processes or a Dask cluster, stored run by run, resumable.

::

    results = run_sweep("quick", "out/quick")                    # 2 local processes
    results = run_sweep("my.toml", "out/my", scheduler="tcp://10.0.0.5:8786")
    results.summary()

Every finished run is written at once (:mod:`echocal.experiments.storage`), so an
interrupted sweep loses at most the runs in flight; running it again into the same
folder skips the finished ones.  Runs are pure functions of their case
(:func:`~echocal.experiments.runner.run_case`), so local and Dask give the same numbers.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd

from echocal import provenance
from echocal._progress import ProgressBar
from echocal._validate import positive_int
from echocal.errors import EchocalValueError
from echocal.experiments import storage
from echocal.experiments._workers import stop_workers, worker_pool
from echocal.experiments.runner import FAILED, run_case
from echocal.experiments.summary import summarize
from echocal.experiments.sweep import RunCase, SweepSpec, expand, load_sweep
from echocal.locking import output_lock
from echocal.setup_digest import setup_digest

__all__ = ["DEFAULT_WORKERS", "SweepResults", "load_results", "run_sweep"]

DEFAULT_WORKERS = 2
"""Local worker processes when ``workers`` is not given."""

Outcome = tuple[dict[str, Any], pd.DataFrame]
Closer = Callable[[bool], None]
"""Stops a back end; its argument: the sweep was interrupted (or failed)."""


@dataclass(frozen=True)
class SweepResults:
    """A sweep's results folder: its spec, and its tables read on first access.

    out_dir : the folder; spec : the resolved sweep; hash : the spec's content hash;
    n_cases : runs in the sweep; n_new : runs computed by the call that returned this
    (0 for :func:`load_results`).
    """

    out_dir: Path
    spec: SweepSpec
    hash: str
    n_cases: int
    n_new: int = 0

    @property
    def runs_path(self) -> Path:
        """``runs.parquet``: one row per run."""
        return self.out_dir / storage.RUNS

    @property
    def history_path(self) -> Path:
        """``history.parquet``: one row per measurement."""
        return self.out_dir / storage.HISTORY

    @property
    def sweep_path(self) -> Path:
        """``sweep.json``: the resolved spec and its hash."""
        return self.out_dir / storage.SWEEP_JSON

    @cached_property
    def runs(self) -> pd.DataFrame:
        """One row per finished run (columns: :func:`~echocal.experiments.runner.run_columns`)."""
        return storage.read_runs(self.out_dir)

    @cached_property
    def history(self) -> pd.DataFrame:
        """Every measurement of every finished run (case_id, index, the two angles [deg]
        named for the sweep's parameterization, value)."""
        return storage.read_history(self.out_dir)

    @property
    def complete(self) -> bool:
        """True when every run of the sweep is stored."""
        return len(self.runs) == self.n_cases

    def summary(self) -> pd.DataFrame:
        """:func:`~echocal.experiments.summary.summarize` of :attr:`runs`."""
        return summarize(self.runs)

    @property
    def n_failed(self) -> int:
        """Stored runs that raised an error (``status`` -1; the error is in ``message``)."""
        return int((self.runs["status"] == FAILED).sum())

    def most_common_failure(self) -> tuple[str, int] | None:
        """The most frequent error of the failed runs (its first line) and how many runs
        raised it; None when no run failed."""
        failed = self.runs.loc[self.runs["status"] == FAILED, "message"]
        if failed.empty:
            return None
        first_lines = failed.fillna("").map(lambda m: m.strip().splitlines()[0] if m else "?")
        counts = first_lines.value_counts(sort=True)
        return str(counts.index[0]), int(counts.iloc[0])


def load_results(out_dir: str | Path) -> SweepResults:
    """The results of the sweep stored in ``out_dir`` (finished or interrupted)."""
    out = Path(out_dir)
    record = storage.read_sweep_json(out)
    spec = SweepSpec.model_validate(record["spec"])
    return SweepResults(out_dir=out, spec=spec, hash=record["hash"], n_cases=record["n_cases"])


def run_sweep(
    spec_or_path: SweepSpec | str | Path | dict[str, Any],
    out_dir: str | Path,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    overwrite: bool = False,
    callback: Callable[[dict[str, Any]], None] | None = None,
    gate: str | None = None,
) -> SweepResults:
    """Run every unfinished case of a sweep into ``out_dir``; return its results.

    Parameters
    ----------
    spec_or_path : a :class:`SweepSpec`, a built-in sweep name, a TOML path or a dict.
    out_dir : results folder; a folder of the same sweep is resumed (finished runs are
        skipped), one of another sweep is refused unless ``overwrite``; one another
        process is writing is refused (:class:`~echocal.locking.OutputLockedError`).
    scheduler : ``"tcp://HOST:PORT"`` of a Dask distributed scheduler; None runs locally.
        Workers need echocal installed and, for a setup file, the same path readable.
    workers : local worker processes (default :data:`DEFAULT_WORKERS`); 1 runs in this
        process.  Ignored with a scheduler.
    progress : show a progress bar with an ETA (on stderr).
    overwrite : delete the results of another sweep found in ``out_dir``.
    callback : called with each finished run's row after it is stored.
    gate : compute every run's metric in this gate (``--gate`` syntax), replacing the
        sweep's own ``gate``; part of the sweep's identity (resuming needs the same).
    """
    # everything is checked (the sweep, its runs, the workers, the scheduler) before the
    # results folder is touched: a refused call leaves no output behind
    opened = provenance.start("sweep run", {"sweep": str(spec_or_path), "out": str(out_dir)})
    n = DEFAULT_WORKERS if workers is None else positive_int("workers", workers)
    if scheduler is not None:
        _check_scheduler(scheduler)
    spec = load_sweep(spec_or_path)
    if gate is not None:  # checked again, with the gate, before anything is written
        spec = load_sweep(spec.model_copy(update={"gate": gate}))
    cases = expand(spec)
    client = None if scheduler is None else _connect(scheduler)
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(output_lock(out_dir))  # one sweep at a time in out_dir
            digest = storage.prepare_folder(out_dir, spec, len(cases), overwrite=overwrite)
            done = storage.finished_case_ids(out_dir)
        except BaseException:
            if client is not None:
                client.close()
            raise
        todo = [case for case in cases if case.case_id not in done]
        # back ends start before the progress bar's thread: worker processes fork from a
        # single-threaded parent
        if client is not None:
            outcomes, close = _dask_outcomes(todo, client, digest)
        else:
            outcomes, close = _local_outcomes(todo, n)
        interrupted = True
        try:
            with _SweepBar(spec.name, len(cases), len(cases) - len(todo), progress) as bar:
                for row, history in outcomes:
                    storage.write_part(out_dir, row, history)
                    bar.advance(failed=row["status"] == FAILED)
                    if callback is not None:
                        callback(row)
            interrupted = False
        finally:
            close(interrupted)
        record = opened.finish_json(
            setup=setup_digest(spec.setup),
            source={"kind": "simulator", "scheduler": scheduler or f"local ({n} workers)"},
            position_m=spec.position,
            seed=spec.seed,
            method={"sweep": spec.name, "hash": digest, "spec": spec.model_dump(mode="json")},
            runs={"total": len(cases), "computed": len(todo), "resumed": len(cases) - len(todo)},
        )
        storage.consolidate(out_dir, [case.case_id for case in cases], record)
    return SweepResults(
        out_dir=Path(out_dir), spec=spec, hash=digest, n_cases=len(cases), n_new=len(todo)
    )


# ---------------------------------------------------------------- back ends
def _local_outcomes(cases: Sequence[RunCase], workers: int) -> tuple[Iterator[Outcome], Closer]:
    """Results in completion order from ``workers`` processes (1: in this process).

    Worker processes use the platform's default start method (fork on Linux: instant,
    and scripts need no ``if __name__ == "__main__"`` guard; the parent has no threads
    yet) and die with this process (:mod:`echocal.experiments._workers`).  Returns the
    results iterator and a function that stops the pool (cancelling runs not yet started;
    interrupted, terminating the workers).
    """
    if workers == 1 or len(cases) <= 1:
        return (run_case(case) for case in cases), lambda interrupted: None
    pool = worker_pool(min(workers, len(cases)))  # workers die with this process
    pending = {pool.submit(run_case, case) for case in cases}

    def results() -> Iterator[Outcome]:
        nonlocal pending
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                yield future.result()

    return results(), lambda interrupted: stop_workers(pool, interrupted=interrupted)


def _check_scheduler(scheduler: str) -> None:
    """Refuse a scheduler that is not an address (before anything is written)."""
    if not isinstance(scheduler, str) or not scheduler.startswith(
        ("tcp://", "tls://", "inproc://", "ws://", "wss://")
    ):
        raise EchocalValueError(
            f"scheduler must be an address like tcp://HOST:PORT; got {scheduler!r}"
        )


def _connect(scheduler: str) -> Any:
    """A Dask distributed client of ``scheduler``, an address :func:`_check_scheduler`
    accepted (EchocalValueError if unreachable)."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise EchocalValueError(
            "scheduler needs dask.distributed; install it (pip install distributed)"
        ) from None
    try:
        # not the default client: xarray would then lock its file writes through the cluster
        return Client(scheduler, timeout="20s", set_as_default=False)
    except OSError as exc:
        raise EchocalValueError(f"scheduler {scheduler}: cannot connect: {exc}") from None


def _dask_outcomes(
    cases: Sequence[RunCase], client: Any, digest: str
) -> tuple[Iterator[Outcome], Closer]:
    """Results in completion order from the Dask distributed cluster of ``client``."""
    from distributed import as_completed

    keys = [f"echocal-run-{digest[:12]}-{storage.part_key(c.case_id)}" for c in cases]
    futures = client.map(run_case, list(cases), key=keys, pure=False) if cases else []

    def results() -> Iterator[Outcome]:
        for future in as_completed(futures, loop=client.loop):  # not the default client
            yield future.result()
            future.release()

    def close(interrupted: bool) -> None:
        if futures:
            client.cancel(futures)
        client.close()

    return results(), close


class _SweepBar(ProgressBar):
    """The sweep's bar: ``sweep NAME`` in bold, runs counted, failures shown in red."""

    def __init__(self, name: str, total: int, completed: int, enabled: bool) -> None:
        from rich.markup import escape

        name = escape(name)  # shown as rich markup
        resumed = f" (resumed: {completed} done)" if completed else ""
        super().__init__(
            "[bold]{task.description}",
            total=total,
            completed=completed,
            enabled=enabled,
            description=f"sweep {name}{resumed}",
            unit="runs",
        )
        self.name = name
        self.failed = 0

    def advance(self, failed: bool = False) -> None:
        """One more run done (``failed``: it failed)."""
        self.failed += bool(failed)
        if self.failed:
            self.describe(f"sweep {self.name} [red]{self.failed} failed")
        super().advance()
