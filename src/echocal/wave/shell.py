"""A thick spherical shell's back wall, paraxially: the equivalent mirror in water.

**Model.**  Near the beam's axis a round trip through a curved wall is a paraxial optical
system: the front face is a lens (the water–solid interface), the wall's thickness a
propagation, the back wall a mirror.  In *reduced* units (refractive index n = c_w/c,
distances in the solid scaled by c_L/c_w, ray slopes by n) each element is a 2 × 2 ray
matrix of determinant 1, and the whole round trip from the front face's tangent plane back
to it is

    M = F · P · B · P · F            (one back-wall echo)
    M_k = F · (P B P) · (S · P B P)^(k−1) · F     (the k-th, with k − 1 bounces under the face)

with F = [[1, 0], [(1 − n_s)/R, 1]] the front face (radius R, refraction either way),
P = [[1, T·c_L/c_w], [0, 1]] the wall, B = [[1, 0], [2 n_s/(R − T), 1]] the convex back
wall (radius R − T) and S = [[1, 0], [−2 n_s/R, 1]] the front face seen from inside (a
concave mirror), n_s = c_w/c_L.  The matrix is palindromic, so A = D, and every such
matrix is also the round trip to a *mirror in water* at distance L = (A − 1)/C behind the
tangent plane with convex radius ρ = 2/C:

    [[1, L], [0, 1]] · [[1, 0], [2/ρ, 1]] · [[1, L], [0, 1]]
        = [[1 + 2L/ρ, 2L + 2L²/ρ], [2/ρ, 1 + 2L/ρ]].

The shell's centre is a fixed point of every element (a ray through it meets each face
normally and comes back on itself), so L + ρ = R: the equivalent sphere is concentric
with the part, whatever the probe's position.

Because the Fresnel (Collins) diffraction integral through a system depends only on its
ray matrix, the probe's exact field reflected by that water sphere is, to paraxial order,
the field that comes back out of the shell: echocal evaluates the back-wall echo as the
wave model's echo of the equivalent sphere, with the plane-wave coefficients
T_ws·R_sw^(2k−1)·T_sw, the two-way time corrected to 2kT/c_L on the axis, and the solid's
attenuation over 2kT.  For a flat wall (R → ∞) this is the plate's equivalent water path
(:mod:`echocal.wave.interior`); for a water-filled shell (n_s = 1) it is the inner sphere
itself.  Checked against a non-paraxial reference (a Rayleigh integral through the curved
front face, Kirchhoff at the back wall) in tests/physics/test_shell.py.

**Where it holds.**  Paraxial: the probe's footprint on the front face must stay well
inside the first critical angle, i.e. a probe radius a ≪ R·sin θ_c.  The validity limit
:data:`MAX_APERTURE_PER_RADIUS` is set from the reference's measured error.  A pipe
(a cylindrical wall) is astigmatic, a different matrix in each plane with different
equivalent distances, and no single mirror reproduces both: pipes are modelled on the
tangent plane instead (:mod:`echocal.wave.curved_wall`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal.errors import GeometryError
from echocal.specimen.interior import Interior

__all__ = [
    "MAX_APERTURE_PER_RADIUS",
    "EquivalentMirror",
    "check_curved_wall",
    "equivalent_mirror",
    "round_trip_matrix",
]

FloatArray = NDArray[np.float64]

MAX_APERTURE_PER_RADIUS = 0.065
"""The largest probe radius (a rectangle's half-diagonal) per front-face radius a/R for
which a curved wall's interior is modelled.  Against a non-paraxial Kirchhoff reference
(tests/physics/test_shell.py; 12.7 mm probe, 10 mm steel wall, 4–6 MHz) the back-wall
echo agrees within 0.7–2.9 % at a/R = 0.053 and is 20–85 % off at a/R = 0.106, where the
footprint reaches half the critical angle on the front face and the reference itself
depends on how its local ray direction is averaged."""


def _lens(power: float) -> FloatArray:
    return np.array([[1.0, 0.0], [power, 1.0]])


def _propagation(length: float) -> FloatArray:
    return np.array([[1.0, length], [0.0, 1.0]])


def round_trip_matrix(radius: float, thickness: float, order: int, ratio: float) -> FloatArray:
    """The reduced ray matrix ``(2, 2)`` of the ``order``-th back-wall echo of a spherical
    shell, from the front face's tangent plane back to it.

    Parameters
    ----------
    radius : [m] the front (outer) face's radius R.
    thickness : [m] the wall's thickness T (0 < T < R).
    order : the echo's order k ≥ 1 (1: the back wall; 2: its first multiple, …).
    ratio : c_L/c_w, the solid's longitudinal speed over the water's.

    The ray vector is (height, n·slope), C > 0 diverges; see the module doc.
    """
    n_s = 1.0 / ratio
    front = _lens((1.0 - n_s) / radius)
    wall = _propagation(thickness * ratio)
    bounce = wall @ _lens(2.0 * n_s / (radius - thickness)) @ wall
    under_face = _lens(-2.0 * n_s / radius)
    inside = bounce
    for _ in range(order - 1):
        inside = inside @ under_face @ bounce
    return front @ inside @ front


@dataclass(frozen=True)
class EquivalentMirror:
    """A water mirror with the round trip's ray matrix.

    Attributes
    ----------
    distance : [m] L, from the front face's apex (its tangent plane) to the mirror's apex.
    radius : [m] ρ, the mirror's convex radius (``math.inf``: flat).
    """

    distance: float
    radius: float


def equivalent_mirror(
    radius: float, thickness: float, order: int, ratio: float
) -> EquivalentMirror:
    """The water mirror equivalent to the ``order``-th back-wall round trip of a shell
    (parameters as :func:`round_trip_matrix`): L = (A − 1)/C, ρ = 2/C."""
    (a, b), (c, _) = round_trip_matrix(radius, thickness, order, ratio)
    if abs(c) * b < 1e-12:  # flat to working precision: the plate's equivalent path
        return EquivalentMirror(0.5 * b, math.inf)
    if c < 0.0:  # a converging round trip would need a concave mirror
        raise GeometryError(
            f"specimen.thickness: the shell's back-wall echo {order} focuses (an equivalent "
            "concave mirror), which the model does not cover; ask for fewer back_wall_echoes"
        )
    return EquivalentMirror((a - 1.0) / c, 2.0 / c)


def check_curved_wall(
    radius: float, interior: Interior, probe_radius: float, ratio: float, spherical: bool
) -> None:
    """Refuse a curved wall (front radius R [m]; a sphere, or a pipe when not
    ``spherical``) the paraxial models do not cover, naming the field: a probe (radius
    [m], a rectangle's half-diagonal) wider than :data:`MAX_APERTURE_PER_RADIUS`·R, or a
    shell's multiple that focuses.  The wall's own geometry is checked by
    :meth:`echocal.specimen.interior.Interior.check_inside`."""
    if probe_radius > MAX_APERTURE_PER_RADIUS * radius:
        limit = 1e3 * MAX_APERTURE_PER_RADIUS * radius
        raise GeometryError(
            f"specimen.thickness: a curved wall's interior is modelled paraxially, for probes "
            f"up to {MAX_APERTURE_PER_RADIUS:g} × the front radius ({limit:.3g} mm here); this "
            f"probe's radius is {1e3 * probe_radius:g} mm: use a smaller probe or a larger part"
        )
    if spherical:
        for k in range(1, interior.back_wall_echoes + 1):
            equivalent_mirror(radius, interior.thickness, k, ratio)
