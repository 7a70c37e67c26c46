"""Variable projection's search: the orders by scans and a bounded search, then a joint polish.

For fixed orders the model is linear in theta (:mod:`fohw.estimators.profile` solves it), so
``J(params) = rss(params) / N`` is a function of the nonlinear parameters only.
:func:`separable_least_squares` scans it on a grid, refines one free order by Brent's bounded
search (several nonlinear parameters: variable projection from the scans' best points, with
Golub and Pereyra's Jacobian), then polishes ``(theta, params)`` jointly by
:func:`scipy.optimize.least_squares` with the exact Jacobian. The method and its options are
described in :mod:`fohw.estimators.varpro`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from ..exceptions import EstimationDivergedError
from ..results import Status
from ._common import (
    bounded_least_squares,
    check_enough_samples,
    kept_above_zero,
    natural_sizes,
    rms_scale,
    scaled_problem,
    solver_status,
    working_scale,
)
from .profile import Profile

__all__ = ["VarproFit", "separable_least_squares"]


@dataclass
class VarproFit:
    """What the search found: :func:`fohw.estimators.varpro.varpro_result` wraps it."""

    linear: np.ndarray
    params: np.ndarray
    rss: float
    grid: np.ndarray
    grid_J: np.ndarray
    search_alphas: list
    search_J: list
    status: Status
    nit: int
    nfev: int
    message: str
    at_lower: np.ndarray
    at_upper: np.ndarray
    covariance: np.ndarray | None
    noise_variance: float
    rank_factor: object


def separable_least_squares(builder, *, bounds, options):
    """Separable least-squares estimate of the linear and nonlinear parameters of one record.

    Parameters
    ----------
    builder : RegressorBuilder
        The record and the model class (:attr:`RegressorBuilder.structure`).
    bounds : (array_like, array_like)
        Lower and upper bounds of each free order (past levels are unbounded).
    options : VarproOptions
        Grid, tolerances and polish (:class:`fohw.estimators.varpro.VarproOptions`).

    Returns
    -------
    VarproFit
        :func:`fohw.identify` wraps it into an ``IdentificationResult``.
    """
    opts = options.check(n_samples=builder.n_samples, bounds=bounds)
    s = builder.structure
    check_enough_samples(builder.n_samples, s)
    lo = np.atleast_1d(np.asarray(bounds[0], dtype=float))
    hi = np.atleast_1d(np.asarray(bounds[1], dtype=float))
    profile = Profile(builder)
    builder = profile.builder
    if s.n_nonlinear == 0:
        return _linear_only(builder, profile)
    if s.n_nonlinear == 1 and len(s.orders.free) == 1:
        params, search, grid, grid_J, nit, ok, message = _scalar_search(builder, profile,
                                                                        lo[0], hi[0], opts)
    else:
        params, search, grid, grid_J, nit, ok, message = _vector_search(builder, profile, lo,
                                                                        hi, opts)
    linear, rss, fac = profile(params)
    nfev = profile.count
    profile.last = None            # free the differences (40 MB at N = 10^6) for the polish
    n_free = len(s.orders.free)
    edge = 1e-5 * (hi - lo)
    at_lower = params[:n_free] - lo < edge
    at_upper = hi - params[:n_free] < edge
    status = Status.CONVERGED if ok else Status.MAX_ITER
    if fac.rank < fac.n_columns:
        message += "; no polish (the information matrix is rank deficient)."
    elif opts.polish:
        linear, params, rss, ls = _polish(builder, linear, params, lo, hi, opts)
        nit += int(ls.njev)
        nfev += int(ls.nfev)
        at_lower, at_upper = ls.active_mask[s.n_linear:][:n_free] < 0, \
            ls.active_mask[s.n_linear:][:n_free] > 0
        status = solver_status(ls)
        message += f"; polish (scipy.optimize.least_squares): {ls.message}"
        fac = None
    cov, s2 = profile.covariance(linear, params, rss)
    return VarproFit(linear=linear, params=params, rss=rss, grid=grid, grid_J=grid_J,
                      search_alphas=search[0], search_J=search[1], status=status, nit=nit,
                      nfev=nfev, message=message, at_lower=np.asarray(at_lower, dtype=bool),
                      at_upper=np.asarray(at_upper, dtype=bool), covariance=cov,
                      noise_variance=s2, rank_factor=fac)


def _linear_only(builder, profile):
    """Every order fixed and no past levels: one linear least-squares solve."""
    linear, rss, fac = profile(np.zeros(0))
    cov, s2 = profile.covariance(linear, np.zeros(0), rss)
    return VarproFit(linear=linear, params=np.zeros(0), rss=rss, grid=np.zeros(0),
                      grid_J=np.zeros(0), search_alphas=[], search_J=[],
                      status=Status.CONVERGED, nit=0, nfev=1,
                      message="converged: linear least squares (every order fixed)",
                      at_lower=np.zeros(0, bool), at_upper=np.zeros(0, bool), covariance=cov,
                      noise_variance=s2, rank_factor=fac)


def _scalar_search(builder, profile, lo, hi, opts):
    """One free order: a grid scan inside the bounds, then Brent's bounded search."""
    n_samples = builder.n_samples
    grid = np.linspace(lo, hi, opts.n_grid + 2)[1:-1]
    grid_J = _finite_somewhere(np.array([profile(a)[1] for a in grid]) / n_samples, builder.y)
    i = int(np.argmin(grid_J))
    left = grid[i - 1] if i > 0 else lo + 1e-6 * (hi - lo)
    right = grid[i + 1] if i < opts.n_grid - 1 else hi - 1e-6 * (hi - lo)
    alphas, values = [], []

    def traced(alpha):
        value = profile(alpha)[1] / n_samples
        alphas.append(float(alpha))
        values.append(value)
        return value

    opt = scipy.optimize.minimize_scalar(traced, bounds=(left, right), method="bounded",
                                         options={"xatol": opts.alpha_xtol, "maxiter": 500})
    alpha = float(opt.x)
    # A minimum in the first or last grid cell may lie on the bound itself (the search stays
    # strictly inside): compare with the profile at the bound.
    for edge_alpha, touched in ((lo, i == 0), (hi, i == opts.n_grid - 1)):
        if touched and profile(edge_alpha)[1] < profile(alpha)[1]:
            alpha = float(edge_alpha)
    message = f"alpha search: {opt.message}"
    return np.array([alpha]), (alphas, values), grid, grid_J, int(opt.nit), bool(opt.success), \
        message


