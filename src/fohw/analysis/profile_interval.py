"""Profile-likelihood intervals of the free orders, and refits of a result's model class.

For a free order ``nu`` of a fit, the profile criterion is the least residual sum of squares
with ``nu`` held at a value and every other parameter refitted, ``RSS(nu)``; with Gaussian
noise of unknown variance (profiled out) the likelihood-ratio statistic is

``LR(nu) = n log(RSS(nu) / RSS(nu_hat))``

(``n`` the samples of the criterion, or an effective sample size ``n_effective`` given for
correlated residuals), and the interval of level ``1 - a`` is the set where
``LR(nu) <= chi2_1 quantile(1 - a)`` (Wilks). For ``"varpro"`` and ``"structured"`` the
criterion is the one-step (equation-error) RSS, ``N J``; for ``"output_error"`` the free-run
RSS. ``RSS(nu)`` is a public :func:`fohw.identify` call with that order fixed (for ``"varpro"``
it is exactly the separable least-squares solution at fixed orders), and an
``"output_error"`` refit starts from the full fit's other parameters. The interval's ends are
found by a coarse grid over the order's bounds and Brent's method between the grid points
that bracket the quantile; an end whose criterion never reaches the quantile is the bound
itself (a one-sided interval). The result objects keep no data, so ``u`` and ``y`` (the
record the fit was made on, checked against the fit's ``J``; for a :class:`fohw.FitResult`,
against its fingerprint) are passed again. A :class:`fohw.FitResult` of any other kind is
profiled the same way, each ``RSS(nu)`` a :func:`fohw.fit` with the fit's own options.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_array, check_inputs, check_int, check_same_length, check_scalar
from ..estimators.fit import check_record, data_digest, data_digest_of, fit, prepare_data
from ..estimators.identify import identify
from ..exceptions import ConvergenceWarning, ParameterError, RankDeficiencyWarning
from ..fit_result import FitResult
from ..lr_statistic import LIKELIHOOD_METHODS, check_result, criterion, order_bounds
from ..model.orders import Orders
from ..model.simulate import record_list, simulate_record
from ..record import check_sampling, record_data
from ..results import IdentificationResult

__all__ = ["ProfileInterval", "profile_interval", "refit", "orders_with", "criterion",
           "check_data", "check_fit_record", "records_digest", "check_n_effective", "fit_weight",
           "sse_with_fixed", "LIKELIHOOD_METHODS"]




def check_data(result, u, y, name):
    """``u``, ``y`` as arrays, checked to be the record ``result`` was fitted to.

    The check recomputes the one-step criterion ``J`` of ``result`` on ``u, y``: a different
    record (or another operating point) gives another ``J``.
    """
    records, u, y = record_data(u, y, what="u", several=False)
    if records is not None:                 # one Record: its samples, at the fit's dt
        check_sampling(records, result.structure.dt, what=f"`{name}`'s dt")
    if u is None or y is None:
        raise ParameterError(f"this needs the record `{name}` was fitted to: pass `u` and `y` "
                             "(fohw's results keep no data).")
    u = check_inputs(u, result.structure.n_inputs, names=result.structure.inputs)
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if u.shape[0] != result.n_samples:
        raise ParameterError(f"`u` and `y` have {u.shape[0]} samples, but `{name}` was fitted to "
                             f"{result.n_samples}: pass the record it was fitted to.")
    if result.structure.output_map is not None and "simulation_sse" in result.details:
        # A series map's J is of the inner one-step prediction (predict applies the map): the
        # free-run criterion, which the fit minimised, identifies its record instead.
        n_init = int(result.options.get("n_init", 0))
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")           # the fit's own record: no extrapolation
            e = (y - np.asarray(result.simulate(u, initial="fitted"), dtype=float))[n_init:]
        sse, fitted = float(e @ e), float(result.details["simulation_sse"])
        if not np.isclose(sse, fitted, rtol=1e-6, atol=1e-300):
            raise ParameterError(f"`u` and `y` are not the record `{name}` was fitted to: its "
                                 f"free-run error sum of squares on them is {sse:.6g}, not its "
                                 f"{fitted:.6g}.")
        return u, y
    J = float(np.mean((y - result.predict(u, y)) ** 2))
    if not np.isclose(J, result.J, rtol=1e-6, atol=1e-300):
        raise ParameterError(f"`u` and `y` are not the record `{name}` was fitted to: its mean "
                             f"squared one-step error on them is {J:.6g}, not its J = "
                             f"{result.J:.6g}.")
    return u, y


def is_fit(result):
    """Whether ``result`` is a fit of a kind other than the lagged one (a fohw.FitResult)."""
    return isinstance(result, FitResult) and not isinstance(result, IdentificationResult)


def fit_weight(result):
    """The ``sample_weight`` ``result`` was fitted with (its ``options``), or None."""
    weight = result.options.get("sample_weight")
    return None if weight is None else np.asarray(weight, dtype=np.float64)


def check_fit_record(result, u, y, name):
    """``u``, ``y`` checked to be the record the FitResult ``result`` was fitted to.

    The fit keeps a fingerprint of its record (:func:`fohw.estimators.fit.data_digest`: the
    samples, ``dt`` and the ``sample_weight`` of its options); another record, a part of it or
    another step size is refused.
    """
    records, u_one, _ = record_data(u, y, what="u")
    if records is not None:
        digest = records_digest(result, records)
        if result.data_digest and digest != result.data_digest:
            raise ParameterError(f"the record(s) given (at dt = {result.model.dt!r}) are not the "
                                 f"data `{name}` was fitted to: their fingerprint is {digest}, "
                                 f"the fit's {result.data_digest}.")
        return (records[0] if u_one is not None else records), None
    if u is None or y is None:
        raise ParameterError(f"this needs the record `{name}` was fitted to: pass `u` and `y` "
                             "(fohw's results keep no data).")
    u, y = check_record(result.model, u, y)
    weight = fit_weight(result)
    length = result.n_samples if weight is None else weight.size
    if y.size != length:
        held = "" if weight is None else f" ({result.n_samples} of them of positive weight)"
        raise ParameterError(f"`u` and `y` have {y.size} samples, but `{name}` was fitted to "
                             f"{length}{held}: pass the record it was fitted to.")
    digest = data_digest(u, y, result.model.dt, weight)
    if result.data_digest and digest != result.data_digest:
        raise ParameterError(f"`u` and `y` (at dt = {result.model.dt!r}) are not the record "
                             f"`{name}` was fitted to: their fingerprint is {digest}, the fit's "
                             f"{result.data_digest}.")
    return u, y


def records_digest(result, records):
    """The fingerprint :func:`fohw.fit` kept of ``records`` (its ``data_digest_of``).

    Each record as the fit saw it: its input as the kind takes it, its share of the fit's
    ``sample_weight``, its instants and the fit's ``warmup``.
    """
    weight = fit_weight(result)
    sizes = [r.n_samples for r in records]
    if weight is not None and weight.size != sum(sizes):
        raise ParameterError(f"the records have {sum(sizes)} samples, but the fit's "
                             f"sample_weight {weight.size}: they are not the data it was fitted to.")
    bounds = np.cumsum([0] + sizes)
    weights = None if weight is None else [weight[bounds[k]:bounds[k + 1]]
                                           for k in range(len(records))]
    experiments, _ = prepare_data(result.model, list(records), None, weights,
                                  int(result.options.get("warmup") or 0),
                                  result.options.get("refine"))
    return data_digest_of(experiments, result.model.dt)


def _free_run_sse(model, u, y, weight, warmup=0):
    """Weighted SSE of ``model``'s free run on arrays, a Record or a list of Records."""
    records = record_list(u)
    if records is None:
        r = y - np.asarray(model.simulate(u), dtype=float)
    else:
        runs = []
        for rec in records:
            if rec.t is None and warmup:
                u_held = np.concatenate([np.repeat(rec.u[:1], warmup, axis=0), rec.u])
                runs.append(np.asarray(model.simulate(u_held), dtype=float)[warmup:])
            else:
                runs.append(simulate_record(model, rec))
        r = np.concatenate([rec.y for rec in records]) - np.concatenate(runs)
    if weight is not None:
        r = r * np.sqrt(weight)
    return float(r @ r)


