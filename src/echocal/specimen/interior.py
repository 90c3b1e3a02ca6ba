"""The inside of a solid specimen: its thickness and the reflectors within it.

A plate of a given ``thickness`` below its front face (a :class:`FinitePlane`, the part's
only shape) has a back wall parallel to the front, at depth T along −n, and may hold
reflectors (flaws).  A :class:`Sphere` with a thickness is a spherical shell and a
:class:`Cylinder` (its outer surface) a pipe: the back wall is the concentric inner
surface of radius R − T (no flaws).  A plate may be a stack of :class:`Layer` s (each a
material and a thickness, top first; the thickness is their sum), its flaws in any layer.
The reflector kinds:

=====================  =====================================================================
kind                   geometry
=====================  =====================================================================
``side-drilled-hole``  a cylindrical hole of ``diameter`` and ``length`` along ``axis``
                       (parallel to the front face), centred at ``position``
``flat-bottom-hole``   the flat bottom (a disc of ``diameter``) of a hole drilled from the
                       back wall towards the probe; ``position`` is the disc's centre
``pore``               a spherical void of ``diameter`` centred at ``position``
=====================  =====================================================================

Each flaw offers its surface as samples (point, outward normal, area) for the physics
(:mod:`echocal.wave.interior`).  Everything here is geometry; no physics.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal.errors import GeometryError
from echocal.materials import Material
from echocal.specimen.cylinder import Cylinder
from echocal.specimen.plane import FinitePlane
from echocal.specimen.sphere import Sphere

__all__ = [
    "FLAW_KINDS",
    "INTERIOR_SHAPES",
    "MAX_ECHO_PATHS",
    "MAX_SHEAR_LEGS",
    "Flaw",
    "Interior",
    "Layer",
    "SurfaceSamples",
    "echo_routes",
    "leg_modes",
    "turn_sequences",
]

FloatArray = NDArray[np.float64]

FLAW_KINDS = ("side-drilled-hole", "flat-bottom-hole", "pore")
"""Reflector kinds a specimen's interior can hold."""

INTERIOR_SHAPES = (
    'an interior needs one plane (a plate\'s front face, e.g. builtin = "flat-plate"), one '
    'sphere (a spherical shell\'s outer face) or one cylinder with surface = "outside" (a '
    "pipe's outer face); meshes and bores are not modelled"
)
"""Why a specimen cannot have an interior: the one sentence every refusal shares."""

MAX_BACK_WALL_ECHOES = 20
"""The largest back-wall multiple order a setup may ask for."""

MAX_ECHO_PATHS = 800
"""The most echo paths a layered plate may list (the count grows as N^(2M−1)); two layers
at order 3 with two shear legs list 732."""
MAX_SHEAR_LEGS = 2
"""The most mode-converted (shear) legs an echo path may have."""


def turn_sequences(n_layers: int, order: int) -> list[tuple[int, ...]]:
    """The interfaces at which each echo path through ``n_layers`` layers turns, every
    path with at most 2·order − 1 reflections, shortest first.  Interface 0 is the front
    face, i the bottom of layer i.  Going down the wave turns at a deeper interface, going
    up at a shallower one (0, the front face seen from below, included).

    Raises :class:`GeometryError` beyond :data:`MAX_ECHO_PATHS` paths."""
    out: list[tuple[int, ...]] = []
    frontier: list[tuple[int, ...]] = [(k,) for k in range(1, n_layers + 1)]
    while frontier:
        out.extend(frontier)
        grown: list[tuple[int, ...]] = []
        for turns in frontier:
            if len(turns) + 2 > 2 * order - 1:
                continue
            for up in range(turns[-1]):
                grown.extend((*turns, up, down) for down in range(up + 1, n_layers + 1))
        frontier = grown
        if len(out) + len(frontier) > MAX_ECHO_PATHS:
            raise GeometryError(
                f"specimen.back_wall_echoes: order {order} over {n_layers} layers gives more "
                f"than {MAX_ECHO_PATHS} echo paths; lower the order"
            )
    return out


