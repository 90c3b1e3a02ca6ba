"""Building a :class:`~echocal.measurement.VirtualSetup` from a validated setup: every
problem collected with its field path, not only the first (see :mod:`echocal.setups`)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from echocal.constants import DEFAULT_CENTER_FREQUENCY
from echocal.echo import echo_model_names
from echocal.errors import ConfigError, DataFileError, EchocalError
from echocal.material_config import (
    build_material,
    build_medium,
)
from echocal.measurement.limits import PositionerLimits, limit_problems
from echocal.measurement.virtual import (
    ReceiverSettings,
    VirtualSetup,
    check_sample_count,
)
from echocal.setups.bench_schema import build_bench
from echocal.setups.fields import _SI_UNIT
from echocal.setups.schema import (
    _SHAPE_FIELDS,
    EchoConfig,
    GateConfig,
    PositionerConfig,
    PulseConfig,
    SetupConfig,
    SpecimenConfig,
    TransducerConfig,
)
from echocal.signal import Pulse, RecordingWindow, make_pulse, pulse_names
from echocal.signal.gates import TimeGate, check_gate, gates_by_name
from echocal.signal.pulses import parse_bandwidth, plausible_bandwidth, pulse_options
from echocal.signal.window import check_window
from echocal.specimen import (
    Cylinder,
    FinitePlane,
    Specimen,
    Sphere,
    TriangleMesh,
    builtin_specimen,
    specimen_names,
)
from echocal.specimen.interior import INTERIOR_SHAPES, Flaw, Interior, Layer
from echocal.transducer import Transducer, directivity_names, make_directivity
from echocal.units import (
    parse_quantity,
    plausible_frequency,
    plausible_sampling_rate,
)

# ---------------------------------------------------------------- building
# Each part of a setup is built and checked on its own, so that one run reports every
# problem; a check that needs another part (the transducer's piston needs the pulse's
# frequency, the reference echo needs everything) runs only when that part is valid.

_PULSE_KINDS = {
    "center_frequency": "frequency",
    "fs": "frequency",
    "phase": "angle",
    "length": "time",
    "start_time": "time",
}
"""Unit kind of the pulse options that carry one (the rest: numbers, names, paths)."""


class _FileProblem(str):
    """A problem with a file the setup refers to (mesh, pulse samples): a
    :class:`~echocal.errors.DataFileError` when it is the only kind of problem."""


def _problem(field: str, exc: Exception | str, options: tuple[str, ...] = ()) -> str:
    """``field: message`` of an error (or a message), the one form of every setup problem.

    A message that already names the field keeps its path, with a colon after it
    (``"pulse.fs must be finite"`` → ``"pulse.fs: must be finite"``); an option named first
    moves into the path (``pulse`` + ``"phase must be finite"`` → ``pulse.phase: must be
    finite``).  A missing data file stays a file problem (:class:`DataFileError`)."""
    message = str(exc)
    kind = _FileProblem if isinstance(exc, DataFileError) else str
    if message.startswith(field + " "):
        return kind(f"{field}: {message[len(field) + 1 :]}")
    if message.startswith((field + ".", field + ":")):
        return kind(message)
    for option in options:
        for sep in (": ", " "):
            if message.startswith(option + sep):
                return kind(f"{field}.{option}: {message[len(option) + len(sep) :]}")
    return kind(f"{field}: {message}")


def _pulse_params(name: str, extra: dict[str, Any], base_dir: Path) -> tuple[dict, list[str]]:
    """The pulse ``name``'s keyword parameters from the ``[pulse]`` table, in SI, and problems."""
    options = pulse_options(name)
    params: dict[str, Any] = {}
    problems = []
    for key, value in extra.items():
        field = f"pulse.{key}"
        if options is not None and key not in options:
            problems.append(f"{field}: unknown option for {name}; valid: {', '.join(options)}")
            continue
        try:
            if key == "file":  # relative to the setup file, as a mesh (absolute stays)
                params[key] = base_dir / Path(str(value))
            elif key == "bandwidth":
                continue  # after center_frequency: a percentage may refer to it
            elif key in _PULSE_KINDS and not isinstance(value, list):
                kind = _PULSE_KINDS[key]
                number = parse_quantity(field, value, kind, _SI_UNIT[kind])
                if key == "center_frequency":
                    plausible_frequency(field, number)
                elif key == "fs":
                    plausible_sampling_rate(field, number)
                params[key] = number
            else:
                params[key] = _parse_any(field, value) if isinstance(value, str) else value
        except EchocalError as exc:
            problems.append(_problem(field, exc))
    if "bandwidth" in extra and (options is None or "bandwidth" in options):
        value = extra["bandwidth"]
        fc = params.get("center_frequency", DEFAULT_CENTER_FREQUENCY)
        try:
            bandwidth = parse_bandwidth(name, value, fc, field="pulse.bandwidth")
            if isinstance(bandwidth, float):
                lobes = params.get("lobes", 4)
                plausible_bandwidth(
                    name,
                    bandwidth,
                    fc,
                    field="pulse.bandwidth",
                    bare=isinstance(value, int | float),
                    lobes=lobes if isinstance(lobes, int) and lobes > 0 else 4,
                )
            params["bandwidth"] = bandwidth
        except EchocalError as exc:
            problems.append(_problem("pulse.bandwidth", exc))
    return params, problems


