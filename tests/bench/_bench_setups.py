"""Small setups for the bench tests: the tiny plate of ``cli_helpers`` plus a ``[bench]``."""

from __future__ import annotations

from pathlib import Path

from cli_helpers import tiny_setup_toml
from echocal.setups import load_setup


def timed_tilts(speed: float, settling: str) -> str:
    """``[bench]`` tables giving both tilt axes ``speed`` [deg/s] and ``settling`` (a time)."""
    return "".join(
        f'[bench.positioner.{axis}]\nspeed = {speed}\nsettling = "{settling}"\n'
        for axis in ("tilt_x", "tilt_y")
    )


def bench_setup(tmp_path: Path, bench: str = "", *, noise: str = "", seed: int = 4):
    """The tiny setup (8 × 8 rays, 256 samples, flat plate 16 mm below) with ``bench`` (the
    body of its ``[bench…]`` tables) and ``noise`` (a ``[noise]`` table body)."""
    text = tiny_setup_toml() + (f"[noise]\n{noise}\n" if noise else "") + bench
    path = tmp_path / f"bench-{abs(hash(text))}.toml"
    path.write_text(text)
    return load_setup(str(path), seed=seed), path
