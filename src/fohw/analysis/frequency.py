"""Bode and Nyquist figures of frequency responses (the frequency view of a fitted model).

:func:`bode_plot` and :func:`nyquist_plot` draw complex responses (from
:mod:`fohw.model.frequency_response` or any other source) and return ``(fig, axes)``; no pyplot:
the figure opens no window and saves with the Agg renderer.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bode_plot", "nyquist_plot"]


def _figure(nrows, figsize):
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    axes = fig.subplots(nrows, 1, sharex=True) if nrows > 1 else fig.subplots()
    return fig, axes


def bode_plot(omega, responses, *, title=None, band=None):
    """Bode diagram (magnitude in dB, phase in degrees) of one or more frequency responses.

    Parameters
    ----------
    omega : array_like, shape (n,)
        Positive angular frequencies (rad per unit time).
    responses : dict of str to array_like of complex, or array_like
        Each response, shape (n,), labelled by its key (a single array gets no legend).
    title : str, optional
        Figure title.
    band : (float, float), optional
        A frequency band to shade (e.g. an Oustaloup approximation band).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : ndarray of Axes, shape (2,)
        Magnitude and phase axes. The figure is not registered with pyplot (never shown).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.analysis.frequency import bode_plot
    >>> w = np.logspace(-2, 2, 50)
    >>> fig, axes = bode_plot(w, {"1/(s+1)": 1 / (1j * w + 1)})
    >>> len(axes)
    2
    """
    omega = np.asarray(omega, dtype=np.float64)
    if not isinstance(responses, dict):
        responses = {None: responses}
    fig, axes = _figure(2, (6.4, 5.6))
    styles = ["-", "--", ":", "-."]
    for i, (label, g) in enumerate(responses.items()):
        g = np.asarray(g, dtype=complex)
        with np.errstate(divide="ignore"):
            axes[0].semilogx(omega, 20 * np.log10(np.abs(g)), styles[i % 4], label=label)
        axes[1].semilogx(omega, np.degrees(np.unwrap(np.angle(g))), styles[i % 4], label=label)
    axes[0].set_ylabel("magnitude [dB]")
    axes[1].set_ylabel("phase [deg]")
    axes[1].set_xlabel("angular frequency ω [rad / time unit]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        if band is not None:
            ax.axvspan(band[0], band[1], color="0.9", zorder=0)
    if any(label is not None for label in responses):
        axes[0].legend()
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig, axes


def nyquist_plot(responses, *, title=None):
    """Nyquist diagram (imaginary against real part) of one or more frequency responses.

    The mirror image for negative frequencies is drawn thin; the critical point ``-1`` is marked.

    Parameters
    ----------
    responses : dict of str to array_like of complex, or array_like
        Each response on positive frequencies.
    title : str, optional
        Figure title.

    Returns
    -------
    fig : matplotlib.figure.Figure
    ax : matplotlib.axes.Axes

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.analysis.frequency import nyquist_plot
    >>> w = np.logspace(-2, 2, 50)
    >>> fig, ax = nyquist_plot(1 / (np.sqrt(1j * w) + 1))
    >>> ax.get_xlabel()
    'real part'
    """
    if not isinstance(responses, dict):
        responses = {None: responses}
    fig, ax = _figure(1, (5.6, 5.0))
    for label, g in responses.items():
        g = np.asarray(g, dtype=complex)
        (line,) = ax.plot(g.real, g.imag, label=label)
        ax.plot(g.real, -g.imag, color=line.get_color(), lw=0.6, alpha=0.6)
    ax.plot([-1.0], [0.0], "r+", ms=10)
    ax.set_xlabel("real part")
    ax.set_ylabel("imaginary part")
    ax.grid(True, alpha=0.3)
    ax.set_aspect("equal", adjustable="datalim")
    if any(label is not None for label in responses):
        ax.legend()
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig, ax
