"""The instrument line protocol, shared by the TCP client and the emulated rig.

A plain-text, SCPI-style protocol over one TCP connection.  Every message is
one line of UTF-8 text ended by ``\\n``; numbers are written with Python's
``repr(float)`` (round-trips exactly; ``inf``/``-inf`` for unlimited axes).
Units are SI metres and degrees, as everywhere in echocal.

========================  ===========================================================
client sends              instrument answers
========================  ===========================================================
``*IDN?``                 one line identifying the instrument (free text)
``MOVE x y z az coel``    ``OK`` once the move is finished, or ``ERR <CODE> <message>``
``POS?``                  ``x y z az coel`` — the pose reached [m, m, m, deg, deg]
``ACQ?``                  header ``ASCAN fs start n`` ([Hz], [s], sample count), then
                          one line: base64 of the ``n`` samples as little-endian
                          float64 (exact and compact; ``8 n`` bytes before encoding)
``LIMITS?``               ``xlo xhi ylo yhi zlo zhi azlo azhi coello coelhi``
``BYE``                   ``OK``, then the instrument closes the connection
========================  ===========================================================

A pose may end with the flag ``GIMBAL`` (``MOVE x y z az coel GIMBAL``; ``POS?``
then answers with the flag too): the beam axis is the same, but the probe's roll
about it is that of a gimbal (tilt-x, tilt-y) positioner, as for poses made with
:meth:`~echocal.geometry.Pose.from_tilt`.  Without it the roll is that of an
(azimuth, co-elevation) positioner (thesis eqs. 9-10).  The roll matters for
non-round apertures.

Error codes after ``ERR``: ``LIMIT`` (pose out of the positioner's limits; the
client raises :class:`~echocal.errors.LimitError`), ``SYNTAX`` (malformed or
unknown command), ``FAULT`` (the instrument failed).  Any other reply is nonsense
and the client raises :class:`~echocal.errors.InstrumentError` naming the command.

The decoders here raise :class:`ProtocolError` (an ``InstrumentError``); the
client adds the command name and resets the connection.
"""

from __future__ import annotations

import base64
import binascii
import math
import zlib

import numpy as np
from numpy.typing import NDArray

from echocal.errors import EchocalValueError, InstrumentError
from echocal.geometry import Pose
from echocal.measurement.limits import PositionerLimits

__all__ = [
    "COMMANDS",
    "ENCODING",
    "GIMBAL",
    "MAX_LINE_BYTES",
    "ProtocolError",
    "check_token",
    "decode_ascan_header",
    "decode_floats",
    "decode_limits",
    "decode_pose",
    "decode_samples",
    "encode_ascan",
    "encode_limits",
    "encode_line",
    "encode_pose",
    "format_float",
    "payload_crc",
]

ENCODING = "utf-8"
MAX_LINE_BYTES = 64 * 1024 * 1024
"""Longest accepted line [bytes] (an A-scan of ~6 million samples); longer is nonsense."""

COMMANDS = ("*IDN?", "MOVE", "POS?", "ACQ?", "LIMITS?", "BYE", "AUTH")
"""Every command the protocol knows."""

GIMBAL = "GIMBAL"
"""Trailing flag of a pose whose probe frame is the gimbal's (tilt positioner)."""

_LIMIT_AXES = ("x", "y", "z", "azimuth", "coelevation")


class ProtocolError(InstrumentError):
    """A line does not follow the protocol (malformed number, wrong count, unknown reply)."""


def format_float(value: float) -> str:
    """``repr`` of a float: exact round trip, ``inf``/``-inf`` for unbounded values."""
    return repr(float(value))


def encode_line(*fields: object) -> bytes:
    """Join ``fields`` with single spaces into one ``\\n``-terminated line.

    Floats are written with :func:`format_float`; a field may not contain a newline.
    """
    parts = [format_float(f) if isinstance(f, float) else str(f) for f in fields]
    text = " ".join(parts)
    if "\n" in text or "\r" in text:
        raise ProtocolError(f"a protocol line may not contain a newline; got {text!r}")
    return (text + "\n").encode(ENCODING)


def decode_floats(text: str, count: int, what: str, *, allow_inf: bool = False) -> list[float]:
    """Parse exactly ``count`` space-separated floats from ``text``.

    Raises
    ------
    ProtocolError : wrong count, a token that is not a number, NaN, or inf when not allowed.
    """
    tokens = text.split()
    if len(tokens) != count:
        raise ProtocolError(f"{what} must hold {count} numbers; got {len(tokens)} in {text!r}")
    out = []
    for token in tokens:
        try:
            value = float(token)
        except ValueError:
            raise ProtocolError(f"{what}: {token!r} is not a number (in {text!r})") from None
        if math.isnan(value) or (math.isinf(value) and not allow_inf):
            raise ProtocolError(f"{what}: {token!r} is not a finite number (in {text!r})")
        out.append(value)
    return out


def encode_pose(pose: Pose) -> str:
    """``"x y z az coel"`` ([m] and [deg]) as used by ``MOVE`` and ``POS?``.

    A gimbal pose (:meth:`~echocal.geometry.Pose.from_tilt`) gets the trailing
    flag ``GIMBAL``: same beam axis, but the probe's roll is the gimbal's.
    """
    text = " ".join(format_float(v) for v in pose.as_array())
    return f"{text} {GIMBAL}" if pose.gimbal else text


