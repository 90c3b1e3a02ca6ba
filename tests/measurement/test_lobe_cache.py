"""The lobe profile's on-disk cache (:mod:`echocal.measurement.lobe_cache`): a second
process (here: the same setup loaded again, new objects, an empty in-process cache) gets
the profile from disk without computing it, bit for bit; other physics is another key;
a damaged file is a miss."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from echocal.measurement import detection_radius as dr
from echocal.measurement import lobe_cache
from echocal.setups import load_setup


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ECHOCAL_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(dr, "_PROFILES", type(dr._PROFILES)())  # an empty process cache
    return tmp_path / "cache"


def _refuse(*args, **kwargs):
    raise AssertionError("the lobe profile was computed again")


def test_a_second_process_reads_the_profile_from_disk(cache, monkeypatch) -> None:
    setup = load_setup("immersion-5mhz-ray", seed=0)
    pos = np.asarray(setup.reference_position, dtype=np.float64)
    first = dr.cached_lobe_profile(setup, pos)
    assert len(list(cache.glob("lobe-*.npz"))) == 1
    again = load_setup("immersion-5mhz-ray", seed=3)  # new objects, the same physics
    monkeypatch.setattr(dr, "_PROFILES", type(dr._PROFILES)())
    monkeypatch.setattr(dr, "lobe_profile", _refuse)
    second = dr.cached_lobe_profile(again, pos)
    assert second.setup is again
    for name in ("angles", "peaks", "reference", "energies", "centre"):
        np.testing.assert_array_equal(getattr(second, name), getattr(first, name))
    assert dr.search_passes(again, pos) == dr.search_passes(setup, pos)


def test_other_physics_or_position_is_another_key(cache) -> None:
    setup = load_setup("immersion-5mhz-ray", seed=0)
    pos = np.asarray(setup.reference_position, dtype=np.float64)
    fields = tuple(getattr(setup, f) for f in dr._PROFILE_FIELDS)
    key = lobe_cache.profile_key(fields, pos, {"a": 1})
    assert key == lobe_cache.profile_key(fields, pos.copy(), {"a": 1})
    slower = dataclasses.replace(setup, sound_speed=setup.sound_speed + 1.0)
    other_fields = tuple(getattr(slower, f) for f in dr._PROFILE_FIELDS)
    assert lobe_cache.profile_key(other_fields, pos, {"a": 1}) != key
    assert lobe_cache.profile_key(fields, pos + np.array([0.0, 0.0, 1e-3]), {"a": 1}) != key
    assert lobe_cache.profile_key(fields, pos, {"a": 2}) != key
    assert lobe_cache.profile_key((lambda: 0,), pos, {}) is None  # not picklable: no cache


def test_a_damaged_or_foreign_file_is_a_miss(cache) -> None:
    arrays = {
        "angles": np.arange(3.0),
        "peaks": np.ones((2, 3)),
        "reference": np.zeros(8),
        "energies": np.ones((2, 3)),
        "centre": np.array([1.0, -2.0]),
    }
    lobe_cache.store("k", arrays)
    got = lobe_cache.load("k")
    assert got is not None and np.array_equal(got["peaks"], arrays["peaks"])
    path = cache / "lobe-k.npz"
    path.rename(cache / "lobe-other.npz")
    assert lobe_cache.load("other") is None  # the file names another key
    lobe_cache.store("k", arrays | {"energies": np.full((2, 3), np.nan)})
    assert lobe_cache.load("k") is None  # not finite
    lobe_cache.store("k", arrays | {"peaks": np.ones((2, 4))})
    assert lobe_cache.load("k") is None  # inconsistent shapes
    path.write_bytes(b"PK\x03\x04 not a zip")
    assert lobe_cache.load("k") is None
    assert lobe_cache.load("missing") is None


def test_a_change_of_the_code_is_another_key(monkeypatch) -> None:
    """Profiles computed by other code are not reused: the key holds the source digest."""
    from echocal import _code_digest

    parts, pos = ("physics",), np.zeros(3)
    before = lobe_cache.profile_key(parts, pos, {"n": 1})
    monkeypatch.setattr(_code_digest, "code_digest", lambda: "0" * 64)
    assert lobe_cache.profile_key(parts, pos, {"n": 1}) != before