def sse_with_fixed(result, u, y, values):
    """The least SSE of ``result``'s model with ``values`` (``{name: value}``) held fixed.

    The other free parameters are refitted by :func:`fohw.fit` with the fit's own options
    (``sample_weight``, ``order_grid``, ``n_starts``, ``max_nfev``, ``tol``: the same
    criterion and search as the fit), from the kind's starts and from the estimate with
    ``values`` put in (``start=``); when none is left, the SSE of the model's free run
    (weighted as the fit was). A refit next to the
    optimum may stop without a step or end rank deficient (an order at 0 can make a gain and a
    time constant one): its SSE is still an upper bound of the profile there, which can only
    widen an interval, so those warnings are not the user's business. ``inf`` when no start
    simulates finitely.
    """
    params = result.parameters
    for name, value in values.items():
        params = params.replace(name, value=float(value), fixed=True)
    model = result.model.with_parameters(params)
    if not params.free_names:
        with np.errstate(all="ignore"):
            sse = _free_run_sse(model, u, y, fit_weight(result),
                                int(result.options.get("warmup") or 0))
        return sse if math.isfinite(sse) else math.inf
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        warnings.simplefilter("ignore", RankDeficiencyWarning)
        try:
            return fit(model, u, y, start=model, **dict(result.options)).sse
        except ParameterError:
            return math.inf


