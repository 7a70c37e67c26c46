"""Validation of an identified model on a record, the way MATLAB's ``compare`` does it.

:func:`compare` (also ``result.validate(u, y)``) simulates the model in free run from the input
alone and predicts one step ahead from the measured data, and reports for both the fit % and
the RMSE in the data's units, plus the residual tests of the one-step errors. A model can
predict one step very well and still simulate badly or diverge; the free run is the measure
that users of identification tools judge models by, so it comes first.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .._validation import check_array, check_int, check_same_length
from ..exceptions import ExtrapolationWarning, SimulationDivergedError
from .metrics import cross_correlation_test, fit_percent, rmse, whiteness_test

__all__ = ["Validation", "compare"]


@dataclass
class Validation:
    """Free-run simulation and one-step prediction of one model on one record.

    Attributes
    ----------
    y : ndarray
        The measured output.
    simulated : ndarray or None
        The free-run output (``None`` if it diverged: see ``diverged``).
    predicted : ndarray
        The one-step-ahead prediction from the measured data.
    fit_simulation, rmse_simulation : float
        Fit % ``100 (1 - ||y - ysim|| / ||y - mean y||)`` and RMSE (data units) of the free
        run, after ``n_init`` samples (NaN if it diverged).
    fit_prediction, rmse_prediction : float
        The same for the one-step prediction.
    whiteness, cross_correlation : CorrelationTest or None
        Residual tests of the one-step errors (``None`` for records too short for them).
    diverged : str
        Why the free run stopped (empty if it did not).
    in_range : bool
        Whether the input stayed inside the estimation input's range (5 % slack).
    n_init : int
        Leading samples left out of every measure.
    """

    y: np.ndarray
    simulated: np.ndarray | None
    predicted: np.ndarray
    fit_simulation: float
    rmse_simulation: float
    fit_prediction: float
    rmse_prediction: float
    whiteness: object
    cross_correlation: object
    diverged: str
    in_range: bool
    n_init: int

    def to_markdown(self, unit=""):
        """A two-row table (free run, one step) and the residual tests."""
        u = f" ({unit})" if unit else ""
        sim_fit = "diverged" if self.simulated is None else f"{self.fit_simulation:.1f}"
        sim_rmse = "diverged" if self.simulated is None else f"{self.rmse_simulation:.4g}"
        out = [f"| | fit % | RMSE{u} |", "|---|---:|---:|",
               f"| free-run simulation | {sim_fit} | {sim_rmse} |",
               f"| one-step prediction | {self.fit_prediction:.1f} | "
               f"{self.rmse_prediction:.4g} |", ""]
        if self.diverged:
            out.append(f"Free run: {self.diverged}")
        if not self.in_range:
            out.append("The input leaves the range the model was estimated on.")
        for name, t in (("whiteness", self.whiteness), ("input cross-correlation",
                                                         self.cross_correlation)):
            if t is not None:
                out.append(f"One-step residual {name}: p = {t.p_value:.3g} "
                           f"({'passed' if t.passed else 'rejected'} at {t.dof} lags).")
        return "\n".join(out) + "\n"

    def plot(self, ax=None, *, dt=None):
        """Measured output, free run and one-step prediction; their errors below."""
        from .._plotting import subplots

        if ax is None:
            fig, axes = subplots(2, 1, figsize=(9, 5.5), sharex=True)
        else:
            axes = ax
            fig = axes[0].figure
        t = np.arange(self.y.size) * (1.0 if dt is None else dt)
        axes[0].plot(t, self.y, "k", lw=1.2, label="measured")
        if self.simulated is not None:
            axes[0].plot(t, self.simulated, "C0", lw=1,
                         label=f"free run: fit {self.fit_simulation:.1f} %")
        else:
            axes[0].plot([], [], "C0", label=f"free run: {self.diverged[:60]}")
        axes[0].plot(t, self.predicted, "C1--", lw=0.9,
                     label=f"one step: fit {self.fit_prediction:.1f} %")
        axes[0].legend(fontsize=8)
        axes[0].set_ylabel("output")
        if self.simulated is not None:
            axes[1].plot(t, self.y - self.simulated, "C0", lw=0.8, label="free run")
        axes[1].plot(t, self.y - self.predicted, "C1", lw=0.8, label="one step")
        if self.n_init:
            for a in axes:
                a.axvspan(t[0], t[min(self.n_init, t.size - 1)], color="0.9")
        axes[1].set_ylabel("error")
        axes[1].set_xlabel("sample k" if dt is None else "time")
        axes[1].legend(fontsize=8)
        fig.tight_layout()
        return fig, axes


def compare(result, u, y, *, history=None, n_init=0, max_lag=25, confidence=0.99):
    """Validate an identified model on a record: free run and one-step prediction.

    Parameters
    ----------
    result : IdentificationResult
        The model.
    u, y : array_like
        The validation record, in the data's units.
    history : (u_past, y_past), optional
        Measured data just before the record (the free run continues from them).
    n_init : int
        Leading samples left out of every measure (a start-up transient).
    max_lag, confidence :
        Of the residual tests (:func:`~fohw.analysis.metrics.whiteness_test`,
        :func:`~fohw.analysis.metrics.cross_correlation_test`).

    Returns
    -------
    Validation
        A free run that diverges is reported in ``diverged`` (with its sample), not raised.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(1200, random_state=0)
    >>> res = fohw.identify(data.u[:800], data.y[:800], na=2, nb=2, f_basis=2, g_basis=3)
    >>> v = res.validate(data.u[800:], data.y[800:])
    >>> v.fit_prediction > v.fit_simulation, v.diverged
    (True, '')
    """
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    n_init = check_int(n_init, "n_init", minimum=0, maximum=y.size - 2)
    diverged, ysim = "", None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        try:
            ysim = result.simulate(u, history=history)
        except SimulationDivergedError as exc:
            diverged = str(exc)
    in_range = not any(issubclass(w.category, ExtrapolationWarning) for w in caught)
    for w in caught:
        if not issubclass(w.category, ExtrapolationWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    yhat = result.predict(u, y)
    fit_s = rmse_s = np.nan
    if ysim is not None:
        fit_s = fit_percent(y, ysim, n_init=n_init)
        rmse_s = rmse(y, ysim, n_init=n_init)
    residual = y - yhat
    white = xcorr = None
    if y.size - n_init > 3 * max_lag:
        white = whiteness_test(residual, max_lag=max_lag, confidence=confidence, n_init=n_init)
        xcorr = cross_correlation_test(residual, u, max_lag=max_lag, confidence=confidence,
                                       n_init=n_init)
    return Validation(y=y, simulated=ysim, predicted=yhat, fit_simulation=fit_s,
                      rmse_simulation=rmse_s,
                      fit_prediction=fit_percent(y, yhat, n_init=n_init),
                      rmse_prediction=rmse(y, yhat, n_init=n_init), whiteness=white,
                      cross_correlation=xcorr, diverged=diverged, in_range=in_range,
                      n_init=n_init)
