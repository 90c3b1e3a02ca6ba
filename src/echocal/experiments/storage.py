"""The results folder of a sweep: written incrementally, resumable, never silently replaced.

Layout of ``OUT/``::

    sweep.json        the resolved spec, its content hash and the number of runs
    parts/            one ``runs-<key>.parquet`` + ``history-<key>.parquet`` per finished run,
                      each written atomically (history first: a runs part marks a run done)
    runs.parquet      one row per run (consolidated at the end, in expansion order)
    history.parquet   every measurement of every run

The angle columns are named for the sweep's parameterization (``tilt_x_deg``, ...:
:mod:`echocal.angle_columns`); tables of older folders, with ``a``/``b``, are read
with their columns renamed.

A folder whose ``sweep.json`` holds another hash is refused (:func:`prepare_folder`)
unless ``overwrite=True``, which deletes exactly these files and nothing else.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from echocal.angle_columns import named_angles
from echocal.errors import ConfigError, DataFileError
from echocal.experiments.runner import history_frame, run_columns, runs_frame
from echocal.experiments.sweep import SweepSpec, spec_hash
from echocal.io import atomic_path, atomic_write_text

__all__ = [
    "FORMAT_VERSION",
    "consolidate",
    "finished_case_ids",
    "part_key",
    "prepare_folder",
    "read_history",
    "read_runs",
    "read_sweep_json",
    "sweep_parameterization",
    "write_part",
]

FORMAT_VERSION = 1
SWEEP_JSON = "sweep.json"
RUNS = "runs.parquet"
HISTORY = "history.parquet"
PARTS = "parts"
PROVENANCE = "provenance.json"
_OURS = (SWEEP_JSON, RUNS, HISTORY, PARTS, PROVENANCE)


def part_key(case_id: str) -> str:
    """Short file-name-safe key of a case id (hex of its SHA-256)."""
    return hashlib.sha256(case_id.encode()).hexdigest()[:20]


def read_sweep_json(out_dir: str | Path) -> dict[str, Any]:
    """The ``sweep.json`` of a results folder (DataFileError if missing or unreadable)."""
    path = Path(out_dir) / SWEEP_JSON
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFileError(f"{out_dir}: not a sweep results folder (no {SWEEP_JSON})") from None
    except (OSError, json.JSONDecodeError) as exc:
        raise DataFileError(f"{path}: unreadable: {exc}") from None


def sweep_parameterization(out_dir: str | Path) -> str:
    """The parameterization of the sweep whose results are in ``out_dir`` (its sweep.json;
    ``"tilt"``, the sweeps' default, for a folder without one)."""
    if not (Path(out_dir) / SWEEP_JSON).exists():
        return "tilt"
    return str(read_sweep_json(out_dir).get("spec", {}).get("parameterization", "tilt"))


def prepare_folder(
    out_dir: str | Path, spec: SweepSpec, n_cases: int, *, overwrite: bool = False
) -> str:
    """Make ``out_dir`` ready for ``spec``; return the spec's hash.

    An empty or missing folder gets a new ``sweep.json``; a folder of the same sweep
    (same hash) is resumed; a folder of another sweep raises
    :class:`~echocal.errors.ConfigError` unless ``overwrite`` (then its sweep files are
    deleted); a non-empty folder that is not a sweep's is always refused.
    """
    out = Path(out_dir)
    digest = spec_hash(spec)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a folder")
    if out.exists() and any(out.iterdir()):
        if not (out / SWEEP_JSON).exists():
            raise ConfigError(
                f"--out {out}: holds files that are not sweep results; choose an empty or new "
                "folder (nothing was changed)"
            )
        old = read_sweep_json(out)
        if old.get("hash") != digest:
            if not overwrite:
                raise ConfigError(
                    f"--out {out}: holds another sweep ({old.get('name')!r}, hash "
                    f"{str(old.get('hash'))[:12]}, {old.get('n_cases')} runs); this sweep "
                    f"{spec.name!r} has hash {digest[:12]}. Choose another folder, or pass "
                    "--overwrite (overwrite=True) to delete those results"
                )
            for name in _OURS:
                path = out / name
                if path.is_dir():
                    shutil.rmtree(path)
                elif path.exists():
                    path.unlink()
    out.mkdir(parents=True, exist_ok=True)
    (out / PARTS).mkdir(exist_ok=True)
    for stale in (out / PARTS).glob(".*.partial*"):  # left by a killed writer
        stale.unlink(missing_ok=True)
    if not (out / SWEEP_JSON).exists():
        record = {
            "format": FORMAT_VERSION,
            "name": spec.name,
            "hash": digest,
            "n_cases": n_cases,
            "spec": spec.model_dump(mode="json"),
        }
        atomic_write_text(out / SWEEP_JSON, json.dumps(record, indent=2) + "\n")
    return digest


def write_part(out_dir: str | Path, row: dict[str, Any], history: pd.DataFrame) -> None:
    """Store one finished run atomically (history first, then the row that marks it done)."""
    parts = Path(out_dir) / PARTS
    key = part_key(row["case_id"])
    parameterization = sweep_parameterization(out_dir)
    with atomic_path(parts / f"history-{key}.parquet") as tmp:
        history_frame([history], parameterization).to_parquet(tmp, index=False)
    with atomic_path(parts / f"runs-{key}.parquet") as tmp:
        runs_frame([row], parameterization).to_parquet(tmp, index=False)


def _part_files(out: Path, kind: str) -> list[Path]:
    # atomic_path's temporaries start with "." and are never matched
    return sorted((out / PARTS).glob(f"{kind}-*.parquet")) if (out / PARTS).is_dir() else []


def _read(paths: Sequence[Path], parameterization: str) -> list[pd.DataFrame]:
    """The tables at ``paths``, legacy ``a``/``b`` columns named for ``parameterization``."""
    frames = []
    for path in paths:
        try:
            frames.append(named_angles(pd.read_parquet(path), parameterization))
        except (OSError, ValueError) as exc:
            raise DataFileError(f"{path}: unreadable results part: {exc}") from None
    return frames


def read_runs(out_dir: str | Path) -> pd.DataFrame:
    """Every finished run of a results folder (consolidated file plus any parts)."""
    out = Path(out_dir)
    paths = ([out / RUNS] if (out / RUNS).exists() else []) + _part_files(out, "runs")
    parameterization = sweep_parameterization(out)
    frames = _read(paths, parameterization)
    if not frames:
        return runs_frame([], parameterization)
    frame = pd.concat(frames, ignore_index=True)
    frame = frame.drop_duplicates("case_id", keep="last")
    columns = run_columns(parameterization)
    return frame.reindex(columns=list(columns)).astype(columns).reset_index(drop=True)


def read_history(out_dir: str | Path, case_ids: Sequence[str] | None = None) -> pd.DataFrame:
    """Measurement history of the finished runs (of ``case_ids`` if given)."""
    out = Path(out_dir)
    paths = ([out / HISTORY] if (out / HISTORY).exists() else []) + _part_files(out, "history")
    parameterization = sweep_parameterization(out)
    frame = history_frame(_read(paths, parameterization), parameterization)
    if case_ids is not None:
        frame = frame[frame["case_id"].isin(set(case_ids))]
    return frame.drop_duplicates(["case_id", "index"], keep="last").reset_index(drop=True)


def finished_case_ids(out_dir: str | Path) -> set[str]:
    """Case ids already stored (their runs row exists)."""
    return set(read_runs(out_dir)["case_id"])


def consolidate(
    out_dir: str | Path, order: Sequence[str], provenance: str | None = None
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Merge parts into ``runs.parquet`` / ``history.parquet`` (sorted by ``order``); drop parts.

    ``provenance`` (a JSON record, :mod:`echocal.provenance`) goes into ``runs.parquet``'s
    key-value metadata (pandas ``attrs``) and into ``provenance.json``.

    Only finished runs are kept: history of a run whose row was never written (killed
    between the two writes) is discarded, and that run will be redone on resume.
    """
    out = Path(out_dir)
    rank = {case_id: i for i, case_id in enumerate(order)}
    runs = read_runs(out)
    runs = runs.iloc[sorted(range(len(runs)), key=lambda i: rank.get(runs["case_id"][i], -1))]
    runs = runs.reset_index(drop=True)
    history = read_history(out, runs["case_id"].tolist())
    history = history.assign(_rank=history["case_id"].map(rank))
    history = history.sort_values(["_rank", "index"], kind="stable").drop(columns="_rank")
    history = history.reset_index(drop=True)
    with atomic_path(out / HISTORY) as tmp:
        history.to_parquet(tmp, index=False)
    if provenance is not None:  # in the file's key-value metadata, and beside it
        runs.attrs["provenance"] = provenance
        atomic_write_text(out / PROVENANCE, provenance + "\n")
    with atomic_path(out / RUNS) as tmp:
        runs.to_parquet(tmp, index=False)
    if (out / PARTS).is_dir():
        shutil.rmtree(out / PARTS)
    return runs, history
