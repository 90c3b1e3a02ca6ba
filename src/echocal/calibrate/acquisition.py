"""Acquisition phase for poor first guesses: find the echo, then hand over to a local method.

When the start lies at the noise floor, every local method wanders on noise.
:class:`Acquisition` first measures x0 and a hexagonal lattice outward from it, ring by ring
(:func:`search_rings`), until a value is *clearly above noise*:

    max_i (m_i − floor) / (σ / √n_i) > ``threshold``   (default 4.5),

m_i the mean of point i and its n_i − 1 measured lattice neighbours (averaging shows a peak
no single value does, as at 10 dB), the floor the objective's ``noise_floor`` or the median,
σ its ``noise_sigma`` or 1.4826 · MAD of the values.  With a ``detector`` (the
matched-filter significance of each A-scan, :meth:`~echocal.calibrate.Objective.detections`)
the test combines those significances over the same neighbourhoods as Σg/√n_i (Stouffer)
instead — a better detector than the energy.  x0 and its first ring are measured before
deciding.  The local method starts at the best point and, if it takes a warm start
(``history``), gets every measurement.  A search past ``max_radius`` stops with status 4.

With ``posterior`` (``auto``'s default) and an ``echo_likelihood``, the search beyond x0's
first ring is Bayesian instead (:mod:`echocal.calibrate.posterior_search`); the detection
test, its confirmation and the hand-over are the same.  With a detector the local method
must confirm the echo it was handed within :data:`CONFIRM_WITHIN` measurements, and where
the likelihood is known the echo must be one it allows (:data:`ECHO_WITHIN`); else the
detection was a false alarm and the search resumes where it stood.  Acquisition batches are
not counted as iterations.
"""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal._validate import capped_float
from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import (
    accepted_options,
    check_option_types,
    finite_float,
    nonnegative_float,
    optional,
    optional_callable,
    positive_float,
    positive_int,
    strict_bool,
    suggestion,
)
from echocal.calibrate.base import Optimizer
from echocal.calibrate.lobe_template import LobeTemplate
from echocal.calibrate.posterior_search import (
    GIVE_UP_EVIDENCE,
    EchoHypotheses,
    EchoLikelihood,
    PosteriorSearch,
)
from echocal.calibrate.registry import get_method, register_method
from echocal.constants import ECHO_THRESHOLD
from echocal.errors import EchocalValueError

__all__ = [
    "LOCAL_INPUTS",
    "MAX_SEARCH_RADIUS",
    "Acquisition",
    "Detector",
    "NoiseModel",
    "hex_spiral",
    "search_rings",
]

NoiseModel = Callable[[], tuple[float | None, float | None]]
"""A live ``(noise_floor, noise_sigma)`` estimate [energy units] (either may be None)."""

_FIRST_RING = 7
"""x0 and its hexagonal first ring: measured as one batch, tested at ``first_threshold``,
and, when none of them sees the echo, the moment the search is replanned."""
_SURE_MARGIN = 2.0
"""A detection this many σ above ``threshold`` needs no confirmation."""
_CONFIRM_LEVEL = 1.0
"""The repeat's own significance must exceed this (noise does so 16 % of the time)."""
CONFIRM_WITHIN = 8
"""Measurements the local method gets to confirm the echo it was handed (one of them, or
all together by Stouffer, significant at ``threshold``); else a false alarm."""
ECHO_WITHIN = 16
"""Measurements after which, where the echo's likelihood is known, the local phase's
strongest peak must reach :data:`WEAK_ECHO_DB` of the weakest echo it allows at the
optimum; else it climbs something else (a lobe's far structure, a weaker reflector)."""
WEAK_ECHO_DB = -6.0
"""[dB] of the weakest echo peak the search's likelihood allows (a recording's or a rig's
hypotheses: 30 dB, so a normalized peak of 16; a simulated probe: its known peak)."""
_PEAK_TABLE_TOP = 60.0
"""The normalized peak a significance is read back to at most (its table ends at 64)."""

