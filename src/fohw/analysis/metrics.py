"""Validation metrics: fit index, error range, RMSE and residual tests (paper Section 6.2 and beyond).

Every function takes the measured output and a model output (one-step prediction or free-run
simulation) and an optional start-up window ``n_init``: the first ``n_init`` samples, where a
zero-initial-condition model is still in its transient, are excluded, and the functions say so
in their results.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import DimensionError

__all__ = ["fit_percent", "error_range", "rmse", "whiteness_test", "cross_correlation_test",
           "CorrelationTest"]


def _pair(y, yhat, n_init):
    y = check_array(y, "y")
    yhat = check_array(yhat, "yhat")
    check_same_length(y, yhat, "y", "yhat")
    n_init = check_int(n_init, "n_init", minimum=0)
    if n_init >= y.shape[0] - 1:
        raise DimensionError(f"`n_init` must leave at least 2 samples; got n_init={n_init} for "
                             f"{y.shape[0]} samples.")
    return y[n_init:], yhat[n_init:]


def fit_percent(y, yhat, *, n_init=0):
    """Fit index ``100 (1 - ||y - yhat|| / ||y - mean(y)||)`` (MATLAB ``compare``'s NRMSE fit).

    Parameters
    ----------
    y, yhat : array_like, shape (N,)
        Measured and model output.
    n_init : int, optional
        Leading samples excluded (start-up transient). Default 0.

    Returns
    -------
    float
        100 for a perfect fit, 0 for the mean, negative for worse than the mean.

    Examples
    --------
    >>> from fohw.analysis.metrics import fit_percent
    >>> fit_percent([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]), fit_percent([1.0, 2.0, 3.0], [2.0, 2.0, 2.0])
    (100.0, 0.0)
    """
    y, yhat = _pair(y, yhat, n_init)
    denom = np.linalg.norm(y - y.mean())
    if denom == 0:
        raise DimensionError("`y` is constant after `n_init`: the fit index is undefined.")
    return float(100.0 * (1.0 - np.linalg.norm(y - yhat) / denom))


def error_range(y, yhat, *, n_init=0):
    """Smallest and largest error ``y - yhat`` after the start-up window (Table 3's measure).

    Examples
    --------
    >>> from fohw.analysis.metrics import error_range
    >>> error_range([0.0, 1.0, 2.0], [5.0, 1.1, 1.8], n_init=1)
    (-0.10000000000000009, 0.19999999999999996)
    """
    y, yhat = _pair(y, yhat, n_init)
    e = y - yhat
    return float(e.min()), float(e.max())


def rmse(y, yhat, *, n_init=0):
    """Root-mean-square error after the start-up window."""
    y, yhat = _pair(y, yhat, n_init)
    return float(np.sqrt(np.mean((y - yhat) ** 2)))


@dataclass(frozen=True)
class CorrelationTest:
    """Result of a residual correlation test.

    Attributes
    ----------
    lags : ndarray
        Lags at which the normalised correlation was computed.
    correlation : ndarray
        Normalised (cross-)correlation at those lags.
    bound : float
        ``z / sqrt(N)``: the band an uncorrelated sequence stays in with the given confidence
        at each lag.
    n_outside : int
        Lags whose correlation leaves the band.
    statistic : float
        ``N * sum(correlation**2)`` (Ljung–Box-type portmanteau; chi-square with
        ``len(lags)`` degrees of freedom under the null hypothesis).
    p_value : float
        Of ``statistic``.
    passed : bool
        ``p_value >= 1 - confidence``.
    """

    lags: np.ndarray
    correlation: np.ndarray
    bound: float
    n_outside: int
    statistic: float
    p_value: float
    passed: bool


def _normalised_xcorr(a, b, lags):
    a = a - a.mean()
    b = b - b.mean()
    n = a.shape[0]
    scale = np.sqrt((a @ a) * (b @ b))
    out = []
    for lag in lags:
        if lag >= 0:
            out.append(a[lag:] @ b[: n - lag])
        else:
            out.append(a[: n + lag] @ b[-lag:])
    return np.array(out) / scale


def _test(corr, lags, n, confidence):
    z = stats.norm.ppf(0.5 + confidence / 2)
    bound = z / np.sqrt(n)
    statistic = float(n * np.sum(corr**2))
    p = float(stats.chi2.sf(statistic, len(lags)))
    return CorrelationTest(lags=np.asarray(lags), correlation=corr, bound=float(bound),
                           n_outside=int(np.sum(np.abs(corr) > bound)), statistic=statistic,
                           p_value=p, passed=p >= 1 - confidence)


def whiteness_test(residuals, *, max_lag=25, confidence=0.99, n_init=0):
    """Test residuals for whiteness by their autocorrelation at lags ``1..max_lag``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.analysis.metrics import whiteness_test
    >>> whiteness_test(np.random.default_rng(0).standard_normal(5000)).passed
    True
    """
    e = check_array(residuals, "residuals")[check_int(n_init, "n_init", minimum=0):]
    max_lag = check_int(max_lag, "max_lag", minimum=1, maximum=e.shape[0] - 2)
    confidence = check_scalar(confidence, "confidence", lower=0.0, upper=1.0,
                              lower_inclusive=False, upper_inclusive=False)
    lags = np.arange(1, max_lag + 1)
    return _test(_normalised_xcorr(e, e, lags), lags, e.shape[0], confidence)


def cross_correlation_test(residuals, u, *, max_lag=25, confidence=0.99, n_init=0):
    """Test residuals for correlation with past and future input, lags ``-max_lag..max_lag``.

    A correlation at positive lag (residual after input) means the model misses input dynamics.
    """
    e = check_array(residuals, "residuals")
    u = check_array(u, "u")
    check_same_length(e, u, "residuals", "u")
    n_init = check_int(n_init, "n_init", minimum=0)
    e, u = e[n_init:], u[n_init:]
    max_lag = check_int(max_lag, "max_lag", minimum=0, maximum=e.shape[0] - 2)
    confidence = check_scalar(confidence, "confidence", lower=0.0, upper=1.0,
                              lower_inclusive=False, upper_inclusive=False)
    lags = np.arange(-max_lag, max_lag + 1)
    return _test(_normalised_xcorr(e, u, lags), lags, e.shape[0], confidence)
