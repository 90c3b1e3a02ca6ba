"""Recorded A-scans replayed as a measurement source.

A replay file (written by :func:`echocal.measurement.recording.record`) is a
NetCDF-4 file (xarray, h5netcdf engine) holding A-scans recorded on a grid of
orientations at one or more positions, with repeats per point:

* variable ``samples``, dims ``(position, azimuth, coelevation, repeat, time)``;
* coordinates ``azimuth`` and ``coelevation`` [degree] (strictly increasing),
  ``position_x``, ``position_y``, ``position_z`` [m] along ``position``,
  ``repeat`` (index) and ``time`` [s]; each with a ``units`` attribute;
* attributes ``echocal_format = "replay/2"``, ``sampling_rate_hz``, ``start_time_s``,
  ``source_info`` (JSON: the recorded source's description, limits and setup) and
  ``grid`` (JSON: the recording grid), plus echocal's NetCDF schema
  (:mod:`echocal.netcdf`: CF-1.10, compressed, Fletcher-32 checksums).

A file whose checksums fail is refused on opening.  A ``replay/1`` file (echocal before
the schema: no checksums, ``fs``/``start_time``/``source`` attributes, ``deg``) still
opens, with a warning; ``echocal convert OLD NEW`` rewrites it as ``replay/2``.

How :meth:`ReplaySource.measure` answers a pose (the ``mode``):

``"nearest"``
    The recording at the nearest recorded position and nearest grid orientation,
    repeat 0 (deterministic).
``"random-repeat"``
    As ``"nearest"``, but one of the repeats drawn uniformly with ``rng`` (seeded:
    reproducible), so replaying shows the recorded noise.
``"interpolate"``
    Bilinear interpolation, in (azimuth, co-elevation), of the repeat-averaged
    A-scans of the 4 grid orientations around the pose (nearest position), plus the
    recorded noise: one repeat of the nearest of the 4, drawn with ``rng``, minus that
    orientation's repeat average, scaled by ``sqrt((n - Σw²) / (n - 1))`` (``n``
    repeats, ``w`` the 4 bilinear weights).  The repeat averages carry noise of
    variance σ²/n each, so their bilinear blend carries σ²·Σw²/n, and a repeat's
    deviation from its average carries σ²·(n − 1)/n, uncorrelated with every average:
    the sum has the variance σ² of one recorded A-scan at every pose (white or
    coloured, the recorded noise's own spectrum), and measuring the same pose again
    draws again.  Without the added deviation the noise would depend on the pose — σ²
    at a grid pose but σ²/(4n) at a cell's centre — and repeat itself.  With one
    repeat (``n = 1``) the noise cannot be told from the echo: the blend of the
    recorded A-scans answers, its noise σ·sqrt(Σw²) (down to σ/2 at a cell's centre)
    and the same at every re-measurement; record ``--repeats 3`` or more for this
    mode.  This interpolates *samples*: between grid points two echoes with different
    arrival times blend into a double echo and the phase is blurred.  For a scalar
    objective without noise, :meth:`ReplaySource.interpolated_metric` — the metric
    computed on every grid A-scan (averaged over repeats), then interpolated
    bilinearly — is another choice.

Tolerance: a pose may lie outside the recorded grid by at most half a grid step
(of the end step of that axis; for an axis with a single value, 1e-9 deg) in
``"nearest"`` and ``"random-repeat"`` modes, and not at all (beyond 1e-9 deg) in
``"interpolate"`` mode; farther raises :class:`~echocal.errors.LimitError`.  An
azimuth is also tried shifted by ±360°.  The position must lie within
``position_tolerance`` [m] of a recorded position (default: half the smallest
distance between recorded positions, or 1 µm if there is only one).  ``limits``
is the recorded grid's extent.  A file with two identical recorded positions is
refused (naming the file and the positions) unless ``position_tolerance`` is given;
then the first of them answers.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Hashable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from echocal._rng import RngLike, as_generator
from echocal._validate import one_of, positive_float
from echocal.ascan import AScan
from echocal.errors import DataFileError, LimitError
from echocal.geometry import PARAMETERIZATIONS, Pose, orientation_to_tilt
from echocal.measurement.base import BaseSource
from echocal.measurement.limits import PositionerLimits
from echocal.netcdf import open_netcdf

if TYPE_CHECKING:
    from echocal.measurement.virtual import VirtualSetup

__all__ = ["DIMS", "FORMAT", "MODES", "REQUIRED_COORDS", "VARIABLES", "ReplaySource"]

FORMAT = "replay/2"
"""Value of the ``echocal_format`` attribute of a replay file."""

DIMS = ("position", "azimuth", "coelevation", "repeat", "time")
"""Dimensions of the ``samples`` variable, in this order."""

REQUIRED_COORDS = {
    "azimuth": "degree",
    "coelevation": "degree",
    "time": "s",
    "position_x": "m",
    "position_y": "m",
    "position_z": "m",
}
"""Coordinates a replay file must have, with the ``units`` attribute each must carry."""

VARIABLES = {
    "samples": ("1", "received amplitude (arbitrary units)"),
    "azimuth": ("degree", "probe azimuth"),
    "coelevation": ("degree", "probe co-elevation"),
    "repeat": ("1", "repeat index"),
    "time": ("s", "time after the transmit pulse"),
    "position_x": ("m", "probe position x"),
    "position_y": ("m", "probe position y"),
    "position_z": ("m", "probe position z"),
}
"""(units, long_name) of each variable of a replay file."""

REQUIRED_ATTRS = ("sampling_rate_hz", "start_time_s", "source_info")

_V1_ATTRS = {"fs": "sampling_rate_hz", "start_time": "start_time_s", "source": "source_info"}
"""replay/1 attribute -> replay/2 attribute."""

MODES = ("nearest", "random-repeat", "interpolate")
"""How :meth:`ReplaySource.measure` answers a pose; see the module docstring."""

_EXACT = 1e-9  # [deg] / relative slack for floating-point round-off at the grid's edge


def _axis_index(values: NDArray[np.float64], value: float, name: str, *, exact: bool) -> float:
    """Fractional index of ``value`` on the sorted axis ``values``; LimitError beyond tolerance."""
    n = values.size
    if n == 1:
        low_tol = high_tol = 0.0
    elif exact:
        low_tol = high_tol = 0.0
    else:
        low_tol = 0.5 * (values[1] - values[0])
        high_tol = 0.5 * (values[-1] - values[-2])
    slack = _EXACT * max(1.0, abs(value))
    if not values[0] - low_tol - slack <= value <= values[-1] + high_tol + slack:
        raise LimitError(
            f"{name}={value:g} is outside the recorded grid [{values[0]:g}, {values[-1]:g}]"
            + (f" by more than the tolerance ({max(low_tol, high_tol):g})" if not exact else "")
        )
    if n == 1:
        return 0.0
    return float(np.interp(value, values, np.arange(n, dtype=np.float64)))


class ReplaySource(BaseSource):
    """A recorded dataset replayed through the measurement interface.

    Open one with :meth:`open`.  See the module docstring for the file format,
    the modes and the tolerances.  The A-scans of a position are read into
    memory the first time that position is measured (one read per position).

    Attributes
    ----------
    path : the replay file.
    mode : one of :data:`MODES`.
    azimuths : [deg], shape ``(n_azimuth,)``.
    coelevations : [deg], shape ``(n_coelevation,)``.
    positions : [m], shape ``(n_positions, 3)``.
    n_repeats : repeats recorded per grid point.
    fs : [Hz]; start_time : [s]; n_samples : samples per A-scan.
    source_info : the recorded source's description, limits and setup (from the file).
    """

    def __init__(
        self,
        dataset: Any,
        *,
        path: Path,
        mode: str = "nearest",
        rng: RngLike = None,
        position_tolerance: float | None = None,
    ) -> None:
        self.path = path
        self.mode = one_of("mode", mode, MODES)
        self._rng = as_generator(rng)
        self._ds = dataset
        self._samples = dataset["samples"]
        self.azimuths = np.asarray(dataset["azimuth"].values, dtype=np.float64)
        self.coelevations = np.asarray(dataset["coelevation"].values, dtype=np.float64)
        self.positions = np.stack(
            [np.asarray(dataset[f"position_{c}"].values, dtype=np.float64) for c in "xyz"], axis=-1
        )
        self.n_repeats = int(dataset.sizes["repeat"])
        self.n_samples = int(dataset.sizes["time"])
        self.fs = float(dataset.attrs["sampling_rate_hz"])
        self.start_time = float(dataset.attrs["start_time_s"])
        self.source_info: dict[str, Any] = json.loads(dataset.attrs["source_info"])
        if position_tolerance is None:
            if len(self.positions) > 1:
                d = np.linalg.norm(self.positions[:, None] - self.positions[None], axis=-1)
                i, j = np.triu_indices(len(d), 1)
                k = int(np.argmin(d[i, j]))
                if not d[i[k], j[k]] > 0:
                    a, b = int(i[k]), int(j[k])
                    where = ", ".join(f"{c:g}" for c in self.positions[a])
                    raise DataFileError(
                        f"{path}: recorded positions #{a} and #{b} are the same point "
                        f"({where}) m, so a measurement there cannot be told apart; record "
                        "each position once, or pass position_tolerance to use the first"
                    )
                position_tolerance = 0.5 * float(d[i[k], j[k]])
            else:
                position_tolerance = 1e-6
        self.position_tolerance = positive_float("position_tolerance", position_tolerance)
        low, high = self.positions.min(axis=0), self.positions.max(axis=0)
        self.limits = PositionerLimits(
            x=(low[0], high[0]),
            y=(low[1], high[1]),
            z=(low[2], high[2]),
            azimuth=(self.azimuths[0], self.azimuths[-1]),
            coelevation=(self.coelevations[0], self.coelevations[-1]),
        )
        recorded = self.source_info.get("description", "unknown source")
        self.description = f"replay of {path.name} ({mode}): {recorded}"
        self._blocks: dict[int, NDArray[np.float64]] = {}
        self._metric_cache: dict[tuple[Hashable, int], NDArray[np.float64]] = {}
        self._closed = False

    # -- opening ----------------------------------------------------------------------------
    def reseed(self, rng: RngLike) -> None:
        """Restart the draws of the ``random-repeat`` and ``interpolate`` modes from
        ``rng`` (seed or Generator)."""
        self._rng = as_generator(rng)

    @classmethod
    def open(
        cls,
        path: str | os.PathLike[str],
        mode: str = "nearest",
        rng: RngLike = None,
        *,
        position_tolerance: float | None = None,
    ) -> ReplaySource:
        """Open a replay file; see the module docstring for ``mode`` and the tolerances.

        Raises
        ------
        DataFileError : the file is missing, unreadable, damaged (a checksum fails), not
            an echocal replay recording, or lacks a variable, coordinate, ``units``
            attribute or attribute (named).
        """
        one_of("mode", mode, MODES)
        file = Path(path)
        ds = open_netcdf(file, what="replay file")
        try:
            ds = _upgrade(ds, file)
            _validate(ds, file)
            return cls(ds, path=file, mode=mode, rng=rng, position_tolerance=position_tolerance)
        except BaseException:
            ds.close()
            raise

    # -- lookup -----------------------------------------------------------------------------
    def _position_index(self, pose: Pose) -> int:
        d = np.linalg.norm(self.positions - pose.position, axis=-1)
        p = int(np.argmin(d))
        if d[p] > self.position_tolerance:
            raise LimitError(
                f"position ({pose.x:g}, {pose.y:g}, {pose.z:g}) m is {d[p]:.3g} m from the "
                f"nearest recorded position; tolerance is {self.position_tolerance:.3g} m"
            )
        return p

    def _fractional(self, pose: Pose, *, exact: bool) -> tuple[float, float]:
        """Fractional (azimuth, coelevation) grid indices of ``pose``."""
        ci = _axis_index(self.coelevations, pose.coelevation, "coelevation", exact=exact)
        error: LimitError | None = None
        for shift in (0.0, -360.0, 360.0):
            try:
                ai = _axis_index(self.azimuths, pose.azimuth + shift, "azimuth", exact=exact)
            except LimitError as exc:
                error = error or exc
                continue
            return ai, ci
        assert error is not None
        raise error

    def _check_open(self) -> None:
        if self._closed:
            raise DataFileError(f"replay source {self.path} is closed")

    def _block(self, p: int) -> NDArray[np.float64]:
        """All A-scans at position ``p``, shape ``(n_azimuth, n_coelevation, n_repeats, n_time)``.

        Read from the file on first use, then kept in memory (read-only).
        """
        if p not in self._blocks:
            block = np.asarray(self._samples[p].values, dtype=np.float64)
            _check_magnitudes(block, self.path, p)
            block.setflags(write=False)
            self._blocks[p] = block
        return self._blocks[p]

    def _grid_pose(self, p: int, a: int, c: int) -> Pose:
        x, y, z = self.positions[p]
        return Pose(x, y, z, self.azimuths[a], self.coelevations[c])

    def measure(self, pose: Pose) -> AScan:
        """The recorded (or interpolated) A-scan for ``pose``; see the module docstring."""
        self._check_open()
        p = self._position_index(pose)
        if self.mode == "interpolate":
            ai, ci = self._fractional(pose, exact=True)
            corners, weights = _bilinear(ai, ci, self.azimuths.size, self.coelevations.size)
            samples, r = self._interpolated_samples(self._block(p), corners, weights)
            x, y, z = (float(v) for v in self.positions[p])
            reached = Pose(x, y, z, pose.azimuth, pose.coelevation)
            meta = {"mode": self.mode, "position_index": p, "grid_index": (ai, ci), "repeat": r}
            return AScan(samples, self.fs, self.start_time, reached, {"source": "replay", **meta})
        ai, ci = self._fractional(pose, exact=False)
        a, c = round(ai), round(ci)
        r = int(self._rng.integers(self.n_repeats)) if self.mode == "random-repeat" else 0
        samples = self._block(p)[a, c, r]
        meta = {"source": "replay", "mode": self.mode, "grid_index": (p, a, c), "repeat": r}
        return AScan(samples, self.fs, self.start_time, self._grid_pose(p, a, c), meta)

    def _interpolated_samples(
        self, block: NDArray[np.float64], corners: list[tuple[int, int]], weights: list[float]
    ) -> tuple[NDArray[np.float64], int | None]:
        """``"interpolate"`` mode's A-scan (n_time,) from a position's ``block`` (see
        :meth:`_block`) and the bilinear ``corners``/``weights``; and the repeat drawn at
        the nearest corner (None with one repeat).  See the module docstring."""
        means = [block[a, c].mean(axis=0) for a, c in corners]
        samples = sum(w * m for w, m in zip(weights, means, strict=True))
        n = self.n_repeats
        if n == 1:
            return np.asarray(samples, dtype=np.float64), None
        k = int(np.argmax(weights))
        r = int(self._rng.integers(n))
        a, c = corners[k]
        scale = np.sqrt((n - sum(w * w for w in weights)) / (n - 1))
        return np.asarray(samples + scale * (block[a, c, r] - means[k]), dtype=np.float64), r

    # -- metrics ----------------------------------------------------------------------------
    def metric_grid(
        self, metric: Callable[[AScan], float], position: int = 0
    ) -> NDArray[np.float64]:
        """``metric`` of each recorded A-scan at position index ``position``, repeat-averaged.

        Returns
        -------
        values : shape ``(n_azimuth, n_coelevation)``; cached per (metric, position).
        """
        self._check_open()
        key = (metric, position)
        if key not in self._metric_cache:
            block = self._block(position)
            out = np.empty(block.shape[:2])
            for a in range(block.shape[0]):
                for c in range(block.shape[1]):
                    pose = self._grid_pose(position, a, c)
                    out[a, c] = np.mean(
                        [
                            float(metric(AScan(block[a, c, r], self.fs, self.start_time, pose)))
                            for r in range(block.shape[2])
                        ]
                    )
            self._metric_cache[key] = out
        return self._metric_cache[key]

    def recorded_setup(self) -> VirtualSetup | None:
        """The simulated setup the recording was made with, rebuilt from the configuration
        ``echocal record`` stores (``source_info["setup"]["config"]``; a setup file's
        relative paths resolved next to it): the ``twin`` of an objective on this
        recording, whose physics gives the lobe's shape.  None when the file stores no
        configuration, or one that no longer builds."""
        import warnings

        from echocal.errors import EchocalError
        from echocal.setups import SetupConfig, build_setup

        stored = self.source_info.get("setup")
        config = stored.get("config") if isinstance(stored, dict) else None
        if not isinstance(config, dict):
            return None
        # JSON stores an unbounded positioner axis as nulls: left out, it takes the default
        # (unbounded) again; limits do not shape the lobe
        axes = config.get("positioner")
        if isinstance(axes, dict):
            kept = {k: v for k, v in axes.items() if not (isinstance(v, list) and None in v)}
            config = {**config, "positioner": kept}
        name = stored.get("setup") if isinstance(stored, dict) else None
        base = Path(name).parent if isinstance(name, str) and name.endswith(".toml") else Path.cwd()
        try:
            with warnings.catch_warnings():  # the stored config lists every default field
                warnings.simplefilter("ignore")
                return build_setup(SetupConfig.model_validate(config), base_dir=base)
        except (EchocalError, ValueError):
            return None

    def grid_step(self, parameterization: str) -> float | None:
        """[deg] the largest step between neighbouring recorded orientations, in the angles
        of ``parameterization`` (``"azimuth-coelevation"`` or ``"tilt"``): below it the
        replay shows the recording's grid (facets, or steps in ``"nearest"`` mode), not the
        lobe.  None for a recording of a single orientation."""
        one_of("parameterization", parameterization, PARAMETERIZATIONS)
        az, co = np.meshgrid(self.azimuths, self.coelevations, indexing="ij")
        if parameterization == "tilt":
            az, co = orientation_to_tilt(az, co)
        angles = np.stack([az, co], axis=-1)  # (n_azimuth, n_coelevation, 2)
        steps = [np.hypot(*np.diff(angles, axis=k).reshape(-1, 2).T) for k in (0, 1)]
        return max((float(s.max()) for s in steps if s.size), default=None)

    def interpolated_metric(self, pose: Pose, metric: Callable[[AScan], float]) -> float:
        """Bilinear interpolation at ``pose`` of :meth:`metric_grid` (nearest position).

        The pose must lie within the recorded grid (no extrapolation); this does
        not count as a measurement and is the same in every ``mode``.
        """
        self._check_open()
        p = self._position_index(pose)
        ai, ci = self._fractional(pose, exact=True)
        grid = self.metric_grid(metric, p)
        corners, weights = _bilinear(ai, ci, self.azimuths.size, self.coelevations.size)
        return float(sum(w * grid[a, c] for (a, c), w in zip(corners, weights, strict=True)))

    def close(self) -> None:
        """Close the file; further measurements raise :class:`DataFileError`."""
        if not self._closed:
            self._closed = True
            self._ds.close()


def _bilinear(
    ai: float, ci: float, n_a: int, n_c: int
) -> tuple[list[tuple[int, int]], list[float]]:
    """Corners (a0,c0), (a1,c0), (a0,c1), (a1,c1) and their bilinear weights."""
    a0 = min(int(np.floor(ai)), max(n_a - 2, 0))
    c0 = min(int(np.floor(ci)), max(n_c - 2, 0))
    a1, c1 = min(a0 + 1, n_a - 1), min(c0 + 1, n_c - 1)
    u, v = float(np.clip(ai - a0, 0, 1)), float(np.clip(ci - c0, 0, 1))
    corners = [(a0, c0), (a1, c0), (a0, c1), (a1, c1)]
    weights = [(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v]
    return corners, weights


def _upgrade(ds: Any, file: Path) -> Any:
    """A ``replay/1`` file (before the NetCDF schema) read as ``replay/2``, with a warning
    that it has no checksums; any other file unchanged."""
    if format_version(ds) != 1:
        return ds
    import warnings

    warnings.warn(
        f"{file} is a replay/1 file without checksums (written before echocal's NetCDF "
        f"schema): a damaged sample would go unnoticed; `echocal convert {file} NEW.nc` "
        "rewrites it as replay/2",
        stacklevel=3,
    )
    attrs = {_V1_ATTRS.get(k, k): v for k, v in ds.attrs.items()}
    attrs["echocal_format"] = FORMAT
    ds = ds.assign_attrs(attrs)
    for k in _V1_ATTRS:
        ds.attrs.pop(k, None)
    for name, (unit, long_name) in VARIABLES.items():
        if name in ds.variables:
            if ds[name].attrs.get("units") in (None, "deg", unit):  # "deg" in replay/1
                ds[name].attrs["units"] = unit
            ds[name].attrs.setdefault("long_name", long_name)
    info = json.loads(str(ds.attrs.get("source_info", "{}")))
    ds.attrs["source"] = str(info.get("description", "unknown source"))
    return ds


def format_version(ds: Any) -> int:
    """The N of ``echocal_format = "replay/N"`` (0: not a replay file)."""
    from echocal.netcdf import format_version as version

    return version(ds, "replay")


def _validate(ds: Any, file: Path) -> None:
    """Check that ``ds`` is an echocal replay recording; DataFileError naming what is wrong."""
    fmt = ds.attrs.get("echocal_format")
    if fmt is None:
        raise DataFileError(
            f"{file} is not an echocal replay recording: attribute 'echocal_format' is missing"
        )
    if fmt != FORMAT:
        raise DataFileError(
            f"{file}: unsupported echocal_format {fmt!r}; this version reads {FORMAT!r}"
        )
    if "samples" not in ds.variables:
        raise DataFileError(f"{file}: variable 'samples' is missing")
    if "samples" in (ds.encoding.get("unchecked_variables") or ()):
        raise DataFileError(
            f"{file}: variable 'samples' has no Fletcher-32 checksum, so damage would go "
            "unnoticed; write replay files with echocal.measurement.save_recording (or "
            "`echocal record`)"
        )
    if tuple(ds["samples"].dims) != DIMS:
        raise DataFileError(
            f"{file}: variable 'samples' must have dims {DIMS}; got {tuple(ds['samples'].dims)}"
        )
    for name, unit in REQUIRED_COORDS.items():
        if name not in ds.variables:
            raise DataFileError(f"{file}: coordinate {name!r} is missing")
        got = ds[name].attrs.get("units")
        if got is None:
            raise DataFileError(f"{file}: coordinate {name!r} has no 'units' attribute")
        if got != unit:
            raise DataFileError(f"{file}: coordinate {name!r} must be in {unit!r}; got {got!r}")
    for name in REQUIRED_ATTRS:
        if name not in ds.attrs:
            raise DataFileError(f"{file}: attribute {name!r} is missing")
    try:
        fs = float(ds.attrs["sampling_rate_hz"])
        float(ds.attrs["start_time_s"])
        json.loads(ds.attrs["source_info"])
    except (TypeError, ValueError) as exc:
        raise DataFileError(
            f"{file}: malformed attribute (sampling_rate_hz, start_time_s or source_info): {exc}"
        ) from None
    if not fs > 0:
        raise DataFileError(f"{file}: attribute 'sampling_rate_hz' must be > 0 [Hz]; got {fs}")
    for axis in ("azimuth", "coelevation"):
        values = np.asarray(ds[axis].values, dtype=np.float64)
        if values.size == 0 or np.any(np.diff(values) <= 0) or not np.all(np.isfinite(values)):
            raise DataFileError(
                f"{file}: coordinate {axis!r} must be finite and strictly increasing"
            )


MAX_SAMPLE = 1e30
"""[a.u.] the largest sample magnitude a recording may hold: metrics square samples, so
beyond it an energy overflows (1e300² is inf) and every later number is meaningless."""


def _check_magnitudes(block: NDArray[np.float64], path: Any, p: int) -> None:
    """Refuse a position's A-scans ``block`` holding an infinite sample or one beyond
    :data:`MAX_SAMPLE` (NaN marks a missing A-scan and stays)."""
    with np.errstate(invalid="ignore"):
        bad = np.abs(block) > MAX_SAMPLE  # NaN compares False; inf is caught
    if not bad.any():
        return
    a, c, r, t = (int(v[0]) for v in np.nonzero(bad))
    raise DataFileError(
        f"{path}: variable 'samples' holds {int(bad.sum())} value(s) that are infinite or "
        f"beyond ±{MAX_SAMPLE:g} at position index {p} (first: azimuth index {a}, "
        f"coelevation index {c}, repeat {r}, sample {t}: {block[a, c, r, t]:g}); a receiver "
        "fault or a damaged file: re-record it, or set those A-scans to NaN (missing)"
    )
