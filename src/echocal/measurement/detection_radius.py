"""How far from the optimum one A-scan still sees the echo, and how coarse a search may be.

A blind search for a lost echo covers the disc around its start with a lattice of
measurements; the lattice may be as coarse as the distance at which one measurement
still detects the echo.  That distance is set by the probe's diffraction (how fast its
pulse-echo lobe falls off with misalignment, tails included) and by the noise.  Given a
simulated setup (its probe, pulse, window and physics model) this module computes it
*before anything is measured*:

1. the noiseless A-scans of the probe tilted by θ = 0 … ``max_angle`` [deg] away from
   its best direction of normal incidence on the surface, in ``directions`` directions
   (the lobe's shape; where the surface normal lies only sets the centre, which the
   search is never told);
2. the matched-filter envelope peak p(θ) of each
   (:class:`~echocal.signal.detection.EchoDetector`);
3. for a peak SNR s [dB] (of the best echo at this position), the noise σ(s)
   (``echocal.signal.noise.noise_sigma_for_snr``) and the envelope peak p_t whose
   significance is the detector's threshold; at the echo's peak the matched envelope
   is the modulus of the echo plus complex Gaussian noise of σ·gain per component (gain:
   the filter's Rayleigh scale per unit σ), a Rice variable, so

       P_detect(θ) ≈ Q₁(p(θ) / (σ·gain), p_t / (σ·gain))   (Marcum's Q: ``rice.sf``),

   one cell's chance — a lower bound, since the echo's neighbouring cells and the
   rest of the window add their own small chances;
4. the detection radius r_q: the largest θ up to which P_detect ≥ q in every direction;
   and the lattice spacing s_c: the coarsest hexagonal lattice of measurements from which
   the echo is detected from a share c of the plane (P_detect averaged over a lattice
   cell at the distance to the nearest measurement, in the worst direction).

Step 3 is checked against noise draws through the detector itself in
tests/measurement/test_detection_radius.py; docs/benchmarks/detection-wave.md compares
the radii with its own noise draws.  ``auto`` searches in passes of s_c
(:func:`search_passes`).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from echocal._curves import first_crossing
from echocal._validate import finite_array, finite_float, in_range, positive_float, positive_int
from echocal.calibrate.lobe_template import LobeTemplate
from echocal.calibrate.posterior_search import EchoLikelihood, rice_sf
from echocal.constants import ECHO_THRESHOLD
from echocal.errors import GeometryError
from echocal.geometry import tilt_frame
from echocal.measurement.virtual import VirtualSetup
from echocal.signal.detection import shared_detector
from echocal.signal.noise import SNR_DB_RANGE, noise_sigma_for_snr, snr_for_noise_sigma
from echocal.signal.processing import pseudo_energy

__all__ = [
    "DETECTION_PROBABILITY",
    "MIN_PASS_SPACING",
    "SEARCH_SNRS",
    "LobeProfile",
    "cached_lobe_profile",
    "detection_radius",
    "echo_snr_for_noise",
    "first_crossing",
    "lobe_profile",
    "passes_for_noise",
    "passes_for_snr",
    "search_passes",
    "white_equivalent_sigma",
]

DETECTION_PROBABILITY = 0.9
"""The share of A-scans that must see the echo at the detection radius."""
PASS_COVERAGE = 0.99
"""The share of the plane from which a search pass must detect the echo."""
SEARCH_SNRS = (30.0, 20.0)
"""[dB] the peak SNRs a blind search is sized for, coarse pass first (see :func:`search_passes`)."""
MIN_PASS_SPACING = 0.25
"""[deg] the finest pass :func:`passes_for_noise` plans.  An echo that needs a finer one
(ŝ below about 0 dB for the 12.7 mm 5 MHz probe, whose 0 dB pass is 0.46° on the ray
model) is not searched blind: a 0.25° pass out to 180° is already 1.9 million points,
and 17 times the measurements of the probe's 10 dB pass (1.04°)."""
_STEP = 0.1
"""[deg] misalignment step of the lobe profile."""
_BLOCK = 2.0
"""[deg] the lobe profile is computed in blocks of this many degrees (see ``stop_below``)."""
_PROFILE_FIELDS = (
    "specimen",
    "transducer",
    "pulse",
    "window",
    "sound_speed",
    "medium",
    "material",
    "interior",
    "reflection",
    "synthesis",
    "wave_spacing",
)
"""What a lobe profile depends on: the setup's physics (not its noise, seed, limits,
gates, reference position or name)."""
_PEAK_AT_NORMAL = 1.01
"""A lobe whose pseudo-energy exceeds normal incidence's by more than this factor
somewhere does not peak at normal incidence (see :meth:`LobeProfile.energy_template`)."""
_RING = 0.1
"""A lobe that rises again by more than this fraction of its peak after falling has a side
lobe; one that stays below half the peak gets no template (see
:meth:`LobeProfile.energy_template`)."""
_CACHE_SIZE = 16
"""Lobe profiles kept per process (least recently used dropped first)."""
_PROFILES: OrderedDict[tuple[Any, ...], tuple[tuple[Any, ...], LobeProfile]] = OrderedDict()
_PROFILES_LOCK = threading.Lock()
"""Guards :data:`_PROFILES` (calibrations in a thread pool share the cache)."""


