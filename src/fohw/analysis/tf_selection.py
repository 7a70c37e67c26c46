"""Choose a fractional transfer function's structure by free-run simulation on held-back data.

:func:`select_fractional_tf` is :func:`fohw.select_structure` for :func:`fohw.fit_fractional_tf`
(FOMCON-style comparison of model structures): every candidate (a dict of ``fit_fractional_tf``
keywords, e.g. its ``den_orders`` and ``free``) is fitted on the estimation part of the record,
simulated in free run from sample 0 through the held-back part it never saw, and ranked by the
fit % on that part. A candidate whose fit raises, whose free run leaves the finite numbers or the
plausible envelope of the measured output (:func:`fohw.analysis.validation.implausible_sample`)
is kept as a row with its status and reason, never scored and never picked; the others go on.
The winner is refitted on all the data; a refit that fails or is implausible is not kept, and the
next candidate is refitted instead.

It is a separate function, not a ``fitter=`` of :func:`fohw.select_structure`, because
everything there past the fit reads an :class:`fohw.IdentificationResult` (its structure and
bases for the identifiability check, its orders for the LR test against the nested integer
candidate, ``simulate(history=)``, the keyword check against ``identify``'s signature); the
table (:class:`fohw.Selection`), the split of the record and the envelope test are shared.
"""

from __future__ import annotations

import difflib
import inspect
import numbers
import time
import warnings

import numpy as np

from .._validation import check_array, check_same_length, check_scalar
from ..estimators.tf_fit import fit_fractional_tf
from ..exceptions import ParameterError, SimulationDivergedError
from .metrics import aic, bic, fit_percent, rmse
from .selection import (
    SCORES,
    Selection,
    expand_candidates,
    pick_refitted,
    split_validation,
    warn_nothing_selected,
)
from .validation import ENVELOPE, check_envelope, implausible_message, implausible_sample

__all__ = ["select_fractional_tf"]

#: Keywords every candidate must give (here or shared).
REQUIRED = ("num_orders", "den_orders")

#: Keywords that are one list per candidate (a number there is a grid written one level short).
ORDER_LISTS = ("num_orders", "den_orders", "num", "den")

#: Row ``status`` values: ``"ok"``, ``"diverged"`` (the free run left the finite numbers),
#: ``"implausible"`` (it left the measured output's envelope), ``"failed"`` (the fit or the
#: simulation raised), and for a winner whose refit on all the data was not kept,
#: ``"refit_failed"``, ``"refit_diverged"``, ``"refit_implausible"``.
STATUSES = ("ok", "diverged", "implausible", "failed", "refit_failed", "refit_diverged",
            "refit_implausible")


def _check_keywords(own, common):
    """Every candidate's keywords (shared ones merged), checked against fit_fractional_tf's."""
    known = {p.name for p in inspect.signature(fit_fractional_tf).parameters.values()
             if p.kind is p.KEYWORD_ONLY} - {"dt"}
    for key in common:
        if key == "dt" or key not in known:
            why = ("`dt` is select_fractional_tf's own argument" if key == "dt"
                   else "not a keyword of fohw.fit_fractional_tf")
            raise ParameterError(f"the keywords shared by every candidate give {key!r}: {why}.")
    cands = []
    for i, mine in enumerate(own):
        for key in mine:
            if key not in known:
                close = difflib.get_close_matches(key, sorted(known), n=1)
                why = ("`dt` is shared: give it once, select_fractional_tf(..., dt=...)"
                       if key == "dt" else "not a keyword of fohw.fit_fractional_tf"
                       + (f"; did you mean {close[0]!r}?" if close else ""))
                raise ParameterError(f"`candidates[{i}]` gives {key!r}: {why}.")
        cands.append(dict(common, **mine))
        for key in ORDER_LISTS:
            value = cands[-1].get(key)
            if isinstance(value, numbers.Real):
                where = f"`candidates[{i}]`" if key in mine else "the shared keywords"
                raise ParameterError(
                    f"{where} give {key}={value!r}, a number: orders and coefficients are a "
                    f"list per candidate, so a grid of them is a list of lists, e.g. "
                    f"{{{key!r}: [[0.5, 0.0], [1.0, 0.0]]}}.")
    for key in REQUIRED:
        missing = [i for i, c in enumerate(cands) if key not in c]
        if missing:
            raise ParameterError(f"`{key}` is required by fohw.fit_fractional_tf and missing "
                                 f"from candidate(s) {', '.join(map(str, missing[:10]))}: give "
                                 "it in `candidates` or shared (select_fractional_tf(..., "
                                 f"{key}=...)).")
    return cands


