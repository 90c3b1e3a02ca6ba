"""Wave-model benchmark: its cost against the thesis ray model and a compiled direct sum.

Run from the repository root::

    python benchmarks/bench_wave.py               # full run (minutes on 2 cores)
    python benchmarks/bench_wave.py --quick       # fewer repeats and frequencies
    python benchmarks/bench_wave.py --tilts-only  # only the tilt table (1.)

Measured in one process, as ratios: 1. and 3. in CPU time (``time.process_time``, every
thread), the others as wall-clock medians (``_common.measure``):

1. the tilt table: one noiseless A-scan of the wave and the ray model at 0, 2, 5, 10, 20
   and 30° off the normal, on ``immersion-5mhz`` (12.7 mm 5 MHz probe, 50 mm water path,
   4096 samples at 100 MHz), with the same probe 50 mm above the level ``flat-plate``
   (where the beam stays on the plate at 30°) and 50 mm above a 25 mm ball; where the
   image form applies also the wave model with the face rule only (the pair rule off), and
   on ``immersion-5mhz`` the compiled direct double Rayleigh sum (``_rayleigh_compiled``,
   numba) at the same distance and incidence, and |V(5 MHz)| from both; on planes the
   model reads its plane table (warm), over the ball its ball table (warm), beside the
   exact form or sum (the tables off), the first A-scan of a fresh table (the nodes it
   fills) and how many A-scans pay that back, and over the ball the first A-scan from a
   position 1 mm aside (its distance and angle between nodes);
2. one noiseless A-scan of ``immersion-5mhz`` near the optimum on the wave model against
   the ray model, its stages, and the Kirchhoff sum over the lit surface;
3. the wave model against the compiled direct double Rayleigh sum for a piston over a
   plane tilted 0.5° at 10 mm, the broadband echo's envelope peak from both (their
   agreement and the CPU-time ratio);
4. the thesis's 4 mm square probe on the wave model (a rectangle's closed-form SIR) against
   the ray model of the same setup, over a plate and over the thesis block;
5. the wave model's cost against its number of points (the slope of a log–log fit: 1 is
   linear): the Kirchhoff sum's surface samples (varying their spacing) and the image
   form's face nodes (varying the number of rings);
6. the figure of the README's physics section: the lobe of both models beside the piston's
   analytic limits (docs/physics-lobe.png, full runs only).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable, Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import scipy.signal  # noqa: E402
from _common import fmt_time, machine_info, markdown_table, measure  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "physics"))
import references as ref  # noqa: E402

from echocal import load_setup  # noqa: E402
from echocal.geometry import normal_to_orientation, orientation_frame, tilt_frame  # noqa: E402
from echocal.setups import setup_with_overrides  # noqa: E402
from echocal.signal.pulses import GaborPulse  # noqa: E402
from echocal.signal.window import RecordingWindow  # noqa: E402
from echocal.specimen.builtins import builtin_specimen  # noqa: E402
from echocal.specimen.casting import _as_shapes  # noqa: E402
from echocal.wave import PistonProbe, WaveEchoModel, image, pairs, threads  # noqa: E402

C = 1480.0


def ray_vs_wave(repeats: int) -> dict[str, float]:
    """Seconds per noiseless A-scan of immersion-5mhz, both models, near the optimum: the
    wave model as it runs (the image form over the plate, its nodes split over the cores
    when there are many) and on one thread, the image form's stages on one thread (finding
    the plane, face nodes' SIR + FFT, synthesis), and the Kirchhoff sum over the lit
    surface (``image_planes=False``, what curved parts use) for comparison."""
    ray = load_setup("immersion-5mhz-ray")
    wave = dataclasses.replace(ray, reflection="wave")
    pos = ray.reference_position[None]
    frames = tilt_frame(np.array([-1.7]), np.array([3.2]))
    t_ray = measure(lambda: ray.ideal_samples(pos, frames), repeats=20 * repeats, warmup=3)
    t_wave = measure(lambda: wave.ideal_samples(pos, frames), repeats=20 * repeats, warmup=1)
    model, shapes = wave.wave_model, _as_shapes(wave.specimen)
    kirchhoff = dataclasses.replace(model, image_planes=False)
    t_kirchhoff = measure(lambda: kirchhoff.ascans(shapes, pos, frames), repeats=repeats, warmup=1)
    plane = model.image_plane(shapes, pos[0], frames[0])
    assert plane is not None, "the plate fills the beam"
    spectrum, _ = model.image_spectrum(plane)
    _, _, area = kirchhoff.surface_samples(shapes, pos[0], frames[0])
    max_threads = threads.MAX_THREADS
    threads.MAX_THREADS = 1
    try:
        t_one = measure(lambda: wave.ideal_samples(pos, frames), repeats=20 * repeats, warmup=1)
        stages = {
            "find_plane_s": measure(
                lambda: model.image_plane(shapes, pos[0], frames[0]), repeats=20 * repeats
            ).median,
            "face_sir_fft_s": measure(
                lambda: model.image_spectrum(plane), repeats=20 * repeats
            ).median,
            "synthesis_s": measure(lambda: model.samples(spectrum), repeats=20 * repeats).median,
        }
        t_kirchhoff_one = measure(
            lambda: kirchhoff.ascans(shapes, pos, frames), repeats=repeats, warmup=1
        )
    finally:
        threads.MAX_THREADS = max_threads
    return {
        "ray_s": t_ray.median,
        "wave_s": t_wave.median,
        "ratio": t_wave.median / t_ray.median,
        "wave_one_thread_s": t_one.median,
        "ratio_one_thread": t_one.median / t_ray.median,
        "face_nodes": float(_face_nodes(model, plane)),
        **stages,
        "kirchhoff_s": t_kirchhoff.median,
        "kirchhoff_one_thread_s": t_kirchhoff_one.median,
        "kirchhoff_ratio": t_kirchhoff.median / t_ray.median,
        "surface_samples": float(np.count_nonzero(area)),
    }


def _face_nodes(model: WaveEchoModel, plane: image.ImagePlane) -> int:
    """The image form's number of face nodes at ``plane``."""
    return int(model.image_nodes(plane)[1].size)


