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

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from .. import _linalg
from .._validation import check_int, check_scalar
from ..exceptions import ParameterError, SimulationDivergedError
from ..model.system import simulate_theta
from ..results import IdentificationResult, Status
from ._common import bound_note, finish
from .options import MethodOptions
from .varpro import (
    VarproOptions,
    _on_active_bound,
    parameter_covariance,
    separable_least_squares,
)

__all__ = ["OutputErrorOptions", "fit_output_error"]


@dataclass(frozen=True, kw_only=True)
class OutputErrorOptions(MethodOptions):
    """Options of ``method="output_error"``.

    Attributes
    ----------
    n_init : int
        Leading samples left out of the simulation-error criterion (the start-up transient of
        a zero-initial-condition model on data that did not start at rest; default 0).
    start : IdentificationResult, (theta, alpha) or None
        Starting point; default (None) the ``"varpro"`` estimate.
    n_grid : int
        Points of the coarse alpha scan of the ``"varpro"`` start (default 41).
    max_nfev : int
        Simulations allowed to :func:`scipy.optimize.least_squares`, the finite-difference
        Jacobians included (default 100 residual evaluations, as scipy counts them).
    """

    renamed = {"max_iter": "max_nfev"}

    n_init: int = 0
    start: object = None
    n_grid: int = 41
    max_nfev: int = 100

    def check(self, n_samples):
        """Validated copy."""
        return self.replace(n_init=check_int(self.n_init, "n_init", minimum=0,
                                             maximum=n_samples - 2),
                            n_grid=check_int(self.n_grid, "n_grid", minimum=3, maximum=100_000),
                            max_nfev=check_int(self.max_nfev, "max_nfev", minimum=1))


@dataclass
class _OEFit:
    theta: np.ndarray
    alpha: float
    sse: float
    start_shrink: float
    status: Status
    message: str
    covariance: np.ndarray | None
    noise_variance: float
    nit: int
    nfev: int
    at_lower: bool
    at_upper: bool


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
        Interval for alpha.
    n_init : int
        Leading samples left out of the criterion (start-up transient of a zero-initial-
        condition model on data that did not start at rest).
    max_nfev : int, optional
        Limit on residual evaluations, passed to :func:`scipy.optimize.least_squares`.

    Returns
    -------
    _OEFit
    """
    n = layout.n_params
    guard = 10.0 * float(np.max(np.abs(y)))
    window = slice(n_init, None)
    m = y.shape[0] - n_init
    penalty = np.full(m, 2.0 * guard)
    count = [0]

    def simulate(x):
        count[0] += 1
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
    lo, hi = bounds
    x0[n] = float(np.clip(x0[n], lo, hi))
    # The solver works on dimensionless z = x / scale, so that its finite-difference steps and
    # tolerances do not depend on the units of u and y (theta's entries scale with them).
    # The residual is divided by the RMS output, so that scipy's absolute gradient tolerance
    # means the same in every unit.
    scale = _parameter_scale(x0, k)
    y_scale = _rms(y)
    ls = scipy.optimize.least_squares(
        lambda z: residual(z * scale) / y_scale, x0 / scale, method="trf", x_scale="jac",
        max_nfev=max_nfev,
        bounds=(np.r_[np.full(n, -np.inf), lo], np.r_[np.full(n, np.inf), hi]))
    ls.x = ls.x * scale
    ls.x[n] = _on_active_bound(ls.x[n], ls.active_mask[n], lo, hi)
    ls.fun = ls.fun * y_scale
    ls.jac = ls.jac * y_scale / scale
    sse = float(ls.fun @ ls.fun)
    cov, s2 = parameter_covariance(ls.jac, sse, m)
    status = Status.CONVERGED if ls.status > 0 else Status.MAX_ITER if ls.status == 0 else \
        Status.FAILED
    return _OEFit(theta=ls.x[:n].copy(), alpha=float(ls.x[n]), sse=sse, start_shrink=shrink,
                  status=status, message=f"output-error fit (scipy.optimize.least_squares): "
                  f"{ls.message} ({count[0]} simulations)", covariance=cov, noise_variance=s2,
                  nit=int(ls.njev), nfev=count[0], at_lower=bool(ls.active_mask[n] < 0),
                  at_upper=bool(ls.active_mask[n] > 0))


def _rms(y):
    value = float(np.sqrt(np.mean(y * y)))
    return value if value > 0 else 1.0


def _parameter_scale(x0, n_output):
    """Typical size of each parameter: ``|x0|``, a zero entry taking its block's largest."""
    scale = np.abs(x0)
    scale[-1] = 1.0                                    # alpha is dimensionless
    for block in (slice(0, n_output), slice(n_output, x0.shape[0] - 1)):
        part = scale[block]
        part[part == 0] = part.max() if part.max() > 0 else 1.0
    return scale


def _start(builder, options, bounds):
    """``(theta0, alpha0, J0, description)``: the varpro estimate or the given start."""
    start = options.start
    if start is None:
        vp = separable_least_squares(builder, bounds=(bounds.lo, bounds.hi),
                                     options=VarproOptions(n_grid=options.n_grid))
        return vp.theta, vp.alpha, vp.rss / builder.n_samples, "the varpro estimate"
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
    J0 = float(np.mean((builder.y - builder.matrix(alpha0) @ theta0) ** 2))
    return theta0, alpha0, J0, "the given start"


def output_error_result(builder, options, bounds):
    """Equation-error start (varpro) or a given one, then the simulation-error fit."""
    options = options.check(builder.n_samples)
    theta0, alpha0, J0, origin = _start(builder, options, bounds)
    record = dict(options.as_dict(), alpha_bounds=(bounds.lo, bounds.hi))
    if options.start is not None:
        record["start"] = origin
    Phi0 = builder.matrix(alpha0)
    fac = _linalg.factor(Phi0, with_q=False)
    if fac.rank < fac.n_columns:        # not identifiable: no fit (it would drift along the
        return finish(builder, method="output_error", theta=theta0, alpha=alpha0,  # null space)
                      status=Status.RANK_DEFICIENT, nit=0, nfev=0, Phi=Phi0, rank_factor=fac,
                      message=f"no simulation-error fit: the start ({origin}) is rank deficient.",
                      options=record)
    fit = fit_output_error(builder.u, builder.y, layout=builder.layout, f_basis=builder.f_basis,
                           g_basis=builder.g_basis, theta0=theta0, alpha0=alpha0,
                           bounds=(bounds.lo, bounds.hi), n_init=options.n_init,
                           max_nfev=options.max_nfev)
    message = fit.message
    message += (f" Started from {origin} (alpha = {alpha0:.6g})"
                + (f", its output-feedback block shrunk by {fit.start_shrink:.3g} to make it "
                   "stable." if fit.start_shrink < 1 else "."))
    message += f" Simulation error criterion from sample {options.n_init} on."
    if fit.at_lower or fit.at_upper:
        message += bound_note(fit.alpha, bounds.lo, bounds.hi, fit.at_lower, fit.at_upper)
    record["simulation_sse"] = fit.sse
    Phi = builder.matrix(fit.alpha)
    J = float(np.mean((builder.y - Phi @ fit.theta) ** 2))
    return finish(builder, method="output_error", theta=fit.theta, alpha=fit.alpha,
                  status=fit.status, nit=fit.nit, nfev=fit.nfev, message=message,
                  alpha_at_bound=fit.at_lower or fit.at_upper, options=record, Phi=Phi,
                  covariance=fit.covariance,
                  noise_variance=fit.noise_variance, alpha_history=[alpha0, fit.alpha],
                  J_history=[J0, J])
