"""Where a blind search for the echo looks: the hexagonal lattice around the start,
ring by ring, and beyond a fine radius either circles whose spacing grows with the distance
or coarse-to-fine passes of hexagonal lattices (used by
:class:`~echocal.calibrate.acquisition.Acquisition`).  Angles in degrees, shapes ``(k, 2)``."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from echocal.calibrate._fd import FloatArray

__all__ = ["hex_spiral", "search_rings"]


def hex_spiral(center: FloatArray, spacing: float, n_rings: int) -> list[FloatArray]:
    """Rings of a hexagonal lattice around ``center`` [deg]: ring 0 (1 point), ring k (6k).

    Returns a list of arrays of shape (6k, 2) (ring 0: (1, 2)), ordered by angle.
    """
    rings = [center[None, :].copy()]
    corners = np.array([[np.cos(a), np.sin(a)] for a in np.arange(7) * np.pi / 3.0])
    for k in range(1, n_rings + 1):
        pts = []
        for side in range(6):
            a, b = corners[side] * k, corners[side + 1] * k
            for j in range(k):
                pts.append(a + (b - a) * j / k)
        rings.append(center[None, :] + spacing * np.array(pts))
    return rings


def search_rings(
    center: FloatArray,
    spacing: float,
    max_radius: float,
    *,
    fine_radius: float = np.inf,
    growth: float = 0.0,
    max_spacing: float | None = None,
    passes: Sequence[float] = (),
) -> list[FloatArray]:
    """Search rings around ``center`` [deg]: the hexagonal lattice of ``spacing`` out to
    ``fine_radius``, then (coarse-to-the-outside) circles whose point spacing s and
    circle spacing (√3/2)·s grow with the radius r as s = ``max(spacing, growth · r)``,
    capped at ``max_spacing`` — the area a measurement must cover grows with the area to
    search.  Consecutive circles carry different point counts, so they are only partly
    staggered: every point of the disc lies within ≈ 0.66 s of a search point (measured;
    a true hexagonal lattice would give s/√3 = 0.58 s).

    ``passes`` [deg]: when given, the search beyond ``fine_radius`` is instead a pass
    per spacing s, coarse to fine, each the hexagonal lattice of spacing s around
    ``center`` (every point of the disc within s/√3 of one of its points; the points
    inside the fine lattice's hexagon and those farther than ``max_radius`` + s/√3 left
    out, as are the points within s/4 of a point searched before — so after each pass
    no point of the disc is farther than s/√3 + s/4 ≈ 0.83 s from a search point, and
    most are within s/√3).  Each pass's lattice is turned by 30° from the next finer
    one's, so a pass √3 times coarser than the next is a part of it: the finer pass
    then spends nothing on the points the coarser one measured.  A coarse first
    pass finds a strong echo far away in few measurements; when it misses, a weaker echo
    is seen from less far, and the next pass searches again, more densely.

    Returns a list of arrays of shape (k_i, 2) (the first is ``center``): the rings in
    the order they are searched.  Without ``passes``, the last circle is the first that
    lies beyond ``max_radius`` by no more than s/√3, which leaves no point of the disc
    of ``max_radius`` farther than ≈ 0.66 s from a search point.
    """
    n_fine = int(np.ceil(min(fine_radius, max_radius) / spacing)) if np.isfinite(fine_radius) else 0
    if not np.isfinite(fine_radius) or (growth <= 0.0 and not passes):
        return hex_spiral(center, spacing, max(1, int(np.ceil(max_radius / spacing))))
    rings = hex_spiral(center, spacing, max(1, n_fine))
    inner = max(1, n_fine) * spacing
    if not passes:
        cap = np.inf if max_spacing is None else max_spacing
        return rings + _circles(
            center, inner, max_radius, lambda r: min(max(spacing, growth * r), cap)
        )
    from scipy.spatial import cKDTree

    for k, step in enumerate(passes if inner < max_radius else ()):  # else: all fine
        searched = cKDTree(np.vstack(rings))
        turn = np.pi / 6.0 * (len(passes) - 1 - k)  # a pass √3 coarser is part of the next
        for ring in _lattice(center, inner, max_radius, step, turn):
            new = ring[searched.query(ring)[0] > _PASS_SKIP * step]
            if len(new):
                rings.append(new)
    return rings


_PASS_SKIP = 0.25
"""A point of a later pass this close to a point already searched (× its spacing) is
left out."""


def _lattice(
    center: FloatArray, inner: float, max_radius: float, step: float, turn: float = 0.0
) -> list[FloatArray]:
    """The rings of the hexagonal lattice of spacing ``step`` around ``center`` [deg],
    turned by ``turn`` [rad], whose points lie outside the hexagon of radius ``inner`` and
    within ``max_radius`` plus their reach (step/√3, the farthest a point of the plane is
    from the lattice): each ring an array of shape (k, 2), nearest ring first."""
    reach = step / np.sqrt(3.0)
    n_rings = int((max_radius + reach) / (0.5 * np.sqrt(3.0) * step))  # ring k: ≥ (√3/2)·k·s
    rotation = np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])
    out = []
    for ring in hex_spiral(np.zeros(2), step, n_rings)[1:]:
        ring = ring @ rotation
        r = np.hypot(*ring.T)
        keep = (r > 0.5 * np.sqrt(3.0) * inner) & (r - reach <= max_radius)
        if keep.any():
            out.append(center[None, :] + ring[keep])
    return out


def _circles(
    center: FloatArray, inner: float, max_radius: float, spacing_at: Callable[[float], float]
) -> list[FloatArray]:
    """Circles around ``center`` beyond radius ``inner`` [deg] to ``max_radius``: point
    spacing s = ``spacing_at(r)`` at radius r, circles (√3/2)·s apart, every other
    circle turned by half a step; each an array of shape (k, 2)."""
    circles: list[FloatArray] = []
    r = inner
    while True:
        s = spacing_at(r)
        r += 0.5 * np.sqrt(3.0) * s
        if r - s / np.sqrt(3.0) > max_radius + 1e-9:  # the previous circle reached the edge
            return circles
        n = int(np.ceil(2.0 * np.pi * r / s))
        ang = (np.arange(n) + 0.5 * (len(circles) % 2)) * 2.0 * np.pi / n
        circles.append(center[None, :] + r * np.stack([np.cos(ang), np.sin(ang)], axis=1))