def steel_plate(repeats: int, ray_s: float) -> dict[str, float]:
    """Seconds per noiseless A-scan of immersion-steel-plate (front wall and three back-wall
    echoes, the back walls through :mod:`echocal.wave.interior`), and its ratio to the ray
    model's immersion-5mhz A-scan ``ray_s`` [s] (a plate's interior needs the wave model)."""
    wave = load_setup("immersion-steel-plate")
    pos = wave.reference_position[None]
    frames = tilt_frame(np.array([0.3]), np.array([0.0]))
    t_wave = measure(lambda: wave.ideal_samples(pos, frames), repeats=repeats, warmup=1)
    return {"wave_s": t_wave.median, "ratio": t_wave.median / ray_s}


def square_probe(repeats: int) -> dict[str, float]:
    """Seconds per noiseless A-scan of the thesis's 4 mm square probe 20 mm above a level
    plate, 4° off the normal: the wave model (a rectangle's image form) against the thesis's
    lambertian ray model of the same setup, and the ray model over the thesis block
    against the wave model there (facets and edges: the Kirchhoff sum)."""
    plate = setup_with_overrides("thesis", specimen="flat-plate")
    pos = np.array([[0.0, 0.0, 0.02]])
    frames = tilt_frame(np.array([4.0]), np.array([0.0]))
    out: dict[str, float] = {}
    for label, ray in (("plate", plate), ("block", load_setup("thesis"))):
        wave = dataclasses.replace(ray, reflection="wave")
        where = pos if label == "plate" else ray.reference_position[None]
        t_ray = measure(lambda r=ray, w=where: r.ideal_samples(w, frames), repeats=20 * repeats)
        t_wave = measure(
            lambda s=wave, w=where: s.ideal_samples(w, frames), repeats=5 * repeats, warmup=1
        )
        out[f"{label}_ray_s"] = t_ray.median
        out[f"{label}_wave_s"] = t_wave.median
        out[f"{label}_ratio"] = t_wave.median / t_ray.median
    return out


TILTS_DEG = (0.0, 2.0, 5.0, 10.0, 20.0, 30.0)


