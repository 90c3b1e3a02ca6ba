"""``VirtualSetup``: the ray-traced simulator as a measurement source.

Data flows one way (docs/architecture.md)::

    pose → transducer rays → closest hits → echoes (a·β, τ) → A-scan (eq. 28) → receiver

The receiver's noise belongs to the instrument: its σ is fixed once, from the
SNR of the noiseless reference echo at ``reference_position`` with the probe
normal to the surface below it, and then applies to every measurement — so
off-optimum orientations really have a lower SNR (thesis §12.2.1.3; docs/physics.md,
"The thesis's errata").

The simulator also knows the truth — the orientation of maximum echo at a
position (:meth:`VirtualSetup.true_optimum`) — but keeps it apart from
:meth:`~VirtualSetup.measure`, so that an algorithm driven through the
:class:`~echocal.measurement.MeasurementSource` interface cannot peek.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._rng import RngLike, as_generator
from echocal._validate import finite_array, in_range, lookup, one_of, positive_float
from echocal.ascan import AScan
from echocal.bench import Bench, GrainField
from echocal.bench.session import BenchSession
from echocal.constants import SOUND_SPEED_WATER
from echocal.echo import (
    WAVE_MODEL,
    RayEchoes,
    _echo_arrays_unchecked,
    _reflection_model,
    check_pose_arrays,
    echo_model_names,
    ray_echoes,
)
from echocal.errors import EchocalValueError, GeometryError
from echocal.geometry import (
    PARAMETERIZATIONS,
    Pose,
    convert_angles,
    pose_from_angles,
    poses_to_arrays,
    tilt_frame,
)
from echocal.materials import WATER, Material
from echocal.measurement.base import BaseSource
from echocal.measurement.limits import PositionerLimits
from echocal.measurement.receiver_settings import (
    MAX_SIMULATED_SAMPLES,
    ReceiverSettings,
    _raise_malloc_threshold,
    check_sample_count,
)
from echocal.measurement.truth import EQUAL_OPTIMUM_RATIO, pose_arrays, search_optima
from echocal.signal import (
    SYNTHESIS_METHODS,
    Pulse,
    Receiver,
    RecordingWindow,
    get_metric,
    noise_sigma_for_snr,
)
from echocal.signal.gates import TimeGate, gated_metric, gates_by_name
from echocal.signal.synthesis import _synthesize_unchecked
from echocal.specimen import Cylinder, FinitePlane, Specimen, Sphere
from echocal.specimen.casting import _as_shapes
from echocal.specimen.interior import INTERIOR_SHAPES, Interior
from echocal.specimen.normals import normal_incidence_directions, perpendicular_start
from echocal.transducer import Transducer

__all__ = ["MAX_SIMULATED_SAMPLES", "ReceiverSettings", "VirtualSetup", "check_sample_count"]

FloatArray = NDArray[np.float64]

_BATCH_ELEMENTS = 16384
"""Poses are simulated in chunks of about this many rays (and samples): the temporaries of
ray tracing and synthesis then stay in the CPU's L2 cache, so a batch costs no more per pose
than a single pose (measured on 64² rays × 4096 samples: in one piece, 100 poses cost
about twice as much per pose as chunks of 4)."""

_METRIC_ELEMENTS = 262144
"""Samples per metric call in :meth:`VirtualSetup.metric_values` (64 A-scans of 4096)."""


def _check_materials(medium: Any, material: Any) -> None:
    """The medium must be a fluid :class:`Material`; the part's a Material or None."""
    if not isinstance(medium, Material):
        raise EchocalValueError(f"medium must be a Material; got {type(medium).__name__}")
    if not medium.is_fluid:
        raise EchocalValueError(
            f"medium: {medium.name!r} has a shear speed ({medium.shear_speed:g} m/s); "
            "the coupling medium must be a fluid"
        )
    if material is not None and not isinstance(material, Material):
        raise EchocalValueError(
            f"material must be a Material or None; got {type(material).__name__}"
        )


