"""Separable least squares (variable projection) for theta and alpha — beyond the paper.

For a fixed ``alpha`` the model ``y = Phi(alpha) theta + v`` is linear in ``theta``, so
``theta(alpha)`` is a linear least-squares solution and ``J(alpha) = mean(residual**2)`` (Eq. 41
at the best theta) is a function of one variable. The estimator

1. scans ``J(alpha)`` on a grid inside the bounds (so a local minimum is not taken for the
   global one),
2. refines the best grid cell by a bounded scalar search (Brent), and
3. polishes ``(theta, alpha)`` jointly with :func:`scipy.optimize.least_squares` (trust-region
   reflective, ``x_scale="jac"``, alpha bounded) and the exact Jacobian
   ``[Phi, dPhi/dalpha @ theta]`` (:meth:`fohw.model.lagged.regressors.RegressorBuilder.jacobian`).

A general structure with several nonlinear parameters (free orders, past levels) replaces
steps 1-2: a scan with the orders moved together (``n_grid`` points), starts from a full grid
of the orders (two or three orders) or from one-order scans (more), and from each start
:func:`scipy.optimize.least_squares` on the profile ``||y - Phi theta(params)||`` with Golub
and Pereyra's Jacobian (tolerance ``tol``; ``xtol`` and ``max_nfev`` do not apply there);
step 3 follows.

Every linear solve equilibrates the columns of ``Phi`` and factors it by QR with column
pivoting, so the estimate does not depend on the units of ``u`` and ``y`` and a rank-deficient
information matrix is reported (it names the dependent columns) instead of giving huge,
meaningless estimates. Each ``J(alpha)`` costs one inverse FFT of the basis signals, whose FFTs
are computed once per record, and one solve that never forms the ``N x n`` matrix: the
triangular factor of ``[Phi, y]`` is accumulated over blocks of rows (TSQR,
:class:`fohw.estimators.profile.Profile`), and so are the Golub–Pereyra Jacobian and the
covariance (``tests/reference_estimators.py`` keeps the full-matrix solves they replaced, for
comparison). The result is the
equation-error (prediction-error) estimate; under white Gaussian equation noise it is the
conditional maximum-likelihood estimate and reaches the Cramér–Rao bound of the unstructured
theta (:func:`fohw.crb`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._threads import thin_solves
from ._common import bound_note, bounds_record, finish
from .options import MAX_NFEV, N_GRID, POSITIVE, Boolean, Method, MethodOptions
from .profile import parameter_covariance, profile_theta
from .profile import rank_factor as blocked_rank_factor
from .varpro_search import separable_least_squares

__all__ = ["VarproOptions", "profile_theta", "separable_least_squares", "parameter_covariance",
           "varpro_result", "METHOD"]


@dataclass(frozen=True, kw_only=True)
class VarproOptions(MethodOptions):
    """Options of ``method="varpro"``.

    Attributes
    ----------
    n_grid : int
        Points of the coarse alpha scan, equally spaced strictly inside ``alpha_bounds``
        (default 41, at least 3).
    alpha_xtol : float
        Absolute tolerance on alpha of the bounded scalar (Brent) search (default ``1e-10``).
    polish : bool
        Polish ``(theta, alpha)`` jointly by least squares with the exact Jacobian (default
        True). Without it, alpha is the scalar search's and theta its profile solution.
    tol : float
        Relative change of the cost at which :func:`scipy.optimize.least_squares` stops
        (its ``ftol``; also its ``xtol`` and ``gtol``), in the polish and in the search of
        several nonlinear parameters (default ``1e-10``).
    max_nfev : int or None
        Evaluations allowed to the polish (default None: scipy's ``100 * (n + 1)``).
    """

    constraints = {"n_grid": N_GRID, "alpha_xtol": POSITIVE, "polish": Boolean(), "tol": POSITIVE,
                   "max_nfev": MAX_NFEV}

    n_grid: int = 41
    alpha_xtol: float = 1e-10
    polish: bool = True
    tol: float = 1e-10
    max_nfev: int | None = None


@thin_solves
def varpro_result(builder, options, bounds, *, operating_point=(0.0, 0.0)):
    """Run separable least squares and wrap it as an IdentificationResult.

    ``bounds`` is ``(lower, upper)`` over the free orders (:func:`fohw.identify` builds it).
    """
    s = builder.structure
    lo, hi = bounds
    fit = separable_least_squares(builder, bounds=(lo, hi), options=options)
    message = fit.message
    for m, name in enumerate(s.orders.free):
        if fit.at_lower[m] or fit.at_upper[m]:
            message += bound_note(name, lo[m], hi[m], fit.at_lower[m], fit.at_upper[m],
                                  value=fit.params[m])
    record = dict(options.as_dict(), alpha_bounds=bounds_record(s, lo, hi))
    profile = np.vstack([fit.grid, fit.grid_J]) if fit.grid.size else None
    rank_factor = fit.rank_factor
    if rank_factor is None:                         # after the polish: the final Phi's rank
        rank_factor = blocked_rank_factor(builder, fit.params)
    return finish(builder, method="varpro", linear=fit.linear, params=fit.params,
                  status=fit.status, nit=fit.nit, nfev=fit.nfev, message=message,
                  alpha_at_bound=bool(np.any(fit.at_lower) or np.any(fit.at_upper)),
                  options=record, rank_factor=rank_factor, covariance=fit.covariance,
                  noise_variance=fit.noise_variance,
                  alpha_history=fit.search_alphas or None, J_history=fit.search_J or None,
                  alpha_profile=profile, operating_point=operating_point)


#: ``method="varpro"`` as :func:`fohw.identify` dispatches it (every structure).
METHOD = Method("varpro", VarproOptions, varpro_result)
