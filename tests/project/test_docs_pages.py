"""The Python blocks of the getting-started and tutorial pages run as written.

Each page's blocks run in order in one namespace, in a fresh folder; a page's TOML block is
saved there under the name its Python code loads. (The gallery examples are executed by
the documentation build, ``make docs``.)  Pages whose code needs a rig at a real address,
or runs for minutes (a 60-run sweep, a 121-point scan), are left to their gallery
counterparts.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"

PAGES = {
    "getting-started.md": None,
    "tutorials/first-calibration.md": None,
    "tutorials/setup-files.md": "my-rig.toml",
    "tutorials/recording-and-replay.md": None,
    "tutorials/inside-the-specimen.md": None,
}
"""page -> the file name its TOML block is saved as (None: no file needed)."""


def _blocks(page: str, language: str) -> list[str]:
    text = (DOCS / page).read_text(encoding="utf-8")
    return re.findall(rf"```{language}\n(.*?)```", text, re.S)


@pytest.mark.slow
@pytest.mark.parametrize("page", sorted(PAGES))
def test_page_python_blocks_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    toml_name = PAGES[page]
    if toml_name is not None:
        (toml,) = _blocks(page, "toml")
        (tmp_path / toml_name).write_text(toml, encoding="utf-8")
    blocks = _blocks(page, "python")
    assert blocks, f"{page} has no Python block"
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, page, "exec"), namespace)


def test_the_gallery_scraper_shows_each_figure_once(tmp_path):
    """echocal's ``Figure`` objects are saved by ``docs/_scraper.py``; pyplot figures are
    left to sphinx-gallery's matplotlib scraper (both saving them showed each one twice)."""
    pytest.importorskip("sphinx_gallery")
    import sys

    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    sys.path.insert(0, str(DOCS))
    try:
        from _scraper import figure_scraper
    finally:
        sys.path.remove(str(DOCS))
    ours, theirs = Figure(), plt.figure()
    try:
        paths = iter(tmp_path / f"image_{k}.png" for k in range(5))
        block_vars = {"example_globals": {"a": ours, "b": theirs}, "image_path_iterator": paths}
        rst = figure_scraper(None, block_vars, {"src_dir": str(tmp_path)})
    finally:
        plt.close(theirs)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["image_0.png"]
    assert "image_0.png" in rst
