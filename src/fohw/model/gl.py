"""Grünwald–Letnikov fractional difference (paper Section 2.1, Eqs. 1–5).

The GL difference of order ``alpha`` of a zero-initial-condition signal ``x`` is

.. math:: (\\Delta^{\\alpha} x)[k] = h^{-\\alpha} \\sum_{j=0}^{k} \\beta_j\\, x[k-j],
   \\qquad \\beta_j = (-1)^j \\binom{\\alpha}{j},

a *linear* convolution of ``x`` with the weights ``beta`` cut to the length of ``x``.
The full-memory sum is evaluated by a zero-padded real FFT (never a circular one);
short signals and short memories use the direct sum.
"""

from __future__ import annotations

import math
import os

import numpy as np

from .._types import ArrayLike
from .._validation import check_array, check_int, check_scalar
from ..exceptions import DimensionError, ParameterError
from .kernels import causal_convolve

__all__ = ["gl_weights", "gl_weights_unchecked", "gl_weights_derivative", "gl_difference",
           "past_transient", "sampling_scale", "check_length"]


def _memory_bytes():
    """The physical memory of this machine in bytes, or None where the system does not say."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):       # pragma: no cover - not POSIX
        return None


def _bytes_text(n_bytes):
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n_bytes >= size:
            return f"{n_bytes / size:.3g} {unit}"
    return f"{n_bytes:.0f} bytes"


def check_length(n, name="n", *, arrays=1):
    """``n`` as a positive int whose ``arrays`` float64 arrays of ``n`` entries fit in memory.

    Refused (naming ``name``, the memory needed and the machine's) when they need more than
    the machine's physical memory: numpy would raise a bare ``MemoryError`` or the system
    would start swapping.
    """
    n = check_int(n, name, minimum=1)
    need = 8 * arrays * n
    have = _memory_bytes()
    if have is not None and need > have:
        raise ParameterError(f"`{name}` = {n} needs {_bytes_text(need)} of memory "
                             f"({arrays} float64 array(s) of {n} entries), more than this "
                             f"machine's {_bytes_text(have)}; use fewer samples or weights.")
    return n


def sampling_scale(h, nu, name="h"):
    """``h**-nu``, the scale of Eq. (4), or a ParameterError naming ``name`` if it overflows."""
    try:
        return h ** -nu
    except OverflowError:
        raise ParameterError(
            f"`{name}` = {h!r} with the order {nu!r} gives the scale {name}**-order = "
            f"10**{-nu * math.log10(h):.4g}, beyond the largest double (1.8e308): the "
            f"difference cannot be represented. Use a sampling time in other units (the "
            f"differences scale with it).") from None


def gl_weights(alpha: float, n: int) -> np.ndarray:
    """Grünwald–Letnikov weights ``beta[j] = (-1)**j * binom(alpha, j)``, ``j = 0..n-1``.

    Parameters
    ----------
    alpha : float
        Order of the difference; any finite real (negative orders give fractional sums).
    n : int
        Number of weights, ``n >= 1``.

    Returns
    -------
    beta : ndarray, shape (n,)
        ``beta[0] = 1`` and ``beta[j] = beta[j-1] * (j - 1 - alpha) / j``.

    Notes
    -----
    Eq. (3) of the paper, evaluated as the cumulative product of the factors
    ``(j - 1 - alpha) / j`` (the same as ``1 - (alpha + 1) / j``, but without its cancellation:
    near an integer order ``j - 1 - alpha`` is exact, so each weight is within ``3 j`` rounding
    errors of the exact one, relative to itself). For a non-negative integer ``alpha`` the factor
    at ``j = alpha + 1`` is exactly zero, so all later weights are exactly zero.

    Examples
    --------
    >>> import fohw
    >>> fohw.gl_weights(0.5, 4)
    array([ 1.    , -0.5   , -0.125 , -0.0625])
    >>> fohw.gl_weights(1.0, 4)
    array([ 1., -1.,  0.,  0.])
    """
    return gl_weights_unchecked(check_scalar(alpha, "alpha"), check_length(n, "n"))


def gl_weights_unchecked(alpha, n):
    """:func:`gl_weights` without validation, for per-sample loops (a float ``alpha``, ``n >= 1``)."""
    beta = np.empty(n)
    beta[0] = 1.0
    j = np.arange(1.0, n)
    np.cumprod((j - 1.0 - alpha) / j, out=beta[1:])
    return beta


def gl_weights_derivative(alpha: float, n: int) -> np.ndarray:
    """Exact derivative of the GL weights with respect to the order, ``d beta[j] / d alpha``.

    Parameters
    ----------
    alpha : float
        Order of the difference; any finite real.
    n : int
        Number of weights, ``n >= 1``.

    Returns
    -------
    dbeta : ndarray, shape (n,)
        ``dbeta[j] = beta[j] * sum_{i=1}^{j} 1 / (alpha + 1 - i)`` wherever that is defined.

    Notes
    -----
    The product ``beta[j] = prod_{i<=j} c_i`` with ``c_i = (i - 1 - alpha)/i`` has one factor
    that can vanish, ``c_{m+1}`` at the integer ``m`` nearest to ``alpha``. That factor is kept
    apart: with ``R_j`` the product of the other factors and ``S_j`` the sum of their logarithmic
    derivatives, ``dbeta[j] = R_j S_j`` before it and ``R_j (c_{m+1} S_j - 1/(m+1))`` from it on.
    The formula is exact for integer ``alpha`` (where ``beta[j] = 0`` but ``dbeta[j] != 0``)
    and has no cancellation near integers. These are the weights of ``h = 1``; for another
    sampling time ``d/d alpha (h**-alpha beta) = h**-alpha (dbeta - log(h) beta)``.

    Examples
    --------
    >>> import fohw
    >>> fohw.model.gl.gl_weights_derivative(1.0, 4)   # beta = [1, -alpha, alpha(alpha-1)/2, ...]
    array([ 0.        , -1.        ,  0.5       ,  0.16666667])
    """
    alpha = check_scalar(alpha, "alpha")
    n = check_length(n, "n", arrays=6)
    i = np.arange(1, n, dtype=np.float64)
    c = (i - 1.0 - alpha) / i
    with np.errstate(divide="ignore"):
        dlog = -1.0 / (i - 1.0 - alpha)
    l0 = int(np.rint(alpha)) + 1          # index of the factor that may vanish
    dbeta = np.zeros(n)
    if l0 < 1 or l0 > n - 1:              # no such factor among the first n - 1
        dbeta[1:] = np.cumprod(c) * np.cumsum(dlog)
        return dbeta
    c_l0 = c[l0 - 1]
    c[l0 - 1] = 1.0
    dlog[l0 - 1] = 0.0
    r = np.cumprod(c)
    s = np.cumsum(dlog)
    dbeta[1:l0] = r[: l0 - 1] * s[: l0 - 1]
    dbeta[l0:] = r[l0 - 1:] * (c_l0 * s[l0 - 1:] - 1.0 / l0)
    return dbeta



def past_transient(nu, lag, n, h=1.0, *, derivative=False):
    """The effect of a past level on a term: ``h**-nu (S_inf(nu) - S_{k-lag}(nu))``, ``k < n``.

    A basis signal that rested at level ``L`` for all ``t < 0`` adds ``L`` times this to the
    term ``(Delta_h^nu s)[k - lag]`` (:class:`fohw.Structure`, notes): ``S_t`` are the partial
    sums of the GL weights (``S_t = 0`` for ``t < 0``), ``S_inf(0) = 1`` and ``S_inf(nu) = 0``
    for ``nu > 0``. The simulator and the information matrix both use it.

    Parameters
    ----------
    nu : float
        The term's order.
    lag : int
        The term's lag, ``>= 0``.
    n : int
        Number of samples.
    h : float, optional
        Sampling time (Eq. 4). Default 1.
    derivative : bool, optional
        Return the derivative with respect to ``nu`` instead.

    Returns
    -------
    ndarray, shape (n,)
    """
    s_inf = 1.0 if nu == 0.0 else 0.0
    w = gl_weights(nu, n - lag) if n > lag else np.zeros(0)
    partial = np.cumsum(w)
    out = np.full(n, s_inf)
    out[lag:] -= partial
    if derivative:
        dpartial = np.cumsum(gl_weights_derivative(nu, n - lag)) if n > lag else np.zeros(0)
        dout = np.zeros(n)
        dout[lag:] = -dpartial
        if h != 1.0:
            dout = (dout - np.log(h) * out) * sampling_scale(h, nu)
        return dout
    return out if h == 1.0 else out * sampling_scale(h, nu)

def gl_difference(x: ArrayLike, alpha: float, *, axis: int = -1, memory: int | None = None,
                  h: float = 1.0) -> np.ndarray:
    """Grünwald–Letnikov fractional difference of a signal (or a batch of signals).

    Parameters
    ----------
    x : array_like
        Signal(s), zero before the first sample. Any number of dimensions; the difference
        runs along ``axis``, so a 2-D batch of signals is one call.
    alpha : float
        Order of the difference; any finite real. ``0`` is the identity, ``1`` the first
        difference ``x[k] - x[k-1]``, negative orders give fractional sums.
    axis : int, optional
        Time axis. Default: the last one.
    memory : int or None, optional
        ``None`` (default) for the full memory ``sum_{j=0}^{k}``; an integer ``L >= 1``
        for the short-memory principle, where the sum stops at ``j = L - 1``.
    h : float, optional
        Sampling time ``h > 0``; the sum is divided by ``h**alpha`` (Eq. 4). Default 1.

    Returns
    -------
    d : ndarray
        Same shape as ``x``, float64.

    Raises
    ------
    ParameterError
        Non-finite ``x`` or ``alpha``, ``memory < 1``, ``h <= 0``, or a difference beyond the
        largest double (``h**-alpha`` or the sums overflow).
    DimensionError
        ``axis`` out of range or an empty time axis.

    Notes
    -----
    Eq. (4) of the paper (Eq. (5) for ``h = 1``). The sum is a linear convolution computed by
    a real FFT zero-padded to at least ``N + L - 1`` points, so no sample wraps around; short
    signals (``N <= 160``) and short memories (``L <= 48``) use the direct sum instead
    (:class:`fohw.model.kernels.CausalConvolution`, the one kernel every part of fohw uses). The result agrees
    with the direct sum to about ``1e-12 * max|x|`` at ``N = 10**6``.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> fohw.gl_difference(np.ones(4), 0.5)   # partial sums of the weights
    array([1.    , 0.5   , 0.375 , 0.3125])
    >>> fohw.gl_difference([1.0, 3.0, 6.0], 1.0)
    array([1., 2., 3.])
    """
    x = check_array(x, "x", ndim=None, min_length=0)
    alpha = check_scalar(alpha, "alpha")
    h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
    if x.ndim == 0:
        raise DimensionError("`x` must have at least one dimension; got a scalar.")
    axis = _normalize_axis(axis, x.ndim)
    n = x.shape[axis]
    if n == 0:
        raise DimensionError(f"`x` must have at least one sample along axis {axis}; got 0.")
    if memory is None:
        m = n
    else:
        m = min(check_int(memory, "memory", minimum=1), n)
    xt = np.moveaxis(x, axis, -1)
    scale = 1.0 if h == 1.0 else sampling_scale(h, alpha)
    with np.errstate(over="ignore", invalid="ignore"):
        out = causal_convolve(xt, gl_weights_unchecked(alpha, m))
        if h != 1.0:
            out *= scale
    if not np.all(np.isfinite(out)):
        by = "" if h == 1.0 else f" and h**-alpha = {scale:.3g}"
        raise ParameterError(
            f"the GL difference of order {alpha!r} overflows: with max |x| = "
            f"{float(np.max(np.abs(x))):.3g}{by} its values go beyond the largest double "
            "(1.8e308). Rescale `x` (the difference scales with it) or `h`.")
    return np.moveaxis(out, -1, axis)


def _normalize_axis(axis, ndim):
    if isinstance(axis, (bool, np.bool_)) or not isinstance(axis, (int, np.integer)):
        raise DimensionError(f"`axis` must be an integer; got {axis!r}.")
    axis = int(axis)
    if not -ndim <= axis < ndim:
        raise DimensionError(f"`axis` {axis} is out of range for `x` with {ndim} dimension(s).")
    return axis % ndim
