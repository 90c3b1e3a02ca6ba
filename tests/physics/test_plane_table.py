"""The wave model's plane table (``echocal.wave.plane_table``) against the exact image form.

Under a flat disc or a bowl the model reads an infinite plane's echo from a table over the
plane's normal distance h and incidence α, filled lazily with the exact form and
interpolated (cubic in 1/h and α, after demodulating the two-way delay 2h/c).  The
reference is the exact form itself (``WaveEchoModel(tables=False)``, its own accuracy held by
test_wave_image.py, test_wave_pairs*.py and test_wave_plate_edge.py), at poses off the
table's nodes drawn with seeds not used to choose the table's steps (those were tuned on a
12.7 mm 5 MHz probe at 20, 50 and 100 mm, seed 1).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from echocal.signal.pulses import GaborPulse
from echocal.signal.window import RecordingWindow
from echocal.wave import PistonProbe, RectangularProbe, WaveEchoModel, image
from echocal.wave import model as model_module
from echocal.wave import plane_table as plane_table_module

C = 1480.0
MM = 1e-3


def _model(
    radius: float,
    f0: float,
    h: float,
    curvature: float | None = None,
    fs: float = 100e6,
    **kw: object,
) -> WaveEchoModel:
    """A wave model whose window (41 µs at ``fs`` [Hz]) holds the echo of a plane ``h`` [m]
    away; ``kw`` go to :class:`~echocal.wave.WaveEchoModel`."""
    start = max(0.0, 2 * h / C - 10e-6)
    window = RecordingWindow(fs=fs, start=start, n_samples=round(4096 * fs / 100e6))
    return WaveEchoModel(
        probe=PistonProbe(radius=radius, curvature=curvature),
        pulse=GaborPulse(center_frequency=f0, bandwidth=60),
        window=window,
        sound_speed=C,
        **kw,  # type: ignore[arg-type]
    )


def _plane(h: float, alpha: float, azimuth: float) -> image.ImagePlane:
    """The plane at normal distance ``h`` [m] from the face centre, incidence ``alpha``
    [rad], tilted towards ``azimuth`` [rad]."""
    s = math.sin(alpha)
    normal = np.array([s * math.cos(azimuth), s * math.sin(azimuth), -math.cos(alpha)])
    return image.ImagePlane(point=np.array([0.0, 0.0, h / math.cos(alpha)]), normal=normal)


def _error(model: WaveEchoModel, plane: image.ImagePlane) -> float:
    """max |table − exact| over the A-scan, relative to the exact echo's peak."""
    got = model.samples(model.image_spectrum(plane)[0])
    want = model.samples(model._exact_image_spectrum(plane)[0])
    return float(np.abs(got - want).max() / np.abs(want).max())


# hold-out geometries: other radii, frequencies, distances and a bowl than the tuning's
HOLD_OUT = [
    (3.0 * MM, 5e6, 35 * MM, None, (0.2, 1.7, 6.0)),
    (9.5 * MM, 2.25e6, 150 * MM, None, (0.2, 1.7, 12.0)),
    (6.35 * MM, 5e6, 15 * MM, 60 * MM, (1.0, 5.0, 12.0)),
    (4.0 * MM, 7.5e6, 70 * MM, None, (0.7, 6.0)),
]


