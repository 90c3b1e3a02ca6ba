"""Setup files: TOML → validated config → VirtualSetup; every problem named by its field."""

from __future__ import annotations

import numpy as np
import pytest

from echocal import ConfigError, DataFileError, UnknownNameError
from echocal.measurement.virtual import VirtualSetup
from echocal.setups import (
    builtin_setup_names,
    load_setup,
    load_setup_config,
    validate_setup_file,
)
from echocal.specimen import TILTED_PLATE_ORIENTATION


def test_builtin_setups_load_and_describe_their_physics():
    assert {"thesis", "immersion-5mhz"} <= set(builtin_setup_names())
    rig = load_setup("immersion-5mhz")
    assert isinstance(rig, VirtualSetup)
    assert rig.transducer.aperture == "circular"
    assert rig.transducer.width == pytest.approx(12.7e-3)
    assert rig.pulse.center_frequency == pytest.approx(5e6)
    assert rig.window.start == pytest.approx(60e-6)
    assert rig.receiver.snr_db == 30.0
    thesis = load_setup("thesis")
    assert thesis.specimen.name == "thesis-block"


def test_immersion_rig_optimum_is_the_plate_normal():
    rig = load_setup("immersion-5mhz")
    az, coel = rig.true_optimum(rig.reference_position)
    # Nearly parallel rays on a plane: the optimum is the plate normal (search tol 1e-5°).
    assert (az, coel) == pytest.approx(TILTED_PLATE_ORIENTATION, abs=1e-3)


def write(tmp_path, text, name="setup.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_units_in_strings_and_si_numbers_agree(tmp_path):
    a = write(tmp_path, '[transducer]\nwidth = "12.7 mm"\n[window]\nstart = "20 us"\n', "a.toml")
    b = write(tmp_path, "[transducer]\nwidth = 0.0127\n[window]\nstart = 20e-6\n", "b.toml")
    ca, _ = load_setup_config(a)
    cb, _ = load_setup_config(b)
    assert ca.transducer.width == pytest.approx(cb.transducer.width)
    assert ca.window.start == pytest.approx(cb.window.start)


def test_every_problem_is_reported_with_its_field_path(tmp_path):
    path = write(
        tmp_path,
        "[transducer]\nwidth = -0.01\nn_h = 0\ncolour = 'red'\n"
        "[window]\nfs = 'fast'\n[noise]\nsnr_db = nan\n",
    )
    problems = validate_setup_file(path)
    text = "\n".join(problems)
    assert "transducer.width: must be greater than 0, got -0.01" in text
    assert "transducer.n_h" in text
    assert "transducer.colour: unknown key" in text
    assert "window.fs" in text
    assert "noise.snr_db" in text
    assert len(problems) == 5


def test_millimetres_given_as_metres_are_caught(tmp_path):
    path = write(tmp_path, "[transducer]\nwidth = 12.7\n")
    with pytest.raises(ConfigError, match=r"transducer.width: .*did you mean '12.7 mm'"):
        load_setup_config(path)


def test_wrong_unit_kind_is_named(tmp_path):
    path = write(tmp_path, '[transducer]\nwidth = "5 MHz"\n')
    with pytest.raises(ConfigError, match="transducer.width.*not a length unit"):
        load_setup_config(path)


def test_shapes_and_mesh_specimens(tmp_path):
    shapes = write(
        tmp_path,
        '[specimen]\nname = "two"\n[[specimen.shapes]]\nkind = "plane"\n'
        'width = "50 mm"\nheight = "50 mm"\n'
        '[[specimen.shapes]]\nkind = "sphere"\ncenter = [0, 0, "-30 mm"]\nradius = "5 mm"\n',
    )
    setup = load_setup(shapes)
    assert len(setup.specimen) == 2
    missing = write(tmp_path, "[[specimen.shapes]]\nkind = 'sphere'\n", "m.toml")
    with pytest.raises(ConfigError, match=r"specimen.shapes.0.radius: required"):
        load_setup(missing)
    nomesh = write(tmp_path, "[specimen]\nmesh = 'absent.stl'\n", "n.toml")
    with pytest.raises(DataFileError, match="absent.stl"):
        load_setup(nomesh)


def test_unknown_names(tmp_path):
    with pytest.raises(UnknownNameError, match="immersion-5mhz"):
        load_setup("no-such-setup")
    bad = write(tmp_path, '[specimen]\nbuiltin = "teapot"\n[pulse]\nname = "chirp"\n')
    problems = validate_setup_file(bad)
    assert any("pulse.name" in p and "gabor" in p for p in problems)


def test_malformed_toml_and_missing_file(tmp_path):
    path = write(tmp_path, "[transducer\nwidth = 1\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_setup_config(path)
    with pytest.raises(DataFileError, match="not found"):
        load_setup_config(tmp_path / "absent.toml")


def test_seed_override_reproduces_noise():
    a = load_setup("thesis", seed=5).simulate([load_setup("thesis").true_pose([0.01, 0, 0.022])])
    b = load_setup("thesis", seed=5).simulate([load_setup("thesis").true_pose([0.01, 0, 0.022])])
    np.testing.assert_array_equal(a, b)


def test_noiseless_receiver_from_toml(tmp_path):
    path = write(tmp_path, '[noise]\nsnr_db = "none"\n')
    assert load_setup(path).receiver.snr_db is None
    assert load_setup(path).noise_sigma == 0.0


def test_mesh_specimen_from_a_file_in_millimetres(tmp_path):
    import trimesh

    # A 40 x 40 mm square made of two triangles, written in millimetres.
    square = trimesh.Trimesh(
        vertices=[[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0]],
        faces=[[0, 1, 2], [0, 2, 3]],
    )
    square.export(tmp_path / "square.stl")
    path = write(tmp_path, '[specimen]\nmesh = "square.stl"\nmesh_scale = 0.001\n')
    setup = load_setup(path)
    hits = setup.specimen.surface_below(0.019, 0.0)
    assert bool(hits.hit) and float(hits.distance) > 0
    assert not bool(setup.specimen.surface_below(0.021, 0.0).hit)  # scaled to 20 mm half-width


def test_sampled_pulse_file_is_relative_to_the_setup_file(tmp_path, monkeypatch):
    # As for a mesh, a relative pulse file is found beside the TOML, whatever the working
    # directory; the loaded samples must be the file's (exact: float repr round trip).
    from echocal.signal import GaborPulse

    folder = tmp_path / "rig"
    folder.mkdir()
    t = np.arange(-100, 101) / 100e6
    w = GaborPulse(center_frequency=5e6).waveform(t)
    np.savetxt(folder / "pulse.csv", np.column_stack([t, w]), delimiter=",", fmt="%.17g")
    path = write(
        folder, '[pulse]\nname = "sampled"\nfile = "pulse.csv"\n[window]\nstart = "20 us"\n'
    )
    monkeypatch.chdir(tmp_path)  # not the setup's folder
    setup = load_setup(path)
    np.testing.assert_array_equal(setup.pulse.samples, w)
    assert setup.pulse.fs == pytest.approx(100e6, rel=1e-9)
