"""Simulation-focused (output-error) fitting — beyond the paper.

The paper's estimators, like every equation-error method, minimise the *one-step* prediction
error (Eq. 41). A model can predict one step ahead very well and still simulate badly (or be
unstable) in free run, which is how users of identification tools judge a model (MATLAB's
``compare``, the fit index of nonlinear benchmarks). This module minimises the free-run
simulation error instead:

``min over (theta, alpha)  sum_{k >= n_init} (y[k] - ysim[k; theta, alpha])**2``

with a trust-region reflective least-squares solver (finite-difference Jacobian), started from
the equation-error estimate. Candidate models whose simulation escapes (beyond ten times the
largest measured ``|y|``) get a large constant residual, so the solver steps back from them; an
unstable starting model is first made stable by shrinking its output-feedback block.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from .._validation import check_scalar
from ..exceptions import ConvergenceWarning, ParameterError, SimulationDivergedError
from ..model.system import simulate_theta
from ..results import IdentificationResult, recover_model
from .varpro import parameter_covariance, separable_least_squares

__all__ = ["fit_output_error"]


@dataclass
class _OEFit:
    theta: np.ndarray
    alpha: float
    sse: float
    start_shrink: float
    converged: bool
    message: str
    covariance: np.ndarray
    noise_variance: float
    nfev: int


def fit_output_error(u, y, *, layout, f_basis, g_basis, theta0, alpha0, bounds, n_init=0,
                     max_nfev=None):
    """Fit ``(theta, alpha)`` to minimise the free-run simulation error.

    Parameters
    ----------
    u, y : ndarray, shape (N,)
        Input and measured output.
    layout : ThetaLayout
        Structure of theta.
    f_basis, g_basis : Basis
        Basis functions.
    theta0, alpha0 : ndarray, float
        Starting point (usually the equation-error estimate).
    bounds : (float, float)
        Open interval for alpha.
    n_init : int
        Leading samples left out of the criterion (start-up transient of a zero-initial-
        condition model on data that did not start at rest).
    max_nfev : int, optional
        Limit on simulations, passed to :func:`scipy.optimize.least_squares`.

    Returns
    -------
    _OEFit
    """
    n = layout.n_params
    guard = 10.0 * float(np.max(np.abs(y)))
    window = slice(n_init, None)
    m = y.shape[0] - n_init
    penalty = np.full(m, 2.0 * guard)

    def simulate(x):
        return simulate_theta(x[:n], x[n], u, na=layout.na, nb=layout.nb, f_basis=f_basis,
                              g_basis=g_basis, divergence_threshold=guard)

    def residual(x):
        try:
            return (y - simulate(x))[window]
        except SimulationDivergedError:
            return penalty

    x0 = np.append(np.asarray(theta0, dtype=np.float64), float(alpha0))
    k = layout.n_output_params
    shrink = 1.0
    for _ in range(60):
        try:
            simulate(x0)
            break
        except SimulationDivergedError:
            shrink *= 0.8
            x0[:k] *= 0.8
    margin = 1e-6 * (bounds[1] - bounds[0])
    lo, hi = bounds[0] + margin, bounds[1] - margin
    x0[n] = float(np.clip(x0[n], lo, hi))
    ls = scipy.optimize.least_squares(
        residual, x0, method="trf", x_scale="jac", max_nfev=max_nfev,
        bounds=(np.r_[np.full(n, -np.inf), lo], np.r_[np.full(n, np.inf), hi]))
    sse = float(ls.fun @ ls.fun)
    cov, s2 = parameter_covariance(ls.jac, sse, m)
    return _OEFit(theta=ls.x[:n].copy(), alpha=float(ls.x[n]), sse=sse, start_shrink=shrink,
                  converged=ls.status > 0,
                  message=f"output-error fit: {ls.message} ({ls.nfev} simulations)",
                  covariance=cov, noise_variance=s2, nfev=int(ls.nfev))


def output_error_result(builder, bounds, n_grid, n_init, start, max_nfev):
    """Equation-error start (varpro) or a given one, then the simulation-error fit."""
    if start is None:
        vp = separable_least_squares(builder, bounds=(bounds.lo, bounds.hi), n_grid=n_grid)
        theta0, alpha0, origin = vp.theta, vp.alpha, "the varpro estimate"
        J0 = vp.rss / builder.n_samples
    else:
        if isinstance(start, IdentificationResult):
            theta0, alpha0 = start.theta, start.alpha
        else:
            try:
                theta0, alpha0 = start
            except (TypeError, ValueError):
                raise ParameterError("`start` must be an IdentificationResult or a pair "
                                     f"(theta, alpha); got {start!r}.") from None
        theta0 = builder.layout.check_theta(theta0, "start theta")
        alpha0 = check_scalar(alpha0, "start alpha", lower=bounds.lo, upper=bounds.hi)
        origin = "the given start"
        J0 = float(np.mean((builder.y - builder.matrix(alpha0) @ theta0) ** 2))
    fit = fit_output_error(builder.u, builder.y, layout=builder.layout, f_basis=builder.f_basis,
                           g_basis=builder.g_basis, theta0=theta0, alpha0=alpha0,
                           bounds=(bounds.lo, bounds.hi), n_init=n_init, max_nfev=max_nfev)
    message = ("converged: " if fit.converged else "NOT converged: ") + fit.message
    message += (f" Started from {origin} (alpha = {alpha0:.6g})"
                + (f", its output-feedback block shrunk by {fit.start_shrink:.3g} to make it "
                   "stable." if fit.start_shrink < 1 else "."))
    message += f" Simulation error criterion from sample {n_init} on."
    if not fit.converged:
        warnings.warn(f"fohw.identify('output_error'): {message}", ConvergenceWarning,
                      stacklevel=3)
    model, note = recover_model(builder, fit.theta, fit.alpha)
    message += note
    J = float(np.mean((builder.y - builder.matrix(fit.alpha) @ fit.theta) ** 2))
    return IdentificationResult(
        method="output_error", schedule="", alpha=fit.alpha, theta=fit.theta, model=model, J=J,
        n_iter=fit.nfev, converged=fit.converged, message=message,
        alpha_at_bound=not (bounds.lo < fit.alpha < bounds.hi), theta_history=None,
        alpha_sample_history=None, alpha_history=np.array([alpha0, fit.alpha]),
        J_history=np.array([J0, J]), layout=builder.layout,
        f_basis=builder.f_basis, g_basis=builder.g_basis, n_samples=builder.n_samples,
        options=dict(alpha_bounds=(bounds.lo, bounds.hi), n_grid=n_grid, n_init=n_init,
                     simulation_sse=fit.sse),
        covariance=fit.covariance, noise_variance=fit.noise_variance)
