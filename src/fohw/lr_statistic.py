"""The likelihood-ratio statistic of the fractional orders, without refitting (its result type).

:class:`LRTest` is the result of :func:`fohw.lr_test`; :func:`order_test` computes the test of
an ``"output_error"`` fit against the integer fit its chain of starts made
(``details["integer_sse"]``), which ``result.order_test()`` and ``summary()`` report. The
pieces are pure reads of a result (its criterion, its orders' bounds, the null class of its
orders, the chi-bar-squared reference) or of two residual series (the corrections of the
statistic for correlated residuals, :func:`corrected_statistic`), so they live below the
analyses that refit (:mod:`fohw.analysis.lrtest`, :mod:`fohw.analysis.profile_interval`),
which use them too.

**Correlated residuals (model error).** ``n log(RSS_r / RSS_f)`` is referred to its
distribution under white residuals. A free run's residuals are usually coloured (by the noise
and by the model's error), and then the statistic is too large by about the factor
``kappa = g' R g / g' g`` (``R`` the residuals' correlation matrix, ``g`` the direction the
free orders move the fit): on 200 records of an integer plant with AR(1) output noise (pole
0.9) the white-noise test rejected orders 0 in 30 % at 5 % (the sandwich: 5 %). :func:`corrected_statistic`
offers three corrections computed from the two fits' residuals (docs/order_test.md compares
their size and power):

``"sandwich"`` (the default)
    ``LR / kappa`` with ``kappa = sum_{|k| <= M} w_k rho_e(k) rho_g(k)``: ``rho_e`` the
    autocorrelation of the full fit's residuals, ``rho_g`` that of the *score direction*
    ``g``: the sensitivity of the fit's output to the tested parameters at the null (the
    restricted estimate, the tested values at their null values), with the other free
    parameters' sensitivities projected out (:func:`fohw.analysis.lrtest.score_direction`);
    Bartlett weights ``w_k = 1 - |k| / (M + 1)`` (they keep ``kappa`` positive), ``M`` twice
    the first lag where ``rho_e`` is not positive, at most ``n // 4``. It is the
    heteroscedasticity-and-autocorrelation-consistent (Newey--West) variance of the score
    ``g' e`` over its white-noise value; with ``q > 1`` tested parameters, the mean
    eigenvalue ``tr((G'G)^-1 sum_k w_k rho_e(k) G_k' G) / q`` (a Satterthwaite-type scale).
    Without the direction (no record, a lagged fit of several inputs, an order
    not identified under the null, an equation-error fit), ``g`` is replaced by the
    difference of the two fits' residuals ``d = e_r - e_f``, which the text says: a weaker
    approximation (``d`` is ``g`` to first order only; with AR(1) noise of sd 1.0 it halved
    ``kappa`` and rejected 14 % at 5 % where the score direction rejected 5.5 %).
``"bartlett"``
    ``LR n_eff / n`` with Bartlett's ``n_eff = n / (1 + 2 sum_k rho_e(k))``
    (:func:`fohw.analysis.metrics.effective_samples`, truncated at the first non-positive
    ``rho_e``): the correction for the mean of the residuals, ``kappa`` at frequency 0. It is
    right when ``g`` is slow and conservative otherwise (with a white input it rejected 0-0.5 %
    at 5 % and lost half the power at the larger noise).
``"prewhitened"``
    ``n log(|A e_r|^2 / |A e_f|^2)``, ``A(q)`` an AR(p) fitted to the restricted fit's
    residuals by Yule--Walker (``p`` by AIC, at most ``min(10, n // 10)``), both residual
    series filtered by it (the first ``p`` samples dropped). The fits are not redone with the
    filter (that would be a prediction-error fit with a noise model), so this is a heuristic:
    it kept the most power and was liberal (8.5-9.5 % at 5 %, at or above the 99 % bound).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy  # submodules (scipy.stats, ...) load on first use: import time

from ._validation import check_array, check_int
from .exceptions import ParameterError
from .model.lagged.structure import Structure
from .model.orders import Orders

__all__ = ["LRTest", "order_test", "effective_samples", "chi_bar_squared_sf", "null_orders",
           "cancelled_orders",
           "mixture", "statistic", "order_notes", "check_result", "criterion", "order_bounds",
           "LIKELIHOOD_METHODS", "CORRECTIONS", "corrected_statistic", "autocorrelation"]


#: ``correction=`` spellings of the statistic for correlated residuals, the default first.
CORRECTIONS = ("sandwich", "bartlett", "prewhitened")

#: Methods whose estimate is a least-squares (Gaussian likelihood) optimum.
LIKELIHOOD_METHODS = ("varpro", "structured", "output_error")


def check_result(result, name):
    """``result`` must be an IdentificationResult of a least-squares method."""
    if not (hasattr(result, "structure") and hasattr(result, "method")):
        raise ParameterError(f"`{name}` must be an IdentificationResult (from fohw.identify); "
                             f"got {type(result).__name__}.")
    if result.method not in LIKELIHOOD_METHODS:
        raise ParameterError(f"`{name}` was fitted by method {result.method!r}, which is not a "
                             f"least-squares optimum; likelihood-ratio tests and profile "
                             f"intervals need one of {LIKELIHOOD_METHODS}.")
    return result


def criterion(result):
    """``(rss, n)``: the fit's residual sum of squares and the samples it covers.

    The one-step RSS ``N J`` for ``"varpro"`` and ``"structured"``; the free-run RSS
    (``details["simulation_sse"]``) over ``N - n_init`` samples for ``"output_error"``.
    """
    if result.method == "output_error":
        n = result.n_samples - int(result.options.get("n_init", 0))
        return float(result.details["simulation_sse"]), n
    return float(result.J) * result.n_samples, result.n_samples


def order_bounds(result, name):
    """``(low, high)`` of free order ``name`` in the fit's ``alpha_bounds``."""
    bounds = result.options.get("alpha_bounds", (0.0, 1.0))
    if isinstance(bounds, dict):
        bounds = bounds[name]
    return float(bounds[0]), float(bounds[1])


