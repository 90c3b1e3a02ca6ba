"""Reading setups: built-in names, files, validation and overrides (see
:mod:`echocal.setups`)."""

from __future__ import annotations

import dataclasses
import importlib.resources
import json
import tomllib
from pathlib import Path
from typing import Any

from pydantic import (
    ValidationError,
)

from echocal.errors import ConfigError, DataFileError, EchocalError, UnknownNameError
from echocal.measurement.virtual import (
    VirtualSetup,
)
from echocal.setups.build import _assemble, _build_parts, _raise_problems
from echocal.setups.schema import SetupConfig, _format_errors
from echocal.specimen import (
    builtin_specimen,
)


# ---------------------------------------------------------------- reading
def builtin_setup_names() -> tuple[str, ...]:
    """Names of the setups shipped with echocal."""
    folder = importlib.resources.files("echocal") / "data" / "setups"
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


def _read_toml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise DataFileError(f"setup file not found: {path}")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None


def _resolve(name_or_path: str | Path) -> tuple[dict[str, Any], Path]:
    text = str(name_or_path)
    if text in builtin_setup_names():
        resource = importlib.resources.files("echocal") / "data" / "setups" / f"{text}.toml"
        return tomllib.loads(resource.read_text(encoding="utf-8")), Path.cwd()
    path = Path(text)
    if path.suffix != ".toml" and not path.exists():
        raise UnknownNameError(
            f"unknown setup {text!r}: not a built-in ({', '.join(builtin_setup_names())}) "
            "and no such .toml file"
        )
    return _read_toml(path), path.parent


def load_setup_config(name_or_path: str | Path) -> tuple[SetupConfig, Path]:
    """Read and validate a setup (built-in name or TOML path); return it and its folder.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    raw, base_dir = _resolve(name_or_path)
    try:
        return SetupConfig.model_validate(raw), base_dir
    except ValidationError as exc:
        problems = _format_errors(exc, raw=raw)
        raise ConfigError(
            f"{name_or_path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)
        ) from None


def _check(
    name_or_path: str | Path,
) -> tuple[SetupConfig | None, Path, dict[str, Any], list[str]]:
    """Config, folder, built parts and EVERY problem of a setup (schema and build together).

    Sections whose schema fails are left out of the build checks (and so are the checks
    needing them); all other sections are still built and checked.
    """
    raw, base_dir = _resolve(name_or_path)
    try:
        config = SetupConfig.model_validate(raw)
    except ValidationError as exc:
        problems = _format_errors(exc, raw=raw)
        invalid = frozenset(str(item["loc"][0]) for item in exc.errors() if item["loc"])
    else:
        return config, base_dir, *_build_parts(config, base_dir)
    try:
        config = SetupConfig.model_validate({k: v for k, v in raw.items() if k not in invalid})
    except ValidationError:  # a top-level problem the schema could not pin to a key
        return None, base_dir, {}, problems
    parts, found = _build_parts(config, base_dir, invalid=invalid)
    return config, base_dir, parts, problems + found


def load_setup(name_or_path: str | Path, *, seed: int | None = None) -> VirtualSetup:
    """The :class:`~echocal.measurement.virtual.VirtualSetup` of a built-in name or TOML file.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    return load_setup_with_config(name_or_path, seed=seed)[2]


def load_setup_with_config(
    name_or_path: str | Path, *, seed: int | None = None
) -> tuple[SetupConfig, Path, VirtualSetup]:
    """:func:`load_setup`, also returning the validated config and the setup's folder."""
    config, base_dir, parts, problems = _check(name_or_path)
    if problems or config is None:
        _raise_problems(name_or_path, problems)
    return config, base_dir, _assemble(config, parts, seed)


_KEEP: Any = object()


def setup_with_overrides(
    name_or_path: str | Path,
    *,
    specimen: str | None = None,
    snr_db: float | None = _KEEP,
    seed: int | None = None,
) -> VirtualSetup:
    """:func:`load_setup` with the usual overrides applied.

    Parameters
    ----------
    specimen : a built-in specimen name replacing the setup's specimen.
    snr_db : [dB] the receiver SNR; ``None`` for a noiseless receiver; omitted: the file's.
    seed : noise seed (overrides the file's).
    """
    virtual = load_setup(name_or_path, seed=seed)
    changes: dict[str, Any] = {}
    if specimen is not None:
        changes["specimen"] = builtin_specimen(specimen)
    if snr_db is not _KEEP:
        changes["receiver"] = dataclasses.replace(virtual.receiver, snr_db=snr_db)
    if not changes:
        return virtual
    return dataclasses.replace(virtual, rng=seed if seed is not None else virtual.rng, **changes)


def validate_setup_file(name_or_path: str | Path) -> list[str]:
    """Every problem of a setup file, one line each with its field path (empty if valid).

    Schema problems and build problems (unknown names, pulse parameters, positioner
    limits, a reference position inside the part, ...) are all reported together; a
    check that needs another, broken part is skipped.  If there is no problem the
    reference echo is simulated too, so that an empty recording window is reported.
    Warnings (a setting that is ignored) are issued with :func:`warnings.warn`.
    """
    try:
        config, _, parts, problems = _check(name_or_path)
        if problems or config is None:
            return problems
        _ = _assemble(config, parts, None).noise_sigma  # simulates the reference echo
    except ConfigError as exc:
        lines = str(exc).splitlines()
        return [line.strip() for line in lines[1:]] if len(lines) > 1 else lines
    except EchocalError as exc:
        return [str(exc)]
    return []


def resolved_data(config: SetupConfig) -> dict[str, Any]:
    """The resolved setup as JSON-ready data (SI units, degrees), without the tables and
    fields a setup leaves out by default (``bench``: the ideal bench; ``specimen.layers``:
    one solid; ``specimen.shear_legs`` 0: longitudinal paths only;
    ``specimen.exact_stack`` false: the listed paths), so a setup written before they
    existed reads, and digests, as it did."""
    data = config.model_dump(mode="json")
    if data.get("bench") is None:
        data.pop("bench", None)
    specimen = data.get("specimen")
    if isinstance(specimen, dict):
        for field, default in _SPECIMEN_DEFAULTS_LEFT_OUT.items():
            if field in specimen and specimen[field] == default:
                specimen.pop(field)
    return data


_SPECIMEN_DEFAULTS_LEFT_OUT: dict[str, Any] = {
    "layers": None,
    "shear_legs": 0,
    "exact_stack": False,
}
"""Specimen fields added after setups were first digested, with the default that leaves
them out of :func:`resolved_data`."""


def config_as_json(config: SetupConfig) -> str:
    """The resolved setup as pretty JSON (:func:`resolved_data`)."""
    return json.dumps(resolved_data(config), indent=2)
