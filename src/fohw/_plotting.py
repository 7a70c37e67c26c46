"""Private: figures and axes for every fohw plot, made one way (no pyplot, a notebook display hook).

Every plotting function and method of fohw returns a :class:`fohw._figure.Figure`: a Matplotlib
figure that is not registered with pyplot (no window, no ``plt.close``, saved with Agg whatever the
backend) and that a notebook displays as a PNG when it is a cell's last expression. New figures use
the constrained layout, so titles, labels and legends placed beside the axes are never clipped.

``ax=`` follows one rule everywhere (:func:`axes_for`): ``None`` makes a new figure with all the
panels a plot has; one Axes receives the main panel only; a sequence of Axes, as many as the plot
has panels, receives all of them, and the figure returned is theirs (its layout is left alone).
"""

from __future__ import annotations

__all__: list[str] = []


def figure(figsize=None, layout="constrained"):
    """A new, empty fohw figure (constrained layout unless ``layout`` says otherwise)."""
    from ._figure import Figure

    return Figure(figsize=figsize, layout=layout)


def subplots(*args, figsize=None, layout="constrained", **kwargs):
    """Like :func:`matplotlib.pyplot.subplots`, without pyplot: ``(fig, axes)``."""
    fig = figure(figsize, layout)
    return fig, fig.subplots(*args, **kwargs)


def axes_for(ax, n, *, figsize=None, sharex=False, ncols=1):
    """``(fig, axes)`` for a plot of ``n`` panels, from the ``ax=`` a user gave.

    ``axes`` is a list: all ``n`` panels for ``ax=None`` (a new figure, ``n`` rows, or ``ncols``
    columns) or a sequence of ``n`` Axes, only the main panel for one Axes.
    """
    from matplotlib.axes import Axes

    if ax is None:
        fig = figure(figsize)
        made = fig.subplots(n // ncols, ncols, sharex=sharex, squeeze=False)
        return fig, list(made.ravel())
    if isinstance(ax, Axes):
        return ax.figure, [ax]
    try:
        if isinstance(ax, (str, bytes)):
            raise TypeError
        axes = list(ax.ravel() if hasattr(ax, "ravel") else ax)
    except TypeError:
        raise TypeError(f"`ax` must be None, one matplotlib Axes (the main panel) or a sequence "
                        f"of {n} Axes (every panel); got {type(ax).__name__} {ax!r:.40}.") from None
    if not all(isinstance(a, Axes) for a in axes):
        kinds = ", ".join(sorted({type(a).__name__ for a in axes}))
        raise TypeError(f"`ax` must be None, one matplotlib Axes (the main panel) or a sequence "
                        f"of {n} Axes (every panel); got a sequence of {kinds}.")
    if len(axes) != n:
        raise ValueError(f"`ax` must be one Axes (the main panel) or a sequence of {n} Axes "
                         f"(every panel); got {len(axes)} Axes.")
    return axes[0].figure, axes