@dataclass(frozen=True, eq=False, kw_only=True)
class VirtualSetup(BaseSource):
    """The simulator: specimen + transducer + pulse + recording window + receiver.

    Parameters
    ----------
    specimen : the part under test.
    transducer : the probe (pinhole model).
    pulse : transmitted pulse w(t).
    window : the receiver's recording window (fs [Hz], start [s], n_samples).
    receiver : noise, ADC and saturation settings.
    reference_position : [m] where the reference echo for the SNR is taken, shape (3,).
    sound_speed : [m/s] c₀ of the medium.
    reflection : echo model: ``wave`` (diffraction theory, :mod:`echocal.wave`; circular
        probes) or the thesis's ray models ``lambertian`` and ``specular``.
    wave_spacing : [m] the wave model's surface-sample spacing (None: its default).
    synthesis : A-scan synthesis method, ``fast`` (default) or ``direct`` (reference).
    limits : the virtual positioner's reachable poses.
    rng : seed or Generator for the receiver noise (reproducible runs).
    name : label for logs and reports.
    medium : the coupling fluid (density, attenuation; water at 20 °C by default); its
        ``longitudinal_speed`` is set to ``sound_speed``, the one c₀ of the simulation.
    material : the specimen's material; None: a perfect reflector (the thesis).  The
        thesis's ray models do not use either.
    interior : the plate's thickness and flaws (:mod:`echocal.specimen.interior`): its
        back-wall and flaw echoes join the front wall's.  Needs the wave model, a solid
        ``material`` and a specimen of one plane (the front face).  None: no interior.
    gates : the setup's own named gates (:class:`~echocal.signal.gates.TimeGate`), which
        ``--gate NAME`` selects beside ``front-wall`` and ``back-wall``.
    bench : the real bench (:class:`~echocal.bench.Bench`: squint, pivot offset,
        positioner, coloured and grain noise, drift, and the time each measurement
        costs), or None (the ideal bench, as is an ideal :class:`~echocal.bench.Bench`).
    """

    specimen: Specimen
    transducer: Transducer
    pulse: Pulse
    window: RecordingWindow
    receiver: ReceiverSettings = field(default_factory=ReceiverSettings)
    reference_position: ArrayLike = (0.0, 0.0, 0.02)
    sound_speed: float = SOUND_SPEED_WATER
    medium: Material = WATER
    material: Material | None = None
    interior: Interior | None = None
    reflection: str = "lambertian"
    synthesis: str = "fast"
    wave_spacing: float | None = None
    limits: PositionerLimits = field(default_factory=PositionerLimits)
    gates: tuple[TimeGate, ...] = ()
    rng: RngLike = None
    name: str = "virtual setup"
    bench: Bench | None = None
    # set by __post_init__, never by the caller
    _generator: np.random.Generator = field(init=False, repr=False)
    _closed: bool = field(init=False, repr=False)
    _truth_cache: dict[tuple[Any, ...], tuple[FloatArray, FloatArray]] = field(
        init=False, repr=False
    )
    _closed_top: float = field(init=False, repr=False)
    _bench_session: BenchSession | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        # Frozen: the cached reference echo, noise level and truth can never go stale.
        # (dataclasses.replace makes a new setup with fresh caches.)
        reference = finite_array("reference_position", self.reference_position, shape_tail=(3,))
        object.__setattr__(self, "reference_position", reference.reshape(3))
        object.__setattr__(self, "sound_speed", positive_float("sound_speed", self.sound_speed))
        lookup("echo model", self.reflection, dict.fromkeys(echo_model_names()))
        if self.wave_spacing is not None:
            object.__setattr__(
                self, "wave_spacing", positive_float("echo.spacing", self.wave_spacing)
            )
        if (
            self.reflection == WAVE_MODEL
            and self.transducer.aperture != "circular"
            and self.transducer.focus is not None
        ):
            raise EchocalValueError(
                "transducer.focus: the wave model's focused probes are circular; set "
                "transducer.aperture = 'circular', or drop the focus for a flat rectangular probe"
            )
        lookup("synthesis method", self.synthesis, dict.fromkeys(SYNTHESIS_METHODS))
        _check_materials(self.medium, self.material)
        object.__setattr__(self, "gates", tuple(gates_by_name(self.gates).values()))
        if self.interior is not None:
            self._check_interior(self.interior)
        if self.medium.longitudinal_speed != self.sound_speed:
            medium = replace(self.medium, longitudinal_speed=self.sound_speed)
            object.__setattr__(self, "medium", medium)
        object.__setattr__(self, "_generator", as_generator(self.rng))
        if self.bench is not None and not isinstance(self.bench, Bench):
            raise EchocalValueError(f"bench must be a Bench or None; got {self.bench!r}")
        if self.bench is not None and self.bench.is_ideal:
            object.__setattr__(self, "bench", None)  # the ideal bench: the plain simulator
        self._start_bench()
        object.__setattr__(self, "_closed", False)
        object.__setattr__(self, "_truth_cache", {})
        # the probe usually sits above the closed shapes: one comparison settles it
        tops = [float(shape.bounds()[1, 2]) for shape in self.specimen if shape.closed]
        object.__setattr__(self, "_closed_top", max(tops, default=-np.inf))
        check_sample_count(self.pulse, self.window)
        self._check_outside(reference[None], what="reference_position")
        _raise_malloc_threshold()

    def _check_interior(self, interior: Interior) -> None:
        """An interior needs the wave model, a solid material and a plate (one plane)."""
        if not isinstance(interior, Interior):
            raise EchocalValueError(
                f"interior must be an Interior or None; got {type(interior).__name__}"
            )
        if self.reflection != WAVE_MODEL:
            raise EchocalValueError(
                "specimen.thickness: echoes from inside the part need the wave model; "
                'set [echo] reflection = "wave"'
            )
        if self.material is None or self.material.is_fluid:
            raise EchocalValueError(
                "specimen.thickness: an interior needs a solid specimen.material"
            )
        front = self.specimen[0] if len(self.specimen) == 1 else None
        if not isinstance(front, (FinitePlane, Sphere, Cylinder)):
            raise GeometryError(f"specimen.thickness: {INTERIOR_SHAPES}")
        interior.check_inside(front)
        if isinstance(front, (Sphere, Cylinder)):
            from echocal.wave.shell import check_curved_wall  # lazy: echocal.wave loads numba

            ratio = self.material.longitudinal_speed / self.sound_speed
            face, spherical = self.transducer.face_radius, isinstance(front, Sphere)
            check_curved_wall(front.radius, interior, face, ratio, spherical)

    @property
    def thickness(self) -> float | None:
        """[m] the plate's thickness, or None when the part has no interior."""
        return None if self.interior is None else self.interior.thickness

    def _check_outside(
        self, positions: FloatArray, *, poses: Sequence[Pose] | None = None, what: str = "pose"
    ) -> None:
        """Refuse probe positions [m] ``(P, 3)`` inside a closed shape of the specimen."""
        if positions[:, 2].min() >= self._closed_top:
            return
        index = self.specimen.containing(positions)  # a bore's hole is not material
        if not np.any(index >= 0):
            return
        first = int(index[index >= 0].min())  # the first shape any position is inside
        shape = self.specimen[first]
        k = int(np.argmax(index == first))
        x, y, z = (1e3 * v for v in positions[k])
        where = f"({x:g}, {y:g}, {z:g}) mm"
        if poses is not None:
            pose = poses[k]
            where = f"{where}, azimuth {pose.azimuth:g} deg, co-elevation {pose.coelevation:g} deg"
        raise GeometryError(
            f"{what} {where} is inside {shape.kind} {shape.name!r} of specimen "
            f"{self.specimen.name!r}: the probe must be outside the part, in the coupling "
            "medium; move it above the surface"
        )

    # ------------------------------------------------------------------ description
    @property
    def description(self) -> str:  # type: ignore[override]  # derived; other sources store it
        """One line: what is simulated."""
        snr = self.receiver.snr_db
        noise = "noiseless" if snr is None else f"SNR {snr:g} dB"
        return (
            f"{self.name}: {self.specimen.name}, {self.transducer.n_rays} rays, "
            f"{self.pulse.name} {self.pulse.center_frequency / 1e6:g} MHz, "
            f"{self.reflection}, {noise}" + ("" if self.bench is None else ", on a bench")
        )

    # ------------------------------------------------------------------ simulation
    def echoes(self, positions: ArrayLike, frames: ArrayLike) -> RayEchoes:
        """Amplitude and time of flight of every ray, shape ``(n_poses, n_rays)``."""
        return ray_echoes(
            self.transducer,
            self.specimen,
            np.asarray(positions, dtype=np.float64).reshape(-1, 3),
            np.asarray(frames, dtype=np.float64).reshape(-1, 3, 3),
            model="lambertian" if self.reflection == WAVE_MODEL else self.reflection,
            sound_speed=self.sound_speed,
        )

    def ideal_samples(self, positions: ArrayLike, frames: ArrayLike) -> FloatArray:
        """Noiseless A-scans, shape ``(n_poses, n_samples)``, normalized by the ray count.

        Parameters
        ----------
        positions : [m] shape ``(n_poses, 3)``.
        frames : transducer frames ``[x', y', n]``, shape ``(n_poses, 3, 3)``.
        """
        positions, frames = check_pose_arrays(positions, frames)
        self._check_outside(positions, what="position")
        return self._ideal(positions, frames)

    def _ideal(self, positions: FloatArray, frames: FloatArray) -> FloatArray:
        """:meth:`ideal_samples` of checked arrays, in cache-sized chunks of poses."""
        n_poses = positions.shape[0]
        out = np.empty((n_poses, self.window.n_samples))
        step = self._pose_chunk
        for lo in range(0, n_poses, step):
            sl = slice(lo, lo + step)
            out[sl] = self._ideal_chunk(positions[sl], frames[sl])
        return out

    @cached_property
    def wave_model(self):  # -> echocal.wave.WaveEchoModel (imported lazily: it loads numba)
        """The diffraction echo model of this setup (``reflection = "wave"``)."""
        from echocal.wave import PistonProbe, RectangularProbe, WaveEchoModel, curvature_for_focus

        transducer = self.transducer
        probe: PistonProbe | RectangularProbe
        if transducer.aperture == "rectangular":
            probe = RectangularProbe(
                half_width=0.5 * transducer.width, half_height=0.5 * transducer.height
            )
        else:
            radius = 0.5 * transducer.width
            curvature = None
            if transducer.focus is not None:
                curvature = curvature_for_focus(
                    transducer.focus,
                    radius=radius,
                    frequency=self.pulse.center_frequency,
                    sound_speed=self.sound_speed,
                )
            probe = PistonProbe(radius=radius, curvature=curvature)
        return WaveEchoModel(
            probe=probe,
            pulse=self.pulse,
            window=self.window,
            sound_speed=self.sound_speed,
            attenuation=self._medium_attenuation,
            reflection=self._reflection_coefficient,
            spacing=self.wave_spacing,
        )

    @property
    def _medium_attenuation(self) -> Callable[[FloatArray], FloatArray] | None:
        """α(f) [Np/m] of the coupling medium, or None when it is lossless."""
        attenuation = self.medium.attenuation
        return None if attenuation.alpha0 == 0.0 else attenuation.alpha

    @property
    def _reflection_coefficient(self) -> Callable[[FloatArray], NDArray[np.complex128]] | None:
        """R(θ [deg]) of the specimen's material against the medium, or None (a perfect
        reflector, the thesis's assumption)."""
        material = self.material
        if material is None:
            return None
        from echocal.coefficients import reflection_fluid_solid

        medium = self.medium
        return lambda theta: reflection_fluid_solid(theta, medium, material)

    @cached_property
    def interior_echoes(self):  # -> echocal.wave.interior.InteriorEchoes | None (lazy: numba)
        """The labelled echo train of a plate with an interior (None without one)."""
        if self.interior is None:
            return None
        from echocal.wave.interior import InteriorEchoes

        assert self.material is not None
        return InteriorEchoes(
            model=self.wave_model,
            front=self.specimen[0],
            interior=self.interior,
            medium=self.medium,
            material=self.material,
        )

    def labelled_echoes(self, pose: Pose) -> dict[str, FloatArray]:
        """Each echo's noiseless samples ``(n_samples,)`` at ``pose``, by label:
        ``front-wall``, ``back-wall``, ``back-wall-2``, …, then the flaws' names.  Without
        an interior the one echo is the ``front-wall``'s (the whole noiseless A-scan)."""
        positions, frames = poses_to_arrays([pose])
        self._check_outside(positions, poses=[pose])
        if self.interior_echoes is None:
            return {"front-wall": self._ideal(positions, frames)[0]}
        return self.interior_echoes.echoes(positions[0], frames[0])

    def _ideal_chunk(self, positions: FloatArray, frames: FloatArray) -> FloatArray:
        if self.interior_echoes is not None:
            return self.interior_echoes.ascans(positions, frames)
        if self.reflection == WAVE_MODEL:
            return self.wave_model.ascans(_as_shapes(self.specimen), positions, frames)
        # checked float64 pose arrays, model and c₀ validated in __post_init__: no re-checks
        amplitude, tof = _echo_arrays_unchecked(
            self.transducer,
            _as_shapes(self.specimen),
            positions,
            frames,
            _reflection_model(self.reflection),
            self.sound_speed,
        )
        # the ray stage gives finite amplitudes and finite-or-inf tofs of one shape: no re-check
        return _synthesize_unchecked(amplitude, tof, self.pulse, self.window, method=self.synthesis)

    @property
    def _pose_chunk(self) -> int:
        """Poses simulated at once (see ``_BATCH_ELEMENTS``)."""
        return max(1, _BATCH_ELEMENTS // max(self.transducer.n_rays, self.window.n_samples))

    def reseed(self, rng: RngLike) -> None:
        """Restart the receiver noise from ``rng`` (seed or Generator): the A-scans that
        follow are those of a setup built with ``rng=rng`` (the bench, if any, restarts
        too: positioner at rest, bench time 0)."""
        object.__setattr__(self, "_generator", as_generator(rng))
        self._start_bench()

    def _start_bench(self) -> None:
        """A fresh bench session (None without a bench); its random stream is spawned
        from the receiver's generator without drawing from it."""
        session = None
        if self.bench is not None:
            seed_seq = getattr(self._generator.bit_generator, "seed_seq", None)
            child = seed_seq.spawn(1)[0] if seed_seq is not None else None
            rng = np.random.default_rng(
                child if child is not None else self._generator.integers(2**63)
            )
            session = BenchSession(self.bench, rng)
        object.__setattr__(self, "_bench_session", session)

    @property
    def bench_time(self) -> float:
        """[s] the bench time spent so far (0 on the ideal bench)."""
        return 0.0 if self._bench_session is None else self._bench_session.clock

    def simulate(
        self, poses: Sequence[Pose], *, noise: bool = True, rng: RngLike = None
    ) -> FloatArray:
        """A-scans of a batch of poses as one array ``(n_poses, n_samples)`` (no limit check),
        on the ideal bench (a :attr:`bench` applies in :meth:`measure_many`).

        ``noise=False`` gives the ideal A-scans.  Noise draws from ``rng`` if given,
        else from the setup's own generator.
        """
        poses = list(poses)
        positions, frames = poses_to_arrays(poses)  # Pose values are already finite
        self._check_outside(positions, poses=poses)
        samples = self._ideal(positions, frames)
        if noise:
            generator = self._generator if rng is None else as_generator(rng)
            samples = self._receiver._receive_unchecked(samples, generator)
        return samples

    @cached_property
    def reference_samples(self) -> FloatArray:
        """The noiseless reference A-scan: the strongest echo at ``reference_position``
        (normal incidence on the surface; see :meth:`normal_incidence_directions`)."""
        reference = np.asarray(self.reference_position, dtype=np.float64)  # (3,) [m]
        x, y, _ = reference
        normal = self.specimen.surface_normal_below(x, y)
        if not np.all(np.isfinite(normal)):
            raise GeometryError(
                f"reference_position ({x:g}, {y:g}) m is not above the specimen; "
                "move it over the part"
            )
        # the reference echo is the best echo at the reference position: the strongest of
        # the directions of normal incidence (the metric's optimum up to its flat top)
        candidates = self.normal_incidence_directions(reference)
        frames = tilt_frame(candidates[:, 0], candidates[:, 1])
        positions = np.broadcast_to(reference, (len(candidates), 3))
        scans = self.ideal_samples(positions, frames)
        samples = scans[int(np.argmax(np.max(np.abs(scans), axis=1)))]
        if not np.any(samples):
            raise GeometryError(
                "the reference echo is silent: no ray returns within the recording window "
                f"[{self.window.start:g}, {self.window.end:g}] s from reference_position"
            )
        return samples

    @cached_property
    def noise_sigma(self) -> float:
        """[a.u.] the receiver's noise standard deviation (0 when noiseless)."""
        if self.receiver.snr_db is None:
            return 0.0
        return float(
            noise_sigma_for_snr(
                self.reference_samples, self.receiver.snr_db, self.window, self.pulse
            )
        )

    @cached_property
    def _digitizer(self) -> Receiver:
        """The receiver's saturation and ADC without its noise (the bench adds its own)."""
        return replace(self._receiver, noise_sigma=0.0)

    @cached_property
    def grain_field(self) -> GrainField | None:
        """The part's grains (:mod:`echocal.bench.grain`), None without grain noise."""
        grain = None if self.bench is None else self.bench.grain
        if grain is None:
            return None
        from echocal.transducer import PistonDirectivity

        reference = np.asarray(self.reference_position, dtype=np.float64)
        hits = self.specimen.surface_below(reference[0], reference[1])
        part_speed = self.sound_speed if self.material is None else self.material.longitudinal_speed
        transducer = self.transducer
        return GrainField.draw(
            grain,
            surface_point=np.asarray(hits.point, dtype=np.float64).reshape(3),
            surface_normal=np.asarray(hits.normal, dtype=np.float64).reshape(3),
            directivity=PistonDirectivity(
                radius=0.5 * min(transducer.width, transducer.height),
                frequency=self.pulse.center_frequency,
                sound_speed=self.sound_speed,
            ),
            sound_speed=self.sound_speed,
            part_speed=part_speed,
        )

    @cached_property
    def grain_scale(self) -> float:
        """[a.u.] the grain field's scale: its A-scan at the reference pose peaks
        ``level_db`` below (or above) the reference echo's peak."""
        field_ = self.grain_field
        if field_ is None or self.bench is None or self.bench.grain is None:
            return 0.0
        reference = np.asarray(self.reference_position, dtype=np.float64)
        tilts = self.normal_incidence_directions(reference)[:1]
        frame = tilt_frame(tilts[:, 0], tilts[:, 1])
        faces, acoustic = self.bench.probe.place(reference[None], frame)
        grain = field_.ascans(faces, acoustic, self.pulse, self.window)
        peak = float(np.max(np.abs(grain)))
        if peak == 0.0:
            raise GeometryError(
                "bench.grain: no grain echo reaches the recording window from the reference "
                "position; widen the window or move the grains (width, depth)"
            )
        target = 10.0 ** (self.bench.grain.level_db / 20.0) * float(
            np.max(np.abs(self.reference_samples))
        )
        return target / peak

    @cached_property
    def _receiver(self) -> Receiver:
        settings = self.receiver
        full_scale = None
        if settings.full_scale is not None:
            full_scale = settings.full_scale * float(np.max(np.abs(self.reference_samples)))
        return Receiver(
            noise_sigma=self.noise_sigma, adc_bits=settings.adc_bits, full_scale=full_scale
        )

    # ------------------------------------------------------------------ source interface
    def _check_open(self) -> None:
        if self._closed:
            raise EchocalValueError(f"{self.name} is closed; create a new setup to measure")

    def measure(self, pose: Pose) -> AScan:
        """Simulate one noisy A-scan at ``pose`` (must be within :attr:`limits`)."""
        return self.measure_many([pose])[0]

    def measure_many(self, poses: Sequence[Pose]) -> list[AScan]:
        """Simulate several poses in one vectorized batch, in order."""
        self._check_open()
        poses = [self.limits.check(p) for p in poses]
        if not poses:
            return []
        metadata = {"source": "virtual", "setup": self.name, "snr_db": self.receiver.snr_db}
        if self._bench_session is None:
            samples = self.simulate(poses)
            facts: list[dict[str, Any]] = [{}] * len(poses)
        else:
            samples, facts = self._bench_session.measure(self, poses)
        samples.setflags(write=False)  # read-only rows: AScan keeps them without a copy
        return [
            AScan(
                samples=row,
                fs=self.window.fs,
                start_time=self.window.start,
                pose=pose,
                metadata={**metadata, **fact},
            )
            for row, pose, fact in zip(samples, poses, facts, strict=True)
        ]

    def skip_noise(self, n_ascans: int) -> None:
        """Advance the receiver noise past ``n_ascans`` A-scans, as if they were measured.

        A resumed recording calls it for the A-scans already saved: the noise of every later
        A-scan is then exactly that of an uninterrupted recording (the noise of one A-scan is
        ``n_samples`` consecutive standard normal draws, however they were batched).
        """
        if self.bench is not None:
            raise EchocalValueError(
                "a recording on a bench (a [bench] table) cannot be resumed: its positioner "
                "and noise depend on every move before; record it again from the start"
            )
        if not self._receiver.noise_sigma:
            return  # a noiseless receiver draws nothing
        left = int(n_ascans) * self.window.n_samples
        while left > 0:
            block = min(left, 1 << 22)
            self._generator.standard_normal(block)
            left -= block

    def close(self) -> None:
        """Mark the setup closed; later measurements raise."""
        object.__setattr__(self, "_closed", True)

    # ------------------------------------------------------------------ ground truth
    def metric_values(
        self,
        position: ArrayLike,
        a: ArrayLike,
        b: ArrayLike,
        *,
        parameterization: str = "azimuth-coelevation",
        metric: str = "pseudo-energy",
        noise: bool = False,
        rng: RngLike = None,
        gate: TimeGate | None = None,
    ) -> FloatArray:
        """The metric at orientations ``(a, b)`` [deg] (broadcast shapes ``(...)``).

        One batched simulation for all orientations — used for cost maps (thesis
        Figs. 12–24 backgrounds) and for the ground truth.  Noiseless by default.
        ``gate``: the metric inside this gate (:func:`echocal.signal.gates.gated_metric`);
        None: the whole recording.  On a bench the orientations are the positioner's
        (mechanical): the probe's squint turns the beam and its pivot offset moves the
        face (:meth:`~echocal.bench.ProbeMount.place`); the positioner's errors, the
        grains and the bench's receiver are left out (``noise=True`` adds white noise).
        """
        get_metric(metric)  # an unknown name is refused before anything is simulated
        one_of("parameterization", parameterization, PARAMETERIZATIONS)
        a, b = np.broadcast_arrays(finite_array("a", a), finite_array("b", b))
        position = finite_array("position", position, shape_tail=(3,)).reshape(3)
        self._check_outside(position[None], what="position")
        positions, frames = pose_arrays(position, a.ravel(), b.ravel(), parameterization)
        if self.bench is not None and not self.bench.probe.is_ideal:
            positions, frames = self.bench.probe.place(np.array(positions), frames)
            self._check_outside(positions, what="probe face")
        generator = None
        if noise:
            generator = self._generator if rng is None else as_generator(rng)
        out = np.empty(a.size)
        # the metric is cheaper per pose on a larger group (fewer calls), synthesis on less
        step = max(self._pose_chunk, _METRIC_ELEMENTS // self.window.n_samples)
        for lo in range(0, a.size, step):
            sl = slice(lo, lo + step)
            samples = self._ideal(positions[sl], frames[sl])
            if generator is not None:
                samples = self._receiver._receive_unchecked(samples, generator)
            out[sl] = gated_metric(metric, samples, self.window, self.pulse, gate)
        return out.reshape(a.shape)

    def true_optimum(
        self,
        position: ArrayLike,
        *,
        parameterization: str = "azimuth-coelevation",
        metric: str = "pseudo-energy",
        gate: TimeGate | None = None,
    ) -> tuple[float, float]:
        """Orientation (a, b) [deg] of the global maximum of the noiseless ``metric`` at
        ``position`` [m] (inside ``gate`` when one is given: the truth of a gated
        calibration): the first of :meth:`true_optima`.

        Kept apart from :meth:`measure`: an algorithm cannot peek.  On a bench it is the
        positioner's orientation whose beam, after the probe's squint and pivot offset,
        gives the strongest echo (see :meth:`metric_values`).
        """
        optima = self.true_optima(
            position, parameterization=parameterization, metric=metric, gate=gate, ratio=1.0
        )
        return float(optima[0, 0]), float(optima[0, 1])

    def true_optima(
        self,
        position: ArrayLike,
        *,
        parameterization: str = "azimuth-coelevation",
        metric: str = "pseudo-energy",
        gate: TimeGate | None = None,
        ratio: float = EQUAL_OPTIMUM_RATIO,
    ) -> FloatArray:
        """Orientations [deg] ``(k, 2)`` of every maximum of the noiseless ``metric`` at
        ``position`` [m] that reaches ``ratio`` of the global one, best first (``k`` = 1
        unless the optimum is not unique: a 12.7 mm probe over a rod sees two humps of
        nearly equal echo).

        Found by :func:`echocal.measurement.truth.search_optima`: the directions of
        normal incidence on the surface (the analytic optimum for a plane) and rings
        1–3° around them, each distinct hump refined by Nelder–Mead to 1e-5°.
        """
        ratio = in_range("ratio", ratio, 0.0, 1.0)
        position = finite_array("position", position, shape_tail=(3,)).reshape(3)
        key = (*position.round(12), metric, gate)
        if key not in self._truth_cache:
            self._truth_cache[key] = self._search_optima(position, metric, gate)
        tilts, values = self._truth_cache[key]
        keep = tilts[values >= ratio * values[0]]
        a, b = convert_angles(keep[:, 0], keep[:, 1], "tilt", parameterization)
        return np.stack([np.asarray(a, float), np.asarray(b, float)], axis=1)

    def _search_optima(
        self, position: FloatArray, metric: str, gate: TimeGate | None = None
    ) -> tuple[FloatArray, FloatArray]:
        def in_tilts(a: FloatArray, b: FloatArray) -> FloatArray:
            return self.metric_values(
                position, a, b, parameterization="tilt", metric=metric, gate=gate
            )

        candidates = self.normal_incidence_directions(position)
        if self.bench is not None and not self.bench.probe.is_ideal:
            candidates = self.bench.probe.mechanical_tilts(candidates)
        return search_optima(in_tilts, candidates)

    def normal_incidence_directions(self, position: FloatArray, *, limit: int = 6) -> FloatArray:
        """Tilts [deg] ``(n, 2)`` of the beam from ``position`` [m] at normal incidence on
        the surface, best first: :func:`echocal.specimen.normals.normal_incidence_directions`."""
        return normal_incidence_directions(self.specimen, position, limit=limit)

    def perpendicular_start(self, position: FloatArray) -> FloatArray:
        """Tilts [deg] ``(2,)`` of the beam from ``position`` [m] towards the nearest surface
        point within ±60°: :func:`echocal.specimen.normals.perpendicular_start`."""
        return perpendicular_start(self.specimen, position)

    def true_pose(self, position: ArrayLike, **kwargs: Any) -> Pose:
        """The pose of maximum echo at ``position`` (see :meth:`true_optimum`)."""
        az, coel = self.true_optimum(position, **kwargs)
        return pose_from_angles(position, az, coel, "azimuth-coelevation")