#: Points per order of the full grid of starts, by number of free orders.
_FULL_GRID = {2: 15, 3: 8}


def _vector_search(builder, profile, lo, hi, opts):
    """Several nonlinear parameters: starts from scans, then variable projection from each.

    The tied scan moves the free orders together, each at the same relative position in its
    bounds (the commensurate line when the bounds are equal), with past levels at 0; it is
    the reported profile. The starts are: for two or three free orders, the best local minima
    (at most four) of a full grid over the orders (:data:`_FULL_GRID` points per order); for
    more, the point reached by one sweep of one-order scans from the best tied point, then the
    best local minima of the tied scan (at most three); with past levels only, rest. From each,
    :func:`scipy.optimize.least_squares` minimises the profile
    ``||y - Phi(params) theta(params)||`` over all nonlinear parameters with Golub and
    Pereyra's Jacobian; the best end point is kept.
    """
    s = builder.structure
    n_free, n_samples = len(s.orders.free), builder.n_samples
    n_past = s.n_nonlinear - n_free
    tau = np.linspace(0.0, 1.0, opts.n_grid + 2)[1:-1]
    grid_points = [np.r_[lo + t * (hi - lo), np.zeros(n_past)] for t in tau]
    if n_free == 0:                       # only past levels: start at rest
        grid_points, tau = [np.zeros(n_past)], np.zeros(1)
    grid_J = _finite_somewhere(np.array([profile(p)[1] for p in grid_points]) / n_samples,
                               builder.y)
    if n_free in _FULL_GRID:
        starts, origin = _grid_minima(profile, lo, hi, n_past)
    else:
        starts, origin = _scan_starts(profile, lo, hi, tau, grid_points, grid_J)
    best, nit = _project_from(profile, starts, lo, hi, n_past, opts.tol)
    message = f"variable projection from {len(starts)} start(s) ({origin}): {best.message}"
    grid = lo[0] + tau * (hi[0] - lo[0]) if n_free else tau
    return best.x, ([], []), grid, grid_J, nit, best.status > 0, message


def _finite_somewhere(values, y):
    """The criterion on a grid, NaN read as +inf; an error naming the cause if none is finite.

    Where no point of the grid has a finite criterion there is no start for any search (the
    squared errors or the regressors overflow); NaN points elsewhere are never minima.
    """
    values = np.where(np.isnan(values), np.inf, values)
    if not np.any(np.isfinite(values)):
        raise EstimationDivergedError(
            "fohw.identify: the one-step criterion J is not finite at any of the "
            f"{values.size} points of the grid of the orders: in the units of the data the "
            f"squared errors (max |y| = {float(np.max(np.abs(y))):.3g}) or the regressors "
            "overflow; rescale u and y (e.g. to an RMS near 1): fohw's estimates rescale with "
            "the data.")
    return values


