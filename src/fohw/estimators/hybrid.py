"""The alternating identification driver (paper Section 4, Steps 1–9 and Table 1).

``identify`` estimates ``theta`` by multi-innovation gradient descent (:mod:`fohw.estimators.migd`) and
the fractional order by the multi-innovation Levenberg–Marquardt step (:mod:`fohw.estimators.milm`),
alternately, under one of two schedules the paper describes:

``"recursive"`` (Table 1, the default)
    At every sample ``k``: rebuild the innovation window ``Phi(P, k)`` at the current
    ``alpha`` (exactly, from the full memory), update ``theta`` (Eqs. 29–31), then update
    ``alpha`` by Eq. (48) on the same window with the new ``theta``. One outer iteration is one
    pass over the record; ``max_iter`` passes at most (default 1: Table 1 as printed).
``"iterative"`` (Steps 1–9)
    Outer iteration ``m``: an ``alpha`` step (Steps 3–5), then a full MIGD pass over the
    record at that ``alpha`` (Steps 6–7), then ``J`` (Eq. 41, Step 8); stop when the relative
    change of ``J`` is at most ``tol`` (Step 9).

Where the paper is ambiguous, the reading closest to the text is the default and the other is
an option:

* ``alpha0`` is not given in the paper; the default 0.5 is the middle of its ``(0, 1)``.
* ``alpha_window`` (iterative schedule): ``"innovation"`` (default) uses Eq. (48) as printed,
  the last ``P`` samples at the current ``k`` — at ``m = 1`` that is ``k = 0`` (Step 1 sets
  ``k = 1``), afterwards the end of the record; ``"record"`` uses every sample, i.e.
  Eqs. (46a–b) summed over the record (a damped Gauss–Newton step on Eq. 41). The recursive
  schedule always uses the last ``P`` samples (Table 1, lines 20–26).
* ``restart_r``: ``r`` continues across passes (default; Table 1 sets ``r(0) = 1`` once) or
  restarts at 1 every pass.
* ``sensitivity``: the finite difference of Eq. (44) with ``delta_alpha = 1e-3`` (default) or
  the exact derivative of the GL weights.
* The order of the two steps follows each source: ``theta`` then ``alpha`` in Table 1;
  ``alpha`` then ``theta`` in Steps 3–6.

The baselines of Fig. 6 are named configurations of the same code:
``method="single_innovation_gradient"`` is ``"hybrid"`` with ``P = 1``, and
``method="single_innovation_lm"`` applies the step of Eq. (48) with ``P = 1`` to
``(theta, alpha)`` jointly.
"""

from __future__ import annotations

import warnings

import numpy as np

from .._base import BaseEstimator, check_is_fitted
from ..exceptions import ConvergenceWarning, ParameterError
from ..model.gl import _weights
from ..results import IdentificationResult, recover_model
from .migd import migd_pass, migd_update
from .milm import alpha_update, milm_step, sensitivity_weights

__all__ = ["run_alternation", "HybridIdentifier", "SCHEDULES"]

SCHEDULES = ("recursive", "iterative")
_DEFAULT_MAX_ITER = {"recursive": 1, "iterative": 50}


def _criterion(J_prev, J):
    return abs(J - J_prev) / abs(J_prev) if J_prev != 0 else (0.0 if J == 0 else np.inf)


