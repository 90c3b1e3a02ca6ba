"""``echocal instrument-server``: an emulated rig on TCP, backed by a virtual setup."""

from __future__ import annotations

import typer

from echocal.cli._setup_option import SETUP_HELP, SNR_HELP

TOKEN_ENV = "ECHOCAL_INSTRUMENT_TOKEN"
"""Environment variable holding the instrument's shared token (kept out of `ps`)."""


def is_loopback(host: str) -> bool:
    """Whether every address ``host`` resolves to is this machine's loopback."""
    import ipaddress
    import socket

    try:
        infos = socket.getaddrinfo(host, None)
    except OSError:
        return False  # unresolvable: not known to be local (binding will say more)
    return bool(infos) and all(
        ipaddress.ip_address(str(info[4][0]).split("%")[0]).is_loopback for info in infos
    )


def _check_host(host: str, allow_remote: bool, token: str | None) -> None:
    """Refuse a non-loopback --host without --allow-remote; warn when it is allowed."""
    from echocal.cli._common import console
    from echocal.errors import EchocalValueError

    if is_loopback(host):
        return
    if not allow_remote:
        raise EchocalValueError(
            f"--host {host} listens beyond this machine: anyone who reaches the port could "
            "move the rig and read its data; pass --allow-remote (with --token SECRET) to do "
            "so, or keep the default 127.0.0.1"
        )
    risk = (
        "clients must send the --token first"
        if token is not None
        else "WITHOUT a token anyone who reaches the port can move the rig (add --token)"
    )
    console.print(
        f"[yellow]warning:[/] listening on {host}, beyond this machine: {risk}; the protocol "
        "is not encrypted (use a trusted network or an SSH tunnel)",
        highlight=False,
        soft_wrap=True,
    )


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
        allow_remote: bool = typer.Option(
            False,
            "--allow-remote",
            help="Allow a --host beyond this machine (e.g. 0.0.0.0): anyone who reaches the "
            "port can then move the rig; use with --token.",
        ),
        token: str | None = typer.Option(
            None,
            "--token",
            envvar=TOKEN_ENV,
            help="Shared secret every client must send first (AUTH <token>); also read "
            f"from ${TOKEN_ENV}.",
        ),
    ) -> None:
        """Serve a virtual setup as an instrument (MOVE, POS?, ACQ?, ...) until Ctrl-C.

        Connect with ``HardwareSource.connect(host, port)``; the protocol is in
        docs/sources.md.  It listens on loopback unless --allow-remote is given.
        """
        from echocal.cli._common import console
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import InstrumentError
        from echocal.measurement.instrument_server import serve_forever
        from echocal.measurement.protocol import check_token

        token = check_token(token)
        _check_host(host, allow_remote, token)
        source = resolve_setup(setup, snr=snr, seed=seed)

        def ready(address: tuple[str, int]) -> None:
            console.print(
                f"emulated rig for {source.description} listening on "
                f"{address[0]}:{address[1]} (Ctrl-C to stop)",
                soft_wrap=True,
                highlight=False,
            )

        try:
            serve_forever(source, host, port, move_time, on_ready=ready, token=token)
        except OSError as exc:  # address in use, host not local, ...
            raise InstrumentError(
                f"cannot listen on {host}:{port}: {exc.strerror or exc}"
            ) from None
        console.print("instrument server stopped", highlight=False)