@dataclass(frozen=True)
class LRTest:
    """The likelihood-ratio test of a fractional class against its integer class.

    Attributes
    ----------
    statistic : float
        ``n log(RSS_restricted / RSS_full)`` (0 when the full fit is not better), ``n`` the
        samples of the criterion or the ``n_effective`` given.
    df : int
        Parameters the full class adds (free orders and their coefficients).
    pvalue : float
        From :attr:`distribution`.
    distribution : str
        The reference used: ``"chi2 mixture 0.5*chi2_0 + 0.5*chi2_1"``, a chi-bar-squared with
        binomial weights, ``"Davies bound"`` (an upper bound of the p-value) or
        ``"bootstrap"``.
    criterion : str
        ``"one-step RSS"`` or ``"free-run RSS"``; with ``n_effective``, followed by
        ``"; n_effective = <n> of <N> samples"``.
    n : int
        Samples of the criterion (``n_effective`` rounded, when given).
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
    statistic_corrected, pvalue_corrected : float
        The statistic corrected for the residuals' correlation (:func:`corrected_statistic`)
        and its p-value from the same reference; NaN when the residuals were not available
        (the lagged kind's fits keep none: pass the record).
    correction : str
        Which correction, and its factor (or why there is none).
    verdict : str
        The test read beside held-back validation
        (:func:`fohw.analysis.order_verdict.verdict`): ``"significant and validates"``,
        ``"significant but does not validate (model error)"``, ``"not significant"``, or
        ``"significant; not validated (no held-back record)"``; empty without a corrected
        p-value.
    validation : tuple
        ``(fit_restricted, fit_full)``: the free-run fit % of both fits on the held-back
        record, when one was given; else ``()``.
    margin : float
        The fit points the fractional fit had to gain there (NaN without ``validation``).
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
    statistic_corrected: float = math.nan
    pvalue_corrected: float = math.nan
    correction: str = ""
    verdict: str = ""
    validation: tuple = ()
    margin: float = math.nan

    def __repr__(self):
        more = (f", pvalue_corrected={self.pvalue_corrected:.4g}"
                if not math.isnan(self.pvalue_corrected) else "")
        more += f", verdict={self.verdict!r}" if self.verdict else ""
        return (f"LRTest(statistic={self.statistic:.4g}, df={self.df}, pvalue={self.pvalue:.4g}, "
                f"distribution={self.distribution!r}, criterion={self.criterion!r}, n={self.n}"
                f"{more})")

    def _corrected_text(self):
        """The corrected statistic, the verdict and the validation, in words."""
        if math.isnan(self.statistic_corrected):
            text = (f" Not corrected for correlated residuals ({self.correction})."
                    if self.correction else "")
        else:
            text = (f" Corrected for correlated residuals ({self.correction}): "
                    f"LR = {self.statistic_corrected:.4g}, p = {self.pvalue_corrected:.4g}.")
        if self.validation:
            r, f = self.validation
            text += (f" Held-back free-run fit: orders 0 {r:.2f} %, fractional {f:.2f} % "
                     f"(margin {self.margin:g} points).")
        if self.verdict:
            text += f" Verdict: {self.verdict}."
        return text

    def _repr_html_(self):
        from ._repr import html_table

        rows = [("LR statistic", self.statistic), ("degrees of freedom", self.df),
                ("p-value", self.pvalue), ("reference", self.distribution),
                ("criterion", f"{self.criterion}, n = {self.n}"),
                ("RSS restricted / full", f"{self.rss_restricted:.6g} / {self.rss_full:.6g}")]
        if not math.isnan(self.statistic_corrected):
            rows += [("corrected LR / p-value", f"{self.statistic_corrected:.4g} / "
                                                f"{self.pvalue_corrected:.4g}"),
                     ("correction", self.correction)]
        if self.validation:
            rows += [("held-back fit %, orders 0 / fractional",
                      f"{self.validation[0]:.2f} / {self.validation[1]:.2f}")]
        rows += [("verdict", self.verdict)] if self.verdict else []
        rows += [("on the boundary", ", ".join(self.boundary))] if self.boundary else []
        rows += [("unidentified under the null", ", ".join(self.unidentified))] \
            if self.unidentified else []
        return html_table("LR test of the fractional orders against orders 0", ["", "value"], rows,
                          notes=[self.note])

    def __str__(self):
        null = self.hypothesis or "the fractional orders against orders 0"
        text = (f"LR test of {null}: LR = {self.statistic:.4g} "
                f"({self.criterion}, n = {self.n}), df = {self.df}, p = {self.pvalue:.4g} "
                f"({self.distribution}; white residuals).") + self._corrected_text()
        return text + (f" {self.note}" if self.note else "")


def chi_bar_squared_sf(x, k):
    """``P(X > x)`` for ``X ~ sum_j C(k, j) 2^-k chi2_j`` (``chi2_0`` a point mass at 0)."""
    x = float(x)
    if x <= 0:
        return 1.0
    return float(sum(math.comb(k, j) * 0.5 ** k * scipy.stats.chi2.sf(x, j)
                     for j in range(1, k + 1)))


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


def mixture(stat, k):
    """``(pvalue, distribution)`` of the chi-bar-squared reference of ``k`` boundary orders."""
    distribution = ("chi2 mixture 0.5*chi2_0 + 0.5*chi2_1" if k == 1 else
                    f"chi-bar-squared sum_j C({k},j)/2^{k} chi2_j (orders assumed "
                    "uncorrelated)")
    return chi_bar_squared_sf(stat, k), distribution


def statistic(rss_r, rss_f, n):
    """The LR statistic ``n log(rss_r / rss_f)``, 0 when the full fit is not better."""
    return max(n * math.log(rss_r / rss_f), 0.0)


def order_notes(full, rss_r, rss_f):
    """What the user must know about a test's two fits (cancelled orders; a full fit above)."""
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
    bootstrap need the record (:func:`lr_test` with ``u``, ``y``). The result keeps no
    residuals, so the test is not corrected for their correlation here (``pvalue_corrected``
    NaN): ``fohw.order_test(result, u, y)`` refits the integer class and gives it, and the verdict.

    A :class:`fohw.FitResult` of another kind keeps no fit at orders 0: the test refits one
    (:func:`fohw.order_test` with the data), so it is refused here, naming that call.

    Returns
    -------
    LRTest or None
        None when ``full`` has no ``details["integer_sse"]`` (another method, a given start,
        no free order, a bound of an order above 0, or a series output map, whose fit starts
        from the fit without the map instead: ``fohw.order_test(result, u, y)`` refits it).

    Raises
    ------
    ParameterError
        ``full`` is not a lagged IdentificationResult of a least-squares method (a FitResult:
        the message gives the call with the data).
    """
    if hasattr(full, "model") and hasattr(full, "parameters") and not hasattr(full, "structure"):
        raise ParameterError(
            f"the order test of a {type(full.model).__name__} fit refits its model with the free "
            "orders held at 0 on the data it was fitted to (a result keeps no data, and the "
            "fitting code sits above the result): fohw.order_test(fit, record) or "
            "fohw.order_test(fit, u, y), with validation=(u_val, y_val) for the verdict.")
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
    stat = statistic(rss_r, rss_f, n)
    df = fs.n_linear - rs.n_linear + fs.n_nonlinear - rs.n_nonlinear
    notes = order_notes(full, rss_r, rss_f)
    if unidentified:
        pvalue, distribution = math.nan, "none without the record"
        notes.append(f"The order(s) {list(unidentified)} are not identified under the null "
                     "(Davies 1977): fohw.lr_test(restricted, full, u=u, y=y) gives Davies' "
                     "bound or a bootstrap p-value.")
    else:
        pvalue, distribution = mixture(stat, len(boundary))
    return LRTest(statistic=stat, df=df, pvalue=float(pvalue), distribution=distribution,
                  criterion="free-run RSS", n=n, rss_restricted=rss_r, rss_full=rss_f,
                  boundary=boundary, unidentified=unidentified, note=" ".join(notes),
                  correction="it needs both fits' residuals: fohw.order_test(result, u, y) with "
                             "the estimation record")


def autocorrelation(x, max_lag, *, demean=True):
    """``rho(k) = sum_t x_t x_{t+k} / sum_t x_t^2`` for ``k = 0 .. max_lag`` (biased; FFT).

    The mean is removed first unless ``demean=False`` (a direction, not a stationary series).
    A linear (zero-padded), not circular, correlation; all zeros give ``rho = [1, 0, ...]``.
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean() if demean else x
    n = x.shape[0]
    nfft = 1 << (2 * n - 1).bit_length()
    spec = np.fft.rfft(x, nfft)
    acov = np.fft.irfft(spec * np.conj(spec), nfft)[:max_lag + 1]
    if not acov[0] > 0:
        return np.r_[1.0, np.zeros(max_lag)]
    return acov / acov[0]


