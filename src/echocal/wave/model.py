"""The wave echo model: a Kirchhoff (physical-optics) integral with exact piston fields.

Pipeline per pose (docs/physics.md, "The wave model")::

    footprint rays → closest hits = surface samples (point, normal, patch area, visibility)
        → two-way SIR correlation per sample → one time grid → spectrum × pulse → A-scan
    (over a plane that fills the beam: the probe's mirror image → one-way SIR per face node
        → one time grid → spectrum × pulse → A-scan)

**Physics.** By reciprocity (Auld 1979; Thompson & Gray's measurement model), the signal
scattered back to a transducer by a surface S on which the Kirchhoff (physical-optics)
boundary values hold is V ∝ ∫_S R·p_inc ∂ₙp_inc dS, with p_inc the transducer's own
transmit field.  Both p_inc and ∂ₙp_inc follow from the closed-form spatial impulse
response h of the piston (``echocal.wave.sir``):
p = ρ ∂ₜh * v and ∂ₙh = (1/c) ∂ₜh_m + h_m/(ct), m the surface normal pointing away from
the probe.  The second term is smaller by 1/(kR) and in quadrature with the first; it
changes amplitudes by O((kR)⁻²) ≈ 10⁻⁵ at 5 MHz and 10 mm, and is left out.  Hence

    A(t) = w(t) * Σₛ Rₛ ΔSₛ / (A_p c²) · ∂²ₜ (hₛ * h_m,ₛ)(t),

normalized so that a perfect reflector at normal incidence in the deep near field of a
large piston returns the pulse w(t − 2d/c) itself (A_p = πa²).  For an infinite rigid
plane the Kirchhoff boundary values are exact (image theorem), so the model is exact
there: it reproduces the Rogers–Van Buren diffraction loss on axis and the exact tilt lobe
(tests/physics).  On curved parts it is physical optics: exact to O(1/(k·radius)).

**Surface samples.** The ray stage fires a fan of rays from a virtual apex behind the
face, through a disc of radius a + margin on it, wide enough to hold the diffracted beam
(its half-angle grows with λ/a) and dense enough that the samples lie about ``spacing``
apart on the surface, and never farther than the two-way Nyquist spacing λ_hi/(4 sin θ) at
the beam axis's incidence θ (finer, and costlier, at large tilts), and on a curved surface
not farther than the coarser of 1.5 times that at the largest incidence on it across the
face's footprint and 0.8 times that of the paths to the probe's rim
(``_CURVED_FOOTPRINT_FRACTION``, ``_CURVED_RIM_FRACTION``; costs in
docs/benchmarks/wave.md).  Over a lone ball the fan is aimed at its centre and covers
the cap its echo comes from, whatever the tilt (``WaveEchoModel._cap``).  Closest hits
keep visibility.

**Planes.** Over a plane that fills the beam (or a plate whose edges' echo comes after its
own, :meth:`WaveEchoModel.image_plane`), the same physics is evaluated exactly and far
more cheaply by the image form (:mod:`echocal.wave.image`): the probe's SIR integrated over
its mirror image, a few hundred face nodes at most near normal incidence (0.5 ms per A-scan
there); for a flat disc off the normal, the same double integral over pairs of the two
faces' abscissae, their ordinates in closed form (:mod:`echocal.wave.pairs`).  Each hit
of the Kirchhoff sum carries the area of its ray tube on the surface, ΔS = dΩ·L²/|cos θ|,
and a smooth taper towards the edge of the fan so that the cut-off edge does not diffract.

**Materials.** Rₛ is the specimen's plane-wave reflection coefficient at the local angle
of incidence (1 for a perfect reflector); the medium's attenuation α(f) multiplies the
spectrum by exp(−α(f)·c·t̂), c·t̂ the path travelled by the echo's envelope peak, which
lowers the centre frequency as it should.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.fft
import scipy.special
from numpy.typing import NDArray

from echocal.signal.analytic import analytic_signal
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow
from echocal.specimen.base import Shape
from echocal.specimen.casting import _cast_soa
from echocal.specimen.sphere import Sphere
from echocal.wave import ball_table, image, pairs, sir
from echocal.wave.echo_table import EchoTable, significant_bins
from echocal.wave.plane_table import PlaneTable
from echocal.wave.probe import Aperture, PistonProbe
from echocal.wave.table_cache import DiskNodes, array_digest
from echocal.wave.threads import one_way_grid, two_way_grid

__all__ = ["WaveEchoModel"]

FloatArray = NDArray[np.float64]

_TAPER = 0.25
"""Fraction of the fan's radius over which the surface weights fall smoothly to zero."""
_GRID_OVERSAMPLING = 5.0
_FRESNEL_MARGIN = 1.0
_SPACING_WAVELENGTHS = 2.7
"""Default surface-sample spacing on planes, in wavelengths at the pulse's centre frequency."""
_CURVED_SPACING_WAVELENGTHS = 1.35
"""Default spacing on curved surfaces (spheres, cylinders, meshes): the two-way time changes
faster between neighbours there; at 2.7 λ a 3 mm probe's echo over a 20 mm rod rose 2–4 %
from the normal to 0.4° off it, at 1.35 λ it falls as it should and agrees with 0.68 λ to
0.3 % (tests/physics/test_wave_optimum.py)."""
_CURVED_RIM_FRACTION = 0.8
"""A curved surface's samples may also lie this fraction of the two-way Nyquist spacing of
the paths to the probe's rim, λ_hi/(4 sin β) with tan β = a/ℓ (a the face's radius, ℓ the
surface's distance), apart (see ``WaveEchoModel._curved_spacing``): every sample's
two-way SIR starts and ends at the paths to the nearest and farthest rim points, which
move at up to sin β per unit step.  50 mm above the 25 mm ball it asks for 0.24 mm: 0.27 %
of the echo's peak at 0°, 0.67 % at 2° (1.0 of it, 0.30 mm: 2.5 and 4.2 %)."""
_CURVED_FOOTPRINT_FRACTION = 1.5
"""With the default spacing, a curved surface's samples may lie this multiple of the
two-way Nyquist spacing λ_hi/(4 sin θ_f) apart, θ_f the largest angle between the surface's
normal and the beam axis where rays from the face's centre and rim, parallel to the axis,
meet it (λ_hi at the pulse's −60 dB frequency: 1.5 of its Nyquist spacing is the Nyquist
spacing at 2/3 of that frequency, the upper −6 dB one of a 60 % Gabor pulse at 5 MHz).
Under a large probe the near field is a plane wave along the axis, so the two-way delay
changes at 2 sin θ_f per unit step across the footprint whatever the distance.  The echo of
a 12.7 mm 5 MHz probe above a 25 mm ball within 2 µs of it, against an independent
physical-optics sum (tests/physics/test_ball.py): at 1.35 λ (0.40 mm) 11, 8.2 and 7.2 % of
its peak off at 10, 25 and 50 mm; 0.30 mm 2.2, 2.6, 2.5 %; 0.25 mm 0.86, 0.96 %; 0.20 mm
0.62, 0.36, 0.14 % (converged); this rule 0.22 mm (the coarser of it and the rim's rule
applies)."""
_SPACING_PER_SIZE = 0.5
"""The default spacing is at most this fraction of the probe's (shorter) half-width: a small
probe's field varies across its own size, finer than a few wavelengths (a 4 mm probe at
1 MHz, 2.7 λ = 4 mm: its normal-incidence echo was 2.5× off for a disc, 0.44× for a square;
at a/2, within 0.1 % of the exact image form)."""
_SPREAD = 1.6
"""The fan reaches this many Fresnel-zone widths √(λd) beyond the probe's rim."""
_IMAGE_NYQUIST_FRACTION = 0.7
"""Image form: the face nodes lie at most this fraction of the two-way Nyquist spacing
λ_hi/(2 sin 2α) apart."""
_CAP_WIDTH = 0.25
"""A ball's cap (``WaveEchoModel._cap``) is lit fully out to the face's central projection
plus the edge waves' Fresnel margin m, and beyond it by ½·erfc(s/(√2·σ)), s the distance
past that, σ this fraction of m, out to ``_CAP_SIGMAS`` σ.  The fading edge crosses the
beam's direct wave, whose two-way phase runs at up to 2k·sin θ there: the Gaussian edge's
leak falls as exp(−(2kσ sin θ)²/2), where a sin² taper's falls only as its square (the
sin² taper over 25 % of the cap gave 7.6× the echo's peak at 10°)."""
_CAP_SIGMAS = 5.0
"""The cap's fan ends this many σ past its fully lit core (the weight 3·10⁻⁷ there)."""
_TABLE_CUT = 1e-9
"""The tables keep the bins where the echo's transfer (the image form's W(f)·2πf/sinc³,
the Kirchhoff sum's W(f)·(2πf)²/sinc⁶) is at least this fraction of its largest
(``echocal.wave.echo_table.significant_bins``)."""
_TABLE_REFINE = 0.7
"""A ball's table computes its nodes with the surface samples this fraction of the spacing
rules apart: at the rules' own spacing (1.5 times the two-way Nyquist spacing over the
cap) the sum's aliasing error changes with the lattice's scale, hence from pose to pose, by
up to a few tenths of a percent of the echo's peak (4 mm probe, 1.3° off a 28 mm ball:
interpolating over 4 × 4 nodes made 0.32 %); at 0.7 of it 0.018 % (and 0.035 % at 0.5)."""
_FOOTPRINT_RAYS = 32
"""Rays on each of the footprint's two rings (rim and half radius) that must all hit the
same plane for the image form."""


