"""The one way spflow makes a figure: a :class:`matplotlib.figure.Figure` that owns its axes, never touched by pyplot.

Drawing through ``matplotlib.pyplot`` needs a backend: the figure modules used to call ``matplotlib.use("Agg")``
(one of them at import time), which switched a notebook user's interactive backend as a side effect of importing
or calling spflow, and each kept its own copy of that code. A ``Figure`` built directly has no backend and no
entry in pyplot's global figure registry: ``Figure.savefig`` renders with the canvas of the file's format (Agg for
PNG), nothing has to be closed, and the caller's pyplot state is left exactly as it was.
"""

from __future__ import annotations

from matplotlib.figure import Figure

__all__ = ["subplots"]


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float] | None = None, **kwargs):
    """``(figure, axes)`` like ``pyplot.subplots`` — same ``sharex``/``sharey``/``squeeze``/``gridspec_kw`` keywords —
    on a pyplot-free :class:`~matplotlib.figure.Figure` of size ``figsize`` (inches)."""
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)
