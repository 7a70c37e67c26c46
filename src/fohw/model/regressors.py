"""The information matrix of fractional differences (paper Eqs. 19–20, 25, 34–38; SPEC §4).

Row ``k`` of the information matrix is

``phi[k] = [psi_1[k], …, psi_nq[k], zeta_1[k], …, zeta_np[k]]`` with
``psi_j[k] = [(Δ^α g_j(y))[k-1], …, (Δ^α g_j(y))[k-na]]`` and
``zeta_j[k] = [(Δ^α f_j(u))[k-1], …, (Δ^α f_j(u))[k-nb]]``, zero before ``k = 0``,

so that ``y = Phi @ theta + v`` for a simulated record.
"""

from __future__ import annotations

import numpy as np

from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import DimensionError
from .basis import as_basis
from .gl import CausalConvolution, convolution_at, gl_weights, gl_weights_derivative
from .params import ThetaLayout

__all__ = ["information_matrix", "RegressorBuilder", "WindowKernel"]


class WindowKernel:
    """Exact information-vector rows of a window, from the basis signals up to the present.

    Parameters
    ----------
    lags : sequence of int
        Number of lags of each stacked basis signal (``na`` for the g-signals, ``nb`` for the
        f-signals).
    """

    def __init__(self, lags):
        self.lags = list(lags)
        self.max_lag = max(self.lags)
        self.n_params = sum(self.lags)
        self._sig_idx = np.repeat(np.arange(len(self.lags)), self.lags)
        self._lag_idx = np.concatenate([np.arange(1, m + 1) for m in self.lags])

    def rows(self, signals, k, innovation_length, weights):
        """Rows ``phi[k], …, phi[k-P+1]`` (index >= 0) for each weight vector.

        ``signals[:, t]`` holds the basis signals at time ``t``, for at least ``t = 0..k-1``;
        each weight vector has at least ``k`` entries. The GL sums are evaluated by
        :func:`fohw.model.gl.convolution_at` (the whole past, no FFT).
        """
        n_rows = min(innovation_length, k + 1)
        if k == 0:
            return [np.zeros((1, self.n_params)) for _ in weights]
        rows = np.arange(k, k - n_rows, -1)
        t_lo = k - n_rows + 1 - self.max_lag          # earliest time a row needs
        index = (self._sig_idx[None, :], rows[:, None] - self._lag_idx[None, :] - t_lo)
        return [convolution_at(signals, w, t_lo, k - 1)[index] for w in weights]


