"""Private least-squares numerics: column equilibration and a rank-revealing QR.

Every least-squares solve and covariance in fohw goes through here, so that results do not
depend on the units of the data (columns are scaled to unit norm before any rank decision) and
rank deficiency is detected and reported instead of producing huge, meaningless estimates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

__all__: list[str] = []


@dataclass(frozen=True)
class Factor:
    """Pivoted QR of a matrix with equilibrated columns, ``A D P = Q R``.

    Attributes
    ----------
    q, r : ndarray
        Thin factors of ``A / scale`` with column pivoting ``perm``.
    perm : ndarray of int
        Column order chosen by the pivoting.
    scale : ndarray
        Euclidean norm of each column of ``A`` (1 for a zero column).
    rank : int
        Numerical rank: diagonal entries of ``R`` above ``rcond * |R[0, 0]|``.
    """

    q: np.ndarray | None
    r: np.ndarray
    perm: np.ndarray
    scale: np.ndarray
    rank: int

    @property
    def n_columns(self) -> int:
        """Number of columns of the factored matrix."""
        return self.scale.shape[0]

    @property
    def dependent(self) -> np.ndarray:
        """Indices of the columns the pivoting left out: combinations of the others."""
        return np.sort(self.perm[self.rank:])

    @property
    def condition(self) -> float:
        """Condition number of the equilibrated matrix (its numerical-rank part)."""
        d = np.abs(np.diag(self.r))
        return float(d[0] / d[self.rank - 1]) if self.rank else np.inf


def factor(a, *, rcond=None, with_q=True) -> Factor:
    """Equilibrate the columns of ``a`` and factor it by QR with column pivoting.

    ``rcond`` defaults to ``max(N, n) * eps``: a column whose component orthogonal to the others
    is smaller than that, relative to the largest, counts as dependent.
    """
    a = np.asarray(a, dtype=np.float64)
    n_rows, n_cols = a.shape
    scale = np.sqrt(np.einsum("ij,ij->j", a, a))
    tiny = np.finfo(float).tiny ** 0.5
    redo = ~np.isfinite(scale) | (scale < tiny)      # squares overflowed or underflowed
    if np.any(redo):                                  # data in units of 1e+-100 and beyond
        peak = np.max(np.abs(a[:, redo]), axis=0)
        peak[peak == 0] = 1.0
        scale[redo] = peak * np.sqrt(np.einsum("ij,ij->j", a[:, redo] / peak, a[:, redo] / peak))
    scale[scale == 0] = 1.0
    if rcond is None:
        rcond = max(n_rows, n_cols) * np.finfo(float).eps
    if with_q:
        q, r, perm = scipy.linalg.qr(a / scale, mode="economic", pivoting=True,
                                     check_finite=False)
    else:
        r, perm = scipy.linalg.qr(a / scale, mode="r", pivoting=True, check_finite=False)
        q = None
        r = r[:n_cols]
    d = np.abs(np.diag(r))
    rank = int(np.sum(d > rcond * d[0])) if d.size and d[0] > 0 else 0
    return Factor(q=q, r=r, perm=perm, scale=scale, rank=rank)


def lstsq(a, b, *, rcond=None):
    """Least squares ``min ||a x - b||`` with equilibrated columns and a rank check.

    Returns
    -------
    x : ndarray
        The basic solution: dependent columns (see :attr:`Factor.dependent`) get 0.
    rss : float
        ``||b - a x||^2``, computed from the residual itself.
    fac : Factor
        The factorisation (rank, dependent columns, scale).
    """
    fac = factor(a, rcond=rcond)
    k = fac.rank
    z = np.zeros(fac.n_columns)
    if k:
        z[fac.perm[:k]] = scipy.linalg.solve_triangular(fac.r[:k, :k], fac.q[:, :k].T @ b,
                                                        check_finite=False)
    x = z / fac.scale
    resid = b - a @ x
    return x, float(resid @ resid), fac


def inverse_gram(jacobian, *, rcond=None):
    """``(G^T G)^{-1}`` from the equilibrated, pivoted QR of ``G`` (never the normal equations).

    Returns ``(inverse, factor)``; the inverse is ``None`` when ``G`` is rank deficient.
    """
    fac = factor(jacobian, rcond=rcond, with_q=False)
    n = fac.n_columns
    if fac.rank < n:
        return None, fac
    rinv = scipy.linalg.solve_triangular(fac.r, np.eye(n), check_finite=False)
    inv_perm = np.empty(n, dtype=int)
    inv_perm[fac.perm] = np.arange(n)
    rinv = rinv[inv_perm]                      # rows back in the original column order
    inner = rinv @ rinv.T
    return inner / np.outer(fac.scale, fac.scale), fac