def _first_nonpositive(rho):
    """The first lag ``k >= 1`` with ``rho[k] <= 0`` (``len(rho)`` when there is none)."""
    neg = np.flatnonzero(rho[1:] <= 0)
    return int(neg[0]) + 1 if neg.size else len(rho)


def _yule_walker_aic(x, max_order):
    """``[1, -a_1, ..., -a_p]`` of an AR(p) fitted to ``x`` by Yule--Walker, ``p`` by AIC."""
    n = x.shape[0]
    rho = autocorrelation(x, max_order)
    best, best_aic = np.ones(1), math.log(1.0)          # p = 0: innovation variance rho(0) = 1
    for p in range(1, max_order + 1):
        a = scipy.linalg.solve_toeplitz(rho[:p], rho[1:p + 1])
        var = float(1.0 - rho[1:p + 1] @ a)
        if not var > 0:
            break
        aic = math.log(var) + 2 * p / n
        if aic < best_aic:
            best, best_aic = np.r_[1.0, -a], aic
    return best


def _sandwich_factor(rho_e, direction, lag):
    """``kappa``: the Bartlett-weighted score variance ratio along ``direction`` (n, q)."""
    G = direction
    gram = G.T @ G
    w = 1.0 - np.arange(lag + 1) / (lag + 1)
    total = gram.copy()
    n = G.shape[0]
    for k in range(1, lag + 1):
        c = G[:n - k].T @ G[k:]
        total += w[k] * rho_e[k] * (c + c.T)
    try:
        ratio = np.linalg.solve(gram, total)
    except np.linalg.LinAlgError:
        return math.nan
    return float(np.trace(ratio)) / G.shape[1]


