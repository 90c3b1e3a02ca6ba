"""Echoes from inside a plate: the back wall, its multiples and flaws, on the wave model.

**Model (paraxial equivalent water path).**  A field that has crossed a plane water–solid
interface obeys, to second order in the transverse wavenumber k_x (the paraxial
expansion k_z ≈ k − k_x²/2k), the same diffraction as in water over an *equivalent
path*: a depth z below the front face in a solid of speed c_L diffracts like a water
column of depth z·c_L/c_w, and arrives z·(1/c_L − c_L/c_w²) earlier than that water path
would say.  So every reflector inside the part is evaluated with the transducer's exact
spatial impulse response at its *equivalent point* (same lateral position, depth scaled by
c_L/c_w), delayed by that correction, in the physical-optics (Kirchhoff) reciprocity
integral of :class:`~echocal.wave.WaveEchoModel`.  In the solid, the normal derivative carries
k_L instead of k_w and the reciprocity integral 1/ρ_s instead of 1/ρ_w; with the pressure
transmission coefficients this makes the weight of a reflector sample

    R_reflector · T_ws(θ_w) · T_sw(θ_L) · ΔS,   with m's depth component scaled by c_w/c_L,

which for a flat reflector parallel to the face reduces to the plane-wave result
T_ws·R·T_sw (= 1 − R² in magnitude for the back wall of a plate in water).

**Echo train.**  The k-th back-wall echo (k = 1 the back wall, k ≥ 2 its multiples) is
the plate's back face at depth k·T with coefficient T_ws·R_sw^(2k−1)·T_sw (R_sw the
solid→water reflection, at the back wall and, for multiples, under the front face), two-way
time 2d/c_w + 2kT/c_L at normal incidence.  A flaw is a void (R = −1, pressure release) with
Kirchhoff boundary values on its lit side (outward normal towards the front face).  The
solid's attenuation α_s(f) acts over the echo's path in the part, the medium's over the
water path: the spectrum is multiplied by exp(−α_w·2d − α_s·2z).  A flaw hides the part of
the back wall behind it: its silhouette along the face's normal, on the wall's equivalent
mirror, is taken out of the wall's echo (:meth:`InteriorEchoes._shadows`).  A plate of
several layers (:mod:`echocal.wave.layered`, docs/layered-parts.md) has an echo per path
through its interfaces, each evaluated the same way (with ``shear_legs``, paths with
mode-converted legs too); with ``exact_stack``, under a flat circular probe, the A-scan is
the whole stack's exact plane-wave response (:mod:`echocal.wave.stack`), the paths plus a
``stack-remainder`` echo (:meth:`InteriorEchoes._whole_stack`).

**Left out** (documented in docs/inside-the-specimen.md): a single plate's mode-converted
(L→T) echoes and the shear waves' own echoes (the coefficients account for the energy
they take), shadowing
of flaws by each other, and flaw–wall interactions.  A
curved front face is modelled for the back wall of a spherical shell
(:mod:`echocal.wave.shell`: an equivalent water sphere) and of a pipe
(:mod:`echocal.wave.curved_wall`: angular spectrum on the tangent plane); no flaws in
curved parts.
The paraxial expansion holds for the beam's angular spectrum well inside the first
critical angle (≈ ±5° of tilt on steel); it is checked against an exact angular-spectrum
solution with the fluid-loaded plate's reflection coefficient in tests/physics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from echocal.coefficients import (
    reflection_solid_fluid,
    transmission_fluid_solid,
    transmission_solid_fluid,
)
from echocal.materials import Material
from echocal.signal.analytic import analytic_signal
from echocal.signal.window import RecordingWindow
from echocal.specimen.cylinder import Cylinder
from echocal.specimen.interior import Flaw, Interior, Layer, SurfaceSamples
from echocal.specimen.plane import FinitePlane
from echocal.specimen.sphere import Sphere
from echocal.wave.curved_wall import curved_back_walls, tangent_plane
from echocal.wave.layered import EchoPath, echo_paths, pp_coefficients
from echocal.wave.layered_spectrum import PistonOverPlate, band_responses, stack_response
from echocal.wave.model import WaveEchoModel
from echocal.wave.probe import PistonProbe
from echocal.wave.shell import equivalent_mirror
from echocal.wave.stack import damped_grid

__all__ = [
    "FRONT_WALL",
    "STACK_REMAINDER",
    "InteriorEchoes",
    "LabelledEcho",
    "back_wall_label",
    "echo_list",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

FRONT_WALL = "front-wall"
"""Label of the front face's echo."""