def leg_modes(turns: tuple[int, ...], shear_legs: int) -> list[str]:
    """The wave modes of the legs of the path that turns at ``turns``: every string of
    ``"L"`` (longitudinal) and ``"S"`` (shear) with at most ``shear_legs`` S, the
    all-longitudinal one first.  The path crosses turns[0] + Σ|Δturns| + turns[−1]
    layers."""
    n_legs = turns[0] + sum(abs(b - a) for a, b in itertools.pairwise(turns))
    n_legs += turns[-1]
    out = []
    for k in range(min(shear_legs, n_legs) + 1):
        for shear in itertools.combinations(range(n_legs), k):
            out.append("".join("S" if i in shear else "L" for i in range(n_legs)))
    return out


def echo_routes(n_layers: int, order: int, shear_legs: int) -> list[tuple[tuple[int, ...], str]]:
    """Every echo path's turns (:func:`turn_sequences`) with each of its legs' modes
    (:func:`leg_modes`).  Raises :class:`GeometryError` beyond :data:`MAX_ECHO_PATHS`."""
    out = [
        (turns, modes)
        for turns in turn_sequences(n_layers, order)
        for modes in leg_modes(turns, shear_legs)
    ]
    if len(out) > MAX_ECHO_PATHS:
        raise GeometryError(
            f"specimen.shear_legs: {shear_legs} shear legs at order {order} over {n_layers} "
            f"layers give {len(out)} echo paths, more than {MAX_ECHO_PATHS}; lower either"
        )
    return out


@dataclass(frozen=True)
class SurfaceSamples:
    """A reflector's surface as samples, world frame.

    Attributes
    ----------
    points : [m] sample positions, shape ``(3, n)``.
    normals : outward unit normals of the reflector (out of the void, into the solid),
        shape ``(3, n)``.
    areas : [m²] patch areas, shape ``(n,)``.
    """

    points: FloatArray
    normals: FloatArray
    areas: FloatArray


def _unit(name: str, value: ArrayLike) -> FloatArray:
    v = np.asarray(value, dtype=np.float64).reshape(3)
    norm = float(np.linalg.norm(v))
    if not math.isfinite(norm) or norm == 0.0:
        raise GeometryError(f"{name}: must be a non-zero direction; got {v.tolist()}")
    return v / norm


