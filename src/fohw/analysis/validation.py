"""Validation of an identified model on a record, the way MATLAB's ``compare`` does it.

:func:`compare` simulates the model in free run from the input
alone and predicts one step ahead from the measured data, and reports for both the fit % and
the RMSE in the data's units, plus the residual tests of the one-step errors. A model can
predict one step very well and still simulate badly or diverge; the free run is the measure
that users of identification tools judge models by, so it comes first.

A free run is scored only when it is *plausible*: besides divergence to infinity (the
simulator's own test, :class:`fohw.SimulationDivergedError`), a free run that leaves the
envelope of the measured output (:func:`implausible_sample`: by default more than
:data:`ENVELOPE` times the measured output's range outside that range) is flagged
``"implausible"`` with its sample and value, and its fit is NaN, never a finite number.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._plausible import ENVELOPE, check_envelope, implausible_message, implausible_sample
from .._types import ArrayLike
from .._validation import check_array, check_inputs, check_int, check_same_length, column_order
from ..exceptions import DimensionError, ExtrapolationWarning, ParameterError, SimulationDivergedError
from ..model.lagged.initial import InitialState, initial_state, simulate_from
from ..model.lagged.system import HammersteinWiener
from ..model.lagged.theta_hw import ThetaHW
from ..model.simulate import check_record_sampling, generic_model, simulate_record
from ..record import record_data
from .metrics import cross_correlation_test, fit_percent, rmse, whiteness_test

__all__ = ["Validation", "PooledValidation", "compare", "implausible_sample", "ENVELOPE",
           "FREE_RUN_STATUSES"]

#: What a free run's ``status`` can be: ``"ok"``; ``"diverged"`` (grew past the simulator's
#: divergence threshold or left the finite numbers); ``"nan"`` (the output basis returned NaN
#: or inf at a finite output); ``"implausible"`` (finite, but outside the envelope of the
#: measured output).
FREE_RUN_STATUSES = ("ok", "diverged", "nan", "implausible")


@dataclass
class Validation:
    """Free-run simulation and one-step prediction of one model on one record.

    Attributes
    ----------
    y : ndarray
        The measured output.
    simulated : ndarray or None
        The free-run output (``None`` if it diverged or was implausible: see ``status`` and
        ``diverged``).
    predicted : ndarray or None
        The one-step-ahead prediction from the measured data (None for a model of a kind other
        than the lagged one: an output-error model, whose one-step prediction is its free run).
    fit_simulation, rmse_simulation : float
        Fit % ``100 (1 - ||y - ysim|| / ||y - mean y||)`` and RMSE (data units) of the free
        run, after ``n_init`` samples (NaN if it diverged or was implausible; the fit % is NaN
        too for a constant measured output, where it is undefined: see ``notes``).
    fit_prediction, rmse_prediction : float
        The same for the one-step prediction (NaN when there is none).
    whiteness, cross_correlation : CorrelationTest or None
        Residual tests of the one-step errors (of the free-run errors for an output-error
        model of another kind; ``None`` for records too short for them, and when they are
        undefined: a constant input or residual, or a free run that was not scored; ``notes``
        says which).
    diverged : str
        Why the free run was not scored (empty if it was): the divergence or the implausible
        sample, with its index and value.
    in_range : bool
        Whether the input stayed inside the estimation input's range (5 % slack); always True
        for a model (rather than an identification result), which carries no estimation range,
        unless its simulator warns with :class:`fohw.ExtrapolationWarning`.
    n_init : int
        Leading samples left out of every measure.
    status : str
        The free run's status, one of :data:`FREE_RUN_STATUSES`: ``"ok"``, ``"diverged"``,
        ``"nan"`` or ``"implausible"``.
    notes : tuple of str
        What was skipped and why (a residual test, a fit % of a constant output, a one-step
        prediction a model cannot give).
    initial : InitialState or None
        The state the free run started from (:func:`fohw.initial_state`): for
        ``initial="estimate"`` the levels (and window) fitted to this record's output, and
        ``initial.n_estimated`` values so fitted.
    dt : float or None
        The sampling time of :meth:`plot`'s time axis: the record's (a :class:`fohw.Record`
        that gives one), else the model's when it has one other than 1.
    time_unit, output_label : str
        From a :class:`fohw.Record`: the unit of time (``"s"``) and the output's
        ``"name [unit]"``, for :meth:`plot`'s labels (empty for arrays).
    t : ndarray or None
        The sampling instants of a record with non-uniform time stamps.
    """

    y: np.ndarray
    simulated: np.ndarray | None
    predicted: np.ndarray | None
    fit_simulation: float
    rmse_simulation: float
    fit_prediction: float
    rmse_prediction: float
    whiteness: object
    cross_correlation: object
    diverged: str
    in_range: bool
    n_init: int
    status: str = "ok"
    notes: tuple = ()
    initial: InitialState | None = None
    dt: float | None = None
    time_unit: str = ""
    output_label: str = ""
    t: np.ndarray | None = None
    t0: float = 0.0

    @property
    def fit(self) -> float:
        """The free run's fit % (:attr:`fit_simulation`)."""
        return self.fit_simulation

    @property
    def rmse(self) -> float:
        """The free run's RMSE in the data's units (:attr:`rmse_simulation`)."""
        return self.rmse_simulation

    def __repr__(self):
        free = (f"fit {self.fit_simulation:.1f} %, RMSE {self.rmse_simulation:.4g}"
                if self.simulated is not None else self.status)
        one = (f"; one step: fit {self.fit_prediction:.1f} %, RMSE {self.rmse_prediction:.4g}"
               if self.predicted is not None else "")     # an output-error kind: none
        return f"Validation(N={self.y.size}, free run: {free}{one}; status={self.status!r})"

    def _repr_html_(self):
        from .._repr import html_table

        ok = self.simulated is not None
        rows = [("free-run simulation", f"{self.fit_simulation:.1f}" if ok else self.status,
                 f"{self.rmse_simulation:.4g}" if ok else self.status)]
        if self.predicted is not None:          # as to_markdown() writes them: no NaN row
            rows.append(("one-step prediction", f"{self.fit_prediction:.1f}",
                         f"{self.rmse_prediction:.4g}"))
        notes = [line for line in self.to_markdown().split("\n\n", 1)[1].splitlines() if line]
        return html_table(f"Validation on {self.y.size} samples"
                          + (f" ({self.n_init} start-up samples left out)" if self.n_init else ""),
                          ["", "fit %", "RMSE"], rows, notes=notes)

    def to_markdown(self, unit=""):
        """A two-row table (free run, one step) and the residual tests."""
        u = f" ({unit})" if unit else ""
        ok = self.simulated is not None
        sim_fit = f"{self.fit_simulation:.1f}" if ok else self.status
        sim_rmse = f"{self.rmse_simulation:.4g}" if ok else self.status
        out = [f"| | fit % | RMSE{u} |", "|---|---:|---:|",
               f"| free-run simulation | {sim_fit} | {sim_rmse} |"]
        if self.predicted is not None:
            out.append(f"| one-step prediction | {self.fit_prediction:.1f} | "
                       f"{self.rmse_prediction:.4g} |")
        out.append("")
        if self.diverged:
            out.append(f"Free run: {self.diverged}")
        if self.initial is not None and self.initial.n_estimated:
            out.append(f"Free run from an initial state fitted to this record's output "
                       f"({self.initial.n_estimated} values): {self.initial!r}.")
        if not self.in_range:
            out.append("The input leaves the range the model was estimated on.")
        for name, t in (("whiteness", self.whiteness), ("input cross-correlation",
                                                         self.cross_correlation)):
            if t is not None:
                out.append(f"{'One-step' if self.predicted is not None else 'Free-run'} "
                           f"residual {name}: p = {t.p_value:.3g} "
                           f"({'passed' if t.passed else 'rejected'} at {t.dof} lags).")
        out.extend(f"Note: {n}" for n in self.notes)
        return "\n".join(out) + "\n"

    def plot(self, ax=None, *, dt=None):
        """Measured output, free run and one-step prediction; their errors below.

        Parameters
        ----------
        ax : matplotlib Axes or sequence of two Axes, optional
            One Axes receives the outputs only; two receive the outputs and the errors
            (default: a new figure with both).
        dt : float, optional
            Sampling time: the horizontal axis is then time in its unit (default:
            :attr:`dt`, the record's when :func:`compare` was given a :class:`fohw.Record`,
            labelled ``time [unit]`` with its :attr:`time_unit`; else the model's when it is
            not 1), else the sample index (``sample k``). A record's name and unit label the
            output axis.

        Returns
        -------
        matplotlib.figure.Figure
            A new figure is not registered with pyplot (no window; ``fig.savefig`` writes it)
            and shows as the last expression of a notebook cell.
        """
        from .._plotting import axes_for

        fig, axes = axes_for(ax, 2, figsize=(9, 5.5), sharex=True)
        dt = self.dt if dt is None else dt
        if self.t is not None:
            t = np.asarray(self.t, dtype=float)
        else:
            t = (self.t0 if dt is not None else 0.0) + np.arange(self.y.size) * (
                1.0 if dt is None else dt)
        axes[0].plot(t, self.y, "k", lw=1.2, label="measured")
        if self.simulated is not None:
            axes[0].plot(t, self.simulated, "C0", lw=1,
                         label=f"free run: fit {self.fit_simulation:.1f} %")
        else:
            axes[0].plot([], [], "C0", label=f"free run: {self.diverged[:60]}")
        if self.predicted is not None:
            axes[0].plot(t, self.predicted, "C1--", lw=0.9,
                         label=f"one step: fit {self.fit_prediction:.1f} %")
        # legends above the panels: a record fills its axes, a legend inside would cover it
        above = dict(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=3, fontsize=8,
                     frameon=False, borderaxespad=0.2)
        axes[0].legend(**above)
        axes[0].set_ylabel(self.output_label or "output")
        if len(axes) > 1:
            if self.simulated is not None:
                axes[1].plot(t, self.y - self.simulated, "C0", lw=0.8, label="free run")
            if self.predicted is not None:
                axes[1].plot(t, self.y - self.predicted, "C1", lw=0.8, label="one step")
            unit = self.output_label.rsplit(" [", 1)[1][:-1] if self.output_label.endswith("]") \
                else ""
            axes[1].set_ylabel(f"error [{unit}]" if unit else "error")
            axes[1].legend(**above)
        if self.n_init:
            for a in axes:
                a.axvspan(t[0], t[min(self.n_init, t.size - 1)], color="0.9")
        if dt is None and self.t is None:
            axes[-1].set_xlabel("sample k")
        else:
            axes[-1].set_xlabel(f"time [{self.time_unit}]" if self.time_unit else "time")
        return fig


