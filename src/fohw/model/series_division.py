"""Causal convolution and power-series division: the O(N log N) kernel of the transfer-function simulator.

A linear, time-invariant recursion with full memory, ``sum_{j=0}^{k} c[j] y[k-j] = f[k]`` for
``k = 0, 1, …``, is the truncated power-series identity ``C(x) Y(x) = F(x) mod x^N``, so
``y = F / C``: the first ``N`` coefficients of the quotient of two power series. The reciprocal
``1 / C`` is computed by Newton's iteration ``r <- r (2 - c r)``, which doubles the number of
correct coefficients per step at the cost of two FFT products (Kung 1974; von zur Gathen &
Gerhard, *Modern Computer Algebra*, Sec. 9.1), in ``O(N log N)`` operations overall. Every
product is a zero-padded (never circular) FFT convolution.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

__all__ = ["causal_product", "series_reciprocal", "series_divide"]

# Below this length np.convolve (direct) is faster than two real FFTs.
DIRECT_MAX = 64


def causal_product(a, b, n=None):
    """First ``n`` coefficients of the product of two power series (a causal convolution).

    Parameters
    ----------
    a, b : array_like, 1-D
        Coefficients, ``a[0]`` of ``x^0`` first.
    n : int, optional
        Number of coefficients wanted (default ``len(a)``).

    Returns
    -------
    ndarray, shape (n,)
        ``out[k] = sum_{j=0}^{k} a[j] b[k-j]`` with entries beyond either input taken as zero.

    Examples
    --------
    >>> from fohw.model.series_division import causal_product
    >>> causal_product([1.0, 1.0], [1.0, 2.0, 3.0], 3)
    array([1., 3., 5.])
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = a.shape[0] if n is None else int(n)
    a = a[:n]
    b = b[:n]
    out = np.zeros(n)
    if a.shape[0] == 0 or b.shape[0] == 0:
        return out
    m = min(n, a.shape[0] + b.shape[0] - 1)
    if min(a.shape[0], b.shape[0]) <= DIRECT_MAX:
        out[:m] = np.convolve(a, b)[:m]
        return out
    nfft = scipy.fft.next_fast_len(a.shape[0] + b.shape[0] - 1, real=True)
    out[:m] = scipy.fft.irfft(scipy.fft.rfft(a, nfft) * scipy.fft.rfft(b, nfft), nfft)[:m]
    return out


def series_reciprocal(c, n=None):
    """First ``n`` coefficients of ``1 / C(x)`` for ``C(x) = sum_j c[j] x^j`` with ``c[0] != 0``.

    Parameters
    ----------
    c : array_like, 1-D
        Coefficients of the series; ``c[0]`` must be non-zero.
    n : int, optional
        Number of coefficients wanted (default ``len(c)``).

    Returns
    -------
    r : ndarray, shape (n,)
        ``sum_{j=0}^{k} c[j] r[k-j] = 1`` for ``k = 0`` and ``0`` for ``0 < k < n``.

    Notes
    -----
    Newton's iteration: with ``r`` correct to ``m`` terms, ``e = (c r)[m:2m]`` and the next
    ``m`` terms are ``-(r e)[:m]``. Each doubling costs two FFT products, so the whole reciprocal
    costs about as much as six products of length ``n``.

    Examples
    --------
    >>> from fohw.model.series_division import series_reciprocal
    >>> series_reciprocal([1.0, -0.5], 4)          # 1 / (1 - x/2) = sum (x/2)^k
    array([1.   , 0.5  , 0.25 , 0.125])
    """
    c = np.asarray(c, dtype=np.float64)
    n = c.shape[0] if n is None else int(n)
    if c.shape[0] == 0 or c[0] == 0.0:
        raise ZeroDivisionError("the series' constant coefficient c[0] is zero: 1/C has no power series")
    r = np.empty(n)
    r[0] = 1.0 / c[0]
    m = 1
    while m < n:
        m2 = min(2 * m, n)
        e = causal_product(c[:m2], r[:m], m2)[m:m2]      # (c r)[m:m2]; (c r)[:m] = [1, 0, …]
        r[m:m2] = -causal_product(r[:m2 - m], e, m2 - m)
        m = m2
    return r


def series_divide(f, c):
    """Solve ``sum_{j=0}^{k} c[j] y[k-j] = f[k]``, ``k = 0..N-1``: the first ``N`` terms of ``F / C``.

    Parameters
    ----------
    f : array_like, shape (N,)
        Right-hand side (the forcing).
    c : array_like, shape (>= 1,)
        The recursion's weights, ``c[0] != 0``; entries beyond ``N`` are ignored and missing
        ones are zero.

    Returns
    -------
    y : ndarray, shape (N,)

    Notes
    -----
    ``y = (1/C) F``: one :func:`series_reciprocal` and one :func:`causal_product`, ``O(N log N)``.
    The implicit recursion ``y[k] = (f[k] - sum_{j>=1} c[j] y[k-j]) / c[0]`` gives the same numbers
    to rounding error (the tests compare every sample with that literal ``O(N^2)`` loop).

    Examples
    --------
    >>> from fohw.model.series_division import series_divide
    >>> series_divide([1.0, 1.0, 1.0], [2.0, -1.0])    # y[k] = (1 + y[k-1]) / 2
    array([0.5  , 0.75 , 0.875])
    """
    f = np.asarray(f, dtype=np.float64)
    n = f.shape[0]
    c = np.asarray(c, dtype=np.float64)[:n]
    return causal_product(series_reciprocal(c, n), f, n)