def _perpendicular_basis(axis: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Two unit vectors completing ``axis`` to a right-handed orthonormal frame."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


@dataclass(frozen=True)
class Flaw:
    """One reflector inside the part.

    Parameters
    ----------
    name : label of its echo (``simulate --json``'s ``echoes``, gates).
    kind : one of :data:`FLAW_KINDS`.
    position : [m] centre, shape ``(3,)`` (see the module's table).
    diameter : [m] hole or pore diameter, > 0.
    length : [m] a side-drilled hole's length (None for other kinds).
    axis : a side-drilled hole's axis direction, shape ``(3,)``; the default is y.
    """

    name: str
    kind: str
    position: FloatArray
    diameter: float
    length: float | None = None
    axis: FloatArray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))

    def __post_init__(self) -> None:
        where = f"specimen.flaws.{self.name}"
        if self.kind not in FLAW_KINDS:
            raise GeometryError(
                f"{where}.kind: unknown flaw kind {self.kind!r}; choose one of: "
                f"{', '.join(FLAW_KINDS)}"
            )
        position = np.asarray(self.position, dtype=np.float64).reshape(3)
        if not np.all(np.isfinite(position)):
            raise GeometryError(f"{where}.position: must be finite; got {position.tolist()}")
        object.__setattr__(self, "position", position)
        if not (math.isfinite(self.diameter) and self.diameter > 0.0):
            raise GeometryError(f"{where}.diameter: must be > 0; got {self.diameter!r}")
        if self.kind == "side-drilled-hole":
            if self.length is None or not (math.isfinite(self.length) and self.length > 0.0):
                raise GeometryError(
                    f"{where}.length: a side-drilled hole needs a length > 0; got {self.length!r}"
                )
        object.__setattr__(self, "axis", _unit(f"{where}.axis", self.axis))

    @property
    def radius(self) -> float:
        """[m] half the diameter."""
        return 0.5 * self.diameter

    def depth_range(self, front: FinitePlane) -> tuple[float, float]:
        """[m] the shallowest and deepest point of the flaw below the front face."""
        depth = float(np.dot(front.center - self.position, front.normal))
        if self.kind == "flat-bottom-hole":
            return depth, depth
        if self.kind == "pore":
            return depth - self.radius, depth + self.radius
        assert self.length is not None
        along = abs(float(np.dot(self.axis, front.normal))) * 0.5 * self.length
        across = math.sqrt(max(0.0, 1.0 - float(np.dot(self.axis, front.normal)) ** 2))
        extent = along + across * self.radius
        return depth - extent, depth + extent

    def surface_samples(self, spacing: float, front_normal: FloatArray) -> SurfaceSamples:
        """The reflector's surface, about ``spacing`` [m] apart (at least 8 per diameter).

        ``front_normal`` is the front face's unit normal (towards the probe): a flat-bottom
        hole's disc faces it."""
        step = min(spacing, self.diameter / 8.0)
        if self.kind == "pore":
            return _sphere_samples(self.position, self.radius, step)
        if self.kind == "flat-bottom-hole":
            return _disc_samples(self.position, self.radius, front_normal, step)
        assert self.length is not None
        return _cylinder_samples(self.position, self.radius, self.length, self.axis, step)

    def silhouette(self, spacing: float, front_normal: FloatArray) -> SurfaceSamples:
        """The flaw's shadow seen along ``front_normal`` (towards the probe), as samples in
        the plane through its centre facing the probe, about ``spacing`` [m] apart: a disc
        of its diameter (flat-bottom hole, pore) or the rectangle of a side-drilled hole
        (its diameter × its length's extent across the normal)."""
        step = min(spacing, self.diameter / 8.0)
        if self.kind != "side-drilled-hole":
            return _disc_samples(self.position, self.radius, front_normal, step)
        assert self.length is not None
        along = self.axis - front_normal * float(self.axis @ front_normal)
        extent = self.length * float(np.linalg.norm(along))
        along = along / max(float(np.linalg.norm(along)), 1e-12)
        across = np.cross(front_normal, along)
        n_along = max(2, math.ceil(extent / step))
        n_across = max(2, math.ceil(self.diameter / step))
        s = ((np.arange(n_along) + 0.5) / n_along - 0.5) * extent
        w = ((np.arange(n_across) + 0.5) / n_across - 0.5) * self.diameter
        ss, ww = (g.ravel() for g in np.meshgrid(s, w))
        points = self.position[:, None] + along[:, None] * ss + across[:, None] * ww
        areas = np.full(ss.size, extent * self.diameter / ss.size)
        return SurfaceSamples(points, np.repeat(front_normal[:, None], ss.size, axis=1), areas)


def _sphere_samples(centre: FloatArray, radius: float, step: float) -> SurfaceSamples:
    """Equal-area samples of a sphere (a Fibonacci lattice), outward normals."""
    n = max(32, math.ceil(4.0 * math.pi * radius**2 / step**2))
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = math.pi * (1.0 + math.sqrt(5.0)) * k
    rho = np.sqrt(1.0 - z * z)
    normals = np.stack([rho * np.cos(phi), rho * np.sin(phi), z])
    areas = np.full(n, 4.0 * math.pi * radius**2 / n)
    return SurfaceSamples(centre[:, None] + radius * normals, normals, areas)


def _disc_samples(
    centre: FloatArray, radius: float, normal: FloatArray, step: float
) -> SurfaceSamples:
    """A disc facing ``normal``: a square grid cut to the disc (cell area each)."""
    u, v = _perpendicular_basis(normal)
    n_side = max(8, math.ceil(2.0 * radius / step))
    g = (np.arange(n_side) + 0.5) / n_side * 2.0 * radius - radius
    gu, gv = np.meshgrid(g, g)
    keep = np.hypot(gu, gv).ravel() <= radius
    gu, gv = gu.ravel()[keep], gv.ravel()[keep]
    points = centre[:, None] + u[:, None] * gu + v[:, None] * gv
    # the cells' total area is scaled to the disc's exactly
    areas = np.full(gu.size, math.pi * radius**2 / gu.size)
    normals = np.repeat(normal[:, None], gu.size, axis=1)
    return SurfaceSamples(points, normals, areas)


