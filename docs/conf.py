"""Sphinx configuration of the echocal documentation (``make docs``).

The site is built with warnings as errors.  Markdown pages are read by MyST, the API
reference comes from the docstrings (autodoc + autosummary, NumPy style through
napoleon), and the example gallery (``docs/examples/``) is executed by sphinx-gallery
on every build; each example is offered as a Python script and a Jupyter notebook.
"""

from __future__ import annotations

import importlib.metadata
import os
import re
import sys
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS))  # _scraper.py, named by string below (a cacheable config)

os.environ.setdefault("MPLBACKEND", "Agg")

project = "echocal"
author = "echocal developers"
copyright = f"2026, {author}"
release = importlib.metadata.version("echocal")
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "Thumbs.db",
    ".DS_Store",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "auto_examples/*.json",
    "auto_examples/*.md5",
    "sg_execution_times.rst",
]

# ---------------------------------------------------------------- MyST (docs/*.md)
myst_enable_extensions = ["colon_fence", "dollarmath", "amsmath", "deflist"]  # $…$ → MathJax
myst_heading_anchors = 3

# ---------------------------------------------------------------- API reference
# Each module and package is documented by its ``__all__`` (a package's public names are
# the ones it re-exports); ``echocal`` itself only re-exports, so api.rst links there.
autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_preserve_defaults = True
autodoc_mock_imports = ["embreex"]  # numba is real: a mocked njit would poison the
# kernels of modules that autosummary imports before the gallery runs them
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False

intersphinx_mapping: dict[str, tuple[str, str | None]] = {}  # offline builds (CI has no web)

# The docstrings write parameters as ``name : [unit] description`` rather than
# ``name : type``; napoleon turns the bracketed units and words like "shape" into type
# cross-references, and several classes share attribute names (``shape``, ``fs``), so
# such references are ambiguous.  Only that warning class is silenced.
suppress_warnings = ["ref.python"]
# ... but a reference to an echocal object that does not exist is an error.
# Not checked: other packages' names (no intersphinx offline), private helpers shown as
# base classes, and objects of internal modules that no ``__all__`` exports (the
# reference documents each package by its ``__all__``).
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(?!echocal\.).*"),
    (r"py:.*", r".*\._\w+"),
    (r"py:class", r".*\.<locals>\..*"),  # closures (a validator's inner function): not objects
    (r"py:class", r"echocal\.measurement\.hardware\.T"),
    (r"py:.*", r"echocal\.(signal\.detection|measurement\.hardware|calibrate\.model_based)\..*"),
    (r"py:.*", r"echocal\.experiments\.(runner|summary)(\..*)?"),
    (r"py:mod", r"echocal\.calibrate\.result"),
    (r"py:obj", r"echocal\.plots\.plot_(pulse|ascan)"),
]

# ---------------------------------------------------------------- gallery
sphinx_gallery_conf = {
    "examples_dirs": ["examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_",
    "image_scrapers": ("_scraper.figure_scraper", "matplotlib"),
    "download_all_examples": True,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "show_memory": False,
    "within_subsection_order": "FileNameSortKey",
    "reset_modules": ("matplotlib",),
    "write_computation_times": False,
}

# ---------------------------------------------------------------- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"echocal {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "header_links_before_dropdown": 4,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_show_sourcelink = True
html_static_path: list[str] = []


# ---------------------------------------------------------------- docstrings as written
# The docstrings are read as plain text too (help(), IDEs), so they write magnitudes as
# |W(f)| and |x|.  In reST a |...| pair is a substitution; escape the bars outside
# literals (``...``) and roles (:role:`...`) so they print as written.
_LITERAL = re.compile(r"(``.*?``|:[a-z:]+:`[^`]*`|`[^`]*`)")


def _escape_bars(app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    for i, line in enumerate(lines):
        if "|" in line:
            parts = _LITERAL.split(line)
            lines[i] = "".join(
                p if k % 2 else p.replace("|", r"\|") for k, p in enumerate(parts)
            )


def setup(app: Any) -> None:
    """Register the docstring hook (before napoleon's, so it sees the plain text)."""
    app.connect("autodoc-process-docstring", _escape_bars, priority=400)
