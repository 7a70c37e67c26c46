"""Bode and Nyquist figures of frequency responses (the frequency view of a fitted model).

:func:`bode_plot` and :func:`nyquist_plot` draw complex responses (from
:mod:`fohw.model.frequency_response` or any other source) and return the figure: it opens no
window, saves with the Agg renderer and shows in a notebook (:mod:`fohw._plotting`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["bode_plot", "nyquist_plot", "frequency_label"]


def frequency_label(time_unit=None, hz=False):
    """The label of a frequency axis in the data's time unit.

    ``time_unit`` ``"s"`` gives ``rad/s`` (``Hz`` with ``hz=True``), another unit ``rad/<unit>``,
    ``"sample"`` ``rad / sample`` (the sample is the time unit), ``None`` (unknown)
    ``rad / time unit``.

    Examples
    --------
    >>> from fohw.frequency_plots import frequency_label
    >>> frequency_label("s"), frequency_label("s", hz=True), frequency_label("sample")
    ('angular frequency ω [rad/s]', 'frequency f [Hz]', 'angular frequency ω [rad / sample]')
    """
    if hz:
        unit = {"s": "Hz", "sample": "cycles / sample", None: "cycles / time unit",
                "": "cycles / time unit"}.get(time_unit, f"1/{time_unit}")
        return f"frequency f [{unit}]"
    unit = {"sample": "rad / sample", None: "rad / time unit",
            "": "rad / time unit"}.get(time_unit, f"rad/{time_unit}")
    return f"angular frequency ω [{unit}]"


def bode_plot(omega, responses, *, title=None, band=None, ax=None, time_unit=None, hz=False):
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
    ax : matplotlib Axes or sequence of two Axes, optional
        Where to draw: one Axes receives the magnitude only, two receive magnitude and phase
        (default: a new figure with both).
    time_unit : str, optional
        The unit of time of ``omega`` (``"s"``: rad/s; ``"sample"``: rad / sample; default
        unknown: rad / time unit), for the axis label (:func:`frequency_label`).
    hz : bool, optional
        Draw against ``f = omega / (2 pi)`` (Hz when ``time_unit`` is ``"s"``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (``fig.axes``: magnitude, phase). A new one is not registered with pyplot:
        it opens no window, saves with ``fig.savefig`` and shows as the last expression of a
        notebook cell.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.frequency_plots import bode_plot
    >>> w = np.logspace(-2, 2, 50)
    >>> fig = bode_plot(w, {"1/(s+1)": 1 / (1j * w + 1)})
    >>> [a.get_ylabel() for a in fig.axes]
    ['magnitude [dB]', 'phase [deg]']
    """
    from ._plotting import axes_for

    omega = np.asarray(omega, dtype=np.float64)
    if not isinstance(responses, dict):
        responses = {None: responses}
    fig, axes = axes_for(ax, 2, figsize=(6.4, 5.6), sharex=True)
    x_label = frequency_label(time_unit, hz)
    if hz:
        omega = omega / (2.0 * np.pi)
    styles = ["-", "--", ":", "-."]
    for i, (label, g) in enumerate(responses.items()):
        g = np.asarray(g, dtype=complex)
        with np.errstate(divide="ignore"):
            axes[0].semilogx(omega, 20 * np.log10(np.abs(g)), styles[i % 4], label=label)
        if len(axes) > 1:
            axes[1].semilogx(omega, np.degrees(np.unwrap(np.angle(g))), styles[i % 4],
                             label=label)
    axes[0].set_ylabel("magnitude [dB]")
    axes[-1].set_xlabel(x_label)
    if len(axes) > 1:
        axes[1].set_ylabel("phase [deg]")
    for a in axes:
        a.grid(True, which="both", alpha=0.3)
        if band is not None:
            a.axvspan(band[0], band[1], color="0.9", zorder=0)
    if any(label is not None for label in responses):
        axes[0].legend()
    if title:
        axes[0].set_title(title)
    return fig


def nyquist_plot(responses, *, title=None, ax=None):
    """Nyquist diagram (imaginary against real part) of one or more frequency responses.

    The mirror image for negative frequencies is drawn thin; the critical point ``-1`` is marked.

    Parameters
    ----------
    responses : dict of str to array_like of complex, or array_like
        Each response on positive frequencies.
    title : str, optional
        Figure title.
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (``fig.axes[0]``); a new one opens no window and shows in a notebook.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.frequency_plots import nyquist_plot
    >>> w = np.logspace(-2, 2, 50)
    >>> fig = nyquist_plot(1 / (np.sqrt(1j * w) + 1))
    >>> fig.axes[0].get_xlabel()
    'real part'
    """
    from ._plotting import axes_for

    if not isinstance(responses, dict):
        responses = {None: responses}
    fig, (ax,) = axes_for(ax, 1, figsize=(5.6, 5.0))
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
    return fig