def _parse_any(field: str, text: str) -> Any:
    """A string with any known unit → SI float; other strings (names, paths) unchanged."""
    for kind, default in _SI_UNIT.items():
        try:
            return parse_quantity(field, text, kind, default)
        except EchocalError:
            continue
    return text


def build_pulse(config: PulseConfig, base_dir: Path, *, where: str = "pulse") -> Pulse:
    """The pulse of a setup's ``[pulse]`` table, built as a setup builds it (file paths
    relative to ``base_dir``); every problem in one :class:`ConfigError` prefixed ``where``."""
    pulse, problems = _build_pulse(config, base_dir)
    if pulse is None:
        raise ConfigError(f"{where}: {'; '.join(problems)}")
    return pulse


def _build_pulse(config: PulseConfig, base_dir: Path) -> tuple[Pulse | None, list[str]]:
    if config.name not in pulse_names():
        return None, [
            f"pulse.name: unknown pulse {config.name!r}; choose one of: {', '.join(pulse_names())}"
        ]
    params, problems = _pulse_params(config.name, dict(config.model_extra or {}), base_dir)
    if problems:
        return None, problems
    try:
        return make_pulse(config.name, **params), []
    except EchocalError as exc:
        if isinstance(exc, DataFileError):  # the samples' file: missing or unreadable
            return None, [_FileProblem(f"pulse.file: {exc}")]
        return None, [_problem("pulse", exc, pulse_options(config.name) or ())]


def _ignored(field: str, reason: str) -> None:
    warnings.warn(f"{field} is ignored: {reason}", UserWarning, stacklevel=4)


def _build_specimen(config: SpecimenConfig, base_dir: Path) -> tuple[Specimen | None, list[str]]:
    given = [k for k in ("builtin", "shapes", "mesh") if getattr(config, k) is not None]
    if len(given) != 1:
        return None, [
            "specimen: give exactly one of builtin, shapes or mesh; "
            f"got {', '.join(given) if given else 'none'}"
        ]
    if "mesh_scale" in config.model_fields_set and config.mesh is None:
        _ignored("specimen.mesh_scale", f"it scales a mesh file; this specimen has {given[0]}")
    if config.builtin is not None:
        if config.builtin not in specimen_names():
            return None, [
                f"specimen.builtin: unknown specimen {config.builtin!r}; "
                f"choose one of: {', '.join(specimen_names())}"
            ]
        return builtin_specimen(config.builtin), []
    if config.mesh is not None:
        path = Path(config.mesh)
        path = path if path.is_absolute() else base_dir / path
        if not path.is_file():
            return None, [_FileProblem(f"specimen.mesh: mesh file not found: {path}")]
        try:
            mesh = TriangleMesh.load(path, scale=config.mesh_scale)
        except EchocalError as exc:
            return None, [_problem("specimen.mesh", exc)]
        return Specimen([mesh], name=config.name or path.stem), []
    shapes, problems = [], []
    if not config.shapes:
        problems.append("specimen.shapes: at least one shape is needed")
    for i, shape in enumerate(config.shapes or []):
        where = f"specimen.shapes.{i}"
        used = _SHAPE_FIELDS[shape.kind]
        for key in sorted(shape.model_fields_set - set(used) - {"kind", "center", "name"}):
            _ignored(f"{where}.{key}", f"a {shape.kind} takes {', '.join(used)}")
        kwargs: dict[str, Any] = {"center": shape.center, "name": shape.name or f"{shape.kind}{i}"}
        missing = [key for key in used if getattr(shape, key) is None]
        problems += [f"{where}.{key}: required for a {shape.kind}" for key in missing]
        if missing:
            continue
        kwargs.update({key: getattr(shape, key) for key in used})
        cls = {"plane": FinitePlane, "sphere": Sphere, "cylinder": Cylinder}[shape.kind]
        try:
            shapes.append(cls(**kwargs))
        except EchocalError as exc:
            problems.append(f"{where}: {exc}")
    if problems:
        return None, problems
    return Specimen(shapes, name=config.name or "custom"), []