def decode_pose(text: str, what: str = "pose") -> Pose:
    """Inverse of :func:`encode_pose` (5 numbers, optionally followed by ``GIMBAL``)."""
    tokens = text.split()
    gimbal = len(tokens) == 6 and tokens[-1] == GIMBAL
    if gimbal:
        text = " ".join(tokens[:5])
    x, y, z, azimuth, coelevation = decode_floats(text, 5, what)
    return Pose(x, y, z, azimuth, coelevation, gimbal=gimbal)


def encode_limits(limits: PositionerLimits) -> str:
    """``"xlo xhi ylo yhi zlo zhi azlo azhi coello coelhi"`` ([m], [deg]; ``inf`` = unlimited)."""
    return " ".join(format_float(b) for axis in _LIMIT_AXES for b in getattr(limits, axis))


def decode_limits(text: str) -> PositionerLimits:
    """Inverse of :func:`encode_limits`."""
    values = decode_floats(text, 10, "LIMITS? reply", allow_inf=True)
    pairs = {axis: (values[2 * i], values[2 * i + 1]) for i, axis in enumerate(_LIMIT_AXES)}
    try:
        return PositionerLimits(**pairs)
    except ValueError as exc:
        raise ProtocolError(f"LIMITS? reply: {exc}") from None


def encode_ascan(samples: NDArray[np.float64], fs: float, start_time: float) -> tuple[str, str]:
    """Header ``"ASCAN fs start n crc32=XXXXXXXX"`` and payload (base64 of little-endian
    float64 samples); the CRC-32 of the payload line lets the client refuse a garbled one.

    Parameters
    ----------
    samples : shape ``(n_samples,)``
    fs : [Hz] sampling frequency.
    start_time : [s] time of the first sample.
    """
    data = np.ascontiguousarray(samples, dtype="<f8")
    payload = base64.b64encode(data.tobytes()).decode("ascii")
    crc = zlib.crc32(payload.encode("ascii"))
    header = f"ASCAN {format_float(fs)} {format_float(start_time)} {data.size} crc32={crc:08x}"
    return header, payload


def decode_ascan_header(text: str) -> tuple[float, float, int]:
    """Parse ``"ASCAN fs start n [crc32=XXXXXXXX]"`` into (fs [Hz], start_time [s],
    n_samples); the optional checksum is read by :func:`payload_crc`."""
    tokens = text.split()
    if len(tokens) == 5:
        payload_crc(text)  # a malformed checksum field is refused here
        tokens = tokens[:4]
    if len(tokens) != 4 or tokens[0] != "ASCAN":
        raise ProtocolError(f"expected an 'ASCAN fs start n' header; got {text[:80]!r}")
    fs, start = decode_floats(" ".join(tokens[1:3]), 2, "ASCAN header")
    try:
        n = int(tokens[3])
    except ValueError:
        raise ProtocolError(f"ASCAN header: sample count {tokens[3]!r} is not an integer") from None
    if fs <= 0.0 or n < 1:
        raise ProtocolError(f"ASCAN header needs fs > 0 and n >= 1; got {text!r}")
    return fs, start, n


def payload_crc(header: str) -> int | None:
    """The CRC-32 an ``ASCAN`` header announces for its payload line (None: no checksum,
    as from an older instrument)."""
    tokens = header.split()
    if len(tokens) != 5:
        return None
    name, _, value = tokens[4].partition("=")
    try:
        if name != "crc32" or len(value) != 8:
            raise ValueError
        return int(value, 16)
    except ValueError:
        raise ProtocolError(
            f"ASCAN header: the fifth field must be crc32=XXXXXXXX (8 hex digits); got "
            f"{tokens[4][:40]!r}"
        ) from None


def decode_samples(text: str, n_samples: int, crc: int | None = None) -> NDArray[np.float64]:
    """Decode an A-scan payload line, checking it holds exactly ``n_samples`` finite samples
    and, when ``crc`` is given (the header's :func:`payload_crc`), that its CRC-32 matches:
    a payload garbled in transit is refused, never read as other numbers."""
    if crc is not None and zlib.crc32(text.strip().encode("ascii", errors="replace")) != crc:
        raise ProtocolError("A-scan payload fails its CRC-32 check: garbled in transit")
    try:
        raw = base64.b64decode(text.strip().encode("ascii"), validate=True)
    except (binascii.Error, UnicodeEncodeError, ValueError):
        raise ProtocolError(f"A-scan payload is not base64 ({text[:40]!r}...)") from None
    if len(raw) != 8 * n_samples:
        raise ProtocolError(
            f"A-scan payload holds {len(raw) / 8:g} samples; the header announced {n_samples}"
        )
    samples = np.frombuffer(raw, dtype="<f8").astype(np.float64)
    if not np.all(np.isfinite(samples)):
        raise ProtocolError("A-scan payload holds NaN or inf samples")
    return samples


def check_token(token: str | None) -> str | None:
    """A token: printable text without spaces, 8 to 256 characters (None: no token)."""
    if token is None:
        return None
    if (
        not isinstance(token, str)
        or not 8 <= len(token) <= 256
        or not token.isprintable()
        or any(c.isspace() for c in token)
    ):
        raise EchocalValueError(
            "token must be 8 to 256 printable characters without spaces (e.g. from "
            "`python -c 'import secrets; print(secrets.token_urlsafe())'`)"
        )
    return token
