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

The F form ``((RSS_r - RSS_f) / q) / (RSS_f / (n - d))`` is exact only for linear models with
chi2 references; the boundary and Davies references are derived for the likelihood ratio, so
fohw uses ``n log``. For ``n`` in the hundreds and ``d`` parameters the two differ by about
``d / n`` relatively (see ``docs/order_test.md`` for the measured null rejection rates).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._parallel import TaskError, run_tasks
from .._validation import check_int, check_random_state
from ..estimators.fit import fit
from ..exceptions import ConvergenceWarning, ParameterError
from ..model.orders import Orders
from ..model.structure import Structure
from ..results import REFITS
from .profile_interval import (
    check_data,
    check_fit_record,
    check_result,
    criterion,
    is_fit,
    order_bounds,
    orders_with,
    refit,
)

__all__ = ["LRTest", "lr_test", "order_test", "davies_bound", "chi_bar_squared_sf",
           "cancelled_orders", "REFERENCES"]

#: ``reference=`` spellings.
REFERENCES = ("auto", "mixture", "davies", "bootstrap")


@dataclass(frozen=True)
class LRTest:
    """The likelihood-ratio test of a fractional class against its integer class.

    Attributes
    ----------
    statistic : float
        ``n log(RSS_restricted / RSS_full)`` (0 when the full fit is not better).
    df : int
        Parameters the full class adds (free orders and their coefficients).
    pvalue : float
        From :attr:`distribution`.
    distribution : str
        The reference used: ``"chi2 mixture 0.5*chi2_0 + 0.5*chi2_1"``, a chi-bar-squared with
        binomial weights, ``"Davies bound"`` (an upper bound of the p-value) or
        ``"bootstrap"``.
    criterion : str
        ``"one-step RSS"`` or ``"free-run RSS"``.
    n : int
        Samples of the criterion.
    rss_restricted, rss_full : float
    boundary, unidentified : tuple of str
        The free orders on the boundary under the null, and those not identified there.
    note : str
        What the user must know: an order whose coefficients cancel (the log-memory limit of
        the mixed class), a full fit worse than the restricted one, the bootstrap's Monte
        Carlo error.
    bootstrap : ndarray or None
        The bootstrap statistics.
    hypothesis : str
        For fits of a kind other than the lagged one: the null, the values the restricted fit
        holds fixed (e.g. ``"alpha = 1"``); empty for the lagged kind (orders 0).
    """

    statistic: float
    df: int
    pvalue: float
    distribution: str
    criterion: str
    n: int
    rss_restricted: float
    rss_full: float
    boundary: tuple = ()
    unidentified: tuple = ()
    note: str = ""
    bootstrap: np.ndarray | None = field(default=None, repr=False)
    hypothesis: str = ""

    def __repr__(self):
        return (f"LRTest(statistic={self.statistic:.4g}, df={self.df}, pvalue={self.pvalue:.4g}, "
                f"distribution={self.distribution!r}, criterion={self.criterion!r}, n={self.n})")

    def _repr_html_(self):
        from .._repr import html_table

        rows = [("LR statistic", self.statistic), ("degrees of freedom", self.df),
                ("p-value", self.pvalue), ("reference", self.distribution),
                ("criterion", f"{self.criterion}, n = {self.n}"),
                ("RSS restricted / full", f"{self.rss_restricted:.6g} / {self.rss_full:.6g}")]
        rows += [("on the boundary", ", ".join(self.boundary))] if self.boundary else []
        rows += [("unidentified under the null", ", ".join(self.unidentified))] \
            if self.unidentified else []
        return html_table("LR test of the fractional orders against orders 0", ["", "value"], rows,
                          notes=[self.note])

    def __str__(self):
        null = self.hypothesis or "the fractional orders against orders 0"
        text = (f"LR test of {null}: LR = {self.statistic:.4g} "
                f"({self.criterion}, n = {self.n}), df = {self.df}, p = {self.pvalue:.4g} "
                f"({self.distribution}).")
        return text + (f" {self.note}" if self.note else "")


def chi_bar_squared_sf(x, k):
    """``P(X > x)`` for ``X ~ sum_j C(k, j) 2^-k chi2_j`` (``chi2_0`` a point mass at 0)."""
    x = float(x)
    if x <= 0:
        return 1.0
    return float(sum(math.comb(k, j) * 0.5 ** k * scipy.stats.chi2.sf(x, j)
                     for j in range(1, k + 1)))


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


