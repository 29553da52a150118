"""Figures without pyplot: every plotting module draws on a ``matplotlib.figure.Figure`` with
its own Agg canvas and writes it with ``save``.

Why: ``matplotlib.use("Agg")`` at import, or pyplot's figure registry, changes the state of the
process that imports the package (a Jupyter user's inline backend, figures kept alive until
``plt.close``).  A Figure made here belongs to no backend and is freed with its last reference
(Matplotlib's "embedding" use of the object-oriented API); ``Figure.savefig`` writes PNG through
the Agg canvas whatever backend the user has.
"""

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def figure(figsize=None) -> Figure:
    """A Figure (figsize (width, height) [in]) on its own Agg canvas, outside pyplot."""
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def subplots(nrows: int = 1, ncols: int = 1, figsize=None, **kwargs):
    """(Figure, axes) as ``pyplot.subplots`` returns them (``Figure.subplots`` keywords:
    squeeze, sharex, sharey, gridspec_kw, subplot_kw), outside pyplot."""
    fig = figure(figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def save(fig: Figure, path, dpi: int = 110, tight: bool = False) -> Path:
    """Write ``fig`` to ``path`` (PNG by its suffix) at ``dpi``; ``tight`` crops to the drawn
    area (bbox_inches="tight").  Returns the path."""
    path = Path(path)
    fig.savefig(path, dpi=dpi, bbox_inches="tight" if tight else None)
    return path