def check_n_effective(n_effective, n):
    """The samples that scale a likelihood-ratio statistic: ``n``, or ``n_effective`` in [1, n]."""
    if n_effective is None:
        return n
    value = check_scalar(n_effective, "n_effective", lower=1.0)
    if value > n:
        raise ParameterError(f"`n_effective` must be at most the {n} samples of the criterion "
                             f"(correlated residuals carry less information, not more); got "
                             f"{n_effective!r}.")
    return value


def orders_with(orders, fixed):
    """``orders`` with the free orders in ``fixed`` (``{name: value}``) replaced by numbers."""
    def branch(terms):
        return [(t.lag, fixed.get(t.order, t.order) if t.free else t.order, t.input)
                for t in terms]
    return Orders([t[:2] for t in branch(orders.output)], branch(orders.input),
                  inputs=orders.inputs or None)


def refit(result, u, y, *, orders=None, start=None):
    """Fit ``result``'s model class again on ``u, y`` (its method, options, bounds).

    Optionally with other ``orders`` and, for ``"output_error"``, a ``start`` pair
    ``(linear, nonlinear)``. A series output map is kept (its resolved form).
    """
    s = result.structure
    orders = s.orders if orders is None else orders
    options = dict(result.options)
    bounds = options.pop("alpha_bounds", (0.0, 1.0))
    if isinstance(bounds, dict):
        bounds = {k: v for k, v in bounds.items() if k in orders.free}
        if not bounds:
            bounds = (0.0, 1.0)
    if result.method == "output_error":
        options["start"] = start
    # A refit started at (or next to) the full fit's optimum may stop without a step ("stuck at
    # its start") or at its evaluation limit: its criterion is still an upper bound of the
    # profile there, which can only widen the interval, so its ConvergenceWarning is not the
    # user's business.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return identify(u, y, na=s.na, nb=s.nb, f_basis=s.f_basis, g_basis=s.g_basis,
                        method=result.method, orders=orders, offset=s.offset,
                        operating_point=result.operating_point, past=s.past, dt=s.dt,
                        alpha_bounds=bounds, output_map=s.output_map, options=options, nk=s.nk)



@dataclass(frozen=True)
class ProfileInterval:
    """A profile-likelihood interval of one free order (or a free parameter of any kind).

    Attributes
    ----------
    name : str
    estimate : float
    low, high : float
        The interval (also :attr:`lower`, :attr:`upper`); an end equal to the parameter's
        bound when the criterion never reaches the quantile on that side (``one_sided`` says
        which).
    level : float
    grid, statistic : ndarray
        The values where the model was refitted and ``n log(RSS(nu) / RSS_hat)`` there.
    one_sided : str
        ``""``, ``"low"`` (the lower end is the bound), ``"high"`` or ``"both"``.
    """

    name: str
    estimate: float
    low: float
    high: float
    level: float
    grid: np.ndarray
    statistic: np.ndarray
    one_sided: str

    def __iter__(self):
        return iter((self.low, self.high))

    @property
    def lower(self) -> float:
        """The lower end (:attr:`low`)."""
        return self.low

    @property
    def upper(self) -> float:
        """The upper end (:attr:`high`)."""
        return self.high

    def __repr__(self):
        side = f", one-sided: {self.one_sided}" if self.one_sided else ""
        return (f"ProfileInterval({self.name} = {self.estimate:.4g}, {self.level:.0%} interval "
                f"[{self.low:.4g}, {self.high:.4g}]{side}; {self.grid.size} refits)")

    def _repr_html_(self):
        from .._repr import html_table

        return html_table(f"Profile-likelihood interval of {self.name}",
                          ["order", "estimate", f"{self.level:.0%} low", f"{self.level:.0%} high",
                           "one-sided"],
                          [(self.name, self.estimate, self.low, self.high, self.one_sided or "no")],
                          notes=[f"n log(RSS(nu) / RSS_hat) on {self.grid.size} refits"])


