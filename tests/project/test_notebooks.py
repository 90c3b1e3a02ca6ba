"""Figures show inline in Jupyter: notebooks executed by a real kernel, images counted.

The gallery's examples are turned into notebooks exactly as the docs site offers them for
download (sphinx-gallery's own converter), executed with nbclient in an IPython kernel,
and every example must leave at least one PNG in its cells' outputs.  A cheap notebook
that calls one public plotting function checks the same mechanism in every run; the
whole gallery (about a minute) is marked slow.
"""

from __future__ import annotations

import copy
import json
import os
from pathlib import Path

import pytest

import echocal

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "docs" / "examples").glob("plot_*.py"))


def _execute(nb, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """Run ``nb`` in a fresh IPython kernel (this interpreter) in ``tmp_path``; the
    executed notebook.  The kernel imports the echocal under test (its folder first on an
    absolute PYTHONPATH) and gets Jupyter's own backend: the test session's MPLBACKEND=Agg
    would stop IPython from choosing its inline backend."""
    paths = [str(Path(echocal.__file__).resolve().parents[1])]
    given = os.environ.get("PYTHONPATH", "").split(os.pathsep)
    paths += [str(Path(p).resolve()) for p in given if p]
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(paths))
    monkeypatch.delenv("MPLBACKEND", raising=False)
    monkeypatch.chdir(tmp_path)
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    return client.execute()


def _images(nb) -> int:
    return sum(
        "image/png" in out.get("data", {})
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.get("outputs", [])
    )


def test_public_plot_shows_inline_in_a_notebook(tmp_path, monkeypatch):
    # the figure is assigned, not the cell's last expression: Jupyter shows it all the same,
    # as it does any pyplot figure; a figure only written to a file is not shown
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(
            "from echocal.plots import plot_pulse\n"
            "from echocal.signal import GaborPulse\n"
            "fig = plot_pulse(GaborPulse(), fs=100e6)"
        ),
        nbformat.v4.new_code_cell(
            "from echocal.experiments._output import write_figure\n"
            "from pathlib import Path\n"
            "write_figure(plot_pulse(GaborPulse(), fs=100e6), Path('.'), 'pulse')"
        ),
    ]
    out = _execute(nb, tmp_path, monkeypatch)
    assert [_images(nbformat.v4.new_notebook(cells=[c])) for c in out.cells] == [1, 0]
    assert (tmp_path / "pulse.png").exists()


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_gallery_notebook_shows_its_figures(example, tmp_path, monkeypatch):
    from sphinx_gallery import gen_gallery
    from sphinx_gallery.notebook import jupyter_notebook
    from sphinx_gallery.py_source_parser import split_code_and_text_blocks

    _, blocks = split_code_and_text_blocks(str(example))
    conf = copy.deepcopy(gen_gallery.DEFAULT_GALLERY_CONF)
    # as the downloadable .ipynb: JSON (its cells' sources as lists of lines), read back
    nb = nbformat.reads(json.dumps(jupyter_notebook(blocks, conf, example.parent)), 4)
    out = _execute(nb, tmp_path, monkeypatch)
    assert _images(out) >= 1, f"{example.name}: the executed notebook shows no figure"