def null_orders(orders):
    """``(restricted orders, boundary names, unidentified names)`` of a class with free orders.

    Every free order is set to 0; a term that then duplicates an order-0 term of its lag is
    dropped, and its free order is *unidentified* under the null (its coefficients are 0
    there); the others are on the boundary ``nu = 0``.
    """
    unidentified = []

    def branch(terms):
        fixed0 = {(t.lag, t.input) for t in terms if not t.free and t.order == 0.0}
        out = []
        for t in terms:
            if t.free and (t.lag, t.input) in fixed0:
                if t.order not in unidentified:
                    unidentified.append(t.order)
                continue
            out.append((t.lag, 0.0 if t.free else t.order, t.input))
        return out

    restricted = Orders([t[:2] for t in branch(orders.output)], branch(orders.input),
                        inputs=orders.inputs or None)
    boundary = tuple(n for n in orders.free if n not in unidentified)
    return restricted, boundary, tuple(unidentified)


def _prefixed(prefix, name):
    """Theta's name of basis ``prefix`` (``p2``) of a term: ``p2b1``, or ``u2.p2b1``."""
    head, dot, tail = name.rpartition(".")
    return f"{head}{dot}{prefix}{tail}"


def cancelled_orders(result, *, ratio=20.0, small=0.05):
    """Notes on free orders that sit near 0 with terms cancelling an order-0 term.

    In the mixed class, ``b0 Delta^0 x + b1 Delta^nu x`` with ``nu -> 0`` and ``b1 = -b0 =
    beta / nu`` tends to ``-beta d/dnu Delta^nu x |_0``, a logarithmic long-memory term
    (``sum_j x(k - j) / j``), not a fractional order. An order below ``small`` whose
    ``nu``-term coefficient is more than ``ratio`` times the sum of the pair, with the
    opposite sign, is reported so (``{order: note}``).
    """
    s = result.structure
    names = s.layout.names
    theta = dict(zip(names, result.theta))
    notes = []
    for letter, terms, term_names in (("a", s.orders.output, s.orders.a_names),
                                      ("b", s.orders.input, s.orders.b_names)):
        zero = {(t.lag, t.input): nm for t, nm in zip(terms, term_names)
                if not t.free and t.order == 0.0}
        for t, nm in zip(terms, term_names):
            key = (t.lag, t.input)
            if not t.free or key not in zero or result.orders[t.order] >= small:
                continue
            prefixes = [""] + [f"{'q' if letter == 'a' else 'p'}{j}" for j in range(2, 10)]
            for pre in prefixes:
                name_nu, name_0 = _prefixed(pre, nm), _prefixed(pre, zero[key])
                if name_nu not in theta:
                    continue
                c_nu, c_0 = theta[name_nu], theta[name_0]
                if abs(c_nu) > ratio * max(abs(c_nu + c_0), np.finfo(float).tiny) \
                        and np.sign(c_nu) != np.sign(c_0):
                    notes.append((t.order, f"{name_nu} = {c_nu:.3g}, {name_0} = {c_0:.3g}"))
    out = {}
    for order, pair in notes:
        out.setdefault(order, []).append(pair)
    return {order: (f"{order} = {result.orders[order]:.3g} with cancelling coefficients "
                    f"({'; '.join(pairs)}): the fit uses the {order} -> 0 limit, a logarithmic "
                    "long-memory term, not a fractional order.")
            for order, pairs in out.items()}


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


def _mixture(stat, k):
    """``(pvalue, distribution)`` of the chi-bar-squared reference of ``k`` boundary orders."""
    distribution = ("chi2 mixture 0.5*chi2_0 + 0.5*chi2_1" if k == 1 else
                    f"chi-bar-squared sum_j C({k},j)/2^{k} chi2_j (orders assumed "
                    "uncorrelated)")
    return chi_bar_squared_sf(stat, k), distribution


def _statistic(rss_r, rss_f, n):
    return max(n * math.log(rss_r / rss_f), 0.0)


def _davies_profile(full, rss_r, n, u, y, n_grid):
    """``LR(nu)`` on a grid of the single unidentified order (and at the estimate)."""
    (name,) = full.orders
    est = float(full.orders[name])
    stat_f = _statistic(rss_r, criterion(full)[0], n)
    prof = full.alpha_profile
    if full.method == "varpro" and prof is not None and len(full.orders) == 1 \
            and full.structure.past == "rest":
        grid, J = prof
        values = [_statistic(rss_r, j * full.n_samples, n) for j in J]
    else:
        u, y = check_data(full, u, y, "full")
        lo, hi = order_bounds(full, name)
        grid = np.linspace(lo + 1e-3 * (hi - lo), hi, n_grid)
        values = []
        for v in grid:
            fit = refit(full, u, y, orders=orders_with(full.structure.orders, {name: float(v)}),
                        start=(full.linear, full.nonlinear[1:]))
            values.append(_statistic(rss_r, criterion(fit)[0], n))
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
    return _statistic(rss_r, criterion(f)[0], n)


