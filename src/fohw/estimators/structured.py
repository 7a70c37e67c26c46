"""Least squares over the model's own parameters (a, b, p, q, orders) — beyond the paper.

Theta is not free: ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20) has ``na + nb + (n_f - 1) + (n_g - 1)``
free numbers, not ``n_g na + n_f nb``. Separable least squares (``"varpro"``) fits theta
unconstrained and recovers ``a, b, p, q`` afterwards (Eqs. 39–40); it reaches the Cramér–Rao
bound of the unstructured theta, which is larger than the bound of the structured parameters
(:func:`fohw.crb` with ``parametrisation="structured"``). This estimator

1. runs ``"varpro"`` (:func:`~fohw.estimators.varpro.separable_least_squares`, polish included),
2. recovers ``a, b, p, q`` from its theta by the best rank-one fit of the blocks ``[q_j a_i]``
   and ``[p_j b_i]`` (their leading singular triples,
   :meth:`fohw.model.lagged.params.ThetaLayout.rank_one_recovery`)
   rather than by the mean of ratios of Eqs. (39)–(40), and
3. minimises the one-step prediction error (Eq. 41)
   ``||y - Phi(nonlinear) theta(a, b, p, q) - offset||^2`` over
   ``x = (a, b, p_2.., q_2.., offset, nonlinear)`` (:attr:`fohw.Structure.structured_names`)
   with :func:`scipy.optimize.least_squares` (trust-region reflective, ``x_scale="jac"``, the
   free orders bounded) and the exact Jacobian ``G M``: ``G = [Phi, dPhi/dnu @ theta, …]``
   (:meth:`fohw.model.lagged.regressors.RegressorBuilder.jacobian`, GL weight derivatives for the
   orders) times
   ``M = d(theta, …)/dx`` (:meth:`fohw.Structure.structured_jacobian`).

Under white Gaussian equation noise the result is the conditional maximum-likelihood estimate
of the structured parameters. Its covariance ``s^2 ((G M)^T G M)^{-1}`` is reported mapped to
``(theta, nonlinear)`` as ``M C M^T`` (rank deficient: theta lies on the rank-one set), so that
:meth:`fohw.IdentificationResult.standard_errors` gives theta's and, through the delta method of
Eqs. (39)–(40) (which inverts the mapping exactly), ``C``'s own entries for ``a, b, p, q``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import ParameterError
from ..results import Status
from ._common import (
    bound_note,
    bounded_least_squares,
    bounds_record,
    finish,
    kept_above_zero,
    natural_sizes,
    rms_scale,
    scaled_problem,
    working_scale,
)
from .options import MAX_NFEV, N_GRID, POSITIVE, Method, MethodOptions
from .profile import parameter_covariance
from .varpro import VarproOptions
from .varpro_search import separable_least_squares

__all__ = ["StructuredOptions", "structured_result", "fit_structured", "METHOD"]


@dataclass(frozen=True, kw_only=True)
class StructuredOptions(MethodOptions):
    """Options of ``method="structured"``.

    Attributes
    ----------
    n_grid : int
        Points of the coarse alpha scan of the ``"varpro"`` start (default 41, at least 3).
    tol : float
        Relative change of the cost at which :func:`scipy.optimize.least_squares` stops (its
        ``ftol``; also its ``xtol`` and ``gtol``), in the start's polish and in the structured
        fit (default ``1e-10``).
    max_nfev : int or None
        Evaluations allowed to the structured fit (default None: scipy's ``100 * (d + 1)``).
    """

    constraints = {"n_grid": N_GRID, "tol": POSITIVE, "max_nfev": MAX_NFEV}

    n_grid: int = 41
    tol: float = 1e-10
    max_nfev: int | None = None


def structured_scale(builder):
    """Working scales of the structured parameters (``a, b, p_2.., q_2..``, offset, nonlinear).

    From the working scales ``w`` of theta's entries (one per basis signal,
    :func:`~fohw.estimators._common.working_scale`): ``a`` takes the first output signal's,
    ``q_j`` the ratio of signal ``j``'s to it (``q_1 = 1``), likewise ``b`` and ``p``. All 1
    for data in moderate units.
    """
    s = builder.structure
    w = working_scale(natural_sizes(builder))
    n_out, n_in = len(s.orders.output), len(s.orders.input)
    n_g, n_f = len(s.g_basis), len(s.f_basis)
    wg = w[0:n_g * n_out:n_out]
    if s.n_inputs > 1:                    # per input: b_i from its first signal, p_i ratios
        groups = s.layout.groups
        wb = [np.full(len(names), w[off]) for _, names, _, off in groups]
        wp = [w[off + len(names):off + nf * len(names):len(names)] / w[off]
              for _, names, nf, off in groups]
        return np.concatenate([np.full(n_out, wg[0])] + wb + wp
                              + [wg[1:] / wg[0], w[s.layout.n_params:]])
    wf = w[n_g * n_out:n_g * n_out + n_f * n_in:n_in]
    return np.r_[np.full(n_out, wg[0]), np.full(n_in, wf[0]), wf[1:] / wf[0], wg[1:] / wg[0],
                 w[s.layout.n_params:]]


def fit_structured(builder, x0, *, lower, upper, tol=1e-10, max_nfev=None):
    """Least squares over the structured parameters from ``x0``.

    Parameters
    ----------
    builder : RegressorBuilder
        The record and the model class.
    x0 : ndarray
        Start, in :attr:`Structure.structured_names` order (clipped into the bounds).
    lower, upper : ndarray
        Bounds of the free orders.
    tol : float
        Tolerances of :func:`scipy.optimize.least_squares`.
    max_nfev : int, optional
        Evaluation limit.

    Returns
    -------
    x : ndarray
        The estimate (orders put on a bound the solver reports active).
    rss : float
        ``||y - Phi theta(x)||^2``.
    jacobian : ndarray, shape (N, d)
        ``G M`` at ``x``: the derivative of the one-step prediction.
    status : Status
    ls : scipy.optimize.OptimizeResult
    """
    s = builder.structure
    y = builder.y
    y_scale = rms_scale(y)
    m = len(s.structured_names) - s.n_nonlinear
    n_free = len(s.orders.free)
    n_past = s.n_nonlinear - n_free

    def residual(x):
        linear, params = s.from_structured(x)
        return (y - builder.matrix(params) @ linear) / y_scale

    def jacobian(x):
        linear, params = s.from_structured(x)
        return builder.jacobian(linear, params) @ s.structured_jacobian(x) / -y_scale

    lo = np.r_[np.full(m, -np.inf), lower, np.full(n_past, -np.inf)]
    hi = np.r_[np.full(m, np.inf), upper, np.full(n_past, np.inf)]
    scale = structured_scale(builder)         # parameters far from size 1: in their units
    res, jac, z0, lo_z, hi_z = scaled_problem(residual, jacobian, x0, lo, hi, scale)
    z, status, ls = bounded_least_squares(res, z0, jac=jac, lower=lo_z, upper=hi_z,
                                          keep=kept_above_zero(s, m, lower),
                                          ftol=tol, xtol=tol, gtol=tol, max_nfev=max_nfev)
    x = z * scale
    rss = float(ls.fun @ ls.fun) * y_scale * y_scale      # inf, not OverflowError
    linear, params = s.from_structured(x)
    return x, rss, builder.jacobian(linear, params) @ s.structured_jacobian(x), status, ls


def structured_result(builder, options, bounds, *, operating_point=(0.0, 0.0)):
    """``"varpro"``, rank-one recovery, then least squares over the structured parameters.

    ``options`` are checked (:meth:`StructuredOptions.check`).
    """
    s = builder.structure
    opts = options
    lower, upper = bounds
    record = dict(opts.as_dict(), alpha_bounds=bounds_record(s, lower, upper))
    vp = separable_least_squares(builder, bounds=(lower, upper),
                                 options=VarproOptions(n_grid=opts.n_grid, tol=opts.tol))
    if vp.rank_factor is not None and vp.rank_factor.rank < vp.rank_factor.n_columns:
        return finish(builder, method="structured", linear=vp.linear, params=vp.params,
                      status=Status.RANK_DEFICIENT, nit=vp.nit, nfev=vp.nfev,
                      rank_factor=vp.rank_factor, options=record,
                      operating_point=operating_point,
                      message="no structured fit: the varpro start is rank deficient.")
    # The rank-one recovery weighs theta's entries in their working units (a best rank-one fit
    # is not invariant to scaling the rows of a block): the same start in every unit.
    w = working_scale(natural_sizes(builder))
    n_lin = s.n_linear
    try:
        x0 = s.to_structured(vp.linear / w[:n_lin], vp.params / w[n_lin:]) \
            * structured_scale(builder)
    except ParameterError as exc:
        raise ParameterError(f"fohw.identify('structured'): cannot start from the varpro "
                             f"estimate: {exc}") from None
    x, rss, jac, status, ls = fit_structured(builder, x0, lower=lower, upper=upper,
                                             tol=opts.tol, max_nfev=opts.max_nfev)
    linear, params = s.from_structured(x)
    cov_x, s2 = parameter_covariance(jac, rss, builder.n_samples)
    covariance = None
    if cov_x is not None:
        M = s.structured_jacobian(x)
        covariance = M @ cov_x @ M.T
        covariance = 0.5 * (covariance + covariance.T)
    n_free = len(s.orders.free)
    m = len(s.structured_names) - s.n_nonlinear
    active = ls.active_mask[m:m + n_free]
    message = (f"structured least squares over {', '.join(s.structured_names)} from the varpro "
               f"estimate (rank-one recovery of q⊗a and p⊗b; varpro: {vp.message}); "
               f"scipy.optimize.least_squares: {ls.message}")
    for j, name in enumerate(s.orders.free):
        if active[j]:
            message += bound_note(name, lower[j], upper[j], active[j] < 0, active[j] > 0,
                                  value=params[j])
    return finish(builder, method="structured", linear=linear, params=params, status=status,
                  nit=vp.nit + int(ls.njev), nfev=vp.nfev + int(ls.nfev), message=message,
                  alpha_at_bound=bool(np.any(active != 0)), options=record,
                  details={"start": "varpro (rank-one recovery)"},
                  covariance=covariance, noise_variance=s2, operating_point=operating_point)


#: ``method="structured"`` as :func:`fohw.identify` dispatches it (every structure).
METHOD = Method("structured", StructuredOptions, structured_result)