@pytest.mark.parametrize(("radius", "f0", "h", "curvature", "tilts"), HOLD_OUT)
def test_table_equals_the_exact_form_at_off_node_poses(
    radius: float,
    f0: float,
    h: float,
    curvature: float | None,
    tilts: tuple[float, ...],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Random poses within two steps of the nominal distance and tilt, any azimuth (seed
    2026): against the exact form on a 4× finer time grid, the table's A-scan is off by at
    most 5·10⁻⁴ of the echo's peak more than the exact form's own error, and it is within
    10⁻³ of the exact form itself.

    The cubic interpolation's own error is ≤ 10⁻⁴ (measured where the exact form is smooth:
    halving both steps moved the error by < 2·10⁻⁵ at 0.5–3°), a tenth of the tightest
    physics tolerance on a disc's plane echo (10⁻³, test_wave_image.py).  The rest is the
    exact form's own quadrature and B-spline noise from pose to pose, which no interpolant
    follows: 1–7·10⁻⁴ of the peak at these poses (measured against the finer grid; the
    table's error against it is no larger on average).  A bowl near its focus, whose
    spatial impulse response has the sharpest edges, has 2–6·10⁻³ of such noise (its |V|
    tolerance in test_wave_image.py is 5·10⁻³): the bowl here is inside its focus."""
    model = _model(radius, f0, h, curvature, fs=400e6)
    coarse = model._grid[1]
    monkeypatch.setattr(model_module, "_GRID_OVERSAMPLING", 4.0 * model_module._GRID_OVERSAMPLING)
    fine = _model(radius, f0, h, curvature, fs=400e6, tables=False)
    assert fine._grid[1] < 0.3 * coarse
    table = model._plane_tables[False].table
    rng = np.random.default_rng(2026)
    for tilt in tilts:
        for _ in range(3):
            u = 1.0 / h + rng.uniform(-2.0, 2.0) * table.u.step
            alpha = abs(math.radians(tilt) + rng.uniform(-2.0, 2.0) * table.v.step)
            plane = _plane(1.0 / u, alpha, rng.uniform(0.0, 2.0 * math.pi))
            assert model._plane_tables[False](plane) is not None  # the table answers
            got = model.samples(model.image_spectrum(plane)[0])
            exact = model.samples(model._exact_image_spectrum(plane)[0])
            reference = fine.samples(fine.image_spectrum(plane)[0])
            peak = np.abs(reference).max()
            pose = f"tilt {math.degrees(alpha):.3f}°, h {1e3 / u:.3f} mm"
            added = (np.abs(got - reference).max() - np.abs(exact - reference).max()) / peak
            assert added < 5e-4, f"{pose}: {added:.1e}"
            error = np.abs(got - exact).max() / np.abs(exact).max()
            assert error < 1e-3, f"{pose}: {error:.1e}"
    assert table.nodes_filled > 0


def test_tabled_nodes_are_demodulated() -> None:
    """What the table interpolates is the spectrum times e^{iω(2h/c − t₀)}: neighbouring
    nodes along 1/h (0.46 mm apart at 50 mm, three wavelengths of two-way path) differ by
    a few % of their size, where the raw spectra's phases differ by several turns."""
    model = _model(6.35 * MM, 5e6, 50 * MM)
    table = model._plane_tables[False].table
    i = round((1.0 / (50 * MM) - table.u.start) / table.u.step)
    j = round(math.radians(5.0) / table.v.step)
    first, _ = table.node_value(i, j)
    second, _ = table.node_value(i + 1, j)
    assert np.abs(second - first).max() < 0.1 * np.abs(first).max()


def test_the_demodulation_is_what_makes_the_table_accurate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Without it (the reference delay patched to 0: the spectra tabled and interpolated
    with their raw phase) the same pose is far off; with it, within the tolerance above."""
    plane = _plane(1.0 / (1.0 / (50 * MM) + 0.013), math.radians(5.03), 0.4)
    assert _error(_model(6.35 * MM, 5e6, 50 * MM), plane) < 5e-4
    monkeypatch.setattr(plane_table_module, "_reference_delay", lambda h, c: 0.0)
    assert _error(_model(6.35 * MM, 5e6, 50 * MM), plane) > 0.1


def test_the_switch_keeps_the_exact_form_reachable() -> None:
    """``tables=False`` is the exact form to the bit; the default reads the table."""
    plane = _plane(41 * MM, math.radians(7.3), 1.1)
    exact = _model(6.35 * MM, 5e6, 41 * MM, tables=False)
    spectrum, path = exact.image_spectrum(plane)
    want, want_path = exact._exact_image_spectrum(plane)
    assert np.array_equal(spectrum, want) and path == want_path
    tabled = _model(6.35 * MM, 5e6, 41 * MM)
    tabled.image_spectrum(plane)
    assert tabled._plane_tables[False].table.nodes_filled == 16
    rectangle = WaveEchoModel(
        probe=RectangularProbe(half_width=5e-3, half_height=2.5e-3),
        pulse=GaborPulse(center_frequency=5e6, bandwidth=60),
        window=exact.window,
        sound_speed=C,
    )
    assert rectangle._plane_tables == {}  # its echo depends on the tilt's azimuth too


def test_coefficient_delay_and_reflection_follow_the_exact_form() -> None:
    """An interior's call (one coefficient, a delay of a whole number of grid steps) is
    conj(coefficient)·e^{−iω·delay} times the unit response, and a model with R(θ) at each
    face node keeps a table of its own: both within the tolerance above of the exact form
    (A-scans, relative to the exact echo's peak), the path time within 1 ns."""

    def reflection(theta: np.ndarray) -> np.ndarray:
        return np.asarray(0.9 - 4e-3 * theta + 0.05j, dtype=np.complex128)

    model = _model(6.35 * MM, 5e6, 50 * MM, reflection=reflection)
    plane = _plane(48.7 * MM, math.radians(3.21), 2.0)
    delay = 7 * model._grid[1]
    for coefficient in (None, 0.3 - 0.4j):
        got, t_got = model.image_spectrum(plane, coefficient, delay)
        want, t_want = model._exact_image_spectrum(plane, coefficient, delay)
        x, y = model.samples(got), model.samples(want)
        assert np.abs(x - y).max() < 5e-4 * np.abs(y).max()
        assert t_got == pytest.approx(t_want, abs=1e-9)
    assert model._plane_tables[True] is not model._plane_tables[False]


def test_an_echo_the_time_grid_would_cut_takes_the_exact_form() -> None:
    """A plane whose echo runs past the grid's end: the exact form (cut there) answers,
    not the table (whose echo would wrap around)."""
    model = _model(6.35 * MM, 5e6, 50 * MM)
    far = 0.5 * C * (model.grid_start + model.grid_period) - 0.1 * MM
    plane = _plane(far, math.radians(2.0), 0.0)
    table = model._plane_tables[False]
    assert table(plane) is None
    spectrum, _ = model.image_spectrum(plane)
    assert np.array_equal(spectrum, model._exact_image_spectrum(plane)[0])


def test_nodes_are_kept_on_disk_between_models(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A fresh model of the same setup reads the nodes an earlier one wrote (one file per
    node) without computing any, and answers the same to the bit; a damaged file is a
    miss (computed again, the same answer); an unwritable folder is skipped."""
    monkeypatch.setenv("ECHOCAL_CACHE_DIR", str(tmp_path))
    plane = _plane(52.3 * MM, math.radians(4.1), 0.7)
    first, _ = _model(6.35 * MM, 5e6, 50 * MM).image_spectrum(plane)
    files = sorted((tmp_path / "tables").glob("plane-*.npy"))
    assert len(files) == 16

    def no_exact(*args: object) -> None:
        raise AssertionError("a node was computed, not read")

    with monkeypatch.context() as patch:
        patch.setattr(WaveEchoModel, "_exact_image_spectrum", no_exact)
        second, _ = _model(6.35 * MM, 5e6, 50 * MM).image_spectrum(plane)
    assert np.array_equal(first, second)

    files[0].write_bytes(b"not a node")
    files[1].write_bytes(files[1].read_bytes()[:-40])
    third, _ = _model(6.35 * MM, 5e6, 50 * MM).image_spectrum(plane)
    assert np.array_equal(first, third)

    blocked = tmp_path / "file"
    blocked.write_text("a file where the folder should be")
    monkeypatch.setenv("ECHOCAL_CACHE_DIR", str(blocked))
    fourth, _ = _model(6.35 * MM, 5e6, 50 * MM).image_spectrum(plane)
    assert np.array_equal(first, fourth)
