"""ophyd devices for echocal's simulator, so Bluesky plans run with no hardware
(``bluesky`` extra: bluesky, ophyd).

* :func:`probe_positioner` — a five-axis probe positioner: ``x``, ``y``, ``z`` [m],
  ``azimuth``, ``coelevation`` [deg], each an :class:`ophyd.SoftPositioner` with the
  setup's limits (a move outside them is refused by ophyd, before anything moves);
* :class:`AScanDetector` — ``trigger()`` measures the simulator (or any
  :class:`~echocal.measurement.MeasurementSource`) at the positioner's pose; it reads
  ``samples`` (the A-scan [a.u.]), ``peak`` [a.u.] (hinted, for live plots), ``fs`` [Hz],
  ``start_time`` [s] and ``seq`` (the measurement's index).

:func:`simulated_devices` builds both for a :class:`~echocal.measurement.VirtualSetup`,
the positioner at the setup's reference pose (straight down over ``reference_position``,
where the echo is).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from echocal.ascan import AScan
from echocal.geometry import Pose
from echocal.measurement.base import MeasurementSource
from echocal.measurement.limits import PositionerLimits

try:
    from ophyd import Component, Device, Signal, SoftPositioner
    from ophyd.device import create_device_from_components
    from ophyd.status import DeviceStatus
except ImportError:  # without the bluesky extra
    raise ImportError(
        "echocal's Bluesky devices need ophyd: pip install 'echocal[bluesky]' (bluesky, ophyd)"
    ) from None

__all__ = ["AXES", "AScanDetector", "probe_positioner", "simulated_devices"]

AXES = ("x", "y", "z", "azimuth", "coelevation")
"""The positioner's axes, in :class:`~echocal.geometry.Pose` order."""


def probe_positioner(
    limits: PositionerLimits, *, name: str = "probe", start: Pose | None = None
) -> Device:
    """A five-axis ophyd device of :class:`ophyd.SoftPositioner` axes within ``limits``.

    ``start`` (default: the origin clipped to the limits) is where each axis begins.
    """
    start = limits.clip(start or Pose(0.0, 0.0, 0.0))
    components = {
        axis: Component(
            SoftPositioner,
            limits=tuple(getattr(limits, axis)),
            init_pos=float(getattr(start, axis)),
            egu="m" if axis in ("x", "y", "z") else "deg",
            kind="hinted",
        )
        for axis in AXES
    }
    cls = create_device_from_components(
        "EchocalProbePositioner",
        docstring="Five-axis probe positioner: x, y, z [m], azimuth, coelevation [deg].",
        **components,
    )
    return cls(name=name)


