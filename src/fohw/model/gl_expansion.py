"""Grünwald–Letnikov weights expanded in the order (paper Eqs. 3–5, for the recursions of Table 1).

The paper's recursive methods (Table 1; the single-innovation baselines of Fig. 6; MI-RLS) change
``alpha`` at every sample, and the window ``Phi(P, k)`` at the new order needs the full memory:
rebuilt directly it costs ``O(k)`` per sample, ``O(N^2)`` per pass. This module removes the
dependence on ``alpha`` from the convolutions.

Each weight ``beta_j(alpha) = prod_{i=1}^{j} (i - 1 - alpha) / i`` is a polynomial of degree ``j``
in ``alpha``. On an interval ``[lo, hi]`` of orders it is replaced by its Chebyshev interpolant of
one degree ``n`` for every ``j``:

.. math:: \\beta_j(\\alpha) \\approx \\tilde\\beta_j(\\alpha) = \\sum_{m=0}^{n} c_{jm}\\, T_m(\\tau),
   \\qquad \\tau = \\frac{2\\alpha - lo - hi}{hi - lo},

so that ``D(alpha) = sum_m T_m(tau) D_m`` with the ``n + 1`` fixed convolutions
``D_m[t] = sum_j c_{jm} x[t - j]``, computed once by FFT (``O(n N log N)``); each sample of the
recursion then costs ``O(n)`` per signal and lag. The derivative with respect to ``alpha`` is the
derivative of the same series.

Error bound (proven, evaluated for each interval and record length)
    ``beta_j`` is entire. On the Bernstein ellipse ``E_rho`` of ``[lo, hi]`` (foci ``lo``, ``hi``,
    semi-axes ``w (rho ± 1/rho) / 2``, ``w = (hi - lo) / 2``, centre ``c``) each factor satisfies
    ``max |i - 1 - z| = |c - (i - 1)| + w (rho + 1/rho) / 2`` (the farthest point of an ellipse
    from a point of its major axis is a vertex), so ``|beta_j| <= K_j(rho) = prod_i (|c - i + 1| +
    w (rho + 1/rho) / 2) / i`` there. The Chebyshev interpolant of degree ``n`` in the
    Chebyshev points of the second kind then errs by at most ``4 K_j rho^-n / (rho - 1)``
    (Trefethen, *Approximation Theory and Approximation Practice*, Thm 8.2), and its derivative
    by at most ``4 K_j sum_{m>n} m^2 rho^-m / w`` (from ``|a_m| <= 2 K_j rho^-m``, Thm 8.1,
    aliasing and ``|T_m'| <= m^2``). Interpolation is exact for ``j <= n``. Hence for every
    signal ``x`` and every ``t``

    ``|D~(alpha)[t] - D(alpha)[t]| <= max|x| * min_rho 4 (sum_{j<N} K_j(rho)) rho^-n / (rho - 1)``,

    the number :attr:`GLExpansion.error_bound`. The degree is the smallest one (even, at least
    8) whose bound is at most ``tol`` (default ``1e-16``, below the rounding of one FFT
    convolution): for ``[0, 1.001]`` it is 24 at ``N = 10**4``, 26 at ``10**5`` and 28 at
    ``10**6``. The bound is on the interpolant itself; the computed coefficients add the
    rounding of the weights at the nodes and of the cosine transform (measured: ``sum_j
    |beta~_j - beta_j| <= 2e-15`` on ``[0, 1.001]`` at ``N = 10**5``, where ``sum_j |beta_j|``
    is 2).
"""

from __future__ import annotations

import math

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_int, check_scalar
from ..exceptions import ParameterError
from .gl import gl_weights_unchecked

__all__ = ["GLExpansion", "ExpandedWindows", "StreamedWindows"]

_RHOS = np.geomspace(1.25, 400.0, 48)     # ellipse parameters tried in the bound
_MAX_DEGREE = 96


