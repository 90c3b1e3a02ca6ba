"""The image form of the pulse-echo response over a plane: exact, and a face's worth of samples.

Over an infinite plane the Kirchhoff boundary values are exact (the image theorem), and the
wave reflected to the probe is the field radiated by the probe's mirror image.  The signal
received by the real face is then, by reciprocity, the integral of the probe's own spatial
impulse response h over its image face A′ (Rogers & Van Buren's formulation of the
diffraction correction, extended to any tilt and to bowls):

    A(t) = w(t) * R/(A_p c) · ∂ₜ H(t),   H(t) = ∫_{A′} h(x′, t) dA′,

normalized like :class:`echocal.wave.WaveEchoModel`'s Kirchhoff sum (a perfect reflector at
normal incidence in the deep near field of a large piston returns w(t − 2d/c)).  The
integral runs over the face, not over the lit surface: a Gauss–Legendre product rule on
the face (:func:`face_samples`) needs a few hundred nodes where the Kirchhoff sum needs the
whole footprint of the diffracted beam (about a thousand samples for a 12.7 mm probe at
50 mm), and each node's SIR is short.

**When it applies.** :func:`find_plane` accepts a pose when every ray of the beam's
footprint (the Kirchhoff fan's rim, a ring at half its radius and the axis) hits the same
plane first: the plane is then, for the beam, infinite and unobstructed.  Asked to
(``edge_clearance``), it also accepts a rectangular plate whose edge cuts the footprint
when the plate's echo and its edges' echo are apart in time: the Kirchhoff integral over
the plate is the one over its infinite plane (the image form, whose response lasts while
the paths from the face to its image do: 2h ± 2ρ, h the plane's distance from the
aperture's origin and ρ the face's radius about it) less the integral over the plane
beyond the plate's edges, nothing of which arrives before the paths 2(D − ρ), D the
distance from the aperture's origin to the nearest point beyond the edges.  When D − h
is at least 2ρ plus the pulse's support (in path), the image form gives the plate's echo
exactly and leaves out only the edges' own, later echo, as it does wherever the plate
fills the footprint.  Anything else (curved parts, edges near the specular point,
several shapes in the beam) uses the Kirchhoff sum.

**Sampling.** Across the image face the two-way delay changes by sin 2α per unit length
(α the beam axis's incidence on the plane), so the nodes lie at most
``nyquist_fraction`` · λ_hi/(2 sin 2α) apart (λ_hi at the pulse's highest frequency), and at
most ``spacing`` apart at normal incidence.  The angular nodes start at the plane's tilt
direction and come in multiples of four, so the rule is symmetric under the reflection
across the plane through the axis and the tilt direction, and under a half turn: a level
plane's echo is symmetric in tilt to round-off, and its maximum lies at the normal.

**Band-limited rule (flat discs).** The Nyquist rule above counts only the specular path's
delay change; a bound on every path's change is much sparser at large tilts (and denser
than the Nyquist rule near the probe at small tilts, where the edge waves' paths change
fastest).  Moving a face node b by a unit length along its ring moves its image x′ by a unit
length in the image plane, and the path |x′ − a| to any point a of the face changes by the
sine of the angle between x′ − a and the image plane's normal: at most sin(α + asin(a/h))
(h the plane's distance from the face centre: the image of the face centre lies 2h away,
at angle α from the image plane's normal, and x′ − a deviates from it by at most 2a).  At
one frequency the integrand along a ring of radius ρ is therefore band-limited to angular
harmonics |m| ≲ z = k_hi·ρ·sin(α + asin(a/h)), whose coefficients beyond z fall like
Bessel functions J_m(z); the uniform (trapezoid) rule in φ is exact below its node count
and :func:`trapezoid_count` takes z + 3z^⅓ + 4 nodes.  After the φ sum the ring mean is an
even function of ρ of bandwidth k_hi·sin(α + asin(a/h)) (β = that × a across the face), a
polynomial of degree about β/2 in s = ρ², so Gauss–Legendre in s needs about β/4 nodes:
:func:`bandwidth_ring_count` takes β/4 + 2β^⅓, with the Fresnel-zone and minimum counts of
:func:`ring_count`.  :func:`face_quadrature` uses whichever of the two rules has fewer
nodes (both measured against a rule at 0.3 of the Nyquist spacing, see
docs/benchmarks/wave.md): the band-limited one from about 3° at 50 mm (6× fewer nodes at
20°), the Nyquist one at smaller tilts and near the probe.

**Symmetry.** The probe is symmetric under that reflection and the plane's normal lies in
its mirror plane, so the integrand is even under it: the rule keeps the nodes on one side
(φ ∈ [0, π] from the tilt direction) and weights those off the mirror twice, half the
nodes for the same sum; at normal incidence a disc's or a bowl's integrand is axially
symmetric and one node per ring carries the ring's weight.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from echocal.specimen.base import Shape
from echocal.specimen.casting import _cast_soa
from echocal.specimen.plane import FinitePlane
from echocal.wave import sir
from echocal.wave.probe import Aperture

__all__ = [
    "BOWL_RINGS_PER_ZONE",
    "FLAT_RINGS_PER_ZONE",
    "MIN_RINGS",
    "MIN_RINGS_BOWL",
    "MIN_SIDE_NODES",
    "SIDE_NODES_PER_ZONE",
    "ImagePlane",
    "angular_bandwidth",
    "bandwidth_ring_count",
    "edge_margin",
    "face_quadrature",
    "face_samples",
    "find_plane",
    "node_spacing",
    "rectangle_samples",
    "ring_count",
    "side_counts",
    "trapezoid_count",
]

FloatArray = NDArray[np.float64]

MIN_RINGS = 8
"""Radial Gauss–Legendre nodes at least: the edge wave's delay varies across the face even
at normal incidence."""
MIN_RINGS_BOWL = 16
FLAT_RINGS_PER_ZONE = 2.0
"""A flat disc's radial nodes per Fresnel zone of :func:`ring_count` (at least
:data:`MIN_RINGS`).  One per zone left an 8.90 mm probe at 9.52 MHz over a plane 44.4 mm
away (11.2 zones, 12 rings) 2–3 % off the exact angular spectrum at normal incidence; 24
rings, 5e-4 (tests/physics/test_wave_pairs_holdout.py).  The built-in setups have under
4 zones: their 8 rings are unchanged."""
BOWL_RINGS_PER_ZONE = 3.0
"""A focused bowl's radial nodes: at least :data:`MIN_RINGS_BOWL`, and this many per
Fresnel zone of :func:`ring_count`.  Against the double Rayleigh integral (3 mm bowl,
R_f 25 mm, 20 mm water): 8 rings 0.5 % low, 16 rings 0.2 %, 32 rings 0.015 %; a 12.7 mm
bowl (R_f 40 mm, 10 mm water, 20 zones at 6 MHz) was 24 % off with 8 rings."""

MIN_SIDE_NODES = 16
SIDE_NODES_PER_ZONE = 4.0
"""A rectangle's Gauss–Legendre nodes per side: at least :data:`MIN_SIDE_NODES`, and this
many per Fresnel zone of :func:`side_counts`.  Against the double Rayleigh integral (10 mm
square at 10 mm water, 10 × 6 mm at 20 mm; 4–6 MHz): 2 per zone (at least 8) left 2.6 % and
6 % of the peak, 4 per zone (at least 16) 0.02–0.06 %, 8 per zone no better."""


@dataclass(frozen=True)
class ImagePlane:
    """A plane in the aperture frame (face centre or bowl apex at the origin, beam along +z).

    Attributes
    ----------
    point : [m] ``(3,)`` a point of the plane (where the beam axis meets it).
    normal : ``(3,)`` unit normal, pointing towards the probe (n·point < 0).
    """

    point: FloatArray
    normal: FloatArray

    @property
    def sin_incidence(self) -> float:
        """sin α, α the beam axis's angle of incidence on the plane."""
        cos_a = min(1.0, abs(float(self.normal[2])))
        return math.sqrt(max(0.0, 1.0 - cos_a * cos_a))

    @property
    def axis_distance(self) -> float:
        """[m] from the aperture's origin to the plane along the beam axis (+z)."""
        return float(-(self.normal @ self.point)) / max(abs(float(self.normal[2])), 1e-6)

    def mirror(self, points: FloatArray) -> FloatArray:
        """The mirror images ``(3, n)`` [m] of ``points`` ``(3, n)`` [m] across the plane."""
        height = self.normal @ (points - self.point[:, None])  # (n,)
        return points - 2.0 * np.outer(self.normal, height)