def _sampling_time(model):
    """The model's sampling time if it is not 1 (the sample index is then the time), else None."""
    dt = getattr(model, "dt", None)
    try:
        dt = float(dt)
    except (TypeError, ValueError):
        return None
    return dt if np.isfinite(dt) and dt > 0 and dt != 1.0 else None


def _free_run(model, u, state):
    """``(ysim or None, status, reason, caught warnings)`` of a result or a model from ``state``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        try:
            if isinstance(model, (HammersteinWiener, ThetaHW)) and isinstance(state, InitialState):
                ysim = simulate_from(model, u, state)
            else:
                ysim = model.simulate(u, initial=state)
        except SimulationDivergedError as exc:
            return None, "nan" if exc.cause == "output_basis" else "diverged", str(exc), caught
    ysim = np.asarray(ysim, dtype=float)
    bad = np.flatnonzero(~np.isfinite(ysim))
    if bad.size:               # a kind whose simulator returns inf or NaN instead of raising
        k = int(bad[0])
        return None, "diverged", (f"the free run leaves the finite numbers at sample k = {k} "
                                  f"(y[k] = {ysim[k]!r})."), caught
    return ysim, "ok", "", caught


def _is_estimate(initial):
    return (isinstance(initial, str) and initial == "estimate") or (
        isinstance(initial, tuple) and len(initial) == 2 and isinstance(initial[0], str))


def _measure(what, fn, notes, *args, **kwargs):
    """``fn(*args)``, or NaN with a note when the measure is undefined (a constant output)."""
    try:
        return fn(*args, **kwargs)
    except DimensionError as exc:
        notes.append(f"{what}: {exc}")
        return np.nan


def compare(model: Any, u: ArrayLike, y: ArrayLike | None = None, *,
            initial: Any = None, n_init: int = 0,
            max_lag: int = 25, confidence: float = 0.99,
            envelope: float = ENVELOPE) -> Validation:
    """Validate an identified model on a record: free run and one-step prediction.

    Parameters
    ----------
    model : IdentificationResult, HammersteinWiener, Model or FitResult
        The model: a result (its fitted predictor, as ``result.simulate``) or a
        :class:`fohw.HammersteinWiener` (simulated by :func:`fohw.simulate`, predicted one
        step ahead through its theta ``[q (x) a, p (x) b]``, Eq. 19). A :class:`fohw.Model`
        of any other kind, or a :class:`fohw.FitResult` (its fitted model), is an output-error
        model: its free run (``model.simulate(u, initial=initial)``) is scored the same way,
        the residual tests are of the free-run errors, and there is no separate one-step
        prediction (``predicted`` None, its fit NaN, a note says so).
    u, y : array_like
        The validation record, in the data's units (at least 2 samples). Or a
        :class:`fohw.Record` as ``u`` (``y`` omitted): its samples, checked against the
        model's sampling time; its ``dt``, instants, names and units reach :meth:`Validation.plot`.
        Or a list of Records: each scored alone (from ``initial``), and all pooled
        (:class:`PooledValidation`). A DataFrame without ``y`` is refused (say its columns
        with :meth:`fohw.Record.from_dataframe`).
    initial : str, tuple or InitialState, optional
        For a model of another kind: passed to its ``simulate`` (``"estimate"`` is refused).
        For the lagged kind, the state the free run starts from
        (:mod:`fohw.model.lagged.initial`): ``"rest"`` (the default of a ``past="rest"`` fit);
        ``"fitted"`` (the levels a ``past="estimate"`` fit
        estimated before its *estimation* record; a HammersteinWiener's own levels, its
        default); ``"estimate"`` or ``("estimate", n)`` (this record's levels, and ``n`` free
        past outputs, fitted by least squares on ``y`` with the model fixed, as MATLAB's
        ``compare(..., InitialCondition='estimate')``; ``initial.n_estimated`` values are then
        fitted on the output that is scored, so the free-run fit is optimistic by that many
        parameters: compare models with the same choice); a measured history
        ``(u_past, y_past)``; or an :class:`fohw.InitialState`. A ``past="estimate"`` result
        has no default: a ParameterError lists the choices.
    n_init : int
        Leading samples left out of every measure (a start-up transient).
    max_lag, confidence :
        Of the residual tests (:func:`~fohw.analysis.metrics.whiteness_test`,
        :func:`~fohw.analysis.metrics.cross_correlation_test`). A test that is undefined on
        this record (a constant input for the cross-correlation, a constant residual) is
        skipped with a note in ``notes``; the fit % and RMSE are still given.
    envelope : float or None
        Plausibility factor (default :data:`ENVELOPE`, 10): a free run that goes more than
        ``envelope`` times the range of the measured ``y`` (and of a measured history's output)
        outside that range is ``"implausible"`` (:func:`implausible_sample`) and not scored.
        None switches the test off.

    Returns
    -------
    Validation or PooledValidation
        A free run that diverges or is implausible is reported in ``status`` and ``diverged``
        (with its sample and value), not raised, and its fit is NaN. A
        :class:`PooledValidation` for a list of records.

    Raises
    ------
    ParameterError
        ``model`` is neither a result nor a model, or a bad ``n_init`` or
        ``envelope``; no ``initial`` for a ``past="estimate"`` result, or a bad ``initial``.
    DimensionError
        ``u`` and ``y`` differ in length, or the record has fewer than 2 samples (or no more
        than the ``2 + n`` unknowns of ``initial="estimate"``).

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(1200, random_state=0)
    >>> res = fohw.identify(data.u[:800], data.y[:800], na=2, nb=2, f_basis=2, g_basis=3)
    >>> v = fohw.compare(res, data.u[800:], data.y[800:])
    >>> v.fit_prediction > v.fit_simulation, v.diverged, v.status
    (True, '', 'ok')
    """
    records, u, y = record_data(u, y, what="u")
    if records is not None:
        kw = dict(initial=initial, n_init=n_init, max_lag=max_lag, confidence=confidence,
                  envelope=envelope)
        each = [_compare_record(model, r, **kw) for r in records]
        return each[0] if u is not None else PooledValidation(each)
    if y is None:
        raise ParameterError("`y` is missing: pass the measured output, or a fohw.Record as `u`.")
    other = generic_model(model)
    if other is not None:
        out = _compare_model(other, u, y, initial=initial, n_init=n_init,
                             max_lag=max_lag, confidence=confidence, envelope=envelope)
        out.dt = _sampling_time(other)
        return out
    out = _compare_lagged(model, u, y, initial=initial, n_init=n_init,
                          max_lag=max_lag, confidence=confidence, envelope=envelope)
    out.dt = _sampling_time(model)
    return out


def _compare_record(model, record, **kw):
    """:func:`compare` on one :class:`fohw.Record` (its sampling checked against the model's)."""
    simulate_at = check_record_sampling(model, record)
    other = generic_model(model)
    if simulate_at is not None:         # non-uniform instants: the kind's simulator on them
        if kw["initial"] is not None:
            raise ParameterError(f"`initial` = {kw['initial']!r}: a record with non-uniform time "
                                 "stamps is simulated from rest (the kind's simulate_at).")
        out = _compare_model(_OnInstants(other, record), record.u, record.y, **kw)
    else:
        out = compare(model, _inputs_by_name(model, record), record.y, **kw)
    out.dt = record.dt if record.dt is not None else out.dt
    out.t = None if record.t is None else np.array(record.t)
    out.t0 = record.t0
    out.time_unit = record.time_unit
    out.output_label = record.label("y") if record.output_unit or \
        record.output_name not in ("", "y") else ""
    return out


def _inputs_by_name(model, record):
    """``record.u`` with its columns in the order of the model's input names (as a DataFrame's)."""
    names = tuple(getattr(getattr(model, "structure", None), "inputs", ()) or ()) or \
        tuple((getattr(model, "data", None) or {}).get("input_names") or ())
    defaults = tuple(f"u{j}" for j in range(1, record.n_inputs + 1))
    if record.n_inputs < 2 or len(names) != record.n_inputs or record.input_names == defaults:
        return record.u                     # one input, or a record without names: in order
    order = column_order(record.input_names, names, "u", "a Record with the inputs")
    return record.u if order is None else record.u[:, order]


class _OnInstants:
    """A model whose free run is its ``simulate_at`` on a record's non-uniform instants."""

    def __init__(self, model, record):
        self.model, self.record = model, record
        self.kind_name = type(model).__name__

    def check_input(self, u):
        return self.model.check_input(u)

    def simulate(self, u, *, initial=None):
        return simulate_record(self.model, self.record)


@dataclass
class PooledValidation:
    """:func:`compare` on several records: each record's :class:`Validation` and the pool.

    Attributes
    ----------
    records : list of Validation
        One per record, each scored alone (its own mean in its fit %).
    fit_simulation, rmse_simulation : float
        Over the pooled samples of every record (after each one's ``n_init``): fit %
        ``100 (1 - ||y - ysim|| / ||y - mean y||)`` with the mean of the pooled output, and
        the RMSE. NaN when a record's free run was not scored (its ``status`` says why).
    """

    records: list

    def _pooled(self):
        if any(v.simulated is None for v in self.records):
            return None
        y = np.concatenate([v.y[v.n_init:] for v in self.records])
        ysim = np.concatenate([v.simulated[v.n_init:] for v in self.records])
        return y, ysim

    @property
    def fit_simulation(self) -> float:
        """The pooled free run's fit %."""
        pooled = self._pooled()
        return np.nan if pooled is None else fit_percent(*pooled)

    @property
    def rmse_simulation(self) -> float:
        """The pooled free run's RMSE (the data's units)."""
        pooled = self._pooled()
        return np.nan if pooled is None else rmse(*pooled)

    fit = fit_simulation
    rmse = rmse_simulation

    def __repr__(self):
        return (f"PooledValidation({len(self.records)} records, N={sum(v.y.size for v in self.records)}:"
                f" free run fit {self.fit_simulation:.1f} %, RMSE {self.rmse_simulation:.4g})")

    def to_markdown(self, unit=""):
        """One row per record and the pooled row (free run)."""
        u = f" ({unit})" if unit else ""
        out = [f"| record | samples | fit % | RMSE{u} |", "|---|---:|---:|---:|"]
        for k, v in enumerate(self.records):
            ok = v.simulated is not None
            out.append(f"| {k} | {v.y.size} | {f'{v.fit_simulation:.1f}' if ok else v.status} | "
                       f"{f'{v.rmse_simulation:.4g}' if ok else v.status} |")
        out.append(f"| pooled | {sum(v.y.size for v in self.records)} | "
                   f"{self.fit_simulation:.1f} | {self.rmse_simulation:.4g} |")
        return "\n".join(out) + "\n"

    def plot(self, ax=None):
        """Each record's measured output and free run, one panel per record (shared labels)."""
        from .._plotting import axes_for

        fig, axes = axes_for(ax, len(self.records), figsize=(9, 2.2 * len(self.records) + 1))
        for a, v in zip(axes, self.records):
            v.plot(ax=a)
        return fig


def _checked_record(u, y, n_init, envelope):
    """``(y, n_init, factor)`` of a validation record whose input ``u`` is already checked."""
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if y.size < 2:
        raise DimensionError(f"the record has {y.size} sample (`u` and `y`); compare needs at "
                             "least 2 (a fit % compares the output with its mean).")
    return y, check_int(n_init, "n_init", minimum=0, maximum=y.size - 2), check_envelope(envelope)


def _replayed(caught):
    """Re-issue a free run's warnings but the extrapolation one; whether the input stayed in range."""
    for w in caught:
        if not issubclass(w.category, ExtrapolationWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return not any(issubclass(w.category, ExtrapolationWarning) for w in caught)


def _in_envelope(ysim, status, diverged, reference, factor):
    """``(ysim, status, diverged)``, or ``(None, "implausible", why)`` outside the envelope."""
    found = implausible_sample(ysim, reference, factor)
    if found is None:
        return ysim, status, diverged
    return None, "implausible", implausible_message(found, factor)


def _compare_lagged(model, u, y, *, initial, n_init, max_lag, confidence, envelope):
    """:func:`compare` of a result or a :class:`fohw.HammersteinWiener` (the lagged kind)."""
    is_model = isinstance(model, HammersteinWiener)
    if not is_model and not all(callable(getattr(model, name, None))
                                for name in ("simulate", "predict")):
        raise ParameterError("`model` must be an identification result (fohw.identify), a "
                             f"fohw.HammersteinWiener or a fohw.ThetaHW; got {type(model).__name__}.")
    u = check_inputs(u, model.structure.n_inputs, names=model.structure.inputs)
    y, n_init, factor = _checked_record(u, y, n_init, envelope)
    state = initial_state(model, u, y if _is_estimate(initial) else None, initial)
    ysim, status, diverged, caught = _free_run(model, u, state)
    in_range = _replayed(caught)
    if ysim is not None:
        reference = y if state.history is None else np.r_[state.history[1], y]
        ysim, status, diverged = _in_envelope(ysim, status, diverged, reference, factor)
    # one copy of Eq. (19): a HammersteinWiener predicts as the ThetaHW of its theta
    predictor = (ThetaHW(model.structure, model.linear, model.nonlinear,
                         operating_point=model.operating_point) if is_model else model)
    yhat = predictor.predict(u, y)
    return _scored(u, y, ysim, yhat, y - yhat, status, diverged, in_range, state, [],
                   n_init=n_init, max_lag=max_lag, confidence=confidence)


def _compare_model(model, u, y, *, initial, n_init, max_lag, confidence, envelope):
    """:func:`compare` of a model of any kind but the lagged one (an output-error model).

    Its one-step prediction is its free run (the noise is on the output), so the free run is
    scored and the residual tests are of its errors; ``initial`` goes to ``model.simulate``.
    """
    kind = getattr(model, "kind_name", None)      # a Model's is a classmethod (a registry name)
    kind = kind if isinstance(kind, str) else type(model).__name__
    if _is_estimate(initial):
        raise ParameterError(f"initial={initial!r} (the record's initial state fitted to its "
                             f"output) is for the lagged HammersteinWiener kind; a {kind} "
                             "takes its own `initial` (passed to its simulate).")
    u = model.check_input(u)
    y, n_init, factor = _checked_record(u, y, n_init, envelope)
    ysim, status, diverged, caught = _free_run(model, u, initial)
    in_range = _replayed(caught)
    if ysim is not None:
        ysim, status, diverged = _in_envelope(ysim, status, diverged, y, factor)
    notes = [f"one-step prediction: a {kind} is an output-error model (the noise on the "
             "output), whose one-step prediction is its free run; the residual tests are of "
             "the free-run errors"]
    return _scored(u, y, ysim, None, None if ysim is None else y - ysim, status, diverged,
                   in_range, None, notes, n_init=n_init, max_lag=max_lag,
                   confidence=confidence)


def _scored(u, y, ysim, yhat, residual, status, diverged, in_range, state, notes, *, n_init,
            max_lag, confidence):
    """The :class:`Validation` of a free run ``ysim`` and a prediction ``yhat`` (None: none).

    The residual tests are of ``residual`` (None: not tested).
    """
    fit_s = rmse_s = fit_p = rmse_p = np.nan
    if ysim is not None:
        fit_s = _measure("free-run fit %", fit_percent, notes, y, ysim, n_init=n_init)
        rmse_s = rmse(y, ysim, n_init=n_init)
    if yhat is not None:
        fit_p = _measure("one-step fit %", fit_percent, notes, y, yhat, n_init=n_init)
        rmse_p = rmse(y, yhat, n_init=n_init)
    white = xcorr = None
    if residual is not None and y.size - n_init > 3 * max_lag:
        white = _measure("whiteness test skipped", whiteness_test, notes, residual,
                         max_lag=max_lag, confidence=confidence, n_init=n_init)
        if u.ndim == 1:
            xcorr = _measure("input cross-correlation test skipped", cross_correlation_test,
                             notes, residual, u, max_lag=max_lag, confidence=confidence,
                             n_init=n_init)
        else:
            notes.append("input cross-correlation test skipped: it is for a single input "
                         f"(`u` has {u.shape[1]} columns)")
        white = None if isinstance(white, float) else white
        xcorr = None if isinstance(xcorr, float) else xcorr
    return Validation(y=y, simulated=ysim, predicted=yhat, fit_simulation=fit_s,
                      rmse_simulation=rmse_s, fit_prediction=fit_p,
                      rmse_prediction=rmse_p, whiteness=white,
                      cross_correlation=xcorr, diverged=diverged, in_range=in_range,
                      n_init=n_init, status=status, notes=tuple(notes), initial=state)