class GLExpansion:
    """Chebyshev interpolant in ``alpha`` of the first ``n_weights`` GL weights on ``[lo, hi]``.

    Parameters
    ----------
    lo, hi : float
        Interval of orders, ``lo < hi``; the series is evaluated on it only.
    n_weights : int
        Number of weights ``beta_0 … beta_{n_weights - 1}`` (the record length).
    tol : float, optional
        Largest admissible :attr:`error_bound` (default ``1e-16``).
    degree : int, optional
        Use this degree instead of the smallest one that meets ``tol``.

    Attributes
    ----------
    degree : int
        ``n``: ``n + 1`` Chebyshev terms.
    error_bound : float
        Proven bound on ``sum_j |beta~_j(alpha) - beta_j(alpha)|`` over the interval, hence on
        ``|D~ - D| / max|x|`` (module notes).
    derivative_error_bound : float
        The same for ``d beta / d alpha``.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> from fohw.model.gl_expansion import GLExpansion
    >>> ex = GLExpansion(0.0, 1.0, 1000)
    >>> ex.degree, ex.error_bound <= 1e-16
    (22, True)
    >>> err = np.max(np.abs(ex.weights(0.6) - fohw.gl_weights(0.6, 1000)))
    >>> # the proven bound, plus rounding of a sum of degree + 1 terms of size <= 1
    >>> bool(err <= ex.error_bound + (ex.degree + 1) * np.finfo(float).eps)
    True
    """

    def __init__(self, lo, hi, n_weights, *, tol=1e-16, degree=None):
        lo = check_scalar(lo, "lo")
        hi = check_scalar(hi, "hi")
        if not lo < hi:
            raise ParameterError(f"`lo` must be below `hi`; got lo={lo!r}, hi={hi!r}.")
        self.lo, self.hi = lo, hi
        self.n_weights = check_int(n_weights, "n_weights", minimum=1)
        tol = check_scalar(tol, "tol", lower=0.0, lower_inclusive=False)
        log_k = self._log_weight_sums()
        if degree is None:
            for n in range(8, _MAX_DEGREE + 1, 2):
                if self._bound(log_k, n) <= tol:
                    break
            else:
                raise ParameterError(f"no degree up to {_MAX_DEGREE} meets `tol` = {tol:g} on "
                                     f"[{lo:g}, {hi:g}] for {self.n_weights} weights; got a bound "
                                     f"of {self._bound(log_k, _MAX_DEGREE):.3g}.")
            self.degree = n
        else:
            self.degree = check_int(degree, "degree", minimum=1, maximum=_MAX_DEGREE)
        self.error_bound = self._bound(log_k, self.degree)
        self.derivative_error_bound = self._bound(log_k, self.degree, derivative=True)
        self._m = np.arange(self.degree + 1, dtype=np.float64)
        self._angles = np.empty((2, 1))
        self._coefficients = None

    # ---- the bound ------------------------------------------------------------------------------
    def _log_weight_sums(self):
        """``log sum_{j<N} K_j(rho)`` for each ``rho`` of the grid (module notes)."""
        c, w = 0.5 * (self.lo + self.hi), 0.5 * (self.hi - self.lo)
        i = np.arange(1, self.n_weights, dtype=np.float64)
        log_i = np.log(i)
        out = np.empty(_RHOS.shape[0])
        for r, rho in enumerate(_RHOS):
            a = 0.5 * w * (rho + 1.0 / rho)
            log_k = np.cumsum(np.log(np.abs(c - (i - 1.0)) + a) - log_i)   # j = 1..N-1
            top = max(float(log_k.max()), 0.0) if log_k.size else 0.0
            out[r] = top + math.log(math.exp(-top) + float(np.exp(log_k - top).sum()))
        return out

    def _bound(self, log_k, n, derivative=False):
        """``min_rho`` of the interpolation bound of degree ``n`` (module notes)."""
        if n + 1 >= self.n_weights:
            return 0.0                     # every weight is a polynomial of degree <= n
        log_rho = np.log(_RHOS)
        if derivative:
            m = np.arange(n + 1, n + 2001, dtype=np.float64)[:, None]
            tail = np.log(np.sum(m * m * np.exp(-(m - n - 1) * log_rho[None, :]), axis=0))
            log_b = math.log(4.0) + log_k + tail - (n + 1) * log_rho \
                - math.log(0.5 * (self.hi - self.lo))
        else:
            log_b = math.log(4.0) + log_k - n * log_rho - np.log(_RHOS - 1.0)
        return float(np.exp(np.min(log_b)))

    # ---- the series -----------------------------------------------------------------------------
    def nodes(self):
        """The ``degree + 1`` Chebyshev points of the second kind, as orders in ``[lo, hi]``."""
        tau = np.cos(np.pi * np.arange(self.degree + 1) / self.degree)
        return 0.5 * (self.lo + self.hi) + 0.5 * (self.hi - self.lo) * tau

    def coefficients(self):
        """``c[m, j]``, shape ``(degree + 1, n_weights)``: ``beta_j = sum_m c[m, j] T_m(tau)``."""
        if self._coefficients is None:
            n = self.degree
            values = np.array([gl_weights_unchecked(a, self.n_weights) for a in self.nodes()])
            c = scipy.fft.dct(values, type=1, axis=0, overwrite_x=True) / n
            c[0] *= 0.5
            c[n] *= 0.5
            self._coefficients = c
        return self._coefficients

    def _tau(self, alpha, name="alpha"):
        alpha = float(alpha)
        if not self.lo <= alpha <= self.hi:
            raise ParameterError(f"`{name}` must be in the expansion interval [{self.lo!r}, "
                                 f"{self.hi!r}]; got {alpha!r}.")
        return min(1.0, max(-1.0, (2.0 * alpha - self.lo - self.hi) / (self.hi - self.lo)))

    def basis(self, alpha):
        """``T_m(tau(alpha))``, ``m = 0..degree``: ``beta~(alpha) = basis(alpha) @ c``."""
        return np.cos(self._m * math.acos(self._tau(alpha)))

    def basis_derivative(self, alpha):
        """``d T_m(tau(alpha)) / d alpha``: ``d beta~ / d alpha = basis_derivative(alpha) @ c``."""
        tau = self._tau(alpha)
        theta = math.acos(tau)
        s = math.sin(theta)
        if s > 1e-4:
            du = self._m * np.sin(self._m * theta) / s
        else:                               # m U_{m-1}(tau) by its recurrence near tau = +-1
            du = np.zeros(self.degree + 1)
            u_prev, u = 0.0, 1.0            # U_{-1}, U_0
            for m in range(1, self.degree + 1):
                du[m] = m * u
                u_prev, u = u, 2.0 * tau * u - u_prev
        return du * (2.0 / (self.hi - self.lo))

    def basis_pair(self, alpha, *, sensitivity="finite_difference", delta_alpha=1e-3, out=None):
        """Rows ``basis(alpha)`` and the basis of the sensitivity weights, shape ``(2, degree + 1)``.

        The second row is ``(basis(alpha + delta_alpha) - basis(alpha)) / delta_alpha`` (Eq. 44)
        for ``sensitivity="finite_difference"`` and :meth:`basis_derivative` for ``"exact"``:
        the expansions of :func:`fohw.estimators.milm.sensitivity_weights`. ``out``, if given,
        receives them (the recursions reuse one array).
        """
        if out is None:
            out = np.empty((2, self.degree + 1))
        if sensitivity == "exact":
            out[0] = self.basis(alpha)
            out[1] = self.basis_derivative(alpha)
            return out
        angles = self._angles
        angles[0, 0] = math.acos(self._tau(alpha))
        angles[1, 0] = math.acos(self._tau(alpha + delta_alpha, "alpha + delta_alpha"))
        np.cos(np.multiply(self._m, angles, out=out), out=out)
        np.subtract(out[1], out[0], out=out[1])
        out[1] *= 1.0 / delta_alpha
        return out

    def weights(self, alpha):
        """``beta~_j(alpha)``, ``j < n_weights`` (for checks; the recursions use :meth:`basis`)."""
        return self.basis(alpha) @ self.coefficients()

    def weights_derivative(self, alpha):
        """``d beta~_j / d alpha``, ``j < n_weights``."""
        return self.basis_derivative(alpha) @ self.coefficients()


