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
triangular factor of ``[Phi, y]`` is accumulated over blocks of rows (TSQR, :class:`_Profile`),
and so are the Golub–Pereyra Jacobian and the covariance. ``_reference=True`` keeps the
full-matrix solves (:class:`_FullMatrixProfile`) for comparison. The result is the
equation-error (prediction-error) estimate; under white Gaussian equation noise it is the
conditional maximum-likelihood estimate and reaches the Cramér–Rao bound of the unstructured
theta (:func:`fohw.crb`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.ndimage
import scipy.optimize

from .. import _linalg
from .._threads import thin_solves
from .._validation import check_int, check_scalar
from ..exceptions import ParameterError
from ..results import Status
from ._common import bound_note, bounded_least_squares, check_enough_samples, finish, rms_scale
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


#: Rows of ``Phi`` per block of the blocked (TSQR) solves: 16384 x 12 doubles, 1.5 MB.
_BLOCK_ROWS = 16384


def _row_blocks(columns, extra=(), rows=None):
    """Rows of ``[Phi, extra...]`` in Fortran-ordered blocks (of :data:`_BLOCK_ROWS` rows).

    One buffer is reused: consume each block before asking for the next.
    """
    rows = _BLOCK_ROWS if rows is None else rows
    n, k = columns.n_samples, columns.n_columns
    buffer = np.empty((min(rows, n), k + len(extra)), order="F")
    for start in range(0, n, rows):
        stop = min(start + rows, n)
        block = buffer if stop - start == buffer.shape[0] else \
            np.empty((stop - start, buffer.shape[1]), order="F")
        columns.fill(start, stop, block)
        for j, vector in enumerate(extra):
            block[:, k + j] = vector[start:stop]
        yield block


class _Profile:
    """``theta(params)`` and ``rss(params)`` of the separable problem, by blocks of rows.

    ``Phi(params)`` is never formed: its columns are lagged views of the GL differences
    (:meth:`fohw.RegressorBuilder.columns`), and the triangular factor of ``[Phi, y]`` is
    accumulated over blocks of :data:`_BLOCK_ROWS` rows (:func:`fohw._linalg.triangular`,
    TSQR); the solve, its rank decision and ``rss`` come from that ``(n + 1) x (n + 1)``
    factor (:func:`fohw._linalg.lstsq_triangular`). The columns and the factor are kept for
    the latest point only (the solver asks for the residual and then the Jacobian at the same
    point); :attr:`count` is the number of distinct points evaluated.
    """

    def __init__(self, builder):
        self.builder = builder
        self.points = set()
        self.last = None               # (key, columns or matrix, linear, rss, factor)

    def solve(self, params):
        """``(columns, linear, rss, factor)`` at ``params``."""
        key = tuple(np.atleast_1d(params).tolist())
        if self.last is None or self.last[0] != key:
            self.last = (key, *self._evaluate(params))
            self.points.add(key)
        return self.last[1:]

    def _evaluate(self, params):
        builder = self.builder
        columns = builder.columns(builder.check_params(params))
        r = _linalg.triangular(_row_blocks(columns, (builder.y,)), columns.n_columns + 1)
        return (columns, *_linalg.lstsq_triangular(r, builder.n_samples))

    def __call__(self, params):
        return self.solve(params)[1:]

    @property
    def count(self):
        return len(self.points)

    def residual(self, params):
        """``y - Phi theta(params)``."""
        columns, linear, _, _ = self.solve(params)
        return self.builder.y - columns.matvec(linear)

    def golub_pereyra(self, params):
        """Golub and Pereyra's Jacobian of :meth:`residual`, shape ``(N, n_nonlinear)``.

        ``d/dp P_perp y = -P_perp dPhi theta - (Phi^+)^T dPhi^T r = -v + Q (Q^T v - z)`` with
        ``v = dPhi theta`` and ``z = R^-T P^T (dPhi^T r / scale)``. ``Q^T v`` comes from the
        triangular factor of ``[Phi, v...]`` (TSQR again; its ``Phi`` part is the profile's
        factor), and ``Q t = (Phi / scale)[:, perm[:k]] R_k^-1 t`` is applied through
        ``Phi``: no ``N x n`` array. Its rounding error is ``eps * cond(R_k)`` relative, against
        ``eps`` through an explicit ``Q``; it only steers the search (the residual defines the
        solution).
        """
        builder = self.builder
        columns, linear, _, fac = self.solve(params)
        params = builder.check_params(params)
        resid = builder.y - columns.matvec(linear)
        k, n = fac.rank, columns.n_columns
        r_k = fac.r[:k, :k]
        v, z = [], []
        for m in range(params.shape[0]):
            derivative = builder.columns(params, which=m)
            v.append(derivative.matvec(linear))
            w = (derivative.rmatvec(resid) / fac.scale)[fac.perm[:k]]
            z.append(scipy.linalg.solve_triangular(r_k, w, trans="T", check_finite=False))
        r = _linalg.triangular(_row_blocks(columns, v), n + len(v))
        qtv = (fac.q.T @ r[:n, n:])[:k]                        # Q^T v, first k entries
        out = np.empty((builder.n_samples, len(v)))
        for m in range(len(v)):
            coef = np.zeros(n)
            coef[fac.perm[:k]] = scipy.linalg.solve_triangular(r_k, qtv[:, m] - z[m],
                                                               check_finite=False)
            out[:, m] = columns.matvec(coef / fac.scale) - v[m]
        return out

    def covariance(self, linear, params, rss):
        """:func:`parameter_covariance` of ``(linear, params)`` without the ``N x d`` Jacobian.

        The Jacobian ``[Phi, dPhi/dparams[m] @ linear]`` is factored by blocks of rows; the
        covariance is computed from its triangular factor as :func:`parameter_covariance`
        computes it from the QR of the whole.
        """
        builder = self.builder
        params = builder.check_params(params)
        columns = builder.columns(params)
        v = [builder.columns(params, which=m).matvec(linear) for m in range(params.shape[0])]
        d = columns.n_columns + len(v)
        r = _linalg.triangular(_row_blocks(columns, v), d)
        s2 = rss / (builder.n_samples - d)
        inverse, _ = _linalg.inverse_gram_triangular(r, builder.n_samples)
        return (None if inverse is None else s2 * inverse), s2


def _rank_factor(builder, params):
    """The rank-revealing factor of ``Phi(params)`` (rank, dependent columns), by blocks."""
    columns = builder.columns(builder.check_params(params))
    r = _linalg.triangular(_row_blocks(columns), columns.n_columns)
    return _linalg.factor_triangular(r, builder.n_samples)


class _FullMatrixProfile(_Profile):
    """The reference: the whole ``N x n`` matrix and its pivoted QR with ``Q`` at every point.

    What varpro did before the blocked solves (fohw 0.x up to issue 15, item 5); kept so the
    two can be compared (``separable_least_squares(..., _reference=True)``, the tests and
    ``benchmarks/bench_varpro.py``).
    """

    def _evaluate(self, params):
        matrix = self.builder.matrix(params)
        return (matrix, *_linalg.lstsq(matrix, self.builder.y))

    def residual(self, params):
        matrix, linear, _, _ = self.solve(params)
        return self.builder.y - matrix @ linear

    def golub_pereyra(self, params):
        # d/dp of P_perp y: -P_perp dPhi theta - (Phi^+)^T dPhi^T r (Golub and Pereyra);
        # Kaufman's approximation drops the second term, exact only at a zero residual.
        matrix, linear, _, fac = self.solve(params)
        k = fac.rank
        q, r_tri = fac.q[:, :k], fac.r[:k, :k]
        resid = self.builder.y - matrix @ linear
        cols = []
        for d in self.builder.matrix_derivatives(params):
            v = d @ linear
            w = ((d.T @ resid) / fac.scale)[fac.perm[:k]]
            z = scipy.linalg.solve_triangular(r_tri, w, trans="T")
            cols.append(-(v - q @ (q.T @ v)) - q @ z)
        return np.column_stack(cols)

    def covariance(self, linear, params, rss):
        return parameter_covariance(self.builder.jacobian(linear, params), rss,
                                    self.builder.n_samples)


class _FullMatrixBuilder:
    """A :class:`fohw.RegressorBuilder` whose :meth:`jacobian` is the reference one.

    The reference Jacobian forms ``Phi`` and every ``dPhi/dparams[m]`` in full and multiplies
    (what :meth:`fohw.RegressorBuilder.jacobian` did before it wrote the columns in place);
    everything else is the builder's.
    """

    def __init__(self, builder):
        self._builder = builder

    def __getattr__(self, name):
        return getattr(self._builder, name)

    def jacobian(self, linear, params):
        linear = np.asarray(linear, dtype=np.float64)
        n = linear.shape[0]
        derivs = self._builder.matrix_derivatives(params)
        G = np.empty((self._builder.n_samples, n + len(derivs)))
        G[:, :n] = self._builder.matrix(params)
        for m, d in enumerate(derivs):
            G[:, n + m] = d @ linear
        return G


def separable_least_squares(builder, *, bounds, options=None, _reference=False):
    """Separable least-squares estimate of the linear and nonlinear parameters of one record.

    Parameters
    ----------
    builder : RegressorBuilder
        The record and the model class (:attr:`RegressorBuilder.structure`).
    bounds : (array_like, array_like)
        Lower and upper bounds of each free order (past levels are unbounded).
    options : VarproOptions, optional
        Grid, tolerances and polish.
    _reference : bool, optional
        Private: the full-matrix solves of fohw before the blocked ones (:class:`_FullMatrixProfile`),
        for the tests and benchmarks that compare the two.

    Returns
    -------
    _VarproFit
        Internal record; :func:`fohw.identify` wraps it into an ``IdentificationResult``.
    """
    opts = (options or VarproOptions()).check()
    s = builder.structure
    check_enough_samples(builder.n_samples, s)
    lo = np.atleast_1d(np.asarray(bounds[0], dtype=float))
    hi = np.atleast_1d(np.asarray(bounds[1], dtype=float))
    if _reference:
        builder = _FullMatrixBuilder(builder)
    profile = (_FullMatrixProfile if _reference else _Profile)(builder)
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
        status = (Status.CONVERGED if ls.status > 0 else
                  Status.MAX_ITER if ls.status == 0 else Status.FAILED)
        message += f"; polish (scipy.optimize.least_squares): {ls.message}"
        fac = None
    cov, s2 = profile.covariance(linear, params, rss)
    return _VarproFit(linear=linear, params=params, rss=rss, grid=grid, grid_J=grid_J,
                      search_alphas=search[0], search_J=search[1], status=status, nit=nit,
                      nfev=nfev, message=message, at_lower=np.asarray(at_lower, dtype=bool),
                      at_upper=np.asarray(at_upper, dtype=bool), covariance=cov,
                      noise_variance=s2, rank_factor=fac)


def _linear_only(builder, profile):
    """Every order fixed and no past levels: one linear least-squares solve."""
    linear, rss, fac = profile(np.zeros(0))
    cov, s2 = profile.covariance(linear, np.zeros(0), rss)
    return _VarproFit(linear=linear, params=np.zeros(0), rss=rss, grid=np.zeros(0),
                      grid_J=np.zeros(0), search_alphas=[], search_J=[],
                      status=Status.CONVERGED, nit=0, nfev=1,
                      message="converged: linear least squares (every order fixed)",
                      at_lower=np.zeros(0, bool), at_upper=np.zeros(0, bool), covariance=cov,
                      noise_variance=s2, rank_factor=fac)


def _scalar_search(builder, profile, lo, hi, opts):
    """One free order: a grid scan inside the bounds, then Brent's bounded search."""
    n_samples = builder.n_samples
    grid = np.linspace(lo, hi, opts.n_grid + 2)[1:-1]
    grid_J = np.array([profile(a)[1] for a in grid]) / n_samples
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
                                         options={"xatol": opts.xtol, "maxiter": 500})
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
    grid_J = np.array([profile(p)[1] for p in grid_points]) / n_samples
    if n_free in _FULL_GRID:
        # The profile of two or three orders can have several minima along a curved valley
        # (a noise-free record with two tied orders had one at J = 2e-7 beside the true
        # J = 0, both off the tied line): the local minima of a full grid are the starts.
        m = _FULL_GRID[n_free]
        axes = [lo[j] + np.linspace(0.0, 1.0, m + 2)[1:-1] * (hi[j] - lo[j])
                for j in range(n_free)]
        mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n_free)
        values = np.array([profile(np.r_[p, np.zeros(n_past)])[1] for p in mesh])
        cube = values.reshape((m,) * n_free)
        minima = np.flatnonzero(cube == scipy.ndimage.minimum_filter(cube, size=3,
                                                                     mode="nearest"))
        starts = [np.r_[mesh[i], np.zeros(n_past)]
                  for i in minima[np.argsort(values[minima])][:4]]
        origin = f"the minima of a {m}^{n_free} grid"
    else:
        interior = [i for i in range(len(grid_J))
                    if (i == 0 or grid_J[i] <= grid_J[i - 1])
                    and (i == len(grid_J) - 1 or grid_J[i] <= grid_J[i + 1])]
        starts = [grid_points[i] for i in sorted(interior, key=lambda i: grid_J[i])[:3]]
        origin = "the tied-order scan"
        if n_free > 1:
            # More orders: one sweep of one-order scans from the best tied point, each order
            # over its bounds with the others held, gives a start off the diagonal.
            point = starts[0].copy()
            for j in range(n_free):
                trial = []
                for t in tau:
                    p = point.copy()
                    p[j] = lo[j] + t * (hi[j] - lo[j])
                    trial.append((profile(p)[1], p))
                point = min(trial, key=lambda item: item[0])[1]
            starts.insert(0, point)
            origin = "one sweep of one-order scans and the tied-order scan"
    y = builder.y
    y_scale = rms_scale(y)
    lower = np.r_[lo, np.full(n_past, -np.inf)]
    upper = np.r_[hi, np.full(n_past, np.inf)]

    def residual(params):
        return profile.residual(params) / y_scale

    def golub_pereyra(params):
        return profile.golub_pereyra(params) / y_scale

    best, nit = None, 0
    for x0 in starts:
        x0 = np.clip(x0, lower, upper)
        ls = scipy.optimize.least_squares(residual, x0, jac=golub_pereyra, bounds=(lower, upper),
                                          method="trf", x_scale="jac", ftol=opts.tol,
                                          xtol=opts.tol, gtol=opts.tol)
        nit += int(ls.njev)
        if best is None or ls.cost < best.cost:
            best = ls
    message = f"variable projection from {len(starts)} start(s) ({origin}): {best.message}"
    grid = lo[0] + tau * (hi[0] - lo[0]) if n_free else tau
    return best.x, ([], []), grid, grid_J, nit, best.status > 0, message


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
    x, _, ls = bounded_least_squares(residual, np.r_[linear, params], jac=jacobian, lower=lower,
                                     upper=upper, ftol=opts.tol, xtol=opts.tol, gtol=opts.tol,
                                     max_nfev=opts.max_nfev)
    rss = float(ls.fun @ ls.fun) * y_scale * y_scale      # inf, not OverflowError
    return x[:n], x[n:], rss, ls


