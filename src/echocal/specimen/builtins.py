"""Built-in specimens by name: ``builtin_specimen("thesis-block")``.

=================  ==========================================================
name               what it is
=================  ==========================================================
``flat-plate``     100 × 100 mm horizontal plate at z = 0
``tilted-plate``   100 × 100 mm plate through the origin, normal (30°, 4°)
``thesis-block``   a valley of three facets: optimum differs at the thesis's
                   three measurement points (see :func:`thesis_block`)
``cylinder``       rod of radius 20 mm along y, top line at z = 0
``sphere``         ball of radius 25 mm, top at z = 0
``wavy-surface``   triangle mesh of a gently corrugated 60 × 60 mm surface
=================  ==========================================================

Further specimens can be added with :func:`register_specimen`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from echocal._validate import lookup
from echocal.constants import MM
from echocal.errors import EchocalValueError
from echocal.geometry import orientation_normal
from echocal.specimen.cylinder import Cylinder
from echocal.specimen.mesh import TriangleMesh
from echocal.specimen.plane import FinitePlane
from echocal.specimen.specimen import Specimen
from echocal.specimen.sphere import Sphere

__all__ = [
    "THESIS_BLOCK_FACETS",
    "THESIS_MEASUREMENT_POINTS",
    "TILTED_PLATE_ORIENTATION",
    "builtin_specimen",
    "register_specimen",
    "specimen_names",
    "thesis_block",
    "wavy_surface_mesh",
]

_REGISTRY: dict[str, Callable[[], Specimen]] = {}


def register_specimen(name: str, factory: Callable[[], Specimen]) -> None:
    """Make ``factory()`` available as ``builtin_specimen(name)``; duplicate names are refused."""
    if not isinstance(name, str) or not name:
        raise EchocalValueError(f"specimen name must be a non-empty string; got {name!r}")
    if name in _REGISTRY:
        raise EchocalValueError(f"specimen {name!r} is already registered; choose another name")
    if not callable(factory):
        raise EchocalValueError(f"specimen factory for {name!r} must be callable")
    _REGISTRY[name] = factory


def specimen_names() -> tuple[str, ...]:
    """Names accepted by :func:`builtin_specimen`, sorted."""
    return tuple(sorted(_REGISTRY))


def builtin_specimen(name: str) -> Specimen:
    """A fresh instance of the built-in specimen ``name`` (unknown names list the valid ones)."""
    return lookup("specimen", name, _REGISTRY)()


# ------------------------------------------------------------------ plates


def flat_plate() -> Specimen:
    """100 × 100 mm horizontal plate at z = 0; optimum orientation (0°, 0°) everywhere."""
    plate = FinitePlane(center=(0.0, 0.0, 0.0), width=100 * MM, height=100 * MM, name="plate")
    return Specimen([plate], name="flat-plate", description="100 x 100 mm plate at z = 0")


TILTED_PLATE_ORIENTATION = (30.0, 4.0)
"""(azimuth, co-elevation) [deg] of the ``tilted-plate`` normal: the optimum everywhere."""


def tilted_plate() -> Specimen:
    """100 × 100 mm plate through the origin with normal (azimuth 30°, co-elevation 4°).

    The optimum orientation (30°, 4°) is off the pole and non-zero in both
    angles (tilts ≈ (−2.0°, 3.5°)), so calibrations must move in both.
    """
    az, co = TILTED_PLATE_ORIENTATION
    plate = FinitePlane(
        center=(0.0, 0.0, 0.0),
        width=100 * MM,
        height=100 * MM,
        azimuth=az,
        coelevation=co,
        name="plate",
    )
    return Specimen(
        [plate], name="tilted-plate", description=f"plate through origin, normal ({az}, {co}) deg"
    )


# ------------------------------------------------------------- thesis block

THESIS_MEASUREMENT_POINTS = np.array([[-10.0, 0.0, 22.0], [0.0, 0.0, 20.0], [10.0, 0.0, 22.0]]) * MM
"""[m] the transducer positions of thesis §12.1.1, shape (3, 3)."""

THESIS_BLOCK_FACETS = {
    "left": {"hinge_x": -5 * MM, "azimuth": 20.0, "coelevation": 10.0},
    "centre": {"hinge_x": 0.0, "azimuth": 0.0, "coelevation": 0.0},
    "right": {"hinge_x": 5 * MM, "azimuth": 165.0, "coelevation": 6.0},
}
"""Facet normals [deg] of ``thesis-block`` and where each side facet meets z = 0 on y = 0 [m]."""


def _side_facet(
    name: str, hinge_x: float, azimuth: float, coelevation: float, centre_x: float
) -> FinitePlane:
    """A 60 × 50 mm facet through (hinge_x, 0, 0) whose centre lies above (centre_x, 0).

    It reaches ~20 mm past its crease, where it passes below the centre plate,
    so the closest hit shows the crease as the planes' intersection line.
    """
    n = orientation_normal(azimuth, coelevation)
    z = -n[0] * (centre_x - hinge_x) / n[2]
    return FinitePlane(
        center=(centre_x, 0.0, z),
        width=60 * MM,
        height=50 * MM,
        azimuth=azimuth,
        coelevation=coelevation,
        name=name,
    )


def thesis_block() -> Specimen:
    """A block with three facets of different tilt (a shallow valley), after thesis Fig. 7.

    * **centre facet** — horizontal, z = 0, visible for x ∈ [−5, 5] mm
      (normal (azimuth 0°, co-elevation 0°): the pole);
    * **left facet** — rises towards −x from the crease through (−5, 0, 0) mm,
      normal (azimuth 20°, co-elevation 10°) ≈ (0.163, 0.059, 0.985),
      tilts (tilt_x, tilt_y) ≈ (−3.4°, 9.4°); at x = −10 mm it is ≈ 0.83 mm high;
    * **right facet** — rises towards +x from the crease through (5, 0, 0) mm,
      normal (azimuth 165°, co-elevation 6°) ≈ (−0.101, 0.027, 0.995), the same
      beam as the signed (−15°, −6°), tilts ≈ (−1.6°, −5.8°); at x = 10 mm it is
      ≈ 0.51 mm high.

    The centre facet is a wide plate at z = 0; the side facets are finite planes
    that rise above it outside the creases and pass below it inside them, so
    the closest hit traces the valley without gaps (the creases are the planes'
    true intersection lines, slanted in plan view by the facets' azimuths).

    Expected optimal orientation (the upward facet normal under the beam) at
    the thesis's measurement points (:data:`THESIS_MEASUREMENT_POINTS`):

    =====================  ===============================
    point [mm]             optimum (azimuth, co-elevation)
    =====================  ===============================
    (−10, 0, 22)           (20°, 10°)  — left facet
    (0, 0, 20)             (any, 0°)   — centre facet
    (10, 0, 22)            (165°, 6°)  — right facet
    =====================  ===============================

    A probe ~10 mm wide at ~20 mm stand-off has its footprint on one facet at
    each point (the centre footprint just reaches the creases).
    """
    f = THESIS_BLOCK_FACETS
    centre = FinitePlane(
        center=(0.0, 0.0, 0.0), width=100 * MM, height=50 * MM, name="centre facet"
    )
    left = _side_facet("left facet", f["left"]["hinge_x"], 20.0, 10.0, centre_x=-15 * MM)
    right = _side_facet("right facet", f["right"]["hinge_x"], 165.0, 6.0, centre_x=15 * MM)
    return Specimen(
        [centre, left, right],
        name="thesis-block",
        description="valley of 3 facets; optimum (20,10)/(0,0)/(165,6) deg at x=-10/0/10 mm",
    )


# ------------------------------------------------------------ curved shapes


def cylinder() -> Specimen:
    """Rod of radius 20 mm and length 100 mm along y; its top line is at z = 0.

    The optimum below (x, y) is the outward radial normal: co-elevation
    asin(|x| / 20 mm), azimuth 0° for x > 0 and 180° for x < 0.
    """
    rod = Cylinder(
        center=(0.0, 0.0, -20 * MM),
        radius=20 * MM,
        length=100 * MM,
        azimuth=90.0,
        coelevation=90.0,
        surface="outside",
        name="rod",
    )
    return Specimen([rod], name="cylinder", description="rod r = 20 mm along y, top at z = 0")


def sphere() -> Specimen:
    """Ball of radius 25 mm centred at (0, 0, −25) mm (top at z = 0); optimum = radial normal."""
    ball = Sphere(center=(0.0, 0.0, -25 * MM), radius=25 * MM, name="ball")
    return Specimen([ball], name="sphere", description="ball r = 25 mm, top at z = 0")


def wavy_surface_mesh(
    *,
    size: float = 60 * MM,
    n: int = 21,
    amplitude: float = 1.0 * MM,
    wavelength: float = 30 * MM,
    name: str = "wavy surface",
) -> TriangleMesh:
    """Triangulated height field ``z = A sin(2πx/λ) cos(2πy/λ)`` over a square.

    Parameters
    ----------
    size : [m] side of the square, centred on the origin.
    n : grid points per side (``2 (n − 1)²`` triangles).
    amplitude, wavelength : [m] of the corrugation.
    """
    if n < 2:
        raise EchocalValueError(f"wavy_surface_mesh n must be >= 2; got {n}")
    g = np.linspace(-size / 2, size / 2, n)
    xx, yy = np.meshgrid(g, g, indexing="ij")
    k = 2 * np.pi / wavelength
    zz = amplitude * np.sin(k * xx) * np.cos(k * yy)
    vertices = np.stack([xx, yy, zz], axis=-1).reshape(-1, 3)
    idx = np.arange(n * n).reshape(n, n)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return TriangleMesh(vertices, faces, engine="auto", name=name)


def wavy_surface() -> Specimen:
    """Triangle mesh (800 faces) of a 60 × 60 mm surface corrugated by ±1 mm."""
    return Specimen(
        [wavy_surface_mesh()], name="wavy-surface", description="60 x 60 mm mesh, ±1 mm waves"
    )


for _name, _factory in (
    ("flat-plate", flat_plate),
    ("tilted-plate", tilted_plate),
    ("thesis-block", thesis_block),
    ("cylinder", cylinder),
    ("sphere", sphere),
    ("wavy-surface", wavy_surface),
):
    register_specimen(_name, _factory)
