"""3D view of the probe against the part: specimen, transducer and a subsample of rays.

Only reads data; returns a matplotlib Figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection
from numpy.typing import NDArray

from echocal.echo import WAVE_MODEL, ray_echoes
from echocal.geometry import Pose, poses_to_arrays
from echocal.plots._figure import new_figure
from echocal.specimen import Cylinder, FinitePlane, Specimen, Sphere, TriangleMesh
from echocal.transducer import Transducer

__all__ = ["scene_figure"]

_MM = 1e3  # plot in millimetres
_FACE = (0.62, 0.68, 0.75, 0.45)
_EDGE = (0.25, 0.3, 0.38, 0.9)
_NORMAL = "magenta"  # the surface normal: apart from the pose colours, the part and the axis


def _shape_polygons(shape: object, resolution: int = 32) -> list[NDArray[np.float64]]:
    """Polygons [m] approximating one shape's surface, for drawing."""
    if isinstance(shape, FinitePlane):
        return [shape.corners()]
    if isinstance(shape, TriangleMesh):
        return list(shape.vertices[shape.faces])
    if isinstance(shape, Sphere):
        u, v = np.meshgrid(
            np.linspace(0, 2 * np.pi, resolution), np.linspace(0, np.pi, resolution // 2)
        )
        pts = shape.center + shape.radius * np.stack(
            [np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], axis=-1
        )
        return _grid_quads(pts)
    if isinstance(shape, Cylinder):
        axis = shape.axis
        helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
        e1 = np.cross(axis, helper)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis, e1)
        u, s = np.meshgrid(
            np.linspace(0, 2 * np.pi, resolution), np.linspace(-0.5, 0.5, 2) * shape.length
        )
        ring = np.cos(u)[..., None] * e1 + np.sin(u)[..., None] * e2
        pts = shape.center + shape.radius * ring + s[..., None] * axis
        return _grid_quads(pts)
    return []


def _grid_quads(pts: NDArray[np.float64]) -> list[NDArray[np.float64]]:
    quads = np.stack([pts[:-1, :-1], pts[:-1, 1:], pts[1:, 1:], pts[1:, :-1]], axis=2)
    return list(quads.reshape(-1, 4, 3))


def _aperture_outline(transducer: Transducer, pose: Pose) -> NDArray[np.float64]:
    """Outline [m] of the sensor area at ``pose``, shape (k, 3)."""
    frame = pose.frame
    w, h = transducer.width / 2, transducer.height / 2
    if transducer.aperture == "circular":
        t = np.linspace(0, 2 * np.pi, 48)
        local = np.stack([w * np.cos(t), h * np.sin(t)], axis=1)
    else:
        local = np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]])
    return pose.position + local @ frame[:, :2].T