def _tilt_direction(plane: image.ImagePlane) -> tuple[float, float]:
    """The unit vector in the face's plane along which ``plane`` is tilted, (0, 0) at
    normal incidence (below 10⁻¹² rad, where the echo differs from the normal one by
    10⁻²⁴).  The image form's integrand is even under the reflection across the plane
    through the probe's axis and this vector: the probe is symmetric under it, and the
    plane's normal lies in it (:func:`echocal.wave.image.face_quadrature`)."""
    nx, ny = float(plane.normal[0]), float(plane.normal[1])
    tilt = math.hypot(nx, ny)
    if tilt < 1e-12:
        return (0.0, 0.0)
    ux, uy = nx / tilt, ny / tilt
    # exactly along a side when it nearly is, so a rectangle's rule folds there too
    return (0.0 if abs(ux) < 1e-12 else ux, 0.0 if abs(uy) < 1e-12 else uy)


@dataclass(frozen=True)
class _Cap:
    """The cap of a ball that its echo comes from (``WaveEchoModel._cap``).

    Attributes
    ----------
    axes : ``(3, 3)`` rows e₁, e₂ and the unit vector from the face centre towards the
        ball's centre, in the aperture frame.
    distance : [m] from the face centre to the ball's top along that line.
    radius : [m] the fan's radius at the top: ``core`` + ``_CAP_SIGMAS`` · ``width``.
    sin_normal : the sine of the largest angle between the cap's normals and the beam axis.
    core : [m] the fully lit radius: the face's central projection plus the Fresnel margin.
    width : [m] σ of the Gaussian edge beyond ``core`` (``_CAP_WIDTH`` of the margin).
    """

    axes: FloatArray
    distance: float
    radius: float
    sin_normal: float
    core: float
    width: float


