"""Private: figures for files, made without pyplot, so library code never touches the backend.

A :class:`matplotlib.figure.Figure` created directly is not registered with pyplot: it needs no
``plt.close``, opens no window, and :meth:`~matplotlib.figure.Figure.savefig` writes it with the
Agg renderer whatever backend the user has chosen.
"""

from __future__ import annotations

__all__: list[str] = []


def subplots(*args, figsize=None, **kwargs):
    """Like :func:`matplotlib.pyplot.subplots`, without pyplot: ``(fig, axes)``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)
