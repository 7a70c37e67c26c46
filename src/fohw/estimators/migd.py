"""Multi-innovation gradient descent for theta (paper Section 3, Eqs. 22–33).

With the innovation window ``Phi(P, k)`` holding ``phi[k], phi[k-1], …, phi[k-P+1]``
(rows before ``k = 0`` absent):

``E = Y(P, k) - Phi(P, k)^T theta(k-1)``, ``r(k) = r(k-1) + ||Phi(P, k)||^2``,
``theta(k) = theta(k-1) + Phi(P, k) E / r(k)``, with ``r(0) = 1`` and ``theta(0) = 1/p0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._base import REQUIRED, BaseEstimator, check_is_fitted
from .._validation import check_alpha, check_array, check_same_length
from ..model.lagged.regressors import RegressorBuilder
from .options import FORGETTING, INNOVATION_LENGTH, POSITIVE, Choice, MethodOptions

__all__ = ["migd_update", "migd_pass", "MultiInnovationGradient", "MigdOptions",
           "NORMALISATIONS"]

#: ``"window"``: ``r += ||Phi(P, k)||_F^2`` (the paper, Eq. 31);
#: ``"current"``: ``r += ||phi(k)||^2`` (Ding's multi-innovation stochastic gradient).
NORMALISATIONS = ("window", "current")


def migd_update(theta, window, outputs, r_prev, *, normalisation="window", forgetting=1.0):
    """One multi-innovation gradient update (Eqs. 29–31).

    Parameters
    ----------
    theta : ndarray, shape (n,)
        ``theta(k-1)``.
    window : ndarray, shape (P, n)
        Rows ``phi[k], phi[k-1], …`` (``Phi(P, k)^T``; fewer rows near the start).
    outputs : ndarray, shape (P,)
        ``Y(P, k) = [y[k], y[k-1], …]``.
    r_prev : float
        ``r(k-1)``.
    normalisation : {"window", "current"}, optional
        ``"window"`` adds ``||Phi(P, k)||_F^2`` to ``r`` (the paper); ``"current"`` adds
        ``||phi(k)||^2`` (Ding's MISG).
    forgetting : float, optional
        ``r(k) = forgetting * r(k-1) + …``; 1 (default) is the paper.

    Returns
    -------
    theta : ndarray, shape (n,)
        ``theta(k)``.
    r : float
        ``r(k)``.
    innovation : ndarray, shape (P,)
        ``E(P, k)`` computed with ``theta(k-1)`` (Eq. 30).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.migd import migd_update
    >>> theta, r, e = migd_update(np.zeros(2), np.array([[1.0, 0.0]]), np.array([2.0]), 1.0)
    >>> theta, r, e
    (array([1., 0.]), 2.0, array([2.]))
    """
    innovation = outputs - window @ theta
    if normalisation == "window":
        increment = float(np.vdot(window, window))
    else:
        increment = float(window[0] @ window[0])
    r = forgetting * r_prev + increment
    return theta + (innovation @ window) / r, r, innovation


def migd_pass(Phi, y, *, innovation_length, theta0, r0=1.0, normalisation="window",
              forgetting=1.0):
    """Run :func:`migd_update` over a whole record with fixed regressors.

    Parameters
    ----------
    Phi : ndarray, shape (N, n)
        Information matrix (rows ``phi[k]``).
    y : ndarray, shape (N,)
        Output.
    innovation_length : int
        ``P >= 1``.
    theta0 : ndarray, shape (n,)
        Initial estimate ``theta(0)``; the first update is at ``k = 0``.
    r0 : float, optional
        ``r`` before the first update (the paper: 1).
    normalisation, forgetting
        As in :func:`migd_update`.

    Returns
    -------
    theta_history : ndarray, shape (N, n)
        ``theta(k)`` after the update at sample ``k``.
    r_history : ndarray, shape (N,)
    innovations : ndarray, shape (N,)
        The single innovation ``e(k) = y[k] - phi[k] @ theta(k-1)``.
    """
    import scipy.signal

    n_samples, n = Phi.shape
    P = innovation_length
    # r(k) does not depend on theta: all of it at once (Eq. 31 or Ding's MISG).
    row2 = np.einsum("ij,ij->i", Phi, Phi)
    if normalisation == "window":
        c = np.cumsum(row2)
        increment = c.copy()
        increment[P:] -= c[:-P]
    else:
        increment = row2
    if forgetting == 1.0:
        r_hist = float(r0) + np.cumsum(increment)
    else:
        r_hist = scipy.signal.lfilter([1.0], [1.0, -forgetting], increment,
                                      zi=[forgetting * float(r0)])[0]
    theta = np.array(theta0, dtype=np.float64)
    history = np.empty((n_samples, n))
    innov = np.empty(n_samples)
    for k in range(n_samples):
        lo = k - P + 1
        window = Phi[k:lo - 1:-1] if lo > 0 else Phi[k::-1]
        outputs = y[k:lo - 1:-1] if lo > 0 else y[k::-1]
        e = outputs - window @ theta
        theta = theta + window.T @ e / r_hist[k]
        history[k] = theta
        innov[k] = e[0]
    return history, r_hist, innov


@dataclass(frozen=True, kw_only=True)
class MigdOptions(MethodOptions):
    """Settings of :class:`MultiInnovationGradient` (one MIGD pass at a given order).

    Attributes
    ----------
    innovation_length : int
        ``P``, the number of innovations per update, ``1 <= P <= N`` (default 5).
    p0 : float
        ``theta(0) = 1/p0`` in every entry (default ``1e6``).
    normalisation : {"window", "current"}
        How ``r(k)`` grows (see :func:`migd_update`). Default ``"window"`` (the paper).
    forgetting : float
        Forgetting factor on ``r`` in ``(0, 1]``; 1 (default) is the paper.
    """

    constraints = {"innovation_length": INNOVATION_LENGTH, "p0": POSITIVE,
                   "normalisation": Choice(NORMALISATIONS), "forgetting": FORGETTING}

    innovation_length: int = 5
    p0: float = 1e6
    normalisation: str = "window"
    forgetting: float = 1.0


class MultiInnovationGradient(BaseEstimator):
    """Multi-innovation gradient estimator of theta for a known fractional order (Eqs. 29–33).

    Parameters
    ----------
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions.
    alpha : float
        The (known or fixed) fractional order, in ``(0, 2)``.
    innovation_length, p0, normalisation, forgetting
        The settings of :class:`MigdOptions`, with its defaults.

    Attributes
    ----------
    theta_ : ndarray
        Final estimate ``theta(N-1)``.
    alpha_ : float
        The order the estimate was fitted at (``alpha`` when ``fit`` ran).
    theta_history_ : ndarray, shape (N, n)
        ``theta(k)`` at every sample.
    r_history_ : ndarray, shape (N,)
    innovation_history_ : ndarray, shape (N,)
        ``e(k) = y[k] - phi[k] @ theta(k-1)``.
    n_iter_ : int
        Number of updates (``N``).

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(2000, random_state=0)
    >>> est = fohw.estimators.migd.MultiInnovationGradient(na=2, nb=2, f_basis=2, g_basis=3, alpha=0.6)
    >>> est.fit(data.u, data.y).theta_.shape
    (10,)
    """

    _model = (("na", REQUIRED), ("nb", REQUIRED), ("f_basis", REQUIRED), ("g_basis", REQUIRED),
              ("alpha", REQUIRED))
    _options = MigdOptions

    def fit(self, u, y):
        """Run one MIGD pass over the record; return ``self``."""
        u = check_array(u, "u")
        y = check_array(y, "y")
        check_same_length(u, y, "u", "y")
        alpha = check_alpha(self.alpha)
        o = self._given_options().check(n_samples=y.shape[0], bounds=None)
        builder = RegressorBuilder(u, y, na=self.na, nb=self.nb, f_basis=self.f_basis,
                                   g_basis=self.g_basis)
        Phi = builder.matrix(alpha)
        theta0 = np.full(builder.layout.n_params, 1.0 / o.p0)
        hist, r_hist, innov = migd_pass(Phi, y, innovation_length=o.innovation_length,
                                        theta0=theta0, normalisation=o.normalisation,
                                        forgetting=o.forgetting)
        self.layout_ = builder.layout
        self._bases = (builder.f_basis, builder.g_basis)
        self.alpha_ = alpha
        self.theta_history_ = hist
        self.r_history_ = r_hist
        self.innovation_history_ = innov
        self.theta_ = hist[-1].copy()
        self.n_iter_ = y.shape[0]
        return self

    def predict(self, u, y):
        """One-step-ahead prediction ``Phi(alpha_) @ theta_`` for a record (Eq. 19).

        Uses what was fitted (structure, bases, ``alpha_``, ``theta_``): settings changed after
        ``fit`` do not affect it.
        """
        check_is_fitted(self, "theta_")
        f_basis, g_basis = self._bases
        builder = RegressorBuilder(u, y, na=self.layout_.na, nb=self.layout_.nb, f_basis=f_basis,
                                   g_basis=g_basis)
        return builder.matrix(self.alpha_) @ self.theta_