def _fixed_value_ok(orders, name, value):
    """Whether fixing ``name`` at ``value`` leaves distinct terms (the mixed class at 0 does not)."""
    try:
        orders_with(orders, {name: value})
    except ParameterError:
        return False
    return True


def profile_interval(result, name, level=0.95, *, u=None, y=None, n_grid=11, xtol=1e-4,
                     n_effective=None):
    """The profile-likelihood interval of free order ``name`` of ``result``.

    Parameters
    ----------
    result : IdentificationResult or FitResult
        A ``"varpro"``, ``"structured"`` or ``"output_error"`` fit with free order ``name``,
        or a :class:`fohw.FitResult` of any other kind (:func:`fohw.fit`): then ``name`` may be
        any of its free parameters, each ``RSS(nu)`` is a :func:`fohw.fit` of its model with
        ``name`` fixed at ``nu`` and the others refitted from the estimate (the fit's options),
        and the scan stays inside the parameter's own bounds in ``result.parameters`` (a side
        without a bound is scanned to 10 standard errors from the estimate).
    name : str
        One of ``result.orders`` (of ``result.free_names`` for a FitResult).
    level : float
        Coverage, in (0, 1).
    u, y : array_like
        The record ``result`` was fitted to (checked through its ``J``; for a FitResult,
        through its ``data_digest``: the same samples at the same ``dt``). Or a
        :class:`fohw.Record` as ``u`` (``y`` omitted); for a FitResult also the list of Records
        it was fitted to (the refits are joint fits of them, with the fit's ``per_record``).
    n_grid : int
        Points of the coarse grid over the parameter's bounds (at least 3).
    xtol : float
        Absolute tolerance of the ends (Brent).
    n_effective : float, optional
        The samples that scale the statistic, ``n_effective log(RSS(nu) / RSS_hat)``, in
        ``[1, n]``; default ``n``, the samples of the criterion (white residuals). For
        correlated residuals (a free run's usually are) ``n`` overstates the information;
        :func:`fohw.analysis.metrics.effective_samples` of the fit's residuals gives Bartlett's
        estimate, and the interval widens accordingly (still an approximation).

    Returns
    -------
    ProfileInterval
        Unpacks as ``(low, high)``.

    Raises
    ------
    ParameterError
        Not a least-squares fit, an unknown order name, ``level`` outside (0, 1), ``u, y``
        missing or not the fit's record (another record, a part of it, another step size or
        other sample weights), or ``n_effective`` outside ``[1, n]``.

    Notes
    -----
    Wilks: ``n log(RSS(nu) / RSS_hat)`` is asymptotically chi2 with 1 degree of freedom at the
    true order when that is inside its bounds. At a bound the interval is one-sided there.
    In the mixed class an order fixed at exactly 0 duplicates the order-0 terms, so the grid
    starts at ``1e-3`` of the bound width above 0 (the log-memory limit: see
    :func:`fohw.lr_test`).

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(500, random_state=0)
    >>> res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> low, high = fohw.profile_interval(res, "alpha", u=data.u, y=data.y)
    >>> bool(low < res.alpha < high)
    True
    """
    level = check_scalar(level, "level", lower=0.0, upper=1.0, lower_inclusive=False,
                         upper_inclusive=False)
    n_grid = check_int(n_grid, "n_grid", minimum=3)
    xtol = check_scalar(xtol, "xtol", lower=0.0, lower_inclusive=False)
    if is_fit(result):
        return _profile_fit(result, name, level, u, y, n_grid, xtol, n_effective)
    result = check_result(result, "result")
    if not isinstance(name, str) or name not in result.orders:
        raise ParameterError(f"`name` must be one of the free orders {list(result.orders)}; "
                             f"got {name!r}.")
    u, y = check_data(result, u, y, "result")
    rss_hat, n = criterion(result)
    n = check_n_effective(n_effective, n)
    quantile = float(scipy.stats.chi2.ppf(level, 1))
    est = float(result.orders[name])
    lo, hi = order_bounds(result, name)
    orders = result.structure.orders
    names = result.structure.nonlinear_names
    others = np.array([v for k, v in zip(names, result.nonlinear) if k != name])

    def stat(value):
        fixed = orders_with(orders, {name: float(value)})
        start = (result.linear, others) if result.method == "output_error" else None
        fit = refit(result, u, y, orders=fixed, start=start)
        return max(n * np.log(criterion(fit)[0] / rss_hat), 0.0)

    eps = 1e-3 * (hi - lo)
    lo_ok = lo if _fixed_value_ok(orders, name, lo) else lo + eps
    hi_ok = hi if _fixed_value_ok(orders, name, hi) else hi - eps
    grid = np.unique(np.r_[np.linspace(lo_ok, hi_ok, n_grid), np.clip(est, lo_ok, hi_ok)])
    values = np.array([stat(v) for v in grid])
    k = int(np.argmin(np.abs(grid - np.clip(est, lo_ok, hi_ok))))
    return _interval(name, est, level, stat, grid, values, k, quantile, lo, hi, xtol)