def run_alternation(builder, *, method, schedule, P, alpha, alpha0, max_iter, tol, bounds, p0,
                    normalisation, forgetting, lm_lambda, delta_alpha, sensitivity, alpha_window,
                    restart_r):
    """The paper's alternation of MIGD (theta) and MI-LM (alpha) under one schedule.

    Settings arrive validated by :func:`fohw.identify`; returns its ``IdentificationResult``.
    """
    n_samples = builder.n_samples
    cfg = dict(P=P, normalisation=normalisation, forgetting=forgetting, lm_lambda=lm_lambda,
               delta_alpha=delta_alpha, sensitivity=sensitivity, n_samples=n_samples)
    theta = np.full(builder.layout.n_params, 1.0 / p0)
    r = 1.0
    alpha_hist, J_hist = [], []
    converged = False
    Phi = None              # the information matrix at the current alpha, once built
    for m in range(1, max_iter + 1):
        if restart_r:
            r = 1.0
        if schedule == "recursive":
            theta, alpha, r, theta_path, alpha_path = _recursive_pass(
                builder, theta, alpha, r, bounds, joint=(method == "single_innovation_lm"), **cfg)
        else:
            k_now = 0 if m == 1 else n_samples - 1
            rows = None if alpha_window == "record" else np.arange(k_now, max(k_now - P, -1), -1)
            alpha = bounds(alpha_update(builder, theta, alpha, rows=rows, lm_lambda=lm_lambda,
                                        sensitivity=sensitivity, delta_alpha=delta_alpha,
                                        Phi=Phi))
            Phi = builder.matrix(alpha)
            theta_path, r_path, _ = migd_pass(Phi, builder.y, innovation_length=P, theta0=theta,
                                              r0=r, normalisation=normalisation,
                                              forgetting=forgetting)
            theta, r = theta_path[-1].copy(), float(r_path[-1])
            alpha_path = np.full(n_samples, alpha)
        if schedule == "recursive":
            Phi = builder.matrix(alpha)
        J = float(np.mean((builder.y - Phi @ theta) ** 2))
        alpha_hist.append(alpha)
        J_hist.append(J)
        if m >= 2 and _criterion(J_hist[-2], J) <= tol:
            converged = True
            break

    if converged:
        message = (f"converged: relative change of J {_criterion(J_hist[-2], J_hist[-1]):.3g} "
                   f"<= tol = {tol:g} after {m} iterations.")
    elif max_iter == 1:
        message = ("one pass only (max_iter=1): convergence of J was not tested; set "
                   "max_iter >= 2 to test it.")
    else:
        message = (f"stopped at max_iter = {max_iter}: relative change of J "
                   f"{_criterion(J_hist[-2], J_hist[-1]):.3g} > tol = {tol:g}.")
    if not converged:
        warnings.warn(f"fohw.identify({method!r}, schedule={schedule!r}): {message}",
                      ConvergenceWarning, stacklevel=3)
    model, note = recover_model(builder, theta, alpha)
    message += note
    if bounds.hit:
        message += f" Alpha was held at a bound of {tuple(bounds.inner)} at least once."
    options = dict(innovation_length=P, alpha0=float(alpha0), max_iter=max_iter, tol=tol,
                   alpha_bounds=(bounds.lo, bounds.hi), p0=p0, normalisation=normalisation,
                   forgetting=forgetting, lm_lambda=lm_lambda, delta_alpha=delta_alpha,
                   sensitivity=sensitivity, alpha_window=alpha_window, restart_r=bool(restart_r))
    return IdentificationResult(
        method=method, schedule=schedule, alpha=float(alpha), theta=theta, model=model, J=J_hist[-1],
        n_iter=len(J_hist), converged=converged, message=message, alpha_at_bound=bounds.hit,
        theta_history=theta_path, alpha_sample_history=alpha_path,
        alpha_history=np.array(alpha_hist), J_history=np.array(J_hist), layout=builder.layout,
        f_basis=builder.f_basis, g_basis=builder.g_basis, n_samples=n_samples, options=options)


