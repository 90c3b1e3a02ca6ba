"""The recording's grid seen by ``echocal calibrate --replay``: which position to use,
which orientations were recorded, the largest tilt box inside them, the grid's centre and
the recording's own metric map (the background of the path plot).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from echocal.cli._calibrate_common import _parse_position


def replay_position(recording: Any, position: str | None) -> tuple[int, Any]:
    """Index and [m] of the recorded position to calibrate at: ``--position`` (which must be
    a recorded one) or, when omitted, the recording's only position."""
    from echocal.errors import EchocalValueError, LimitError

    recorded = recording.positions
    listed = "; ".join(f"({mm(p)})" for p in recorded[:8])
    if len(recorded) > 8:
        listed += f"; ... ({len(recorded)} in all)"
    if position is None:
        if len(recorded) > 1:
            raise EchocalValueError(
                f"{recording.path} holds {len(recorded)} positions, {listed} mm: choose one "
                "with --position X,Y,Z"
            )
        return 0, recorded[0]
    where = _parse_position(position)
    distance = np.linalg.norm(recorded - where, axis=1)
    index = int(np.argmin(distance))
    if distance[index] > recording.position_tolerance:
        raise LimitError(
            f"--position ({mm(where)}) mm is not a position of {recording.path}: it holds "
            f"{listed} mm (tolerance {1e3 * recording.position_tolerance:g} mm)"
        )
    return index, recorded[index]


def in_recording(recording: Any, azimuth: Any, coelevation: Any) -> Any:
    """Which orientations [deg] lie on a recording's grid (an azimuth also ±360°)."""
    az, coel = recording.azimuths, recording.coelevations
    inside = np.zeros(np.broadcast(azimuth, coelevation).shape, dtype=bool)
    for shift in (0.0, -360.0, 360.0):
        inside |= (az[0] <= azimuth + shift) & (azimuth + shift <= az[-1])
    return inside & (coel[0] <= coelevation) & (coelevation <= coel[-1])


def tilt_extent(recording: Any) -> Any:
    """[deg] (2, 2): the tilt box around a recording's grid (its grid sampled densely)."""
    from echocal.geometry import convert_angles

    az, coel = recording.azimuths, recording.coelevations
    a, c = np.meshgrid(
        np.linspace(az[0], az[-1], 101), np.linspace(coel[0], coel[-1], 101), indexing="ij"
    )
    tx, ty = convert_angles(a, c, "azimuth-coelevation", "tilt")
    return np.array([[tx.min(), tx.max()], [ty.min(), ty.max()]])


def tilt_bounds_in_recording(recording: Any, start: tuple[float, float]) -> Any:
    """[deg] (2, 2): the largest tilt box around ``start`` whose every orientation the
    recording holds.

    The grid is in (azimuth, co-elevation): in tilts it is a curved region.  On a 161 × 161
    lattice over that region, less one lattice step all round (its curved edges bulge
    between lattice points), the box of largest area that contains ``start`` is found; it
    is shrunk further, a step at a time, should any of 400 points along each of its edges
    lie off the grid.
    """
    from scipy.ndimage import binary_erosion

    from echocal.errors import LimitError
    from echocal.geometry import convert_angles

    def inside(tx: Any, ty: Any) -> Any:
        return in_recording(recording, *convert_angles(tx, ty, "tilt", "azimuth-coelevation"))

    extent = tilt_extent(recording)
    ga, gb = (np.linspace(lo, hi, 161) for lo, hi in extent)
    ok = binary_erosion(inside(ga[:, None], gb[None, :]), np.ones((3, 3)), border_value=0)
    # the lattice cell holding start: rows i0..i1 (tilt_x), columns j0..j1 (tilt_y)
    i0 = int(np.clip(np.searchsorted(ga, start[0]) - 1, 0, ga.size - 2))
    j0 = int(np.clip(np.searchsorted(gb, start[1]) - 1, 0, gb.size - 2))
    i1, j1 = i0 + 1, j0 + 1
    covered = (
        f"it covers azimuth [{recording.azimuths[0]:g}, {recording.azimuths[-1]:g}] and "
        f"co-elevation [{recording.coelevations[0]:g}, {recording.coelevations[-1]:g}] deg, "
        f"tilt_x [{extent[0, 0]:.3g}, {extent[0, 1]:.3g}], tilt_y [{extent[1, 0]:.3g}, "
        f"{extent[1, 1]:.3g}] deg"
    )
    at_edge = (
        f"--x0 (tilt_x={start[0]:g}, tilt_y={start[1]:g}) deg lies at the edge of "
        f"{recording.path}: start farther inside ({covered}), or calibrate in its own "
        "angles (--parameterization azimuth-coelevation)"
    )
    if not bool(inside(*start)):
        raise LimitError(
            f"--x0 (tilt_x={start[0]:g}, tilt_y={start[1]:g}) deg is not an orientation of "
            f"{recording.path}: {covered}"
        )
    if not ok[i0 : i1 + 1, j0 : j1 + 1].all():
        raise LimitError(at_edge)
    box, area = (i0, i1, j0, j1), 0
    rows = ok[i1].copy()
    for lo in range(i0, -1, -1):  # tilt_x rows lo..hi around the cell; a tilt_y run through it
        rows &= ok[lo]
        if not rows[j0 : j1 + 1].all():
            break
        cols = rows.copy()
        for hi in range(i1, ok.shape[0]):
            cols &= ok[hi]
            if not cols[j0 : j1 + 1].all():
                break
            gaps = np.flatnonzero(~cols)
            k = int(np.searchsorted(gaps, j0))
            left = int(gaps[k - 1]) + 1 if k > 0 else 0
            right = int(gaps[k]) - 1 if k < gaps.size else ok.shape[1] - 1
            if (hi - lo) * (right - left) > area:
                box, area = (lo, hi, left, right), (hi - lo) * (right - left)
    edge = np.linspace(0.0, 1.0, 400)
    for shrink in range(5):
        lo_a, hi_a, lo_b, hi_b = box[0] + shrink, box[1] - shrink, box[2] + shrink, box[3] - shrink
        if lo_a >= hi_a or lo_b >= hi_b:
            break
        bounds = np.array([[ga[lo_a], ga[hi_a]], [gb[lo_b], gb[hi_b]]])
        (a0, a1), (b0, b1) = bounds
        ring_a = np.concatenate([a0 + edge * (a1 - a0)] * 2 + [np.full(400, a0), np.full(400, a1)])
        ring_b = np.concatenate([np.full(400, b0), np.full(400, b1)] + [b0 + edge * (b1 - b0)] * 2)
        if inside(ring_a, ring_b).all():
            if not (a0 <= start[0] <= a1 and b0 <= start[1] <= b1):
                raise LimitError(at_edge)
            return bounds
    raise LimitError(
        f"{recording.path} is too narrow around --x0 for a calibration in tilts: {covered}; "
        "calibrate in its own angles (--parameterization azimuth-coelevation)"
    )


