"""Bode and Nyquist figures of frequency responses (the frequency view of a fitted model).

:func:`bode` and :func:`nyquist` draw any model kind that has a frequency response (its
:meth:`fohw.Model.frequency_response` hook), or the model of a fit result with the record's time
unit on the axis: they are the one implementation behind ``model.bode()``, ``fit.bode()`` and
``fohw.bode(model_or_fit)``. :func:`bode_plot` and :func:`nyquist_plot` draw complex responses
(from :mod:`fohw.model.frequency_response` or any other source). Every figure is returned: it
opens no window, saves with the Agg renderer and shows in a notebook (:mod:`fohw._plotting`).
"""

from __future__ import annotations

import numpy as np

from .exceptions import ParameterError

__all__ = ["bode", "nyquist", "bode_plot", "nyquist_plot", "frequency_label"]


def _source(system, what):
    """``(responder, data)``: the object whose ``frequency_response`` is drawn, a fit's record facts.

    A model (anything with ``frequency_response``) is its own responder; a fit result (an
    object with a ``model``) lends its model and its ``data`` (the record's names and units).
    """
    if hasattr(system, "frequency_response"):
        return system, {}
    if hasattr(system, "model"):
        model = system.model
        if model is None:
            raise ParameterError(f"`{what}`: this {type(system).__name__} has no model (see its "
                                 "message), so it has no frequency response.")
        if not hasattr(model, "frequency_response"):
            raise ParameterError(f"`{what}`: the model of this {type(system).__name__} is a "
                                 f"{type(model).__name__}, which has no frequency_response.")
        return model, dict(getattr(system, "data", None) or {})
    raise ParameterError(f"`{what}` must be a fohw.Model, a fit result or an object with a "
                         f"frequency_response(omega); got {type(system).__name__}.")


def _response(responder, omega, where, what):
    """``responder.frequency_response(omega, **where)``, refused when the kind has none."""
    g = responder.frequency_response(omega, **where)
    if g is None:
        kind = type(responder).__name__
        raise ParameterError(f"`{what}`: a {kind} has no frequency response (its "
                             "frequency_response hook returns None, fohw.Model's default), so it "
                             f"has no Bode or Nyquist plot. Give the {kind} class a "
                             "frequency_response(omega) to draw it.")
    return np.asarray(g, dtype=complex)


def _curves(system, omega, others, label, where):
    """``(omega, {label: response}, responder, data)`` of ``system`` and ``others``."""
    responder, data = _source(system, "system")
    if omega is None:
        if not hasattr(responder, "default_frequencies"):
            raise ParameterError(f"`omega` is needed: a {type(responder).__name__} has no "
                                 "default_frequencies().")
        omega = responder.default_frequencies()
    omega = np.asarray(omega, dtype=np.float64)
    if label is None:
        if others and responder is not system:
            label = "estimate"                  # a fit beside other models
        elif hasattr(responder, "response_label"):
            label = responder.response_label()
        else:
            label = type(responder).__name__
    curves = {label: _response(responder, omega, where, "system")}
    for name, other in (others or {}).items():
        what = f"others[{name!r}]"
        curves[name] = _response(_source(other, what)[0], omega, where, what)
    return omega, curves, responder, data


def bode(system, omega=None, *, others=None, label=None, title=None, ax=None, hz=False,
         time_unit=None, **where):
    """Bode diagram of a model's frequency response, or of a fit's model.

    Parameters
    ----------
    system : Model, fit result or object with ``frequency_response(omega)``
        What to draw: a :class:`fohw.Model` (its :meth:`~fohw.Model.frequency_response`), a
        :class:`fohw.FitResult` or :class:`fohw.IdentificationResult` (its ``model``; the
        frequency axis in the record's time unit), or e.g. a
        :class:`fohw.model.lagged.hw_frequency.LinearBlock`.
    omega : array_like, optional
        Angular frequencies (default: the system's ``default_frequencies()``).
    others : dict of str to model or fit, optional
        Further systems drawn on the same axes at the same frequencies (e.g. the true model
        beside an estimate).
    label : str, optional
        The name of ``system``'s curve (default: ``"estimate"`` for a fit drawn beside
        ``others``, else the model's :meth:`~fohw.Model.response_label`).
    title : str, optional
        Figure title.
    ax : matplotlib Axes or sequence of two Axes, optional
        One Axes: the magnitude only; two: magnitude and phase (default: a new figure).
    hz : bool, optional
        Against ``f = omega / (2 pi)`` (Hz for a record in seconds).
    time_unit : str, optional
        The unit of time of ``omega`` for the axis label (:func:`frequency_label`); default the
        fit's record's (``data["time_unit"]``), else unknown.
    **where
        Passed to every ``frequency_response`` (an operating point, e.g. ``soc=`` and
        ``temperature=`` of :class:`fohw.CircuitTables`).

    Returns
    -------
    matplotlib.figure.Figure
        Magnitude and phase axes (:func:`bode_plot`).

    Raises
    ------
    ParameterError
        A kind without a frequency response (its hook returns ``None``), named; a fit without
        a model; an object that is none of these.

    Examples
    --------
    >>> import fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    >>> fig = fohw.bode(G)
    >>> [line.get_label() for line in fig.axes[0].get_lines()]
    ['1 / (s^0.5 + 1)']
    """
    omega, curves, _, data = _curves(system, omega, others, label, where)
    unit = time_unit if time_unit is not None else (data.get("time_unit") or None)
    return bode_plot(omega, curves, title=title, ax=ax, time_unit=unit, hz=hz)


def nyquist(system, omega=None, *, others=None, label=None, title=None, ax=None, **where):
    """Nyquist diagram of a model's frequency response, or of a fit's model.

    The parameters are those of :func:`bode` (without ``hz`` and ``time_unit``). A kind whose
    :attr:`~fohw.Model.response_kind` is ``"impedance"`` (the circuits) is drawn in the
    impedance plane (``-Im Z`` upwards, no critical point).

    Returns
    -------
    matplotlib.figure.Figure
        :func:`nyquist_plot`'s figure.

    Examples
    --------
    >>> import fohw
    >>> from fohw.model.circuit import ZARC
    >>> cell = fohw.EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015)
    >>> fohw.nyquist(cell).axes[0].get_ylabel()
    '-imaginary part'
    """
    omega, curves, responder, _ = _curves(system, omega, others, label, where)
    impedance = getattr(responder, "response_kind", "transfer") == "impedance"
    return nyquist_plot(curves, title=title, ax=ax, impedance=impedance)


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


def nyquist_plot(responses, *, title=None, ax=None, impedance=False):
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
    impedance : bool, optional
        Draw the impedance plane: ``-Im`` upwards, positive frequencies only, no critical point
        (default False).

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
        if impedance:
            ax.plot(g.real, -g.imag, label=label)
            continue
        (line,) = ax.plot(g.real, g.imag, label=label)
        ax.plot(g.real, -g.imag, color=line.get_color(), lw=0.6, alpha=0.6)
    if not impedance:
        ax.plot([-1.0], [0.0], "r+", ms=10)
    ax.set_xlabel("real part")
    ax.set_ylabel("-imaginary part" if impedance else "imaginary part")
    ax.grid(True, alpha=0.3)
    ax.set_aspect("equal", adjustable="datalim")
    if any(label is not None for label in responses):
        ax.legend()
    if title:
        ax.set_title(title)
    return fig
