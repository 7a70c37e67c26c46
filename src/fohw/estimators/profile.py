"""The separable problem's profile ``theta(params)``, ``rss(params)``, by blocks of rows (TSQR).

For fixed nonlinear parameters (orders, past levels) the model is linear in theta, so theta is
a linear least-squares solution. :class:`Profile` computes it without forming the ``N x n``
information matrix: the columns of ``Phi`` are lagged views of the GL differences, and the
triangular factor of ``[Phi, y]`` is accumulated over blocks of :data:`BLOCK_ROWS` rows
(:func:`fohw._linalg.triangular`); so are Golub and Pereyra's Jacobian of the profile residual
and the covariance of the estimates. Every solve equilibrates the columns and pivots, so the
estimate does not depend on the units of ``u`` and ``y`` and a rank-deficient matrix is
reported by the columns it makes dependent. Used by :mod:`fohw.estimators.varpro_search`.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .. import _linalg
from ._common import rms_scale, working_scale

__all__ = ["Profile", "BLOCK_ROWS", "row_blocks", "rank_factor", "profile_theta",
           "parameter_covariance"]


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
    >>> from fohw.estimators.profile import profile_theta
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


#: Rows of ``Phi`` per block of the blocked (TSQR) solves: 16384 x 12 doubles, 1.5 MB.
BLOCK_ROWS = 16384


def row_blocks(columns, extra=(), rows=None):
    """Rows of ``[Phi, extra...]`` in Fortran-ordered blocks (of :data:`BLOCK_ROWS` rows).

    One buffer is reused: consume each block before asking for the next.
    """
    rows = BLOCK_ROWS if rows is None else rows
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


class Profile:
    """``theta(params)`` and ``rss(params)`` of the separable problem, by blocks of rows.

    ``Phi(params)`` is never formed: its columns are lagged views of the GL differences
    (:meth:`fohw.model.lagged.regressors.RegressorBuilder.columns`), and the triangular factor of
    ``[Phi, y]`` is
    accumulated over blocks of :data:`BLOCK_ROWS` rows (:func:`fohw._linalg.triangular`,
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
        r = _linalg.triangular(row_blocks(columns, (builder.y,)), columns.n_columns + 1)
        return (columns, *_linalg.lstsq_triangular(r, builder.n_samples))

    def __call__(self, params):
        """``(linear, rss, factor)`` at ``params``."""
        return self.solve(params)[1:]

    @property
    def count(self):
        """Distinct points evaluated."""
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
        # dPhi^T r in units of y (a power of 2, 1 for moderate units): regressors of 1e300
        # times residuals of 1e100 would overflow before the division by the column norms.
        y_unit = float(working_scale(np.log2(rms_scale(builder.y))))
        v, z = [], []
        for m in range(params.shape[0]):
            derivative = builder.columns(params, which=m)
            v.append(derivative.matvec(linear))
            w = (derivative.rmatvec(resid / y_unit) / fac.scale)[fac.perm[:k]] * y_unit
            z.append(scipy.linalg.solve_triangular(r_k, w, trans="T", check_finite=False))
        r = _linalg.triangular(row_blocks(columns, v), n + len(v))
        qtv = (fac.q.T @ r[:n, n:])[:k]                        # Q^T v, first k entries
        out = np.empty((builder.n_samples, len(v)))
        for m in range(len(v)):
            coef = np.zeros(n)
            coef[fac.perm[:k]] = scipy.linalg.solve_triangular(r_k, qtv[:, m] - z[m],
                                                               check_finite=False)
            out[:, m] = _scaled_matvec(columns, coef, fac.scale) - v[m]
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
        r = _linalg.triangular(row_blocks(columns, v), d)
        s2 = rss / (builder.n_samples - d)
        inverse, _ = _linalg.inverse_gram_triangular(r, builder.n_samples)
        return (None if inverse is None else s2 * inverse), s2


def _scaled_matvec(columns, coef, scale):
    """``Phi @ (coef / scale)``, also where ``coef / scale`` overflows but the product does not.

    The columns of data in units of 1e-100 and beyond have norms (``scale``) near the smallest
    double, so ``coef / scale`` can exceed the largest while each column times it is moderate:
    then each equilibrated column ``Phi[:, j] / scale[j]`` is formed and multiplied instead.
    """
    with np.errstate(over="ignore"):
        x = coef / scale
    if np.all(np.isfinite(x)):
        return columns.matvec(x)
    out = np.zeros(columns.n_samples)
    for j in np.flatnonzero(coef):                 # rare: O(N n^2), never at moderate units
        e = np.zeros(columns.n_columns)
        e[j] = 1.0
        out += coef[j] * (columns.matvec(e) / scale[j])
    return out


def rank_factor(builder, params):
    """The rank-revealing factor of ``Phi(params)`` (rank, dependent columns), by blocks."""
    columns = builder.columns(builder.check_params(params))
    r = _linalg.triangular(row_blocks(columns), columns.n_columns)
    return _linalg.factor_triangular(r, builder.n_samples)
