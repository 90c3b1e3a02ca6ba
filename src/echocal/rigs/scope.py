"""A SCPI oscilloscope or digitizer as echocal's A-scan receiver (PyVISA).

:class:`VisaReceiver` reads one trace per :meth:`~VisaReceiver.acquire`:

1. the *acquire* commands (a single acquisition, or an averaged one: the
   averaging is set on the instrument by :meth:`~VisaReceiver.configure`), then
   the *wait* query (``*OPC?`` answers ``1`` once the acquisition is complete);
2. the trace preamble — the sample interval Δt [s], the time of the first
   sample, and the vertical scale and offset — as one query (Keysight, Rigol:
   ``:WAVeform:PREamble?``) or one query per value (Tektronix: ``WFMOutpre:...?``);
3. the samples as an IEEE 488.2 binary block (``#<n><length><bytes>``) read with
   PyVISA's ``query_binary_values``, converted to volts:
   ``v = (code − y_reference) · y_increment + y_origin``, and the time of sample i is
   ``x_origin + (i − x_reference) · Δt``.

The instrument must be triggered by the pulser's sync output, so that its time zero
is the firing time (add a known delay with ``time_offset``).  Command templates come
from a vendor preset (:data:`SCOPE_PRESETS`) and may be overridden one by one.
Faults follow :class:`~echocal.rigs.visa_io.VisaInstrument`'s policy.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from echocal._validate import finite_float, lookup, positive_int
from echocal.ascan import AScan
from echocal.errors import EchocalValueError
from echocal.rigs.visa_io import Nonsense, VisaInstrument, parse_float

__all__ = ["PREAMBLE_KEYS", "SCOPE_PRESETS", "ScopePreset", "VisaReceiver", "scope_preset"]

PREAMBLE_KEYS = ("x_increment", "x_origin", "x_reference", "y_increment", "y_origin", "y_reference")
"""The preamble values a receiver needs (names as in Keysight's manuals)."""


@dataclass(frozen=True, slots=True)
class ScopePreset:
    """Command templates of one oscilloscope family.

    Templates may use ``{channel}`` and (averaging only) ``{averages}``.

    Attributes
    ----------
    name, family : the preset's name and the instruments it is written for.
    setup : commands sent once when the receiver connects (trace source, format).
    average_on : commands that set averaging over ``{averages}`` acquisitions.
    average_off : commands for single acquisitions (``averages = 1``).
    acquire : commands that start one (averaged) acquisition.
    wait : query answered ``1`` once the acquisition is complete.
    preamble : one query answering comma-separated values in ``preamble_fields`` order,
        or empty to ask ``preamble_queries`` one by one.
    preamble_fields : names of the values of ``preamble`` (other names are ignored).
    preamble_queries : query per :data:`PREAMBLE_KEYS` entry (when ``preamble`` is empty);
        a key left out is 0.
    data : query answering the samples as an IEEE 488.2 binary block.
    datatype : :mod:`struct` code of one sample (``b`` int8, ``B`` uint8, ``h`` int16).
    big_endian : byte order of the samples.
    origin_in_codes : ``y_origin`` counts ADC codes (Rigol) rather than volts.
    """

    name: str
    family: str
    setup: tuple[str, ...]
    average_on: tuple[str, ...]
    average_off: tuple[str, ...]
    acquire: tuple[str, ...]
    data: str
    datatype: str
    wait: str = "*OPC?"
    preamble: str = ""
    preamble_fields: tuple[str, ...] = ()
    preamble_queries: tuple[tuple[str, str], ...] = ()
    big_endian: bool = False
    origin_in_codes: bool = False

    def __post_init__(self) -> None:
        if not self.preamble and not self.preamble_queries:
            raise EchocalValueError(
                f"scope preset {self.name!r}: give preamble or preamble_queries"
            )
        if self.datatype not in ("b", "B", "h", "H", "i", "f"):
            raise EchocalValueError(
                f"scope preset {self.name!r}: datatype must be one of b, B, h, H, i, f; "
                f"got {self.datatype!r}"
            )


_WAVEFORM_FIELDS = (
    "format",
    "type",
    "points",
    "count",
    "x_increment",
    "x_origin",
    "x_reference",
    "y_increment",
    "y_origin",
    "y_reference",
)

SCOPE_PRESETS: dict[str, ScopePreset] = {
    p.name: p
    for p in (
        ScopePreset(
            name="keysight",
            family="Keysight / Agilent InfiniiVision and Infiniium (:WAVeform subsystem)",
            setup=(
                ":WAVeform:SOURce CHANnel{channel}",
                ":WAVeform:FORMat WORD",
                ":WAVeform:BYTeorder LSBFirst",
                ":WAVeform:UNSigned 0",
            ),
            average_on=(":ACQuire:TYPE AVERage", ":ACQuire:COUNt {averages}"),
            average_off=(":ACQuire:TYPE NORMal",),
            acquire=(":DIGitize CHANnel{channel}",),
            preamble=":WAVeform:PREamble?",
            preamble_fields=_WAVEFORM_FIELDS,
            data=":WAVeform:DATA?",
            datatype="h",
        ),
        ScopePreset(
            name="tektronix",
            family="Tektronix MSO/DPO/TDS (DATa, WFMOutpre and CURVe?)",
            setup=(
                "DATa:SOUrce CH{channel}",
                "DATa:ENCdg SRIbinary",
                "WFMOutpre:BYT_Nr 2",
                "DATa:STARt 1",
            ),
            average_on=("ACQuire:MODe AVErage", "ACQuire:NUMAVg {averages}"),
            average_off=("ACQuire:MODe SAMple",),
            acquire=("ACQuire:STOPAfter SEQuence", "ACQuire:STATE ON"),
            preamble_queries=(
                ("x_increment", "WFMOutpre:XINcr?"),
                ("x_origin", "WFMOutpre:XZEro?"),
                ("x_reference", "WFMOutpre:PT_Off?"),
                ("y_increment", "WFMOutpre:YMUlt?"),
                ("y_origin", "WFMOutpre:YZEro?"),
                ("y_reference", "WFMOutpre:YOFf?"),
            ),
            data="CURVe?",
            datatype="h",
        ),
        ScopePreset(
            name="rigol",
            family="Rigol DS1000Z / MSO5000 (:WAV subsystem, byte mode)",
            setup=(":WAV:SOUR CHAN{channel}", ":WAV:MODE NORM", ":WAV:FORM BYTE"),
            average_on=(":ACQ:TYPE AVER", ":ACQ:AVER {averages}"),
            average_off=(":ACQ:TYPE NORM",),
            acquire=(":SING",),
            preamble=":WAV:PRE?",
            preamble_fields=_WAVEFORM_FIELDS,
            data=":WAV:DATA?",
            datatype="B",
            origin_in_codes=True,
        ),
    )
}
"""Command templates per oscilloscope family (see :class:`ScopePreset`)."""


def scope_preset(name: str, **overrides: Any) -> ScopePreset:
    """The preset ``name`` with some templates replaced (``setup=[...]``, ``data="..."``).

    An unknown name lists the valid ones; an unknown template name lists the fields.
    """
    preset = lookup("scope preset", name, SCOPE_PRESETS)
    fields = {f.name for f in dataclasses.fields(ScopePreset)} - {"name", "family"}
    unknown = sorted(set(overrides) - fields)
    if unknown:
        raise EchocalValueError(
            f"unknown scope command {unknown[0]!r}; known: {', '.join(sorted(fields))}"
        )
    tuples = {"setup", "average_on", "average_off", "acquire", "preamble_fields"}
    clean: dict[str, Any] = {k: tuple(v) if k in tuples else v for k, v in overrides.items()}
    if "preamble_queries" in clean:
        clean["preamble_queries"] = tuple(dict(clean["preamble_queries"]).items())
    return dataclasses.replace(preset, **clean)


class VisaReceiver:
    """:class:`~echocal.measurement.hardware.Receiver` on a SCPI oscilloscope.

    Parameters
    ----------
    instrument : the VISA resource (owned: closed by :meth:`close`).
    preset : the instrument family's commands (:func:`scope_preset`).
    channel : the input the probe's echo arrives on (>= 1).
    averages : acquisitions the instrument averages per A-scan (>= 1; 1 = none).
    time_offset : [s] added to the instrument's time axis (e.g. a sync delay), so that
        0 is the firing time.
    """

    def __init__(
        self,
        instrument: VisaInstrument,
        preset: ScopePreset,
        *,
        channel: int = 1,
        averages: int = 1,
        time_offset: float = 0.0,
    ) -> None:
        self.instrument = instrument
        self.preset = preset
        self.channel = positive_int("channel", channel)
        self.averages = positive_int("averages", averages)
        self.time_offset = finite_float("time_offset", time_offset)
        self._configured = False

    @property
    def description(self) -> str:
        """The preset and the resource."""
        return f"{self.preset.name} oscilloscope at {self.instrument.resource}"

    def identify(self) -> str:
        """The instrument's ``*IDN?`` answer."""
        return self.instrument.identify()

    def _fill(self, template: str) -> str:
        return template.format(channel=self.channel, averages=self.averages)

    def configure(self) -> None:
        """Send the preset's setup and averaging commands (once; :meth:`acquire` calls it)."""
        p = self.preset
        averaging = p.average_on if self.averages > 1 else p.average_off
        for template in (*p.setup, *averaging):
            self.instrument.write(self._fill(template))
        self._configured = True

    def preamble(self) -> dict[str, float]:
        """The trace's scale and time base: each of :data:`PREAMBLE_KEYS` [s, V or codes]."""
        p = self.preset
        if p.preamble:
            text = self.instrument.query(p.preamble)
            values = [v for v in text.split(",") if v.strip()]
            if len(values) != len(p.preamble_fields):
                raise self._nonsense(
                    p.preamble,
                    f"expected {len(p.preamble_fields)} comma-separated values; got "
                    f"{len(values)} in {text[:80]!r}",
                )
            named = dict(zip(p.preamble_fields, values, strict=True))
            out = {k: self._number(p.preamble, k, named.get(k, "0")) for k in PREAMBLE_KEYS}
        else:
            queries = dict(p.preamble_queries)
            out = {
                k: self.instrument.query_float(queries[k]) if k in queries else 0.0
                for k in PREAMBLE_KEYS
            }
        if not out["x_increment"] > 0.0 or out["y_increment"] == 0.0:
            raise self._nonsense(
                p.preamble or "preamble",
                f"the sample interval must be > 0 and the vertical scale non-zero; got "
                f"x_increment={out['x_increment']:g}, y_increment={out['y_increment']:g}",
            )
        return out

    def _nonsense(self, command: str, message: str) -> Exception:
        from echocal.errors import InstrumentError

        return InstrumentError(
            f"{command}: VISA resource {self.instrument.resource} answered nonsense: {message}"
        )

    def _number(self, command: str, key: str, text: str) -> float:
        try:
            return parse_float(text, key)
        except Nonsense as exc:
            raise self._nonsense(command, str(exc)) from None

    def acquire(self) -> AScan:
        """Acquire (averaged on the instrument), read the preamble and the block: one A-scan
        in volts, with ``fs`` [Hz] and ``start_time`` [s] from the preamble."""
        p = self.preset
        if not self._configured:
            self.configure()
        for template in p.acquire:
            self.instrument.write(self._fill(template))
        if p.wait:
            done = self.instrument.query(p.wait)
            if done.strip().lstrip("+") not in ("1", "1.0"):
                raise self._nonsense(p.wait, f"expected 1 (acquisition complete); got {done!r}")
        pre = self.preamble()
        codes = self.instrument.query_block(self._fill(p.data), p.datatype, p.big_endian)
        if codes.size < 2:
            raise self._nonsense(p.data, f"the block holds {codes.size} sample(s); need >= 2")
        reference = pre["y_reference"] + (pre["y_origin"] if p.origin_in_codes else 0.0)
        origin = 0.0 if p.origin_in_codes else pre["y_origin"]
        volts = (codes - reference) * pre["y_increment"] + origin
        dt = pre["x_increment"]
        start = pre["x_origin"] - pre["x_reference"] * dt + self.time_offset
        return AScan(
            samples=volts,
            fs=1.0 / dt,
            start_time=start,
            metadata={"receiver": self.description, "averages": self.averages},
        )

    def close(self) -> None:
        """Close the VISA resource."""
        self.instrument.close()
