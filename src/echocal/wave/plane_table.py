"""The echo of an infinite plane under an axisymmetric probe, tabled over its two invariants.

Under a flat disc or a bowl the image form's echo of an infinite plane
(``WaveEchoModel.image_spectrum``) depends on the pose only through h, the plane's normal
distance from the face centre (the bowl's apex), and α, the beam axis's incidence on it:
turning the plane about the axis turns the face's nodes with it.  :class:`PlaneTable`
computes the exact spectrum at the nodes of a uniform grid in (1/h, α)
(:class:`~echocal.wave.echo_table.EchoTable`, each node on first use) and interpolates
between them, so that a setup's thousands of A-scans (Monte-Carlo studies, lobe profiles,
cost maps, sweeps) pay the exact form once per node.

**Demodulation.** Every path from the face to its mirror image has the two-way length
2h·cos β + O(…) where the path meets the plane's normal at β; the spectrum carries the
phase e^{−iω·2h/c} of the path along the normal, which turns through 2π every half
wavelength of h.  The table stores the spectrum times e^{iω(2h/c − t₀)} (t₀ the model's
time grid's first point), and a query multiplies it back by e^{−iω(2h_q/c − t₀)}: what is
interpolated is the residual, whose phase changes with h only through the paths' spread,
about k·ρ²·δ(1/h) for a lateral spread ρ ≤ 2a (hence the grid's uniform steps in 1/h,
``_INVERSE_STEP``).  Across α the response's features move by about 2a·δα across the face
(``_TILT_STEP``).  The echo is even in α (the plane tilted the other way is the same plane
turned by half a turn): the α axis reaches across 0 to the mirrored nodes.

**Exactness of what is tabled.** Each node is the exact form of a plane at (h, α), its
echo moved by a whole number of the grid's steps to the middle of the grid (an integer
shift of the grid's B-spline deposit is exact), so that no node is cut by the grid's ends;
a query is answered from the table only when its own echo (the span of the face-to-image
paths, ``_span``) lies inside the grid, else the exact form answers (it would be cut there,
the table's would wrap around).  Rectangles, whose echo depends on the tilt's azimuth too,
keep the exact form.

**Coefficients and delays.** An interior's echo (one coefficient for the whole plane, a
delay added to every path) is linear in them: conj(coefficient)·e^{−iω·delay} times the
unit, zero-delay response, which has a table of its own when the model's R(θ) varies with
each face node's angle (that table then holds R(θ) at each node's angle, exactly as the
exact form takes it).

**Between processes.** The nodes of a table that the model can name (the unit response,
or any table of a model without R(θ)) are also kept on disk (``echocal.wave.table_cache``),
so a later run, or a parallel worker, reads them instead of computing them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.wave import image
from echocal.wave.echo_table import EchoTable, TableAxis
from echocal.wave.probe import Aperture
from echocal.wave.table_cache import DiskNodes

__all__ = ["PlaneTable"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
ExactForm = Callable[[image.ImagePlane, float], tuple[ComplexArray, float]]
"""``exact(plane, delay) -> (spectrum, path_time)``: the image form's spectrum (full length)
and mean two-way time [s] of ``plane`` with ``delay`` [s] added to every path."""

_INVERSE_STEP = 0.25
"""The grid's step in 1/h, in units of 1/(k_hi·a²) (k_hi the pulse's highest wavenumber,
a the face's radius): the demodulated phase of a path whose ends lie ρ ≤ 2a apart along
the plane changes by k·ρ²/4 per unit of 1/h."""
_TILT_STEP = 0.25
"""The grid's step in α [rad], in units of 1/(k_hi·a)."""
_DEGREE = 3
"""The interpolating polynomials' degree (cubic: 4 × 4 nodes per query)."""
_TILT_LIMIT = math.radians(50.0)
"""Planes tilted further than this take the exact form."""
_MARGIN_STEPS = 8
"""Grid steps the echo must keep from the grid's ends (the pair rule's B-splines reach
four steps either side)."""


def _reference_delay(h: float, c: float) -> float:
    """[s] 2h/c: the two-way delay along the plane's normal that the table demodulates."""
    return 2.0 * h / c