_DIRECTIVITY_PARAMS = {
    "none": (),
    "gaussian": ("opening_angle",),
    "piston": ("radius", "frequency"),
}


def _build_transducer(
    config: TransducerConfig, pulse_frequency: float, c0: float
) -> tuple[Transducer | None, list[str]]:
    d = config.directivity
    where = "transducer.directivity"
    if d.model not in directivity_names():
        return None, [
            f"{where}.model: unknown directivity model {d.model!r}; "
            f"choose one of: {', '.join(directivity_names())}"
        ]
    used = _DIRECTIVITY_PARAMS.get(d.model, ())
    for key in sorted(d.model_fields_set - set(used) - {"model"}):
        takes = ", ".join(used) if used else "no parameters"
        _ignored(f"{where}.{key}", f"the {d.model} directivity takes {takes}")
    params: dict[str, float] = {}
    if d.model == "gaussian" and d.opening_angle is not None:
        params["opening_angle"] = d.opening_angle
    if d.model == "piston":
        params = {
            "radius": d.radius if d.radius is not None else config.width / 2,
            "frequency": d.frequency if d.frequency is not None else pulse_frequency,
            "sound_speed": c0,
        }
    try:
        directivity = make_directivity(d.model, **params)
    except EchocalError as exc:
        return None, [_problem(where, exc, ("directivity",))]
    try:
        return Transducer(
            width=config.width,
            height=config.height if config.height is not None else config.width,
            n_h=config.n_h,
            n_v=config.n_v if config.n_v is not None else config.n_h,
            pinhole_distance=config.pinhole_distance,
            focus=config.focus,
            aperture=config.aperture,
            directivity=directivity,
        ), []
    except EchocalError as exc:
        return None, [str(exc)]


def _build_parts(
    config: SetupConfig, base_dir: Path, *, invalid: frozenset[str] = frozenset()
) -> tuple[dict[str, Any], list[str]]:
    """Every part of the setup that can be built, and every problem found on the way.

    ``invalid`` names the sections whose schema already failed: they (and the checks
    that need them) are skipped, the others are still checked.
    """
    parts: dict[str, Any] = {}
    problems: list[str] = []

    def run(section: str, build: Callable[[], tuple[Any, list[str]]]) -> None:
        if section in invalid:
            return
        part, found = build()
        problems.extend(found)
        if part is not None and not found:
            parts[section] = part

    run("medium", lambda: build_medium(config.medium))
    medium = parts.get("medium")
    c0 = medium.longitudinal_speed if medium is not None else config.medium.sound_speed
    if "specimen" not in invalid and config.specimen.material is not None:
        material, found = build_material("specimen.material", config.specimen.material)
        problems.extend(found)
        parts["material"] = material
    if "specimen" not in invalid and config.specimen.layers:
        layers, found = _build_layers(config)
        problems.extend(found)
        if layers is not None:
            parts["layers"] = layers
            parts["material"] = layers[0].material  # the front face's reflection
    run("pulse", lambda: _build_pulse(config.pulse, base_dir))
    pulse = parts.get("pulse")
    # the piston's default frequency is the pulse's; a broken pulse leaves the default
    fc = pulse.center_frequency if pulse is not None else DEFAULT_CENTER_FREQUENCY
    run("specimen", lambda: _build_specimen(config.specimen, base_dir))
    run("transducer", lambda: _build_transducer(config.transducer, fc, c0))
    run("window", lambda: _wrap("window", lambda: RecordingWindow(**config.window.model_dump())))
    run(
        "noise",
        lambda: _wrap("noise", lambda: ReceiverSettings(**config.noise.model_dump())),
    )
    run("echo", lambda: _check_echo(config.echo))
    has_inside = config.specimen.thickness is not None or config.specimen.layers
    if "specimen" not in invalid and has_inside:
        run("interior", lambda: _build_interior(config, parts))
    elif "specimen" not in invalid:
        problems.extend(_inside_without_interior(config.specimen))
    run("positioner", lambda: _build_limits(config.positioner))
    if config.bench is not None:
        bench = config.bench
        run("bench", lambda: _wrap("bench", lambda: build_bench(bench, config.medium.temperature)))
    if "pulse" in parts and "window" in parts:
        for check in (check_sample_count, lambda p, w: check_window(w, p)):
            try:
                check(parts["pulse"], parts["window"])
            except EchocalError as exc:
                problems.append(_problem("window", exc, ("fs",)))
                parts.pop("window")
                break
    if "specimen" in parts and "positioner" in parts:
        problems.extend(_reference_problems(parts["specimen"], config.positioner))
    run("gates", lambda: _build_gates(config.gates, parts.get("window")))
    return parts, problems


