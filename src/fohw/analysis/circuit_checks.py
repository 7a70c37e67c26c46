"""Does a circuit's fractional element earn its keep: LR test, profile interval of its order, impedance check.

Three checks of a :func:`fohw.fit` result of an :class:`fohw.EquivalentCircuit`:

- :func:`circuit_lr_test`: the likelihood-ratio test of a fractional element against its integer
  limit (a ZARC's ``alpha = 1`` is the RC element), ``LR = n log(RSS_restricted / RSS_full)``.
  The order sits on the boundary of its range under the null, so the reference is the
  ``0.5 chi2_0 + 0.5 chi2_1`` mixture (Self & Liang 1987; :func:`fohw.analysis.lrtest.chi_bar_squared_sf`,
  :class:`fohw.analysis.lrtest.LRTest`);
- :func:`circuit_order_interval`: the profile-likelihood interval of an order, refitting every
  other parameter at fixed orders (:class:`fohw.analysis.profile_interval.ProfileInterval`);
- :func:`impedance_error`: the relative error of the circuit's impedance against a measured
  spectrum in a band.

Both likelihood statistics assume white Gaussian residuals. A drive cycle's simulation residuals
are strongly correlated, so ``n`` overstates the information; :func:`effective_samples` gives
the Bartlett estimate ``n / (1 + 2 sum_k rho_k)`` from the residuals' autocorrelation, which can
be passed as ``n`` for a more honest (still approximate) statistic.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_array, check_int, check_scalar
from ..estimators.fit import fit as fohw_fit
from ..exceptions import ConvergenceWarning, ParameterError, RankDeficiencyWarning
from ..fit_result import FitResult
from ..model.circuit import EquivalentCircuit
from .lrtest import LRTest, chi_bar_squared_sf
from .profile_interval import ProfileInterval

__all__ = ["circuit_lr_test", "circuit_order_interval", "effective_samples", "impedance_error"]


def effective_samples(residuals, max_lag=None):
    """Bartlett's effective sample size ``n / (1 + 2 sum_{k>=1} rho_k)`` of correlated residuals.

    Parameters
    ----------
    residuals : array_like, shape (n,)
    max_lag : int, optional
        Lags summed; default: up to the first non-positive autocorrelation (Geyer's initial
        positive sequence, a common truncation), at most ``n // 4``.

    Returns
    -------
    float
        Between 1 and ``n`` (white residuals give about ``n``).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.analysis.circuit_checks import effective_samples
    >>> e = np.random.default_rng(0).standard_normal(20_000)
    >>> x = np.convolve(e, np.ones(10) / 10)[:20_000]     # a moving average: n_eff ~ n / 10
    >>> 1500 < effective_samples(x) < 2500
    True
    """
    r = check_array(residuals, "residuals", min_length=4)
    n = r.shape[0]
    r = r - r.mean()
    nfft = 1 << (2 * n - 1).bit_length()
    spec = np.fft.rfft(r, nfft)
    acf = np.fft.irfft(spec * np.conj(spec), nfft)[:n]
    acf = acf / acf[0]
    limit = n // 4 if max_lag is None else check_int(max_lag, "max_lag", minimum=1)
    total = 0.0
    for k in range(1, min(limit, n - 1) + 1):
        if max_lag is None and acf[k] <= 0:
            break
        total += acf[k]
    return float(min(max(n / (1.0 + 2.0 * total), 1.0), n))


def _check_fit(fit, name):
    if not isinstance(fit, FitResult) or not isinstance(fit.model, EquivalentCircuit):
        what = type(fit).__name__
        if isinstance(fit, FitResult):
            what += f" of a {type(fit.model).__name__}"
        raise ParameterError(f"`{name}` must be a fohw.fit result of an EquivalentCircuit; got {what}.")
    return fit


def circuit_lr_test(restricted, full, *, n=None):
    """LR test of the fractional orders of ``full`` against ``restricted`` with them at 1.

    Parameters
    ----------
    restricted, full : FitResult
        :func:`fohw.fit` results of circuits on the same record: ``full`` with free orders,
        ``restricted`` the same circuit with those orders fixed at 1
        (``circuit.parameters.replace("alpha1", value=1.0, fixed=True)``), or with the ZARC
        elements replaced by RC elements.
    n : float, optional
        Samples of the statistic; default ``full.n_samples`` (white residuals). Pass
        :func:`effective_samples` of the residuals for correlated ones.

    Returns
    -------
    LRTest
        ``statistic = n log(SSE_restricted / SSE_full)``, reference ``0.5 chi2_0 + 0.5 chi2_1``
        for one order (chi-bar-squared with binomial weights for several).
    """
    restricted = _check_fit(restricted, "restricted")
    full = _check_fit(full, "full")
    if restricted.data_digest != full.data_digest:
        raise ParameterError("`restricted` and `full` must be fits of the same record (and weights); "
                             f"their data digests differ ({restricted.data_digest} and "
                             f"{full.data_digest}).")
    kinds_r = tuple("zarc" if k == "rc" else k for k in restricted.model.kinds)
    if kinds_r != tuple("zarc" if k == "rc" else k for k in full.model.kinds):
        raise ParameterError(f"`restricted` must have the elements of `full` with integer orders; got "
                             f"{restricted.model.kinds} and {full.model.kinds}.")
    free = [nm for nm in full.free_names if nm.startswith("alpha")]
    rpar = restricted.parameters
    tested = [nm for nm in free if nm not in rpar or (rpar[nm].value == 1.0 and rpar[nm].fixed)]
    k = len(tested)
    if k == 0:
        raise ParameterError("`restricted` holds no order of `full` at 1: nothing to test.")
    if n is None:
        n = full.n_samples
    n = check_scalar(n, "n", lower=1.0)
    stat = max(n * math.log(restricted.sse / full.sse), 0.0)
    dist = ("chi2 mixture 0.5*chi2_0 + 0.5*chi2_1" if k == 1 else
            f"chi-bar-squared, binomial weights over {k} orders")
    note = ""
    if full.sse > restricted.sse:
        note = "The full fit is worse than the restricted one: its search did not converge to the best."
    if n < full.n_samples:
        note = (note + f" n = {n:.4g} effective samples of {full.n_samples}.").strip()
    return LRTest(statistic=float(stat), df=k, pvalue=chi_bar_squared_sf(stat, k),
                  distribution=dist, criterion="free-run RSS", n=int(round(n)),
                  rss_restricted=restricted.sse, rss_full=full.sse, boundary=tuple(tested),
                  note=note)


def circuit_order_interval(fit, u, y, name="alpha1", level=0.95, *, n=None, n_grid=9,
                           xtol=1e-3):
    """Profile-likelihood interval of one order of a fitted circuit.

    Parameters
    ----------
    fit : FitResult
        A :func:`fohw.fit` result of an :class:`fohw.EquivalentCircuit`.
    u, y : array_like
        The record ``fit`` was fitted to (``u = [current, soc]``, ``y`` the voltage).
    name : str, optional
        The order (default ``"alpha1"``).
    level : float, optional
        Confidence level (default 0.95): the interval is where
        ``n log(SSE(alpha) / SSE_hat) <= chi2_1(level)``.
    n : float, optional
        Samples of the statistic (default ``fit.n_samples``; see :func:`effective_samples`).
    n_grid : int, optional
        Grid points over the order's bounds (default 9; the bounds of the fit's parameter),
        each a refit with the order fixed, started from the fit's parameters (and the
        circuit's scan); the ends are then found by root finding between grid points.
    xtol : float, optional
        Accuracy of the ends (default 1e-3).

    Returns
    -------
    ProfileInterval
        With ``grid`` and ``statistic`` of every refit.
    """
    fit = _check_fit(fit, "fit")
    orders = [nm for nm in fit.free_names if fit.parameters[nm].order]
    if name not in orders:
        raise ParameterError(f"`name` must be a free order of the fit ({', '.join(orders)}); got {name!r}.")
    level = check_scalar(level, "level", lower=0.0, upper=1.0, lower_inclusive=False,
                         upper_inclusive=False)
    n_grid = check_int(n_grid, "n_grid", minimum=2)
    n = fit.n_samples if n is None else check_scalar(n, "n", lower=1.0)
    crit = float(scipy.stats.chi2.ppf(level, 1))
    lo, hi = fit.parameters[name].bounds
    estimate = fit.parameters[name].value
    weight = fit.options.get("sample_weight")
    cache = {}

    def refit(value):
        value = float(value)
        if value not in cache:
            params = fit.parameters.replace(name, value=value, fixed=True)
            model = fit.model.with_parameters(params)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", (ConvergenceWarning, RankDeficiencyWarning))
                r = fohw_fit(model, u, y, start=model, sample_weight=weight, order_grid=1,
                             n_starts=1)
            cache[value] = max(n * math.log(r.sse / fit.sse), 0.0)
        return cache[value]

    grid = np.unique(np.concatenate([np.linspace(lo, hi, n_grid), [estimate]]))
    stats = np.array([refit(a) for a in grid])

    def end(side):
        j0 = int(np.argmin(np.abs(grid - estimate)))
        js = range(j0 - 1, -1, -1) if side == "low" else range(j0 + 1, grid.size)
        prev = j0
        for j in js:
            if stats[j] > crit:
                a, b = sorted((grid[prev], grid[j]))
                return scipy.optimize.brentq(lambda x: refit(x) - crit, a, b, xtol=xtol), False
            prev = j
        return (lo if side == "low" else hi), True

    low, open_low = end("low")
    high, open_high = end("high")
    one_sided = {(False, False): "", (True, False): "low", (False, True): "high",
                 (True, True): "both"}[(open_low, open_high)]
    keys = np.array(sorted(cache))
    return ProfileInterval(name=name, estimate=estimate, low=float(low), high=float(high),
                           level=level, grid=keys, statistic=np.array([cache[x] for x in keys]),
                           one_sided=one_sided)


def impedance_error(circuit, f, z, band=None, *, discrete=False, capacity=None, ocv_slope=0.0):
    """Relative error ``|Z_model - Z| / |Z|`` of a circuit's impedance against a measured spectrum.

    Parameters
    ----------
    circuit : EquivalentCircuit
    f : array_like, shape (m,)
        Frequencies [Hz].
    z : array_like of complex, shape (m,)
        Measured impedance [ohm].
    band : (float, float), optional
        Keep the frequencies in ``[low, high]`` [Hz]; default all.
    discrete : bool, optional
        Use the GL-discretised model's response at its ``dt`` (see ``EquivalentCircuit.impedance``).
    capacity, ocv_slope : float, optional
        Add the OCV's capacitor (see ``EquivalentCircuit.impedance``).

    Returns
    -------
    f, model, rel : ndarray
        The frequencies kept, the model's impedance there and the relative errors; the RMS
        relative error is ``sqrt(mean(rel**2))``.
    """
    f = check_array(f, "f")
    z = np.asarray(z, dtype=np.complex128).ravel()
    if z.shape != f.shape:
        raise ParameterError(f"`z` must have one value per frequency; got {z.shape[0]} values for "
                             f"{f.shape[0]} frequencies.")
    keep = np.ones(f.shape, dtype=bool)
    if band is not None:
        keep = (f >= band[0]) & (f <= band[1])
        if not keep.any():
            raise ParameterError(f"`band` {band!r} holds none of the frequencies.")
    model = circuit.impedance(f[keep], discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)
    return f[keep], model, np.abs(model - z[keep]) / np.abs(z[keep])