class ExpandedWindows:
    """Rows ``phi[k], …, phi[k-P+1]`` of a record at any order of an expansion's interval.

    The drop-in for :meth:`fohw.model.lagged.regressors.WindowKernel.rows` in the recursions: the
    fixed convolutions ``D_m`` of the stacked basis signals with the expansion's coefficient
    vectors are computed by FFT once (in blocks of time, see ``max_bytes``), and a window is a
    sum over ``m`` of ``degree + 1`` terms. Samples must be asked for in increasing ``k``.

    Parameters
    ----------
    signals : ndarray, shape (S, N)
        Stacked basis signals, zero before ``t = 0``.
    lags : sequence of int
        Lags of each signal (``na`` for the g-signals, ``nb`` for the f-signals).
    expansion : GLExpansion
        With ``n_weights >= N``.
    innovation_length : int
        ``P``.
    max_bytes : int, optional
        Memory for one block of ``D_m`` (default 256 MB); longer records are done in blocks
        whose FFTs cover the past up to the block's end (about ``(blocks + 1) / 2`` times the
        work of one block).
    """

    def __init__(self, signals, lags, expansion, innovation_length, *, max_bytes=2**28):
        self.signals = signals
        self.n_signals, self.n = signals.shape
        self.expansion = expansion
        self.lags = list(lags)
        self.P = int(innovation_length)
        # times one window needs, and the flat gather index of each row count's rows
        self.width, self._index = _window_index(self.lags, self.P)
        terms = expansion.degree + 1
        per_time = self.n_signals * terms * 8
        self.block = max(int(max_bytes) // per_time - self.width, 64)
        self._t0 = self._t1 = None
        self._D = None

    def _compute_block(self, t_start):
        """``D_m`` for times ``t_start - width .. t_start + block - 1`` (zeros before 0)."""
        t0 = t_start - self.width
        t1 = min(t_start + self.block, self.n)
        c = self.expansion.coefficients()
        terms = c.shape[0]
        D = np.zeros((t1 - t0, self.n_signals, terms))
        lo = max(t0, 0)
        if t1 > lo:
            # Outputs lo..t1-1 of the linear convolution of x[:t1] and c[:, :t1], clean for a
            # circular transform of size >= 2 t1 - 1 - lo.
            nfft = scipy.fft.next_fast_len(2 * t1 - 1 - lo, real=True)
            X = scipy.fft.rfft(self.signals[:, :t1], n=nfft, axis=-1)
            for m in range(terms):
                Cm = scipy.fft.rfft(c[m, :t1], n=nfft)
                D[lo - t0:, :, m] = scipy.fft.irfft(X * Cm, n=nfft, axis=-1)[:, lo:t1].T
        self._t0, self._t1 = t0, t1
        self._D = D.reshape((t1 - t0) * self.n_signals, terms)

    def rows(self, k, vectors):
        """Rows ``phi[k], …`` (``min(P, k + 1)`` of them) for two vectors of ``T_m`` values.

        ``vectors``, shape ``(2, degree + 1)``: e.g. :meth:`GLExpansion.basis_pair`, the
        expansions of the weights and of the sensitivity weights. Returns an array of shape
        ``(2, min(P, k + 1), n)``: the window and its sensitivity.
        """
        if self._D is None or not self._t0 + self.width <= k <= self._t1:
            self._compute_block(k)
        S = self.n_signals
        win = self._D[(k - self.width - self._t0) * S:(k - self._t0) * S]
        return np.dot(vectors, win.T).ravel()[self._index[min(self.P, k + 1) - 1]]


def _window_index(lags, innovation_length):
    """The window width and the flat gather index of the window rows, per row count.

    Row ``r`` (``phi[k - r]``) needs time ``k - r - lag``, at position
    ``width - 1 - (r + lag - 1)`` of the window ending at ``k - 1``. The product of two weight
    rows with the window is ``(2, width * S)``; the index gathers both rows' ``(n_rows, n)``
    blocks from it in one flat take.
    """
    n_signals = len(lags)
    width = innovation_length + max(lags) - 1
    sig_idx = np.repeat(np.arange(n_signals), lags)
    lag_idx = np.concatenate([np.arange(1, m + 1) for m in lags])
    size = width * n_signals
    out = []
    for n_rows in range(1, innovation_length + 1):
        r = np.arange(n_rows)[:, None]
        one = (width - r - lag_idx[None, :]) * n_signals + sig_idx[None, :]
        out.append(np.stack([one, one + size]))
    return width, out


class StreamedWindows:
    """:class:`ExpandedWindows` for signals that arrive in chunks (MI-RLS ``partial_fit``).

    ``D_m[t] = sum_j c[m, j] x[t - j]`` is built sample by sample as the signals arrive, by a
    partitioned convolution whose grid is fixed in absolute time: the first ``leaf`` weights
    directly at each sample, the weights ``[L, 2L)`` (``L = leaf * 2**l``) by one FFT per
    output block ``[b, b + L)`` (``b`` a multiple of ``L``) as soon as ``x[b - 1]`` is known.
    Every ``D_m[t]`` is therefore computed by the same operations in the same order however the
    record is cut into chunks: streaming gives exactly the numbers of one pass. The
    coefficients are formed by an explicit cosine sum, one weight at a time, for the same
    reason. Cost ``O(M N log^2 N)``; memory ``8 M S N`` bytes (``M = degree + 1``).

    Parameters
    ----------
    lags : sequence of int
        Lags of each stacked signal.
    lo, hi : float
        Interval of orders.
    innovation_length : int
        ``P``.
    leaf : int, optional
        Weights applied directly (default 64; a power of two).
    """

    def __init__(self, lags, lo, hi, innovation_length, *, leaf=64):
        self.lags = list(lags)
        self.n_signals = len(self.lags)
        self.expansion = _stream_expansion(float(lo), float(hi))
        self.terms = self.expansion.degree + 1
        self.P = int(innovation_length)
        self.width, self._index = _window_index(self.lags, self.P)
        self.leaf = int(leaf)
        self._x = np.zeros((self.n_signals, self.leaf - 1 + 1024))   # leaf - 1 zeros first
        self._n_x = 0
        self._D = np.zeros((self.width + 1024, self.n_signals, self.terms))   # width zeros first
        self._n_done = 0                    # D final for t < _n_done
        self._c = np.zeros((self.terms, 0))
        self._spectra = {}

    def append(self, x):
        """Add the next samples of the signals, shape ``(S, m)``."""
        m = x.shape[1]
        need = self.leaf - 1 + self._n_x + m
        if need > self._x.shape[1]:
            grown = np.zeros((self.n_signals, max(need, 2 * self._x.shape[1])))
            grown[:, :self._x.shape[1]] = self._x
            self._x = grown
        self._x[:, self.leaf - 1 + self._n_x:need] = x
        self._n_x += m

    def _coefficients(self, n):
        """``c[:, :n]``, each column by the same explicit sum whatever ``n`` (see above)."""
        have = self._c.shape[1]
        if n <= have:
            return self._c
        n = max(n, 2 * have)
        deg = self.expansion.degree
        nodes = self.expansion.nodes()
        values = np.array([gl_weights_unchecked(a, n) for a in nodes])
        k = np.arange(deg + 1)
        c = np.zeros((deg + 1, n))
        for m in range(deg + 1):
            w = np.cos(np.pi * m * k / deg) * (2.0 / deg)
            w[0] *= 0.5
            w[deg] *= 0.5
            if m in (0, deg):
                w *= 0.5
            for j in range(deg + 1):
                c[m] += w[j] * values[j]
        self._c = c
        self._spectra = {}
        self._near = np.ascontiguousarray(c[:, self.leaf - 1::-1])    # reversed first weights
        return c

    def _grow_D(self, t_end):
        need = self.width + t_end
        if need > self._D.shape[0]:
            grown = np.zeros((max(need, 2 * self._D.shape[0]), self.n_signals, self.terms))
            grown[:self._D.shape[0]] = self._D
            self._D = grown

    def _finish(self, t):
        """Make ``D[t]`` final (needs ``x[t]``)."""
        B, S, W = self.leaf, self.n_signals, self.width
        L = B
        while t >= L and t % L == 0:             # output block [t, t + L) of weights [L, 2L)
            c = self._coefficients(2 * L)
            spec = self._spectra.get(L)
            if spec is None:
                spec = self._spectra[L] = scipy.fft.rfft(c[:, L:2 * L], n=2 * L, axis=-1)
            lo = t - 2 * L + 1
            xin = np.zeros((S, 2 * L - 1))
            xin[:, max(-lo, 0):] = self._x[:, B - 1 + max(lo, 0):B - 1 + t]
            X = scipy.fft.rfft(xin, n=2 * L, axis=-1)
            out = scipy.fft.irfft(spec[:, None, :] * X[None, :, :], n=2 * L, axis=-1)
            self._grow_D(t + L)
            self._D[W + t:W + t + L] += out[:, :, L - 1:2 * L - 1].transpose(2, 1, 0)
            L *= 2
        if self._c.shape[1] < B:
            self._coefficients(B)
        if W + t >= self._D.shape[0]:
            self._grow_D(t + 1)
        self._D[W + t] += np.dot(self._x[:, t:t + B], self._near.T)

    def rows(self, k, vectors):
        """Window and sensitivity at sample ``k`` (``x`` known up to ``k - 1`` at least)."""
        while self._n_done < k:
            self._finish(self._n_done)
            self._n_done += 1
        win = self._D[k:k + self.width].reshape(self.width * self.n_signals, self.terms)
        return np.dot(vectors, win.T).ravel()[self._index[min(self.P, k + 1) - 1]]


_STREAM_EXPANSIONS = {}


def _stream_expansion(lo, hi):
    """One expansion per interval: degree with bound <= 1e-17 at 2**17 weights (cached)."""
    key = (lo, hi)
    if key not in _STREAM_EXPANSIONS:
        _STREAM_EXPANSIONS[key] = GLExpansion(lo, hi, 2**17, tol=1e-17)
    return _STREAM_EXPANSIONS[key]
