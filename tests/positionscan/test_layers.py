"""Layer thickness from the interface echoes of a simulated steel plate (wave model)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cli_helpers import run_main
from echocal.errors import EchocalValueError
from echocal.positionscan import receiver_noise, simulate_position_scan
from echocal.positionscan.layers import layer_thickness
from echocal.setups import load_setup
from echocal.signal.gates import TimeGate

THICKNESS, C_STEEL = 20e-3, 5900.0  # the immersion-steel-plate setup's plate (its file)


@pytest.fixture(scope="module")
def plate():
    setup = load_setup("immersion-steel-plate")  # 12.7 mm 5 MHz probe, 50 mm water, 30 dB
    xs = np.linspace(-2e-3, 2e-3, 3)
    return setup, simulate_position_scan(setup, x=xs, y=xs, noise=False)


def test_thickness_map_of_a_steel_plate(plate):
    setup, ideal = plate
    exact = layer_thickness(ideal, [C_STEEL])
    # every trace within 0.1 % of 20 mm (the rest: the back-wall echo's extra diffraction
    # delay through 20 mm of steel, about +0.09 %)
    assert np.all(np.abs(exact.thickness / THICKNESS - 1) < 1e-3)
    noisy = layer_thickness(receiver_noise(ideal, setup, 3), [C_STEEL])
    stats = noisy.statistics()[0]
    assert stats["traces"] == 9
    # the noise is unbiased: the 30 dB mean lies within 3 standard errors of the exact one
    sem = stats["std"] / np.sqrt(stats["traces"])
    assert abs(stats["mean"] - exact.thickness.mean()) < 3 * sem
    assert stats["std"] < 1.5e-3 * THICKNESS  # per trace at 30 dB (back wall at -25 dB)


def test_gates_per_interface_and_refusals(plate):
    _, ideal = plate
    # absolute gates around the front wall (67.6 us) and the first back wall (+6.78 us)
    gates = [
        TimeGate(name="fw", start=66e-6, width=3e-6),
        TimeGate(name="bw", start=73e-6, width=3e-6),
    ]
    gated = layer_thickness(ideal, [C_STEEL], gates=gates)
    np.testing.assert_allclose(
        gated.thickness, layer_thickness(ideal, [C_STEEL]).thickness, rtol=1e-6
    )
    with pytest.raises(EchocalValueError, match="one per interface"):
        layer_thickness(ideal, [C_STEEL], gates=gates[:1])
    with pytest.raises(EchocalValueError, match="every interface behind the front wall"):
        layer_thickness(ideal, [C_STEEL, 2700.0])
    with pytest.raises(EchocalValueError, match="speeds"):
        layer_thickness(ideal, [-5900.0])


def test_cli_layers(plate, tmp_path, capsys, monkeypatch):
    _, ideal = plate
    path = tmp_path / "plate.nc"
    ideal.save(path)
    out = tmp_path / "layers.nc"
    code, stdout, err = run_main(
        ["layers", str(path), "--speed", "5900", "--json", "--out", str(out)], capsys, monkeypatch
    )
    assert code == 0, err
    stats = json.loads(stdout)["layers"][0]
    assert abs(stats["mean"] / THICKNESS - 1) < 1e-3 and out.stat().st_size > 0


def test_two_layers_of_a_layered_part_within_0_1_percent():
    # the built-in layered part: acrylic 30 mm (2730 m/s) on aluminium 50 mm (6320 m/s),
    # scanned 25 mm off its two flat-bottom holes; each interface in a gate of its own,
    # centred on the ray-path time through the layers (computed here from the speeds)
    setup = load_setup("immersion-layered")
    scan = simulate_position_scan(
        setup, x=np.linspace(-12e-3, -8e-3, 3), y=np.array([-25e-3, -24e-3]), noise=False
    )
    front = 2 * 50e-3 / 1480.0
    first = front + 2 * 30e-3 / 2730.0
    second = first + 2 * 50e-3 / 6320.0
    gates = [None] + [
        TimeGate(name=f"interface-{k}", start=t - 2e-6, width=4e-6)
        for k, t in ((1, first), (2, second))
    ]
    layers = layer_thickness(scan, [2730.0, 6320.0], gates=gates)
    # measured -0.067 % and -0.060 %: the interface echoes' diffraction delays
    np.testing.assert_array_less(np.abs(layers.thickness[0] / 30e-3 - 1), 1e-3)
    np.testing.assert_array_less(np.abs(layers.thickness[1] / 50e-3 - 1), 1e-3)
