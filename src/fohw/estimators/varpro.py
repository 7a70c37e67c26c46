"""Separable least squares (variable projection) for theta and alpha — beyond the paper.

For a fixed ``alpha`` the model ``y = Phi(alpha) theta + v`` is linear in ``theta``, so
``theta(alpha)`` is a linear least-squares solution and ``J(alpha) = mean(residual**2)`` (Eq. 41
at the best theta) is a function of one variable. The estimator

1. scans ``J(alpha)`` on a grid inside the bounds (so a local minimum is not taken for the
   global one),
2. refines the best grid cell by a bounded scalar search (Brent), and
3. polishes ``(theta, alpha)`` jointly with :func:`scipy.optimize.least_squares` (trust-region
   reflective, ``x_scale="jac"``, alpha bounded) and the exact Jacobian
   ``[Phi, dPhi/dalpha @ theta]`` (:meth:`fohw.RegressorBuilder.jacobian`).

Every linear solve equilibrates the columns of ``Phi`` and factors it by QR with column
pivoting, so the estimate does not depend on the units of ``u`` and ``y`` and a rank-deficient
information matrix is reported (it names the dependent columns) instead of giving huge,
meaningless estimates. Each ``J(alpha)`` costs one inverse FFT of the stacked basis signals, whose
FFTs are computed once per record. The result is the equation-error (prediction-error) estimate;
under white Gaussian equation noise it is the conditional maximum-likelihood estimate and reaches
the Cramér–Rao bound of the unstructured theta (:func:`fohw.crb`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from .. import _linalg
from .._validation import check_int, check_scalar
from ..exceptions import ParameterError
from ..results import Status
from ._common import bound_note, finish
from .options import MethodOptions

__all__ = ["VarproOptions", "profile_theta", "separable_least_squares", "parameter_covariance"]


@dataclass(frozen=True, kw_only=True)
class VarproOptions(MethodOptions):
    """Options of ``method="varpro"``.

    Attributes
    ----------
    n_grid : int
        Points of the coarse alpha scan, equally spaced strictly inside ``alpha_bounds``
        (default 41, at least 3).
    xtol : float
        Absolute tolerance on alpha of the bounded scalar search (default ``1e-10``).
    polish : bool
        Polish ``(theta, alpha)`` jointly by least squares with the exact Jacobian (default
        True). Without it, alpha is the scalar search's and theta its profile solution.
    tol : float
        ``ftol``, ``xtol`` and ``gtol`` of :func:`scipy.optimize.least_squares` in the polish
        (default ``1e-10``).
    max_nfev : int or None
        Evaluations allowed to the polish (default None: scipy's ``100 * (n + 1)``).
    """

    n_grid: int = 41
    xtol: float = 1e-10
    polish: bool = True
    tol: float = 1e-10
    max_nfev: int | None = None

    def check(self):
        """Validated copy."""
        if not isinstance(self.polish, (bool, np.bool_)):
            raise ParameterError(f"`polish` must be True or False; got {self.polish!r}.")
        return self.replace(
            n_grid=check_int(self.n_grid, "n_grid", minimum=3, maximum=100_000),
            xtol=check_scalar(self.xtol, "xtol", lower=0.0, lower_inclusive=False),
            tol=check_scalar(self.tol, "tol", lower=0.0, lower_inclusive=False),
            max_nfev=None if self.max_nfev is None else check_int(self.max_nfev, "max_nfev",
                                                                  minimum=1))


def profile_theta(Phi, y):
    """Least-squares ``theta`` for fixed regressors (equilibrated columns, pivoted QR).

    Parameters
    ----------
    Phi : ndarray, shape (N, n)
    y : ndarray, shape (N,)

    Returns
    -------
    theta : ndarray, shape (n,)
        The solution; if ``Phi`` is rank deficient, the basic solution with the dependent
        columns' entries at 0.
    rss : float
        Residual sum of squares ``||y - Phi theta||^2``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.varpro import profile_theta
    >>> theta, rss = profile_theta(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    ...                            np.array([1.0, 2.0, 3.0]))
    >>> theta.round(12), round(rss, 12)
    (array([1., 2.]), 0.0)
    """
    theta, rss, _ = _linalg.lstsq(Phi, y)
    return theta, rss


def parameter_covariance(jacobian, rss, n_samples):
    """Asymptotic covariance ``s^2 (G^T G)^{-1}`` of least-squares estimates.

    Parameters
    ----------
    jacobian : ndarray, shape (N, d)
        Derivative of the predicted output with respect to the ``d`` parameters.
    rss : float
        Residual sum of squares at the estimate.
    n_samples : int
        ``N``.

    Returns
    -------
    covariance : ndarray, shape (d, d), or None
        ``None`` when ``G`` is rank deficient (the parameters are not identifiable).
    noise_variance : float
        ``s^2 = rss / (N - d)``.

    Notes
    -----
    Computed from the triangular factor of the column-equilibrated, pivoted QR of ``G`` (never
    from the normal equations), so it does not depend on the units of the parameters.
    """
    d = jacobian.shape[1]
    s2 = rss / (n_samples - d)
    inverse, _ = _linalg.inverse_gram(jacobian)
    return (None if inverse is None else s2 * inverse), s2


@dataclass
class _VarproFit:
    theta: np.ndarray
    alpha: float
    rss: float
    grid: np.ndarray
    grid_J: np.ndarray
    search_alphas: list
    search_J: list
    status: Status
    nit: int
    nfev: int
    message: str
    at_lower: bool
    at_upper: bool
    covariance: np.ndarray | None
    noise_variance: float
    rank_factor: object


def separable_least_squares(builder, *, bounds, options=None):
    """Separable least-squares estimate of ``(theta, alpha)`` for one record.

    Parameters
    ----------
    builder : RegressorBuilder
        The record.
    bounds : (float, float)
        Interval searched for alpha (the polish may reach its ends).
    options : VarproOptions, optional
        Grid, tolerances and polish.

    Returns
    -------
    _VarproFit
        Internal record; :func:`fohw.identify` wraps it into an ``IdentificationResult``.
    """
    opts = (options or VarproOptions()).check()
    y = builder.y
    n_samples = builder.n_samples
    lo, hi = bounds
    grid = np.linspace(lo, hi, opts.n_grid + 2)[1:-1]
    cache = {}

    def profile(alpha):
        alpha = float(alpha)
        if alpha not in cache:
            cache[alpha] = _linalg.lstsq(builder.matrix(alpha), y)
        return cache[alpha]

    grid_J = np.array([profile(a)[1] for a in grid]) / n_samples
    i = int(np.argmin(grid_J))
    left = grid[i - 1] if i > 0 else lo + 1e-6 * (hi - lo)
    right = grid[i + 1] if i < opts.n_grid - 1 else hi - 1e-6 * (hi - lo)
    search_alphas, search_J = [], []

    def traced(alpha):
        value = profile(alpha)[1] / n_samples
        search_alphas.append(float(alpha))
        search_J.append(value)
        return value

    opt = scipy.optimize.minimize_scalar(traced, bounds=(left, right), method="bounded",
                                         options={"xatol": opts.xtol, "maxiter": 500})
    alpha = float(opt.x)
    # A minimum in the first or last grid cell may lie on the bound itself (the search stays
    # strictly inside): compare with the profile at the bound.
    for edge_alpha, touched in ((lo, i == 0), (hi, i == opts.n_grid - 1)):
        if touched and profile(edge_alpha)[1] < profile(alpha)[1]:
            alpha = float(edge_alpha)
    theta, rss, fac = profile(alpha)
    nit, nfev = int(opt.nit), len(cache)
    edge = 1e-5 * (hi - lo)
    at_lower, at_upper = alpha - lo < edge, hi - alpha < edge
    status = Status.CONVERGED if opt.success else Status.MAX_ITER
    message = f"alpha search: {opt.message}"
    if fac.rank < fac.n_columns:
        message += "; no polish (the information matrix is rank deficient)."
    elif opts.polish:
        theta, alpha, rss, ls = _polish(builder, theta, alpha, lo, hi, opts)
        nit += int(ls.njev)
        nfev += int(ls.nfev)
        at_lower, at_upper = bool(ls.active_mask[-1] < 0), bool(ls.active_mask[-1] > 0)
        status = (Status.CONVERGED if ls.status > 0 else
                  Status.MAX_ITER if ls.status == 0 else Status.FAILED)
        message += f"; polish (scipy.optimize.least_squares): {ls.message}"
        fac = None
    cov, s2 = parameter_covariance(builder.jacobian(theta, alpha), rss, n_samples)
    return _VarproFit(theta=theta, alpha=alpha, rss=rss, grid=grid, grid_J=grid_J,
                      search_alphas=search_alphas, search_J=search_J, status=status, nit=nit,
                      nfev=nfev, message=message, at_lower=at_lower, at_upper=at_upper,
                      covariance=cov, noise_variance=s2, rank_factor=fac)


def _polish(builder, theta, alpha, lo, hi, opts):
    """Joint least squares over ``(theta, alpha)`` from the profile estimate.

    The residual is divided by the RMS output so that the solver's absolute gradient
    tolerance means the same whatever the units of ``y``; ``x_scale="jac"`` does the same for
    the parameters.
    """
    n = theta.shape[0]
    y = builder.y
    y_scale = float(np.sqrt(np.mean(y * y))) or 1.0

    def residual(x):
        return (y - builder.matrix(x[n]) @ x[:n]) / y_scale

    def jacobian(x):
        return builder.jacobian(x[:n], x[n]) / -y_scale

    ls = scipy.optimize.least_squares(
        residual, np.append(theta, np.clip(alpha, lo, hi)), jac=jacobian, method="trf",
        bounds=(np.r_[np.full(n, -np.inf), lo], np.r_[np.full(n, np.inf), hi]),
        x_scale="jac", ftol=opts.tol, xtol=opts.tol, gtol=opts.tol, max_nfev=opts.max_nfev)
    rss = float(ls.fun @ ls.fun) * y_scale**2
    alpha = float(_on_active_bound(ls.x[n], ls.active_mask[n], lo, hi))
    return ls.x[:n].copy(), alpha, rss, ls


def _on_active_bound(value, active, lo, hi):
    """The trust-region solver stays ~1e-10 inside a bound it reports active: put it on it."""
    return lo if active < 0 else hi if active > 0 else value


def varpro_result(builder, options, bounds):
    """Run separable least squares and wrap it as an IdentificationResult."""
    fit = separable_least_squares(builder, bounds=(bounds.lo, bounds.hi), options=options)
    message = fit.message
    if fit.at_lower or fit.at_upper:
        message += bound_note(fit.alpha, bounds.lo, bounds.hi, fit.at_lower, fit.at_upper)
    return finish(builder, method="varpro", theta=fit.theta, alpha=fit.alpha, status=fit.status,
                  nit=fit.nit, nfev=fit.nfev, message=message,
                  alpha_at_bound=fit.at_lower or fit.at_upper,
                  options=dict(options.as_dict(), alpha_bounds=(bounds.lo, bounds.hi)),
                  rank_factor=fit.rank_factor, covariance=fit.covariance,
                  noise_variance=fit.noise_variance, alpha_history=fit.search_alphas,
                  J_history=fit.search_J, alpha_profile=np.vstack([fit.grid, fit.grid_J]))
