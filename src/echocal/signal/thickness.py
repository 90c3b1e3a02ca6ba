"""Wall thickness from the front-to-back time of flight, as an ultrasonic thickness gauge
measures it (mode 2: interface echo to first back-wall echo).

    T = c_L · (t_back − t_front) / 2

* ``t_front`` — the front-wall (interface) echo: the matched-envelope peak inside the
  ``front-wall`` gate (:func:`echocal.signal.gates.named_gate`), which follows the first
  echo reaching half the A-scan's peak;
* ``t_back`` — the back-wall echo: the matched-envelope peak inside ``back_gate`` (e.g.
  the setup's ``back-wall`` gate, which needs the nominal thickness), or without one the
  strongest echo after the front-wall gate — on a plate the first back-wall echo, since
  each multiple is weaker by R² and the losses of a longer path.  A reflector inside the
  part that echoes more strongly than the back wall is read instead, as on a gauge
  without gates.

Both times are refined to a fraction of a sample (Gaussian peak interpolation), and both
echoes pass the same matched filter, so its group delay cancels.  At oblique incidence
the difference is the refracted path's, 2T/(c_L cos θ_t): calibrate the orientation
first, as :func:`echocal.scanning.scan_surface` does.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import positive_float
from echocal.signal.gates import TimeGate, named_gate
from echocal.signal.processing import _peak_position, matched_envelope
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = ["echo_times", "wall_thickness"]

_F64 = NDArray[np.float64]


def _peak_time(env: _F64, inside: NDArray[np.bool_], window: RecordingWindow) -> _F64:
    """[s] the interpolated peak of ``env`` within ``inside`` per A-scan; NaN if empty."""
    masked = np.where(inside, env, 0.0)
    t = window.start + _peak_position(masked) / window.fs
    return np.where(np.any(masked > 0.0, axis=-1), t, np.nan)


def echo_times(
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    back_gate: TimeGate | None = None,
) -> tuple[_F64, _F64]:
    """[s] (t_front, t_back) of each A-scan, each shape ``(...,)`` (NaN where not found).

    Parameters
    ----------
    samples : A-scans, shape ``(..., n_samples)``.
    back_gate : where the back-wall echo is looked for; None: anywhere after the
        front-wall gate.
    """
    x = np.asarray(samples, dtype=np.float64)
    env = matched_envelope(x, pulse, window.fs)
    front = named_gate("front-wall", pulse=pulse)
    t_front = _peak_time(env, front.masks(x, window), window)
    if back_gate is None:
        end = front.starts(x, window) + front.width
        after = window.times > end[..., None]
    else:
        after = back_gate.masks(x, window)
    return t_front, _peak_time(env, after, window)


def wall_thickness(
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    longitudinal_speed: float,
    back_gate: TimeGate | None = None,
) -> _F64:
    """[m] wall thickness c_L·(t_back − t_front)/2 of each A-scan, shape ``(...,)``.

    Parameters
    ----------
    longitudinal_speed : [m/s] the part's c_L.
    back_gate : see :func:`echo_times`.
    """
    c = positive_float("longitudinal_speed", longitudinal_speed)
    t_front, t_back = echo_times(samples, window, pulse, back_gate)
    return c * (t_back - t_front) / 2.0