def _notes(full, rss_r, rss_f):
    notes = list(cancelled_orders(full).values())
    if rss_f > rss_r * (1 + 1e-9):
        notes.append(f"The full fit's RSS ({rss_f:.6g}) is above the restricted one's "
                     f"({rss_r:.6g}), though its class contains it: the full fit missed its "
                     "optimum; the statistic is set to 0.")
    return notes


def order_test(full):
    """:func:`lr_test` of an ``"output_error"`` fit against the integer fit its chain made.

    The default chain of starts of ``method="output_error"`` fits the integer class the fit's
    class contains (every order 0, as :func:`null_orders` builds it) and keeps its free-run RSS
    in ``details["integer_sse"]``; this is the test :func:`lr_test` computes from that fit and
    ``full``, without refitting (the same statistic, df and mixture). An order not identified
    under the null (the mixed class) gets no p-value here (NaN): Davies' bound and the
    bootstrap need the record (:func:`lr_test` with ``u``, ``y``).

    Returns
    -------
    LRTest or None
        None when ``full`` has no ``details["integer_sse"]`` (another method, a given start,
        no free order, a bound of an order above 0, or a series output map, whose fit starts
        from the fit without the map instead: use :func:`lr_test` with both fits).
    """
    full = check_result(full, "full")
    if "integer_sse" not in full.details or not full.orders:
        return None
    if any(order_bounds(full, name)[0] != 0.0 for name in full.orders):
        return None
    fs = full.structure
    null, boundary, unidentified = null_orders(fs.orders)
    rs = Structure(null, fs.f_basis, fs.g_basis, fs.offset, fs.past, fs.dt, fs.output_map)
    rss_r = float(full.details["integer_sse"])
    rss_f, n = criterion(full)
    stat = _statistic(rss_r, rss_f, n)
    df = fs.n_linear - rs.n_linear + fs.n_nonlinear - rs.n_nonlinear
    notes = _notes(full, rss_r, rss_f)
    if unidentified:
        pvalue, distribution = math.nan, "none without the record"
        notes.append(f"The order(s) {list(unidentified)} are not identified under the null "
                     "(Davies 1977): fohw.lr_test(restricted, full, u=u, y=y) gives Davies' "
                     "bound or a bootstrap p-value.")
    else:
        pvalue, distribution = _mixture(stat, len(boundary))
    return LRTest(statistic=stat, df=df, pvalue=float(pvalue), distribution=distribution,
                  criterion="free-run RSS", n=n, rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, unidentified=unidentified, note=" ".join(notes))


def lr_test(restricted, full, *, reference="auto", u=None, y=None, n_bootstrap=199,
            random_state=None, executor=None, n_grid=21):
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
        The record both were fitted to (results keep no data): needed by the bootstrap and by
        Davies' bound unless ``full`` is a ``"varpro"`` fit of one free order (its scan is the
        profile). When given, they are checked against both fits' ``J``. For two FitResults,
        checked against their fingerprint, and ``full`` is refitted from its own and the
        restricted estimate (:func:`fohw.fit` with ``start=``), so its SSE never ends above
        the restricted one (without them a full fit above it gives 0 and a warning).
    n_bootstrap : int
        Bootstrap records (default 199).
    random_state : None, int or Generator
        Seeds the bootstrap.
    executor : concurrent.futures.Executor, optional
        Runs the bootstrap refits.
    n_grid : int
        Points of the order grid for Davies' profile when it is refitted.

    Returns
    -------
    LRTest
        ``.statistic``, ``.df``, ``.pvalue``, ``.distribution``, ``.note``.

    Raises
    ------
    ParameterError
        Wrong types, a method that is not a least-squares optimum, a pair that is not nested
        (the message says how), an unknown ``reference``, or missing data.

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
    if is_fit(restricted) or is_fit(full):
        return _lr_fits(restricted, full, reference, u, y)
    restricted = check_result(restricted, "restricted")
    full = check_result(full, "full")
    if reference not in REFERENCES:
        raise ParameterError(f"`reference` must be one of {REFERENCES}; got {reference!r}.")
    boundary, unidentified = _check_nested(restricted, full)
    if u is not None or y is not None:
        u, y = check_data(restricted, u, y, "restricted")
        check_data(full, u, y, "full")
    rss_r, n = criterion(restricted)
    rss_f, _ = criterion(full)
    stat = _statistic(rss_r, rss_f, n)
    df = (full.structure.n_linear - restricted.structure.n_linear
          + full.structure.n_nonlinear - restricted.structure.n_nonlinear)
    notes = _notes(full, rss_r, rss_f)
    if reference == "auto":
        reference = "davies" if unidentified else "mixture"
    boot = None
    if reference == "mixture":
        if unidentified:
            raise ParameterError(f"`reference='mixture'` does not apply: the order(s) "
                                 f"{list(unidentified)} are not identified under the null (their "
                                 "coefficients are 0 there; Davies 1977); use 'davies' or "
                                 "'bootstrap'.")
        pvalue, distribution = _mixture(stat, len(boundary))
    elif reference == "davies":
        if len(unidentified) != 1 or len(full.orders) != 1:
            raise ParameterError("`reference='davies'` is implemented for one free order that is "
                                 f"not identified under the null; `full` has {list(full.orders)} "
                                 f"({list(unidentified)} unidentified): use 'bootstrap'.")
        s = df - 1
        profile = _davies_profile(full, rss_r, n, u, y, check_int(n_grid, "n_grid", minimum=3))
        pvalue = davies_bound(stat, s, profile)
        distribution = "Davies bound"
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
    crit_name = "free-run RSS" if full.method == "output_error" else "one-step RSS"
    return LRTest(statistic=stat, df=df, pvalue=float(pvalue), distribution=distribution,
                  criterion=crit_name, n=n, rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, unidentified=unidentified, note=" ".join(notes),
                  bootstrap=boot)