def _grid_minima(profile, lo, hi, n_past):
    """Starts for two or three free orders: the best local minima of a full grid of them.

    The profile of two or three orders can have several minima along a curved valley (a
    noise-free record with two tied orders had one at J = 2e-7 beside the true J = 0, both off
    the tied line).
    """
    n_free = lo.shape[0]
    m = _FULL_GRID[n_free]
    axes = [lo[j] + np.linspace(0.0, 1.0, m + 2)[1:-1] * (hi[j] - lo[j]) for j in range(n_free)]
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n_free)
    values = _finite_somewhere(np.array([profile(np.r_[p, np.zeros(n_past)])[1] for p in mesh]),
                               profile.builder.y)
    cube = values.reshape((m,) * n_free)
    minima = np.flatnonzero(cube == scipy.ndimage.minimum_filter(cube, size=3, mode="nearest"))
    starts = [np.r_[mesh[i], np.zeros(n_past)] for i in minima[np.argsort(values[minima])][:4]]
    return starts, f"the minima of a {m}^{n_free} grid"


def _scan_starts(profile, lo, hi, tau, grid_points, grid_J):
    """Starts from the tied scan: its best local minima (at most three).

    With more than one free order (four or more: fewer take :func:`_grid_minima`), first the
    point one sweep of one-order scans reaches from the best of them.
    """
    interior = [i for i in range(len(grid_J))
                if (i == 0 or grid_J[i] <= grid_J[i - 1])
                and (i == len(grid_J) - 1 or grid_J[i] <= grid_J[i + 1])]
    starts = [grid_points[i] for i in sorted(interior, key=lambda i: grid_J[i])[:3]]
    if lo.shape[0] <= 1:
        return starts, "the tied-order scan"
    # Each order over its bounds with the others held gives a start off the diagonal.
    point = starts[0].copy()
    for j in range(lo.shape[0]):
        trial = []
        for t in tau:
            p = point.copy()
            p[j] = lo[j] + t * (hi[j] - lo[j])
            trial.append((profile(p)[1], p))
        point = min(trial, key=lambda item: item[0])[1]
    starts.insert(0, point)
    return starts, "one sweep of one-order scans and the tied-order scan"


def _project_from(profile, starts, lo, hi, n_past, tol):
    """Variable projection (least squares on the profile residual) from each start.

    Returns the solver's result of the best end point and the Jacobians evaluated in all.
    """
    y_scale = rms_scale(profile.builder.y)
    lower = np.r_[lo, np.full(n_past, -np.inf)]
    upper = np.r_[hi, np.full(n_past, np.inf)]

    def residual(params):
        return profile.residual(params) / y_scale

    def golub_pereyra(params):
        return profile.golub_pereyra(params) / y_scale

    n_free = lo.shape[0]
    scale = working_scale(natural_sizes(profile.builder)[-(n_free + n_past):]) \
        if n_free + n_past else np.ones(0)
    res, jac, _, lower_z, upper_z = scaled_problem(residual, golub_pereyra, None, lower, upper,
                                                   scale)
    best, nit = None, 0
    for x0 in starts:
        x0 = np.clip(x0, lower, upper)
        ls = scipy.optimize.least_squares(res, x0 / scale, jac=jac, bounds=(lower_z, upper_z),
                                          method="trf", x_scale="jac", ftol=tol, xtol=tol,
                                          gtol=tol)
        nit += int(ls.njev)
        if best is None or ls.cost < best.cost:
            best = ls
    best.x = best.x * scale
    return best, nit


def _polish(builder, linear, params, lo, hi, opts):
    """Joint least squares over ``(linear, params)`` from the profile estimate.

    The residual is divided by the RMS output so that the solver's absolute gradient
    tolerance means the same whatever the units of ``y``; ``x_scale="jac"`` does the same for
    the parameters.
    """
    s = builder.structure
    n, n_free = s.n_linear, len(s.orders.free)
    n_past = s.n_nonlinear - n_free
    y = builder.y
    y_scale = rms_scale(y)

    def residual(x):
        return (y - builder.matrix(x[n:]) @ x[:n]) / y_scale

    def jacobian(x):
        return builder.jacobian(x[:n], x[n:]) / -y_scale

    lower = np.r_[np.full(n, -np.inf), lo, np.full(n_past, -np.inf)]
    upper = np.r_[np.full(n, np.inf), hi, np.full(n_past, np.inf)]
    # Parameters far from size 1 (data in units of 1e±6 and beyond) are searched in units of
    # their natural size, so that the step tolerance means the same in every unit.
    scale = working_scale(natural_sizes(builder))
    res, jac, z0, lower_z, upper_z = scaled_problem(residual, jacobian, np.r_[linear, params],
                                                    lower, upper, scale)
    z, _, ls = bounded_least_squares(res, z0, jac=jac, lower=lower_z, upper=upper_z,
                                     keep=kept_above_zero(s, n, lo), ftol=opts.tol,
                                     xtol=opts.tol, gtol=opts.tol, max_nfev=opts.max_nfev)
    x = z * scale
    rss = float(ls.fun @ ls.fun) * y_scale * y_scale      # inf, not OverflowError
    return x[:n], x[n:], rss, ls