def _cpu_per_call(fn: Callable[[], object], min_seconds: float) -> float:
    """[s] CPU time (``time.process_time``, every thread of the process) per call of
    ``fn``: one untimed call, then calls until ``min_seconds`` of CPU time have passed."""
    fn()
    calls = 0
    start = time.process_time()
    while True:
        fn()
        calls += 1
        spent = time.process_time() - start
        if spent >= min_seconds:
            return spent / calls


def tilt_table(
    min_seconds: float,
    n_freq: int,
    max_direct_tilt: float = 90.0,
    setups: tuple[str, ...] = (),
) -> list[dict[str, float | str]]:
    """CPU time per noiseless A-scan of the wave and ray models at :data:`TILTS_DEG` off
    the normal, on ``immersion-5mhz`` (the plate: tilted from its normal, along the
    azimuth of its tilt, at the setup's reference position) and with the same 12.7 mm
    5 MHz probe 50 mm above the top of a 25 mm ball (the beam tilted from the vertical;
    the Kirchhoff sum), and on the plate the compiled direct double Rayleigh sum
    (``_rayleigh_compiled``) over ``n_freq`` frequencies of the pulse's band at the same
    distance and incidence (up to ``max_direct_tilt`` [deg]), with the agreement of |V| at
    5 MHz; and the same probe 50 mm above the level ``flat-plate``.  Where the image form
    applies, also the wave model with the face rule only (the pair rule off: the model
    before it), the face rule's nodes and the pair rule's pairs.  ``setups``: only the
    rows of these setups (their labels' first words: ``immersion-5mhz``, ``plate``,
    ``sphere``); empty, all."""
    import _rayleigh_compiled as direct

    rows: list[dict[str, float | str]] = []
    plate_ray = load_setup("immersion-5mhz-ray")
    sphere_ray = setup_with_overrides("immersion-5mhz-ray", specimen="sphere")
    level_ray = setup_with_overrides("immersion-5mhz-ray", specimen="flat-plate")
    cases = (
        ("immersion-5mhz", plate_ray, plate_ray.reference_position),
        ("12.7 mm over a level plate", level_ray, np.array([0.0, 0.0, 0.05])),
        ("12.7 mm over a sphere", sphere_ray, np.array([0.0, 0.0, 0.05])),
    )
    for label, ray, position in cases:
        if setups and _setup_key(label) not in setups:
            continue
        wave = dataclasses.replace(ray, reflection="wave")
        model, shapes = wave.wave_model, _as_shapes(wave.specimen)
        pos = position[None]
        if label == "immersion-5mhz":
            level = tilt_frame(np.array([0.0]), np.array([0.0]))[0]
            normal_plane = model.image_plane(shapes, position, level)
            assert normal_plane is not None, "the plate fills the beam"
            basis = np.stack([level[:, 0], level[:, 1], -level[:, 2]])  # world → aperture
            normal = basis.T @ normal_plane.normal  # towards the probe, in the world frame
            azimuth, coelevation = (float(v) for v in normal_to_orientation(normal))
        else:
            azimuth, coelevation = 0.0, 0.0
        for tilt in TILTS_DEG:
            frames = orientation_frame(np.array([azimuth]), np.array([coelevation + tilt]))
            t_ray = _cpu_per_call(lambda r=ray, p=pos, f=frames: r.ideal_samples(p, f), min_seconds)
            t_wave = _cpu_per_call(
                lambda w=wave, p=pos, f=frames: w.ideal_samples(p, f), min_seconds
            )
            row: dict[str, float | str] = {
                "setup": label,
                "tilt_deg": tilt,
                "ray_s": t_ray,
                "wave_s": t_wave,
                "wave_over_ray": t_wave / t_ray,
            }
            plane = model.image_plane(shapes, position, frames[0], edges=True)  # as A-scans
            if plane is not None and model._plane_tables:
                row.update(_cold(wave, pos, frames, t_wave, min_seconds))
            elif label.endswith("sphere"):
                row.update(_cold(wave, pos, frames, t_wave, min_seconds))
                row.update(_aside(wave, pos, frames))
            if plane is not None:
                row["face_nodes"] = float(_face_nodes(model, plane))
                row["pairs"] = float(_pairs(model, plane)) if model._pairs_pay(plane) else 0.0
                exact = _exact_setup(wave)
                with _face_rule():
                    row["wave_face_s"] = _cpu_per_call(
                        lambda w=exact, p=pos, f=frames: w.ideal_samples(p, f), min_seconds
                    )
            with_direct = label == "immersion-5mhz" and tilt <= max_direct_tilt
            if plane is not None and with_direct:
                row["incidence_deg"] = math.degrees(math.asin(plane.sin_incidence))
                row.update(_direct_sum(model, plane, n_freq, direct))
            rows.append(row)
    return rows