def _build_gates(
    gates: list[GateConfig], window: RecordingWindow | None
) -> tuple[tuple[TimeGate, ...] | None, list[str]]:
    """The setup's named gates: names unique and not built-in, absolute ones inside the
    recording window (when it is valid)."""
    built: list[TimeGate] = []
    problems: list[str] = []
    for i, g in enumerate(gates):
        where = f"gates.{i}"
        try:
            gate = TimeGate(
                name=g.name, width=g.width, start=g.start, delay=g.delay, threshold=g.threshold
            )
            if window is not None:
                check_gate(gate, window, field=where)
        except EchocalError as exc:
            problems.append(_gate_problem(where, g.name, exc))
            continue
        built.append(gate)
    try:
        gates_by_name(built)
    except EchocalError as exc:
        problems.append(str(exc))
    return (None, problems) if problems else (tuple(built), [])


def _gate_problem(where: str, name: str, exc: Exception) -> str:
    """``gates.0 (NAME): message``: the gate's index and name, each once (the gate's own
    messages start with ``gates.0 NAME:`` or ``gate NAME:``)."""
    message = str(exc)
    for prefix in (f"{where} {name}: ", f"gate {name}: "):
        if message.startswith(prefix):
            message = message[len(prefix) :]
            break
    return f"{where} ({name}): {message}"


def _wrap(field: str, build: Callable[[], Any]) -> tuple[Any, list[str]]:
    try:
        return build(), []
    except EchocalError as exc:
        return None, [_problem(field, exc)]


def _build_layers(config: SetupConfig) -> tuple[tuple[Layer, ...] | None, list[str]]:
    """The layers of a layered plate (``specimen.layers``), top first, and the problems:
    each layer's material by itself; ``material`` and ``thickness`` belong to the layers."""
    spec = config.specimen
    assert spec.layers  # only called with layers
    for key in ("material", "thickness"):
        if getattr(spec, key) is not None:
            return None, [
                f"specimen.{key}: a layered plate gives each layer's {key} in "
                "[[specimen.layers]]; remove specimen." + key
            ]
    layers, problems = [], []
    for i, entry in enumerate(spec.layers):
        where = f"specimen.layers.{i}"
        material, found = build_material(f"{where}.material", entry.material)
        problems.extend(found)
        if material is None:
            continue
        try:
            layers.append(Layer(material, entry.thickness))
        except EchocalError as exc:
            problems.append(_problem(where, exc))
    return (None, problems) if problems else (tuple(layers), [])


def _inside_without_interior(spec: SpecimenConfig) -> list[str]:
    """A part without ``thickness`` or ``layers`` has no inside: its flaws, shear legs and
    exact stack are refused (they were dropped without a word); a ``back_wall_echoes``
    given is warned about as ignored."""
    given = [
        key for key in ("flaws", "shear_legs", "exact_stack") if getattr(spec, key)
    ]  # 0 shear legs or a false exact_stack ask for nothing
    if "back_wall_echoes" in spec.model_fields_set:
        _ignored("specimen.back_wall_echoes", "the part has no specimen.thickness or layers")
    return [
        f"specimen.{key}: the part has no inside (no specimen.thickness or "
        "[[specimen.layers]]); give one or leave it out"
        for key in given
    ]