class PlaneTable:
    """The tabled image-form echo of an infinite plane (see the module docstring).

    Parameters
    ----------
    exact : the exact form (``ExactForm``) the nodes are computed by.
    probe : a flat disc or a bowl.
    sound_speed : [m/s].
    shortest_wavelength : [m] at the pulse's highest frequency.
    frequencies : [Hz] the model's grid's rfft frequencies ``(size,)``.
    t0, dt : [s] the time grid's first point and step; its period is ``size`` … (the
        grid's length ``n_fft``).
    n_fft : the time grid's length.
    bins : the bins the nodes keep (``echocal.wave.echo_table.significant_bins``).
    identity : what the exact form's nodes depend on besides this table's grid and the
        code (JSON-ready: see ``WaveEchoModel._table_identity``), to keep them on disk
        between processes (``echocal.wave.table_cache``); None: in memory only (a model
        whose R(θ) is a function the cache cannot name).
    """

    def __init__(
        self,
        exact: ExactForm,
        probe: Aperture,
        sound_speed: float,
        shortest_wavelength: float,
        frequencies: FloatArray,
        t0: float,
        dt: float,
        n_fft: int,
        bins: slice,
        identity: dict[str, Any] | None = None,
    ) -> None:
        self._exact = exact
        self._a = probe.radius
        self._depth = probe.depth
        self._c = sound_speed
        self._t0, self._dt, self._period = t0, dt, n_fft * dt
        self._omega = 2.0 * math.pi * np.asarray(frequencies, dtype=np.float64)
        self._bins = bins
        self._omega_kept = self._omega[bins]
        k_hi = 2.0 * math.pi / shortest_wavelength
        inverse_step = _INVERSE_STEP / (k_hi * self._a**2)
        tilt_step = _TILT_STEP / (k_hi * self._a)
        # 1/h from the farthest plane whose echo can reach the grid to one at a tenth of
        # the face's radius (the face may not cross the plane: ``_clear``), the nodes at
        # whole multiples of the step whatever the window, so that moving the window moves
        # no node (tests/physics/test_window_invariance.py)
        far = 0.5 * sound_speed * (t0 + self._period) + 2.0 * math.hypot(self._a, self._depth)
        near = 0.1 * self._a
        first = max(1, math.floor(1.0 / (far * inverse_step)) - _DEGREE)
        count = math.ceil(1.0 / (near * inverse_step)) - first + 1
        u = TableAxis(first * inverse_step, inverse_step, count)
        v = TableAxis(0.0, tilt_step, math.ceil(_TILT_LIMIT / tilt_step) + _DEGREE + 1, even=True)
        store = None
        if identity is not None:
            grid = {"u": [u.start, u.step], "v": v.step, "bins": [bins.start, bins.stop]}
            store = DiskNodes("plane", {**identity, **grid})
        self.table = EchoTable(self._node, u, v, bins, self._omega.size, _DEGREE, store)

    def _span(self, h: float, alpha: float) -> tuple[float, float]:
        """[s] bounds on the two-way times of every path from the face to its image across
        the plane at normal distance ``h`` [m] and incidence ``alpha`` [rad] (no delay):
        a point x of the face lies e(x) = h + n·x above the plane, n·x within
        [−a sin α − depth, a sin α], and the path from x to the image of y has the length
        √(|x − y|²_∥ + (e(x) + e(y))²), |x − y|_∥ ≤ 2a."""
        lift = self._a * math.sin(alpha)
        low = 2.0 * (h - lift - self._depth)
        high = math.hypot(2.0 * self._a, 2.0 * (h + lift))
        return low / self._c, high / self._c

    def _node(self, u: float, alpha: float) -> tuple[ComplexArray, float]:
        """The demodulated exact spectrum and path time (less 2h/c and the shift) at
        1/h = ``u`` [1/m], incidence ``alpha`` [rad]."""
        h = 1.0 / u
        plane = image.ImagePlane(
            point=np.array([0.0, 0.0, h / math.cos(alpha)]),
            normal=np.array([math.sin(alpha), 0.0, -math.cos(alpha)]),
        )
        low, high = self._span(h, alpha)
        middle = self._t0 + 0.5 * self._period
        shift = self._dt * round((middle - 0.5 * (low + high)) / self._dt)
        spectrum, path_time = self._exact(plane, shift)
        reference = _reference_delay(h, self._c) + shift
        return spectrum * np.exp(1j * self._omega * (reference - self._t0)), path_time - reference

    def __call__(
        self, plane: image.ImagePlane, coefficient: complex = 1.0, delay: float = 0.0
    ) -> tuple[ComplexArray, float] | None:
        """The spectrum (full length, 0 outside the kept bins) and mean two-way time [s] of
        ``plane``'s echo, times conj(``coefficient``), every path ``delay`` [s] longer; or
        None where the exact form must answer (a tilt beyond ``_TILT_LIMIT``, a plane
        nearer than the table reaches or than the face's own extent allows, an echo that
        the time grid would cut)."""
        h = abs(float(plane.normal @ plane.point))
        alpha = math.asin(min(1.0, plane.sin_incidence))
        if alpha > _TILT_LIMIT or not self._clear(h, alpha):
            return None
        low, high = self._span(h, alpha)
        margin = _MARGIN_STEPS * self._dt
        if low + delay < self._t0 + margin or high + delay > self._t0 + self._period - margin:
            return None
        kept, side = self.table(1.0 / h, alpha)
        reference = _reference_delay(h, self._c) + delay
        phase = np.exp(-1j * self._omega_kept * (reference - self._t0))
        out = np.zeros(self._omega.size, dtype=np.complex128)
        out[self._bins] = kept[self._bins] * phase * np.conj(complex(coefficient))
        return out, side + reference

    def _clear(self, h: float, alpha: float) -> bool:
        """Whether every node a query at (``h``, ``alpha``) reads lies in the table and
        keeps the face off the plane (nodes up to ``_DEGREE`` steps nearer and more
        tilted)."""
        u_axis, v_axis = self.table.u, self.table.v
        u = 1.0 / h
        if not u_axis.start <= u <= u_axis.stop:
            return False
        nearest = 1.0 / (u + _DEGREE * u_axis.step)
        steepest = alpha + _DEGREE * v_axis.step
        return nearest - self._a * math.sin(steepest) - self._depth > 0.05 * self._a
