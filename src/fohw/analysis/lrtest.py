"""Does the fractional order earn its keep? The likelihood-ratio test against orders 0.

``lr_test(restricted, full)`` compares a fit of a fractional class (``full``: commensurate,
per-lag, mixed, …) with a fit of the integer class it contains (``restricted``: the same
lags, bases, offset and past with every order 0), both by the same least-squares method on the
same record. With Gaussian noise of unknown variance (profiled out), the statistic is

``LR = n log(RSS_restricted / RSS_full)``

with ``n`` the samples of the criterion: the one-step (equation-error) RSS ``N J`` of
``"varpro"`` and ``"structured"``, the free-run RSS ``details["simulation_sse"]`` over
``N - n_init`` samples of ``"output_error"``. Its reference distribution depends on how the
null sits in the full class:

*An order on the boundary* (commensurate, per-lag: ``nu >= 0`` and ``nu = 0`` under the null,
the other parameters identified): Self & Liang (1987), a chi-bar-squared mixture. One order:
``0.5 chi2_0 + 0.5 chi2_1``. ``k`` orders: ``sum_j C(k, j) 2^-k chi2_j``, which assumes the
orders' estimates are asymptotically uncorrelated given the coefficients (the weights of an
orthant with a diagonal information matrix; with correlated orders the true weights move
towards the extremes, and this mixture is then an approximation).

*An order not identified under the null* (the mixed class: the coefficients of the ``nu``-terms
are 0 under the integer model, so ``nu`` vanishes from it; Davies 1977, 1987): the mixture
does not apply. fohw offers Davies' (1987) upper bound

``P(sup LR > c) <= P(chi2_s > c) + V c^((s-1)/2) exp(-c/2) 2^(-s/2) / Gamma(s/2)``

with ``s`` the coefficients the order brings and ``V`` the total variation of
``sqrt(LR(nu))`` over the order's range, read from the profile ``LR(nu)`` on a grid (for
``"varpro"``, the grid scan it keeps in ``alpha_profile``; otherwise refits at fixed orders,
which need ``u, y``), or a parametric bootstrap (``reference="bootstrap"``: records simulated
from the restricted fit with its noise variance, both classes refitted on each).

Every reference assumes white residuals. A free run's residuals are usually correlated (by
the noise and by model error), so ``n`` overstates the information and the test rejects far
too often (30 % at 5 % on integer-order records with AR(1) output noise, pole 0.9). Every
test therefore also reports a statistic corrected from the two fits' residuals
(``correction=``, default ``"sandwich"``; :func:`fohw.lr_statistic.corrected_statistic`,
compared in docs/order_test.md) and its p-value from the same reference, beside the
white-noise one; and, given a held-back record, the verdict of
:mod:`fohw.analysis.order_verdict`. ``n_effective=`` (e.g. Bartlett's estimate,
:func:`fohw.analysis.metrics.effective_samples`) instead replaces ``n`` in the statistic
itself, ``n_effective log(RSS_restricted / RSS_full)``, with the same reference (the result's
``criterion`` says which ``n`` was used, and that statistic is then the corrected one).

The F form ``((RSS_r - RSS_f) / q) / (RSS_f / (n - d))`` is exact only for linear models with
chi2 references; the boundary and Davies references are derived for the likelihood ratio, so
fohw uses ``n log``. For ``n`` in the hundreds and ``d`` parameters the two differ by about
``d / n`` relatively (see ``docs/order_test.md`` for the measured null rejection rates).

:func:`order_test` makes the restricted fit and calls :func:`lr_test`, for every kind: a
:class:`fohw.FitResult`'s model with its free orders (``Parameter(order=True)``) held at 0,
refitted by :func:`fohw.fit` with the fit's settings (:func:`fit_at_orders_zero`); a lagged
fit's integer class, refitted by its own method.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._parallel import TaskError, run_tasks
from .._validation import check_int, check_random_state
from ..estimators.fit import fit, free_jacobian, prepare_data, records_jacobian
from ..exceptions import ConvergenceWarning, ParameterError
from ..lr_statistic import (
    CORRECTIONS,
    LRTest,
    cancelled_orders,
    check_result,
    chi_bar_squared_sf,
    corrected_statistic,
    criterion,
    mixture,
    null_orders,
    order_bounds,
    order_notes,
    statistic,
)
from ..lr_statistic import order_test as order_test_without_record
from ..model.simulate import record_list
from ..record import Record
from .order_verdict import LEVEL, MARGIN, check_level_margin, validation_fits, verdict
from .profile_interval import (
    check_data,
    check_fit_record,
    check_n_effective,
    is_fit,
    orders_with,
    refit,
)

__all__ = ["LRTest", "lr_test", "order_test", "orders_zero", "fit_at_orders_zero", "fit_options",
           "davies_bound",
           "chi_bar_squared_sf",
           "cancelled_orders", "REFERENCES", "CORRECTIONS", "score_direction"]

#: ``reference=`` spellings.
REFERENCES = ("auto", "mixture", "davies", "bootstrap")




def davies_bound(statistic, s, profile):
    """Davies' (1987) upper bound of ``P(sup_nu LR(nu) > statistic)``, LR(nu) ~ chi2_s each.

    ``profile`` is ``LR(nu)`` on a grid of the order (sorted by ``nu``); ``V`` is the total
    variation of its square root.
    """
    c = float(statistic)
    if c <= 0:
        return 1.0
    root = np.sqrt(np.maximum(np.asarray(profile, dtype=float), 0.0))
    V = float(np.sum(np.abs(np.diff(root))))
    tail = V * c ** ((s - 1) / 2) * math.exp(-c / 2) * 2 ** (-s / 2) / scipy.special.gamma(s / 2)
    return float(min(1.0, scipy.stats.chi2.sf(c, s) + tail))




def _check_nested(restricted, full):
    rs, fs = restricted.structure, full.structure
    if restricted.method != full.method:
        raise ParameterError(f"`restricted` and `full` must be fitted by the same method; got "
                             f"{restricted.method!r} and {full.method!r}.")
    if rs.orders.free:
        raise ParameterError(f"`restricted` must be the integer class (every order fixed at 0); "
                             f"it has free orders {list(rs.orders.free)} (the call is "
                             "lr_test(restricted, full)).")
    if not fs.orders.free:
        raise ParameterError(f"`full` has no free order ({fs.describe()}): nothing to test.")
    null, boundary, unidentified = null_orders(fs.orders)
    if rs.orders != null:
        raise ParameterError(f"`restricted` ({rs.describe()}) is not `full` ({fs.describe()}) "
                             f"with its orders at 0, which is {null!r}: same lags, every order 0.")
    if (rs.f_basis, rs.g_basis, rs.offset, rs.past, rs.dt) != \
            (fs.f_basis, fs.g_basis, fs.offset, fs.past, fs.dt):
        raise ParameterError(f"`restricted` ({rs.describe()}; bases {rs.f_basis!r}, "
                             f"{rs.g_basis!r}) and `full` ({fs.describe()}; bases {fs.f_basis!r}, "
                             f"{fs.g_basis!r}) differ beyond their orders.")
    if rs.output_map != fs.output_map:
        def text(m):
            return "none" if m is None else m.describe()
        raise ParameterError(f"`restricted` (output map {text(rs.output_map)}) and `full` (output map "
                             f"{text(fs.output_map)}) differ beyond their orders: the map's "
                             "parameters would enter the test beside the orders, and its reference "
                             "distribution counts the orders only. Fit both with the same "
                             "`output_map`.")
    for what in ("n_samples", "operating_point", "input_range"):
        a, b = getattr(restricted, what), getattr(full, what)
        if a != b:
            raise ParameterError(f"`restricted` and `full` were not fitted to the same record: "
                                 f"{what} {a!r} and {b!r}.")
    n_init = (restricted.options.get("n_init", 0), full.options.get("n_init", 0))
    if n_init[0] != n_init[1]:
        raise ParameterError(f"`restricted` and `full` leave out different start-up samples "
                             f"(n_init {n_init[0]} and {n_init[1]}): the criteria differ.")
    for name in fs.orders.free:
        lo, _ = order_bounds(full, name)
        if lo != 0.0:
            raise ParameterError(f"`full`'s order {name} is bounded below by {lo:g}, so orders 0 "
                                 "are not in its class: refit it with alpha_bounds starting at 0.")
    return boundary, unidentified



def _criterion_text(name, n_effective, n):
    """``LRTest.criterion``: the criterion, and the effective samples when they scale it."""
    if n_effective is None:
        return name
    return f"{name}; n_effective = {float(n_effective):.4g} of {n} samples"


def davies_from_fit(full):
    """Whether the Davies bound reads its profile from ``full`` (varpro's, no refits)."""
    return (full.method == "varpro" and full.alpha_profile is not None
            and len(full.orders) == 1 and full.structure.past == "rest")


def _davies_profile(full, rss_r, n, u, y, n_grid):
    """``LR(nu)`` on a grid of the single unidentified order (and at the estimate)."""
    (name,) = full.orders
    est = float(full.orders[name])
    stat_f = statistic(rss_r, criterion(full)[0], n)
    if davies_from_fit(full):
        grid, J = full.alpha_profile
        values = [statistic(rss_r, j * full.n_samples, n) for j in J]
    else:
        u, y = check_data(full, u, y, "full")
        lo, hi = order_bounds(full, name)
        grid = np.linspace(lo + 1e-3 * (hi - lo), hi, n_grid)
        values = []
        for v in grid:
            fit = refit(full, u, y, orders=orders_with(full.structure.orders, {name: float(v)}),
                        start=(full.linear, full.nonlinear[1:]))
            values.append(statistic(rss_r, criterion(fit)[0], n))
    order = np.argsort(np.r_[grid, est])
    return np.r_[values, stat_f][order]


def _bootstrap_one(restricted, full, u, seed, noise_std):
    """Both classes refitted on a record simulated from ``restricted`` (one bootstrap draw)."""
    rng = np.random.default_rng(seed)
    if restricted.method == "output_error":           # on the estimation record: its own past
        y = restricted.simulate(u, initial="fitted") + noise_std * rng.standard_normal(u.shape[0])
    else:
        y = restricted.simulate(u, initial="fitted", noise_std=noise_std, random_state=rng)
    r = refit(restricted, u, y)
    f = refit(full, u, y)
    rss_r, n = criterion(r)
    return statistic(rss_r, criterion(f)[0], n)




def criterion_residuals(result, u, y):
    """The residuals of ``result``'s criterion on its record (checked by the caller).

    A FitResult's own ``residuals``; for the lagged kind, the free-run errors after ``n_init``
    (``"output_error"``, from the fitted past) or the one-step errors (``"varpro"``,
    ``"structured"``).
    """
    if is_fit(result):
        return None if result.residuals is None else np.asarray(result.residuals, dtype=float)
    if u is None:
        return None
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")           # the fit's own record: no extrapolation
        if result.method == "output_error":
            n_init = int(result.options.get("n_init", 0))
            return (y - result.simulate(u, initial="fitted"))[n_init:]
        return y - result.predict(u, y)


def criterion_rows(result, rows):
    """``rows`` (a FitResult's residuals, or a Jacobian's rows) as they enter its criterion.

    A fit's criterion is ``sum_k w_k e_k^2`` over its samples (``options["sample_weight"]``):
    each row is scaled by ``sqrt(w_k)`` and the samples of weight 0, held back from the fit, are
    dropped, so they do not enter the correction for correlated residuals (a held-back block
    whose residuals are huge would otherwise set it). ``rows`` unchanged without weights; None
    for None, or for rows that are not one per sample of the fit.
    """
    if rows is None:
        return None
    rows = np.asarray(rows, dtype=float)
    weight = result.options.get("sample_weight") if is_fit(result) else None
    if weight is None:
        return rows
    weight = np.asarray(weight, dtype=float)
    if rows.shape[0] != weight.shape[0]:
        return None
    keep = weight > 0
    root = np.sqrt(weight[keep])
    return rows[keep] * (root if rows.ndim == 1 else root[:, None])


def score_direction(restricted, full, u):
    """The score direction of the sandwich correction, or None where there is none.

    The sensitivities of ``full``'s free run to the tested parameters at the null (the
    restricted estimate, the tested parameters at their restricted values: orders 0), the other
    free parameters' sensitivities projected out; rows over the criterion's samples. A
    FitResult's through :func:`fohw.estimators.fit.free_jacobian` (the kind's exact Jacobian,
    or finite differences); the lagged kind's through the exact
    :func:`fohw.model.lagged.sensitivity.simulation_jacobian` of ``full``'s structure at
    ``[restricted.linear, 0, restricted.nonlinear]``, checked to reproduce the restricted
    fit's free run. None without the record ``u``; for an equation-error lagged fit (its
    criterion is not the free run), several inputs, an order not identified under the null
    (the mixed class); or when the Jacobian cannot be computed.
    """
    if u is None:
        return None
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            if is_fit(full):
                values = {name: p.value for name, p in restricted.parameters.items()}
                tested = [n for n in full.parameters.free_names
                          if restricted.parameters[n].fixed]
                null = full.model.with_parameters(values)
                names = list(null.parameters.free_names)
                if not tested or any(n not in names for n in tested) or \
                        getattr(full, "n_per_record", 0):
                    return None     # (per-record values: no single model to differentiate)
                if record_list(u) is None:
                    _, jac, _ = free_jacobian(null, u)
                else:                   # records: run as the fit ran them
                    experiments, _ = prepare_data(null, u, None, None,
                                                  int(full.options.get("warmup") or 0),
                                                  full.options.get("refine"))
                    _, jac, _ = records_jacobian(null, experiments)
                idx = [names.index(n) for n in tested]
                jac = criterion_rows(full, jac)     # the weighted rows, projected as weighted
                if jac is None:
                    return None
            else:
                jac, idx = _lagged_jacobian(restricted, full, u)
                if jac is None:
                    return None
        T, X = jac[:, idx], np.delete(jac, idx, axis=1)
        if X.shape[1]:
            T = T - X @ np.linalg.lstsq(X, T, rcond=None)[0]
        return T if np.all(np.isfinite(T)) and np.any(T) else None
    except (ParameterError, ValueError, ArithmeticError, np.linalg.LinAlgError):
        return None


def _lagged_jacobian(restricted, full, u):
    """``(jacobian rows over the criterion, tested columns)`` of a lagged output-error pair."""
    from ..model.lagged.sensitivity import simulation_jacobian

    s = full.structure
    if (full.method != "output_error" or s.n_inputs != 1 or null_orders(s.orders)[2]
            or restricted.structure.layout.names != s.layout.names):
        return None, None
    n_orders = len(s.orders.free)
    params = np.r_[np.zeros(n_orders), np.asarray(restricted.nonlinear, dtype=float)]
    if params.shape[0] != len(s.nonlinear_names):
        return None, None
    u0, y0 = full.operating_point
    u = np.asarray(u, dtype=float)
    yhat, jac = simulation_jacobian(s, np.asarray(restricted.linear, dtype=float), params,
                                    u - u0 if u0 else u, y0=y0)
    own = np.asarray(restricted.simulate(u, initial="fitted"), dtype=float) - y0
    if not np.max(np.abs(yhat - own)) <= 1e-6 * max(float(np.max(np.abs(own))), 1e-300):
        return None, None               # (e.g. levels of the past the structure does not hold)
    n_init = int(full.options.get("n_init", 0))
    first = len(s.linear_names)
    return np.asarray(jac, dtype=float)[n_init:], list(range(first, first + n_orders))


def _corrected(stat, e_r, e_f, correction, n_effective, pvalue_of, direction=None):
    """``(statistic, pvalue, text)`` of the correction for correlated residuals."""
    if n_effective is not None:
        return stat, pvalue_of(stat), "the n_effective given scales the statistic"
    if correction is None:
        return math.nan, math.nan, "correction=None"
    if e_r is None or e_f is None:
        return math.nan, math.nan, ("needs both fits' residuals: the lagged kind's results keep "
                                    "none, pass u=, y=")
    try:
        if direction is not None and direction.shape[0] != np.shape(e_f)[0]:
            direction = None
        value, text = corrected_statistic(e_r, e_f, stat, correction=correction,
                                          direction=direction)
    except ParameterError as exc:
        return math.nan, math.nan, f"none: {exc}"
    return value, pvalue_of(value), text


def _check_correction(correction):
    if correction is not None and correction not in CORRECTIONS:
        raise ParameterError(f"`correction` must be one of {CORRECTIONS} or None; got "
                             f"{correction!r}.")


def _with_verdict(test, restricted, full, validation, level, margin):
    """``test`` with its held-back fits (``validation=(u, y)`` or a Record) and its verdict."""
    fits = ()
    if validation is not None:
        try:
            u_val, y_val = ((validation.u, validation.y) if isinstance(validation, Record)
                            else validation)
        except (TypeError, ValueError):
            raise ParameterError(f"`validation` must be the held-back record (u, y) or a "
                                 f"fohw.Record; got "
                                 f"{type(validation).__name__}.") from None
        fits = validation_fits(restricted, full, u_val, y_val)
    text = verdict(test.pvalue_corrected, *(fits or (math.nan, math.nan)), level=level,
                   margin=margin)
    return dataclasses.replace(test, validation=tuple(fits), verdict=text,
                               margin=margin if fits else math.nan)


def lr_test(restricted, full, *, reference="auto", u=None, y=None, n_bootstrap=199,
            random_state=None, executor=None, n_grid=21, n_effective=None,
            correction="sandwich", validation=None, level=LEVEL, margin=MARGIN):
    """Likelihood-ratio test of a fractional class (``full``) against orders 0 (``restricted``).

    Parameters
    ----------
    restricted : IdentificationResult or FitResult
        The integer class: ``full``'s structure with every order 0 (for the mixed class, the
        order-0 terms only), same method, same record. Or a :class:`fohw.FitResult` of any
        other kind: ``full``'s model (same kind and settings) with some of its free parameters
        held fixed (e.g. an order at 1), fitted to the same record (its ``data_digest``,
        ``n_samples`` and ``dt``).
    full : IdentificationResult or FitResult
        A ``"varpro"``, ``"structured"`` or ``"output_error"`` fit with free orders bounded
        below by 0; or the FitResult with those parameters free. Their statistic is
        ``n log(SSE_restricted / SSE_full)`` with ``df`` the parameters fixed in
        ``restricted``, referred to ``chi2_df``, or to the chi-bar-squared mixture for
        values on their bounds in ``full`` (an order at 0 with bounds (0, 2)).
    reference : {"auto", "mixture", "davies", "bootstrap"}
        The reference distribution. ``"auto"``: the chi-bar-squared mixture when every free
        order is on the boundary under the null, Davies' bound when an order is not identified
        there (the mixed class). ``"mixture"`` is refused for an unidentified order.
    u, y : array_like, optional
        The record both were fitted to (results keep no data), or a :class:`fohw.Record` as
        ``u`` (``y`` omitted); for two FitResults also the list of Records they were fitted
        to. Needed by the bootstrap and by Davies' bound unless ``full`` is a ``"varpro"``
        fit of one free order (its scan is the profile). When given, they are checked
        against both fits' ``J``. For two FitResults, checked against their fingerprint,
        and ``full`` is refitted from its own and the restricted estimate (:func:`fohw.fit`
        with ``start=``), so its SSE never ends above the restricted one (without them a
        full fit above it gives 0 and a warning).
    n_bootstrap : int
        Bootstrap records (default 199).
    random_state : None, int or Generator
        Seeds the bootstrap.
    executor : concurrent.futures.Executor, optional
        Runs the bootstrap refits.
    n_grid : int
        Points of the order grid for Davies' profile when it is refitted.
    n_effective : float, optional
        The samples that scale the statistic, ``n_effective log(RSS_restricted / RSS_full)``,
        in ``[1, n]``; default ``n``, the samples of the criterion (white residuals). For
        correlated residuals, e.g. Bartlett's
        :func:`fohw.analysis.metrics.effective_samples` of ``full.residuals``; the reference
        distribution is unchanged (an approximation) and ``criterion`` names the ``n`` used.
        Not with ``reference="bootstrap"``, which calibrates the statistic itself. When
        given, it is the correction (``statistic_corrected`` is this statistic).
    correction : {"sandwich", "bartlett", "prewhitened"} or None
        The correction of the statistic for correlated residuals, reported beside the
        white-noise one (:func:`fohw.lr_statistic.corrected_statistic`; docs/order_test.md
        measures their size and power). It needs both fits' residuals: a FitResult keeps
        them; for the lagged kind pass ``u``, ``y``. A fit's ``sample_weight`` applies (its
        residuals and score direction scaled by ``sqrt(w)``; samples of weight 0 left out).
        None (NaN) with ``reference="bootstrap"`` (its records have white noise).
    validation : (u, y) or Record, optional
        A held-back record neither fit saw: both fits are simulated free on it and the test
        is read beside their fit % (:mod:`fohw.analysis.order_verdict`) into ``verdict``.
    level, margin : float
        The verdict's level (0.05) and the fit points the fractional fit must gain on the
        held-back record (0.5).

    Returns
    -------
    LRTest
        ``.statistic``, ``.df``, ``.pvalue``, ``.distribution``, ``.note``; corrected:
        ``.statistic_corrected``, ``.pvalue_corrected``, ``.correction``; ``.validation``,
        ``.verdict``.

    Raises
    ------
    ParameterError
        Wrong types, a method that is not a least-squares optimum, a pair that is not nested
        (the message says how: another kind or settings, fits to two records or at two step
        sizes, parameters that are not one model's with some fixed), an unknown
        ``reference``, missing data, or ``n_effective`` outside ``[1, n]``.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> kw = dict(na=2, nb=2, f_basis=2, g_basis=3)
    >>> integer = fohw.identify(data.u, data.y, orders=0, **kw)
    >>> frac = fohw.identify(data.u, data.y, orders="commensurate", **kw)
    >>> t = fohw.lr_test(integer, frac)
    >>> t.distribution, t.df, t.pvalue < 1e-6
    ('chi2 mixture 0.5*chi2_0 + 0.5*chi2_1', 1, True)
    """
    _check_correction(correction)
    level, margin = check_level_margin(level, margin)
    if is_fit(restricted) or is_fit(full):
        test = _lr_fits(restricted, full, reference, u, y, n_effective, correction)
        return _with_verdict(test, restricted, full, validation, level, margin)
    restricted = check_result(restricted, "restricted")
    full = check_result(full, "full")
    if reference not in REFERENCES:
        raise ParameterError(f"`reference` must be one of {REFERENCES}; got {reference!r}.")
    boundary, unidentified = _check_nested(restricted, full)
    if u is not None or y is not None:
        u, y = check_data(restricted, u, y, "restricted")
        check_data(full, u, y, "full")
    rss_r, n_criterion = criterion(restricted)
    rss_f, _ = criterion(full)
    n = check_n_effective(n_effective, n_criterion)
    if n_effective is not None and reference == "bootstrap":
        raise ParameterError("`n_effective` does not apply with reference='bootstrap': the "
                             "bootstrap records have white noise and calibrate the statistic "
                             "themselves; use 'mixture' or 'davies' with n_effective.")
    stat = statistic(rss_r, rss_f, n)
    df = (full.structure.n_linear - restricted.structure.n_linear
          + full.structure.n_nonlinear - restricted.structure.n_nonlinear)
    notes = order_notes(full, rss_r, rss_f)
    if reference == "auto":
        reference = "davies" if unidentified else "mixture"
    boot = None
    if reference == "mixture":
        if unidentified:
            raise ParameterError(f"`reference='mixture'` does not apply: the order(s) "
                                 f"{list(unidentified)} are not identified under the null (their "
                                 "coefficients are 0 there; Davies 1977); use 'davies' or "
                                 "'bootstrap'.")
        pvalue, distribution = mixture(stat, len(boundary))

        def pvalue_of(x):
            return mixture(x, len(boundary))[0]
    elif reference == "davies":
        if len(unidentified) != 1 or len(full.orders) != 1:
            raise ParameterError("`reference='davies'` is implemented for one free order that is "
                                 f"not identified under the null; `full` has {list(full.orders)} "
                                 f"({list(unidentified)} unidentified): use 'bootstrap'.")
        s = df - 1
        profile = _davies_profile(full, rss_r, n, u, y, check_int(n_grid, "n_grid", minimum=3))
        pvalue = davies_bound(stat, s, profile)
        distribution = "Davies bound"

        def pvalue_of(x):            # the profile scaled as the statistic is
            return davies_bound(x, s, profile * (x / stat if stat > 0 else 1.0))
    else:
        n_bootstrap = check_int(n_bootstrap, "n_bootstrap", minimum=1)
        if u is None:
            check_data(restricted, u, y, "restricted")
        rng = check_random_state(random_state)
        seeds = rng.integers(0, 2**63 - 1, size=n_bootstrap)
        noise_std = math.sqrt(rss_r / n)
        values = run_tasks(_bootstrap_one, [(restricted, full, u, int(s), noise_std)
                                            for s in seeds], executor=executor,
                           label="lr_test bootstrap")
        failed = [v for v in values if isinstance(v, TaskError)]
        if failed:
            raise ParameterError(f"{len(failed)} bootstrap refits could not be run on `executor`: "
                                 f"{failed[0].message}")
        boot = np.array(values, dtype=float)
        pvalue = float((1 + np.sum(boot >= stat)) / (n_bootstrap + 1))
        mc = math.sqrt(max(pvalue * (1 - pvalue), 1e-12) / n_bootstrap)
        notes.append(f"Bootstrap p-value from {n_bootstrap} records (Monte Carlo sd {mc:.2g}).")
        distribution = "bootstrap"
        pvalue_of = None
    if pvalue_of is None:
        stat_c, p_c, text = (math.nan, math.nan, "none: the bootstrap records have white "
                             "noise; use reference='mixture' or 'davies' for a corrected test")
    else:
        direction = score_direction(restricted, full, u) if correction == "sandwich" else None
        stat_c, p_c, text = _corrected(stat, criterion_residuals(restricted, u, y),
                                       criterion_residuals(full, u, y), correction,
                                       n_effective, pvalue_of, direction)
    crit_name = "free-run RSS" if full.method == "output_error" else "one-step RSS"
    test = LRTest(statistic=stat, df=df, pvalue=float(pvalue), distribution=distribution,
                  criterion=_criterion_text(crit_name, n_effective, n_criterion),
                  n=int(round(n)), rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, unidentified=unidentified, note=" ".join(notes),
                  bootstrap=boot, statistic_corrected=float(stat_c),
                  pvalue_corrected=float(p_c), correction=text)
    return _with_verdict(test, restricted, full, validation, level, margin)


def _short(value, width=80):
    """``repr(value)``, cut to ``width`` characters (an OCV table is long)."""
    text = repr(value)
    return text if len(text) <= width else text[:width - 5] + " ...)"


def settings_differ(restricted_model, full_model, u=None):
    """Why two models of one kind differ in their settings apart from their parameters, or None.

    ``restricted_model`` is given ``full_model``'s parameters (values, bounds, fixed flags,
    ties), so that only the settings that are not parameters are compared:

    1. when both give a :meth:`~fohw.Model.config` (the settings a file holds), the two
       configs must be equal;
    2. when one cannot (e.g. a circuit whose OCV map is a Python function, which no file can
       hold), the kind's own ``==`` decides (the circuit's compares its OCV maps with ``==``:
       the same function, the same bound method of one object, or equal tables); a kind
       whose ``==`` needs ``config()`` too cannot be compared, which is said;
    3. with a record ``u``, both must also simulate it to the same output (to 1e-12 of its
       largest magnitude): a setting the first two cannot see still shows in the output.
    """
    if type(restricted_model) is not type(full_model):
        return (f"a {type(restricted_model).__name__} and a {type(full_model).__name__} are "
                "different model kinds")
    try:
        aligned = restricted_model.with_parameters(full_model.parameters)
    except (ParameterError, KeyError) as exc:
        return f"`full`'s parameters do not fit `restricted`'s model ({exc})"
    try:
        rc, fc = aligned.config(), full_model.config()
    except ParameterError:
        try:
            same = bool(aligned == full_model)
        except ParameterError:
            if u is None:
                return ("a setting of the kind has no config() and its == needs one, so the "
                        "settings cannot be compared without the record: pass u=, y=")
            same = True         # decided by the simulation below
        if not same:
            return (f"the {type(full_model).__name__}'s == says their settings differ (a "
                    "setting no file can hold, e.g. a Python-function OCV map, must be the same "
                    "object in both)")
    else:
        if rc != fc:
            keys = [k for k in dict.fromkeys([*rc, *fc]) if rc.get(k) != fc.get(k)]
            return "their config() differ in " + "; ".join(
                f"{k!r} ({_short(rc.get(k))} and {_short(fc.get(k))})" for k in keys)
    if record_list(u) is not None:          # records: the first one's input shows a setting
        u = record_list(u)[0].u
    if u is not None:
        with np.errstate(all="ignore"):
            try:
                yr = np.asarray(aligned.simulate(u), dtype=float)
            except (ParameterError, ArithmeticError) as exc:
                return f"`restricted`'s model with `full`'s values does not simulate the record ({exc})"
            yf = np.asarray(full_model.simulate(u), dtype=float)
            scale = float(np.nanmax(np.abs(yf))) if np.any(np.isfinite(yf)) else 1.0
            gap = np.abs(yr - yf)
            bad = np.flatnonzero(~(gap <= 1e-12 * scale) & ~(np.isnan(yr) & np.isnan(yf)))
        if bad.size:
            k = int(bad[0])
            return (f"with the same parameter values they simulate the record differently "
                    f"(sample {k}: {yr[k]!r} and {yf[k]!r}), so a setting that is not a "
                    "parameter differs")
    return None


def nested_fits(restricted, full, u=None):
    """``(fixed names, boundary names)`` of two FitResults, or a ParameterError saying why not.

    Same kind and settings (:func:`settings_differ`; with the record ``u`` also compared by
    simulation), one record (its fingerprint, ``n_samples`` and ``dt``), and ``restricted`` is
    ``full`` with some free parameters held fixed at values inside their bounds in ``full``
    (on a bound: a boundary of the parameter space).
    """
    for name, res in (("restricted", restricted), ("full", full)):
        if not is_fit(res):
            raise ParameterError(f"`restricted` and `full` must both be fohw.FitResult (fits of "
                                 f"the same kind); `{name}` is a {type(res).__name__}.")
    rm, fm = restricted.model, full.model
    if rm.dt != fm.dt:
        raise ParameterError(f"`restricted` and `full` were fitted at different step sizes "
                             f"(dt {rm.dt!r} and {fm.dt!r}): their criteria are of different "
                             "records, so their ratio tests nothing.")
    if restricted.parameters.names == full.parameters.names or type(rm) is not type(fm):
        why = settings_differ(rm, fm, u)
        if why is not None:
            raise ParameterError(f"`restricted` and `full` must be fits of one model kind with "
                                 f"the same settings; got {type(rm).__name__} and "
                                 f"{type(fm).__name__} fits: {why}.")
    if restricted.n_samples != full.n_samples or restricted.data_digest != full.data_digest:
        raise ParameterError(f"`restricted` and `full` were not fitted to the same record "
                             f"({restricted.n_samples} and {full.n_samples} samples, "
                             f"fingerprints {restricted.data_digest or 'none'} and "
                             f"{full.data_digest or 'none'}): their criteria are of different "
                             "data, so their ratio tests nothing.")
    rp, fp = restricted.parameters, full.parameters
    if rp.names != fp.names:
        raise ParameterError(f"`restricted` and `full` have different parameters ({list(rp)} and "
                             f"{list(fp)}): they are not one model with some of them fixed.")
    fixed, boundary = [], []
    for name, f in fp.items():
        r = rp[name]
        if f.free and r.fixed:
            if not f.bounds[0] <= r.value <= f.bounds[1]:
                raise ParameterError(f"`restricted` holds {name} = {r.value!r}, outside its "
                                     f"bounds {f.bounds} in `full`: the restricted model is not "
                                     "in the full class.")
            fixed.append(name)
            if r.value in f.bounds:
                boundary.append(name)
        elif (r.bounds, r.fixed, r.tie, r.order) != (f.bounds, f.fixed, f.tie, f.order) or \
                (f.fixed and r.value != f.value):
            raise ParameterError(
                f"`restricted` is not `full` with some free parameters fixed: parameter {name} "
                f"is {r!r} in `restricted` and {f!r} in `full` (the call is "
                "lr_test(restricted, full)).")
    if not fixed:
        raise ParameterError(f"`restricted` fixes no parameter that `full` frees (free in both: "
                             f"{list(fp.free_names)}): nothing to test.")
    return tuple(fixed), tuple(boundary)


def _lr_fits(restricted, full, reference, u, y, n_effective, correction):
    """:func:`lr_test` of two :class:`fohw.FitResult` (any kind but the lagged one)."""
    if u is not None or y is not None:
        u, y = check_fit_record(restricted, u, y, "restricted")
    fixed, boundary = nested_fits(restricted, full, u)
    if reference not in REFERENCES:
        raise ParameterError(f"`reference` must be one of {REFERENCES}; got {reference!r}.")
    if reference not in ("auto", "mixture"):
        raise ParameterError(f"`reference={reference!r}` is for the lagged kind's orders; a fit "
                             f"of a {type(full.model).__name__} is tested against chi2 (or the "
                             "chi-bar-squared mixture for a value on its bound): use 'auto'.")
    notes = []
    rss_r, rss_f = restricted.sse, full.sse
    n = check_n_effective(n_effective, full.n_samples)
    if u is not None:
        with warnings.catch_warnings():       # its status is the user's `full`'s business
            warnings.simplefilter("ignore", ConvergenceWarning)
            again = fit(full.model, u, y, start=restricted.model, **fit_options(full, u))
        if again.sse < rss_f * (1 - 1e-6):
            notes.append(f"`full` refitted from its estimate and the restricted one: SSE "
                         f"{rss_f:.6g} -> {again.sse:.6g}.")
        rss_f = min(rss_f, again.sse)
    if rss_f > rss_r * (1 + 1e-9):
        text = (f"The full fit's SSE ({rss_f:.6g}) is above the restricted one's ({rss_r:.6g}), "
                "though its class contains it: the full fit missed its optimum (pass u=, y= to "
                "refit it from the restricted estimate); the statistic is set to 0.")
        notes.append(text)
        warnings.warn(text, ConvergenceWarning, stacklevel=3)
    stat = statistic(rss_r, rss_f, n)
    df, k = len(fixed), len(boundary)
    def pvalue_of(x):
        if k == 0:
            return float(scipy.stats.chi2.sf(x, df))
        if k == df:
            return mixture(x, k)[0]
        # Self & Liang: k values on their bounds, df - k inside
        return float(sum(math.comb(k, j) * 0.5 ** k * scipy.stats.chi2.sf(x, df - k + j)
                         for j in range(k + 1)))

    pvalue = pvalue_of(stat)
    distribution = (f"chi2_{df}" if k == 0 else mixture(stat, k)[1] if k == df else
                    f"chi-bar-squared sum_j C({k},j)/2^{k} chi2_({df - k}+j)")
    e_f = full.residuals
    if u is not None and again.sse < full.sse * (1 - 1e-6):
        e_f = again.residuals                  # the refit's, whose SSE the statistic uses
    direction = score_direction(restricted, full, u) if correction == "sandwich" else None
    stat_c, p_c, text = _corrected(stat, criterion_rows(restricted, restricted.residuals),
                                   criterion_rows(full, e_f), correction, n_effective,
                                   pvalue_of, direction)
    rp = restricted.parameters
    return LRTest(statistic=stat, df=df, pvalue=pvalue, distribution=distribution,
                  criterion=_criterion_text("free-run RSS", n_effective, full.n_samples),
                  n=int(round(n)), rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, note=" ".join(notes),
                  hypothesis=", ".join(f"{name} = {rp[name].value:g}" for name in fixed),
                  statistic_corrected=float(stat_c), pvalue_corrected=float(p_c),
                  correction=text)




def orders_zero(full):
    """``full``'s model with its free orders held fixed at 0, and their names.

    The orders are the free parameters marked ``Parameter(order=True)``; each must have 0
    within its bounds (the null inside the full class). Raises a ParameterError naming the
    fit's parameters when none is free, and the order and its bounds when 0 is outside them.
    """
    params = full.parameters
    orders = tuple(n for n in params.free_names if params[n].order)
    kind = type(full.model).__name__
    if not orders:
        listed = ", ".join(f"{n} ({'order, ' if p.order else ''}"
                           f"{'fixed' if p.fixed else 'tied' if p.tie else 'free'})"
                           for n, p in params.items())
        raise ParameterError(f"`full` (a {kind} fit) has no free order (a free parameter marked "
                             f"Parameter(order=True)): nothing to test against orders 0. Its "
                             f"parameters: {listed}.")
    for name in orders:
        lo, hi = params[name].bounds
        if not lo <= 0.0 <= hi:
            raise ParameterError(f"`full`'s order {name} is bounded to ({lo:g}, {hi:g}), so orders 0 "
                                 f"are outside its bounds: the null is not in the {kind}'s class "
                                 "(refit it with bounds that hold 0, where the kind allows them; "
                                 "or test another value with fohw.lr_test).")
    for name in orders:
        params = params.replace(name, value=0.0, fixed=True)
    try:
        model = full.model.with_parameters(params)
    except ParameterError as exc:
        raise ParameterError(f"the {kind} refuses its orders {list(orders)} held at 0: "
                             f"{exc}") from None
    return model, orders


def fit_at_orders_zero(full, data_or_u, y=None):
    """:func:`fohw.fit` of ``full``'s model with its free orders held at 0, on ``full``'s data.

    The same settings as ``full`` (its ``options``: ``order_grid``, ``n_starts``, ``max_nfev``,
    ``tol``, ``sample_weight``, ``per_record``, ``warmup``, ``refine``), started from the
    kind's starts and from ``full``'s estimate with the orders put to 0 (``start=``), so it
    never ends above that nested model's simulation error. Its ConvergenceWarning is not
    raised (the test's note reports a restricted fit that did not converge); a
    RankDeficiencyWarning is (orders 0 that leave parameters unidentified: the order is then
    not identified under the null, and the chi2 reference does not hold).
    """
    model, orders = orders_zero(full)
    per = [n for n in full.options.get("per_record") or () if n in orders]
    if per:
        raise ParameterError(f"`full` estimates the order(s) {per} once per record: holding them "
                             "at 0 fixes one value per record, which the test's degrees of "
                             "freedom do not count; fit the order shared (per_record without it).")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return fit(model, data_or_u, y, start=model, **fit_options(full, data_or_u))


def fit_options(full, data_or_u):
    """``full.options`` as :func:`fohw.fit` takes them again for the same data.

    The fit keeps its ``sample_weight`` as one array over the records it was given; for a list
    of Records it is split back into one array per record.
    """
    options = dict(full.options)
    records = record_list(data_or_u)
    weight = options.get("sample_weight")
    if records is not None and len(records) > 1 and weight is not None:
        weight = np.asarray(weight, dtype=float)
        bounds = np.cumsum([0] + [r.n_samples for r in records])
        options["sample_weight"] = [weight[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    return options


def _restricted_note(test, restricted):
    """``test`` with a note when the fit at orders 0 did not converge."""
    if restricted.status.name == "CONVERGED":
        return test
    text = (f"The fit at orders 0 ended {restricted.status.name}: {restricted.message}"
            + (" Orders 0 leave parameters unidentified: an order not identified under the null "
               "(Davies 1977), for which the chi2 reference does not hold."
               if restricted.status.name == "RANK_DEFICIENT" else ""))
    return dataclasses.replace(test, note=" ".join(t for t in (test.note, text) if t))


def order_test(full, data_or_u=None, y=None, *, correction="sandwich", validation=None,
               level=LEVEL, margin=MARGIN):
    """The test of a fit's free orders against orders 0, and its verdict, for every kind.

    The restricted fit is ``full``'s model with every free order (``Parameter(order=True)``)
    held at 0, fitted to the same data with the same settings; :func:`lr_test` of it against
    ``full`` gives the statistic ``n log(SSE_restricted / SSE_full)``, its p-value (the
    chi-bar-squared mixture for orders on their lower bound 0, chi2 for 0 inside the bounds),
    the statistic corrected for correlated residuals (``correction``) and, with a held-back
    ``validation=(u, y)``, the verdict (:mod:`fohw.analysis.order_verdict`).

    - A :class:`fohw.FitResult` (any kind, :func:`fohw.fit`): the restricted fit is
      :func:`fohw.fit` of the model at orders 0 with ``full``'s options, started from the
      kind's starts and from ``full``'s estimate with the orders put to 0; ``full`` is refitted
      from the restricted estimate too (:func:`lr_test`), so neither ends above what it should.
    - A lagged :class:`fohw.IdentificationResult` (:func:`fohw.identify`): its own method
      refits the integer class (``full``'s structure with every order 0, its output map kept).
      Without the record: :func:`fohw.lr_statistic.order_test` (the integer fit the
      ``"output_error"`` chain kept, no refit; white-noise statistic only).

    Parameters
    ----------
    full : FitResult or IdentificationResult
        A fit with free orders whose bounds hold 0 (an order bounded away from 0, e.g. a
        ZARC's in (0, 1], is refused: the null is outside the bounds).
    data_or_u : Record, list of Record or array_like
        The data ``full`` was fitted to (checked against its fingerprint, or for the lagged
        kind its criterion): a :class:`fohw.Record`, a list of Records, or the input ``u``
        with ``y``. Optional for the lagged kind only.
    y : array_like, optional
        The measured output, with an array ``u``.
    correction, validation, level, margin
        As for :func:`lr_test`.

    Returns
    -------
    LRTest
        Its ``hypothesis`` names the orders held at 0 for a FitResult; its ``note`` says when
        the fit at orders 0 did not converge. None for a lagged fit without the record that
        kept no integer fit.

    Raises
    ------
    ParameterError
        No free order (the message names the fit's parameters), an order whose bounds do not
        hold 0, data that are not ``full``'s, or a ``validation`` without the data.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(300, random_state=0)
    >>> kw = dict(na=1, nb=1, f_basis=1, g_basis=1, method="output_error")
    >>> full = fohw.identify(data.u[:200], data.y[:200], orders="commensurate", **kw)
    >>> t = fohw.order_test(full, data.u[:200], data.y[:200],
    ...                     validation=(data.u[200:], data.y[200:]))
    >>> from fohw.analysis.order_verdict import VERDICTS
    >>> t.correction.split(":")[0], t.verdict in VERDICTS
    ('sandwich', True)
    """
    if data_or_u is None and y is None:
        if validation is not None:
            raise ParameterError("`validation` needs the estimation record too: "
                                 "fohw.order_test(full, u, y, validation=(u_val, y_val)).")
        return order_test_without_record(full)      # a FitResult: refused, naming the call
    if is_fit(full):
        orders_zero(full)                    # refuse before the data are read
        check_fit_record(full, data_or_u, y, "full")
        restricted = fit_at_orders_zero(full, data_or_u, y)
        test = lr_test(restricted, full, u=data_or_u, y=y, correction=correction,
                       validation=validation, level=level, margin=margin)
        return _restricted_note(test, restricted)
    # The lagged kind: its own method refits the integer class (same method).
    full = check_result(full, "full")
    data_or_u, y = check_data(full, data_or_u, y, "full")
    if not full.structure.orders.free:
        raise ParameterError(f"`full` has no free order ({full.structure.describe()}): "
                             "nothing to test.")
    null, _, _ = null_orders(full.structure.orders)
    restricted = refit(full, data_or_u, y, orders=null)
    return lr_test(restricted, full, u=data_or_u, y=y, correction=correction,
                   validation=validation, level=level, margin=margin)
