"""``echocal instrument-server``: an emulated rig on TCP, backed by a virtual setup."""

from __future__ import annotations

import typer

from echocal._net import is_loopback
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP

TOKEN_ENV = "ECHOCAL_INSTRUMENT_TOKEN"
"""Environment variable holding the instrument's shared token (kept out of `ps`)."""


def _check_host(host: str, allow_remote: bool, token: str | None) -> None:
    """Refuse a non-loopback --host without --allow-remote and a token; warn when it is
    allowed (the protocol is not encrypted)."""
    from echocal.cli._common import console
    from echocal.errors import EchocalValueError

    if is_loopback(host):
        return
    if not allow_remote:
        raise EchocalValueError(
            f"--host {host} listens beyond this machine: anyone who reaches the port could "
            "move the rig and read its data; pass --allow-remote with --token SECRET (or "
            f"${TOKEN_ENV}) to do so, or keep the default 127.0.0.1"
        )
    if token is None:
        raise EchocalValueError(
            f"--allow-remote: --host {host} needs a token, so that only clients that send it "
            f"can move the rig; give --token SECRET (or set ${TOKEN_ENV})"
        )
    risk = "clients must send the --token first"
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
            help="Allow a --host beyond this machine (e.g. 0.0.0.0); needs --token, which "
            "every client must then send first.",
        ),
        token: str | None = typer.Option(
            None,
            "--token",
            envvar=TOKEN_ENV,
            help="Shared secret every client must send first (AUTH <token>); also read "
            f"from ${TOKEN_ENV}.",
        ),
        protocol: str = typer.Option(
            "echocal",
            "--protocol",
            help="echocal: the line protocol (MOVE, ACQ?, ...; the tcp driver); scpi: a "
            "SCPI motion controller and Keysight-style scope on one port, for the visa "
            "drivers through pyvisa-py (TCPIP::HOST::PORT::SOCKET; loopback only).",
        ),
        rig_file: str | None = typer.Option(
            None,
            "--rig-file",
            help="With --protocol scpi: write a rig file for this bench here (the visa "
            "drivers over pyvisa-py), for --rig and `echocal rig check`.",
        ),
    ) -> None:
        """Serve a virtual setup as an instrument (MOVE, POS?, ACQ?, ...) until Ctrl-C.

        Connect with ``HardwareSource.connect(host, port)``; the protocol is in
        docs/sources.md.  It listens on loopback unless --allow-remote is given.
        """
        from echocal.cli._common import console
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import EchocalValueError, InstrumentError
        from echocal.measurement.instrument_server import serve_forever
        from echocal.measurement.protocol import check_token

        token = check_token(token)
        from echocal._validate import one_of

        one_of("--protocol", protocol, ("echocal", "scpi"))
        if protocol == "scpi":
            _serve_scpi(setup, host, port, snr, seed, token, rig_file)
            return
        if rig_file is not None:
            raise EchocalValueError("--rig-file: only with --protocol scpi")
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


def _serve_scpi(
    setup: str,
    host: str,
    port: int,
    snr: str | None,
    seed: int | None,
    token: str | None,
    rig_file: str | None,
) -> None:
    """Serve ``setup`` as the simulated SCPI bench until Ctrl-C (``--protocol scpi``)."""
    from pathlib import Path

    from echocal.cli._common import console
    from echocal.cli._setup_option import resolve_setup
    from echocal.errors import EchocalValueError, InstrumentError
    from echocal.rigs.scpi_bench import ScpiBench, rig_file_text

    if token is not None or not is_loopback(host):
        raise EchocalValueError(
            "--protocol scpi: SCPI has no authentication, so the bench listens on loopback "
            "only and takes no --token (reach it from elsewhere through an SSH tunnel)"
        )
    source = resolve_setup(setup, snr=snr, seed=seed)
    try:
        bench = ScpiBench(source, host=host, port=port)
    except OSError as exc:
        raise InstrumentError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    try:
        if rig_file is not None:
            text = rig_file_text(bench.resource, setup=setup)
            try:
                Path(rig_file).write_text(text, encoding="utf-8")
            except OSError as exc:
                raise EchocalValueError(
                    f"--rig-file {rig_file}: cannot write it: {exc.strerror or exc}"
                ) from None
        console.print(
            f"simulated SCPI bench for {source.description} at VISA resource "
            f"{bench.resource} (library @py)"
            + (f"; rig file {rig_file}" if rig_file else "")
            + " (Ctrl-C to stop)",
            soft_wrap=True,
            highlight=False,
        )
        try:
            bench.serve_forever()
        except KeyboardInterrupt:
            pass
    finally:
        bench.close()
    console.print("instrument server stopped", highlight=False)
