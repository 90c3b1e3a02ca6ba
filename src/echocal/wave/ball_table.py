"""The echo of a lone ball from a table over its two invariants.

A circular piston (flat or a bowl) and a ball are symmetric enough that the whole echo
spectrum, R(θ) at each surface point's incidence from the face centre included, depends
on two numbers only: D, the distance from the face centre (a bowl's apex) to the ball's
centre, and ψ, the angle between the beam axis and the line to the centre.  Any pose
turns into the canonical one (the ball's centre at the origin, the face centre at
(0, 0, D), the axis turned by ψ off the line to the centre towards +x) by a rotation
about the ball's centre and one about the probe's own axis, neither of which changes the
Kirchhoff integral.

The table's nodes are that canonical pose's echo through the exact Kirchhoff sum
(``WaveEchoModel.kirchhoff_echo``), demodulated by the two-way delay τ = 2(D − R)/c of the
path from the face centre to the ball's top (with the grid's first time t₀: the spectrum
times e^{i2πf(τ − t₀)}), so that what is interpolated varies only as the echo's shape
does: in ψ like the probe's two-way directivity towards the centre (its lobes about
λ/(2a) apart in sin ψ), in D by diffraction (the rim's path excess a²/(D − R)).
The lookup re-modulates with the query's own τ and t₀.

Each node is computed with its recording window moved so that the whole echo (``span``)
lies on the grid; a query whose grid does not hold the whole echo (the exact sum would
drop what falls off it) takes the exact sum instead.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from echocal.specimen.base import Shape
from echocal.specimen.sphere import Sphere
from echocal.wave.echo_table import TableAxis

__all__ = [
    "BallPose",
    "axes",
    "ball_pose",
    "canonical_pose",
    "distance_coordinate",
    "distance_from_coordinate",
    "span",
]

FloatArray = NDArray[np.float64]

ANGLE_STEP = 1.0 / 7.0
"""ψ's step [rad] in units of λ_hi/(2a) (λ_hi at the pulse's highest frequency, a the face's
radius): the scale on which the two-way directivity towards the centre varies."""
DISTANCE_PHASE_STEP = 0.3
"""Near the ball, the step of the top's distance h = D − R is at most this [rad] over
k_hi·a²/h² (k_hi = 2π/λ_hi, a the face's radius): the rim's two-way path excess over the
face centre's, at most a²/h (the plane's), turns its phase by at most this per step."""
DISTANCE_STEP = 0.02
"""Farther out, h's step is at most this fraction of h: the echo's amplitude and shape
change with h by diffraction, as powers of h."""


def distance_coordinate(top: float, knee: float) -> float:
    """The table's u at the top's distance h = ``top`` [m]: ln(h/1 m) − h*/h, h* = ``knee``
    [m] (``axes``).  Uniform steps ε in u are steps ε·h²/(h + h*) in h: the phase rule's
    ε·h²/h* nearer than h*, ε·h beyond it."""
    return math.log(top) - knee / top


def distance_from_coordinate(u: float, knee: float) -> float:
    """[m] the h whose ``distance_coordinate`` is ``u``: Newton's method on x = ln h, where
    u(x) = x − h*·e^{−x} is increasing and concave, so that after the first step from
    above the root (never below u) it climbs to it monotonically, to machine precision."""
    x = max(u, math.log(knee)) + 1.0  # ln h, above the root
    for _ in range(100):
        h = math.exp(x)
        step = (x - knee / h - u) / (1.0 + knee / h)
        x -= step
        if abs(step) < 1e-15 * max(1.0, abs(x)):
            break
    return math.exp(x)


@dataclasses.dataclass(frozen=True)
class BallPose:
    """A probe's pose over a ball, by its invariants.

    Attributes
    ----------
    radius : [m] the ball's radius R.
    distance : [m] D, from the face centre (a bowl's apex) to the ball's centre.
    angle : [rad] ψ, between the beam axis and the line from the face centre to the centre.
    """

    radius: float
    distance: float
    angle: float


def ball_pose(
    shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray, face_radius: float
) -> BallPose | None:
    """The invariants of a pose over one ball whose surface keeps clear of the face by
    more than ``face_radius`` [m] (the scenes ``WaveEchoModel._cap`` takes), or None.

    ``position`` [m] ``(3,)``: the face centre; ``frame`` ``(3, 3)``: columns x', y', n
    (the beam along −n)."""
    if len(shapes) != 1 or not isinstance(shapes[0], Sphere):
        return None
    ball = shapes[0]
    towards = ball.center - position
    distance = float(np.linalg.norm(towards))
    if distance <= ball.radius + face_radius:
        return None
    cos_angle = float(-(frame[:, 2] @ towards)) / distance
    return BallPose(float(ball.radius), distance, math.acos(min(1.0, max(-1.0, cos_angle))))


def axes(
    face_radius: float, depth: float, shortest_wavelength: float, anchor: float
) -> tuple[TableAxis, TableAxis, float]:
    """A ball's table's axes under a face of ``face_radius`` a [m] (a bowl ``depth`` [m]
    deep), λ_hi = ``shortest_wavelength`` [m]: u = ``distance_coordinate`` of the top's
    distance h = D − R from just above √(a² + depth²) (the nearest pose
    ``WaveEchoModel._cap`` takes) to 100 m, its knee h* = ``DISTANCE_STEP``·k_hi·a² /
    ``DISTANCE_PHASE_STEP``, with a node at h = ``anchor`` [m] (the first query's: every
    later one from the same position, as the orientations of a lobe or a calibration,
    needs the nodes of that line only); v = ψ [rad] from 0 (even: the echo at −ψ is the one
    at ψ) past π (``ANGLE_STEP``).  Returns (u, v, h*)."""
    nearest = math.hypot(face_radius, depth) * (1.0 + 1e-9)
    k_hi = 2.0 * math.pi / shortest_wavelength
    knee = DISTANCE_STEP * k_hi * face_radius * face_radius / DISTANCE_PHASE_STEP
    lowest = distance_coordinate(nearest, knee)
    on = distance_coordinate(max(anchor, nearest), knee)
    start = on - math.floor((on - lowest) / DISTANCE_STEP) * DISTANCE_STEP
    count = math.ceil((distance_coordinate(100.0, knee) - start) / DISTANCE_STEP) + 1
    u = TableAxis(start=start, step=DISTANCE_STEP, count=max(4, count))
    dv = ANGLE_STEP * shortest_wavelength / (2.0 * face_radius)
    v = TableAxis(start=0.0, step=dv, count=math.ceil(math.pi / dv) + 1, even=True)
    return u, v, knee


def canonical_pose(
    radius: float, distance: float, angle: float
) -> tuple[tuple[Shape, ...], FloatArray, FloatArray]:
    """The canonical scene of a ball of ``radius`` [m]: its centre at the origin, the face
    centre at (0, 0, ``distance``) [m], the beam axis turned by ``angle`` [rad] from −z
    towards +x.  Returns (shapes, position ``(3,)``, frame ``(3, 3)``)."""
    s, c = math.sin(angle), math.cos(angle)
    frame = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])  # columns x', y', n
    return (Sphere(center=(0.0, 0.0, 0.0), radius=radius),), np.array([0.0, 0.0, distance]), frame


def span(
    pose: BallPose, face_radius: float, depth: float, sound_speed: float, cap_radius: float
) -> tuple[float, float]:
    """[s] bounds on the two-way times of a ball's echo before and after τ = 2(D − R)/c
    (a face of ``face_radius`` a [m], a bowl ``depth`` [m] deep): (before, after).

    Before: every path from a face point p to the surface is at least |p − C| − R (C the
    ball's centre), and |p − C| ≥ D·cos ψ for a flat face (where D·sin ψ ≤ a; else
    √(D² + a² − 2aD·sin ψ)), D − √(a² + depth²) for a bowl.  After: the cap's samples
    (``WaveEchoModel._cap``: the fan's rays through a disc of ``cap_radius``/2 [m] about
    the face centre from an apex D − R behind it) lie at most L from the face centre, L
    where the fan's outermost ray meets the ball (its limb if that ray misses), so every
    path is at most L + √(a² + depth²)."""
    big_r, d = pose.radius, pose.distance
    reach = math.hypot(face_radius, depth)
    if depth > 0.0:
        nearest = d - reach
    else:
        lateral = d * math.sin(pose.angle)
        rho = min(face_radius, lateral)
        nearest = math.sqrt(max(0.0, d * d + rho * rho - 2.0 * rho * lateral))
    top = d - big_r
    # the outermost ray in the cap's frame: from (0, 0, −top) through (cap_radius/2, 0, 0);
    # the ball's centre at (0, 0, d)
    slope = 0.5 * cap_radius / top  # dx/dz
    norm = math.sqrt(1.0 + slope * slope)
    ux, uz = slope / norm, 1.0 / norm
    # |(0, 0, −top) + t (ux, 0, uz) − (0, 0, d)|² = R²
    b = -(top + d) * uz
    disc = b * b - ((top + d) ** 2 - big_r * big_r)
    if disc < 0.0:
        far = math.sqrt(d * d - big_r * big_r)  # the limb
    else:
        t = -b - math.sqrt(disc)
        far = math.hypot(t * ux, -top + t * uz)
    return 2.0 * (d - nearest) / sound_speed, 2.0 * (far + reach - top) / sound_speed