LOCAL_INPUTS = ("noise_model", "lobe_template", "normal_echo", "resolution")
"""Inputs from the objective a local method may take (handed on by an acquisition)."""

Detector = Callable[[], "FloatArray | None"]
"""The detection significances of the points just measured, shape (k,), or None."""

MAX_SEARCH_RADIUS = 180.0
"""[deg] the farthest a search may go from x0 (180° of tilt reach every orientation)."""
_CAP_WHY = "deg (180 deg of tilt reach every orientation)"


def _local_options(
    local: str, cls: type[Optimizer], options: Mapping[str, Any] | None
) -> dict[str, Any]:
    """``local_options`` checked now, not when the echo is found: a dict whose names the
    local method accepts and whose values have the right types."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise EchocalValueError(
            f"local_options must be a dict of options for the local method {local!r} "
            f'(e.g. {{"radius": 0.5}}); got {options!r}'
        )
    valid = accepted_options(cls)
    for key in options:
        if key not in valid:
            raise EchocalValueError(
                f"local_options: unknown option {key!r} of method {local!r}"
                f"{suggestion(str(key), valid)}; accepted: {', '.join(sorted(valid))}"
            )
    check_option_types(cls, options, where=f"method {local!r} (local_options)")
    return dict(options)


def _spacings(name: str, values: Any) -> tuple[float, ...]:
    """A list of positive spacings [deg] (``passes``), or EchocalValueError naming it."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise EchocalValueError(
            f"{name} must be a list of spacings in degrees, coarse to fine (e.g. [4.2]); "
            f"got {values!r}"
        )
    return tuple(positive_float(f"{name}[{i}]", v) for i, v in enumerate(values))