def nested_fits(restricted, full):
    """``(fixed names, boundary names)`` of two FitResults, or a ParameterError saying why not.

    Same kind and settings, one record (its fingerprint, ``n_samples`` and ``dt``), and
    ``restricted`` is ``full`` with some free parameters held fixed at values inside their
    bounds in ``full`` (on a bound: a boundary of the parameter space).
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
    same = type(rm) is type(fm)
    if same:        # the settings apart from the values (a kind's config may hold values too)
        try:
            same = rm.with_parameters(fm.parameters.valuesdict()).config() == fm.config()
        except ParameterError:
            same = False
    if not same:
        raise ParameterError(f"`restricted` and `full` must be fits of one model kind with the "
                             f"same settings; got a {type(rm).__name__} {rm.config()!r} and a "
                             f"{type(fm).__name__} {fm.config()!r}.")
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


def _lr_fits(restricted, full, reference, u, y):
    """:func:`lr_test` of two :class:`fohw.FitResult` (any kind but the lagged one)."""
    fixed, boundary = nested_fits(restricted, full)
    if reference not in REFERENCES:
        raise ParameterError(f"`reference` must be one of {REFERENCES}; got {reference!r}.")
    if reference not in ("auto", "mixture"):
        raise ParameterError(f"`reference={reference!r}` is for the lagged kind's orders; a fit "
                             f"of a {type(full.model).__name__} is tested against chi2 (or the "
                             "chi-bar-squared mixture for a value on its bound): use 'auto'.")
    notes = []
    rss_r, rss_f, n = restricted.sse, full.sse, full.n_samples
    if u is not None or y is not None:
        u, y = check_fit_record(restricted, u, y, "restricted")
        with warnings.catch_warnings():       # its status is the user's `full`'s business
            warnings.simplefilter("ignore", ConvergenceWarning)
            again = fit(full.model, u, y, start=restricted.model, **dict(full.options))
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
    stat = _statistic(rss_r, rss_f, n)
    df, k = len(fixed), len(boundary)
    if k == 0:
        pvalue, distribution = float(scipy.stats.chi2.sf(stat, df)), f"chi2_{df}"
    elif k == df:
        pvalue, distribution = _mixture(stat, k)
    else:       # Self & Liang: k values on their bounds, df - k inside
        pvalue = float(sum(math.comb(k, j) * 0.5 ** k * scipy.stats.chi2.sf(stat, df - k + j)
                           for j in range(k + 1)))
        distribution = f"chi-bar-squared sum_j C({k},j)/2^{k} chi2_({df - k}+j)"
    rp = restricted.parameters
    return LRTest(statistic=stat, df=df, pvalue=pvalue, distribution=distribution,
                  criterion="free-run RSS", n=n, rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, note=" ".join(notes),
                  hypothesis=", ".join(f"{name} = {rp[name].value:g}" for name in fixed))


REFITS["order_test"] = order_test            # IdentificationResult.order_test calls it