def node_spacing(
    shortest_wavelength: float, sin_incidence: float, nyquist_fraction: float
) -> float:
    """[m] the largest distance between face nodes along a ring for a plane at incidence
    sine ``sin_incidence``: ``nyquist_fraction`` × λ_hi/(2 sin 2α) (``shortest_wavelength``
    λ_hi [m]); infinite at normal incidence, where the image of a ring lies at one distance
    from the probe's axis and the integrand does not depend on φ."""
    sin_2a = 2.0 * sin_incidence * math.sqrt(max(0.0, 1.0 - sin_incidence**2))
    if sin_incidence >= math.sqrt(0.5):  # beyond 45° the image's tilt 2α passes 90°
        sin_2a = 1.0
    if sin_2a <= 0.0:
        return math.inf
    return nyquist_fraction * shortest_wavelength / (2.0 * sin_2a)


def angular_bandwidth(
    shortest_wavelength: float, sin_incidence: float, radius: float, distance: float
) -> float:
    """[rad/m] k_hi·sin(α + asin(a/h)): a bound on the rate at which the phase of every path
    from the image face to the face changes per unit length along the image face (see the
    module's "Band-limited rule"), for a flat face of radius ``radius`` a [m] over a plane
    ``distance`` h [m] from the face centre (along the plane's normal) at incidence sine
    ``sin_incidence`` (k_hi = 2π/``shortest_wavelength`` [m])."""
    alpha = math.asin(min(1.0, sin_incidence))
    spread = math.asin(min(1.0, radius / max(distance, radius)))
    k_hi = 2.0 * math.pi / shortest_wavelength
    return k_hi * math.sin(min(0.5 * math.pi, alpha + spread))