# -- where a blind search looks (angles [deg], points (k, 2)) ---------------------------
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
    """Search rings around ``center`` [deg], in the order they are searched (arrays (k_i, 2),
    the first ``center``): the hexagonal lattice of ``spacing`` out to ``fine_radius``, then
    circles whose point spacing s = ``max(spacing, growth · r)`` (capped at
    ``max_spacing``) and circle spacing (√3/2)·s grow with the radius r, out to the first
    beyond ``max_radius`` by no more than s/√3: every point of the disc within ≈ 0.66 s of a
    search point (measured; partly staggered circles).

    ``passes`` [deg]: beyond ``fine_radius`` instead a pass per spacing s, coarse to fine,
    each the hexagonal lattice of spacing s (every point within s/√3 of one of its points)
    without the points inside the fine lattice's hexagon, beyond ``max_radius`` + s/√3, or
    within s/4 of a point searched before.  Each pass is turned by 30° from the next finer
    one's, so a pass √3 times coarser is part of it and costs the finer one nothing.  A
    coarse first pass finds a strong echo far away in few measurements; a weaker one is
    seen from less far, by the next pass.
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


@register_method("acquisition")
class Acquisition(Optimizer):
    """Outward hexagonal search until the echo is clearly above noise, then a local method.

    Parameters
    ----------
    local : name of the local method (default ``"model-based"``).
    local_options : dict of options for the local method, checked at construction.
    spacing : [deg] lattice spacing (≈ the peak width: a peak of width w stays
        detectable up to ~1.7 w from its centre at 30 dB with threshold 6).
    max_radius : [deg] give up beyond this distance from x0.
    threshold : detection threshold in units of σ.
    first_threshold : the threshold while only x0 and the first ring are measured.
    confirm : (true or false) a marginal detection (below ``threshold`` + 2) must survive
        one re-measurement of its best point: the repeat joins its neighbourhood, which
        must still pass, and with a detector its own significance must exceed 1.
    noise_sigma : [energy units] known noise σ (None: estimated from the data).
    noise_floor : [energy units] mean value of pure noise (None: median of the data).
    noise_model : callable returning the objective's live ``(noise_floor, noise_sigma)``
        (either may be None), used where the fixed values above are None.
    lobe_template, normal_echo, resolution : handed to a local method that takes them
        (:meth:`~echocal.calibrate.Objective.lobe_template`,
        :meth:`~echocal.calibrate.Objective.normal_echo`, and ``resolution`` [deg], a
        replay's grid step; None: continuous).
    detector : callable returning the detection significances of the points just
        measured, shape (k,), or None (then the values are tested) — e.g.
        :meth:`~echocal.calibrate.Objective.detections`.
    batch : maximum points per acquisition ask (1 = stop at the first detection).
    fine_radius : [deg] the lattice of ``spacing`` out to this distance from x0, coarser
        circles or passes beyond (:func:`search_rings`).
        Default: infinite (the fine lattice everywhere).
    growth : beyond ``fine_radius`` the point spacing is ``max(spacing, growth · r)``.
    max_spacing : [deg] cap on that spacing (gaps of up to ≈ 0.66 × it).
    passes : [deg] point spacings of hexagonal passes beyond ``fine_radius``, coarse to
        fine, instead of circles: a weaker echo than the first pass saw is searched for
        again, more densely.  Default: none (circles).
    replan : callable returning the passes for the rest of the search once x0 and its
        first ring saw no echo, or None to keep the plan — e.g.
        :meth:`~echocal.calibrate.Objective.passes_for_measured_noise`.  They replace
        ``passes`` and the fine lattice beyond the first ring, unless their first pass is
        finer than every planned one (a weaker echo than planned: the fine lattice stays
        out to ``fine_radius``).  Called once.
    echo_likelihood : callable returning how the detector's significance is distributed
        versus misalignment (:class:`~echocal.calibrate.posterior_search.EchoLikelihood`
        or :class:`~echocal.calibrate.posterior_search.EchoHypotheses`) or None — e.g.
        :meth:`~echocal.calibrate.Objective.echo_likelihood`.
    posterior : (true or false) once x0 and its first ring saw no echo, given a
        ``detector``, an ``echo_likelihood`` (asked then, once) and ``batch`` 1, search by
        the posterior over the optimum instead of the lattice
        (:mod:`echocal.calibrate.posterior_search`); it gives up (status 4) once the
        measurements are 1,000 times likelier with no echo within ``max_radius`` than
        with one.  ``replan`` is then not asked.
    move_time : callable returning the positioner's time [s] to reach each of points
        [deg] ``(k, 2)``, ``(k,)``, or None — e.g.
        :meth:`~echocal.calibrate.Objective.move_times`: the posterior search weighs a
        shorter move against a lower detection chance
        (:meth:`~echocal.calibrate.posterior_search.PosteriorSearch.next_point`).
    measurement_price : [s] the bench time of a measurement apart from its travel, or
        None (0) — e.g. :meth:`~echocal.calibrate.Objective.measurement_price`.
    """

    def __init__(
        self,
        x0: ArrayLike,
        *,
        local: str = "model-based",
        local_options: dict[str, Any] | None = None,
        spacing: float = 1.0,
        max_radius: float = 20.0,
        threshold: float = ECHO_THRESHOLD,
        first_threshold: float = 3.0,
        confirm: bool = True,
        noise_sigma: float | None = None,
        noise_floor: float | None = None,
        noise_model: NoiseModel | None = None,
        lobe_template: Callable[[], LobeTemplate | None] | None = None,
        normal_echo: Callable[[], float | None] | None = None,
        resolution: float | None = None,
        detector: Detector | None = None,
        batch: int = 1,
        fine_radius: float | None = None,
        growth: float = 0.0,
        max_spacing: float | None = None,
        passes: Sequence[float] = (),
        replan: Callable[[], Sequence[float] | None] | None = None,
        echo_likelihood: Callable[[], EchoLikelihood | EchoHypotheses | None] | None = None,
        posterior: bool = False,
        move_time: Callable[[FloatArray], FloatArray | None] | None = None,
        measurement_price: float | None = None,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize="none")
        self.noise_model = noise_model
        self.lobe_template = lobe_template
        self.normal_echo = normal_echo
        self.resolution = optional(positive_float, "resolution", resolution)
        self.detector = detector
        self._use_significance = detector is not None
        if not isinstance(local, str):
            raise EchocalValueError(f"local must be a method name; got {local!r}")
        self._local_cls = get_method(local)
        if self._local_cls is Acquisition or issubclass(self._local_cls, Acquisition):
            raise EchocalValueError(f"local must be a local method, not {local!r}")
        self.local_name = local
        self._local_params = inspect.signature(self._local_cls.__init__).parameters
        self.local_options = _local_options(local, self._local_cls, local_options)
        self._local_normalize = normalize
        self.spacing = positive_float("spacing", spacing)
        self.max_radius = capped_float("max_radius", max_radius, MAX_SEARCH_RADIUS, _CAP_WHY)
        self.threshold = positive_float("threshold", threshold)
        self.first_threshold = positive_float("first_threshold", first_threshold)
        self.confirm = strict_bool("confirm", confirm)
        self._confirming: FloatArray | None = None  # a detection's best point to re-measure
        self._confirmed = 0  # re-measurements made
        self.noise_sigma = optional(nonnegative_float, "noise_sigma", noise_sigma)
        self.noise_floor = optional(finite_float, "noise_floor", noise_floor)
        self.batch = positive_int("batch", batch)
        self.fine_radius = (
            np.inf if fine_radius is None else positive_float("fine_radius", fine_radius)
        )
        self.growth = nonnegative_float("growth", growth)
        self.max_spacing = optional(positive_float, "max_spacing", max_spacing)
        self.passes = _spacings("passes", passes)
        if self.passes and (self.growth > 0.0 or self.max_spacing is not None):
            raise EchocalValueError(
                "growth and max_spacing shape the circles searched when passes is empty; "
                f"with passes {list(self.passes)} they have no effect: give passes=[] to "
                "search in circles, or leave growth and max_spacing out"
            )
        self.replan = optional_callable("replan", replan)
        self.echo_likelihood = optional_callable("echo_likelihood", echo_likelihood)
        self.posterior = strict_bool("posterior", posterior)
        self.move_time = optional_callable("move_time", move_time)
        self.measurement_price = optional(nonnegative_float, "measurement_price", measurement_price)
        self.search: PosteriorSearch | None = None
        """The Bayesian search once it has taken over from the lattice (None: the lattice)."""
        self._search_asked = False
        self.replanned: tuple[float, ...] | None = None
        """The passes ``replan`` returned (None: the plan was kept, or not yet asked)."""
        self._queue, self._ring = self._search_queue(self.fine_radius, self.passes)
        self._next = 0
        self._raw_significance = np.zeros(0)  # the detector's last significances, NaN kept
        self._x = np.zeros((0, 2))
        self._y = np.zeros(0)
        self._g = np.zeros(0)  # detection significance per point (when a detector is used)
        self._sum = np.zeros((0, 2))  # neighbourhood sums of (value, significance)
        self._cnt = np.zeros(0, dtype=np.int64)
        self.local: Optimizer | None = None
        """The local optimizer once the echo has been found."""
        self.found_at: int | None = None
        """Measurements spent by the acquisition phase (None while searching)."""
        self.false_alarms = np.zeros((0, 2))
        """[deg] (k, 2) the detections the local method did not confirm (the search
        resumed after each)."""
        self._local_g: list[float] = []  # the local phase's significances, until checked
        self._local_x = np.zeros((0, 2))
        self._local_y = np.zeros(0)
        self._echo_confirmed = False
        self._handed = self.x0.copy()  # [deg] where the local phase was started

    def _search_queue(
        self, fine_radius: float, passes: tuple[float, ...]
    ) -> tuple[FloatArray, np.ndarray]:
        """The points to search, in order, shape ``(n, 2)`` [deg], and the ring of each,
        shape ``(n,)``: :func:`search_rings` around x0,
        within the bounds."""
        rings = search_rings(
            self.x0,
            self.spacing,
            self.max_radius,
            fine_radius=fine_radius,
            growth=self.growth,
            max_spacing=self.max_spacing,
            passes=passes,
        )
        pts = np.vstack(rings)
        inside = np.all((pts >= self.bounds[:, 0]) & (pts <= self.bounds[:, 1]), axis=1)
        ring = np.concatenate([np.full(len(r), k) for k, r in enumerate(rings)])
        return pts[inside], ring[inside]

    def _replan(self) -> None:
        """Once x0's first ring has been searched in vain: the passes ``replan`` gives, if
        any, replace the planned ones (see ``replan``); what was measured stays measured."""
        first = self._first_ring_size()
        if self.replan is None or self._next < first:
            return
        plan, self.replan = self.replan(), None
        if plan is None:
            return
        passes = _spacings("replan", plan)
        weaker = bool(self.passes) and passes[0] < min(self.passes)
        queue, ring = self._search_queue(self.fine_radius if weaker else self.spacing, passes)
        if len(queue) < first or not np.allclose(queue[:first], self._queue[:first]):
            return  # the bounds clip the first ring differently: keep the plan
        self.replanned = passes
        self._queue = np.vstack([self._queue[: self._next], queue[first:]])
        self._ring = np.concatenate([self._ring[: self._next], ring[first:]])

    def _start_search(self) -> None:
        """Once x0's first ring has seen no echo: hand the search to the posterior
        (``posterior``, a detector, one point per ask, and the echo's likelihood, asked
        once now)."""
        if (
            not self.posterior
            or self._search_asked
            or self._next < self._first_ring_size()
            or self.batch != 1
            or not self._use_significance
            or self.echo_likelihood is None
        ):
            return
        self._search_asked = True
        likelihood = self.echo_likelihood()
        if likelihood is None:
            return
        self.search = PosteriorSearch(self.x0, self.max_radius, likelihood, self.bounds)
        self.search.update(self._x, self._g)

    def _update_search(self, points: FloatArray, ok: np.ndarray, sig: FloatArray | None) -> None:
        """Fold the points just measured into the posterior (their raw significances: NaN
        is no evidence); a point that measured NaN is not asked again; once the detector
        stops giving significances the posterior can learn nothing more, and the search
        goes back to the lattice where it left it (the replan asked then)."""
        search = self.search
        if search is None:
            return
        if sig is None:
            self.search = None
            self._replan()
            return
        search.update(points[ok], self._raw_significance[ok])
        for point in points[~ok]:
            search.exclude(point)

    def _search_exhausted(self) -> bool:
        """Whether the posterior search has given up: the measurements are
        1 / :data:`~echocal.calibrate.posterior_search.GIVE_UP_EVIDENCE` times likelier
        with no echo within ``max_radius`` than with one."""
        return self.search is not None and self.search.log_evidence() < np.log(GIVE_UP_EVIDENCE)

    @property
    def batch_size(self) -> int:  # type: ignore[override]
        return self.local.batch_size if self.local is not None else 1

    @property
    def min_budget(self) -> int:
        return self._first_ring_size() if len(self._queue) else 1

    def _add(self, points: FloatArray, values: FloatArray, significance: FloatArray) -> None:
        """Append measurements and update the neighbour sums (lattice neighbours: points
        within 1.01 spacing, each point being its own neighbour)."""
        for p, v, g in zip(points, values, significance, strict=True):
            near = np.hypot(*(self._x - p).T) <= 1.01 * self.spacing if len(self._x) else []
            self._sum[near] += (v, g)
            self._cnt[near] += 1
            own = np.array([v, g]) + np.stack([self._y[near], self._g[near]], axis=1).sum(axis=0)
            self._sum = np.vstack([self._sum, own[None, :]])
            self._cnt = np.append(self._cnt, 1 + int(np.count_nonzero(near)))
            self._x = np.vstack([self._x, p[None, :]])
            self._y = np.append(self._y, v)
            self._g = np.append(self._g, g)

    def _significances(self, k: int) -> FloatArray | None:
        """The detector's significances of the last k measured points, or None — after
        which the values are tested for the rest of the search."""
        if not self._use_significance or self.detector is None:
            return None
        sig = self.detector()
        if sig is None or np.shape(sig) != (k,):
            if sig is not None:
                warnings.warn(
                    f"the detector returned shape {np.shape(sig)} for {k} measured point(s); "
                    "the acquisition tests the values instead for the rest of the search",
                    UserWarning,
                    stacklevel=4,
                )
            self._use_significance = False
            return None
        sig = np.asarray(sig, dtype=np.float64)
        self._raw_significance = sig  # NaN kept: the posterior skips it (no evidence)
        return np.where(np.isnan(sig), 0.0, sig)  # NaN (e.g. no noise estimate yet): no evidence

    def scores(self) -> FloatArray:
        """Detection statistic per measured point, shape (n,): z-score of the mean of the
        point and its measured lattice neighbours above the noise floor (with a detector:
        their combined significance Σg/√n)."""
        if self._use_significance:
            return self._sum[:, 1] / np.sqrt(self._cnt)
        y = self._y
        floor, sigma = self.noise_floor, self.noise_sigma
        if self.noise_model is not None:
            live_floor, live_sigma = self.noise_model()
            floor = live_floor if floor is None else floor
            sigma = live_sigma if sigma is None else sigma
        floor = float(np.median(y)) if floor is None else floor
        if sigma is None:
            sigma = 1.4826 * float(np.median(np.abs(y - np.median(y))))
        mean = self._sum[:, 0] / self._cnt
        if sigma <= 0.0:
            return np.where(mean > floor, np.inf, -np.inf)
        return (mean - floor) / (sigma / np.sqrt(self._cnt))

    def _threshold(self) -> float:
        # x0 and its first ring: only 7 tests, so a lower threshold keeps the false-alarm
        # rate low (7 Q(3) ≈ 1 %, neighbourhoods overlapping) and a start near a weak
        # peak hands over at once; repeats made to confirm do not count as new points
        first_ring = len(self._y) - self._confirmed <= _FIRST_RING
        return self.first_threshold if first_ring else self.threshold

    def _first_ring_size(self) -> int:
        """x0 and its first ring as the bounds leave them: measured as one batch."""
        return min(_FIRST_RING, len(self._queue))

    def _detected(self) -> bool:
        if len(self._y) < self._first_ring_size() or len(self._y) == 0:
            return False
        return bool(np.max(self.scores()) > self._threshold())

    @property
    def local_class(self) -> type[Optimizer]:
        """The class of the local method (``local``)."""
        return self._local_cls

    def local_setup(self) -> dict[str, Any]:
        """The options the local method will be built with, apart from the warm-start
        ``history`` (this phase's measurements, handed over when the echo is found):
        ``local_options`` plus what this phase supplies — its spacing as the design
        ``radius`` of a warm-started method, its noise model and floor, ``normalize``."""
        opts = dict(self.local_options)
        params = self._local_params
        if "history" in params and "radius" in params:
            opts.setdefault("radius", self.spacing)
        for name in LOCAL_INPUTS:
            if name in params and getattr(self, name) is not None:
                opts.setdefault(name, getattr(self, name))
        if "noise_floor" in params and self.noise_floor is not None:
            opts.setdefault("noise_floor", self.noise_floor)
        opts.setdefault("normalize", self._local_normalize)
        return opts

    def _start_local(self, best: FloatArray | None = None) -> None:
        best = self._x[int(np.argmax(self.scores()))] if best is None else best
        opts = self.local_setup()
        if "history" in self._local_params:
            opts.setdefault("history", (self._x.copy(), self._y.copy()))
        self.local = self._local_cls(best, bounds=self.bounds, rng=self.rng, **opts)
        self._iterate = best.copy()
        self.found_at = self.n_told
        self._handed = best.copy()
        self._local_g, self._local_x, self._local_y = [], np.zeros((0, 2)), np.zeros(0)
        self._echo_confirmed = not self._use_significance  # values alone: not checked
        # the echo's strength is checked against the echo's likelihood, where there is one
        known = self.search is not None or (self.posterior and self.echo_likelihood is not None)
        self._strength_checked = self._echo_confirmed or not known

    def _check_local(self, points: FloatArray, values: FloatArray) -> bool:
        """Whether the local phase's measurements refute the detection it was handed (the
        search then resumes, :meth:`_resume`): none of its first :data:`CONFIRM_WITHIN`, nor
        all together (Σg/√n), significant at ``threshold``; or, where the echo's likelihood
        is known, the strongest of its first :data:`ECHO_WITHIN` too weak
        (:meth:`_too_weak`).  Checked once each."""
        if self._echo_confirmed and self._strength_checked:
            return False
        sig = self._significances(len(points))
        if sig is None:  # the detector stopped answering: nothing to check against
            self._echo_confirmed = self._strength_checked = True
            return False
        ok = ~self.last_nan
        self._local_x = np.vstack([self._local_x, points[ok]])
        self._local_y = np.append(self._local_y, values[ok])
        self._local_g.extend(sig[ok].tolist())
        g = np.asarray(self._local_g)
        if not self._echo_confirmed:
            if g.size and (g.max() > self.threshold or g.sum() / np.sqrt(g.size) > self.threshold):
                self._echo_confirmed = True
            else:
                return g.size >= CONFIRM_WITHIN
        if g.size < ECHO_WITHIN:
            return False
        self._strength_checked = True
        return self._too_weak(float(g.max()))

    def _too_weak(self, significance: float) -> bool:
        """Whether the strongest significance of the local phase, read back to a normalized
        peak t, stays below :data:`WEAK_ECHO_DB` of the weakest echo peak at the optimum
        that the echo's likelihood allows (the posterior search's, else asked now; at most
        :data:`_PEAK_TABLE_TOP`).  False without a likelihood."""
        if self.search is not None:
            like = self.search.likelihood
        else:  # handed on from x0's first ring, before the posterior search was asked
            asked = self.echo_likelihood() if self.echo_likelihood is not None else None
            if asked is None:
                return False
            like = asked
        models = (like,) if isinstance(like, EchoLikelihood) else like.likelihoods
        weakest = min(float(np.max(m.echo)) for m in models)
        needed = min(weakest * 10.0 ** (WEAK_ECHO_DB / 20.0), _PEAK_TABLE_TOP)
        return models[0].peak_of_significance(significance) < needed

    def _resume(self) -> None:
        """A false alarm: the significances within a lattice spacing of where the local phase
        started stop counting, its measurements join the search's (and its posterior), and
        the search goes on from where it stood."""
        self.false_alarms = np.vstack([self.false_alarms, self._handed[None, :]])
        self._g[np.hypot(*(self._x - self._handed).T) <= 1.01 * self.spacing] = 0.0
        dist = np.hypot(*(self._x[:, None, :] - self._x[None, :, :]).transpose(2, 0, 1))
        self._sum[:, 1] = (dist <= 1.01 * self.spacing) @ self._g
        g = np.asarray(self._local_g)
        self._add(self._local_x, self._local_y, g)
        if self.search is not None:
            self.search.update(self._local_x, g)
        self.local = None
        self.found_at = None
        self._iterate = self._handed.copy()

    def _ask(self) -> FloatArray:
        if self.local is not None:
            return self.local.ask()
        if self._confirming is not None:
            return self._confirming[None, :]
        if self.search is not None:
            price = self.measurement_price or 0.0
            return self.search.next_point(self.move_time, price)[None, :]
        n = self.batch
        if self._next == 0:
            n = max(n, self._first_ring_size())
        out = self._queue[self._next : self._next + n]
        return out

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        if self.local is not None:
            done = self.local.tell(np.where(self.last_nan, np.nan, values))
            self._iterate = self.local.iterate
            if self._check_local(points, values):
                self._resume()
                self._search_on()
                return False
            if self.local.finished:
                self.finished, self.finish_status = True, self.local.finish_status
            return done
        confirming = self._confirming is not None
        if confirming:
            self._confirming = None
        elif self.search is None:  # the lattice's next points (the posterior asks its own)
            self._next += len(points)
        ok = ~self.last_nan
        sig = self._significances(len(points))
        self._add(points[ok], values[ok], np.zeros(len(points))[ok] if sig is None else sig[ok])
        if self.search is not None:
            self._update_search(points, ok, sig)
        if confirming:
            if not ok.any():
                return False  # the repeat failed (NaN): search on; a detection asks again
            self._confirmed += 1
            # the repeat joined the neighbourhood it was to confirm: that one must still pass,
            # and (with a detector) the repeat itself must look like an echo, not like noise
            own = self._g[-1] > _CONFIRM_LEVEL if self._use_significance else True
            if own and self.scores()[-1] > self._threshold():
                self._start_local(self._x[-1].copy())
                return False
        self._search_on(confirming)
        return False

    def _reorder(self) -> None:
        """Search first where the echo is strongest so far: within each ring of the
        lattice still to search, the points nearest to the best value come first."""
        if self.search is None and len(self._y) and self._next < len(self._queue):
            best = self._x[int(np.argmax(self._g if self._use_significance else self._y))]
            rest = self._queue[self._next :]
            order = np.lexsort((np.hypot(*(rest - best).T), self._ring[self._next :]))
            self._queue[self._next :] = rest[order]
            self._ring[self._next :] = self._ring[self._next :][order]

    def _give_up_if_done(self) -> None:
        """Status 4 once the posterior gave up or the lattice is searched to its end."""
        if self._search_exhausted() or (self.search is None and self._next >= len(self._queue)):
            self.finished, self.finish_status = True, 4
            if len(self._y):
                self._iterate = self._x[int(np.argmax(self._y))]

    def _search_on(self, confirming: bool = False) -> None:
        """The search's next step after a batch (or after a false alarm, whose local
        measurements may show the echo at once): a detection is handed over; without one,
        unless a confirmation just failed, the posterior takes over from the first ring if
        it had not yet (else the replan), and the search gives up once it is done."""
        detected = self._detected()
        if not confirming and not detected:
            self._start_search()
            if self.search is None:
                self._replan()
        self._reorder()
        if detected:
            self._hand_over()
        else:
            self._give_up_if_done()

    def _hand_over(self) -> None:
        """A detection: re-measure its best point first when it is marginal (``confirm``),
        else start the local method there."""
        sure = float(np.max(self.scores())) > self.threshold + _SURE_MARGIN
        if self.confirm and not sure:
            self._confirming = self._x[int(np.argmax(self.scores()))].copy()
        else:
            self._start_local()

    def _recommend(self) -> FloatArray:
        if self.local is not None:
            return self.local.recommend()
        return self._iterate

    def recommend_value(self) -> float | None:
        return self.local.recommend_value() if self.local is not None else None

    @property
    def concave(self) -> bool | None:
        return self.local.concave if self.local is not None else None

    @property
    def iterate(self) -> FloatArray:
        return self.local.iterate if self.local is not None else self._iterate.copy()