class UnitSignal(Signal):
    """An ophyd :class:`~ophyd.Signal` whose ``describe()`` gives its ``units``."""

    def __init__(self, *args: Any, units: str = "", **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.units = units

    def describe(self) -> dict[str, dict[str, Any]]:
        desc = super().describe()
        if self.units:
            desc[self.name]["units"] = self.units
        return desc


class AScanDetector(Device):
    """An ophyd detector whose ``trigger()`` measures ``source`` at ``positioner``'s pose.

    Reads ``<name>_samples`` [a.u.] (shape (n_samples,)), ``<name>_peak`` [a.u.] (the
    largest ``|sample|``: the hinted field a live plot shows), ``<name>_fs`` [Hz],
    ``<name>_start_time`` [s] and ``<name>_seq`` (the measurement's index, set by the
    plan before each trigger; 0 when unset).  ``gimbal``: the positioner's angles are a
    gimbal's (the probe's roll about its axis is that of
    :meth:`~echocal.geometry.Pose.from_tilt`), as for calibrations in the ``tilt``
    parameterization.

    On a simulator (a source with ``simulate``, e.g. :class:`~echocal.measurement.VirtualSetup`)
    with ``seed`` given, the receiver noise of measurement ``seq`` is drawn from the seed
    sequence ``(seed, seq)``: a measurement retaken after a pause (Bluesky rewinds to the
    last checkpoint and triggers again) is the same A-scan, so a resumed run equals an
    uninterrupted one.  ``trigger()`` never raises: a failed measurement finishes its
    status with the exception (``status.set_exception``), as ophyd devices do.
    """

    samples = Component(UnitSignal, value=np.zeros(1), units="a.u.", kind="normal")
    peak = Component(UnitSignal, value=0.0, units="a.u.", kind="hinted")
    fs = Component(UnitSignal, value=0.0, units="Hz", kind="normal")
    start_time = Component(UnitSignal, value=0.0, units="s", kind="normal")
    seq = Component(Signal, value=0, kind="normal")

    def __init__(
        self,
        prefix: str = "",
        *,
        source: MeasurementSource,
        positioner: Device,
        gimbal: bool = False,
        seed: int | None = None,
        name: str = "ascan",
        **kwargs: Any,
    ) -> None:
        super().__init__(prefix, name=name, **kwargs)
        self.source = source
        self.positioner = positioner
        self.gimbal = bool(gimbal)
        self.seed = None if seed is None else int(seed)
        self.pulse = getattr(source, "pulse", None)
        """The transmitted pulse, when the source knows it (the simulator does)."""
        self.n_measurements = 0
        """A-scans measured so far (a retake after a pause counts again)."""

    def pose(self) -> Pose:
        """The positioner's pose (a gimbal's roll when ``gimbal``)."""
        x, y, z, az, coel = (float(getattr(self.positioner, a).position) for a in AXES)
        return Pose(x, y, z, az, coel, gimbal=self.gimbal)

    def _measure(self, pose: Pose) -> AScan:
        """One A-scan at ``pose``: the noise of measurement ``seq`` when seeded."""
        seq = int(self.seq.get())
        simulate = getattr(self.source, "simulate", None)
        if self.seed is None or seq <= 0 or simulate is None:
            return self.source.measure(pose)
        pose = self.source.limits.check(pose)
        rng = np.random.default_rng([self.seed, seq])
        window = self.source.window  # type: ignore[attr-defined]
        samples = simulate([pose], rng=rng)[0]
        return AScan(samples=samples, fs=window.fs, start_time=window.start, pose=pose)

    def trigger(self) -> DeviceStatus:
        """Measure one A-scan at the positioner's pose; the status finishes when it is
        read, or with the measurement's exception."""
        status = DeviceStatus(self)
        try:
            scan = self._measure(self.pose())
        except Exception as exc:  # the status carries it to the RunEngine
            status.set_exception(exc)
            return status
        samples = np.asarray(scan.samples, dtype=np.float64)
        self.n_measurements += 1
        self.samples.put(samples)
        self.peak.put(float(np.max(np.abs(samples))) if samples.size else 0.0)
        self.fs.put(float(scan.fs))
        self.start_time.put(float(scan.start_time))
        status.set_finished()
        return status


def simulated_devices(
    source: MeasurementSource,
    *,
    gimbal: bool = True,
    start: Pose | None = None,
    seed: int | None = 0,
) -> tuple[Device, AScanDetector]:
    """(positioner, detector) ophyd devices for a simulator (any measurement source):
    the positioner within ``source.limits``, named ``probe``, at ``start`` (default the
    reference pose: straight down over ``source.reference_position`` when the source has
    one, else the origin); the detector ``ascan``, with ``seed`` for its per-measurement
    noise (see :class:`AScanDetector`)."""
    if start is None:
        reference = getattr(source, "reference_position", None)
        if reference is not None:
            x, y, z = (float(v) for v in np.asarray(reference, dtype=np.float64))
            start = Pose(x, y, z, 0.0, 0.0, gimbal=gimbal)
    positioner = probe_positioner(source.limits, name="probe", start=start)
    detector = AScanDetector(source=source, positioner=positioner, gimbal=gimbal, seed=seed)
    return positioner, detector