@dataclass(frozen=True, eq=False)
class LobeProfile:
    """The probe's matched-filter peak versus misalignment at one position.

    Attributes
    ----------
    setup : the simulated setup the profile was computed for.
    angles : [deg] misalignments, shape ``(n,)``, from 0 in steps of 0.1°.
    peaks : [a.u.] matched-envelope peak of the noiseless A-scan, shape ``(directions, n)``.
    reference : [a.u.] the noiseless A-scan at the best direction of normal incidence
        (the echo a peak SNR refers to), shape ``(n_samples,)``.
    energies : [a.u.] pseudo-energy of the noiseless A-scan (default energy window),
        shape ``(directions, n)``.
    centre : [deg] gimbal tilts (α, β) the misalignments are counted from (the best
        direction of normal incidence), shape ``(2,)``; None when not known.
    """

    setup: VirtualSetup
    angles: np.ndarray
    peaks: np.ndarray
    reference: np.ndarray
    energies: np.ndarray
    centre: np.ndarray | None = None

    def energy_template(self, absolute: bool = False) -> LobeTemplate | None:
        """The lobe's pseudo-energy relative to normal incidence's, as a
        :class:`~echocal.calibrate.lobe_template.LobeTemplate` centred on the peak — or
        None when the peak is not at normal incidence (a large probe over a curved part:
        two humps), where the template's peak is not the echo's, or when the lobe rises
        again after falling (by > 0.1 of its peak) to a side lobe below half its peak.  A
        ring above half the peak (the 12.7 mm probe's near field over a ball: a dip to
        about 0.3 of the peak 0.8° out, a ring at about 0.8 at 1.6°) is part of the
        template: it would hold a local climber, the fit tells it from the peak, and
        ``model-based`` counts only the main lobe as the top (the ball's cell at 10 dB: 60
        → 100 % within 0.1° after 60).  A lower side lobe holds no climber, and a template
        with one slowed a run: the test rig's small probe, a side lobe of 0.21 8° out,
        within 0.1° after 32 measurements instead of 20.
        ``absolute``: the template's ``peak`` is normal incidence's noiseless
        pseudo-energy (for a source measured in this setup's own units).  The lobe ends
        where the profile does (cached to the 2° block where a 30 dB echo is no longer
        detected, 9.4° for the 5 MHz probe); beyond, its last value holds."""
        top = float(np.mean(self.energies[:, 0]))
        if not top > 0.0 or float(self.energies.max()) > _PEAK_AT_NORMAL * top:
            return None
        phi = np.linspace(0.0, 2.0 * np.pi, len(self.energies), endpoint=False)
        template = LobeTemplate(
            self.angles.copy(), phi, self.energies / top, peak=top if absolute else None
        )
        if template.rise > _RING and template.side_lobe < 0.5:
            return None  # a side lobe that holds no climber
        return template

    def detection_probability(self, snr_db: float, threshold: float = ECHO_THRESHOLD) -> np.ndarray:
        """P_detect(θ), shape ``(directions, n)``, for an echo whose best A-scan here has
        peak SNR ``snr_db`` [dB] against white noise, at significance ``threshold`` [σ]."""
        setup = self.setup
        detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
        sigma = float(noise_sigma_for_snr(self.reference, snr_db, setup.window, setup.pulse))
        level = detector.threshold_peak(sigma, threshold)
        scale = sigma * detector.noise_gain
        return rice_sf(level / scale, self.peaks / scale)

    def echo_likelihood(
        self,
        noise_sigma: float,
        threshold: float = ECHO_THRESHOLD,
        noise_ar: tuple[float, ...] = (),
    ) -> EchoLikelihood | None:
        """How one A-scan's matched-filter peak is distributed versus misalignment against
        noise of per-sample σ ``noise_sigma`` [a.u.] and colour ``noise_ar`` (AR
        coefficients, :func:`echocal.bench.receiver.ar_noise`; () white), for a Bayesian
        search (:class:`~echocal.calibrate.posterior_search.EchoLikelihood`): the
        profile's peaks averaged over its directions, in units of σ · the noise gain of
        the detector calibrated on that colour, and the detection threshold ``threshold``
        [σ of significance] on the same scale.  None when the lobe does not peak at
        normal incidence (a large probe over a curved part: the optimum is not where the
        profile is centred)."""
        top = float(np.mean(self.peaks[:, 0]))
        if not top > 0.0 or float(self.peaks.max()) > _PEAK_AT_NORMAL * top:
            return None
        setup = self.setup
        window = setup.window
        detector = shared_detector(setup.pulse, window.fs, window.n_samples, noise_ar)
        sigma = positive_float("noise_sigma", noise_sigma)
        scale = sigma * detector.noise_gain
        return EchoLikelihood(
            angles=self.angles,
            echo=self.peaks.mean(axis=0) / scale,
            n_cells=detector.n_cells,
            threshold=detector.threshold_peak(sigma, threshold) / scale,
        )

    def peak_shape(self) -> np.ndarray | None:
        """The profile's peaks averaged over its directions, relative to normal
        incidence's, shape ``(n,)`` (1 at 0°): the lobe's shape for a source whose echo
        amplitude is unknown (:func:`~echocal.calibrate.posterior_search.scaled_lobe`).
        None when the lobe does not peak at normal incidence (as :meth:`echo_likelihood`)."""
        top = float(np.mean(self.peaks[:, 0]))
        if not top > 0.0 or float(self.peaks.max()) > _PEAK_AT_NORMAL * top:
            return None
        return np.asarray(self.peaks.mean(axis=0) / top, dtype=np.float64)

    def radius(
        self,
        snr_db: float,
        *,
        probability: float = DETECTION_PROBABILITY,
        threshold: float = ECHO_THRESHOLD,
    ) -> float:
        """[deg] the largest misalignment up to which P_detect ≥ ``probability`` in every
        direction (linear interpolation between profile angles); 0 when even normal
        incidence falls short, ``angles[-1]`` when no angle does."""
        probability = in_range("probability", probability, 0.0, 1.0)
        prob = self.detection_probability(snr_db, threshold)
        radii = [first_crossing(self.angles, p, probability) for p in prob]
        return float(min(radii))

    def lattice_spacing(
        self,
        snr_db: float,
        *,
        coverage: float = PASS_COVERAGE,
        threshold: float = ECHO_THRESHOLD,
    ) -> float:
        """[deg] the largest spacing of a hexagonal lattice of measurements that detects an
        echo of peak SNR ``snr_db`` [dB] from a share ``coverage`` of the plane: the mean,
        over points uniform in a lattice cell, of P_detect at their distance to the nearest
        measurement (the worst direction's P_detect; 0 beyond the profile), bisected to
        0.01°, never beyond √3 × the profile's last angle (the lattice that leaves no point
        farther than that angle, which a broad lobe seen beyond the profile gets)."""
        coverage = in_range("coverage", coverage, 0.0, 1.0)
        prob = self.detection_probability(snr_db, threshold).min(axis=0)

        def covered(spacing: float) -> float:
            d = spacing * _UNIT_CELL_DISTANCES
            return float(np.mean(np.interp(d, self.angles, prob, right=0.0)))

        lo, hi = 0.0, float(np.sqrt(3.0) * self.angles[-1])  # no point beyond the profile
        if covered(hi) >= coverage:
            return hi
        if covered(_BISECT_TOL) < coverage:
            return 0.0
        while hi - lo > _BISECT_TOL:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if covered(mid) >= coverage else (lo, mid)
        return lo


