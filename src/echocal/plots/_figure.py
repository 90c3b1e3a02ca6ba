"""Where echocal's figures are made: a plain Figure, or a pyplot one inside IPython (private).

Outside IPython every plotting function builds its figure with the object-oriented API
(``matplotlib.figure.Figure``: no pyplot state, safe in threads and servers).  Inside an
IPython session (a Jupyter notebook, the IPython shell) the figure is made through
:func:`matplotlib.pyplot.figure` instead, so the notebook shows it when the cell ends,
like any pyplot figure (and closes it after showing it).  Code that only writes figures
to files hands them to :func:`release` once written, so a notebook shows none of them.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

__all__ = ["cell_edges", "in_ipython", "new_figure", "release"]


def in_ipython() -> bool:
    """Whether this process runs an IPython session (Jupyter kernel or IPython shell)."""
    ipython = sys.modules.get("IPython")
    get = getattr(ipython, "get_ipython", None)
    return get is not None and get() is not None


def new_figure(**kwargs: Any) -> Figure:
    """A new figure (``kwargs`` as for :class:`matplotlib.figure.Figure`): through pyplot
    inside IPython, so that it displays inline, else a plain, state-free Figure."""
    if in_ipython():
        import matplotlib.pyplot as plt

        return plt.figure(**kwargs)
    return Figure(**kwargs)


def release(fig: Figure) -> None:
    """Forget a written-to-file figure in pyplot's registry (if it is there), so a
    notebook does not show it; a plain Figure needs nothing."""
    if getattr(fig.canvas, "manager", None) is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)


def cell_edges(centres: ArrayLike) -> NDArray[np.float64]:
    """The cell edges of a monotonic grid of ``centres`` (n,), shape (n + 1,): midpoints
    inside, half a step beyond each end (one cell of width 1 for a single centre)."""
    c = np.asarray(centres, dtype=np.float64)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2.0 * c[0] - mid[0]], mid, [2.0 * c[-1] - mid[-1]]])
