"""Simulated VISA instruments (pyvisa-sim YAML) for protocol tests and ``echocal rig check``.

These instruments test the protocol only: pyvisa-sim answers fixed text, so each scope
returns the same trace at every pose and a calibration on them means nothing.  For
echoes that follow the pose, use :class:`echocal.rigs.scpi_bench.ScpiBench`
(``echocal instrument-server --protocol scpi``).

pyvisa-sim answers each query with fixed text encoded as UTF-8 (version 0.7), so a
binary block can only hold bytes below 0x80; ``\\n``, ``\\r`` and ``\\`` are also left
out (a line end would end the read, a backslash starts pyvisa-sim's escapes).  The
simulated waveforms therefore use ADC codes whose bytes avoid these
(:func:`encodable`), and the IEEE 488.2 block is written as text (:func:`ieee_block`):
a real binary transfer through PyVISA's ``query_binary_values``, with a restricted
alphabet.  The instruments:

* ``TCPIP0::keysight.sim::INSTR``, ``TCPIP0::tektronix.sim::INSTR``,
  ``TCPIP0::rigol.sim::INSTR`` — oscilloscopes answering their preset's commands with
  one 5 MHz echo (:func:`echo_codes`); averaging is a checked property;
* ``TCPIP0::mute.sim::INSTR`` — a Keysight scope whose data query never answers (a timeout);
* ``TCPIP0::garbled.sim::INSTR`` — a Keysight scope whose block header is broken;
* ``ASRL1::INSTR`` — a five-axis controller of the ``scpi`` motion preset; a move out of
  the travel limits is refused (``SYST:ERR?`` answers ``-222,"Data out of range"``).

The shipped file ``echocal/data/visa/echocal-sim.yaml`` is :func:`write_sim_file`'s
output (``python -m echocal.rigs.simfile``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "AXIS_LIMITS",
    "ECHO",
    "echo_codes",
    "encodable",
    "ieee_block",
    "motion_device",
    "scope_device",
    "sim_definition",
    "write_sim_file",
]

_FORBIDDEN = frozenset({0x0A, 0x0D, 0x5C})

ECHO = {"fs": 100e6, "start": 60e-6, "n": 1000, "f0": 5e6, "t0": 66.5e-6, "sigma": 0.25e-6}
"""The simulated echo: sampling rate [Hz], first sample [s], sample count, centre
frequency [Hz], arrival [s] and Gaussian envelope width [s]."""

AXIS_LIMITS = {
    "X": (-50.0, 50.0),
    "Y": (-50.0, 50.0),
    "Z": (5.0, 80.0),
    "AZ": (-180.0, 180.0),
    "COEL": (-30.0, 30.0),
}
"""Travel limits of the simulated controller, in its units (mm, deg)."""


def encodable(codes: np.ndarray, datatype: str) -> np.ndarray:
    """Whether each code's bytes (little-endian) can be sent by pyvisa-sim, shape of codes."""
    raw = np.asarray(codes).astype(np.dtype(datatype).newbyteorder("<"))
    as_bytes = raw.view(np.uint8).reshape(raw.size, -1)
    ok = (as_bytes < 0x80) & ~np.isin(as_bytes, list(_FORBIDDEN))
    return np.all(ok, axis=1).reshape(np.shape(codes))


def _nearest_encodable(values: np.ndarray, datatype: str, low: int, high: int) -> np.ndarray:
    grid = np.arange(low, high + 1)
    grid = grid[encodable(grid, datatype)]
    idx = np.clip(np.searchsorted(grid, values), 1, grid.size - 1)
    left, right = grid[idx - 1], grid[idx]
    return np.where(np.abs(values - left) <= np.abs(right - values), left, right)


def echo_codes(datatype: str, centre: int, amplitude: float) -> np.ndarray:
    """ADC codes of :data:`ECHO` (a Gabor pulse), rounded to encodable codes, shape (n,)."""
    t = ECHO["start"] + np.arange(ECHO["n"]) / ECHO["fs"]
    tau = t - ECHO["t0"]
    wave = np.exp(-0.5 * (tau / ECHO["sigma"]) ** 2) * np.cos(2 * np.pi * ECHO["f0"] * tau)
    ideal = np.rint(centre + amplitude * wave).astype(np.int64)
    info = np.iinfo(np.dtype(datatype))
    return _nearest_encodable(ideal, datatype, max(info.min, 0), min(info.max, 0x7F7F))


def ieee_block(codes: np.ndarray, datatype: str) -> str:
    """``#<digits><length><bytes>`` of ``codes`` (little-endian) as text (bytes < 0x80)."""
    data = np.asarray(codes).astype(np.dtype(datatype).newbyteorder("<")).tobytes()
    if any(b >= 0x80 or b in _FORBIDDEN for b in data):
        raise ValueError("codes hold bytes pyvisa-sim cannot send; see encodable()")
    length = str(len(data))
    return f"#{len(length)}{length}" + data.decode("ascii")


_EOM = {
    "TCPIP INSTR": {"q": "\n", "r": "\n"},
    "ASRL INSTR": {"q": "\n", "r": "\n"},
}


def _quiet(*commands: str) -> list[dict[str, str]]:
    return [{"q": c} for c in commands]