def _exact_setup(setup: Any) -> Any:
    """A copy of ``setup`` whose wave model takes the exact form and sum at every pose (its
    tables off)."""
    exact = dataclasses.replace(setup)
    exact.__dict__["wave_model"] = dataclasses.replace(setup.wave_model, tables=False)
    return exact


@contextlib.contextmanager
def _no_disk_nodes() -> Iterator[None]:
    """An empty disk cache for the tables' nodes (``ECHOCAL_CACHE_DIR`` a fresh temporary
    folder), so that a fresh model's first A-scan computes its nodes instead of reading
    those an earlier model of the run wrote."""
    import tempfile

    from echocal.signal.detector_cache import CACHE_ENV

    before = os.environ.get(CACHE_ENV)
    with tempfile.TemporaryDirectory() as folder:
        os.environ[CACHE_ENV] = folder
        try:
            yield
        finally:
            if before is None:
                del os.environ[CACHE_ENV]
            else:
                os.environ[CACHE_ENV] = before


def _nodes_filled(model: WaveEchoModel) -> int:
    """How many nodes ``model``'s plane and ball tables hold."""
    planes = {id(t): t.table.nodes_filled for t in model._plane_tables.values()}
    balls = sum(table.nodes_filled for table, _ in model._ball_tables.values())
    return sum(planes.values()) + balls


def _cold(
    wave: Any, pos: np.ndarray, frames: np.ndarray, t_warm: float, min_seconds: float
) -> dict[str, float]:
    """The tables' costs at one pose: the exact form's (or sum's) A-scan (``exact_s``), the
    first A-scan of a fresh model with the nodes on disk (``disk_s``: the warm runs wrote
    them) and with an empty disk cache (``cold_s``: the nodes it fills, ``cold_nodes``, at
    about ``node_s`` each), and how many A-scans at new poses of the same cells pay the
    fill back against the exact form (``payback``: (cold − warm)/(exact − warm))."""
    exact = _exact_setup(wave)
    t_exact = _cpu_per_call(lambda: exact.ideal_samples(pos, frames), min_seconds)

    def first_scan() -> tuple[float, int]:
        fresh = dataclasses.replace(wave)
        start = time.process_time()
        fresh.ideal_samples(pos, frames)
        return time.process_time() - start, _nodes_filled(fresh.wave_model)

    t_disk, _ = first_scan()
    with _no_disk_nodes():
        t_cold, nodes = first_scan()
    saving = t_exact - t_warm
    return {
        "exact_s": t_exact,
        "disk_s": t_disk,
        "cold_s": t_cold,
        "cold_nodes": float(nodes),
        "node_s": (t_cold - t_warm) / max(nodes, 1),
        "payback": (t_cold - t_warm) / saving if saving > 0.0 else math.inf,
    }


def _aside(wave: Any, pos: np.ndarray, frames: np.ndarray) -> dict[str, float]:
    """Over the ball, after one A-scan of a fresh model (its table's distance grid then
    holds that pose's distance: 1–4 nodes), the first A-scan from a position 1 mm aside,
    whose distance and angle lie between nodes (``aside_s``; ``aside_nodes`` new nodes,
    up to 16)."""
    fresh = dataclasses.replace(wave)
    with _no_disk_nodes():
        fresh.ideal_samples(pos, frames)
        nodes = _nodes_filled(fresh.wave_model)
        start = time.process_time()
        fresh.ideal_samples(pos + np.array([[1e-3, 0.0, 0.0]]), frames)
        aside = time.process_time() - start
    return {"aside_s": aside, "aside_nodes": float(_nodes_filled(fresh.wave_model) - nodes)}


