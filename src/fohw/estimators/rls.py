"""Online identification: multi-innovation recursive least squares with recursive alpha — beyond the paper.

At every sample the window ``Phi(P, k)`` is rebuilt at the current ``alpha`` from the full
memory, with the GL weights expanded in alpha (:class:`fohw.model.gl_expansion.StreamedWindows`:
within a proven bound of the exact window: the degree is chosen so the bound is ``1e-17
max|x|`` for ``2**17`` weights, and it grows slowly with the record (at ``10**6`` samples
4e-17 on ``[0, 1]``, 2.2e-16 on ``[0, 2]``; not bounded beyond), ``O(M N log^2 N)``
per pass instead of ``O(N^2)``, memory about ``8 M S N`` bytes with ``M`` about 30 and ``S``
the number of basis signals: 120 MB at ``N = 10**5`` for the paper's example), and the
extended parameter ``x = [theta, alpha]`` is updated by recursive least squares on the
linearised predictor (a recursive prediction-error / Gauss–Newton method):

``Psi = [Phi(P, k), dPhi(P, k)/dalpha @ theta]``, ``E = Y(P, k) - Phi(P, k) theta``,
``L = S Psi^T (lambda I + Psi S Psi^T)^{-1}``, ``x <- x + L E``, ``S <- (S - L Psi S) / lambda``.

With ``estimate_alpha=False`` it is the multi-innovation RLS of theta for a fixed alpha. The
estimator streams: ``partial_fit`` on consecutive chunks gives exactly the estimates of one
``fit`` on the whole record, since every update uses only the samples seen so far and the
expanded differences are computed on a grid fixed in absolute time, whatever the chunks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._base import BaseEstimator, check_is_fitted
from .._validation import AlphaBounds, check_array, check_int, check_same_length, check_scalar
from ..model.basis import as_basis
from ..model.gl import gl_weights_derivative, gl_weights_unchecked
from ..model.gl_expansion import StreamedWindows
from ..model.params import ThetaLayout
from ..model.regressors import RegressorBuilder, WindowKernel
from ..results import Status
from ._common import finish
from .options import MethodOptions

__all__ = ["MultiInnovationRLS", "RlsOptions"]


class MultiInnovationRLS(BaseEstimator):
    """Multi-innovation recursive least squares with recursive fractional-order tracking.

    Parameters
    ----------
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions.
    innovation_length : int, optional
        ``P`` (default 1: ordinary RLS / recursive prediction error method).
    forgetting : float, optional
        Forgetting factor ``lambda`` in ``(0, 1]`` (default 1: no forgetting).
    alpha0 : float, optional
        Initial fractional order (default 0.5), inside ``alpha_bounds``.
    estimate_alpha : bool, optional
        Track alpha recursively (default True); otherwise alpha stays at ``alpha0``.
    alpha_bounds : (float, float), optional
        Open interval for alpha (default ``(0, 1)``); alpha is clipped ``1e-3`` of its width
        inside it.
    initial_covariance : float, optional
        Initial covariance of theta, ``initial_covariance * I`` (default ``1e6``);
        ``theta(0) = 0``. (Called ``p0`` in fohw 0.1, a name that means ``theta(0) = 1/p0`` in
        the paper's MIGD.)
    initial_alpha_variance : float, optional
        Initial variance of alpha (default 0.1: a standard deviation of about 0.3).

    Attributes
    ----------
    theta_, alpha_ : ndarray, float
        Current estimates.
    theta_history_ : ndarray, shape (N, n)
    alpha_history_ : ndarray, shape (N,)
        ``N`` is ``n_samples_seen_``.
    n_samples_seen_ : int
    covariance_ : ndarray
        The RLS matrix ``S`` (for ``lambda = 1`` and white noise of variance ``s^2``, ``s^2 S``
        approximates the covariance of the estimates).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> whole = fohw.MultiInnovationRLS(2, 2, 2, 3).fit(data.u, data.y)
    >>> chunks = fohw.MultiInnovationRLS(2, 2, 2, 3)
    >>> for i in range(0, 1000, 250):
    ...     _ = chunks.partial_fit(data.u[i:i + 250], data.y[i:i + 250])
    >>> bool(np.array_equal(whole.theta_, chunks.theta_))
    True
    """

    #: Private: rebuild each window from the GL weights (O(N^2), the code before the expansion
    #: in alpha); the tests compare it with the default.
    _reference = False

    _renamed = {"p0": "it is now called `initial_covariance`.",
                "alpha_p0": "it is now called `initial_alpha_variance`."}

    def __init__(self, na, nb, f_basis, g_basis, innovation_length=1, forgetting=1.0, alpha0=0.5,
                 estimate_alpha=True, alpha_bounds=(0.0, 1.0), initial_covariance=1e6,
                 initial_alpha_variance=0.1):
        self.na = na
        self.nb = nb
        self.f_basis = f_basis
        self.g_basis = g_basis
        self.innovation_length = innovation_length
        self.forgetting = forgetting
        self.alpha0 = alpha0
        self.estimate_alpha = estimate_alpha
        self.alpha_bounds = alpha_bounds
        self.initial_covariance = initial_covariance
        self.initial_alpha_variance = initial_alpha_variance

    def _initialise(self):
        self._f = as_basis(self.f_basis, "f_basis")
        self._g = as_basis(self.g_basis, "g_basis")
        na = check_int(self.na, "na", minimum=1)
        nb = check_int(self.nb, "nb", minimum=1)
        self._layout = ThetaLayout(na=na, nb=nb, n_g=len(self._g), n_f=len(self._f))
        self._P = check_int(self.innovation_length, "innovation_length", minimum=1)
        self._lam = check_scalar(self.forgetting, "forgetting", lower=0.0, upper=1.0,
                                 lower_inclusive=False)
        bounds = AlphaBounds(self.alpha_bounds)
        lo, hi = bounds.lo, bounds.hi
        self._inner = bounds.inner
        alpha = check_scalar(self.alpha0, "alpha0", lower=lo, upper=hi, lower_inclusive=False,
                             upper_inclusive=False)
        p0 = check_scalar(self.initial_covariance, "initial_covariance", lower=0.0,
                          lower_inclusive=False)
        ap0 = check_scalar(self.initial_alpha_variance, "initial_alpha_variance", lower=0.0,
                           lower_inclusive=False)
        n = self._layout.n_params
        d = n + 1 if self.estimate_alpha else n
        lags = [na] * len(self._g) + [nb] * len(self._f)
        self._kernel = WindowKernel(lags)
        self._streamed = None if self._reference else StreamedWindows(lags, lo, hi, self._P)
        self._vectors = None if self._reference else np.zeros((2, self._streamed.terms))
        self.layout_ = self._layout
        self._signals = np.zeros((len(self._g) + len(self._f), 1024))
        self._y = np.zeros(1024)
        self._x = np.zeros(d)
        self._x[n:] = alpha
        self._S = np.diag(np.r_[np.full(n, p0), np.full(d - n, ap0)])
        self._theta_hist, self._alpha_hist = [], []
        self.n_samples_seen_ = 0
        self.alpha_at_bound_ = False

    def fit(self, u, y):
        """Forget everything and process the whole record; return ``self``."""
        if hasattr(self, "n_samples_seen_"):
            del self.n_samples_seen_
        return self.partial_fit(u, y)

    def partial_fit(self, u, y):
        """Process the next chunk of a record (continuing from the samples already seen).

        Parameters
        ----------
        u, y : array_like, shape (m,)
            The next ``m >= 1`` samples of input and output.

        Returns
        -------
        self
        """
        u = check_array(u, "u")
        y = check_array(y, "y")
        check_same_length(u, y, "u", "y")
        if not hasattr(self, "n_samples_seen_"):
            self._initialise()
        k0 = self.n_samples_seen_
        m = y.shape[0]
        need = k0 + m
        if need > self._signals.shape[1]:
            grown = np.zeros((self._signals.shape[0], max(need, 2 * self._signals.shape[1])))
            grown[:, :self._signals.shape[1]] = self._signals
            self._signals = grown
            ygrown = np.zeros(grown.shape[1])
            ygrown[:self._y.shape[0]] = self._y
            self._y = ygrown
        self._signals[:, k0:k0 + m] = np.vstack(
            [self._g.evaluate(y, "y"), self._f.evaluate(u, "u")])
        self._y[k0:k0 + m] = y
        if self._streamed is not None:
            self._streamed.append(self._signals[:, k0:k0 + m])
        n = self._layout.n_params
        for k in range(k0, k0 + m):
            self._update(k, n)
        self.n_samples_seen_ = k0 + m
        self.theta_ = self._x[:n].copy()
        self.alpha_ = float(self._x[n]) if self.estimate_alpha else float(self.alpha0)
        self.theta_history_ = np.array(self._theta_hist)
        self.alpha_history_ = np.array(self._alpha_hist)
        self.covariance_ = self._S.copy()
        return self

    def _update(self, k, n):
        x, S, lam = self._x, self._S, self._lam
        theta = x[:n]
        alpha = float(x[n]) if self.estimate_alpha else float(self.alpha0)
        if self._streamed is None:             # the reference: each window from the weights
            length = max(k, 1)
            weights = [gl_weights_unchecked(alpha, length)]
            if self.estimate_alpha:
                weights.append(gl_weights_derivative(alpha, length))
            wins = self._kernel.rows(self._signals, k, self._P, weights)
        else:
            v = self._vectors
            v[0] = self._streamed.expansion.basis(alpha)
            if self.estimate_alpha:
                v[1] = self._streamed.expansion.basis_derivative(alpha)
            wins = self._streamed.rows(k, v)
        phi = wins[0]
        rows = phi.shape[0]
        yw = self._y[k - rows + 1:k + 1][::-1]
        innov = yw - phi @ theta
        psi = np.hstack([phi, (wins[1] @ theta)[:, None]]) if self.estimate_alpha else phi
        sp = S @ psi.T
        gain = np.linalg.solve(lam * np.eye(rows) + psi @ sp, sp.T).T
        x = x + gain @ innov
        S = (S - gain @ sp.T) / lam
        self._S = 0.5 * (S + S.T)
        if self.estimate_alpha:
            a = float(np.clip(x[n], *self._inner))
            if a != x[n]:
                self.alpha_at_bound_ = True
                x[n] = a
        self._x = x
        self._theta_hist.append(x[:n].copy())
        self._alpha_hist.append(float(x[n]) if self.estimate_alpha else float(self.alpha0))

    def predict(self, u, y):
        """One-step-ahead prediction of a record with the fitted estimates (Eq. 19).

        Uses what was fitted (structure, bases, ``theta_``, ``alpha_``), not the current
        settings: ``set_params`` after ``fit`` does not change the predictions.
        """
        check_is_fitted(self, "theta_")
        builder = RegressorBuilder(u, y, na=self._layout.na, nb=self._layout.nb,
                                   f_basis=self._f, g_basis=self._g)
        return builder.matrix(self.alpha_) @ self.theta_


@dataclass(frozen=True, kw_only=True)
class RlsOptions(MethodOptions):
    """Options of ``method="rls"``: the parameters of :class:`MultiInnovationRLS`.

    Attributes
    ----------
    innovation_length : int
        ``P`` (default 1).
    forgetting : float
        Forgetting factor in ``(0, 1]`` (default 1): the weight ``forgetting**(k - j)`` of
        sample ``j`` in the running sums at ``k``.
    alpha0 : float or None
        Initial fractional order; default the middle of ``alpha_bounds``.
    estimate_alpha : bool
        Track alpha recursively (default True).
    initial_covariance : float
        ``S(0) = initial_covariance * I`` for theta (default ``1e6``).
    initial_alpha_variance : float
        Initial variance of alpha (default 0.1).
    """

    renamed = {"p0": "initial_covariance", "alpha_p0": "initial_alpha_variance"}

    innovation_length: int = 1
    forgetting: float = 1.0
    alpha0: float | None = None
    estimate_alpha: bool = True
    initial_covariance: float = 1e6
    initial_alpha_variance: float = 0.1


def rls_result(builder, options, bounds, *, operating_point=(0.0, 0.0)):
    """One pass of MultiInnovationRLS wrapped as an IdentificationResult."""
    alpha0 = 0.5 * (bounds.lo + bounds.hi) if options.alpha0 is None else options.alpha0
    options = options.replace(alpha0=alpha0)
    check_int(options.innovation_length, "innovation_length", minimum=1,
              maximum=builder.n_samples)
    est = MultiInnovationRLS(builder.layout.na, builder.layout.nb, builder.f_basis,
                             builder.g_basis, alpha_bounds=(bounds.lo, bounds.hi),
                             **options.as_dict()).fit(builder.u, builder.y)
    message = ("one pass: a recursive estimator's final value is its estimate; convergence "
               "was not tested.")
    if est.alpha_at_bound_:
        message += " Alpha was held at a bound at least once."
    return finish(builder, method="rls", schedule="recursive", linear=est.theta_,
                  params=[est.alpha_], status=Status.NOT_TESTED, nit=1, nfev=1, message=message,
                  operating_point=operating_point,
                  alpha_at_bound=est.alpha_at_bound_,
                  options=dict(options.as_dict(), alpha_bounds=(bounds.lo, bounds.hi)),
                  theta_history=est.theta_history_, alpha_sample_history=est.alpha_history_)