def _label(candidate):
    return " ".join(f"{k}={v}" for k, v in candidate.items())


def _free_run(fit, u, reference, envelope):
    """``(ysim, status, reason, k)``: the fitted model's free run on ``u``, the first bad sample.

    ``ysim`` is None unless the status is ``"ok"`` (then ``k`` is None).
    """
    try:
        ysim = fit.model.simulate(u)
    except SimulationDivergedError as exc:
        return None, "diverged", str(exc), exc.sample
    found = implausible_sample(ysim, reference, envelope)
    if found is not None:
        return None, "implausible", implausible_message(found, envelope), found[0]
    return ysim, "ok", "", None


def _blank_row(**changes):
    return dict(dict(status="ok", fit=np.nan, rmse=np.nan, fit_estimation=np.nan, aic=np.nan,
                     bic=np.nan, n_params=0, estimated_orders="", model="", fit_status="",
                     refit_status="", seconds=np.nan, reason=""), **changes)


def _notes(caught):
    return sorted({str(w.message).split("\n")[0] for w in caught})


def _fit_and_score(u_est, y_est, u_sim, y_score, score_from, dt, candidate, reference, envelope):
    """One candidate's row and fit (None if the fit raised); never raises."""
    t0 = time.perf_counter()
    row = _blank_row()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fit = fit_fractional_tf(u_est, y_est, dt=dt, **candidate)
        except Exception as exc:                 # noqa: BLE001 - one candidate never loses the others
            row.update(status="failed", reason=f"fit: {type(exc).__name__}: {exc}",
                       seconds=time.perf_counter() - t0)
            return row, None
        n, d = len(y_est), len(fit.free_names)
        row.update(n_params=d, model=str(fit.model),
                   fit_status="converged" if fit.converged else "budget",
                   estimated_orders=", ".join(f"{k}={v:.4g}" for k, v in fit.estimates.items()
                                              if k.startswith(("alpha", "beta"))
                                              and k in fit.free_names))
        if fit.sse > 0:
            row["aic"], row["bic"] = aic(fit.sse / n, n, d), bic(fit.sse / n, n, d)
        try:
            ysim, status, reason, k = _free_run(fit, u_sim, reference, envelope)
            if status != "ok" and score_from:
                part = "estimation" if k < score_from else "held-back"
                reason = (f"on the {part} part (samples 0-{score_from - 1} are the estimation "
                          f"part): {reason}")
            yest = ysim[:score_from] if status == "ok" and score_from else None
            if status == "ok" and not score_from:            # a separate validation record
                yest, status, reason, _ = _free_run(fit, u_est, reference, envelope)
                reason = reason and f"on the estimation input: {reason}"
        except Exception as exc:                 # noqa: BLE001 - reported in the row
            status, reason = "failed", f"simulation: {type(exc).__name__}: {exc}"
    notes = _notes(caught)
    row["seconds"] = time.perf_counter() - t0
    if status != "ok":
        row.update(status=status, reason="; ".join([reason, *notes]))
        return row, fit
    if np.ptp(y_est) > 0:
        row["fit_estimation"] = fit_percent(y_est, yest)
    row["rmse"] = rmse(y_score, ysim[score_from:])
    if np.ptp(y_score) > 0:
        row["fit"] = fit_percent(y_score, ysim[score_from:])
    else:
        notes.append("the held-back output is constant: its fit % is undefined (NaN)")
    row["reason"] = "; ".join(notes)
    return row, fit