def _build_interior(
    config: SetupConfig, parts: dict[str, Any]
) -> tuple[Interior | None, list[str]]:
    """The plate's thickness (or layers) and flaws, checked against the front face and
    the models."""
    spec = config.specimen
    material = parts.get("material")
    if (spec.material is not None or spec.layers) and material is None:
        return None, []  # the material's own problem is reported
    if spec.layers and "layers" not in parts:
        return None, []  # the layers' problems are reported
    if material is None or material.is_fluid:
        return None, [
            "specimen.thickness: an interior needs a solid specimen.material "
            '(e.g. material = "steel")'
        ]
    if config.echo.reflection != "wave":
        return None, [
            "specimen.thickness: echoes from inside the part need the wave model; "
            'set [echo] reflection = "wave"'
        ]
    specimen = parts.get("specimen")
    if specimen is None:
        return None, []
    if len(specimen) != 1 or not isinstance(specimen[0], (FinitePlane, Sphere, Cylinder)):
        return None, [f"specimen.thickness: {INTERIOR_SHAPES}"]
    try:
        flaws = tuple(
            Flaw(
                name=f.name,
                kind=f.kind,
                position=np.asarray(f.position),
                diameter=f.diameter,
                length=f.length,
                axis=np.asarray(f.axis),
            )
            for f in spec.flaws or ()
        )
        layers: tuple[Layer, ...] = parts.get("layers", ())
        thickness = sum(layer.thickness for layer in layers) if layers else spec.thickness
        assert thickness is not None  # only called with a thickness or layers
        interior = Interior(
            thickness, spec.back_wall_echoes, flaws, layers, spec.shear_legs, spec.exact_stack
        )
        interior.check_inside(specimen[0])
    except EchocalError as exc:
        return None, [_problem("specimen", exc)]
    return interior, []


def _check_echo(config: EchoConfig) -> tuple[EchoConfig | None, list[str]]:
    if config.reflection not in echo_model_names():
        return None, [
            f"echo.reflection: unknown echo model {config.reflection!r}; "
            f"choose one of: {', '.join(echo_model_names())}"
        ]
    if config.spacing is not None and config.reflection != "wave":
        _ignored(
            "echo.spacing",
            f"it sets the wave model's surface sampling; this is {config.reflection}",
        )
    return config, []


def _build_limits(config: PositionerConfig) -> tuple[PositionerLimits | None, list[str]]:
    axes = {n: getattr(config, n) for n in ("x", "y", "z", "azimuth", "coelevation")}
    problems = [f"positioner.{p}" for p in limit_problems(**axes)]
    return (None, problems) if problems else (PositionerLimits(**axes), [])


def _reference_problems(specimen: Specimen, config: PositionerConfig) -> list[str]:
    """The reference position must be outside every closed shape and above the part."""
    ref = np.asarray(config.reference_position, dtype=np.float64)
    where = "positioner.reference_position"
    shown = ", ".join(f"{1e3 * v:g}" for v in ref)
    inside = int(specimen.containing(ref[None])[0])
    if inside >= 0:
        shape = specimen[inside]
        return [
            f"{where}: ({shown}) mm is inside {shape.kind} {shape.name!r} of specimen "
            f"{specimen.name!r}; the probe must be outside the part — move it above the surface"
        ]
    if not bool(specimen.surface_below(ref[0], ref[1]).hit):
        return [
            f"{where}: ({shown}) mm is not above the specimen {specimen.name!r}; "
            "move it over the part"
        ]
    return []


def build_setup(config: SetupConfig, *, base_dir: Path | None = None, seed: int | None = None):
    """A :class:`~echocal.measurement.virtual.VirtualSetup` from a validated config.

    ``seed`` overrides the file's seed (noise reproducibility).  Raises
    :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    base_dir = Path.cwd() if base_dir is None else base_dir
    parts, problems = _build_parts(config, base_dir)
    if problems:
        _raise_problems(config.name, problems)
    return _assemble(config, parts, seed)


def _assemble(config: SetupConfig, parts: dict[str, Any], seed: int | None) -> VirtualSetup:
    try:
        return VirtualSetup(
            specimen=parts["specimen"],
            transducer=parts["transducer"],
            pulse=parts["pulse"],
            window=parts["window"],
            receiver=parts["noise"],
            reference_position=config.positioner.reference_position,
            sound_speed=parts["medium"].longitudinal_speed,
            medium=parts["medium"],
            material=parts.get("material"),
            interior=parts.get("interior"),
            reflection=config.echo.reflection,
            synthesis=config.echo.synthesis,
            wave_spacing=config.echo.spacing,
            limits=parts["positioner"],
            gates=parts.get("gates", ()),
            rng=seed if seed is not None else config.seed,
            name=config.name,
            bench=parts.get("bench"),
        )
    except (ConfigError, DataFileError):
        raise
    except EchocalError as exc:
        raise ConfigError(f"{config.name}: {exc}") from None


def _raise_problems(name_or_path: str | Path, problems: list[str]) -> NoReturn:
    only_files = problems and all(isinstance(p, _FileProblem) for p in problems)
    raise (DataFileError if only_files else ConfigError)(
        f"{name_or_path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)
    )