def scene_figure(
    specimen: Specimen,
    transducer: Transducer,
    poses: Sequence[Pose],
    *,
    n_rays: int = 60,
    reflection: str = "lambertian",
    title: str | None = None,
) -> Figure:
    """Specimen, transducer(s) at ``poses`` and up to ``n_rays`` rays per pose with their hits.

    Rays that hit are drawn from the pixel to the hit point, coloured by their
    echo amplitude a·β (on a ``wave`` setup, its ray stage's Lambertian amplitude);
    misses are drawn short and grey.  Each pose's beam axis is drawn (black, dashed) to
    where it meets the part, with the part's surface normal there (magenta arrow): the
    angle between them is what a calibration removes.  Axes in millimetres.
    """
    fig = new_figure(figsize=(8, 6.5), constrained_layout=True)
    ax = fig.add_subplot(projection="3d", computed_zorder=False)  # part, rays, then axes
    polygons = [p for shape in specimen for p in _shape_polygons(shape)]
    if polygons:
        ax.add_collection3d(
            Poly3DCollection(
                [p * _MM for p in polygons], facecolors=_FACE, edgecolors=_EDGE, linewidths=0.3
            )
        )
    positions, frames = poses_to_arrays(list(poses))
    # the wave model finds what the sound reaches with the same rays (its echo transfer
    # is not per ray): shade them as its ray stage does, Lambertian
    model = "lambertian" if reflection == WAVE_MODEL else reflection
    echoes = ray_echoes(transducer, specimen, positions, frames, model=model)
    rays = transducer.rays(positions, frames)
    pick = np.unique(np.linspace(0, transducer.n_rays - 1, min(n_rays, transducer.n_rays)).round())
    pick = pick.astype(int)
    colors = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange")
    extent = list(polygons)  # [m] everything drawn, to frame the axes
    for k, pose in enumerate(poses):
        color = colors[k % len(colors)]
        outline = _aperture_outline(transducer, pose)
        ax.plot(*(outline * _MM).T, color=color, lw=2.0, label=_pose_label(pose))
        origin = rays.origins[k, pick]
        hit_point = echoes.hits.point[k, pick]
        hit = np.isfinite(echoes.hits.distance[k, pick])
        end = np.where(hit[:, None], hit_point, origin + 0.3 * pose.z * rays.directions[k, pick])
        segments = np.stack([origin, end], axis=1) * _MM
        amplitude = echoes.amplitude[k, pick]
        shade = np.where(hit, 0.25 + 0.75 * amplitude / max(amplitude.max(), 1e-12), 0.15)
        ax.add_collection3d(
            Line3DCollection(segments, colors=[(*_rgb(color), s) for s in shade], linewidths=0.7)
        )
        ax.scatter(*(hit_point[hit] * _MM).T, s=4, color=color)
        extent += [outline, end, *_beam_and_normal(ax, specimen, pose, first=k == 0)]
    points = np.concatenate(extent) * _MM
    _equal_axes(ax, points)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or f"{specimen.name}: probe and {len(pick)} of {transducer.n_rays} rays")
    return fig


def _beam_and_normal(
    ax: Any, specimen: Specimen, pose: Pose, *, first: bool
) -> list[NDArray[np.float64]]:
    """Draw the beam axis (black, dashed) from the probe to where it meets the part and the part's
    surface normal there (a magenta arrow as long as the water path); a beam that misses is
    drawn as long as the probe's height.  Returns the points drawn [m], for framing."""
    from echocal.specimen.casting import cast

    start, beam = pose.position, pose.beam_direction
    hits = cast(specimen, start[None, :], beam[None, :])
    hit = bool(hits.hit[0])
    end = hits.point[0] if hit else start + max(abs(pose.z), 1e-3) * beam
    ax.plot(
        *(np.stack([start, end]) * _MM).T,
        color="k",
        ls=(0, (4, 2)),
        lw=1.8,
        zorder=7,  # over the normal: where they coincide, the dashes show both
        label="beam axis" if first else None,
    )
    if not hit:
        return [end[None, :]]
    tip = end + float(hits.distance[0]) * hits.normal[0]
    ax.quiver(
        *(end * _MM),
        *((tip - end) * _MM),
        color=_NORMAL,
        lw=2.0,
        arrow_length_ratio=0.15,
        zorder=6,
    )
    if first:
        ax.plot([], [], color=_NORMAL, lw=2.0, label="surface normal at the beam's hit")
    return [end[None, :], tip[None, :]]


def _pose_label(pose: Pose) -> str:
    return (
        f"({pose.x * _MM:.1f}, {pose.y * _MM:.1f}, {pose.z * _MM:.1f}) mm, "
        f"az {pose.azimuth:.1f}°, coel {pose.coelevation:.1f}°"
    )


def _rgb(name: str) -> tuple[float, float, float]:
    from matplotlib.colors import to_rgb

    return to_rgb(name)


def _equal_axes(ax: object, points: NDArray[np.float64]) -> None:
    points = points[np.all(np.isfinite(points), axis=1)]
    centre = (points.max(axis=0) + points.min(axis=0)) / 2
    half = max(float((points.max(axis=0) - points.min(axis=0)).max()) / 2, 1.0)
    ax.set_xlim(centre[0] - half, centre[0] + half)  # type: ignore[attr-defined]
    ax.set_ylim(centre[1] - half, centre[1] + half)  # type: ignore[attr-defined]
    ax.set_zlim(centre[2] - half, centre[2] + half)  # type: ignore[attr-defined]
    ax.set_box_aspect((1.0, 1.0, 1.0))  # type: ignore[attr-defined]