def _unit_cell_distances(n: int = 200) -> np.ndarray:
    """Distances from points uniform in a cell of the hexagonal lattice of unit spacing to
    the nearest lattice point, shape ``(n²,)``: a grid over the rhombus spanned by the
    lattice vectors (1, 0) and (½, √3/2), whose nearest lattice point is one of its
    corners."""
    u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
    x = u + 0.5 * v
    y = (np.sqrt(3.0) / 2.0) * v
    corners = np.array(
        [[0.0, 0.0], [1.0, 0.0], [0.5, np.sqrt(3.0) / 2.0], [1.5, np.sqrt(3.0) / 2.0]]
    )
    d = np.hypot(x.ravel()[:, None] - corners[:, 0], y.ravel()[:, None] - corners[:, 1])
    return d.min(axis=1)


_UNIT_CELL_DISTANCES = _unit_cell_distances()
_BISECT_TOL = 0.01
"""[deg] the resolution of :meth:`LobeProfile.lattice_spacing`."""


def lobe_profile(
    setup: VirtualSetup,
    position: Sequence[float] | np.ndarray,
    *,
    max_angle: float = 15.0,
    directions: int = 4,
    until_snr_db: float | None = None,
) -> LobeProfile:
    """The probe's noiseless matched-filter peak versus tilt away from its best direction
    of normal incidence on the surface from ``position`` [m] (3,), in ``directions``
    evenly spaced directions, out to ``max_angle`` [deg] — or, given ``until_snr_db``, to
    the end of the first 2° block in which an echo of that peak SNR [dB] stays below half
    the detector's threshold everywhere (detected in about 0.2 % of A-scans there, against
    the 90 % of the radius; see the module docstring).

    Raises
    ------
    GeometryError
        No direction from ``position`` meets the surface at normal incidence.
    """
    max_angle = positive_float("max_angle", max_angle)
    directions = positive_int("directions", directions)
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
    centre, reference = _normal_reference(setup, pos)
    stop = 0.0
    if until_snr_db is not None:
        until_snr_db = finite_float("until_snr_db", until_snr_db)
        sigma = float(noise_sigma_for_snr(reference, until_snr_db, setup.window, setup.pulse))
        stop = 0.5 * detector.threshold_peak(sigma, ECHO_THRESHOLD)
    phi = np.linspace(0.0, 2.0 * np.pi, directions, endpoint=False)
    angles = np.arange(0.0, max_angle + 0.5 * _STEP, _STEP)
    blocks: list[np.ndarray] = []
    energies: list[np.ndarray] = []
    for block in np.array_split(angles, max(1, int(np.ceil(max_angle / _BLOCK)))):
        tx = centre[0] + block[None, :] * np.cos(phi)[:, None]
        ty = centre[1] + block[None, :] * np.sin(phi)[:, None]
        scans = _scans(setup, pos, tx.ravel(), ty.ravel())
        blocks.append(detector.peak(scans).reshape(directions, len(block)))
        energy = pseudo_energy(scans, setup.window, setup.pulse)
        energies.append(np.asarray(energy).reshape(directions, len(block)))
        if np.all(blocks[-1] < stop):
            break
    profile = np.concatenate(blocks, axis=1)
    return LobeProfile(
        setup,
        angles[: profile.shape[1]],
        profile,
        reference,
        np.concatenate(energies, axis=1),
        np.asarray(centre, dtype=np.float64),
    )