def grid_centre(recording: Any, parameterization: str) -> tuple[float, float]:
    """[deg] the centre of a recording's grid in ``parameterization`` (the default x0)."""
    from echocal.geometry import convert_angles

    az, coel = recording.azimuths, recording.coelevations
    centre = convert_angles(
        0.5 * (az[0] + az[-1]),
        0.5 * (coel[0] + coel[-1]),
        "azimuth-coelevation",
        parameterization,
    )
    return float(centre[0]), float(centre[1])


class RecordingMap:
    """A recording's own metric at one position, repeat-averaged (no measurement counted):
    its best grid pose, its value at given orientations, and the path plot's map."""

    def __init__(
        self,
        recording: Any,
        index: int,
        pulse: Any,
        metric: str,
        parameterization: str,
        gate: Any = None,
    ) -> None:
        from functools import partial

        from echocal.geometry import convert_angles
        from echocal.measurement.objective import ascan_metric

        self.recording, self.parameterization = recording, parameterization
        self.position = recording.positions[index]
        # one object: cached; inside the calibration's gate (None: the whole recording)
        self.metric = partial(ascan_metric, metric=metric, pulse=pulse, gate=gate)
        self.values = recording.metric_grid(self.metric, index)  # (n_azimuth, n_coelevation)
        finite = np.isfinite(self.values)
        self.peak = float(np.max(self.values[finite])) if finite.any() else float("nan")
        self.best: Any = None
        if finite.any():
            a, c = np.unravel_index(np.argmax(np.where(finite, self.values, -np.inf)), finite.shape)
            best = convert_angles(
                recording.azimuths[a],
                recording.coelevations[c],
                "azimuth-coelevation",
                parameterization,
            )
            self.best = np.array(best, dtype=float)

    def at(self, points: Any) -> Any:
        """The recording's metric interpolated at orientations ``points`` [deg], shape (k, 2);
        NaN off the grid."""
        from echocal.errors import LimitError
        from echocal.geometry import pose_from_angles

        out = np.full(len(points), np.nan)
        for k, (a, b) in enumerate(points):
            pose = pose_from_angles(self.position, a, b, self.parameterization)
            try:
                out[k] = self.recording.interpolated_metric(pose, self.metric)
            except LimitError:
                continue
        return out

    def cost_map(self) -> Any:
        """The path plot's background: the grid itself in (azimuth, co-elevation), or the
        grid interpolated onto a 81 × 81 tilt lattice over its extent (NaN off the grid);
        None for a grid with a single azimuth or co-elevation."""
        from echocal.calibrate.objective import PARAMETERIZATIONS
        from echocal.evaluation import CostMap

        names = PARAMETERIZATIONS[self.parameterization]
        az, coel = self.recording.azimuths, self.recording.coelevations
        if az.size < 2 or coel.size < 2:
            return None
        if self.parameterization == "azimuth-coelevation":
            return CostMap(a=az, b=coel, values=self.values, names=names)
        (a0, a1), (b0, b1) = tilt_extent(self.recording)
        a, b = np.linspace(a0, a1, 81), np.linspace(b0, b1, 81)
        grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
        return CostMap(a=a, b=b, values=self.at(grid).reshape(81, 81), names=names)


def mm(point: Any) -> str:
    """A position [m] as ``"x, y, z"`` in mm."""
    return ", ".join(f"{1e3 * float(v):g}" for v in point)
