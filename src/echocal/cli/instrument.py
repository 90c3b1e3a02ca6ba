"""``echocal instrument-server``: an emulated rig on TCP, backed by a virtual setup."""

from __future__ import annotations

import typer

from echocal.errors import ConfigError


def _resolve_source(setup: str, seed: int | None) -> object:
    """The measurement source of setup ``setup`` (a built-in name or a TOML path)."""
    try:
        from echocal.setups import load_setup  # written separately; imported lazily
    except ImportError as exc:
        raise ConfigError(
            f"--setup needs echocal.setups, which is not available here ({exc})"
        ) from None
    from echocal.measurement.base import MeasurementSource

    loaded = load_setup(setup)
    if isinstance(loaded, MeasurementSource):
        return loaded
    build = getattr(loaded, "build", None)
    if callable(build):
        source = build(rng=seed) if seed is not None else build()
        if isinstance(source, MeasurementSource):
            return source
    raise ConfigError(f"--setup {setup!r} does not describe a measurement source")


def register(app: typer.Typer) -> None:
    """Add ``instrument-server`` to ``app``."""

    @app.command("instrument-server")
    def instrument_server(
        setup: str = typer.Option("thesis", "--setup", help="Built-in setup name or TOML file."),
        host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
        port: int = typer.Option(5025, "--port", help="TCP port (0 picks a free one)."),
        move_time: float = typer.Option(0.0, "--move-time", help="Seconds each MOVE takes."),
        seed: int | None = typer.Option(None, "--seed", help="Seed of the receiver noise."),
    ) -> None:
        """Serve a virtual setup as an instrument (MOVE, POS?, ACQ?, ...) until Ctrl-C."""
        from echocal.cli._common import console
        from echocal.measurement.instrument_server import serve_forever

        source = _resolve_source(setup, seed)

        def ready(address: tuple[str, int]) -> None:
            console.print(
                f"emulated rig for {source.description} listening on "  # type: ignore[attr-defined]
                f"{address[0]}:{address[1]} (Ctrl-C to stop)"
            )

        serve_forever(source, host, port, move_time, on_ready=ready)  # type: ignore[arg-type]