STACK_REMAINDER = "stack-remainder"
"""Label of what a layered plate's exact echo train holds beyond its listed paths (the
multiples past their order, the mode conversions past ``shear_legs``): the A-scan is the
front wall, the paths and this remainder."""

STACK_BAND_FLOOR = 1e-6
"""The whole stack's response is computed where the pulse's spectrum is above this fraction
of its peak (lower than the paths' 10⁻³: the band's cut spreads over the window, where
undamping the response (:func:`echocal.wave.stack.damped_grid`) raises it towards the
window's end)."""

_SOLID_SAMPLES_PER_WAVELENGTH = 6.0
"""Flaw surfaces are sampled at λ_L/6 (at the pulse's centre frequency): two-way time steps
of a sixth of a period across a curved flaw."""


_NO_ECHO = 1e-7
"""An echo below this fraction of the strongest one is reported as absent."""


@dataclass(frozen=True)
class LabelledEcho:
    """One echo of the train: its label, time of flight [s] and amplitude (the envelope
    peak of its noiseless samples, the A-scan's units)."""

    label: str
    tof_s: float
    amplitude: float


def echo_list(echoes: dict[str, FloatArray], window: RecordingWindow) -> list[LabelledEcho]:
    """Each labelled echo's envelope peak and its time (parabolic interpolation between
    samples), in the order given; an echo with no signal (outside the window, or blocked
    beyond the critical angle: below 1e-7 of the strongest echo, the spectral leak of one
    that arrives after the window) has amplitude 0 and time NaN."""
    envelopes = {label: np.abs(analytic_signal(x)) for label, x in echoes.items()}
    floor = _NO_ECHO * max((float(e.max()) for e in envelopes.values()), default=0.0)
    out = []
    for label, envelope in envelopes.items():
        i = int(np.argmax(envelope))
        peak = float(envelope[i])
        if peak <= floor:
            out.append(LabelledEcho(label, math.nan, 0.0))
            continue
        shift = 0.0
        if 0 < i < envelope.size - 1:
            y0, y1, y2 = envelope[i - 1 : i + 2]
            curvature = y0 - 2.0 * y1 + y2
            shift = 0.5 * (y0 - y2) / curvature if curvature < 0.0 else 0.0
        out.append(LabelledEcho(label, window.start + (i + shift) / window.fs, peak))
    return out


def back_wall_label(order: int) -> str:
    """``back-wall`` for the first back-wall echo, ``back-wall-2`` for its first multiple, …"""
    return "back-wall" if order == 1 else f"back-wall-{order}"


@dataclass(frozen=True)
class _Front:
    """The front face in the aperture frame at one pose."""

    point: FloatArray  # [m] (3,) a point of the face
    normal: FloatArray  # (3,) unit, towards the probe
    water_path: float  # [m] along the beam axis to the face