def _interval(name, est, level, stat, grid, values, k, quantile, lo, hi, xtol):
    """The :class:`ProfileInterval` from ``stat`` on a grid: Brent between bracketing points.

    From the grid point ``k`` nearest the estimate outwards, the first point whose statistic
    exceeds ``quantile`` brackets the end with its inner neighbour; a side where none does
    ends at its bound (``lo`` or ``hi``), one-sided.
    """
    def end(side):
        idx = range(k - 1, -1, -1) if side < 0 else range(k + 1, grid.size)
        inner = k
        for j in idx:
            if values[j] > quantile:
                if values[inner] > quantile:        # no sign change for Brent: say why
                    raise ParameterError(
                        f"the profile of {name!r} does not cross the {level:g} quantile "
                        f"({quantile:.4g}) between {grid[inner]:.6g} and {grid[j]:.6g}: the "
                        f"refit nearest the estimate already has a statistic of "
                        f"{values[inner]:.4g}, so the refits do not reproduce the fit there "
                        "(a search that stops early: raise the fit's max_nfev or n_starts).")
                a, b = grid[inner], grid[j]
                return scipy.optimize.brentq(lambda v: stat(v) - quantile, min(a, b),
                                             max(a, b), xtol=xtol), False
            inner = j
        return (lo if side < 0 else hi), True

    low, low_open = end(-1)
    high, high_open = end(+1)
    one_sided = {(False, False): "", (True, False): "low", (False, True): "high",
                 (True, True): "both"}[(low_open, high_open)]
    return ProfileInterval(name=name, estimate=est, low=float(low), high=float(high),
                           level=level, grid=grid, statistic=values, one_sided=one_sided)


#: How far (in standard errors) the profile of a parameter without a bound on a side is scanned.
SCAN_STANDARD_ERRORS = 10.0


def _profile_fit(result, name, level, u, y, n_grid, xtol, n_effective):
    """:func:`profile_interval` of a FitResult: refits with ``name`` fixed, in its own bounds."""
    free = result.free_names
    if not isinstance(name, str) or name not in free:
        raise ParameterError(f"`name` must be one of the free parameters {list(free)} of the "
                             f"{type(result.model).__name__} fit; got {name!r}.")
    if name in (result.per_record or {}):
        raise ParameterError(
            f"`name` = {name!r} is estimated per record (the fit's per_record: one value for each "
            f"of its {len(result.per_record[name]['values'])} records): a profile fixes one value, "
            "which such a parameter does not have. Profile a shared parameter, or refit with "
            f"{name!r} shared (per_record without it) to profile it.")
    u, y = check_fit_record(result, u, y, "result")
    rss_hat, n = result.sse, check_n_effective(n_effective, result.n_samples)
    quantile = float(scipy.stats.chi2.ppf(level, 1))
    est = result.parameters[name].value
    lo, hi = result.parameters[name].bounds
    if not (math.isfinite(lo) and math.isfinite(hi)):
        if result.covariance is None:
            raise ParameterError(f"parameter {name!r} has no bound on a side and the fit no "
                                 f"covariance (status {result.status.name}) to scale a scan: "
                                 "give it finite bounds.")
        se = result.standard_errors()[name]
        lo = lo if math.isfinite(lo) else est - SCAN_STANDARD_ERRORS * se
        hi = hi if math.isfinite(hi) else est + SCAN_STANDARD_ERRORS * se

    def stat(value):     # no finite free run there (sse inf): far past any quantile, finite
        value = n * math.log(sse_with_fixed(result, u, y, {name: value}) / rss_hat)
        return min(max(value, 0.0), 1e12)

    grid = np.unique(np.r_[np.linspace(lo, hi, n_grid), est])
    values = np.array([stat(v) for v in grid])
    k = int(np.argmin(np.abs(grid - est)))
    return _interval(name, est, level, stat, grid, values, k, quantile, lo, hi, xtol)