def corrected_statistic(residuals_restricted, residuals_full, statistic_white, *,
                        correction="sandwich", direction=None):
    """The LR statistic corrected for correlated residuals, and a sentence saying how.

    Parameters
    ----------
    residuals_restricted, residuals_full : array_like, shape (n,)
        The residuals of the criterion of both fits (free-run errors for a simulation-error
        fit, one-step errors for an equation-error one) over the same ``n`` samples.
    statistic_white : float
        ``n log(RSS_r / RSS_f)`` (what :func:`statistic` gives), corrected by ``"sandwich"``
        and ``"bartlett"``; ``"prewhitened"`` recomputes it from the filtered residuals.
    correction : {"sandwich", "bartlett", "prewhitened"}
        See the module's docstring and docs/order_test.md.
    direction : array_like, shape (n,) or (n, q), optional
        The score direction for ``"sandwich"`` (the tested parameters' sensitivities at the
        null, the others projected out); default the difference of the residuals.

    Returns
    -------
    (float, str)
        The corrected statistic (``>= 0``) and the correction in words with its factor.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.lr_statistic import corrected_statistic
    >>> rng = np.random.default_rng(0)
    >>> e = rng.standard_normal(2000)
    >>> e_r = e + 0.05 * np.sin(np.arange(2000) / 5)
    >>> lr = 2000 * np.log((e_r @ e_r) / (e @ e))
    >>> x, text = corrected_statistic(e_r, e, lr)     # white residuals: about the same
    >>> bool(abs(x / lr - 1) < 0.2), text.split(":")[0]
    (True, 'sandwich')
    """
    if correction not in CORRECTIONS:
        raise ParameterError(f"`correction` must be one of {CORRECTIONS} or None; got "
                             f"{correction!r}.")
    e_r = np.asarray(residuals_restricted, dtype=float)
    e_f = np.asarray(residuals_full, dtype=float)
    if e_r.shape != e_f.shape or e_r.ndim != 1 or e_r.shape[0] < 8:
        raise ParameterError(f"the residuals of both fits must be 1-D of one length, at least 8 "
                             f"samples; got shapes {e_r.shape} and {e_f.shape}.")
    if not (np.all(np.isfinite(e_r)) and np.all(np.isfinite(e_f))):
        raise ParameterError("the residuals of a fit are not finite: no correction.")
    n = e_f.shape[0]
    stat = float(statistic_white)
    if correction == "prewhitened":
        A = _yule_walker_aic(e_r, min(10, n // 10))
        p = A.shape[0] - 1
        w_r = scipy.signal.lfilter(A, [1.0], e_r)[p:]
        w_f = scipy.signal.lfilter(A, [1.0], e_f)[p:]
        ss_r, ss_f = float(w_r @ w_r), float(w_f @ w_f)
        value = max(n * math.log(ss_r / ss_f), 0.0) if ss_f > 0 and ss_r > 0 else 0.0
        return value, (f"prewhitened: AR({p}) of the restricted fit's residuals (Yule-Walker, "
                       f"AIC) applied to both")
    if np.ptp(e_f) == 0:
        raise ParameterError("the full fit's residuals are constant: their autocorrelation "
                             "is undefined.")
    if correction == "bartlett":
        n_eff = effective_samples(e_f)
        return stat * n_eff / n, f"bartlett: n_eff = {n_eff:.4g} of {n} samples"
    rho_e = autocorrelation(e_f, n // 4)
    lag = min(2 * _first_nonpositive(rho_e), n // 4)
    along = "the score direction"
    if direction is not None:
        G = np.asarray(direction, dtype=float)
        G = G[:, None] if G.ndim == 1 else G
        if G.shape[0] != n or not np.all(np.isfinite(G)) or not np.any(G):
            raise ParameterError(f"`direction` must be finite, not all 0, with {n} rows (the "
                                 f"residuals'); got shape {G.shape}.")
        kappa = _sandwich_factor(rho_e, G, lag)
    if direction is None or not math.isfinite(kappa):
        along = "the fits' difference (no score direction)"
        d = e_r - e_f
        kappa = _sandwich_factor(rho_e, d[:, None], lag) if np.any(d) else 1.0
    kappa = max(kappa, 1.0 / n)
    return stat / kappa, f"sandwich: factor {kappa:.4g}, lags up to {lag}, along {along}"


def effective_samples(residuals, max_lag=None):
    """Bartlett's effective sample size ``n / (1 + 2 sum_{k>=1} rho_k)`` of correlated residuals.

    A likelihood-ratio statistic ``n log(RSS_r / RSS_f)`` and a profile interval assume white
    residuals; with correlated ones (a free run's usually are) ``n`` overstates the
    information. This estimate can be passed as ``n_effective`` to :func:`fohw.lr_test` and
    :func:`fohw.profile_interval` for a more honest, still approximate, statistic.

    Parameters
    ----------
    residuals : array_like, shape (n,)
        At least 4 finite samples, not all equal.
    max_lag : int, optional
        Lags summed; default: up to the first non-positive autocorrelation (Geyer's initial
        positive sequence, a common truncation), at most ``n // 4``.

    Returns
    -------
    float
        Between 1 and ``n`` (white residuals give about ``n``).

    Notes
    -----
    ``rho_k`` is the sample autocorrelation at lag ``k`` (the mean removed, the biased
    estimator ``sum_t r_t r_{t+k} / sum_t r_t^2``), computed by FFT with zero padding (a
    linear, not circular, correlation). For an AR(1) with coefficient ``phi`` the sum gives
    ``n (1 - phi) / (1 + phi)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.lr_statistic import effective_samples
    >>> e = np.random.default_rng(0).standard_normal(20_000)
    >>> x = np.convolve(e, np.ones(10) / 10)[:20_000]     # a moving average: n_eff ~ n / 10
    >>> 1500 < effective_samples(x) < 2500
    True
    """
    r = check_array(residuals, "residuals", min_length=4)
    if np.ptp(r) == 0:
        raise ParameterError(f"`residuals` are constant ({float(r[0])!r} at all {r.size} samples): their "
                             "autocorrelation is undefined.")
    n = r.shape[0]
    acf = autocorrelation(r, n - 1)
    limit = n // 4 if max_lag is None else check_int(max_lag, "max_lag", minimum=1)
    total = 0.0
    for k in range(1, min(limit, n - 1) + 1):
        if max_lag is None and acf[k] <= 0:
            break
        total += acf[k]
    return float(min(max(n / (1.0 + 2.0 * total), 1.0), n))
