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

from .._base import REQUIRED, BaseEstimator, check_is_fitted
from .._validation import AlphaBounds, check_array, check_int, check_same_length
from ..model.basis import as_basis
from ..model.gl_expansion import StreamedWindows
from ..model.lagged.params import ThetaLayout
from ..model.lagged.regressors import RegressorBuilder
from ..results import Status
from ._common import finish, paper_model_only
from .options import ALPHA0, FORGETTING, INNOVATION_LENGTH, POSITIVE, Boolean, Method, MethodOptions

__all__ = ["MultiInnovationRLS", "RlsOptions", "METHOD"]


@dataclass(frozen=True, kw_only=True)
class RlsOptions(MethodOptions):
    """Options of ``method="rls"``: the settings of :class:`MultiInnovationRLS`.

    Attributes
    ----------
    innovation_length : int
        ``P`` (default 1: ordinary RLS / recursive prediction error method).
    forgetting : float
        Forgetting factor ``lambda`` in ``(0, 1]`` (default 1: no forgetting): the weight
        ``forgetting**(k - j)`` of sample ``j`` in the running sums at ``k``.
    alpha0 : float or None
        Initial fractional order, strictly inside ``alpha_bounds``; default (None) their middle.
    estimate_alpha : bool
        Track alpha recursively (default True); otherwise alpha stays at ``alpha0``.
    initial_covariance : float
        ``S(0) = initial_covariance * I`` for theta, ``theta(0) = 0`` (default ``1e6``).
    initial_alpha_variance : float
        Initial variance of alpha (default 0.1: a standard deviation of about 0.3).
    """

    constraints = {"innovation_length": INNOVATION_LENGTH, "forgetting": FORGETTING,
                   "alpha0": ALPHA0, "estimate_alpha": Boolean(), "initial_covariance": POSITIVE,
                   "initial_alpha_variance": POSITIVE}

    innovation_length: int = 1
    forgetting: float = 1.0
    alpha0: float | None = None
    estimate_alpha: bool = True
    initial_covariance: float = 1e6
    initial_alpha_variance: float = 0.1

    def complete(self, context):
        """``alpha0`` defaults to the middle of the bounds."""
        if self.alpha0 is not None:
            return self
        return self.replace(alpha0=float(0.5 * (context.lower[0] + context.upper[0])))