def _recursive_pass(builder, theta, alpha, r, bounds, *, joint, P, normalisation, forgetting,
                    lm_lambda, delta_alpha, sensitivity, n_samples):
    """One pass of Table 1: at each k, theta by Eq. (29) then alpha by Eq. (48).

    With ``joint=True`` (the single-innovation LM baseline) both are updated together by the
    step of Eq. (48) applied to ``(theta, alpha)``.
    """
    y = builder.y
    n = theta.shape[0]
    theta_path = np.empty((n_samples, n))
    alpha_path = np.empty(n_samples)
    for k in range(n_samples):
        length = max(k, 1)
        beta = _weights(alpha, length)
        phi_w, dphi_w = builder.window(k, P, [
            beta, sensitivity_weights(alpha, length, sensitivity=sensitivity,
                                      delta_alpha=delta_alpha, beta=beta)])
        y_w = y[k:k - phi_w.shape[0]:-1] if k - phi_w.shape[0] >= 0 else y[k::-1]
        if joint:
            jac = np.hstack([phi_w, (dphi_w @ theta)[:, None]])
            step = milm_step(jac, y_w - phi_w @ theta, n_samples=n_samples, lm_lambda=lm_lambda)
            theta = theta + step[:n]
            alpha = bounds(alpha + step[n])
        else:
            theta, r, _ = migd_update(theta, phi_w, y_w, r, normalisation=normalisation,
                                      forgetting=forgetting)
            alpha = bounds(alpha + milm_step(dphi_w @ theta, y_w - phi_w @ theta,
                                             n_samples=n_samples, lm_lambda=lm_lambda))
        theta_path[k] = theta
        alpha_path[k] = alpha
    return theta, alpha, r, theta_path, alpha_path


class HybridIdentifier(BaseEstimator):
    """Estimator interface to :func:`fohw.identify` (scikit-learn conventions, no dependency).

    Parameters
    ----------
    na, nb, f_basis, g_basis
        Model structure, as in :func:`fohw.identify`.
    **options
        Any keyword argument of :func:`fohw.identify` (``method``, ``innovation_length``, …),
        stored as the attribute of the same name.

    Attributes
    ----------
    result_ : IdentificationResult
    theta_, alpha_, model_, n_iter_
        Shortcuts into ``result_``.

    Examples
    --------
    >>> import warnings, fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> est = fohw.HybridIdentifier(na=2, nb=2, f_basis=2, g_basis=3, schedule="iterative",
    ...                             max_iter=30)
    >>> est.get_params()["schedule"]
    'iterative'
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", fohw.ConvergenceWarning)
    ...     est = est.fit(data.u, data.y)
    >>> est.theta_.shape
    (10,)
    """

    _OPTIONS = ("method", "innovation_length", "alpha0", "schedule", "max_iter", "tol",
                "random_state", "alpha_bounds", "p0", "normalisation", "forgetting",
                "lm_lambda", "delta_alpha", "sensitivity", "alpha_window", "restart_r", "n_grid",
                "n_init", "start")

    def __init__(self, na, nb, f_basis, g_basis, **options):
        self.na = na
        self.nb = nb
        self.f_basis = f_basis
        self.g_basis = g_basis
        unknown = set(options) - set(self._OPTIONS)
        if unknown:
            raise ParameterError(f"unknown option(s) {sorted(unknown)}; valid: {self._OPTIONS}.")
        self._options = dict(options)
        for key, value in options.items():
            setattr(self, key, value)

    def get_params(self, deep=True):
        """Return the structure and every option that was set."""
        params = {k: getattr(self, k) for k in ("na", "nb", "f_basis", "g_basis")}
        params.update({k: getattr(self, k) for k in self._OPTIONS if hasattr(self, k)})
        return params

    def set_params(self, **params):
        """Set structure or options by name; returns ``self``."""
        for key, value in params.items():
            if key not in ("na", "nb", "f_basis", "g_basis") + self._OPTIONS:
                raise ValueError(f"invalid parameter {key!r} for HybridIdentifier.")
            setattr(self, key, value)
        return self

    def fit(self, u, y):
        """Identify from ``(u, y)``; return ``self``."""
        from .identify import identify

        opts = {k: getattr(self, k) for k in self._OPTIONS if hasattr(self, k)}
        self.result_ = identify(u, y, na=self.na, nb=self.nb, f_basis=self.f_basis,
                                g_basis=self.g_basis, **opts)
        self.theta_ = np.array(self.result_.theta)
        self.alpha_ = self.result_.alpha
        self.model_ = self.result_.model
        self.n_iter_ = self.result_.n_iter
        return self

    def predict(self, u, y):
        """One-step-ahead prediction with the fitted model (Eq. 19)."""
        check_is_fitted(self, "result_")
        return self.result_.predict(u, y)