@dataclass(frozen=True, eq=False)
class InteriorEchoes:
    """Labelled noiseless echoes of a plate, its back wall and its flaws, on the wave model.

    Parameters
    ----------
    model : the setup's wave model (the front wall's echo, exact probe fields).
    front : the plate's front face; or the outer face of a spherical shell
        (:mod:`echocal.wave.shell`) or of a pipe (:mod:`echocal.wave.curved_wall`), with
        no flaws.
    interior : its thickness and flaws.
    medium : the coupling fluid (its ``longitudinal_speed`` is the model's sound speed).
    material : the plate's solid material.
    """

    model: WaveEchoModel
    front: FinitePlane | Sphere | Cylinder
    interior: Interior
    medium: Material
    material: Material

    @property
    def labels(self) -> tuple[str, ...]:
        """Every echo's label, in the order of :meth:`echoes`."""
        if self.interior.layers:
            paths = tuple(p.label for p in self.paths(0.0))
            rest = (STACK_REMAINDER,) if self._stack_route else ()
            return (FRONT_WALL, *paths, *rest, *(f.name for f in self.interior.flaws))
        walls = tuple(back_wall_label(k) for k in range(1, self.interior.back_wall_echoes + 1))
        return (FRONT_WALL, *walls, *(f.name for f in self.interior.flaws))

    def ascans(self, positions: FloatArray, frames: FloatArray) -> FloatArray:
        """Noiseless A-scans ``(n_poses, n_samples)``: the sum of every echo."""
        out = np.empty((positions.shape[0], self.model.window.n_samples))
        for i in range(positions.shape[0]):
            out[i] = sum(self.echoes(positions[i], frames[i]).values())
        return out

    def echoes(self, position: FloatArray, frame: FloatArray) -> dict[str, FloatArray]:
        """Each echo's noiseless samples ``(n_samples,)`` at one pose, by label.

        ``position`` [m] ``(3,)``; ``frame`` ``(3, 3)``, columns x', y', n (beam along −n).
        """
        front = self._front(position, frame)
        if front is None:  # the beam axis never meets the face: nothing enters the part
            zero = np.zeros(self.model.window.n_samples)
            out = {FRONT_WALL: self._front_wall(position, frame)}
            return out | {label: zero for label in self.labels[1:]}
        orders = range(1, self.interior.back_wall_echoes + 1)
        if self.interior.layers:
            out = self._layered_echoes(position, frame, front)
        elif isinstance(self.front, Cylinder):  # a pipe: every order in one propagation
            out = {FRONT_WALL: self._front_wall(position, frame)}
            spectra = curved_back_walls(
                self.model,
                self.front,
                self.interior.thickness,
                len(orders),
                self.material.longitudinal_speed,
                position,
                frame,
                lambda k: self._wall_coefficient(k, front),
            )
            for k, spectrum in zip(orders, spectra, strict=True):
                depth = k * self.interior.thickness
                out[back_wall_label(k)] = self._finish(spectrum, front, 2.0 * depth)
        else:
            out = {FRONT_WALL: self._front_wall(position, frame)}
            for k in orders:
                out[back_wall_label(k)] = self._back_wall(k, position, frame, front)
        for flaw in self.interior.flaws:
            out[flaw.name] = self._flaw(flaw, position, frame, front)
        return out

    def _layered_echoes(
        self, position: FloatArray, frame: FloatArray, front: _Front
    ) -> dict[str, FloatArray]:
        """A layered plate's front-wall echo and every path's, by label: over the probe's
        plane-wave spectrum where :meth:`_exact_paths` applies, else on the paraxial
        equivalent mirrors; each less the flaws' shadows."""
        out: dict[str, FloatArray] = {}
        sin_w = math.sin(math.radians(self._axis_angles(front)[0]))
        paths = self.paths(sin_w)
        exact = self._exact_paths(paths, position, frame, front)
        if exact is not None:  # the front face's echo over the same spectrum
            spectrum = self.model.spectrum_of_response(exact[0])
            spectrum = spectrum * self.model.attenuation_factor(2.0 * front.water_path)
            out[FRONT_WALL] = self.model.samples(spectrum)
        else:
            out[FRONT_WALL] = self._front_wall(position, frame)
        unit: dict[tuple[float, float], ComplexArray] = {}  # paths of equal legs
        whole_stack = self._stack_route and exact is not None
        listed = np.zeros_like(self.model.frequencies, dtype=np.complex128)  # paths' sum
        for j, path in enumerate(paths):
            if exact is not None:
                spectrum = self.model.spectrum_of_response(exact[j + 1])
            else:
                key = (round(path.equivalent_depth, 12), round(path.delay, 15))
                if key not in unit:
                    unit[key] = self._mirror(
                        path.equivalent_depth, 1.0, path.delay, position, frame
                    )
                spectrum = np.conj(path.coefficient) * unit[key]
            echo = self._attenuated(path, spectrum, front)
            if whole_stack:
                listed += echo
            if self.interior.flaws:
                wall = float(self.interior.interfaces[max(path.turns)])
                spectrum = spectrum - self._shadows(
                    wall,
                    path.equivalent_depth,
                    path.coefficient,
                    path.delay,
                    position,
                    frame,
                    front,
                )
                echo = self._attenuated(path, spectrum, front)
            out[path.label] = self.model.samples(echo)
        if self._stack_route:
            out[STACK_REMAINDER] = np.zeros(self.model.window.n_samples)
            if whole_stack:  # the exact train less the front wall and the paths
                whole = self._whole_stack(front)
                out[STACK_REMAINDER] = whole - out[FRONT_WALL] - self.model.samples(listed)
        return out

    @property
    def _stack_route(self) -> bool:
        """Whether the layered plate's A-scan is the exact stack's (:meth:`_whole_stack`,
        with a :data:`STACK_REMAINDER` echo): asked for (``exact_stack``), a flat piston
        over a flat layered plate (other probes: the paths alone)."""
        probe = self.model.probe
        return (
            self.interior.exact_stack
            and bool(self.interior.layers)
            and isinstance(probe, PistonProbe)
            and probe.curvature is None
            and isinstance(self.front, FinitePlane)
        )

    def _whole_stack(self, front: _Front) -> FloatArray:
        """The whole plate's exact echo train (front wall, every multiple and mode
        conversion; :func:`echocal.wave.layered_spectrum.stack_response`), on a grid
        longer in period than the model's and damped (:func:`echocal.wave.stack.damped_grid`),
        so that the plate's ringing past the window does not fold back onto it."""
        model = self.model
        probe = model.probe
        assert isinstance(probe, PistonProbe)
        tilt = math.radians(self._axis_angles(front)[0])
        distance = front.water_path * math.cos(tilt)
        c_w = model.sound_speed
        window = model.window
        end = window.start + window.n_samples / window.fs
        support = model.pulse.support
        factor, damping = damped_grid(
            end + support - model.grid_start, end + support, model.grid_period
        )
        f = model.refined_frequencies(factor)
        magnitude = np.abs(model.pulse.spectrum(f))
        band = (magnitude > STACK_BAND_FLOOR * magnitude.max()) & (f > 0.0)
        setting = PistonOverPlate(
            probe.radius, self._medium_at_model_speed, self.interior.layers, distance, tilt
        )
        response = np.zeros(f.size, dtype=np.complex128)
        span = end - 2.0 * distance / c_w
        complex_f = f[band] + 1j * damping / (2.0 * math.pi)
        response[band] = stack_response(setting, complex_f, span)
        if model.attenuation is not None:
            response *= np.exp(-np.asarray(model.attenuation(f)) * 2.0 * front.water_path)
        return model.refined_samples(response, factor, damping)

    def _front_wall(self, position: FloatArray, frame: FloatArray) -> FloatArray:
        """The front face's echo by the wave model (its reflection R(θ) at each sample)."""
        return self.model.ascans((self.front,), position[None], frame[None])[0]

    def paths(self, sin_water: float = 0.0) -> list[EchoPath]:
        """The layered plate's echo paths (:func:`echocal.wave.layered.echo_paths`) at the
        beam axis's incidence sine ``sin_water`` in the medium; empty without layers."""
        if not self.interior.layers:
            return []
        return echo_paths(
            self.interior.layers,
            self._medium_at_model_speed,
            sin_water,
            self.interior.back_wall_echoes,
            self.interior.shear_legs,
        )

    def describe(self) -> dict[str, dict[str, object]]:
        """Each echo's path through a layered plate, by label (``simulate --json``): the
        interfaces it reflects at (0 the front face seen from below) and its legs (layer
        number, material, wave mode), at normal incidence; a flaw's host layer.  Empty
        without layers."""
        if not self.interior.layers:
            return {}
        layers = self.interior.layers
        out: dict[str, dict[str, object]] = {}
        for path in self.paths(0.0):
            out[path.label] = {
                "reflections": list(path.turns),
                "legs": [
                    {"layer": leg, "material": layers[leg - 1].material.name, "mode": mode}
                    for leg, mode in zip(path.legs, path.modes, strict=True)
                ],
            }
        if self._stack_route:
            out[STACK_REMAINDER] = {"paths": "the exact stack's echo train less those listed"}
        for flaw in self.interior.flaws:
            host = len(self._flaw_column(flaw).layers)
            out[flaw.name] = {"layer": host, "material": layers[host - 1].material.name}
        return out

    def _exact_paths(
        self, paths: list[EchoPath], position: FloatArray, frame: FloatArray, front: _Front
    ) -> ComplexArray | None:
        """The front face's and every path's exact response V(f) ``(1 + n_paths, n_f)``
        over the probe's plane-wave spectrum (:mod:`echocal.wave.layered_spectrum`) when it
        applies: a flat piston over a flat layered plate whose face fills the beam; else
        None (the paraxial equivalent mirrors)."""
        probe = self.model.probe
        if not (isinstance(probe, PistonProbe) and probe.curvature is None):
            return None
        if not isinstance(self.front, FinitePlane) or not paths:
            return None
        if self.model.image_plane((self.front,), position, frame) is None:
            return None
        tilt = math.radians(self._axis_angles(front)[0])
        f = self.model.frequencies
        setting = PistonOverPlate(
            probe.radius,
            self._medium_at_model_speed,
            self.interior.layers,
            front.water_path * math.cos(tilt),
            tilt,
        )
        return band_responses(
            setting,
            [((), ""), *((p.turns, p.modes) for p in paths)],
            f,
            np.abs(self.model.pulse.spectrum(f)),
        )

    @property
    def _medium_at_model_speed(self) -> Material:
        return Material(
            name=self.medium.name,
            density=self.medium.density,
            longitudinal_speed=self.model.sound_speed,
        )

    def _attenuated(self, path: EchoPath, spectrum: ComplexArray, front: _Front) -> ComplexArray:
        """A layered plate's echo spectrum along ``path`` from its ``spectrum`` before
        attenuation (its equivalent water mirror's echo: :meth:`_mirror` with coefficient 1
        scaled by conj(c), the e^{−iωt} phase in numpy's convention, or its plane-wave
        response), attenuated in each layer over the distance the path runs there and in
        the water."""
        f = self.model.frequencies
        loss = np.zeros_like(f)
        for layer, mode, length in path.attenuation_path:
            material = self.interior.layers[layer - 1].material
            law = material.attenuation
            if mode == "S" and material.shear_attenuation is not None:
                law = material.shear_attenuation
            loss += np.asarray(law.alpha(f)) * length
        return spectrum * np.exp(-loss) * self.model.attenuation_factor(2.0 * front.water_path)

    # ------------------------------------------------------------------ geometry
    @property
    def _ratio(self) -> float:
        """c_L/c_w, the depth scale of the equivalent water path."""
        return self.material.longitudinal_speed / self.model.sound_speed

    def _delay_per_depth(self) -> float:
        """[s/m] two-way time correction per metre of depth: 2(1/c_L − c_L/c_w²)."""
        c_l, c_w = self.material.longitudinal_speed, self.model.sound_speed
        return 2.0 * (1.0 / c_l - c_l / c_w**2)

    @staticmethod
    def _basis(frame: FloatArray) -> FloatArray:
        """World → aperture frame rotation (rows x', y', −n)."""
        return np.stack([frame[:, 0], frame[:, 1], -frame[:, 2]])

    def _front(self, position: FloatArray, frame: FloatArray) -> _Front | None:
        basis = self._basis(frame)
        if isinstance(self.front, (Sphere, Cylinder)):  # where the radius meets the probe
            plane = tangent_plane(self.front, position)
            point = basis @ (plane.origin - position)
            normal = basis @ plane.basis[2]
        else:
            point = basis @ (self.front.center - position)
            normal = basis @ self.front.normal
        if float(normal @ point) > 0.0:  # make it point towards the probe (the origin)
            normal = -normal
        along = -float(normal[2])  # the beam (+z) meets the face where z·(−n_z) = −n·p
        if along <= 1e-6:
            return None
        return _Front(point, normal, float(-(normal @ point)) / along)

    # ------------------------------------------------------------------ coefficients
    def _axis_angles(self, front: _Front) -> tuple[float, float]:
        """The beam axis's incidence angle [deg] on the face, in water and (Snell) in the
        solid (90 beyond the critical angle)."""
        theta_w = math.degrees(math.acos(min(1.0, -float(front.normal[2]))))
        sin_l = math.sin(math.radians(theta_w)) * self._ratio
        return theta_w, math.degrees(math.asin(min(1.0, sin_l)))

    def _through_the_face(self, theta_w: float, theta_l: float) -> complex:
        """T_ws(θ_w)·T_sw(θ_L): into the part and back out (0 beyond the critical angle).

        Taken at the beam axis's angle for every sample: in the paraxial picture the field
        inside the part travels along the refracted axis (a sample's geometric angle from
        the face centre is not the direction its field travels in).  Against the exact
        angular spectrum of the back-wall term this is within 0.1 % at 0–0.5° of tilt."""
        if math.sin(math.radians(theta_w)) * self._ratio >= 1.0:
            return 0.0j
        t_in = transmission_fluid_solid(theta_w, self.medium, self.material).longitudinal
        t_out = transmission_solid_fluid(theta_l, self.material, self.medium)
        return complex(t_in * t_out)

    def _wall_coefficient(self, order: int, front: _Front) -> complex:
        """T_ws·R_sw^(2k−1)·T_sw of the ``order``-th back-wall echo at the beam axis's angle."""
        theta_w, theta_l = self._axis_angles(front)
        r_sw = complex(reflection_solid_fluid(theta_l, self.material, self.medium).longitudinal)
        return self._through_the_face(theta_w, theta_l) * r_sw ** (2 * order - 1)

    def _solid_attenuation(self, path: float) -> FloatArray:
        attenuation = self.material.attenuation
        f = self.model.frequencies
        return np.exp(-np.asarray(attenuation.alpha(f)) * path)

    def _finish(self, spectrum: ComplexArray, front: _Front, solid_path: float) -> FloatArray:
        spectrum = spectrum * self.model.attenuation_factor(2.0 * front.water_path)
        return self.model.samples(spectrum * self._solid_attenuation(solid_path))

    # ------------------------------------------------------------------ echoes
    def _back_wall(
        self, order: int, position: FloatArray, frame: FloatArray, front: _Front
    ) -> FloatArray:
        """The ``order``-th back-wall echo's samples (see :meth:`back_wall_spectrum`), less
        the part of the wall the flaws hide (:meth:`_shadows`)."""
        spectrum = self.back_wall_spectrum(order, position, frame, front)
        if self.interior.flaws and isinstance(self.front, FinitePlane):
            depth = order * self.interior.thickness
            spectrum = spectrum - self._shadows(
                self.interior.thickness,
                depth * self._ratio,
                self._wall_coefficient(order, front),
                self._delay_per_depth() * depth,
                position,
                frame,
                front,
            )
        return self._finish(spectrum, front, 2.0 * order * self.interior.thickness)

    def _shadows(
        self,
        wall_depth: float,
        equivalent_depth: float,
        coefficient: complex,
        delay: float,
        position: FloatArray,
        frame: FloatArray,
        front: _Front,
    ) -> ComplexArray:
        """The echo spectrum of the parts of a wall (an interface ``wall_depth`` [m] below
        the face) that the flaws above it hide from the probe: each flaw's silhouette
        projected along the face's normal onto the wall's equivalent mirror, with the
        wall path's ``coefficient`` and ``delay`` — the physical-optics echo of the wall
        is that of its lit part only.  A multiple loses its shadowed patch once (first
        order in the hidden fraction)."""
        assert isinstance(self.front, FinitePlane)  # flaws sit in plates only
        total = np.zeros(self.model.frequencies.shape, dtype=np.complex128)
        basis = self._basis(frame)
        for flaw in self.interior.flaws:
            if flaw.depth_range(self.front)[1] >= wall_depth:
                continue  # not above this wall
            samples = self._silhouettes[flaw.name]
            points = basis @ (samples.points - position[:, None])
            depth = (front.point - points.T) @ front.normal
            points = points - np.outer(front.normal, equivalent_depth - depth)
            unit_m = np.repeat(-front.normal[:, None], samples.areas.size, axis=1)
            weights = np.full(samples.areas.shape, coefficient, dtype=np.complex128)
            delays = np.full(samples.areas.shape, delay)
            spectrum, _ = self.model.spectrum(points, unit_m, samples.areas, weights, delays)
            total += spectrum
        return total

    @cached_property
    def _silhouettes(self) -> dict[str, SurfaceSamples]:
        """Each flaw's silhouette along the face's normal, sampled at the surface spacing
        the wave model uses on planes."""
        assert isinstance(self.front, FinitePlane)
        spacing = self.model._sample_spacing((self.front,))
        return {f.name: f.silhouette(spacing, self.front.normal) for f in self.interior.flaws}

    def back_wall_spectrum(
        self, order: int, position: FloatArray, frame: FloatArray, front: _Front
    ) -> ComplexArray:
        """The ``order``-th back-wall echo's spectrum before attenuation, for a plate or a
        spherical shell: the wave model's echo of the equivalent water mirror — the
        plate's face at the equivalent depth (by the image form when it fills the beam),
        or the shell's concentric equivalent sphere (:mod:`echocal.wave.shell`) — its
        two-way time corrected to 2kT/c_L below the face."""
        depth = order * self.interior.thickness
        through = self._wall_coefficient(order, front)
        if isinstance(self.front, Sphere):
            mirror = equivalent_mirror(
                self.front.radius, self.interior.thickness, order, self._ratio
            )
            sphere = Sphere(
                center=self.front.center, radius=mirror.radius, name="equivalent back wall"
            )
            delay = 2.0 * depth / self.material.longitudinal_speed
            delay -= 2.0 * mirror.distance / self.model.sound_speed
            return self._kirchhoff(sphere, position, frame, through, delay)
        return self._mirror(
            depth * self._ratio, through, self._delay_per_depth() * depth, position, frame
        )

    def _mirror(
        self,
        equivalent_depth: float,
        coefficient: complex,
        delay: float,
        position: FloatArray,
        frame: FloatArray,
    ) -> ComplexArray:
        """The echo spectrum (before attenuation) of a copy of the plate's face
        ``equivalent_depth`` [m] below it, with one ``coefficient`` and two-way ``delay``
        [s]: by the image form when it fills the beam, else the Kirchhoff sum."""
        assert isinstance(self.front, FinitePlane)  # a pipe's walls come from curved_wall
        equivalent = FinitePlane(
            center=self.front.center
            - self.front.normal
            * equivalent_depth
            * np.sign(float(self.front.normal @ (position - self.front.center))),
            width=self.front.width,
            height=self.front.height,
            azimuth=self.front.azimuth,
            coelevation=self.front.coelevation,
            name="equivalent back wall",
        )
        plane = self.model.image_plane((equivalent,), position, frame)
        if plane is not None:  # the wall fills the beam: the exact image form
            spectrum, _ = self.model.image_spectrum(plane, coefficient, delay)
            return spectrum
        return self._kirchhoff(equivalent, position, frame, coefficient, delay)

    def _kirchhoff(
        self,
        mirror: FinitePlane | Sphere,
        position: FloatArray,
        frame: FloatArray,
        coefficient: complex,
        delay: float,
    ) -> ComplexArray:
        """The wave model's Kirchhoff sum over ``mirror`` with one coefficient and one
        two-way ``delay`` [s] for every sample."""
        points, unit_m, area = self.model.surface_samples((mirror,), position, frame)
        weights = np.full(area.shape, coefficient, dtype=np.complex128)
        spectrum, _ = self.model.spectrum(points, unit_m, area, weights, np.full(area.shape, delay))
        return spectrum

    @cached_property
    def _flaw_samples(self) -> dict[str, SurfaceSamples]:
        assert isinstance(self.front, FinitePlane)  # flaws are refused inside a shell
        out = {}
        for f in self.interior.flaws:
            c_l = self._flaw_column(f).layers[-1].material.longitudinal_speed
            spacing = c_l / self.model.pulse.center_frequency / _SOLID_SAMPLES_PER_WAVELENGTH
            out[f.name] = f.surface_samples(spacing, self.front.normal)
        return out

    def _flaw_column(self, flaw: Flaw) -> _Column:
        """The layers above ``flaw`` and the one that holds it (the last; the plate's one
        layer without layers), its top [m] below the face."""
        assert isinstance(self.front, FinitePlane)
        layers = self.interior.layers or (Layer(self.material, self.interior.thickness),)
        centre = float((self.front.center - flaw.position) @ self.front.normal)
        tops = self.interior.interfaces[:-1]
        j = int(np.searchsorted(tops, centre, side="right"))  # 1-based layer number
        return _Column(layers[:j], float(tops[j - 1]))

    def _flaw(
        self, flaw: Flaw, position: FloatArray, frame: FloatArray, front: _Front
    ) -> FloatArray:
        """A void's echo: Kirchhoff over its lit side, fields at the equivalent points
        (through the layers above it, each at its own equivalent depth)."""
        column = self._flaw_column(flaw)
        host = column.layers[-1].material
        c_w = self.model.sound_speed
        ratio = host.longitudinal_speed / c_w
        above = column.layers[:-1]
        eq_top = sum(layer.thickness * layer.material.longitudinal_speed / c_w for layer in above)
        delay_top = sum(
            2.0
            * layer.thickness
            * (1.0 / layer.material.longitudinal_speed - layer.material.longitudinal_speed / c_w**2)
            for layer in above
        )
        samples = self._flaw_samples[flaw.name]
        basis = self._basis(frame)
        points = basis @ (samples.points - position[:, None])
        outward = basis @ samples.normals
        lit = (front.normal @ outward) > 0.0
        points, outward, area = points[:, lit], outward[:, lit], samples.areas[lit]
        depth = (front.point - points.T) @ front.normal  # (n,) [m] below the face
        in_host = depth - column.top
        points_eq = points - np.outer(front.normal, eq_top + in_host * ratio - depth)
        # m: the normal pointing away from the probe (into the void); its component along
        # the depth direction carries k_L/k_w = c_w/c_L (see the module doc)
        m = -outward
        m_depth = -(front.normal @ m)  # component along −n_f (into the part)
        m_eff = m + np.outer(front.normal, m_depth * (1.0 - 1.0 / ratio))
        through = self._through_layers(column, front)
        coefficient = np.full(area.shape, -through * ratio, dtype=np.complex128)  # R = −1
        delays = delay_top + 2.0 * in_host * (1.0 / host.longitudinal_speed - ratio / c_w)
        spectrum, _ = self.model.spectrum(points_eq, m_eff, area, coefficient, delays)
        centre_depth = float((front.point - basis @ (flaw.position - position)) @ front.normal)
        f = self.model.frequencies
        loss = 2.0 * (centre_depth - column.top) * np.asarray(host.attenuation.alpha(f))
        for layer in above:
            loss += 2.0 * layer.thickness * np.asarray(layer.material.attenuation.alpha(f))
        spectrum = spectrum * np.exp(-loss) * self.model.attenuation_factor(2.0 * front.water_path)
        return self.model.samples(spectrum)

    def _through_layers(self, column: _Column, front: _Front) -> complex:
        """Π T_down · Π T_up through the front face and every interface above the host
        layer, at the beam axis's angle (0 beyond a critical angle)."""
        medium = self._medium_at_model_speed
        sin_w = math.sin(math.radians(self._axis_angles(front)[0]))
        media = [medium, *(layer.material for layer in column.layers)]
        sines = [sin_w * m.longitudinal_speed / self.model.sound_speed for m in media]
        if any(s >= 1.0 for s in sines):
            return 0.0j
        through = 1.0 + 0.0j
        for i in range(len(media) - 1):
            through *= pp_coefficients(sines[i], media[i], media[i + 1])[1]
            through *= pp_coefficients(sines[i + 1], media[i + 1], media[i])[1]
        return through


@dataclass(frozen=True)
class _Column:
    """The layers from the face down to a flaw's (its host, last) and the host's top [m]."""

    layers: tuple[Layer, ...]
    top: float
