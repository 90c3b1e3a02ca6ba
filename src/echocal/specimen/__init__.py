"""Specimen surfaces and the specimens built from them.

Shapes implement :class:`Shape` (``intersect(origins, directions) -> (distance,
normal)``, ``bounds()``); a :class:`Specimen` is any number of them.  Casting
rays at a specimen lives in :mod:`echocal.raytrace`.
"""

from __future__ import annotations

from echocal.specimen.base import EPS_REL, GRAZING_COS, Shape
from echocal.specimen.builtins import (
    THESIS_BLOCK_FACETS,
    THESIS_MEASUREMENT_POINTS,
    TILTED_PLATE_ORIENTATION,
    builtin_specimen,
    register_specimen,
    specimen_names,
    thesis_block,
    wavy_surface_mesh,
)
from echocal.specimen.cylinder import CYLINDER_SURFACES, Cylinder
from echocal.specimen.mesh import MESH_ENGINES, TriangleMesh, embree_available
from echocal.specimen.plane import FinitePlane
from echocal.specimen.specimen import Specimen
from echocal.specimen.sphere import Sphere

__all__ = [
    "CYLINDER_SURFACES",
    "EPS_REL",
    "GRAZING_COS",
    "MESH_ENGINES",
    "THESIS_BLOCK_FACETS",
    "THESIS_MEASUREMENT_POINTS",
    "TILTED_PLATE_ORIENTATION",
    "Cylinder",
    "FinitePlane",
    "Shape",
    "Specimen",
    "Sphere",
    "TriangleMesh",
    "builtin_specimen",
    "embree_available",
    "register_specimen",
    "specimen_names",
    "thesis_block",
    "wavy_surface_mesh",
]