@thin_solves
def varpro_result(builder, options, bounds, *, operating_point=(0.0, 0.0), _reference=False):
    """Run separable least squares and wrap it as an IdentificationResult.

    ``bounds`` is ``(lower, upper)`` over the free orders (:func:`fohw.identify` builds it);
    ``_reference`` as in :func:`separable_least_squares`.
    """
    s = builder.structure
    lo, hi = bounds
    fit = separable_least_squares(builder, bounds=(lo, hi), options=options,
                                  _reference=_reference)
    message = fit.message
    for m, name in enumerate(s.orders.free):
        if fit.at_lower[m] or fit.at_upper[m]:
            message += bound_note(name, lo[m], hi[m], fit.at_lower[m], fit.at_upper[m])
    record = dict(options.as_dict(), alpha_bounds=_bounds_record(s, lo, hi))
    profile = np.vstack([fit.grid, fit.grid_J]) if fit.grid.size else None
    rank_factor = fit.rank_factor
    if rank_factor is None and not _reference:      # after the polish: the final Phi's rank
        rank_factor = _rank_factor(builder, fit.params)
    return finish(builder, method="varpro", linear=fit.linear, params=fit.params,
                  status=fit.status, nit=fit.nit, nfev=fit.nfev, message=message,
                  alpha_at_bound=bool(np.any(fit.at_lower) or np.any(fit.at_upper)),
                  options=record, rank_factor=rank_factor, covariance=fit.covariance,
                  noise_variance=fit.noise_variance,
                  alpha_history=fit.search_alphas or None, J_history=fit.search_J or None,
                  alpha_profile=profile, operating_point=operating_point)


def _bounds_record(structure, lo, hi):
    """``alpha_bounds`` as given back in the result: a pair, or one pair per free order."""
    if len(set(zip(lo.tolist(), hi.tolist()))) <= 1 and lo.size:
        return (float(lo[0]), float(hi[0]))
    return {name: (float(a), float(b)) for name, a, b in zip(structure.orders.free, lo, hi)}