def _normal_reference(setup: VirtualSetup, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The best direction of normal incidence from ``pos`` [m] (tilts [deg], (2,)) and its
    noiseless A-scan (n_samples,); raises GeometryError when there is none."""
    candidates = setup.normal_incidence_directions(pos)  # tilts [deg], best first
    if not len(candidates):
        raise GeometryError(
            f"no direction from position {tuple(pos)} m meets the surface at normal "
            "incidence; move the probe over the part"
        )
    detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
    at_normal = _scans(setup, pos, candidates[:, 0], candidates[:, 1])
    best = int(np.argmax(detector.peak(at_normal)))
    return candidates[best], at_normal[best]


def normal_incidence_energy(setup: VirtualSetup, position: Sequence[float] | np.ndarray) -> float:
    """[a.u.] pseudo-energy (default energy window, whole recording) of ``setup``'s
    noiseless A-scan at its best direction of normal incidence from ``position`` [m]: the
    lobe profile's energy at 0° (:attr:`LobeProfile.energies`), for a few A-scans instead
    of a profile's hundreds.  Raises GeometryError where no direction meets the surface at
    normal incidence."""
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    _, reference = _normal_reference(setup, pos)
    return float(np.asarray(pseudo_energy(reference[None, :], setup.window, setup.pulse))[0])


def _scans(setup: VirtualSetup, pos: np.ndarray, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """Noiseless A-scans, shape ``(n, n_samples)``, at ``pos`` [m] tilted ``(tx, ty)`` [deg]."""
    return setup.ideal_samples(np.broadcast_to(pos, (tx.size, 3)), tilt_frame(tx, ty))


def detection_radius(
    setup: VirtualSetup,
    position: Sequence[float] | np.ndarray,
    snr_db: float,
    *,
    probability: float = DETECTION_PROBABILITY,
    threshold: float = ECHO_THRESHOLD,
) -> float:
    """[deg] the misalignment up to which one A-scan of ``setup``'s probe at ``position``
    [m] detects the echo with ``probability`` at peak SNR ``snr_db`` [dB] (module docstring)."""
    return lobe_profile(setup, position).radius(
        snr_db, probability=probability, threshold=threshold
    )


def search_passes(setup: VirtualSetup, position: Sequence[float] | np.ndarray) -> tuple[float, ...]:
    """[deg] the spacings of a blind search's passes, coarse first, for ``setup``'s probe
    at ``position`` [m]: pass k is the coarsest hexagonal lattice that detects an echo of
    peak SNR ``SEARCH_SNRS[k]`` from :data:`PASS_COVERAGE` of the plane
    (:meth:`LobeProfile.lattice_spacing`).

    For the 12.7 mm 5 MHz probe at 50 mm on the wave model: (8.62, 4.17)°; on the ray
    model, whose lobe has no diffraction tails: (4.18, 1.97)°.  A pass no finer than the
    one before it is left out (a broad lobe seen beyond the profile's ``max_angle`` at both
    SNRs needs one pass).  The profile is computed once per probe, specimen and position
    in a process (2 s on the wave model) and reused by every setup built from the same
    physics objects (one that differs only in its noise or seed).
    """
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    profile = cached_lobe_profile(setup, pos)
    passes: list[float] = []
    for snr in SEARCH_SNRS:
        spacing = _floored(profile.lattice_spacing(snr))
        if spacing > 0.0 and (not passes or spacing < passes[-1]):
            passes.append(spacing)
    return tuple(passes)


def white_equivalent_sigma(
    setup: VirtualSetup, noise_sigma: float, noise_ar: tuple[float, ...] = ()
) -> float:
    """[a.u. per sample] the σ of white noise that puts as much power through ``setup``'s
    matched filter as noise of per-sample σ ``noise_sigma`` and colour ``noise_ar`` (AR
    coefficients; () white: σ itself): σ · g_AR / g_white, the two detectors' measured
    noise gains (:class:`~echocal.signal.detection.EchoDetector`).  AR(1) noise of
    coefficient 0.6 at the 5 MHz probe's band and 100 MHz sampling puts 2.9 times the
    white noise's power density into the band: its white-equivalent σ is 1.7 σ, an SNR
    4.7 dB lower."""
    sigma = float(noise_sigma)
    if not noise_ar:
        return sigma
    window = setup.window
    white = shared_detector(setup.pulse, window.fs, window.n_samples)
    coloured = shared_detector(setup.pulse, window.fs, window.n_samples, tuple(noise_ar))
    return sigma * coloured.noise_gain / white.noise_gain


def echo_snr_for_noise(
    setup: VirtualSetup,
    position: Sequence[float] | np.ndarray,
    noise_sigma: float,
    noise_ar: tuple[float, ...] = (),
) -> float:
    """[dB] ŝ, the peak SNR of the best echo of ``setup``'s probe at ``position`` [m]
    against a receiver noise σ [a.u. per sample] of colour ``noise_ar`` (AR coefficients;
    () white): its noiseless A-scan (the lobe profile's reference) through the matched
    filter, against the white-equivalent σ (:func:`white_equivalent_sigma`).  NaN where
    neither has power (σ = 0 and no echo)."""
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    profile = cached_lobe_profile(setup, pos)
    white = white_equivalent_sigma(setup, noise_sigma, noise_ar)
    return float(snr_for_noise_sigma(profile.reference, white, setup.window, setup.pulse))


def passes_for_snr(
    setup: VirtualSetup, position: Sequence[float] | np.ndarray, snr_db: float
) -> tuple[float, ...] | None:
    """[deg] a blind search's passes for an echo of peak SNR ``snr_db`` (ŝ) of
    ``setup``'s probe at ``position`` [m]: the first pass is the coarsest hexagonal
    lattice that detects it from :data:`PASS_COVERAGE` of the plane, the finer passes of
    :func:`search_passes` follow as a fall-back (should the echo be weaker than the
    model says).  For the 12.7 mm 5 MHz probe at 50 mm on the wave model: (8.61, 4.17)°
    at 30 dB, (4.17,)° at 20 dB, (1.33,)° at 10 dB.

    None when ŝ is NaN or no lattice of at least :data:`MIN_PASS_SPACING` detects the
    echo from that share of the plane (ŝ near 0 dB): the plan stays.
    """
    if np.isnan(snr_db):
        return None
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    profile = cached_lobe_profile(setup, pos)
    first = _floored(profile.lattice_spacing(float(np.clip(snr_db, *SNR_DB_RANGE))))
    if first < MIN_PASS_SPACING:
        return None
    return (first, *(p for p in search_passes(setup, pos) if p < first))


def passes_for_noise(
    setup: VirtualSetup, position: Sequence[float] | np.ndarray, noise_sigma: float
) -> tuple[float, ...] | None:
    """[deg] a blind search's passes for ``setup``'s probe at ``position`` [m] once the
    receiver's noise σ [a.u. per sample] has been measured: those of
    :func:`passes_for_snr` for the SNR the best echo then has
    (:func:`echo_snr_for_noise`).  An acquisition whose planned passes
    (:func:`search_passes`, sized for 30 and 20 dB) are all coarser than the first keeps
    its fine lattice around the start and searches on this one beyond it
    (:class:`~echocal.calibrate.Acquisition`, ``replan``): a 10 dB echo is then found
    beyond 3° too, where the 8.61° and 4.17° passes cannot see it.
    """
    return passes_for_snr(setup, position, echo_snr_for_noise(setup, position, noise_sigma))


def _floored(spacing: float) -> float:
    """[deg] ``spacing`` floored to 0.01° (a pass is never coarser than its rule)."""
    return float(np.floor(100.0 * spacing) / 100.0)


def cached_lobe_profile(setup: VirtualSetup, pos: np.ndarray) -> LobeProfile:
    """:func:`lobe_profile` of ``setup`` at ``pos`` [m], computed once per process for the
    same physics objects (a setup rebuilt with another noise level or seed shares them)
    and position.  Keyed by the objects' identities, which the entry keeps alive and
    checks, so a key is never reused by another object.  Across processes the profile is
    kept on disk, keyed by the physics' content (:mod:`echocal.measurement.lobe_cache`)."""
    parts = tuple(getattr(setup, f) for f in _PROFILE_FIELDS)
    key = (*(id(p) for p in parts), pos.tobytes())
    with _PROFILES_LOCK:
        hit = _PROFILES.get(key)
        if hit is not None and all(a is b for a, b in zip(hit[0], parts, strict=True)):
            _PROFILES.move_to_end(key)
            return hit[1]
    # computed outside the lock: two threads may both compute a missing profile (the same
    # result), but no thread waits on another's 2–50 s computation
    profile = _stored_or_computed(setup, parts, pos)
    with _PROFILES_LOCK:
        _PROFILES[key] = (parts, profile)
        while len(_PROFILES) > _CACHE_SIZE:
            _PROFILES.popitem(last=False)
    return profile


def _stored_or_computed(
    setup: VirtualSetup, parts: tuple[Any, ...], pos: np.ndarray
) -> LobeProfile:
    """The profile :func:`cached_lobe_profile` keeps: from the disk cache when it holds one
    for the same physics (``parts``, the :data:`_PROFILE_FIELDS` of ``setup``) and
    position, else computed and stored there."""
    from echocal.measurement import lobe_cache

    until = max(SEARCH_SNRS)
    constants = {"until_snr_db": until, "max_angle": 15.0, "directions": 4, "step": _STEP}
    key = lobe_cache.profile_key(parts, pos, constants)
    stored = None if key is None else lobe_cache.load(key)
    if stored is not None:
        return LobeProfile(
            setup,
            stored["angles"],
            stored["peaks"],
            stored["reference"],
            stored["energies"],
            stored["centre"],
        )
    profile = lobe_profile(setup, pos, until_snr_db=until)
    if key is not None:
        arrays = {
            "angles": profile.angles,
            "peaks": profile.peaks,
            "reference": profile.reference,
            "energies": profile.energies,
            "centre": np.asarray(profile.centre, dtype=np.float64),
        }
        lobe_cache.store(key, arrays)
    return profile
