"""Layer thicknesses under every trace of a position scan, from the interface echoes.

With the speeds c₁ … c_L of the L layers given, the echo times t₀ (front wall) … t_L
(the back of layer L) of each trace give

    T_k = c_k · (t_k − t_{k−1}) / 2,

as a thickness gauge does in mode 2 (interface echo to back-wall echo).  Each echo time is
the sub-sample peak of the matched envelope (the template: the scan's own front-wall echo,
:func:`~echocal.positionscan.tof.stacked_template`) inside that interface's gate; the
front wall's default gate is the interface-triggered ``front-wall`` gate, and with one
layer the back wall's default is the strongest echo after it — a plate's first back-wall
echo (each multiple is weaker).  Both echoes pass the same filter, so its delay cancels.
At oblique incidence the difference is the refracted path's: scan at normal incidence.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal._validate import positive_float
from echocal.errors import EchocalValueError
from echocal.positionscan.dataset import PositionScan
from echocal.positionscan.tof import (
    echo_template,
    front_wall_tof,
    gated_peak_time,
    stacked_template,
)
from echocal.signal.gates import TimeGate, named_gate
from echocal.signal.processing import matched_envelope

__all__ = ["LayerMap", "layer_thickness"]

FloatArray = NDArray[np.float64]


def _stats(values: FloatArray) -> dict[str, float | int | None]:
    v = values[np.isfinite(values)]
    if not v.size:
        return {"traces": 0, "mean": None, "std": None, "median": None, "min": None, "max": None}
    return {
        "traces": int(v.size),
        "mean": float(v.mean()),
        "std": float(v.std(ddof=1)) if v.size > 1 else 0.0,
        "median": float(np.median(v)),
        "min": float(v.min()),
        "max": float(v.max()),
    }


@dataclass(frozen=True)
class LayerMap:
    """Thickness of each layer under each trace (plain data).

    Attributes
    ----------
    thickness : [m] shape ``(n_layers, n_y, n_x)`` (NaN where an echo is missing).
    times : [s] interface echo times, shape ``(n_layers + 1, n_y, n_x)``.
    speeds : [m/s] the layers' speeds.
    """

    thickness: FloatArray
    times: FloatArray
    speeds: tuple[float, ...]

    def statistics(self) -> list[dict[str, Any]]:
        """Per layer: its speed and the traces, mean, std, median, min and max [m]."""
        return [
            {"layer": k + 1, "speed_m_s": c, **_stats(self.thickness[k])}
            for k, c in enumerate(self.speeds)
        ]

    def dataset(self, scan: PositionScan) -> Any:
        """The thickness and echo-time maps as an ``xarray.Dataset`` (dims layer, y, x)."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "thickness": (("layer", "y", "x"), self.thickness),
                "echo_time": (("interface", "y", "x"), self.times),
            },
            coords={
                "x": ("x", scan.x),
                "y": ("y", scan.y),
                "layer": ("layer", np.arange(1, len(self.speeds) + 1)),
                "interface": ("interface", np.arange(len(self.speeds) + 1)),
            },
        )
        ds["thickness"].attrs.update(units="m", long_name="layer thickness")
        ds["echo_time"].attrs.update(units="s", long_name="interface echo time of flight")
        ds["x"].attrs.update(units="m", long_name="probe position x")
        ds["y"].attrs.update(units="m", long_name="probe position y")
        ds["layer"].attrs.update(units="1", long_name="layer number from the front wall")
        ds["interface"].attrs.update(units="1", long_name="interface number (0: front wall)")
        ds.attrs["speeds_m_s"] = json.dumps(list(self.speeds))
        ds.attrs["statistics"] = json.dumps(self.statistics())
        return ds


def layer_thickness(
    scan: PositionScan,
    speeds: Sequence[float],
    *,
    gates: Sequence[TimeGate | None] | None = None,
) -> LayerMap:
    """Thickness of each layer under each trace (see the module docstring).

    Parameters
    ----------
    speeds : [m/s] the longitudinal speed of each layer, front to back.
    gates : one gate per interface (``len(speeds) + 1``: the front wall first); None
        entries take the defaults (the front wall's triggered gate; for one layer the
        back wall's is everything after the front-wall gate).  More than one layer needs
        a gate for every interface behind the front wall.
    """
    cs = tuple(positive_float(f"speeds[{k}]", c) for k, c in enumerate(speeds))
    if not cs:
        raise EchocalValueError("speeds: give the speed of at least one layer")
    chosen: list[TimeGate | None] = list(gates) if gates is not None else [None] * (len(cs) + 1)
    if len(chosen) != len(cs) + 1:
        raise EchocalValueError(
            f"gates: {len(chosen)} gates for {len(cs)} layers; give one per interface "
            f"({len(cs) + 1}: the front wall and the back of each layer)"
        )
    if len(cs) > 1 and any(g is None for g in chosen[1:]):
        raise EchocalValueError(
            "gates: with several layers, give a gate for every interface behind the front wall"
        )
    x = scan.samples
    window = scan.window
    front = front_wall_tof(x, window, gate=chosen[0])
    template = (
        stacked_template(x, window, front)
        if np.any(np.isfinite(front))
        else echo_template(x, window.fs)
    )
    env = matched_envelope(x, template, window.fs)
    times = [front]
    for gate in chosen[1:]:
        if gate is None:  # one layer: everything after the front-wall gate
            fw = chosen[0] or named_gate("front-wall", pulse=template)
            end = fw.starts(x, window) + fw.width
            inside = window.times > end[..., None]
        else:
            inside = gate.masks(x, window)
        times.append(gated_peak_time(env, inside, window))
    t = np.stack(times)
    t = np.where(scan.valid[None], t, np.nan)
    c = np.asarray(cs)[:, None, None]
    return LayerMap(thickness=c * np.diff(t, axis=0) / 2.0, times=t, speeds=cs)