def scope_device(preset_name: str, *, data: str | None = None) -> dict[str, Any]:
    """pyvisa-sim definition of an oscilloscope of ``preset_name`` (keysight, tektronix,
    rigol) holding the :data:`ECHO`; ``data`` replaces the data query's answer ("" = none)."""
    from echocal.rigs.scope import scope_preset

    p = scope_preset(preset_name)
    dt = 1.0 / ECHO["fs"]
    if preset_name == "rigol":  # uint8 codes, V = (code - y_origin - y_reference) * y_inc
        codes, y_inc, y_origin, y_ref = echo_codes("B", 64, 60.0), 0.02, 4.0, 60.0
        x_origin, x_ref = ECHO["start"], 0.0
    else:  # int16 codes, V = (code - y_reference) * y_inc + y_origin
        codes, y_inc, y_origin, y_ref = echo_codes("h", 16384, 12000.0), 2e-5, 0.01, 16384.0
        x_origin, x_ref = ECHO["start"] + 3 * dt, 3.0
    block = ieee_block(codes, p.datatype)
    answers: dict[str, str] = {
        p.wait: "1",
        p.data.format(channel=1): block if data is None else data,
    }
    preamble = {
        "x_increment": dt,
        "x_origin": x_origin,
        "x_reference": x_ref,
        "y_increment": y_inc,
        "y_origin": y_origin,
        "y_reference": y_ref,
    }
    if p.preamble:
        fields = {"format": 1 if p.datatype == "h" else 0, "type": 2, "points": len(codes)}
        fields["count"] = 1
        values = [repr(float({**fields, **preamble}[f])) for f in p.preamble_fields]
        answers[p.preamble] = ",".join(values)
    else:
        for key, query in p.preamble_queries:
            answers[query] = repr(float(preamble[key]))
    average_count = p.average_on[1].split(" ")[0]
    commands = [c.format(channel=1) for c in (*p.setup, *p.acquire)]
    dialogues = [
        {"q": "*IDN?", "r": f"{p.name.upper()},SIMULATED-SCOPE,SIM0001,echocal-pyvisa-sim"},
        *_quiet(*commands, *p.average_off, p.average_on[0]),
        *[({"q": q, "r": r} if r else {"q": q}) for q, r in answers.items()],
    ]
    return {
        "eom": _EOM,
        "error": "ERROR",
        "dialogues": dialogues,
        "properties": {
            "averages": {
                "default": 1,
                "getter": {"q": f"{average_count}?", "r": "{:d}"},
                "setter": {"q": f"{average_count} {{:d}}"},
                "specs": {"min": 1, "max": 65536, "type": "int"},
            }
        },
    }


def motion_device() -> dict[str, Any]:
    """pyvisa-sim definition of the five-axis ``scpi`` controller (:data:`AXIS_LIMITS`)."""
    properties = {}
    dialogues = [{"q": "*IDN?", "r": "ECHOCAL,SIMULATED-STAGE,SIM0002,echocal-pyvisa-sim"}]
    for axis, (low, high) in AXIS_LIMITS.items():
        start = 20.0 if axis == "Z" else 0.0
        properties[f"position_{axis.lower()}"] = {
            "default": start,
            "getter": {"q": f"POS? {axis}", "r": "{:.6f}"},
            "setter": {"q": f"MOVE:ABS {axis},{{:f}}"},
            "specs": {"min": low, "max": high, "type": "float"},
        }
        dialogues += [
            {"q": f"LIM? {axis}", "r": f"{low!r},{high!r}"},
            {"q": f"MOVE:DONE? {axis}", "r": "1"},
        ]
    return {
        "eom": _EOM,
        "error": {
            "error_queue": [
                {
                    "q": "SYST:ERR?",
                    "default": '0,"No error"',
                    "command_error": '-222,"Data out of range"',
                }
            ]
        },
        "dialogues": dialogues,
        "properties": properties,
    }


def sim_definition() -> dict[str, Any]:
    """The whole pyvisa-sim file: devices and the resources they answer on."""
    devices = {
        "keysight": scope_device("keysight"),
        "tektronix": scope_device("tektronix"),
        "rigol": scope_device("rigol"),
        "mute": scope_device("keysight", data=""),
        "garbled": scope_device("keysight", data="#9" + "A" * 40),
        "stage": motion_device(),
    }
    resources = {
        f"TCPIP0::{name}.sim::INSTR": {"device": name} for name in devices if name != "stage"
    }
    resources["ASRL1::INSTR"] = {"device": "stage"}
    return {"spec": "1.1", "devices": devices, "resources": resources}


def write_sim_file(path: str | Path) -> Path:
    """Write :func:`sim_definition` as YAML to ``path``."""
    import yaml

    path = Path(path)
    path.write_text(
        "# Simulated instruments for pyvisa-sim, written by `python -m echocal.rigs.simfile`.\n"
        + yaml.safe_dump(sim_definition(), sort_keys=False, width=100, allow_unicode=False),
        encoding="utf-8",
    )
    return path


if __name__ == "__main__":  # pragma: no cover - regenerates the shipped file
    default = Path(__file__).parents[1] / "data" / "visa" / "echocal-sim.yaml"
    print(write_sim_file(sys.argv[1] if len(sys.argv) > 1 else default))