def select_fractional_tf(u, y, candidates, *, dt, validation=0.25, score="fit", refit=True,
                         envelope=ENVELOPE, **common):
    """Choose among fractional transfer-function structures by free-run fit on held-back data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output (zero initial conditions, as :func:`fohw.fit_fractional_tf`).
    candidates : list of dict, or dict of lists
        Keywords of :func:`fohw.fit_fractional_tf` for each candidate (``num_orders`` and
        ``den_orders`` required, here or in ``**common``), or a grid ``{"den_orders": [[1, 0],
        [0.5, 0]]}`` (all combinations).
    dt : float
        Sampling time (shared by every candidate).
    validation : float, int or (u_val, y_val), optional
        The held-back part, as in :func:`fohw.select_structure`: a fraction (default 0.25) or a
        number of samples at the end, simulated on from the estimation part; or a separate
        record, simulated from rest.
    score : {"fit", "rmse", "aic", "bic"}
        The ranking (default the held-back fit %; AIC and BIC use the estimation SSE).
    refit : bool
        Refit the winner on all of ``u, y`` (default True; not with a separate record).
    envelope : float or None
        Plausibility factor of :func:`fohw.analysis.validation.implausible_sample` (default 10);
        None switches the test off.
    **common
        ``fit_fractional_tf`` keywords shared by every candidate (a candidate's own value wins).

    Returns
    -------
    Selection
        ``.rows`` (per candidate, in the order given: its keywords, ``candidate``, ``status``
        (:data:`STATUSES`), ``fit``, ``rmse``, ``fit_estimation``, ``aic``, ``bic``,
        ``n_params``, ``estimated_orders`` (the free orders), ``model``, ``fit_status``
        (``"converged"`` or ``"budget"``), ``refit_status``, ``seconds``, ``reason``),
        ``.best`` (the refitted winner, a :class:`fohw.FractionalTFFit`; None if nothing was
        selected), ``.best_row``, ``.results`` (the estimation-part fits), ``.to_markdown()``,
        ``.to_csv()``.

    Raises
    ------
    ParameterError
        At once, before any fit: bad or empty ``candidates``, a keyword ``fit_fractional_tf``
        does not take, ``num_orders``/``den_orders`` missing, a bad ``dt``, ``validation``,
        ``score`` or ``envelope``. A candidate's own failure is its row, not an exception.

    Warns
    -----
    ConvergenceWarning
        Nothing was selected; ``best`` is None and the rows say why.

    Examples
    --------
    >>> import numpy as np
    >>> import fohw
    >>> u = np.random.default_rng(0).standard_normal(300)
    >>> y = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0]).simulate(u, dt=0.05)
    >>> sel = fohw.select_fractional_tf(u, y, {"den_orders": [[1.0, 0.0], [0.5, 0.0]]},
    ...                                 dt=0.05, num_orders=[0.0], free=None)
    >>> sel.best_row["candidate"], round(sel.best.estimates["alpha0"], 3)
    ('den_orders=[0.5, 0.0]', 0.6)
    """
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    dt = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
    if score not in SCORES:
        raise ParameterError(f"`score` must be one of {sorted(SCORES)}; got {score!r}.")
    if not isinstance(refit, (bool, np.bool_)):
        raise ParameterError(f"`refit` must be True or False; got {refit!r}.")
    own = expand_candidates(candidates, what="fit_fractional_tf")
    cands = _check_keywords(own, common)
    factor = check_envelope(envelope)
    u_est, y_est, u_sim, y_score, score_from, described = split_validation(u, y, validation)
    if score == "fit" and np.ptp(y_score) == 0:
        raise ParameterError(f"the held-back output ({described}) is constant "
                             f"({float(y_score[0])!r}): no candidate can be ranked by its fit %. "
                             "Hold back a part where the output moves (`validation`), or rank "
                             "by score='rmse'.")
    reference = np.r_[y, y_score] if score_from == 0 else y
    t0 = time.perf_counter()
    rows, results = [], []
    for c, mine in zip(cands, own):
        row, fit = _fit_and_score(u_est, y_est, u_sim, y_score, score_from, dt, c, reference,
                                  factor)
        rows.append(dict(c, candidate=_label(mine), **row))
        results.append(fit)
    selection = Selection(rows=rows, best=None, best_index=None, results=results, score=score,
                          validation=described, seconds=time.perf_counter() - t0)
    _pick(selection, cands, u, y, dt, bool(refit) and score_from > 0, factor)
    if selection.best is None:
        warn_nothing_selected("select_fractional_tf", rows)
    return selection


def _pick(selection, cands, u, y, dt, refit, envelope):
    """The best scored row, refitted on all the data if asked (a rejected refit: the next)."""
    def refit_one(index):
        best = fit_fractional_tf(u, y, dt=dt, **cands[index])
        return (best, *_free_run(best, u, y, envelope)[1:3])

    def finish(row, best):
        row["refit_status"] = "converged" if best.converged else "budget"

    pick_refitted(selection, refit_one, finish, refit=refit)
