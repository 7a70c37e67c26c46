"""Private: the Figure class of every figure fohw returns (a notebook displays it, pyplot never sees it).

A :class:`matplotlib.figure.Figure` created directly is not registered with pyplot: it needs no
``plt.close``, opens no window, and :meth:`~matplotlib.figure.Figure.savefig` writes it with the
Agg renderer whatever backend the user has chosen. Such a figure has no display hook of its own
(Jupyter shows a plain Figure only after pyplot has loaded the inline backend), so this subclass
adds ``_repr_png_``: the last expression of a cell shows the image, with or without pyplot, and
shows it once (pyplot's end-of-cell flush only knows the figures pyplot made).

This module imports matplotlib; :mod:`fohw._plotting` loads it on the first figure, so
``import fohw`` does not.
"""

from __future__ import annotations

import io

from matplotlib.figure import Figure as _MplFigure

__all__ = ["Figure"]


class Figure(_MplFigure):
    """A :class:`matplotlib.figure.Figure` that shows itself as a PNG in a notebook."""

    def _repr_png_(self):
        buf = io.BytesIO()
        self.savefig(buf, format="png")
        return buf.getvalue()
