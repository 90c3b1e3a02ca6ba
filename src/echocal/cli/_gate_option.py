"""The ``--gate`` option shared by calibrate, scan, record, sweep, lobe and simulate."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from echocal.signal.gates import TimeGate

__all__ = ["GATE_HELP", "gate_for_setup", "gate_for_source"]

GATE_HELP = (
    "Compute the metric inside a gate, as a flaw detector does: front-wall (around the "
    "first strong echo), back-wall (2T/c_L after the front wall, following it when the "
    "water path changes; needs a plate thickness), a gate NAME of the setup file "
    "([[gates]]) or START,WIDTH (µs unless a unit is given, e.g. 30us,2us).  Default: "
    "the whole recording.  See docs/gates.md."
)


def gate_for_setup(text: str | None, virtual: Any, *, field: str = "--gate") -> TimeGate | None:
    """:func:`echocal.signal.gates.setup_gate` of ``text`` (None without a gate): refused,
    before anything is measured, outside the recording window or never seeing an echo."""
    if text is None:
        return None
    from echocal.signal.gates import setup_gate

    return setup_gate(text, virtual, field=field)


def gate_for_source(
    text: str | None,
    *,
    pulse: Any,
    setup: Any = None,
    window: Any = None,
    field: str = "--gate",
) -> TimeGate | None:
    """The gate ``text`` names on a recording or a rig: the built-in gates and those of
    ``setup`` (a :class:`~echocal.measurement.VirtualSetup`, its name or file, or None); an
    absolute one is checked against ``window`` when the source's recording window is known
    (a rig's is checked on its first A-scan)."""
    if text is None:
        return None
    from echocal.signal.gates import check_gate, plate_layers, resolve_gate

    if isinstance(setup, str):
        from echocal.setups import load_setup

        setup = load_setup(setup)
    gate = resolve_gate(
        text,
        pulse=pulse,
        thickness=getattr(setup, "thickness", None),
        material=getattr(setup, "material", None),
        defined=getattr(setup, "gates", ()),
        field=field,
        layers=plate_layers(setup),
    )
    if window is not None:
        check_gate(gate, window, field=field)
    return gate
