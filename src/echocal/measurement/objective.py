"""``SourceObjective``: any measurement source + a metric, as a calibration objective.

This is the seam between the two halves of echocal: calibration methods see
an :class:`~echocal.calibrate.Objective` of two angles [deg]; behind it any
:class:`~echocal.measurement.MeasurementSource` — the simulator, a replayed
recording or a rig — measures A-scans at a fixed position, and a metric
(pseudo-energy by default, thesis eq. 79) turns each A-scan into one value.
Counting, logging, budget, bounds and repeats are the base class's.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from echocal._validate import finite_array
from echocal.ascan import AScan
from echocal.calibrate.lobe_template import LobeTemplate
from echocal.calibrate.objective import Objective, as_points
from echocal.calibrate.posterior_search import EchoHypotheses, EchoLikelihood
from echocal.errors import EchocalError, EchocalValueError
from echocal.geometry import Pose, convert_angles, pose_from_angles
from echocal.measurement.base import MeasurementSource
from echocal.measurement.virtual import VirtualSetup
from echocal.signal import Pulse, RecordingWindow, get_metric
from echocal.signal.detection import shared_detector as _detector
from echocal.signal.gates import TimeGate, gated_metric
from echocal.signal.noise import scan_noise_sigma
from echocal.signal.processing import energy_to_db, pseudo_energy_with_peak

if TYPE_CHECKING:
    from echocal.measurement.detection_radius import LobeProfile

__all__ = ["SourceObjective", "ascan_metric", "default_bounds", "scan_noise_sigma"]


def default_bounds(source: MeasurementSource, parameterization: str) -> np.ndarray:
    """Angle bounds [deg], shape (2, 2), from the source's positioner limits.

    For (azimuth, co-elevation) these are the limits themselves.  For tilts, the
    largest square tilt box inside the co-elevation cone θ_max: its corner (h, h)
    is arccos(cos² h) from vertical, so h = arccos(√cos θ_max) (21.4° for 30°).
    """
    limits = source.limits
    if parameterization == "tilt":
        cone = min(max(abs(limits.coelevation[0]), abs(limits.coelevation[1])), 90.0)
        half = float(np.rad2deg(np.arccos(np.sqrt(np.cos(np.deg2rad(cone))))))
        return np.array([[-half, half], [-half, half]])
    return np.array([limits.azimuth, limits.coelevation], dtype=np.float64)


def ascan_metric(
    scan: AScan,
    metric: str,
    pulse: Pulse,
    window_length: float | None = None,
    gate: TimeGate | None = None,
) -> float:
    """One metric value of one A-scan (inside ``gate`` if given); NaN for an A-scan with
    non-finite samples."""
    if not scan.is_finite:
        return float("nan")
    window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
    return float(gated_metric(metric, scan.samples, window, pulse, gate, window_length))


def _noise_colour(source: MeasurementSource) -> tuple[float, ...]:
    """The AR coefficients of the source's receiver noise when it says (the simulator on a
    bench with coloured noise), else () — white noise."""
    bench = getattr(source, "bench", None)
    return () if bench is None else tuple(bench.receiver.noise_ar)


def _tilt_axes(source: MeasurementSource) -> tuple[np.ndarray, np.ndarray, bool]:
    """Speeds [deg/s] and settling times [s] of the source's tilt axes, ``(2,)`` each, and
    whether they cost time: a simulated bench's, else 1 deg/s and no settling (the order
    is then the shortest in angle, and its time unknown)."""
    bench = getattr(source, "bench", None)
    if bench is not None:
        axes = (bench.positioner.tilt_x, bench.positioner.tilt_y)
        speeds = np.array([axis.speed for axis in axes])
        settling = np.array([axis.settling for axis in axes])
        if np.any(np.isfinite(speeds)) or np.any(settling > 0.0):
            return np.where(np.isfinite(speeds), speeds, 1e300), settling, True
    return np.ones(2), np.zeros(2), False


class SourceObjective(Objective):
    """Calibration objective measuring a source at a fixed position.

    Parameters
    ----------
    source : any measurement source.
    position : [m] where the transducer stays while its orientation is calibrated, shape (3,).
    metric : metric name (``pseudo-energy``, ``peak-amplitude``, ``energy-db``).
    pulse : the transmitted pulse, the matched filter's template; defaults to
        ``source.pulse`` when the source has one (the simulator does; pass it for a replay
        or a rig).
    parameterization : ``"azimuth-coelevation"`` or ``"tilt"``.
    bounds : [deg] (2, 2) angle bounds; default from the source's limits.
    window_length : [s] pseudo-energy window; default tied to the pulse duration.
    gate : compute the metric inside this gate (:class:`~echocal.signal.gates.TimeGate`,
        e.g. ``resolve_gate("back-wall", ...)``); None: the whole recording.  An absolute
        gate outside the first A-scan's window is refused.
    budget, out_of_bounds, repeats : see :class:`~echocal.calibrate.Objective`.
    twin : the simulated setup of a rig's probe, pulse and part (its setup file), from
        whose diffraction lobe a blind search is sized (:meth:`search_passes`); None:
        the source itself when it is the simulator.
    motion_aware : measure each batch of points along a short path of the positioner
        (:func:`echocal.bench.motion.short_order`, from where the last batch ended) instead
        of in the order asked; values come back in the order asked.  On a simulated bench
        :attr:`bench_time_saved` keeps the motion and settling time this saved against
        the plain order, predicted from the bench's tilt axes; and a method that weighs
        its next point's move (``auto``'s posterior search) is told the moves'
        times (:meth:`move_times`).
    """

    def __init__(
        self,
        source: MeasurementSource,
        position: ArrayLike,
        *,
        metric: str = "pseudo-energy",
        pulse: Pulse | None = None,
        parameterization: str = "azimuth-coelevation",
        bounds: ArrayLike | None = None,
        window_length: float | None = None,
        gate: TimeGate | None = None,
        budget: int | None = None,
        out_of_bounds: str = "clip",
        repeats: int = 1,
        twin: VirtualSetup | None = None,
        motion_aware: bool = False,
    ) -> None:
        get_metric(metric)  # unknown names fail here, listing the valid ones
        pulse = pulse if pulse is not None else getattr(source, "pulse", None)
        if pulse is None:
            raise EchocalValueError(
                "pulse is required: this source does not say which pulse it transmits "
                "(pass pulse=make_pulse(...) for the matched filter)"
            )
        super().__init__(
            bounds=default_bounds(source, parameterization) if bounds is None else bounds,
            budget=budget,
            out_of_bounds=out_of_bounds,
            repeats=repeats,
            parameterization=parameterization,
            description=f"{metric} of {source.description}"
            + ("" if gate is None else f" in gate {gate.name}"),
        )
        self.source = source
        self.position = finite_array("position", position, shape_tail=(3,)).reshape(3)
        self.metric = metric
        self.pulse = pulse
        self.window_length = window_length
        if gate is not None and not isinstance(gate, TimeGate):
            raise EchocalValueError(f"gate must be a TimeGate or None; got {gate!r}")
        self.gate = gate
        if twin is not None and not isinstance(twin, VirtualSetup):
            raise EchocalValueError(f"twin must be a simulated setup (VirtualSetup); got {twin!r}")
        self.twin = (
            twin if twin is not None else source if isinstance(source, VirtualSetup) else None
        )
        self._last_scan: AScan | None = None
        self._scan_sigmas: list[float] = []  # robust per-sample noise σ of each A-scan
        self._noise_cache: tuple[float, tuple[float, float]] | None = None
        self._peaks = np.zeros(0)  # matched-envelope peak of each A-scan of the last batch
        self._warned_coarse = False
        self._gate_window: RecordingWindow | None = None
        self._spent: float | None = None
        self._normal_energy: float | None = None  # normal_echo()'s, once computed
        self._noise_ar = _noise_colour(source)
        self.motion_aware = bool(motion_aware)
        self.bench_time_saved: float | None = None
        """[s] the motion and settling time the motion-aware order saved so far against the
        plain order (predicted from a simulated bench's tilt axes); None otherwise."""
        self._at: np.ndarray | None = None  # tilts [deg] of the last point measured
        self._plain_at: np.ndarray | None = None  # ... had every batch gone in its order

    @property
    def last_scan(self) -> AScan | None:
        """The last A-scan measured (the last of the last batch), None before any."""
        return self._last_scan

    def pose(self, a: float, b: float) -> Pose:
        """The pose measured for orientation ``(a, b)`` [deg]."""
        return pose_from_angles(self.position, float(a), float(b), self.parameterization)

    def _evaluate(self, points: np.ndarray) -> np.ndarray:
        order = self._motion_order(points) if self.motion_aware else None
        if order is not None:
            values = np.empty(len(points))
            peaks = np.empty(len(points))
            values[order] = self._measure(points[order])
            peaks[order] = self._peaks
            self._peaks = peaks
            return values
        return self._measure(points)

    def _motion_order(self, points: np.ndarray) -> np.ndarray | None:
        """The short order of ``points`` [deg] ``(k, 2)``, or None to keep the order asked
        (one point; or, on a simulated bench, a short order that saves no more than the
        price of one point, :meth:`measurement_price`: the noise is then drawn in the
        order a plain objective draws it); the time it saves is added to
        :attr:`bench_time_saved`: the predicted motion and settling of the plain order
        (along its own path since the first batch) minus the short order's."""
        from echocal.bench.motion import move_times, short_order

        tilts = np.column_stack(
            convert_angles(points[:, 0], points[:, 1], self.parameterization, "tilt")
        )
        start, plain_start = self._at, self._plain_at
        speeds, settling, timed = _tilt_axes(self.source)
        order = short_order(tilts, start, speeds, settling)
        if timed:  # against the plain order's own path, batch after batch
            plain = move_times(tilts, plain_start, speeds, settling).sum()
            short = move_times(tilts[order], start, speeds, settling).sum()
            if plain - short <= (self.measurement_price() or 0.0):
                order = np.arange(len(points))
                short = move_times(tilts, start, speeds, settling).sum()
            self.bench_time_saved = (self.bench_time_saved or 0.0) + float(plain - short)
        self._at, self._plain_at = tilts[order[-1]], tilts[-1]
        keep = len(points) == 1 or np.array_equal(order, np.arange(len(points)))
        return None if keep else order

    def move_times(self, points: np.ndarray) -> np.ndarray | None:
        """[s] the predicted motion and settling from the last point measured to each of
        ``points`` [deg] ``(k, 2)``, ``(k,)`` (:func:`echocal.bench.motion.reach_times`),
        when this objective is motion-aware on a simulated bench whose tilt axes take
        time; None otherwise, and before the first measurement."""
        speeds, settling, timed = _tilt_axes(self.source)
        if not (self.motion_aware and timed) or self._at is None:
            return None
        from echocal.bench.motion import reach_times

        pts = as_points("points", points)
        tilts = np.column_stack(convert_angles(pts[:, 0], pts[:, 1], self.parameterization, "tilt"))
        return reach_times(self._at, tilts, speeds, settling)

    def measurement_price(self) -> float | None:
        """[s] the bench time of a point apart from its travel — ``repeats`` acquisitions
        plus the longest settling of the tilt axes — when this objective is motion-aware
        on a simulated bench whose tilt axes take time (:meth:`move_times`); else None."""
        _, settling, timed = _tilt_axes(self.source)
        if not (self.motion_aware and timed):
            return None
        acquisition = float(self.source.bench.positioner.acquisition_time)  # type: ignore[attr-defined]
        return self.repeats * acquisition + float(settling.max())

    def _measure(self, points: np.ndarray) -> np.ndarray:
        """Measure ``points`` [deg] ``(k, 2)`` in this order; their metric values ``(k,)``."""
        poses = [self.pose(a, b) for a, b in points]
        scans = self.source.measure_many(poses)
        values = np.full(len(scans), np.nan)
        self._peaks = np.full(len(scans), np.nan)
        for i, scan in enumerate(scans):
            if scan.is_finite:
                self._note_noise(scan.samples)
                values[i], self._peaks[i] = self._metric_and_peak(scan)
        self._last_scan = scans[-1] if scans else None
        spent = [scan.metadata.get("bench_time") for scan in scans]
        known = [float(t) for t in spent if t is not None]
        self._spent = sum(known) if known else None
        return values

    def echo_floor(self) -> float | None:
        """[pseudo-energy units] half the simulator's noiseless echo at normal incidence
        (:meth:`normal_echo`): the optimum's echo is at least the normal one, so an
        estimate whose echo is below half of it sits off the main lobe — on a side lobe
        (a square probe's, 8° out at 0.14 of the peak) or on the grains' backscatter,
        which peaks at any tilt.  None without :meth:`normal_echo` (a rig, a gate, another
        metric)."""
        echo = self.normal_echo()
        return None if echo is None else 0.5 * echo

    def bench_uncertainty(self) -> float | None:
        """[deg] the simulated bench's positioner error
        (:attr:`~echocal.bench.positioner.PositionerModel.tilt_error`), None on the ideal
        positioner or another source."""
        bench = getattr(self.source, "bench", None)
        if bench is None or bench.positioner.is_exact:
            return None
        return float(bench.positioner.tilt_error)

    def _bench_spent(self) -> float | None:
        """[s] the bench time of the last batch: the sum of its A-scans' ``bench_time``
        (the simulator's bench model reports it), None when none reports one."""
        return self._spent

    def _metric_and_peak(self, scan: AScan) -> tuple[float, float]:
        """The metric of one finite A-scan and its matched-filter envelope peak [a.u.]
        (one matched filter for both when the metric is the pseudo-energy or its dB), both inside
        the gate when there is one."""
        window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
        samples = scan.samples
        if self.gate is not None:
            self._check_gate_window(window)
            samples = self.gate.apply(samples, window)
        if self.metric in ("pseudo-energy", "energy-db"):
            energy, peak = pseudo_energy_with_peak(samples, window, self.pulse, self.window_length)
            in_db = self.metric == "energy-db"
            return float(energy_to_db(energy) if in_db else energy), float(peak)
        metric = gated_metric(self.metric, samples, window, self.pulse, None, self.window_length)
        detector = _detector(self.pulse, scan.fs, scan.n_samples, self._noise_ar)
        return float(metric), float(detector.peak(samples))

    def _check_gate_window(self, window: RecordingWindow) -> None:
        """Refuse an absolute gate outside the source's recording window (checked on the
        first A-scan: a replay's or a rig's window is known only from its A-scans)."""
        if self._gate_window != window:
            from echocal.signal.gates import check_gate

            assert self.gate is not None
            check_gate(self.gate, window, field="gate")
            self._gate_window = window

    def _note_noise(self, samples: np.ndarray) -> None:
        """Record the A-scan's noise σ; warn once if its noise is below the ADC step."""
        sigma, coarse = scan_noise_sigma(samples)
        if sigma is not None:
            self._scan_sigmas.append(sigma)
        if coarse and not self._warned_coarse:
            self._warned_coarse = True
            warnings.warn(
                f"the A-scans from {self.source.description} are quantized more "
                "coarsely than their noise (most samples share one ADC level): the "
                "noise is then impulsive, not Gaussian, and the echo detection of the "
                "acquisition phase may fire on noise; raise the receiver gain or the "
                "ADC resolution so the noise spans a few ADC steps",
                UserWarning,
                stacklevel=5,
            )

    def _receiver_sigma(self) -> float:
        """[a.u.] the receiver's per-sample noise σ measured so far: the median of the
        A-scans' robust estimates (0 before the first)."""
        return float(np.median(self._scan_sigmas)) if self._scan_sigmas else 0.0

    def _significance(self) -> np.ndarray | None:
        """Matched-filter peak significance of each A-scan of the last batch against the
        receiver noise σ measured so far (median of the per-scan robust estimates)."""
        scan = self._last_scan
        if scan is None:
            return None
        sigma = self._receiver_sigma()
        if sigma <= 0.0:  # no noise measured yet: no evidence either way
            return np.full(len(self._peaks), np.nan)
        detector = _detector(self.pulse, scan.fs, scan.n_samples, self._noise_ar)
        return detector.significance_of_peak(self._peaks, sigma)

    def search_passes(self) -> tuple[float, ...] | None:
        """[deg] a blind search's pass spacings sized from the diffraction lobe of the
        simulated probe (the source, or the rig's ``twin``) at this position
        (:func:`~echocal.measurement.detection_radius.search_passes`); None without a
        simulated probe (a recording), for a gated metric, or where the simulated probe
        cannot see the part from this position (no normal incidence, no echo in the
        window)."""
        from echocal.measurement.detection_radius import search_passes

        if self.twin is None or self.gate is not None:
            return None
        try:
            return search_passes(self.twin, self.position)
        except EchocalError:  # no normal incidence, no echo in the window, ...: the defaults
            return None

    def passes_for_measured_noise(self) -> tuple[float, ...] | None:
        """[deg] the passes for the echo the simulated source predicts at this position
        against the noise σ measured in its A-scans so far (median of the per-scan robust
        estimates): those of :func:`~echocal.measurement.detection_radius.passes_for_snr`
        for the echo's predicted peak SNR ŝ
        (:func:`~echocal.measurement.detection_radius.echo_snr_for_noise`, against the
        white-equivalent σ of a simulated bench's coloured noise), which
        :attr:`search_snr_db` keeps.  None before a noisy A-scan, for a gated metric,
        where the probe cannot see the part, and for a rig's ``twin``: a setup file does
        not give the rig's echo amplitude in the rig's units, so it cannot say how far
        above the rig's noise the echo stands."""
        from echocal.measurement.detection_radius import echo_snr_for_noise, passes_for_snr

        self.search_snr_db = None
        twin = self.twin
        if twin is None or twin is not self.source or self.gate is not None:
            return None
        sigma = self._receiver_sigma()
        if not sigma > 0.0:  # no noise measured yet
            return None
        try:
            snr = echo_snr_for_noise(twin, self.position, sigma, self._noise_ar)
            passes = passes_for_snr(twin, self.position, snr)
        except EchocalError:  # no normal incidence, no echo in the window, ...
            return None
        if passes is not None:
            self.search_snr_db = snr
        return passes

    def echo_likelihood(self) -> EchoLikelihood | EchoHypotheses | None:
        """How each A-scan's matched-filter peak is distributed versus misalignment, against
        the receiver noise σ measured so far: what a Bayesian search of a lost echo weighs
        each significance with.  Only with tilt angles (the lobe's misalignments), one
        A-scan per point, ungated, and after a noisy A-scan; None otherwise.

        * The simulator measured with its own pulse: its probe's lobe at its known
          amplitude
          (:meth:`~echocal.measurement.detection_radius.LobeProfile.echo_likelihood`), of
          the colour of a simulated bench's receiver noise (its AR model: the detector
          calibrated on it, the echo's effective SNR); None where the probe cannot see
          the part or its lobe does not peak at normal incidence.
        * A rig or a recording (any other source): the echo's amplitude in its units is
          unknown, so :class:`~echocal.calibrate.posterior_search.EchoHypotheses` over it —
          the lobe's shape from the ``twin``'s physics when there is one
          (:func:`~echocal.calibrate.posterior_search.scaled_lobe`; None where the twin's
          lobe does not peak at normal incidence), else a Lorentzian of unknown width
          (:func:`~echocal.calibrate.posterior_search.lorentzian_lobes`) — with the
          detector of the A-scans' own sampling and length."""
        if self.gate is not None or self.repeats != 1 or self.parameterization != "tilt":
            return None
        sigma = self._receiver_sigma()
        if not sigma > 0.0:  # no noise measured yet
            return None
        if not self._own_units():
            return self._unknown_amplitude(sigma)
        from echocal.measurement.detection_radius import cached_lobe_profile

        assert self.twin is not None
        try:
            profile = cached_lobe_profile(self.twin, self.position)
            return profile.echo_likelihood(sigma, noise_ar=self._noise_ar)
        except EchocalError:  # no normal incidence, no echo in the window, ...
            return None

    def _unknown_amplitude(self, sigma: float) -> EchoHypotheses | None:
        """:meth:`echo_likelihood` for a source whose echo amplitude is unknown (a rig, a
        recording), against per-sample noise σ [a.u.]."""
        from echocal.calibrate.posterior_search import lorentzian_lobes, scaled_lobe
        from echocal.constants import ECHO_THRESHOLD

        scan = self._last_scan
        if scan is None:
            return None
        detector = _detector(self.pulse, scan.fs, scan.n_samples, self._noise_ar)
        scale = sigma * detector.noise_gain
        threshold = detector.threshold_peak(sigma, ECHO_THRESHOLD) / scale
        if self.twin is None:
            return lorentzian_lobes(detector.n_cells, threshold)
        from echocal.measurement.detection_radius import cached_lobe_profile

        try:
            profile = cached_lobe_profile(self.twin, self.position)
        except EchocalError:  # the twin cannot see the part from here: shape unknown
            return lorentzian_lobes(detector.n_cells, threshold)
        shape = profile.peak_shape()
        if shape is None:  # the lobe does not peak at normal incidence (two humps)
            return None
        return scaled_lobe(profile.angles, shape, detector.n_cells, threshold)

    def lobe_template(self) -> LobeTemplate | None:
        """The simulated probe's pseudo-energy lobe at this position (the source, or the
        rig's ``twin``; :meth:`~echocal.measurement.detection_radius.LobeProfile.energy_template`),
        relative to its peak: for the pseudo-energy in its default window, over the whole
        recording, with tilt angles (whose offsets are the lobe's misalignments).  The
        peak's own pseudo-energy comes with it for the simulator measured with its own
        pulse, in its units (not for a rig's twin, whose units are not the rig's, nor for
        another matched-filter pulse).  None
        otherwise, without a simulated probe, where the probe cannot see the part, and
        where the lobe does not peak at normal incidence (a large probe over a curved part)."""
        if self.parameterization != "tilt":
            return None
        profile = self._lobe_profile()
        return None if profile is None else profile.energy_template(absolute=self._own_units())

    def normal_echo(self) -> float | None:
        """[pseudo-energy units] the simulator's noiseless echo at its best direction of
        normal incidence from this position (the mean over the lobe profile's directions
        at 0°), which the optimum's echo is at least: for the simulator measured with its
        own pulse, in the default window, over the whole recording, with tilt angles —
        the units of its measurements.  None otherwise: a rig's twin does not give the
        rig's units; a receiver that saturates (``full_scale``) measures less than the
        noiseless echo; where no direction of normal incidence lies within the bounds the
        bounded optimum may be weaker; where the probe cannot see the part."""
        twin = self.twin
        if twin is None or not self._own_units() or self.parameterization != "tilt":
            return None
        if twin.receiver.full_scale is not None:
            return None
        normal = twin.normal_incidence_directions(self.position)
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        if not np.any(np.all((normal >= lo) & (normal <= hi), axis=1)):
            return None
        if self._normal_energy is None:
            self._normal_energy = self._normal_incidence_energy()
        echo = self._normal_energy
        return echo if echo > 0.0 else None

    def _normal_incidence_energy(self) -> float:
        """[pseudo-energy units] the twin's noiseless echo at normal incidence
        (:func:`~echocal.measurement.detection_radius.normal_incidence_energy`), 0.0 where
        the lobe profile would not apply (a gate, another metric or window) or the probe
        cannot see the part."""
        from echocal.measurement.detection_radius import normal_incidence_energy

        if (
            self.twin is None
            or self.gate is not None
            or self.metric != "pseudo-energy"
            or self.window_length is not None
        ):
            return 0.0
        try:
            return normal_incidence_energy(self.twin, self.position)
        except EchocalError:  # no normal incidence, no echo in the window, ...
            return 0.0

    def _own_units(self) -> bool:
        """Whether the measurements are the simulated twin's own, in its units: the
        simulator itself (not a rig's twin) measured with its own pulse."""
        return self.twin is not None and self.twin is self.source and self.pulse is self.twin.pulse

    def _lobe_profile(self) -> LobeProfile | None:
        """The simulated probe's (cached) pseudo-energy lobe profile at this position, for
        the default window over the whole recording; None without a simulated probe, for
        another metric or window, or where the probe cannot see the part."""
        from echocal.measurement.detection_radius import cached_lobe_profile

        if (
            self.twin is None
            or self.gate is not None
            or self.metric != "pseudo-energy"
            or self.window_length is not None
        ):
            return None
        try:
            return cached_lobe_profile(self.twin, self.position)
        except EchocalError:  # no normal incidence, no echo in the window, ...
            return None

    def resolution(self) -> float | None:
        """[deg] the source's grid step in this objective's angles (a replay's,
        :meth:`~echocal.measurement.ReplaySource.grid_step`), None for a simulator
        or a rig."""
        grid_step = getattr(self.source, "grid_step", None)
        return None if grid_step is None else grid_step(self.parameterization)

    def noise_estimate(self) -> tuple[float | None, float | None]:
        """Live ``(noise_floor, noise_sigma)`` of the metric, measured from the A-scans.

        Each A-scan carries its own noise: the echo fills a small part of the
        recording, so 1.4826 · MAD of the samples estimates the receiver's
        per-sample σ.  The metric of pure noise at that σ (mean and standard
        deviation over 64 synthetic noise A-scans of the same window and of the
        receiver's colour, :func:`echocal.bench.receiver.ar_noise` — white unless a
        simulated bench colours it —, with a fixed internal seed so the source's random
        stream is untouched) gives the floor that an echo must clear.  None until the
        first finite A-scan.
        """
        if not self._scan_sigmas or self._last_scan is None:
            return super().noise_estimate()
        sigma = self._receiver_sigma()
        cached = self._noise_cache
        if cached is not None and abs(cached[0] - sigma) <= 0.05 * max(cached[0], 1e-300):
            return cached[1]
        scan = self._last_scan
        from echocal.bench.receiver import ar_noise

        shape = (64, scan.n_samples)
        noise = ar_noise(shape, self._noise_ar, np.random.default_rng(12345)) * sigma
        window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
        if self.gate is not None:  # pure noise in a gate as wide, where the last one was
            noise = np.where(self.gate.masks(scan.samples, window), noise, 0.0)
        values = gated_metric(self.metric, noise, window, self.pulse)
        estimate = (float(np.mean(values)), float(np.std(values)))
        self._noise_cache = (sigma, estimate)
        return estimate