SETUP_KEYS = ("immersion-5mhz", "plate", "sphere")
"""The tilt table's setups as ``--setups`` names them."""


def _setup_key(label: str) -> str:
    """The :data:`SETUP_KEYS` name of a tilt-table row's setup ``label``."""
    return next(key for key in SETUP_KEYS if key in label)


@contextlib.contextmanager
def _face_rule() -> Iterator[None]:
    """The image form with the face rule only (the pair rule off), for the before/after
    columns of the tilt table."""
    pays = pairs.pays
    pairs.pays = lambda *args: False  # type: ignore[assignment]
    try:
        yield
    finally:
        pairs.pays = pays


def _pairs(model: WaveEchoModel, plane: image.ImagePlane) -> int:
    """The pair rule's number of pairs at ``plane``."""
    half = pairs.pair_count(model._plane_bandwidth(plane), model.probe.radius) // 2
    return half * (half + 1) // 2


def _direct_sum(
    model: WaveEchoModel, plane: image.ImagePlane, n_freq: int, direct: Any
) -> dict[str, float]:
    """CPU time [s] of the compiled direct double Rayleigh sum at ``plane``'s distance and
    incidence over ``n_freq`` frequencies (the pulse's band, through 5 MHz), and |V(5 MHz)|
    from it and from the wave model's image form."""
    a, d, c = model.probe.radius, plane.axis_distance, model.sound_speed
    tilt = math.degrees(math.asin(plane.sin_incidence))
    lo, hi = model.pulse.bandwidth_6db
    step = max(5e6 - 0.7 * lo, 1.3 * hi - 5e6) / max(1, n_freq // 2)
    freqs = 5e6 + step * (np.arange(n_freq) - n_freq // 2)
    direct.pulse_echo(a, freqs[:1], d, tilt, c)  # compiled (or loaded) before the timing
    start = time.process_time()
    v = direct.pulse_echo(a, freqs, d, tilt, c)
    t_direct = time.process_time() - start
    spectrum, _ = model.image_spectrum(plane)
    f = model.frequencies
    i = int(np.argmin(np.abs(f - 5e6)))
    v_wave = abs(spectrum[i] * model._grid[1] / model.pulse.spectrum(f[i : i + 1])[0])
    v_direct = abs(v[n_freq // 2])
    return {
        "direct_s": t_direct,
        "direct_frequencies": float(n_freq),
        "v5_wave": float(v_wave),
        "v5_direct": float(v_direct),
    }


def _payback(row: dict[str, float | str]) -> str:
    """The tilt table's payback cell: "—" off the table, "never" where the exact form is
    no dearer than the warm table."""
    if "payback" not in row:
        return "—"
    payback = float(row["payback"])
    return f"{payback:.0f}" if math.isfinite(payback) else "never"


def tilt_markdown(rows: list[dict[str, float | str]]) -> str:
    """The tilt table as Markdown."""
    body = []
    for r in rows:
        direct = r.get("direct_s")
        before = r.get("wave_face_s")
        agree = (
            "—" if direct is None else f"{float(r['v5_wave']):.4g} / {float(r['v5_direct']):.4g}"
        )
        exact = r.get("exact_s")
        aside = r.get("aside_s")
        body.append(
            [
                r["setup"],
                f"{float(r['tilt_deg']):.0f}",
                fmt_time(float(r["ray_s"])),
                fmt_time(float(r["wave_s"])),
                f"{float(r['wave_over_ray']):.1f}x",
                "—" if exact is None else fmt_time(float(exact)),
                "—" if exact is None else f"{float(exact) / float(r['ray_s']):.1f}x",
                "—" if exact is None else f"{fmt_time(float(r['cold_s']))} ({r['cold_nodes']:.0f})",
                "—" if exact is None else fmt_time(float(r["disk_s"])),
                _payback(r),
                "—" if aside is None else f"{fmt_time(float(aside))} ({r['aside_nodes']:.0f})",
                "—" if before is None else fmt_time(float(before)),
                "—" if before is None else f"{float(before) / float(r['ray_s']):.1f}x",
                "—" if before is None else f"{r['pairs']:.0f} / {r['face_nodes']:.0f}",
                "—" if direct is None else fmt_time(float(direct)),
                "—" if direct is None else f"{float(direct) / float(r['wave_s']):.0f}x",
                agree,
            ]
        )
    header = [
        "setup",
        "tilt [°]",
        "ray (CPU)",
        "wave (CPU)",
        "wave / ray",
        "exact form or sum (CPU)",
        "exact / ray",
        "first A-scan, fresh table (nodes)",
        "first A-scan, nodes on disk",
        "A-scans to pay the fill back",
        "1 mm aside: first A-scan (nodes)",
        "wave, face rule (CPU)",
        "face rule / ray",
        "pairs / face nodes",
        "direct sum (CPU)",
        "direct / wave",
        "|V(5 MHz)| wave / direct",
    ]
    return markdown_table(header, body)


def _envelope(x: np.ndarray) -> float:
    return float(np.abs(scipy.signal.hilbert(x)).max())


def wave_vs_rayleigh(accuracy: float, n_freq: int) -> dict[str, float]:
    """The broadband echo of a 12.7 mm probe over a plane tilted 0.5° at 10 mm, relative to
    normal incidence, from the wave model and from the compiled direct double Rayleigh sum
    (``_rayleigh_compiled``) over ``n_freq`` frequencies: CPU time of both (each computes
    the tilted and the normal echo) and their agreement."""
    import _rayleigh_compiled as direct

    a, d, tilt = 6.35e-3, 0.010, 0.5
    pulse = GaborPulse(center_frequency=5e6, bandwidth=60)
    sigma_t = 1.0 / math.sqrt(2.0 * pulse.alpha)
    window = RecordingWindow(fs=100e6, start=2 * d / C - 4e-6, n_samples=1024)
    model = WaveEchoModel(probe=PistonProbe(radius=a), pulse=pulse, window=window, sound_speed=C)
    plane = tuple(builtin_specimen("flat-plate"))
    pos = np.array([[0.0, 0.0, d]])

    def wave_ratio() -> float:
        tilted = model.ascans(plane, pos, tilt_frame(np.array([tilt]), np.array([0.0])))[0]
        normal = model.ascans(plane, pos, tilt_frame(np.array([0.0]), np.array([0.0])))[0]
        return _envelope(tilted) / _envelope(normal)

    t_wave = _cpu_per_call(wave_ratio, 0.2)
    freqs = np.linspace(1.5e6, 8.5e6, n_freq)
    spectrum = ref.gabor_spectrum(freqs, 5e6, sigma_t)

    def rayleigh_ratio() -> float:
        v = np.array(
            [direct.pulse_echo(a, freqs, d, t, C, accuracy=accuracy) for t in (tilt, 0.0)]
        ).T
        peaks = ref.pulse_echo_envelope_peak(v, freqs, spectrum)
        return float(peaks[0] / peaks[1])

    rayleigh_ratio()  # compiles the reference
    start = time.process_time()
    brute = rayleigh_ratio()
    t_brute = time.process_time() - start
    got = wave_ratio()
    return {
        "wave_s": t_wave,
        "rayleigh_s": t_brute,
        "speedup": t_brute / t_wave,
        "wave_relative_echo": got,
        "rayleigh_relative_echo": brute,
        "relative_difference": got / brute - 1.0,
        "frequencies": float(n_freq),
    }


def scaling(repeats: int) -> dict[str, object]:
    """Cost against the number of points for both forms near the optimum: the Kirchhoff
    sum's surface samples (spacing 0.4 … 1.2 mm) and the image form's face nodes (forcing
    8 … 64 rings through :data:`echocal.wave.image.MIN_RINGS`)."""
    base = load_setup("immersion-5mhz")
    pos = base.reference_position[None]
    frames = tilt_frame(np.array([-1.7]), np.array([3.2]))
    shapes = _as_shapes(base.specimen)
    rows = []
    for spacing in (0.4e-3, 0.6e-3, 0.8e-3, 1.2e-3):
        setup = dataclasses.replace(base, wave_spacing=spacing)
        model = dataclasses.replace(setup.wave_model, image_planes=False)
        samples = int(np.count_nonzero(model.surface_samples(shapes, pos[0], frames[0])[2]))
        t = measure(lambda m=model: m.ascans(shapes, pos, frames), repeats=repeats, warmup=1)
        rows.append((spacing, samples, t.median))
    model = base.wave_model
    plane = model.image_plane(shapes, pos[0], frames[0])
    assert plane is not None
    image_rows = []
    min_rings = image.MIN_RINGS
    try:
        for rings in (8, 16, 32, 64):
            image.MIN_RINGS = rings
            nodes = _face_nodes(model, plane)
            t = measure(lambda: model.image_spectrum(plane), repeats=5 * repeats, warmup=1)
            image_rows.append((rings, nodes, t.median))
    finally:
        image.MIN_RINGS = min_rings
    return {
        "rows": rows,
        "slope": _slope(rows),
        "image_rows": image_rows,
        "image_slope": _slope(image_rows),
    }


def _slope(rows: list[tuple[float, int, float]]) -> float:
    """The slope of log(seconds) against log(points): 1 is linear."""
    n = np.log([r[1] for r in rows])
    t = np.log([r[2] for r in rows])
    return float(np.polyfit(n, t, 1)[0])


def lobe_figure(path: Path) -> dict[str, float]:
    from echocal.lobe import echo_lobe
    from echocal.plots import save_figure
    from echocal.plots.lobe import plot_lobe

    ray = load_setup("immersion-5mhz-ray")
    lobes = [echo_lobe(ray), echo_lobe(dataclasses.replace(ray, reflection="wave"))]
    save_figure(
        plot_lobe(lobes, title="immersion-5mhz: echo lobe of the ray and wave models"), path
    )
    return {lobe.model: lobe.minus6db_deg for lobe in lobes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, cheaper reference")
    parser.add_argument("--smoke", action="store_true", help="one repeat of everything cheap")
    parser.add_argument("--json", type=Path, help="write every number to this file")
    parser.add_argument("--tilts-only", action="store_true", help="only the tilt table")
    parser.add_argument(
        "--setups",
        nargs="+",
        choices=SETUP_KEYS,
        default=[],
        help="the tilt table's rows for these setups only (default: all)",
    )
    args = parser.parse_args()
    cheap = args.quick or args.smoke
    repeats = 1 if args.smoke else (3 if args.quick else 7)
    result: dict[str, object] = {"machine": machine_info(("numpy", "scipy", "numba"))}
    table = tilt_table(
        0.05 if cheap else 0.5,
        8 if args.smoke else (12 if args.quick else 32),
        max_direct_tilt=10.0 if args.smoke else 90.0,  # the direct sum at 20°: ~10 s
        setups=tuple(args.setups),
    )
    result["tilt_table"] = table
    print(tilt_markdown(table))
    worst = max(float(r["wave_over_ray"]) for r in table)
    print(f"HEADLINE wave / ray CPU time at 0-30 deg, both setups: at most {worst:.1f}x")
    tabled = [r for r in table if "exact_s" in r and "aside_s" not in r]
    if tabled:
        exact_worst = max(float(r["exact_s"]) / float(r["ray_s"]) for r in tabled)
        payback = max(p for p in (float(r["payback"]) for r in tabled) if math.isfinite(p))
        print(
            f"HEADLINE wave (plane table, warm) / ray at most "
            f"{max(float(r['wave_over_ray']) for r in tabled):.1f}x on planes (exact form "
            f"{exact_worst:.1f}x); a fresh cell's fill is paid back after at most "
            f"{payback:.0f} A-scans in it (never where the exact form is as cheap)"
        )
    balls = [r for r in table if "aside_s" in r]
    if balls:
        print(
            "HEADLINE over the ball, the table (warm) / ray: at most "
            f"{max(float(r['wave_over_ray']) for r in balls):.1f}x (the exact sum at most "
            f"{max(float(r['exact_s']) / float(r['ray_s']) for r in balls):.0f}x); a fresh "
            f"table's first A-scan {fmt_time(min(float(r['cold_s']) for r in balls))}–"
            f"{fmt_time(max(float(r['cold_s']) for r in balls))} CPU, paid back after "
            f"{max(float(r['payback']) for r in balls):.0f} A-scans at most; from 1 mm "
            f"aside {fmt_time(max(float(r['aside_s']) for r in balls))} at most"
        )
    if args.tilts_only:
        if args.json:
            args.json.write_text(json.dumps(result, indent=2, default=float), encoding="utf-8")
        return
    speed = ray_vs_wave(repeats)
    result["ray_vs_wave"] = speed
    print(
        f"HEADLINE one A-scan, immersion-5mhz: ray {fmt_time(speed['ray_s'])}, wave "
        f"{fmt_time(speed['wave_s'])}: the wave model costs {speed['ratio']:.1f}x the ray model"
    )
    print(
        f"HEADLINE on one thread: wave {fmt_time(speed['wave_one_thread_s'])} "
        f"({speed['ratio_one_thread']:.1f}x): find the plane {fmt_time(speed['find_plane_s'])}, "
        f"{speed['face_nodes']:.0f} face nodes' SIR + FFT {fmt_time(speed['face_sir_fft_s'])}, "
        f"synthesis {fmt_time(speed['synthesis_s'])}"
    )
    print(
        f"HEADLINE the Kirchhoff sum (curved parts): {fmt_time(speed['kirchhoff_s'])} "
        f"({speed['kirchhoff_ratio']:.1f}x the ray model; one thread "
        f"{fmt_time(speed['kirchhoff_one_thread_s'])}), {speed['surface_samples']:.0f} samples"
    )
    plate = steel_plate(repeats, speed["ray_s"])
    result["steel_plate"] = plate
    print(
        f"HEADLINE one A-scan, immersion-steel-plate (front wall + 3 back-wall echoes): "
        f"wave {fmt_time(plate['wave_s'])}, {plate['ratio']:.1f}x the ray model's A-scan"
    )
    square = square_probe(repeats)
    result["square_probe"] = square
    print(
        f"HEADLINE thesis 4 mm square probe, wave vs ray: over a plate "
        f"{fmt_time(square['plate_wave_s'])} vs {fmt_time(square['plate_ray_s'])} "
        f"({square['plate_ratio']:.1f}x); over the thesis block "
        f"{fmt_time(square['block_wave_s'])} vs {fmt_time(square['block_ray_s'])} "
        f"({square['block_ratio']:.1f}x)"
    )
    brute = wave_vs_rayleigh(accuracy=0.5 if cheap else 1.0, n_freq=8 if args.smoke else 24)
    result["wave_vs_rayleigh"] = brute
    print(
        f"HEADLINE 0.5 deg tilt at 10 mm (CPU): wave {fmt_time(brute['wave_s'])}, compiled "
        f"direct Rayleigh sum {fmt_time(brute['rayleigh_s'])} ({brute['speedup']:.0f}x); "
        f"relative echo "
        f"{brute['wave_relative_echo']:.4f} vs {brute['rayleigh_relative_echo']:.4f} "
        f"({100 * brute['relative_difference']:+.2f} %)"
    )
    if not args.smoke:
        scale = scaling(repeats)
        result["scaling"] = scale
        for spacing, samples, seconds in scale["rows"]:  # type: ignore[union-attr]
            print(f"  spacing {1e3 * spacing:.1f} mm: {samples} samples, {fmt_time(seconds)}")
        for rings, nodes, seconds in scale["image_rows"]:  # type: ignore[union-attr]
            print(f"  image form, {rings} rings: {nodes} face nodes, {fmt_time(seconds)}")
        print(
            f"HEADLINE cost ~ samples^{scale['slope']:.2f} (Kirchhoff), "
            f"~ nodes^{scale['image_slope']:.2f} (image form) (1 = linear)"
        )
    if not cheap:
        widths = lobe_figure(ROOT / "docs" / "physics-lobe.png")
        result["minus6db_deg"] = widths
        print(f"HEADLINE -6 dB half-widths: {widths}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2, default=float), encoding="utf-8")


if __name__ == "__main__":
    main()
