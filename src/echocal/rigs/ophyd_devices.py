"""ophyd devices for echocal's simulator, so Bluesky plans run with no hardware
(``bluesky`` extra: bluesky, ophyd).

* :func:`probe_positioner` — a five-axis probe positioner: ``x``, ``y``, ``z`` [m],
  ``azimuth``, ``coelevation`` [deg], each an :class:`ophyd.SoftPositioner` with the
  setup's limits (a move outside them is refused by ophyd, before anything moves);
* :class:`AScanDetector` — ``trigger()`` measures the simulator (or any
  :class:`~echocal.measurement.MeasurementSource`) at the positioner's pose; it reads
  ``samples`` (the A-scan [a.u.]), ``fs`` [Hz] and ``start_time`` [s].

:func:`simulated_devices` builds both for a :class:`~echocal.measurement.VirtualSetup`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

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


class AScanDetector(Device):
    """An ophyd detector whose ``trigger()`` measures ``source`` at ``positioner``'s pose.

    Reads ``<name>_samples`` (shape (n_samples,)), ``<name>_fs`` [Hz] and
    ``<name>_start_time`` [s].  ``gimbal``: the positioner's angles are a gimbal's (the
    probe's roll about its axis is that of :meth:`~echocal.geometry.Pose.from_tilt`),
    as for calibrations in the ``tilt`` parameterization.
    """

    samples = Component(Signal, value=np.zeros(1), kind="normal")
    fs = Component(Signal, value=0.0, kind="normal")
    start_time = Component(Signal, value=0.0, kind="normal")

    def __init__(
        self,
        prefix: str = "",
        *,
        source: MeasurementSource,
        positioner: Device,
        gimbal: bool = False,
        name: str = "ascan",
        **kwargs: Any,
    ) -> None:
        super().__init__(prefix, name=name, **kwargs)
        self.source = source
        self.positioner = positioner
        self.gimbal = bool(gimbal)
        self.pulse = getattr(source, "pulse", None)
        """The transmitted pulse, when the source knows it (the simulator does)."""
        self.n_measurements = 0
        """A-scans measured so far."""

    def pose(self) -> Pose:
        """The positioner's pose (a gimbal's roll when ``gimbal``)."""
        x, y, z, az, coel = (float(getattr(self.positioner, a).position) for a in AXES)
        return Pose(x, y, z, az, coel, gimbal=self.gimbal)

    def trigger(self) -> DeviceStatus:
        """Measure one A-scan at the positioner's pose (done when it returns)."""
        scan = self.source.measure(self.pose())
        self.n_measurements += 1
        self.samples.put(np.asarray(scan.samples, dtype=np.float64))
        self.fs.put(float(scan.fs))
        self.start_time.put(float(scan.start_time))
        status = DeviceStatus(self)
        status.set_finished()
        return status


def simulated_devices(
    source: MeasurementSource, *, gimbal: bool = True, start: Pose | None = None
) -> tuple[Device, AScanDetector]:
    """(positioner, detector) ophyd devices for a simulator (any measurement source):
    the positioner within ``source.limits``, named ``probe``; the detector ``ascan``."""
    positioner = probe_positioner(source.limits, name="probe", start=start)
    detector = AScanDetector(source=source, positioner=positioner, gimbal=gimbal)
    return positioner, detector
