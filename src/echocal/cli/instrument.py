"""``echocal instrument-server``: an emulated rig on TCP, backed by a virtual setup."""

from __future__ import annotations

import typer

from echocal.cli._setup_option import SETUP_HELP, SNR_HELP


def register(app: typer.Typer) -> None:
    """Add ``instrument-server`` to ``app``."""

    @app.command("instrument-server")
    def instrument_server(
        setup: str = typer.Option("thesis", "--setup", help=SETUP_HELP),
        host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
        port: int = typer.Option(
            5025, "--port", min=0, max=65535, help="TCP port (0 picks a free one; printed)."
        ),
        move_time: float = typer.Option(
            0.0, "--move-time", min=0.0, help="Seconds each MOVE takes (a slow positioner)."
        ),
        seed: int | None = typer.Option(
            None, "--seed", help="Seed of the receiver noise (default: the setup's)."
        ),
        snr: str | None = typer.Option(None, "--snr", help=SNR_HELP),
    ) -> None:
        """Serve a virtual setup as an instrument (MOVE, POS?, ACQ?, ...) until Ctrl-C.

        Connect with ``HardwareSource.connect(host, port)``; the protocol is in
        docs/sources.md.
        """
        from echocal.cli._common import console
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import InstrumentError
        from echocal.measurement.instrument_server import serve_forever

        source = resolve_setup(setup, snr=snr, seed=seed)

        def ready(address: tuple[str, int]) -> None:
            console.print(
                f"emulated rig for {source.description} listening on "
                f"{address[0]}:{address[1]} (Ctrl-C to stop)",
                soft_wrap=True,
                highlight=False,
            )

        try:
            serve_forever(source, host, port, move_time, on_ready=ready)
        except OSError as exc:  # address in use, host not local, ...
            raise InstrumentError(
                f"cannot listen on {host}:{port}: {exc.strerror or exc}"
            ) from None
        console.print("instrument server stopped", highlight=False)