def _cylinder_samples(
    centre: FloatArray, radius: float, length: float, axis: FloatArray, step: float
) -> SurfaceSamples:
    """The mantle of a cylinder (no end caps: a side-drilled hole runs through)."""
    u, v = _perpendicular_basis(axis)
    n_around = max(16, math.ceil(2.0 * math.pi * radius / step))
    n_along = max(2, math.ceil(length / step))
    phi = 2.0 * math.pi * (np.arange(n_around) + 0.5) / n_around
    s = (np.arange(n_along) + 0.5) / n_along * length - 0.5 * length
    pp, ss = np.meshgrid(phi, s)
    normals = u[:, None] * np.cos(pp).ravel() + v[:, None] * np.sin(pp).ravel()
    points = centre[:, None] + radius * normals + axis[:, None] * ss.ravel()
    areas = np.full(pp.size, 2.0 * math.pi * radius * length / pp.size)
    return SurfaceSamples(points, normals, areas)


@dataclass(frozen=True)
class Layer:
    """One layer of a plate: a solid ``material`` and its ``thickness`` [m] (> 0)."""

    material: Material
    thickness: float

    def __post_init__(self) -> None:
        t = self.thickness
        if isinstance(t, bool) or not (isinstance(t, int | float) and math.isfinite(t) and t > 0):
            raise GeometryError(f"thickness: must be a length > 0; got {t!r}")
        if not isinstance(self.material, Material) or self.material.is_fluid:
            raise GeometryError(
                f"material: a layer must be a solid (with a shear speed); got "
                f"{getattr(self.material, 'name', self.material)!r}"
            )