class RegressorBuilder:
    """Information matrices of one record for many fractional orders.

    The basis signals ``g_j(y)``, ``f_j(u)`` and their FFTs are computed once; each
    :meth:`matrix` call then costs one inverse FFT of the stacked signals. This is what
    alpha searches and sensitivities use.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records, same length, finite.
    na, nb : int
        Output and input lag orders (``>= 1``); ``N`` must exceed both.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> rng = np.random.default_rng(0)
    >>> u, y = rng.uniform(-1, 1, 200), rng.uniform(-1, 1, 200)
    >>> builder = fohw.RegressorBuilder(u, y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> builder.matrix(0.6).shape
    (200, 10)
    """

    def __init__(self, u, y, *, na, nb, f_basis, g_basis):
        u = check_array(u, "u")
        y = check_array(y, "y")
        check_same_length(u, y, "u", "y")
        na = check_int(na, "na", minimum=1)
        nb = check_int(nb, "nb", minimum=1)
        self.f_basis = as_basis(f_basis, "f_basis")
        self.g_basis = as_basis(g_basis, "g_basis")
        n = y.shape[0]
        if n <= max(na, nb):
            raise DimensionError(f"the record must be longer than the lags: got {n} samples for "
                                 f"na={na}, nb={nb} (need at least {max(na, nb) + 1}).")
        self.layout = ThetaLayout(na=na, nb=nb, n_g=len(self.g_basis), n_f=len(self.f_basis))
        self.n_samples = n
        self.u, self.y = u, y
        # Stacked basis signals: g_1(y), …, g_nq(y), f_1(u), …, f_np(u).
        self.signals = np.vstack([self.g_basis.evaluate(y, "y"), self.f_basis.evaluate(u, "u")])
        self._lags = [na] * len(self.g_basis) + [nb] * len(self.f_basis)
        self._convolution = CausalConvolution(self.signals)
        self._window_kernel = WindowKernel(self._lags)

    def differences(self, alpha, *, derivative=False):
        """GL differences of all basis signals, shape ``(n_g + n_f, N)``.

        With ``derivative=True``, their exact derivative with respect to ``alpha``
        (convolution with :func:`fohw.gl_weights_derivative`).
        """
        alpha = check_scalar(alpha, "alpha")
        n = self.n_samples
        w = gl_weights_derivative(alpha, n) if derivative else gl_weights(alpha, n)
        return self._convolution(w)

    def window(self, k, innovation_length, weights):
        """Rows ``phi[k], phi[k-1], …, phi[k-P+1]`` (those with index >= 0), for given weights.

        Each row is computed exactly from the full history (no FFT), so this is what a
        recursion whose fractional order changes at every sample uses.

        Parameters
        ----------
        k : int
            Current sample, ``0 <= k < N``.
        innovation_length : int
            ``P``.
        weights : sequence of ndarray
            GL weight vectors (e.g. for ``alpha`` and ``alpha + delta``), each of length at
            least ``k``.

        Returns
        -------
        rows : list of ndarray, each of shape (min(P, k + 1), n)
            One window per weight vector.
        """
        return self._window_kernel.rows(self.signals, k, innovation_length, weights)

    def lag(self, differences):
        """Arrange stacked differences into the ``(N, n)`` matrix of lagged columns."""
        n = self.n_samples
        phi = np.zeros((n, self.layout.n_params))
        col = 0
        for row, lags in zip(differences, self._lags):
            for i in range(1, lags + 1):
                phi[i:, col] = row[: n - i]
                col += 1
        return phi

    def matrix(self, alpha):
        """Information matrix ``Phi(alpha)``, shape ``(N, n)``, rows ``phi[k]``."""
        return self.lag(self.differences(alpha))

    def matrix_derivative(self, alpha):
        """Exact ``d Phi / d alpha``, shape ``(N, n)``."""
        return self.lag(self.differences(alpha, derivative=True))

    def jacobian(self, theta, alpha):
        """Jacobian ``G = [Phi(alpha), dPhi/dalpha @ theta]`` of the one-step predictor.

        The derivative of ``yhat = Phi(alpha) theta`` with respect to ``(theta, alpha)``, built
        in one ``N x (n + 1)`` array; the estimators' Gauss–Newton steps, their covariances and
        the Cramér–Rao bound all use it.

        Returns
        -------
        G : ndarray, shape (N, n + 1)
        """
        theta = self.layout.check_theta(theta)
        n = theta.shape[0]
        G = np.empty((self.n_samples, n + 1))
        G[:, :n] = self.matrix(alpha)
        G[:, n] = self.matrix_derivative(alpha) @ theta
        return G


def information_matrix(u, y, alpha, *, na, nb, f_basis, g_basis):
    """Information matrix of a fractional-order Hammerstein–Wiener record.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output, same length, finite, zero before ``k = 0``.
    alpha : float
        Fractional order (any finite real).
    na, nb : int
        Output and input lag orders, ``1 <= na, nb < N``.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree).

    Returns
    -------
    Phi : ndarray, shape (N, n)
        Row ``k`` is ``phi[k]`` of Eq. (20) in SPEC §4 order, ``n = n_g*na + n_f*nb``;
        entries that would need samples before ``k = 0`` are zero.

    Notes
    -----
    Eqs. (19)–(20) and (34)–(38). All basis signals are differenced in one batched GL call.
    For a record simulated by :func:`fohw.simulate`, ``y - Phi @ model.theta`` equals the
    noise to rounding error.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> model = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
    >>> u = np.random.default_rng(1).uniform(-1, 1, 500)
    >>> y = fohw.simulate(model, u)
    >>> Phi = fohw.information_matrix(u, y, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
    >>> bool(np.max(np.abs(y - Phi @ model.theta)) < 1e-12)
    True
    """
    return RegressorBuilder(u, y, na=na, nb=nb, f_basis=f_basis, g_basis=g_basis).matrix(alpha)
