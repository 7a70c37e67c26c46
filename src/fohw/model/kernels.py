"""The kernels every simulator shares: one causal FFT product, one online convolution.

- :class:`CausalConvolution` / :func:`causal_convolve` / :func:`causal_product`: the *linear*
  (zero-padded, never circular) causal convolution ``D[t] = sum_{j<=t} w[j] x[t-j]`` cut to the
  signal's length, by a real FFT for long signals and memories and by shifted sums for short
  ones (the GL difference, Eqs. 4–5, and every product of power series).
- :func:`divide_and_conquer` with :class:`HalfMerge`: the online convolution of a feedback
  recursion whose sample ``k`` needs ``sum_{m<k} w[k-m] z[m]`` of samples only known once
  finished (the lagged simulator's memory, Eqs. 14 and 16, and its sensitivity), in
  ``O(N log^2 N)``.
- :func:`series_divide` / :func:`series_reciprocal`: a linear, time-invariant recursion with full
  memory, ``sum_{j=0}^{k} c[j] y[k-j] = f[k]``, i.e. the first ``N`` terms of the power-series
  quotient ``F / C`` (the transfer-function and circuit simulators), solved by that same online
  convolution.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

__all__ = ["CausalConvolution", "causal_convolve", "convolution_at", "causal_product",
           "HalfMerge", "divide_and_conquer", "series_divide", "series_reciprocal"]

# Below these sizes the direct O(N * L) sum beats the FFT (see benchmarks/bench_gl.py).
_DIRECT_MAX_MEMORY = 48
_DIRECT_MAX_LENGTH = 160


def _use_direct(n, m):
    return m <= _DIRECT_MAX_MEMORY or n <= _DIRECT_MAX_LENGTH


def _direct(x, weights):
    """``out[..., t] = sum_j weights[j] x[..., t - j]`` by shifted sums (short memories)."""
    out = weights[0] * x
    for j in range(1, weights.shape[0]):
        out[..., j:] += weights[j] * x[..., :-j]
    return out


class CausalConvolution:
    """The one GL convolution kernel: ``D[..., t] = sum_{j=0}^{t} w[j] x[..., t - j]``.

    A *linear* (zero-padded, never circular) convolution of fixed signals ``x`` (along the last
    axis, zero before ``t = 0``) with any number of weight vectors, cut to the length ``N`` of
    ``x``. Long signals are transformed once (real FFT of size at least ``N + L - 1``) and each
    weight vector then costs one forward and one inverse transform; short signals and short
    memories use shifted sums. :meth:`at` evaluates a few consecutive samples only, by sums of
    products that stay out of the (multithreaded) BLAS path, for recursions that rebuild the
    latest samples at every step.

    Parameters
    ----------
    x : ndarray, shape (..., N)
        Signals, float64. Not copied; do not modify them while the object is in use.
    memory : int, optional
        Longest weight vector that will be used (default ``N``: full memory).
    """

    def __init__(self, x, memory=None):
        self.x = x
        self.n = x.shape[-1]
        self.memory = self.n if memory is None else min(int(memory), self.n)
        self.direct = _use_direct(self.n, self.memory)
        self._spectrum = None

    def nfft(self):
        """The FFT size of the transformed signals (at least ``N + memory - 1``)."""
        return scipy.fft.next_fast_len(self.n + self.memory - 1, real=True)

    def __call__(self, weights, *, weights_spectrum=None):
        """Convolve with ``weights`` (at most ``memory`` of them); shape of ``x``."""
        if self.direct:
            return _direct(self.x, weights)
        nfft = self.nfft()
        if self._spectrum is None:
            self._spectrum = scipy.fft.rfft(self.x, n=nfft, axis=-1)
        if weights_spectrum is None:
            weights_spectrum = scipy.fft.rfft(weights, n=nfft)
        return scipy.fft.irfft(self._spectrum * weights_spectrum, n=nfft, axis=-1)[..., :self.n]

    def at(self, weights, t_lo, t_hi):
        """Samples ``t_lo..t_hi`` of the convolution (:func:`convolution_at`)."""
        return convolution_at(self.x, weights, t_lo, t_hi)


def convolution_at(x, weights, t_lo, t_hi):
    """Samples ``t_lo..t_hi`` (inclusive) of :class:`CausalConvolution` of ``x`` and ``weights``.

    ``x`` needs samples ``0..t_hi`` along its last axis and ``weights`` at least ``t_hi + 1``
    entries; samples with ``t < 0`` are zero. Each sample is one sum of products over the whole
    past (``np.einsum``, never BLAS), so a recursion that rebuilds its latest samples at every
    step runs at the same speed whatever the machine's BLAS threading.
    """
    out = np.zeros(x.shape[:-1] + (t_hi - t_lo + 1,))
    w_rev = np.ascontiguousarray(weights[:t_hi + 1][::-1])   # contiguous: SIMD sums
    for t in range(max(t_lo, 0), t_hi + 1):
        out[..., t - t_lo] = np.einsum("...j,j->...", x[..., :t + 1], w_rev[t_hi - t:])
    return out


def causal_convolve(x, weights):
    """``sum_{j=0}^{t} weights[j] x[..., t - j]`` along the last axis, cut to ``x.shape[-1]``."""
    return CausalConvolution(x, memory=weights.shape[0])(weights)


def divide_and_conquer(n, leaf_size, leaf, merge):
    """Call ``leaf(lo, hi)`` on consecutive segments of ``[0, n)`` and ``merge`` between them.

    ``solve(lo, hi)``: a segment of at most ``leaf_size`` samples is a leaf; a longer one is
    split at ``mid = (lo + hi) // 2``: ``solve(lo, mid)``, ``merge(lo, mid, hi)``,
    ``solve(mid, hi)``. Segments of one level differ in length by at most one sample.
    """
    def solve(lo, hi):
        if hi - lo <= leaf_size:
            leaf(lo, hi)
            return
        mid = (lo + hi) // 2
        solve(lo, mid)
        merge(lo, mid, hi)
        solve(mid, hi)

    if n > 0:
        solve(0, n)


class HalfMerge:
    """Add ``sum_{m in [lo, mid)} w_a[t - m] z[s_a, m]`` to ``dz[a, t]`` for ``t in [mid, hi)``.

    The merge step of :func:`divide_and_conquer` for any number of accumulators ``a``, each
    the convolution of one signal ``s_a`` with one weight vector ``w_a`` (time on axis 1 of
    ``z`` and ``dz``; further axes are carried along).

    Parameters
    ----------
    weights : sequence of ndarray, shape (n,)
        The distinct weight vectors (full length).
    pairs : sequence of (int, int, int)
        ``(accumulator, signal, weight index)`` for every accumulator that has memory.

    Notes
    -----
    The outputs needed, ``t - lo in [mid - lo, hi - lo)``, see weights ``w[1 .. hi - lo - 1]``
    only, so a circular convolution of any size ``nfft >= hi - lo`` gives them without
    wrap-around: ``z[lo:mid]`` zero-padded to ``nfft`` and ``w[:nfft]`` (whose entries beyond
    ``hi - lo`` reach only outputs past ``hi``). One FFT size ``next_fast_len(hi - lo)`` thus
    serves every segment of a level (their lengths differ by at most one), half the size of a
    full linear convolution, and the weights' spectra are computed once per FFT size and kept
    for the call. Each merge then costs one real FFT per signal and one inverse per accumulator.
    """

    def __init__(self, weights, pairs):
        self.weights = [np.asarray(w, dtype=np.float64) for w in weights]
        self.pairs = [(int(a), int(s), int(k)) for a, s, k in pairs]
        self.signals = sorted({s for _, s, _ in self.pairs})
        self._spectra = {}

    def spectra(self, nfft):
        """The rfft of every weight vector cut to ``nfft``, shape ``(n_weights, nfft // 2 + 1)``."""
        spec = self._spectra.get(nfft)
        if spec is None:
            stack = np.zeros((len(self.weights), nfft))
            for i, w in enumerate(self.weights):
                m = min(nfft, w.shape[0])
                stack[i, :m] = w[:m]
            spec = self._spectra[nfft] = scipy.fft.rfft(stack, axis=1)
        return spec

    def __call__(self, z, dz, lo, mid, hi):
        """``dz[a, mid:hi] +=`` the contribution of ``z[s_a, lo:mid]`` (in place)."""
        if not self.pairs:
            return
        nfft = scipy.fft.next_fast_len(hi - lo, real=True)
        spec = self.spectra(nfft)
        extra = (1,) * (z.ndim - 2)            # the weights act along time only
        zf = {s: scipy.fft.rfft(z[s, lo:mid], n=nfft, axis=0) for s in self.signals}
        for a, s, k in self.pairs:
            prod = zf[s] * spec[k].reshape(spec.shape[1:] + extra)
            dz[a, mid:hi] += scipy.fft.irfft(prod, n=nfft, axis=0,
                                             overwrite_x=True)[mid - lo:hi - lo]


# Blocks of this length are solved by a dense triangular Toeplitz inverse (256 from 2^16 samples
# on: 1.3 s against 2.1 s at 1e6 samples; 128 below: 8 ms against 22 ms at 1e4).
LEAF = 128
LEAF_LONG = 256


def causal_product(a, b, n=None):
    """First ``n`` coefficients of the product of two power series (a causal convolution).

    :func:`causal_convolve` of ``b`` (zero-padded or cut to ``n``) with the weights ``a``.

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
    >>> from fohw.model.kernels import causal_product
    >>> causal_product([1.0, 1.0], [1.0, 2.0, 3.0], 3)
    array([1., 3., 5.])
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = a.shape[0] if n is None else int(n)
    a = a[:n]
    x = np.zeros(n)
    x[:min(n, b.shape[0])] = b[:n]
    if a.shape[0] == 0:
        return x * 0.0
    return causal_convolve(x, a)


def _leaf_inverse(c, size):
    """Lower-triangular Toeplitz matrix of the first ``size`` terms of ``1/C`` (literal recursion)."""
    r = np.zeros(size)
    r[0] = 1.0 / c[0]
    for k in range(1, size):
        m = min(k, c.shape[0] - 1)
        r[k] = -np.dot(c[1:m + 1], r[k - m:k][::-1]) / c[0]
    idx = np.subtract.outer(np.arange(size), np.arange(size))
    return np.where(idx >= 0, r[np.clip(idx, 0, None)], 0.0)


def series_divide(f, c, *, leaf=None):
    """Solve ``sum_{j=0}^{k} c[j] y[k-j] = f[k]``, ``k = 0..N-1``: the first ``N`` terms of ``F / C``.

    Parameters
    ----------
    f : array_like, shape (N,)
        Right-hand side (the forcing).
    c : array_like, shape (>= 1,)
        The recursion's weights, ``c[0] != 0``; entries beyond ``N`` are ignored and missing
        ones are zero.
    leaf : int, optional
        Longest block solved directly (by the triangular Toeplitz inverse of its first
        ``leaf`` terms); default 128, or 256 from 65536 samples on.

    Returns
    -------
    y : ndarray, shape (N,)

    Notes
    -----
    The online convolution of :func:`divide_and_conquer` and :class:`HalfMerge` (the lagged
    simulator's): the samples ``[lo, hi)`` are split at ``mid``, the first half is solved, the
    contribution of its ``y`` to the second half's equations is added by one FFT product, and
    the second half is solved. Every pair of samples meets at exactly one split, so this is the
    implicit recursion ``y[k] = (f[k] - sum_{j>=1} c[j] y[k-j]) / c[0]`` with its sums
    regrouped, in ``O(N log^2 N)`` operations. (Newton's iteration for ``1/C``,
    ``O(N log N)``, was measured to lose up to 7 digits on a lightly damped second-order system
    sampled finely, against 0 for this scheme; the tests compare every sample with the literal
    ``O(N^2)`` loop.)

    Examples
    --------
    >>> from fohw.model.kernels import series_divide
    >>> series_divide([1.0, 1.0, 1.0], [2.0, -1.0])    # y[k] = (1 + y[k-1]) / 2
    array([0.5  , 0.75 , 0.875])
    """
    g = np.array(f, dtype=np.float64)
    n = g.shape[0]
    c = np.asarray(c, dtype=np.float64)[:n]
    if c.shape[0] == 0 or c[0] == 0.0:
        raise ZeroDivisionError("the recursion's weight c[0] is zero: the implicit step is singular")
    c = np.concatenate([c, np.zeros(n - c.shape[0])])
    y = np.zeros((1, n))
    past = np.zeros((1, n))              # sum_{j >= 1} c[j] y[k - j] over the finished samples
    if leaf is None:
        leaf = LEAF_LONG if n >= 65536 else LEAF
    size = max(1, min(int(leaf), n))
    inverse = _leaf_inverse(c[:size], size)
    merge = HalfMerge([c], [(0, 0, 0)])

    def solve(lo, hi):                   # the block's own samples, its past already in `past`
        y[0, lo:hi] = inverse[:hi - lo, :hi - lo] @ (g[lo:hi] - past[0, lo:hi])

    divide_and_conquer(n, size, solve, lambda lo, mid, hi: merge(y, past, lo, mid, hi))
    return y[0]


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
        ``sum_{j=0}^{k} c[j] r[k-j] = 1`` for ``k = 0`` and ``0`` for ``0 < k < n``
        (:func:`series_divide` of a unit impulse).

    Examples
    --------
    >>> from fohw.model.kernels import series_reciprocal
    >>> series_reciprocal([1.0, -0.5], 4)          # 1 / (1 - x/2) = sum (x/2)^k
    array([1.   , 0.5  , 0.25 , 0.125])
    """
    c = np.asarray(c, dtype=np.float64)
    n = c.shape[0] if n is None else int(n)
    return series_divide(np.eye(1, n)[0], c)