class MultiInnovationRLS(BaseEstimator):
    """Multi-innovation recursive least squares with recursive fractional-order tracking.

    Parameters
    ----------
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions.
    alpha_bounds : (float, float), optional
        Open interval for alpha (default ``(0, 1)``); alpha is clipped ``1e-3`` of its width
        inside it.
    innovation_length, forgetting, alpha0, estimate_alpha, initial_covariance, \
initial_alpha_variance
        The settings of :class:`RlsOptions`, with its defaults (``alpha0``: the middle of
        ``alpha_bounds``).

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
    >>> whole = fohw.estimators.rls.MultiInnovationRLS(na=2, nb=2, f_basis=2, g_basis=3).fit(data.u, data.y)
    >>> chunks = fohw.estimators.rls.MultiInnovationRLS(na=2, nb=2, f_basis=2, g_basis=3)
    >>> for i in range(0, 1000, 250):
    ...     _ = chunks.partial_fit(data.u[i:i + 250], data.y[i:i + 250])
    >>> bool(np.array_equal(whole.theta_, chunks.theta_))
    True
    """

    _model = (("na", REQUIRED), ("nb", REQUIRED), ("f_basis", REQUIRED), ("g_basis", REQUIRED),
              ("alpha_bounds", (0.0, 1.0)))
    _options = RlsOptions

    def _initialise(self):
        self._f = as_basis(self.f_basis, "f_basis")
        self._g = as_basis(self.g_basis, "g_basis")
        na = check_int(self.na, "na", minimum=1)
        nb = check_int(self.nb, "nb", minimum=1)
        self._layout = ThetaLayout(na=na, nb=nb, n_g=len(self._g), n_f=len(self._f))
        bounds = AlphaBounds(self.alpha_bounds)
        lo, hi = bounds.lo, bounds.hi
        self._inner = bounds.inner
        o = self._given_options().check(n_samples=None, bounds=(lo, hi))
        self._P, self._lam = o.innovation_length, o.forgetting
        self._estimate_alpha, self._alpha0 = o.estimate_alpha, o.alpha0
        n = self._layout.n_params
        d = n + 1 if o.estimate_alpha else n
        self._lags = [na] * len(self._g) + [nb] * len(self._f)
        self._start_windows(lo, hi)
        self.layout_ = self._layout
        self._signals = np.zeros((len(self._g) + len(self._f), 1024))
        self._y = np.zeros(1024)
        self._x = np.zeros(d)
        self._x[n:] = o.alpha0
        self._S = np.diag(np.r_[np.full(n, o.initial_covariance),
                                np.full(d - n, o.initial_alpha_variance)])
        self._theta_hist, self._alpha_hist = [], []
        self.n_samples_seen_ = 0
        self.alpha_at_bound_ = False

    def _start_windows(self, lo, hi):
        """The windows of the record to come: GL weights expanded in alpha, streamed."""
        self._streamed = StreamedWindows(self._lags, lo, hi, self._P)
        self._vectors = np.zeros((2, self._streamed.terms))

    def _append_signals(self, start, stop):
        """Take the basis signals of samples ``start:stop`` into the streamed windows."""
        self._streamed.append(self._signals[:, start:stop])

    def _windows(self, k, alpha):
        """``Phi(P, k)^T`` (and, when alpha is tracked, its derivative in alpha) at ``alpha``."""
        v = self._vectors
        v[0] = self._streamed.expansion.basis(alpha)
        if self._estimate_alpha:
            v[1] = self._streamed.expansion.basis_derivative(alpha)
        return self._streamed.rows(k, v)

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
        self._append_signals(k0, k0 + m)
        n = self._layout.n_params
        for k in range(k0, k0 + m):
            self._update(k, n)
        self.n_samples_seen_ = k0 + m
        self.theta_ = self._x[:n].copy()
        self.alpha_ = float(self._x[n]) if self._estimate_alpha else float(self._alpha0)
        self.theta_history_ = np.array(self._theta_hist)
        self.alpha_history_ = np.array(self._alpha_hist)
        self.covariance_ = self._S.copy()
        return self

    def _update(self, k, n):
        x, S, lam = self._x, self._S, self._lam
        theta = x[:n]
        alpha = float(x[n]) if self._estimate_alpha else float(self._alpha0)
        wins = self._windows(k, alpha)
        phi = wins[0]
        rows = phi.shape[0]
        yw = self._y[k - rows + 1:k + 1][::-1]
        innov = yw - phi @ theta
        psi = np.hstack([phi, (wins[1] @ theta)[:, None]]) if self._estimate_alpha else phi
        sp = S @ psi.T
        gain = np.linalg.solve(lam * np.eye(rows) + psi @ sp, sp.T).T
        x = x + gain @ innov
        S = (S - gain @ sp.T) / lam
        self._S = 0.5 * (S + S.T)
        if self._estimate_alpha:
            a = float(np.clip(x[n], *self._inner))
            if a != x[n]:
                self.alpha_at_bound_ = True
                x[n] = a
        self._x = x
        self._theta_hist.append(x[:n].copy())
        self._alpha_hist.append(float(x[n]) if self._estimate_alpha else float(self._alpha0))

    def predict(self, u, y):
        """One-step-ahead prediction of a record with the fitted estimates (Eq. 19).

        Uses what was fitted (structure, bases, ``theta_``, ``alpha_``), not the current
        settings: ``set_params`` after ``fit`` does not change the predictions.
        """
        check_is_fitted(self, "theta_")
        builder = RegressorBuilder(u, y, na=self._layout.na, nb=self._layout.nb,
                                   f_basis=self._f, g_basis=self._g)
        return builder.matrix(self.alpha_) @ self.theta_


def rls_result(builder, options, bounds, *, operating_point=(0.0, 0.0)):
    """One pass of MultiInnovationRLS wrapped as an IdentificationResult.

    ``options`` are checked (:meth:`RlsOptions.check`: ``alpha0`` filled in) and ``bounds`` is
    ``(lower, upper)`` of the one free order.
    """
    lo, hi = (float(b[0]) for b in bounds)
    est = MultiInnovationRLS(na=builder.layout.na, nb=builder.layout.nb,
                             f_basis=builder.f_basis, g_basis=builder.g_basis,
                             alpha_bounds=(lo, hi), **options.as_dict()).fit(builder.u, builder.y)
    message = ("one pass: a recursive estimator's final value is its estimate; convergence "
               "was not tested.")
    if est.alpha_at_bound_:
        message += " Alpha was held at a bound at least once."
    return finish(builder, method="rls", schedule="recursive", linear=est.theta_,
                  params=[est.alpha_], status=Status.NOT_TESTED, nit=1, nfev=1, message=message,
                  operating_point=operating_point,
                  alpha_at_bound=est.alpha_at_bound_,
                  options=dict(options.as_dict(), alpha_bounds=(lo, hi)),
                  theta_history=est.theta_history_, alpha_sample_history=est.alpha_history_)


#: ``method="rls"`` as :func:`fohw.identify` dispatches it (the commensurate model only).
METHOD = Method("rls", RlsOptions, rls_result, supports=paper_model_only)