def trapezoid_count(z: float) -> int:
    """Uniform nodes on a full ring for an integrand band-limited to angular harmonics
    |m| ≲ ``z``: z + 3z^⅓ + 4 (the coefficients beyond z fall like J_m(z), below 10⁻³ of
    the largest 3z^⅓ past it), rounded up to a multiple of four, at least eight."""
    nodes = z + 3.0 * z ** (1.0 / 3.0) + 4.0
    return 4 * max(2, math.ceil(nodes / 4.0))


def bandwidth_ring_count(
    probe: Aperture, distance: float, shortest_wavelength: float, bandwidth: float
) -> int:
    """Radial Gauss–Legendre nodes (in s = ρ²) of a flat disc's band-limited rule: β/4 +
    2β^⅓ with β = ``bandwidth`` [rad/m] × a, the ring mean being a polynomial of degree
    about β/2 in s; at least :data:`MIN_RINGS` and the Fresnel zones of :func:`ring_count`
    (``distance`` [m] along the axis, ``shortest_wavelength`` [m])."""
    beta = bandwidth * probe.radius
    d = max(distance, shortest_wavelength)
    zones = probe.radius**2 / (2.0 * d * shortest_wavelength)
    return max(MIN_RINGS, math.ceil(beta / 4.0 + 2.0 * beta ** (1.0 / 3.0)), math.ceil(zones))


def ring_count(probe: Aperture, distance: float, shortest_wavelength: float, spacing: float) -> int:
    """Radial Gauss–Legendre nodes for the probe's face over a plane ``distance`` [m] away
    along the axis: at least :data:`MIN_RINGS`, at least a/``spacing`` (``spacing`` [m]
    from :func:`node_spacing`), and :data:`FLAT_RINGS_PER_ZONE` per Fresnel zone of the
    edge wave across the face, a²(1/(2d) + 1/R_f)/λ_hi: the path from a node at radius ρ
    of the image to the probe's rim changes by a²/(4d) (plus a²/(2R_f) for a bowl, whose
    sag adds to it) from the centre to the rim, and its phase runs through one period per
    half wavelength of that change; the nodes are uniform in ρ², as the zones are (λ_hi
    ``shortest_wavelength`` [m]).  A bowl's integrand converges more slowly (its SIR near
    the focus has sharper breakpoints): :data:`BOWL_RINGS_PER_ZONE` rings per zone, at
    least :data:`MIN_RINGS_BOWL`."""
    a = probe.radius
    d = max(distance, shortest_wavelength)
    along = a / spacing if math.isfinite(spacing) else 0.0
    if probe.curvature is None:
        zones = a * a / (2.0 * d * shortest_wavelength)
        return max(MIN_RINGS, math.ceil(along), math.ceil(FLAT_RINGS_PER_ZONE * zones))
    zones = a * a * (1.0 / (2.0 * d) + 1.0 / probe.curvature) / shortest_wavelength
    return max(MIN_RINGS_BOWL, math.ceil(along), math.ceil(BOWL_RINGS_PER_ZONE * zones))