@dataclass(frozen=True)
class Interior:
    """A solid part's inside: the plate below its front face.

    Parameters
    ----------
    thickness : [m] T, the distance from the front face to the back wall (> 0).
    back_wall_echoes : how many back-wall echoes to simulate (1 = the back wall only,
        2 adds its first multiple, …), 0 to 20.
    flaws : reflectors inside the part.
    layers : the plate's layers, top first (their thicknesses sum to ``thickness``); empty:
        one layer of the specimen's material.  With layers, ``back_wall_echoes`` is the
        order M of the echo train: every path with at most 2M − 1 reflections
        (:mod:`echocal.wave.layered`).
    shear_legs : with layers, the most mode-converted (shear) legs an echo path may have,
        0 to :data:`MAX_SHEAR_LEGS` (0: longitudinal paths only).
    exact_stack : with layers, the A-scan is the whole stack's exact plane-wave response
        under a flat circular probe (:mod:`echocal.wave.stack`), its paths labelled and
        what they leave out a remainder of its own.
    """

    thickness: float
    back_wall_echoes: int = 3
    flaws: tuple[Flaw, ...] = ()
    layers: tuple[Layer, ...] = ()
    shear_legs: int = 0
    exact_stack: bool = False

    def __post_init__(self) -> None:
        t = self.thickness
        if isinstance(t, bool) or not (isinstance(t, int | float) and math.isfinite(t) and t > 0):
            raise GeometryError(f"specimen.thickness: must be a length > 0; got {t!r}")
        n = self.back_wall_echoes
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= MAX_BACK_WALL_ECHOES:
            raise GeometryError(
                f"specimen.back_wall_echoes: must be an integer from 0 to "
                f"{MAX_BACK_WALL_ECHOES}; got {n!r}"
            )
        names = [f.name for f in self.flaws]
        duplicate = next((n for n in names if names.count(n) > 1), None)
        if duplicate is not None:
            raise GeometryError(f"specimen.flaws: the name {duplicate!r} is used twice")
        object.__setattr__(self, "flaws", tuple(self.flaws))
        object.__setattr__(self, "layers", tuple(self.layers))
        if self.layers:
            total = sum(layer.thickness for layer in self.layers)
            if not math.isclose(total, t, rel_tol=1e-9):
                raise GeometryError(
                    f"specimen.thickness: {1e3 * t:g} mm is not the layers' total "
                    f"{1e3 * total:g} mm; leave thickness out with layers"
                )
        m = self.shear_legs
        if isinstance(m, bool) or not isinstance(m, int) or not 0 <= m <= MAX_SHEAR_LEGS:
            raise GeometryError(
                f"specimen.shear_legs: must be an integer from 0 to {MAX_SHEAR_LEGS}; got {m!r}"
            )
        if m and not self.layers:
            raise GeometryError(
                "specimen.shear_legs: needs [[specimen.layers]] (shear legs are listed for "
                "layered plates); leave it out or give the layers"
            )
        if not isinstance(self.exact_stack, bool):
            raise GeometryError(
                f"specimen.exact_stack: must be true or false; got {self.exact_stack!r}"
            )
        if self.exact_stack and not self.layers:
            raise GeometryError(
                "specimen.exact_stack: needs [[specimen.layers]] (the exact stack is a "
                "layered plate's); leave it out or give the layers"
            )
        if self.layers:
            echo_routes(len(self.layers), n, m)  # refuses an order with too many paths

    @property
    def interfaces(self) -> FloatArray:
        """[m] depths of the interfaces below the front face, ``(N + 1,)``: 0, then the
        bottom of each layer (the last is the back wall); ``(0, T)`` without layers."""
        if not self.layers:
            return np.array([0.0, self.thickness])
        return np.concatenate([[0.0], np.cumsum([layer.thickness for layer in self.layers])])

    def check_inside(self, front: FinitePlane | Sphere | Cylinder) -> None:
        """Refuse a flaw that is not wholly inside the plate below ``front``; for a curved
        wall (``front`` the outer face of a spherical shell or a pipe), a wall as thick as
        the part, a bore, or any flaw."""
        if isinstance(front, (Sphere, Cylinder)):
            if isinstance(front, Cylinder) and front.bore:
                raise GeometryError(f"specimen.thickness: {INTERIOR_SHAPES}")
            if not self.thickness < front.radius:
                raise GeometryError(
                    f"specimen.thickness: {1e3 * self.thickness:g} mm is not less than the "
                    f"{front.kind}'s radius {1e3 * front.radius:g} mm; a curved wall must be "
                    "thinner than its radius"
                )
            if self.flaws:
                raise GeometryError(
                    f"specimen.flaws.{self.flaws[0].name}: flaws are modelled inside plates "
                    f"only, not inside a curved wall ({front.kind}); remove the flaws or use a "
                    "plate"
                )
            return
        for flaw in self.flaws:
            shallow, deep = flaw.depth_range(front)
            where = f"specimen.flaws.{flaw.name}.position"
            if shallow <= 0.0 or deep >= self.thickness:
                raise GeometryError(
                    f"{where}: the flaw spans depths {1e3 * shallow:g} to {1e3 * deep:g} mm "
                    f"below the front face; it must lie inside the part (0 to "
                    f"{1e3 * self.thickness:g} mm): move it or make it smaller"
                )
            inner = self.interfaces[1:-1]
            crossed = inner[(inner > shallow) & (inner < deep)] if self.layers else inner[:0]
            if crossed.size:
                raise GeometryError(
                    f"{where}: the flaw spans depths {1e3 * shallow:g} to {1e3 * deep:g} mm, "
                    f"across the interface at {1e3 * float(crossed[0]):g} mm; a flaw must lie "
                    "within one layer"
                )
            offset = flaw.position - front.center
            lateral = (abs(float(offset @ front.x_axis)), abs(float(offset @ front.y_axis)))
            if lateral[0] > 0.5 * front.width or lateral[1] > 0.5 * front.height:
                raise GeometryError(
                    f"{where}: the flaw lies outside the plate's {1e3 * front.width:g} × "
                    f"{1e3 * front.height:g} mm face; move it under the face"
                )