@dataclass(frozen=True, kw_only=True)
class WaveEchoModel:
    """Noiseless A-scans of a piston probe over a specimen, from diffraction theory.

    Parameters
    ----------
    probe : the piston: circular (:class:`~echocal.wave.PistonProbe`, flat or focused) or
        rectangular (:class:`~echocal.wave.RectangularProbe`).
    pulse : the echo waveform w(t) of a perfect plane reflector in the deep near field.
    window : the recording window.
    sound_speed : [m/s] c of the medium.
    attenuation : α(f) [Np/m] of the medium at frequencies f [Hz], or None (lossless).
    reflection : R(θ) (complex, pressure) of the specimen at incidence angles θ [deg], or
        None for a perfect reflector (R = 1).
    spacing : [m] target distance between surface samples at the surface; None: on planes
        2.7 wavelengths at the pulse's centre frequency (at most half the probe's radius or
        shorter half-side) (0.8 mm at 5 MHz: measured against
        the exact angular spectrum, the tilt lobe stays within 0.5 % of its peak at
        10–150 mm and tilts 0.25–2° for 3 and 12.7 mm probes; 1.0 mm gives up to 1.2 %),
        on curved surfaces half that (see ``_CURVED_SPACING_WAVELENGTHS``).
    image_planes : over a plane that fills the beam, integrate over the probe's mirror
        image instead of the lit surface (:mod:`echocal.wave.image`: exact, 4–8× cheaper);
        False forces the Kirchhoff sum everywhere (for comparisons).
    tables : under a flat disc or a bowl, read the image form's echo from a table over the
        plane's distance and tilt, filled lazily with the exact form and interpolated
        (:mod:`echocal.wave.plane_table`), and a lone ball's Kirchhoff sum from one over
        the distance to its centre and the axis's angle off it (``echocal.wave.ball_table``);
        False: the exact form and sum at every pose (for comparisons, and for poses of a
        setup seen once).
    """

    probe: Aperture
    pulse: Pulse
    window: RecordingWindow
    sound_speed: float
    attenuation: Callable[[FloatArray], FloatArray] | None = None
    reflection: Callable[[FloatArray], NDArray[np.complex128]] | None = None
    spacing: float | None = None
    image_planes: bool = True
    tables: bool = True

    # ------------------------------------------------------------------ derived constants
    @cached_property
    def _wavelength(self) -> float:
        return self.sound_speed / self.pulse.center_frequency

    @cached_property
    def _longest_wavelength(self) -> float:
        """[m] the wavelength at the pulse's lower −6 dB frequency (at most 1/0.3 of the
        centre one): it sets the diffracted beam's spread."""
        f_lo = max(self.pulse.bandwidth_6db[0], 0.3 * self.pulse.center_frequency)
        return self.sound_speed / f_lo

    @cached_property
    def _footprint_rays(self) -> FloatArray:
        """``(2, 2·_FOOTPRINT_RAYS + 1)`` the footprint rays' points on the face, in units of
        the fan's radius: the rim, a ring at half the radius, and the axis last."""
        phi = 2.0 * math.pi * np.arange(_FOOTPRINT_RAYS) / _FOOTPRINT_RAYS
        radii = np.repeat([1.0, 0.5], _FOOTPRINT_RAYS)
        return np.stack(
            [
                np.append(radii * np.tile(np.cos(phi), 2), 0.0),
                np.append(radii * np.tile(np.sin(phi), 2), 0.0),
            ]
        )

    @cached_property
    def _shortest_wavelength(self) -> float:
        """[m] the wavelength at the pulse's highest frequency."""
        return self.sound_speed / self.pulse.highest_frequency

    def _sample_spacing(self, shapes: tuple[Shape, ...], sin_incidence: float = 0.0) -> float:
        """[m] the surface-sample spacing over ``shapes`` (finer unless all are planes), and
        never coarser than the two-way Nyquist spacing λ_hi/(4 sin θ) at the beam axis's
        incidence θ on the surface: each sample stands for its patch, so the two-way delay
        may change by at most half a period of the highest frequency between neighbours,
        or the sum aliases into a spurious echo (at 8–25° tilt it stood at −20 dB where the
        exact echo is below −49 dB)."""
        if self.spacing is not None:
            base = float(self.spacing)
        else:
            flat = all(shape.kind == "plane" for shape in shapes)
            wavelengths = _SPACING_WAVELENGTHS if flat else _CURVED_SPACING_WAVELENGTHS
            base = min(wavelengths * self._wavelength, _SPACING_PER_SIZE * self.probe.spread_radius)
        if sin_incidence <= 0.0:
            return base
        return min(base, self._pose_spacing(sin_incidence))

    def _pose_spacing(self, sin_incidence: float) -> float:
        """[m] the two-way Nyquist spacing at incidence sine ``sin_incidence``."""
        return self.sound_speed / (4.0 * self.pulse.highest_frequency * sin_incidence)

    @cached_property
    def _grid(self) -> tuple[int, float, int, int]:
        """(M, Δ_g [s], pad [grid points], n_fft): the correlation grid is every M-th output
        sample, padded by the pulse's support on both sides."""
        fs = self.window.fs
        m = max(1, int(fs / (_GRID_OVERSAMPLING * self.pulse.highest_frequency)))
        dt = m / fs
        pad = math.ceil(self.pulse.support / dt) + 2
        n_window = math.ceil(self.window.n_samples / m) + 1
        n_fft = scipy.fft.next_fast_len(n_window + 2 * pad, real=True)
        return m, dt, pad, n_fft

    @cached_property
    def _lead(self) -> int:
        """Output samples from the correlation grid's first point to the window's start:
        the pad plus ``round(start·fs) mod M``, so that the grid's points fall on sample
        numbers (counted from t = 0) divisible by M whatever the start.  The B-spline
        deposit's aliasing error depends on where an echo sits between grid points; with
        the grid anchored, moving the window by whole samples leaves every echo exactly
        where it was on the grid (else a narrow-band pulse's echo, M = 3, changed by
        1.1 % per microsecond of shift)."""
        m, _, pad, _ = self._grid
        return pad * m + round(self.window.start * self.window.fs) % m

    @cached_property
    def _t0(self) -> float:
        """[s] the time of the correlation grid's first point."""
        return self.window.start - self._lead / self.window.fs

    @cached_property
    def _transfer(self) -> NDArray[np.complex128]:
        """W(f)·(i2πf)²/sinc⁶(fΔ_g) on the grid's rfft frequencies (one-sided)."""
        _, dt, _, n_fft = self._grid
        f = np.fft.rfftfreq(n_fft, dt)
        iw = 2j * math.pi * f
        return self.pulse.spectrum(f) * iw * iw / np.sinc(f * dt) ** 6

    @cached_property
    def _image_transfer(self) -> NDArray[np.complex128]:
        """W(f)·(i2πf)/(A_p c·sinc³(fΔ_g)): the image form's one-way B-spline grid → echo."""
        _, dt, _, n_fft = self._grid
        f = np.fft.rfftfreq(n_fft, dt)
        scale = 1.0 / (self.probe.area * self.sound_speed)
        return self.pulse.spectrum(f) * (2j * math.pi * f) * scale / np.sinc(f * dt) ** 3

    @cached_property
    def _frequencies(self) -> FloatArray:
        _, dt, _, n_fft = self._grid
        return np.asarray(np.fft.rfftfreq(n_fft, dt), dtype=np.float64)

    # ------------------------------------------------------------------ footprint
    def _fresnel_margin(self, distance: float) -> float:
        """[m] 2λ + ``_FRESNEL_MARGIN``·√(λ_lo·d): how far beyond the face's rim (or a
        ball's specular cap) the edge waves of a surface ``distance`` d [m] away reach."""
        lam = self._wavelength
        return 2.0 * lam + _FRESNEL_MARGIN * math.sqrt(
            self._longest_wavelength * max(distance, lam)
        )

    def _fan_extent(self, distance: float) -> tuple[float, float]:
        """(r₀, apex) [m]: the fan's radius on the face and the distance of its virtual apex
        behind the face, for a surface about ``distance`` [m] away."""
        # diffracted beam: half-angle _SPREAD·λ_lo/(2a) past the first null (a the shorter
        # half-side of a rectangle); near the face the edge waves need a margin of a couple
        # of Fresnel-zone widths
        tan_spread = min(_SPREAD * self._longest_wavelength / (2.0 * self.probe.spread_radius), 1.0)
        r0 = self.probe.radius + self._fresnel_margin(distance)
        return r0, r0 / tan_spread

    def _fan(
        self,
        distance: float,
        spacing: float,
        cap: _Cap | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray, float]:
        """The footprint fan for a surface about ``distance`` [m] away, its samples about
        ``spacing`` [m] apart there: about the beam axis, or with a ``cap`` about the line
        to a ball's centre, its rays through the cap's full radius at its top.

        Returns local ray origins ``(3, n)`` [m] (on the face, or on the plane through the
        face centre normal to the cap's axis), local directions ``(3, n)`` (beam along +z),
        the solid angle per ray [sr] ``(n,)`` and the apex distance [m]."""
        if cap is None:
            r0, apex = self._fan_extent(distance)
            axes = np.eye(3)
        else:
            # rays from an apex the cap's distance behind the face centre, through a disc
            # of half the cap's radius about the centre: the cap's radius at its top
            distance = cap.distance
            r0, apex = 0.5 * cap.radius, cap.distance
            axes = cap.axes
        # face pitch so that the samples are `spacing` apart at the surface
        pitch = spacing * apex / (apex + max(distance, 0.0))
        n_side = math.ceil(2.0 * r0 / pitch)
        u = (np.arange(n_side) + 0.5) / n_side * 2.0 * r0 - r0
        uu, vv = np.meshgrid(u, u)
        rr = np.hypot(uu, vv).ravel()
        keep = rr <= r0
        x, y = uu.ravel()[keep], vv.ravel()[keep]
        length = np.sqrt(x * x + y * y + apex * apex)
        origins = axes.T @ np.stack([x, y, np.zeros_like(x)])
        dirs = axes.T @ np.stack([x / length, y / length, apex / length])
        cell = (2.0 * r0 / n_side) ** 2
        solid_angle = cell * apex / length**3  # dΩ = A cosγ / ℓ²
        if cap is None:
            taper = np.clip((r0 - rr[keep]) / (_TAPER * r0), 0.0, 1.0)
            solid_angle *= np.sin(0.5 * math.pi * taper) ** 2
        else:
            edge = (2.0 * rr[keep] - cap.core) / (math.sqrt(2.0) * cap.width)
            solid_angle *= 0.5 * scipy.special.erfc(edge)
        return origins, dirs, solid_angle, apex

    def _cap(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> _Cap | None:
        """Over one ball seen from outside, the cap of it that the echo comes from, or None
        (another scene: the fan about the beam axis applies).

        On a smooth convex surface the Kirchhoff integrand's stationary points (the
        specular paths from one point of the face to another, the rim's edge waves
        included) lie where the surface's normal meets the face: on a ball of radius R
        whose centre is D from the face centre, the face's central projection, a cap of
        radius R·a/(D − a) about the top (a the face's radius).  Elsewhere the two-way phase
        has no stationary point and the lit surface's contributions cancel, wherever the
        beam's main lobe falls: the fan covers that cap and the edge waves' Fresnel margin
        (``_fresnel_margin`` at the top's distance) fully, and fades out beyond it with a
        Gaussian edge (``_CAP_WIDTH``, ``_CAP_SIGMAS``), whatever the tilt.  Past the cap
        the sum would only add the lit side's truncation and its grazing, aliased flank."""
        if len(shapes) != 1 or not isinstance(shapes[0], Sphere):
            return None
        ball = shapes[0]
        basis = np.stack([frame[:, 0], frame[:, 1], -frame[:, 2]])  # rows: the local axes
        towards = basis @ (ball.center - position)  # aperture frame
        centre = float(np.linalg.norm(towards))
        a = self.probe.radius
        if centre <= ball.radius + a:
            return None  # the face touches or is inside the ball
        axis = towards / centre
        helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = helper - (helper @ axis) * axis
        e1 /= np.linalg.norm(e1)
        axes = np.stack([e1, np.cross(axis, e1), axis])
        distance = centre - ball.radius
        core = ball.radius * a / (centre - a) + self._fresnel_margin(distance)
        width = _CAP_WIDTH * self._fresnel_margin(distance)
        radius = core + _CAP_SIGMAS * width
        cos_tilt = float(np.clip(axis[2], -1.0, 1.0))
        # the largest angle between the cap's normals and the beam axis
        turn = math.asin(min(1.0, core / ball.radius))
        sin_normal = math.sin(min(0.5 * math.pi, math.acos(cos_tilt) + turn))
        return _Cap(axes, distance, radius, sin_normal, core, width)

    def _surface_distance(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> tuple[float, float]:
        """[m] the nearest surface within the beam's cone (9 × 9 probe rays), and the sine
        of the beam axis's angle of incidence on the surface (0 when the axis misses)."""
        a = self.probe.radius
        g = np.linspace(-1.0, 1.0, 9)
        uu, vv = np.meshgrid(g, g)
        local = np.stack([uu.ravel(), vv.ravel(), np.full(81, 2.0)])
        local /= np.linalg.norm(local, axis=0)
        origins_l = np.stack([uu.ravel() * a, vv.ravel() * a, np.zeros(81)])
        t, sine = self._incidence(shapes, origins_l, local, position, frame)
        axis = 40  # the centre of the 9 × 9 grid: on the beam axis
        t = t[np.isfinite(t)]
        return (float(t.min()) if t.size else 3.0 * a), float(sine[axis])

    def _curved_spacing(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray, distance: float
    ) -> float:
        """[m] the spacing a curved surface ``distance`` [m] away needs besides the axis's
        Nyquist spacing: the coarser of the footprint's and the rim's rules
        (``_CURVED_FOOTPRINT_FRACTION``, ``_CURVED_RIM_FRACTION``), each an upper bound on the
        delay's rate that the other overstates: the rim's paths near the probe (at 10 mm
        the rim rule asked for 0.057 mm where 0.2 mm had converged), the footprint's grazing
        hits at large tilts (at 20° 72,000 samples for no change in the echo's window)."""
        sin_footprint = self._footprint_sine(shapes, position, frame)
        footprint = (
            _CURVED_FOOTPRINT_FRACTION * self._pose_spacing(sin_footprint)
            if sin_footprint > 0.0
            else math.inf
        )
        sin_rim = math.sin(math.atan2(self.probe.radius, max(distance, 0.0)))
        return max(footprint, _CURVED_RIM_FRACTION * self._pose_spacing(sin_rim))

    def _cap_spacing(
        self, cap: _Cap, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> float:
        """[m] the spacing over a ball's cap: ``_CURVED_FOOTPRINT_FRACTION`` of the two-way
        Nyquist spacing at the largest angle between the beam axis and the normals where
        the beam's direct wave meets the cap's core (the smaller of the core's largest and
        the footprint's, ``_footprint_sine``).  Unlike the fan about the axis, the rim's
        coarser rule does not apply: at a tilt the direct wave crosses the cap where its
        normals lie far from the axis (at 10° the rim's 0.24 mm made the echo 7.6× too
        strong)."""
        sin_beam = self._footprint_sine(shapes, position, frame)
        sin_normal = min(cap.sin_normal, sin_beam) if sin_beam > 0.0 else cap.sin_normal
        return _CURVED_FOOTPRINT_FRACTION * self._pose_spacing(sin_normal)

    def _footprint_sine(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> float:
        """The largest sine of the angle between the surface's normal and the beam axis
        where rays parallel to the axis from the face's centre and 16 points of its rim
        (radius a) meet ``shapes`` (0 if none does): see ``_CURVED_FOOTPRINT_FRACTION``."""
        phi = 2.0 * math.pi * np.arange(16) / 16
        a = self.probe.radius
        origins = np.stack(
            [np.append(a * np.cos(phi), 0.0), np.append(a * np.sin(phi), 0.0), np.zeros(17)]
        )
        axis = np.zeros((3, 17))
        axis[2] = 1.0
        return float(self._incidence(shapes, origins, axis, position, frame)[1].max())

    def _incidence(
        self,
        shapes: tuple[Shape, ...],
        origins: FloatArray,
        dirs: FloatArray,
        position: FloatArray,
        frame: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Rays from local ``origins`` [m] ``(3, n)`` along local unit ``dirs`` ``(3, n)``
        (beam along +z): their distances to ``shapes`` [m] ``(n,)`` (inf for a miss) and
        the sines of their angles of incidence there ``(n,)`` (0 for a miss)."""
        o, d = self._to_world(origins, dirs, position, frame)
        t, normal, _ = _cast_soa(shapes, o, d)
        hit = np.isfinite(t)
        cos = np.abs(np.sum(normal[:, hit] * d[:, hit], axis=0))
        sine = np.zeros(t.shape)
        sine[hit] = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
        return t, sine

    @staticmethod
    def _to_world(
        origins: FloatArray, dirs: FloatArray, position: FloatArray, frame: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Local (beam along +z = −n) → world: x' , y' and −n columns of ``frame``."""
        basis = np.stack([frame[:, 0], frame[:, 1], -frame[:, 2]], axis=1)  # (3, 3)
        o = basis @ origins + position[:, None]
        d = basis @ dirs
        return np.ascontiguousarray(o), np.ascontiguousarray(d)

    def image_plane(
        self,
        shapes: tuple[Shape, ...],
        position: FloatArray,
        frame: FloatArray,
        edges: bool = False,
    ) -> image.ImagePlane | None:
        """The plane that fills the beam's whole footprint at this pose, in the aperture
        frame, or None (the Kirchhoff sum applies); see :func:`echocal.wave.image.find_plane`.

        ``position`` [m] ``(3,)``; ``frame`` ``(3, 3)``, columns x', y', n (beam along −n).
        ``edges``: also a rectangular plate whose edge cuts the footprint, when its edges'
        echo arrives after the plate's own (``_edge_clearance``): the image form then
        gives the plate's echo exactly and leaves out the edges' later echo (the axis
        and the footprint's inner ring must still hit the plate: only its rim may pass an
        edge)."""
        basis = np.stack([frame[:, 0], frame[:, 1], -frame[:, 2]])
        axis = -frame[:, 2:3]
        distance, _, _ = _cast_soa(shapes, position[:, None].copy(), np.ascontiguousarray(axis))
        if not math.isfinite(float(distance[0])):
            return None
        r0, apex = self._fan_extent(float(distance[0]))
        x, y = self._footprint_rays * r0
        length = np.sqrt(x * x + y * y + apex * apex)
        o, d = self._to_world(
            np.stack([x, y, np.zeros_like(x)]),
            np.stack([x / length, y / length, apex / length]),
            position,
            frame,
        )
        clearance = self._edge_clearance if edges else None
        return image.find_plane(shapes, o, d, basis, position, clearance, self._rim_rays)

    @cached_property
    def _rim_rays(self) -> NDArray[np.bool_]:
        """``(2·_FOOTPRINT_RAYS + 1,)`` the footprint's rim rays: the only ones that may
        pass a plate's edges (the edge then lies in the beam's outer fringe, where the
        Kirchhoff sum's taper weights the surface least)."""
        rim = np.zeros(self._footprint_rays.shape[1], dtype=bool)
        rim[:_FOOTPRINT_RAYS] = True
        return rim

    @cached_property
    def _edge_clearance(self) -> float:
        """[m] 2ρ + c·s: the margin by which the plane beyond a plate's edges must lie
        farther from the aperture's origin than the plane itself for the plate's echo
        (paths 2h ± 2ρ, ρ the face's radius about the origin, a bowl's sag included) and
        its edges' (paths from 2(D − ρ)) to be apart after the pulse (half-support s)."""
        rho = math.hypot(self.probe.radius, self.probe.depth)
        return 2.0 * rho + self.sound_speed * self.pulse.support

    def image_nodes(self, plane: image.ImagePlane) -> tuple[FloatArray, FloatArray]:
        """The image form's quadrature over the probe's mirror image across ``plane``:
        points [m] ``(3, n)`` in the aperture frame and weights [m²] ``(n,)`` (see
        :func:`echocal.wave.image.face_quadrature`)."""
        face, weights = self._face_rule(plane)
        return plane.mirror(face), weights

    def _face_rule(self, plane: image.ImagePlane) -> tuple[FloatArray, FloatArray]:
        """The face nodes [m] ``(3, n)`` (before the mirror) and weights [m²] ``(n,)`` of
        :meth:`image_nodes`."""
        spacing = image.node_spacing(
            self._shortest_wavelength, plane.sin_incidence, _IMAGE_NYQUIST_FRACTION
        )
        return image.face_quadrature(
            self.probe,
            plane.axis_distance,
            self._shortest_wavelength,
            spacing,
            _tilt_direction(plane),
            self._plane_bandwidth(plane),
        )

    def image_spectrum(
        self,
        plane: image.ImagePlane,
        coefficient: complex | None = None,
        delay: float = 0.0,
    ) -> tuple[NDArray[np.complex128], float]:
        """The echo spectrum of an infinite plane, by the image form (before attenuation):
        over the face's nodes (:meth:`image_nodes`), or for a flat disc with one
        coefficient for the whole plane by the pair rule (:mod:`echocal.wave.pairs`) where
        that is estimated cheaper.

        Parameters
        ----------
        plane : the plane in the aperture frame (from :meth:`image_plane`).
        coefficient : one complex reflection (× transmission) coefficient for the whole
            plane; None: the model's R(θ) at each node's geometric incidence angle (from the
            face centre), as the Kirchhoff sum takes it, or 1 without one.
        delay : [s] a two-way delay added to every node (an interior's equivalent path).

        Returns
        -------
        The one-sided spectrum on :attr:`frequencies` and the weighted mean two-way time [s]
        (as :meth:`spectrum`).  With ``tables`` (flat discs and bowls), interpolated in
        the plane's table where it answers (:mod:`echocal.wave.plane_table`).
        """
        table = self._plane_tables.get(coefficient is not None) if self.tables else None
        if table is not None:
            unit = 1.0 if coefficient is None else coefficient
            answer = table(plane, unit, delay)
            if answer is not None:
                return answer
        return self._exact_image_spectrum(plane, coefficient, delay)

    def _exact_image_spectrum(
        self, plane: image.ImagePlane, coefficient: complex | None = None, delay: float = 0.0
    ) -> tuple[NDArray[np.complex128], float]:
        """:meth:`image_spectrum` by the exact form, never the table."""
        if (coefficient is not None or self.reflection is None) and self._pairs_pay(plane):
            return self._pair_spectrum(plane, 1.0 if coefficient is None else coefficient, delay)
        points, weights = self.image_nodes(plane)
        if coefficient is not None:
            r = np.full(weights.shape, complex(coefficient), dtype=np.complex128)
        elif self.reflection is not None:
            cos_theta = np.abs(plane.normal @ points) / np.linalg.norm(points, axis=0)
            theta = np.degrees(np.arccos(np.clip(cos_theta, 0.0, 1.0)))
            r = np.asarray(self.reflection(theta), dtype=np.complex128)
        else:
            r = np.ones(weights.shape, dtype=np.complex128)
        _, dt, _, n_fft = self._grid
        t0 = self._t0
        delays = np.full(weights.shape, float(delay))
        spectrum = np.zeros(n_fft // 2 + 1, dtype=np.complex128)
        path_time = 0.0
        for part, factor in ((r.real, 1.0), (r.imag, -1j)):  # e^{−iωt} phase → numpy's
            if not np.any(part != 0.0):
                continue
            grid, swt, sw = one_way_grid(
                self.probe.kind,
                self.probe.parameters,
                points,
                weights * part,
                delays,
                self.sound_speed,
                t0,
                dt,
                n_fft,
            )
            if factor == 1.0 and sw > 0.0:
                path_time = swt / sw
            spectrum += factor * scipy.fft.rfft(grid)
        return spectrum * self._image_transfer, path_time

    @cached_property
    def _plane_tables(self) -> dict[bool, PlaneTable]:
        """The plane's tables (:mod:`echocal.wave.plane_table`), by whether they hold the
        unit response (an interior's coefficient and delay applied to it) or the model's
        own R(θ) (one table when R is 1); empty for a rectangle."""
        if self.probe.kind == sir.RECT:
            return {}
        _, dt, _, n_fft = self._grid
        bins = significant_bins(np.abs(self._image_transfer), _TABLE_CUT)
        tables: dict[bool, PlaneTable] = {}
        for unit in (False, True) if self.reflection is not None else (False,):
            tables[unit] = PlaneTable(
                self._unit_exact if unit else self._own_exact,
                self.probe,
                self.sound_speed,
                self._shortest_wavelength,
                self._frequencies,
                self._t0,
                dt,
                n_fft,
                bins,
                self._table_identity() if unit or self.reflection is None else None,
            )
        if self.reflection is None:
            tables[True] = tables[False]
        return tables

    def _table_identity(self) -> dict[str, Any]:
        """What a plane table's node depends on besides its grid and the code (for its disk
        cache): the probe, the sound speed, the time grid (its step, length, and the
        fraction of a step by which its first point is off the step's multiples) and the
        image form's transfer on it (the pulse's spectrum)."""
        _, dt, _, n_fft = self._grid
        offset = (self._t0 / dt + 0.5) % 1.0 - 0.5
        return {
            "probe": [int(self.probe.kind), *(float(p) for p in self.probe.parameters)],
            "sound_speed": float(self.sound_speed),
            "dt": float(dt),
            "n_fft": int(n_fft),
            "offset": round(offset, 6),
            "transfer": array_digest(self._image_transfer),
        }

    def _own_exact(
        self, plane: image.ImagePlane, delay: float
    ) -> tuple[NDArray[np.complex128], float]:
        """The exact form with the model's own R(θ), ``delay`` [s] on every path."""
        return self._exact_image_spectrum(plane, None, delay)

    def _unit_exact(
        self, plane: image.ImagePlane, delay: float
    ) -> tuple[NDArray[np.complex128], float]:
        """The exact form with the coefficient 1, ``delay`` [s] on every path."""
        return self._exact_image_spectrum(plane, 1.0, delay)

    def _plane_bandwidth(self, plane: image.ImagePlane) -> float:
        """[rad/m] :func:`echocal.wave.image.angular_bandwidth` at ``plane``."""
        return image.angular_bandwidth(
            self._shortest_wavelength,
            plane.sin_incidence,
            self.probe.radius,
            abs(float(plane.normal @ plane.point)),
        )

    def _pairs_pay(self, plane: image.ImagePlane) -> bool:
        """Whether the pair rule (:mod:`echocal.wave.pairs`) takes ``plane``'s echo: a flat
        disc over a tilted plane, where its estimated cost is below the face rule's
        (:func:`echocal.wave.pairs.pays`)."""
        if self.probe.kind != sir.DISC or _tilt_direction(plane) == (0.0, 0.0):
            return False
        bandwidth = self._plane_bandwidth(plane)
        if bandwidth <= 0.0:
            return False
        _, dt, _, _ = self._grid
        face_nodes = int(self._face_rule(plane)[1].size)
        return pairs.pays(
            self.probe.radius,
            abs(float(plane.normal @ plane.point)),
            plane.sin_incidence,
            bandwidth,
            face_nodes,
            self.sound_speed * dt,
        )

    def _pair_spectrum(
        self, plane: image.ImagePlane, coefficient: complex, delay: float
    ) -> tuple[NDArray[np.complex128], float]:
        """:meth:`image_spectrum` by the pair rule (one reflection ``coefficient`` for the
        whole plane, ``delay`` [s] added to every path)."""
        a, c = self.probe.radius, self.sound_speed
        distance = abs(float(plane.normal @ plane.point))
        _, dt, _, n_fft = self._grid
        grid = pairs.pair_grid(
            a,
            distance,
            plane.sin_incidence,
            self._plane_bandwidth(plane),
            c,
            self._t0,
            dt,
            n_fft,
            delay,
        )
        spectrum = np.conj(complex(coefficient)) * scipy.fft.rfft(grid) * self._pair_transfer
        path = pairs.mean_image_distance(a, distance, plane.sin_incidence)
        return spectrum, path / c + delay

    @cached_property
    def _pair_transfer(self) -> NDArray[np.complex128]:
        """:attr:`_image_transfer` for the pair rule's higher-degree B-splines."""
        _, dt, _, _ = self._grid
        return self._image_transfer / pairs.smoothing(self._frequencies, dt)

    def surface_samples(
        self,
        shapes: tuple[Shape, ...],
        position: FloatArray,
        frame: FloatArray,
        refine: float = 1.0,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Surface samples seen by the probe at one pose, in the aperture frame, ``refine``
        times as far apart as the spacing rules (or ``spacing``) ask.

        Returns
        -------
        points : [m] ``(3, n)`` (face centre, or bowl apex, at the origin; beam along +z).
        unit_m : ``(3, n)`` the surface normal pointing away from the probe.
        area : [m²] ``(n,)`` patch area × taper (0 for a miss).
        """
        cap = self._cap(shapes, position, frame)
        if cap is not None:
            distance = cap.distance
            spacing = self._sample_spacing(shapes)
            if self.spacing is None:
                spacing = min(spacing, self._cap_spacing(cap, shapes, position, frame))
        else:
            distance, sin_axis = self._surface_distance(shapes, position, frame)
            spacing = self._sample_spacing(shapes, sin_axis)
            if self.spacing is None and not all(shape.kind == "plane" for shape in shapes):
                spacing = min(spacing, self._curved_spacing(shapes, position, frame, distance))
        origins, dirs, solid_angle, apex = self._fan(distance, refine * spacing, cap)
        o, d = self._to_world(origins, dirs, position, frame)
        t, normal, _ = _cast_soa(shapes, o, d)
        hit = np.isfinite(t)
        t = np.where(hit, t, 0.0)
        length = np.sqrt(np.sum(origins**2, axis=0) + apex * apex)  # apex → origin
        cos_inc = np.abs(np.sum(normal * d, axis=0))
        area = np.where(
            hit & (cos_inc > 0.05),
            solid_angle * (length + t) ** 2 / np.maximum(cos_inc, 0.05),
            0.0,
        )
        points = origins + dirs * t
        basis = np.stack([frame[:, 0], frame[:, 1], -frame[:, 2]], axis=1)
        unit_m = -(basis.T @ normal)  # facing the ray → pointing away from the probe
        return points, unit_m, area

    # ------------------------------------------------------------------ A-scans
    def ascans(
        self, shapes: tuple[Shape, ...], positions: FloatArray, frames: FloatArray
    ) -> FloatArray:
        """Noiseless A-scans ``(n_poses, n_samples)`` at positions ``(P, 3)`` [m] and frames
        ``(P, 3, 3)`` (columns x', y', n; the beam travels along −n)."""
        out = np.empty((positions.shape[0], self.window.n_samples))
        for i in range(positions.shape[0]):
            out[i] = self._ascan(shapes, positions[i], frames[i])
        return out

    def _ascan(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> FloatArray:
        # only a plane can fill the beam: curved parts skip the two extra ray casts
        has_plane = self.image_planes and any(shape.kind == "plane" for shape in shapes)
        plane = self.image_plane(shapes, position, frame, edges=True) if has_plane else None
        if plane is not None:
            spectrum, path_time = self.image_spectrum(plane)
            if path_time > 0.0:
                spectrum *= self.attenuation_factor(self.sound_speed * path_time)
            return self.samples(spectrum)
        echo = self._ball_echo(shapes, position, frame) if self.tables else None
        spectrum, t_echo = (
            echo if echo is not None else self.kirchhoff_echo(shapes, position, frame)
        )
        if t_echo > 0.0:
            # every contribution arriving at two-way time t has travelled c·t in the medium:
            # the echo is attenuated over the path c·t of its envelope peak
            spectrum = spectrum * self.attenuation_factor(self.sound_speed * t_echo)
        return self.samples(spectrum)

    def _ball_echo(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> tuple[NDArray[np.complex128], float] | None:
        """:meth:`kirchhoff_echo` over a lone ball from its table (``echocal.wave.ball_table``),
        or None where the exact sum applies (another scene or probe, or a grid that does not
        hold the whole echo)."""
        if not isinstance(self.probe, PistonProbe):
            return None
        pose = ball_table.ball_pose(shapes, position, frame, self.probe.radius)
        if pose is None or not self._ball_fits(pose):
            return None
        table, knee = self._ball_table(pose.radius, pose.distance - pose.radius)
        u = ball_table.distance_coordinate(pose.distance - pose.radius, knee)
        if not table.u.start <= u <= table.u.stop:
            return None  # nearer the face than the table's nodes can be, or very far
        return self._ball_lookup(pose)

    def _ball_bounds(self, pose: ball_table.BallPose) -> tuple[float, float]:
        """[s] the times before and after τ = 2(D − R)/c that must lie on the grid for the
        whole echo at ``pose`` to (``ball_table.span``), each widened by the pulse's
        half-support and four grid steps."""
        _, dt, _, _ = self._grid
        cap = self._cap(*ball_table.canonical_pose(pose.radius, pose.distance, pose.angle))
        assert cap is not None, "ball_pose took it"
        margin = self.pulse.support + 4.0 * dt
        early, late = ball_table.span(
            pose, self.probe.radius, self.probe.depth, self.sound_speed, cap.radius
        )
        return early + margin, late + margin

    def _ball_fits(self, pose: ball_table.BallPose) -> bool:
        """Whether the grid holds the whole echo at ``pose`` (``_ball_bounds``)."""
        before, after = self._ball_bounds(pose)
        tau = 2.0 * (pose.distance - pose.radius) / self.sound_speed
        return tau - before >= self._t0 and tau + after <= self._t0 + self.grid_period

    def _ball_node(self, pose: ball_table.BallPose) -> tuple[NDArray[np.complex128], float]:
        """The table's node at ``pose``: the Kirchhoff sum's echo at the canonical pose
        (:meth:`kirchhoff_echo`), its window moved so that the whole echo lies on the grid,
        times e^{i2πf(τ − t₀)}, averaged over two grids one step Δ_g apart; and its
        envelope's peak time less τ [s] (0 if the medium is lossless).

        The two-way deposit bins each one-way SIR from half the grid's first time, so the
        sum's small aliasing error repeats when the grid moves by 2Δ_g and changes sign,
        to first order, when it moves by Δ_g (a 3 mm probe 45 mm above a 29 mm ball, 5°
        off it: 0.87 % of the echo's peak between the two): the mean of the two leaves
        the nodes smooth in D and ψ, where the grid's phase τ − t₀ would vary from node to
        node."""
        tau = 2.0 * (pose.distance - pose.radius) / self.sound_speed
        before, _ = self._ball_bounds(pose)
        m, _, pad, _ = self._grid
        scene = ball_table.canonical_pose(pose.radius, pose.distance, abs(pose.angle))
        samples = self._kirchhoff_samples(*scene, refine=_TABLE_REFINE)
        spectrum = np.zeros_like(self._frequencies, dtype=np.complex128)
        offset = 0.0
        for step in (0, 1):
            start = tau - before + (pad - step) * m / self.window.fs
            node = dataclasses.replace(
                self, window=dataclasses.replace(self.window, start=start), tables=False
            )
            part, t_echo = node._kirchhoff_spectrum(*samples)
            spectrum += 0.5 * part * np.exp(2j * math.pi * self._frequencies * (tau - node._t0))
            offset += 0.5 * (t_echo - tau if t_echo > 0.0 else 0.0)
        return spectrum, offset

    @cached_property
    def _ball_tables(self) -> dict[float, tuple[EchoTable, float]]:
        """The ball's tables (``echocal.wave.ball_table``), one per ball radius [m]."""
        return {}

    def _ball_table(self, radius: float, top: float) -> tuple[EchoTable, float]:
        """The table of a ball of ``radius`` [m] under this model's probe and its knee h*
        [m] (``ball_table.axes``: u from the top's distance h = D − R, v = ψ [rad]), built
        on first use with a node at h = ``top`` [m]."""
        entry = self._ball_tables.get(radius)
        if entry is None:
            assert isinstance(self.probe, PistonProbe), "_ball_echo checked it"
            u, v, knee = ball_table.axes(
                self.probe.radius, self.probe.depth, self._shortest_wavelength, top
            )

            def node(coordinate: float, angle: float) -> tuple[NDArray[np.complex128], float]:
                top = ball_table.distance_from_coordinate(coordinate, knee)
                return self._ball_node(ball_table.BallPose(radius, radius + top, angle))

            bins = significant_bins(np.abs(self._transfer), _TABLE_CUT)
            store = None
            if self.reflection is None:  # an R(θ) law is a function: no content to key on
                grid = {"radius": radius, "u": [u.start, u.step, knee], "v": v.step}
                identity = {**self._ball_identity(), **grid, "bins": [bins.start, bins.stop]}
                store = DiskNodes("ball", identity)
            table = EchoTable(node, u, v, bins, self._frequencies.size, store=store)
            entry = (table, knee)
            self._ball_tables[radius] = entry
        return entry

    def _ball_identity(self) -> dict[str, Any]:
        """What a ball table's node depends on besides its grid and the code (for its disk
        cache): the probe, the sound speed, the time grid (sampling rate, step, length; the
        node's window is placed from the pose alone), the pulse's support and the sum's
        transfer on the grid (the pulse's spectrum), and whether the medium is lossy (the
        node's envelope time)."""
        _, dt, _, n_fft = self._grid
        return {
            "probe": [int(self.probe.kind), *(float(p) for p in self.probe.parameters)],
            "sound_speed": float(self.sound_speed),
            "fs": float(self.window.fs),
            "dt": float(dt),
            "n_fft": int(n_fft),
            "support": float(self.pulse.support),
            "transfer": array_digest(self._transfer),
            "spacing": self.spacing,
            "lossy": self.attenuation is not None,
        }

    def _ball_lookup(self, pose: ball_table.BallPose) -> tuple[NDArray[np.complex128], float]:
        """:meth:`kirchhoff_echo` at ``pose`` from the ball's table, re-modulated by
        e^{−i2πf(τ − t₀)}, and the envelope's peak time [s] (0 if the medium is lossless)."""
        top = pose.distance - pose.radius
        table, knee = self._ball_table(pose.radius, top)
        spectrum, offset = table(ball_table.distance_coordinate(top, knee), pose.angle)
        tau = 2.0 * top / self.sound_speed
        spectrum *= np.exp(-2j * math.pi * self._frequencies * (tau - self._t0))
        return spectrum, (tau + offset if self.attenuation is not None else 0.0)

    def kirchhoff_echo(
        self, shapes: tuple[Shape, ...], position: FloatArray, frame: FloatArray
    ) -> tuple[NDArray[np.complex128], float]:
        """The Kirchhoff sum's echo spectrum at one pose (:meth:`surface_samples`, R(θ) at
        each sample's incidence from the face centre, :meth:`spectrum`), before the
        medium's attenuation, and the time [s] of its envelope's peak (the path c·t it is
        attenuated over; 0 when the medium is lossless or nothing contributes).

        ``position`` [m] ``(3,)``; ``frame`` ``(3, 3)``, columns x', y', n."""
        return self._kirchhoff_spectrum(*self._kirchhoff_samples(shapes, position, frame))

    def _kirchhoff_samples(
        self,
        shapes: tuple[Shape, ...],
        position: FloatArray,
        frame: FloatArray,
        refine: float = 1.0,
    ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.complex128] | None]:
        """:meth:`surface_samples` (``refine``) and R(θ) at each (None without a reflection
        law)."""
        points, unit_m, area = self.surface_samples(shapes, position, frame, refine)
        reflection = None
        if self.reflection is not None:
            r = np.linalg.norm(points, axis=0)
            cos_theta = np.abs(np.sum(unit_m * points, axis=0)) / np.maximum(r, 1e-300)
            theta = np.degrees(np.arccos(np.clip(cos_theta, 0.0, 1.0)))
            reflection = np.asarray(self.reflection(theta), dtype=np.complex128)
        return points, unit_m, area, reflection

    def _kirchhoff_spectrum(
        self,
        points: FloatArray,
        unit_m: FloatArray,
        area: FloatArray,
        reflection: NDArray[np.complex128] | None,
    ) -> tuple[NDArray[np.complex128], float]:
        """:meth:`kirchhoff_echo` of given samples (:meth:`_kirchhoff_samples`)."""
        spectrum, path_time = self.spectrum(points, unit_m, area, reflection)
        if self.attenuation is None or path_time <= 0.0:
            return spectrum, 0.0
        _, dt, _, n_fft = self._grid
        analytic = analytic_signal(scipy.fft.irfft(spectrum, n=n_fft))
        return spectrum, self._t0 + dt * float(np.argmax(np.abs(analytic)))

    def attenuation_factor(self, path: float) -> NDArray[np.float64]:
        """exp(−α(f)·path) of the medium on the grid's frequencies (path [m]); 1 if lossless."""
        if self.attenuation is None:
            return np.ones_like(self._frequencies)
        return np.exp(-np.asarray(self.attenuation(self._frequencies)) * path)

    @property
    def frequencies(self) -> FloatArray:
        """[Hz] the frequencies of :meth:`spectrum`'s bins, shape ``(n_fft // 2 + 1,)``."""
        return self._frequencies

    def spectrum(
        self,
        points: FloatArray,
        unit_m: FloatArray,
        area: FloatArray,
        reflection: NDArray[np.complex128] | None = None,
        delays: FloatArray | None = None,
    ) -> tuple[NDArray[np.complex128], float]:
        """The echo spectrum of surface samples, before the medium's attenuation.

        Parameters
        ----------
        points : [m] samples in the aperture frame, ``(3, n)``.
        unit_m : the vectors m of the kernel ``echocal.wave.sir.accumulate_two_way`` (the
            surface normal pointing away from the probe, or its scaled form inside a part),
            ``(3, n)``.
        area : [m²] patch areas (× any real factor), ``(n,)``.
        reflection : complex reflection (× transmission) coefficients, ``(n,)``; None: 1.
        delays : [s] two-way delays added to the samples' geometric times, ``(n,)``.

        Returns
        -------
        The one-sided spectrum on :attr:`frequencies` (pass it to :meth:`samples`) and the
        weighted mean two-way time [s] of the samples (0 if none contributes).
        """
        _, dt, _, n_fft = self._grid
        t0 = self._t0
        c = self.sound_speed
        weights = area / (self.probe.area * c * c)
        delays = np.zeros(weights.shape[0]) if delays is None else delays
        prm = self.probe.parameters
        n_scratch = sir.scratch_bins(c, dt, 2.0 * self.probe.radius)
        spectrum = np.zeros(n_fft // 2 + 1, dtype=np.complex128)
        parts: list[tuple[FloatArray, complex]] = [
            (weights if reflection is None else weights * reflection.real, 1.0)
        ]
        if reflection is not None and np.any(reflection.imag != 0.0):
            parts.append((weights * reflection.imag, -1j))  # e^{−iωt} phase → numpy's
        path_time = 0.0
        for w, factor in parts:
            grid, swt, sw = two_way_grid(
                self.probe.kind, prm, points, unit_m, w, delays, c, t0, dt, n_fft, n_scratch
            )
            if factor == 1.0 and sw > 0.0:
                path_time = swt / sw
            spectrum += factor * scipy.fft.rfft(grid)
        return spectrum * self._transfer, path_time

    def spectrum_of_response(self, response: NDArray[np.complex128]) -> NDArray[np.complex128]:
        """The echo spectrum (as :meth:`spectrum` returns it) of a pulse-echo response V(f)
        on :attr:`frequencies`, given in the e^{−iωt} convention and normalized as the
        average over the receiving face of the returned pressure p/(ρcv₀) (V = e^{2ikd} for
        a plane wave reflected at distance d): W(f)·conj(V)·e^{iωt₀}/Δ_g, t₀ the grid's
        first time, Δ_g its spacing."""
        _, dt, _, _ = self._grid
        t0 = self._t0
        f = self._frequencies
        return self.pulse.spectrum(f) * np.conj(response) * np.exp(2j * math.pi * f * t0) / dt

    def refined_frequencies(self, factor: int) -> FloatArray:
        """[Hz] the bins of a grid ``factor`` times finer than :attr:`frequencies` (its
        period ``factor`` times longer), shape ``(factor·n_fft // 2 + 1,)``."""
        _, dt, _, n_fft = self._grid
        return np.asarray(np.fft.rfftfreq(factor * n_fft, dt), dtype=np.float64)

    def refined_samples(
        self, response: NDArray[np.complex128], factor: int, damping: float
    ) -> FloatArray:
        """The recording window's samples ``(n_samples,)`` of a pulse-echo response given
        (as :meth:`spectrum_of_response` takes it) at the complex frequencies f + iε/2π,
        f on :meth:`refined_frequencies` (``factor``) and ε = ``damping`` [1/s]: the
        response times e^{−εt}.  The pulse is damped alike (its waveform times e^{−εt},
        transformed here), the echo is undamped after the inverse transform: what the
        response holds past the (``factor`` times longer) period folds back damped by
        e^{−ε·period}."""
        m, dt, _, n_fft = self._grid
        f = self.refined_frequencies(factor)
        pulse = self._damped_pulse_spectrum(f, damping)
        t0 = self._t0  # the damping is referred to the grid's first point
        shift = np.exp(2j * math.pi * f * t0 + damping * t0)
        x = m * scipy.fft.irfft(pulse * np.conj(response) * shift / dt, n=factor * m * n_fft)
        t = (np.arange(self.window.n_samples) + self._lead) / self.window.fs
        return x[self._lead : self._lead + self.window.n_samples] * np.exp(damping * t)

    def _damped_pulse_spectrum(self, f: FloatArray, damping: float) -> NDArray[np.complex128]:
        """∫ w(t) e^{−εt} e^{−i2πft} dt at ``f`` [Hz]: the trapezoid rule over the
        pulse's support at 8 points per period of its highest frequency (spectrally
        accurate: w is smooth and below 1e-7 of its peak at the ends)."""
        s = self.pulse.support
        n = int(16.0 * s * self.pulse.highest_frequency) + 65
        t = np.linspace(-s, s, n)
        w = self.pulse.waveform(t) * np.exp(-damping * t) * (t[1] - t[0])
        out = np.empty(f.size, dtype=np.complex128)
        chunk = max(1, 2_000_000 // n)
        for i in range(0, f.size, chunk):
            out[i : i + chunk] = np.exp(-2j * math.pi * np.outer(f[i : i + chunk], t)) @ w
        return out

    @property
    def grid_period(self) -> float:
        """[s] the period of :meth:`samples`' grid (its first point at ``window.start``
        less the pad)."""
        _, dt, _, n_fft = self._grid
        return n_fft * dt

    @property
    def grid_start(self) -> float:
        """[s] the time of the grid's first point."""
        return self._t0

    def samples(self, spectrum: NDArray[np.complex128]) -> FloatArray:
        """The recording window's samples ``(n_samples,)`` of a :meth:`spectrum`."""
        m, _, _, n_fft = self._grid
        x = m * scipy.fft.irfft(spectrum, n=m * n_fft)
        return x[self._lead : self._lead + self.window.n_samples]
