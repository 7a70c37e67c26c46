"""The order verdict: the corrected order test read beside held-back validation.

A likelihood-ratio test says whether the fractional orders lower the estimation criterion by
more than chance would; on measured records, model error colours the residuals and the
correction of :func:`fohw.lr_statistic.corrected_statistic` only partly undoes that. The
verdict asks the question that decides whether the order earns its keep: does the fractional
fit also *simulate held-back data* better than its orders-0 fit?

**The rule.** Both fits are made on the estimation part only. Each is simulated free (from
its own initial-state convention, as :meth:`simulate` does by default; for a
``past="estimate"`` lagged fit, from rest) on the held-back input, and scored by the fit index
(:func:`fohw.analysis.metrics.fit_percent`, MATLAB's NRMSE fit). With the corrected p-value
``p`` at level ``level`` (default 0.05) and ``margin`` (default :data:`MARGIN`, 0.5 fit points):

- ``p >= level``: ``"not significant"`` (whatever the validation says);
- ``p < level`` and ``fit_full >= fit_restricted + margin``: ``"significant and validates"``;
- ``p < level`` and not: ``"significant but does not validate (model error)"`` (a free run
  that diverges or is not finite on the held-back part does not validate);
- ``p < level`` and no held-back record: ``"significant; not validated (no held-back
  record)"``.

The margin: a gain below half a fit point is not one a user would pay a parameter for (the
issue's measured case: p = 6e-9 for a 0.16-point gain), and it is above the spread of the
difference between two nested fits of a correct model on a held-back part of a few hundred
samples. It is a setting (``margin=``), stated with every verdict.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .._validation import check_scalar
from ..exceptions import FohwError, ParameterError
from .metrics import fit_percent

__all__ = ["verdict", "validation_fits", "LEVEL", "MARGIN", "SIGNIFICANT_VALIDATES",
           "SIGNIFICANT_NOT_VALIDATED", "NOT_SIGNIFICANT", "NOT_VALIDATED", "VERDICTS"]

#: The test's level.
LEVEL = 0.05
#: Fit points by which the fractional fit must beat the orders-0 fit on held-back data.
MARGIN = 0.5

SIGNIFICANT_VALIDATES = "significant and validates"
SIGNIFICANT_NOT_VALIDATED = "significant but does not validate (model error)"
NOT_SIGNIFICANT = "not significant"
NOT_VALIDATED = "significant; not validated (no held-back record)"
#: Every verdict, in the order above.
VERDICTS = (SIGNIFICANT_VALIDATES, SIGNIFICANT_NOT_VALIDATED, NOT_SIGNIFICANT, NOT_VALIDATED)


def check_level_margin(level, margin):
    """``level`` in (0, 1) and ``margin`` >= 0 (fit points), as floats."""
    level = check_scalar(level, "level", lower=0.0, upper=1.0, lower_inclusive=False,
                         upper_inclusive=False)
    return level, check_scalar(margin, "margin", lower=0.0)


def verdict(pvalue, fit_restricted=math.nan, fit_full=math.nan, *, level=LEVEL, margin=MARGIN):
    """The order verdict from the corrected p-value and the held-back fits (the module's rule).

    Parameters
    ----------
    pvalue : float
        The corrected p-value of the order test; NaN gives ``""`` (no verdict).
    fit_restricted, fit_full : float, optional
        Held-back free-run fit % of the orders-0 and the fractional fit; both NaN: no
        held-back record. A non-finite ``fit_full`` with a finite ``fit_restricted`` (the
        fractional free run diverged) does not validate.
    level : float
        The test's level (default 0.05).
    margin : float
        Fit points the fractional fit must gain (default 0.5).

    Returns
    -------
    str
        One of :data:`VERDICTS`, or ``""``.

    Examples
    --------
    >>> from fohw.analysis.order_verdict import verdict
    >>> verdict(0.001, 80.0, 86.9), verdict(0.001, 80.0, 80.16), verdict(0.3, 80.0, 90.0)
    ('significant and validates', 'significant but does not validate (model error)', \
'not significant')
    """
    level, margin = check_level_margin(level, margin)
    pvalue = float(pvalue)
    if math.isnan(pvalue):
        return ""
    if pvalue >= level:
        return NOT_SIGNIFICANT
    fr, ff = float(fit_restricted), float(fit_full)
    if math.isnan(fr) and math.isnan(ff):
        return NOT_VALIDATED
    if math.isfinite(ff) and (not math.isfinite(fr) or ff >= fr + margin):
        return SIGNIFICANT_VALIDATES
    return SIGNIFICANT_NOT_VALIDATED


def _free_run_fit(result, u, y):
    """Free-run fit % of ``result`` on ``(u, y)``; -inf when the run is not finite."""
    kwargs = {}
    structure = getattr(result, "structure", None)
    if structure is not None and structure.past == "estimate":
        kwargs["initial"] = "rest"               # the fitted levels belong to the estimation part
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")       # an extrapolation warning is the fit % 's story
            yhat = np.asarray(result.simulate(u, **kwargs), dtype=float)
    except (FohwError, ArithmeticError, ValueError):
        return -math.inf
    if not np.all(np.isfinite(yhat)):
        return -math.inf
    return float(fit_percent(y, yhat))


def validation_fits(restricted, full, u, y):
    """``(fit_restricted, fit_full)``: both fits' free-run fit % on the held-back ``(u, y)``.

    Any kind: each result's own ``simulate(u)`` (a lagged ``past="estimate"`` fit from rest);
    a run that diverges or is not finite scores ``-inf``.
    """
    y = np.asarray(y, dtype=float)
    if y.ndim != 1 or np.ptp(y) == 0:
        raise ParameterError(f"the held-back output must be 1-D and not constant (its fit % is "
                             f"undefined otherwise); got shape {y.shape}"
                             + (f", constant {float(y[0])!r}" if y.ndim == 1 and y.size else "")
                             + ".")
    if _is_estimation_record(full, u, y):
        raise ParameterError(
            f"`validation` is the record the fit was estimated on ({y.size} samples, on which the "
            "full fit's errors are its own residuals): a verdict needs held-back data the fits "
            "never saw. Hold back a part of the experiment (fit the first 70 % of the samples "
            "and validate on the rest) or another experiment.")
    return _free_run_fit(restricted, u, y), _free_run_fit(full, u, y)


def _is_estimation_record(result, u, y):
    """Whether ``(u, y)`` is the record ``result`` was fitted to, to rounding.

    A :class:`fohw.FitResult` of one record: its free run on ``u`` leaves its stored residuals;
    a lagged result: its one-step criterion ``J`` recomputed on ``(u, y)``. False where neither
    applies (several records, a warm-up, a series output map) or the run fails.
    """
    if getattr(result, "n_samples", None) != y.size:
        return False
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            residuals = getattr(result, "residuals", None)
            if residuals is not None:
                options = getattr(result, "options", None) or {}
                if np.shape(residuals) != y.shape or options.get("warmup") or \
                        getattr(result, "per_record", None):
                    return False
                e = y - np.asarray(result.simulate(u), dtype=float)
                scale = max(float(np.max(np.abs(y))), 1e-300)
                return bool(np.allclose(e, residuals, rtol=1e-9, atol=1e-12 * scale))
            structure = getattr(result, "structure", None)
            if structure is None or structure.output_map is not None or \
                    not callable(getattr(result, "predict", None)):
                return False
            J = float(np.mean((y - np.asarray(result.predict(u, y), dtype=float)) ** 2))
            return bool(np.isclose(J, float(result.J), rtol=1e-9, atol=1e-300))
    except (FohwError, ArithmeticError, ValueError, TypeError):
        return False
