"""``echocal calibrate --from result.json``: rerun a calibration from its provenance (private).

The command stores its own parameters in the provenance record of ``result.json``
(:func:`rerun_parameters` is their inverse): the setup and a recording as absolute paths,
everything else as typed.  A rerun refuses a setup or recording whose content changed
since (their SHA-256 digests are in the record): the same numbers need the same inputs.
``--current-setup`` reruns on a changed setup file as it is now, and the new result's
provenance records it (``rerun``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from echocal.errors import ConfigError

NOT_RECORDED = (
    "ctx", "from_file", "out", "plots", "map_points", "json_output", "token", "overwrite",
    "current_setup",
)  # fmt: skip
"""calibrate parameters that are the rerun's own (where to write, how to print; the token
is a secret and never written to a file)."""


def recorded_parameters(given: dict[str, Any]) -> dict[str, Any]:
    """The parameters of one ``echocal calibrate`` to store for a rerun: files as absolute
    paths (a rerun may start elsewhere)."""
    out = {k: v for k, v in given.items() if k not in NOT_RECORDED}
    for key in ("setup", "replay"):
        value = out.get(key)
        if value is not None and Path(value).is_file():
            out[key] = str(Path(value).resolve())
        elif isinstance(value, Path):
            out[key] = str(value)
    return out


RERUN_KEY = "echocal.rerun"
"""Where :func:`rerun_parameters` leaves, in the click context's ``meta``, what the rerun's
provenance records under ``rerun``: the file rerun and the setup's digests."""


def rerun_parameters(path: Path, ctx: Any, *, current_setup: bool = False) -> dict[str, Any]:
    """The parameters recorded in ``path`` (a ``result.json``), checked for a rerun.

    Raises :class:`~echocal.errors.ConfigError` for another command's file, options given
    beside ``--from`` (they would change the run), or a setup or recording that changed
    (a setup file that changed is used as it is now with ``current_setup``).  Leaves in
    ``ctx.meta[RERUN_KEY]`` the record of the rerun: ``from`` (the file), ``setup``
    (``"recorded"``: unchanged, or ``"current"``) and the setup's ``recorded_sha256`` and
    ``current_sha256``.
    """
    from echocal.provenance import file_digest, read_provenance
    from echocal.setup_digest import setup_digest

    record = read_provenance(path)
    if record.get("command") != "calibrate":
        raise ConfigError(
            f"--from {path}: written by `echocal {record.get('command')}`, not calibrate"
        )
    extra = sorted(
        f"--{name.replace('_', '-')}"
        for name in ctx.params
        if name not in NOT_RECORDED and _given(ctx, name)
    )
    if extra:
        raise ConfigError(
            f"--from {path} reruns the recorded calibration as it was; drop {', '.join(extra)}"
            " (only --out, --plots/--no-plots, --map-points, --json, --token, --overwrite and"
            " --current-setup may change)"
        )
    recorded = record.get("parameters")
    if not isinstance(recorded, dict) or not recorded:
        raise ConfigError(
            f"--from {path}: its provenance holds no parameters (provenance.parameters is "
            "missing or empty), so the run cannot be repeated; give the options again instead"
        )
    params = dict(recorded)
    unknown = sorted(set(params) - set(ctx.params))
    if unknown:
        raise ConfigError(f"--from {path}: unknown recorded parameters {', '.join(unknown)}")
    missing = sorted(set(ctx.params) - set(NOT_RECORDED) - set(params))
    if missing:
        raise ConfigError(
            f"--from {path}: provenance.parameters lacks {', '.join(missing)}, so the rerun "
            "would fall back to defaults the run may not have used; give the options again "
            "instead"
        )
    setup = record.get("setup")
    rerun: dict[str, Any] = {"from": str(Path(path).resolve()), "setup": "recorded"}
    if isinstance(setup, dict) and setup.get("sha256") and params.get("setup"):
        if not Path(str(params["setup"])).is_file() and Path(str(params["setup"])).suffix:
            raise ConfigError(
                f"--from {path}: setup file {params['setup']} is missing; restore it to rerun"
            )
        now = setup_digest(str(params["setup"]))["sha256"]
        rerun.update(recorded_sha256=setup["sha256"], current_sha256=now)
        if now != setup["sha256"]:
            if not current_setup:
                raise ConfigError(
                    f"--from {path}: setup {params['setup']} has changed since the run "
                    f"(sha256 {setup['sha256'][:12]}… then, {now[:12]}… now); restore it to "
                    "rerun, or add --current-setup to rerun on it as it is now"
                )
            rerun["setup"] = "current"
    elif current_setup:
        raise ConfigError(f"--from {path}: --current-setup: the run recorded no setup digest")
    ctx.meta[RERUN_KEY] = rerun
    source = record.get("source")
    if isinstance(source, dict) and source.get("kind") == "replay" and source.get("sha256"):
        now = file_digest(source["file"])
        if now != source["sha256"]:
            raise ConfigError(
                f"--from {path}: recording {source['file']} has changed since the run "
                f"(sha256 {source['sha256'][:12]}… then, {now[:12]}… now)"
            )
    if params.get("replay") is not None:
        params["replay"] = Path(params["replay"])
    return params


def _given(ctx: Any, name: str) -> bool:
    """Whether option ``name`` was given on the command line (not a default)."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name in ("COMMANDLINE", "ENVIRONMENT", "PROMPT")