def face_samples(
    probe: Aperture,
    n_rings: int,
    spacing: float,
    symmetry: tuple[float, float] | None = None,
    bandwidth: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Gauss–Legendre product nodes on the probe's face: ``n_rings`` rings, nodes at most
    about ``spacing`` [m] apart along each ring, or with ``bandwidth`` [rad/m] > 0 (from
    :func:`angular_bandwidth`), :func:`trapezoid_count` (``bandwidth`` × ρ) nodes on the
    ring of radius ρ.

    Flat disc: Gauss–Legendre in s = ρ² on [0, a²] (dA = ½ ds dφ) × uniform φ.  Bowl: in
    u = cos θ on [cos θmax, 1] (dA = R_f² du dφ) × uniform φ.  Either way the weights are
    uniform in the radial variable's measure, the nodes crowd towards the rim where the
    edge wave's delay changes fastest, and the weights sum to the face's area exactly.  Each
    ring has its own number of angular nodes (a multiple of four, at least eight), about
    ``spacing`` apart along the ring (eight at normal incidence, ``spacing`` = inf).

    ``symmetry``: None, every node.  A unit vector (u_x, u_y) in the face's plane: the
    integrand is even under the reflection across the plane through the axis and u (a
    plane tilted along u), so each ring's angles start at u and only φ ∈ [0, π] are kept,
    the nodes strictly inside weighted twice: half the nodes, the same sum.  (0, 0): the
    integrand is axially symmetric (normal incidence), one node per ring on the x axis
    with the ring's whole weight.

    Returns
    -------
    points : [m] ``(3, n)`` in the aperture frame (face centre or bowl apex at the origin).
    weights : [m²] ``(n,)``.
    """
    points, weights = _face_samples(
        probe.radius, probe.curvature, n_rings, spacing, symmetry, bandwidth
    )
    return points.copy(), weights.copy()


@functools.lru_cache(maxsize=256)
def _gauss_legendre(n: int) -> tuple[FloatArray, FloatArray]:
    """The ``n``-point Gauss–Legendre nodes and weights on [−1, 1] (cached: numpy solves an
    eigenvalue problem each time, 1–2 ms at a few dozen nodes; do not modify)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w


@functools.lru_cache(maxsize=64)
def _face_samples(
    a: float,
    curvature: float | None,
    n_rings: int,
    spacing: float,
    symmetry: tuple[float, float] | None = None,
    bandwidth: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    x, w = _gauss_legendre(n_rings)  # on [−1, 1]
    if curvature is None:
        s = 0.5 * (x + 1.0) * a * a
        rho = np.sqrt(s)
        ring_area = 0.5 * (0.5 * a * a * w)  # × 2π: the ring's share of πa²
        z = np.zeros_like(rho)
    else:
        rf = curvature
        u_min = math.sqrt(1.0 - (a / rf) ** 2)
        u = u_min + 0.5 * (x + 1.0) * (1.0 - u_min)
        rho = rf * np.sqrt(np.maximum(0.0, 1.0 - u * u))
        ring_area = rf * rf * (0.5 * (1.0 - u_min) * w)
        z = rf * (1.0 - u)
    axial = symmetry is not None and symmetry[0] == 0.0 and symmetry[1] == 0.0
    start = 0.0 if symmetry is None or axial else math.atan2(symmetry[1], symmetry[0])
    columns: list[FloatArray] = []
    weights: list[FloatArray] = []
    for rho_i, z_i, area_i in zip(rho, z, ring_area, strict=True):
        if axial:
            columns.append(np.array([[rho_i], [0.0], [z_i]]))
            weights.append(np.array([area_i * 2.0 * math.pi]))
            continue
        if bandwidth > 0.0:
            n_phi = trapezoid_count(bandwidth * rho_i)
        else:
            along = 2.0 * math.pi * rho_i / (4.0 * spacing) if math.isfinite(spacing) else 0.0
            n_phi = 4 * max(2, math.ceil(along))
        j = np.arange(n_phi if symmetry is None else n_phi // 2 + 1)
        ring_w = np.full(j.size, area_i * 2.0 * math.pi / n_phi)
        if symmetry is not None:
            ring_w[1:-1] *= 2.0  # 0 < φ < π stands for its mirror image too
        phi = start + 2.0 * math.pi * j / n_phi
        columns.append(np.stack([rho_i * np.cos(phi), rho_i * np.sin(phi), np.full(j.size, z_i)]))
        weights.append(ring_w)
    return np.concatenate(columns, axis=1), np.concatenate(weights)


def side_counts(
    half_width: float,
    half_height: float,
    distance: float,
    shortest_wavelength: float,
    spacing: float,
) -> tuple[int, int]:
    """Gauss–Legendre nodes along a rectangular face's two sides (half-sides [m]) over a
    plane ``distance`` [m] away: per side at least :data:`MIN_SIDE_NODES`, at least
    π·a/``spacing`` (the widest gap between n Gauss–Legendre nodes on [−a, a] is about πa/n),
    and :data:`SIDE_NODES_PER_ZONE` per Fresnel zone of the edge wave, a²/(2dλ_hi) across
    the half-side (λ_hi ``shortest_wavelength`` [m]): in x, not x², the zones crowd towards
    the edges, and the rectangle's SIR has a breakpoint per edge and corner."""
    d = max(distance, shortest_wavelength)

    def count(a: float) -> int:
        along = math.pi * a / spacing if math.isfinite(spacing) else 0.0
        zones = a * a / (2.0 * d * shortest_wavelength)
        return max(MIN_SIDE_NODES, math.ceil(along), math.ceil(SIDE_NODES_PER_ZONE * zones))

    return count(half_width), count(half_height)


@functools.lru_cache(maxsize=64)
def _rectangle_samples(
    half_width: float, half_height: float, nx: int, ny: int
) -> tuple[FloatArray, FloatArray]:
    x, wx = np.polynomial.legendre.leggauss(nx)
    y, wy = np.polynomial.legendre.leggauss(ny)
    xx, yy = np.meshgrid(half_width * x, half_height * y, indexing="ij")
    weights = np.outer(half_width * wx, half_height * wy).ravel()
    points = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])
    return points, weights


def rectangle_samples(
    half_width: float, half_height: float, nx: int, ny: int
) -> tuple[FloatArray, FloatArray]:
    """Gauss–Legendre product nodes on the rectangle |x| ≤ ``half_width``, |y| ≤
    ``half_height`` [m] (``nx`` × ``ny`` nodes, symmetric under x → −x and y → −y; the
    weights sum to the area).

    Returns
    -------
    points : [m] ``(3, nx·ny)`` in the aperture frame (face centre at the origin).
    weights : [m²] ``(nx·ny,)``.
    """
    points, weights = _rectangle_samples(half_width, half_height, nx, ny)
    return points.copy(), weights.copy()


def face_quadrature(
    probe: Aperture,
    distance: float,
    shortest_wavelength: float,
    spacing: float,
    symmetry: tuple[float, float] | None = None,
    bandwidth: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """The image form's nodes on the probe's face for a plane ``distance`` [m] away along
    the axis, nodes at most about ``spacing`` [m] apart (from :func:`node_spacing`):
    :func:`face_samples` with :func:`ring_count` rings on a disc or a bowl,
    :func:`rectangle_samples` with :func:`side_counts` on a rectangle.  On a flat disc
    with ``bandwidth`` [rad/m] > 0 (from :func:`angular_bandwidth`) and a tilted plane,
    the band-limited rule (:func:`bandwidth_ring_count` rings, :func:`trapezoid_count`
    nodes per ring) instead where it has fewer nodes.

    ``symmetry`` (see :func:`face_samples`): the plane's tilt direction (u_x, u_y) in the
    face's plane, or (0, 0) at normal incidence; the rule then keeps one node of each set
    of nodes the symmetry maps onto each other, with their summed weight (a rectangle:
    where u lies along a side or is zero).  None: every node.

    Returns points [m] ``(3, n)`` in the aperture frame and weights [m²] ``(n,)``."""
    if probe.kind == sir.RECT:
        half_width, half_height = (float(v) for v in probe.parameters[1:3])
        nx, ny = side_counts(half_width, half_height, distance, shortest_wavelength, spacing)
        points, weights = rectangle_samples(half_width, half_height, nx, ny)
        if symmetry is not None:
            for axis, half in ((0, half_width), (1, half_height)):
                if symmetry[axis] == 0.0:  # even under this coordinate's sign
                    points, weights = _fold(points, weights, axis, 1e-12 * half)
        return points, weights
    n_rings = ring_count(probe, distance, shortest_wavelength, spacing)
    axial = symmetry is not None and symmetry[0] == 0.0 and symmetry[1] == 0.0
    if probe.curvature is None and bandwidth > 0.0 and not axial:
        band_rings = bandwidth_ring_count(probe, distance, shortest_wavelength, bandwidth)
        z = bandwidth * _ring_radii(probe.radius, band_rings)
        band_nodes = np.sum(4 * np.maximum(2, np.ceil((z + 3.0 * np.cbrt(z) + 4.0) / 4.0)))
        along = 2.0 * math.pi / (4.0 * spacing) if math.isfinite(spacing) else 0.0
        rho = _ring_radii(probe.radius, n_rings)
        nyquist_nodes = np.sum(4 * np.maximum(2, np.ceil(along * rho)))
        if band_nodes < nyquist_nodes:
            return face_samples(probe, band_rings, spacing, symmetry, bandwidth)
    return face_samples(probe, n_rings, spacing, symmetry)


@functools.lru_cache(maxsize=256)
def _ring_radii(a: float, n_rings: int) -> FloatArray:
    """[m] the ring radii ``(n_rings,)`` of :func:`face_samples`' rule on a flat disc of
    radius ``a`` [m]: Gauss–Legendre nodes in s = ρ² on [0, a²] (cached: do not modify)."""
    x, _ = _gauss_legendre(n_rings)
    radii: FloatArray = np.sqrt(0.5 * (x + 1.0) * a * a)
    radii.flags.writeable = False
    return radii


def _fold(
    points: FloatArray, weights: FloatArray, axis: int, tolerance: float
) -> tuple[FloatArray, FloatArray]:
    """The nodes with ``points[axis]`` ≥ 0 of a rule symmetric under that coordinate's
    sign, those off the axis (beyond ``tolerance`` [m]) weighted twice."""
    keep = points[axis] >= -tolerance
    doubled = np.where(points[axis] > tolerance, 2.0, 1.0)
    return points[:, keep], (weights * doubled)[keep]


def find_plane(
    shapes: tuple[Shape, ...],
    origins: FloatArray,
    directions: FloatArray,
    basis: FloatArray,
    position: FloatArray,
    edge_clearance: float | None = None,
    may_miss: NDArray[np.bool_] | None = None,
) -> ImagePlane | None:
    """The plane that every ray of a footprint hits first, or None.

    Parameters
    ----------
    shapes : the specimen's shapes.
    origins, directions : [m], unit; the footprint's rays in world coordinates ``(3, n)``;
        the last one is the beam axis.
    basis : ``(3, 3)`` world → aperture rotation (rows x′, y′, −n).
    position : [m] ``(3,)`` the aperture frame's origin in world coordinates.
    edge_clearance : [m] None: every ray must hit the plane.  Else the rays may also pass
        beyond the edges of the rectangular plate (:class:`~echocal.specimen.FinitePlane`)
        that the axis hits, hitting nothing else, when the nearest point of its plane
        beyond its edges lies at least this much farther from ``position`` than the plane
        does (:func:`edge_margin`; see the module's "When it applies").
    may_miss : ``(n,)`` with ``edge_clearance``, the rays that may pass the plate's edges
        (the rest must hit it); None: any but the axis.
    """
    distance, normal, index = _cast_soa(shapes, origins, directions)
    if not np.isfinite(distance[-1]):
        return None
    shape = shapes[int(index[-1])]
    if shape.kind != "plane":
        return None
    hit = np.isfinite(distance)
    if np.any(index[hit] != index[-1]):
        return None
    if not np.all(hit):
        if edge_clearance is None or not isinstance(shape, FinitePlane):
            return None
        if may_miss is not None and np.any(~hit & ~may_miss):
            return None
        if edge_margin(shape, position) < edge_clearance:
            return None
        # the rays that pass the plate must meet its plane ahead (behind it, nothing else)
        ahead = (shape.normal @ directions[:, ~hit]) * float(shape.normal @ directions[:, -1])
        if np.any(ahead <= 0.0):
            return None
    axis_point = origins[:, -1] + directions[:, -1] * distance[-1]
    point = basis @ (axis_point - position)
    n = basis @ normal[:, -1]  # facing the ray: towards the probe
    return ImagePlane(point=point, normal=n / np.linalg.norm(n))


def edge_margin(plate: FinitePlane, position: FloatArray) -> float:
    """[m] D − h: how much farther from ``position`` [m] ``(3,)`` the nearest point of
    ``plate``'s plane beyond its edges lies (D) than the plane itself (h); 0 when the foot
    of the perpendicular from ``position`` lies on or beyond an edge."""
    offset = position - plate.center
    h = abs(float(plate.normal @ offset))
    gap = min(
        0.5 * plate.width - abs(float(plate.x_axis @ offset)),
        0.5 * plate.height - abs(float(plate.y_axis @ offset)),
    )
    if gap <= 0.0:
        return 0.0
    return math.hypot(h, gap) - h
