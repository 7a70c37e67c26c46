"""Private least-squares numerics: column equilibration and a rank-revealing QR.

Every least-squares solve and covariance in fohw goes through here, so that results do not
depend on the units of the data (columns are scaled to unit norm before any rank decision) and
rank deficiency is detected and reported instead of producing huge, meaningless estimates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

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


def rank_tolerance(n_rows, n_cols):
    """Relative tolerance of every rank decision: ``max(n_rows, n_cols) * eps``.

    The default ``rcond`` of :func:`factor` and the singular-value tolerance of
    ``numpy.linalg.matrix_rank`` for an ``n_rows x n_cols`` matrix.
    """
    return max(n_rows, n_cols) * np.finfo(float).eps


def factor(a, *, rcond=None, with_q=True) -> Factor:
    """Equilibrate the columns of ``a`` and factor it by QR with column pivoting.

    ``rcond`` defaults to ``max(N, n) * eps``: a column whose component orthogonal to the others
    is smaller than that, relative to the largest, counts as dependent. When ``a`` is rank
    deficient, which columns are named dependent follows one rule, ties to the first column
    (:func:`_pivoted_qr`), so of two identical columns the later one is named, whatever the
    rounding: LAPACK's pivoting breaks such ties by the rounding of the column norms.
    """
    a = np.asarray(a, dtype=np.float64)
    n_rows, n_cols = a.shape
    scale = _column_scale(a)
    if rcond is None:
        rcond = rank_tolerance(n_rows, n_cols)
    if with_q:
        q, r, perm = scipy.linalg.qr(a / scale, mode="economic", pivoting=True,
                                     check_finite=False)
    else:
        r, perm = scipy.linalg.qr(a / scale, mode="r", pivoting=True, check_finite=False)
        q = None
        r = r[:n_cols]
    rank = _rank(r, rcond)
    if rank < n_cols:                # which columns are named dependent: ties to the first
        unpivoted = np.empty_like(r)
        unpivoted[:, perm] = r                        # a / scale = q @ unpivoted
        q2, r, perm = _pivoted_qr(unpivoted)
        rank = _rank(r, rcond)
        q = None if q is None else q @ q2
    return Factor(q=q, r=r, perm=perm, scale=scale, rank=rank)


def _column_scale(a):
    """Euclidean norm of each column (1 for a zero column), without overflow or underflow."""
    scale = np.sqrt(np.einsum("ij,ij->j", a, a))
    tiny = np.finfo(float).tiny ** 0.5
    redo = ~np.isfinite(scale) | (scale < tiny)      # squares overflowed or underflowed
    if np.any(redo):                                  # data in units of 1e+-100 and beyond
        peak = np.max(np.abs(a[:, redo]), axis=0)
        peak[peak == 0] = 1.0
        scale[redo] = peak * np.sqrt(np.einsum("ij,ij->j", a[:, redo] / peak, a[:, redo] / peak))
    scale[scale == 0] = 1.0
    return scale


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


def triangular(blocks, n_cols):
    """Triangular factor ``R`` of the QR of row blocks stacked, never holding them all (TSQR).

    Each block (shape ``(rows, n_cols)``, any number of rows; it is overwritten) is reduced
    to its ``n_cols x n_cols`` triangle by Householder QR, and the stacked triangles are
    reduced again: ``A = Q R`` with the ``R`` of the QR of the whole ``A`` (up to the signs of
    its rows), to rounding, in ``O(rows * n_cols)`` memory. Householder QR is columnwise
    backward stable, so the columns need no scaling first: ``R D`` is the factor of ``A D``.

    Returns
    -------
    r : ndarray, shape (n_cols, n_cols)
        Upper triangular (zero rows if the blocks have fewer rows than columns).
    """
    pieces, n_pieces = [], 0
    for block in blocks:
        pieces.append(_qr_r(block, n_cols))
        n_pieces += 1
        if n_pieces % 256 == 0:                       # keep the stack of triangles small
            pieces = [_qr_r(np.vstack(pieces), n_cols)]
    return _qr_r(np.vstack(pieces) if pieces else np.zeros((0, n_cols)), n_cols)


def triangular_factor(rows, n_rows, n_cols, *, block=8192):
    """Upper-triangular ``R`` with ``A^T A = R^T R``, ``A``'s rows read by ``rows(start, stop)``.

    The matrix is never held whole. The Cholesky factor of the column-scaled Gram matrix is
    used when it is well conditioned (estimated reciprocal condition number above 1e-4, so
    ``cond(A) <~ 1e4`` and the squared condition number costs at most about 8 digits);
    otherwise ``R`` comes from Householder QR over row blocks (:func:`triangular`), which keeps
    the accuracy of ill-conditioned problems (nearly noise-free records).

    Parameters
    ----------
    rows : callable
        ``rows(start, stop)`` returns rows ``start..stop-1`` of ``A``, shape
        ``(stop - start, n_cols)``; it is called twice per block when the Gram matrix is
        ill-conditioned.
    n_rows, n_cols : int
        Shape of ``A``.
    block : int, optional
        Rows read at a time.

    Returns
    -------
    ndarray, shape (n_cols, n_cols)
    """
    gram = np.zeros((n_cols, n_cols))
    for start in range(0, n_rows, block):
        a = rows(start, min(start + block, n_rows))
        gram += a.T @ a
    scale = np.sqrt(np.diag(gram))
    if np.all(scale > 0):
        try:
            r = np.linalg.cholesky(gram / np.outer(scale, scale)).T
        except np.linalg.LinAlgError:
            r = None
        if r is not None:
            rcond, info = scipy.linalg.lapack.dtrcon(r, norm="1", uplo="U")
            if info == 0 and rcond > 1e-4:
                return r * scale
    return triangular((rows(start, min(start + block, n_rows))
                       for start in range(0, n_rows, block)), n_cols)


def full_column_rank(r, n_rows, *, fast_only=False):
    """Whether the triangular factor ``r`` of an ``n_rows``-row matrix has full column rank.

    A cheap LAPACK estimate of the reciprocal condition number settles the usual case
    (``> 1e-8``); otherwise the singular values are compared with :func:`rank_tolerance`
    (``numpy.linalg.matrix_rank``'s), or, with ``fast_only``, ``False`` is returned for the
    caller to decide itself.
    """
    rcond, info = scipy.linalg.lapack.dtrcon(r, norm="1", uplo="U")
    if info == 0 and rcond > 1e-8:
        return True
    if fast_only:
        return False
    sv = np.linalg.svd(r, compute_uv=False)
    return bool(sv[-1] > rank_tolerance(n_rows, r.shape[1]) * sv[0])


def _qr_r(a, n_cols):
    """Upper triangle ``R`` (``n_cols`` rows, zero-padded) of the unpivoted QR of ``a``."""
    r = np.zeros((n_cols, n_cols))
    if a.shape[0]:
        a = np.asfortranarray(a)
        geqrf, = scipy.linalg.get_lapack_funcs(("geqrf",), (a,))
        qr, _, _, info = geqrf(a, overwrite_a=True)
        if info != 0:                                 # pragma: no cover - LAPACK argument error
            raise ValueError(f"LAPACK geqrf failed (info = {info}).")
        k = min(a.shape[0], n_cols)
        r[:k] = np.triu(qr[:k])
    return r


def factor_triangular(r, n_rows, *, rcond=None) -> Factor:
    """:func:`factor` of a tall matrix ``A`` (``n_rows`` rows) given only ``R`` of ``A = Q1 R``.

    The column norms of ``R`` are those of ``A``, and pivoted QR of ``R / scale`` gives the
    pivots and triangle of pivoted QR of ``A / scale`` (``Q1`` is orthonormal): the same rank
    and condition number to rounding, with the default ``rcond`` of ``A``
    (``max(n_rows, n) * eps``). The returned ``q`` is the ``n x n`` factor of ``R / scale``:
    ``A / scale`` permuted is ``(Q1 q) r``. Dependent columns are named by :func:`factor`'s
    rule (ties to the first column), so the blocked and the full-matrix paths name the same.
    """
    n_cols = np.shape(r)[1]
    if rcond is None:
        rcond = rank_tolerance(n_rows, n_cols)
    return factor(r, rcond=rcond)


def _rank(r, rcond):
    """The leading run of diagonal entries above ``rcond * |r[0, 0]|`` (pivoted ``r``)."""
    d = np.abs(np.diag(r))
    if not d.size or not d[0] > 0:
        return 0
    small = np.flatnonzero(d <= rcond * d[0])
    return int(small[0]) if small.size else d.size


#: Remaining column norms within this fraction of the largest are a tie (relative: a nearly
#: independent column of remaining norm 6e-13 must not tie with a dependent one of 1e-16).
_TIE = 2.0 ** -40


def _pivoted_qr(a):
    """Householder QR with column pivoting of a small square matrix, ties to the first column.

    Returns ``q, r, perm`` with ``a[:, perm] = q @ r``. The remaining norms are recomputed
    at every step (``O(n^3)`` in all; ``n`` is the number of parameters).
    """
    r = np.array(a, dtype=np.float64)
    m, n = r.shape
    q = np.eye(m)
    perm = np.arange(n)
    for j in range(min(m, n)):
        norms = np.sqrt(np.einsum("ij,ij->j", r[j:, j:], r[j:, j:]))
        ties = np.flatnonzero(norms >= norms.max() * (1.0 - _TIE))
        pick = j + ties[np.argmin(perm[j + ties])]
        if pick != j:
            r[:, [j, pick]] = r[:, [pick, j]]
            perm[[j, pick]] = perm[[pick, j]]
        x = r[j:, j]
        alpha = np.linalg.norm(x)
        if alpha == 0.0:
            continue
        v = x.copy()
        v[0] += np.copysign(alpha, x[0])
        v /= np.linalg.norm(v)
        r[j:, j:] -= 2.0 * np.outer(v, v @ r[j:, j:])
        q[:, j:] -= 2.0 * np.outer(q[:, j:] @ v, v)
        r[j + 1:, j] = 0.0
    return q, np.triu(r), perm


def lstsq_triangular(r, n_rows, *, rcond=None):
    """:func:`lstsq` from the triangular factor of ``[a, b]`` (:func:`triangular`).

    ``r`` is the ``(n + 1) x (n + 1)`` factor of ``[a, b]``: ``r[:n, :n]`` is that of ``a``,
    ``r[:n, n] = Q1^T b`` and ``|r[n, n]|`` the norm of the part of ``b`` outside the range of
    ``a``. Returns ``(x, rss, fac)`` as :func:`lstsq` does, ``fac`` from
    :func:`factor_triangular`; ``rss = ||r[:n, n] - r[:n, :n] x||^2 + r[n, n]^2``.
    """
    n = r.shape[1] - 1
    fac = factor_triangular(r[:n, :n], n_rows, rcond=rcond)
    k = fac.rank
    z = np.zeros(n)
    if k:
        z[fac.perm[:k]] = scipy.linalg.solve_triangular(fac.r[:k, :k], fac.q[:, :k].T @ r[:n, n],
                                                        check_finite=False)
    x = z / fac.scale
    resid = r[:n, n] - r[:n, :n] @ x
    return x, float(resid @ resid + r[n, n] ** 2), fac


def inverse_gram(jacobian, *, rcond=None):
    """``(G^T G)^{-1}`` from the equilibrated, pivoted QR of ``G`` (never the normal equations).

    Returns ``(inverse, factor)``; the inverse is ``None`` when ``G`` is rank deficient.
    """
    return _inverse_gram(factor(jacobian, rcond=rcond, with_q=False))


def inverse_gram_triangular(r, n_rows, *, rcond=None):
    """:func:`inverse_gram` of a tall ``G`` (``n_rows`` rows) from the ``R`` of ``G = Q1 R``."""
    return _inverse_gram(factor_triangular(r, n_rows, rcond=rcond))


def _inverse_gram(fac):
    n = fac.n_columns
    if fac.rank < n:
        return None, fac
    rinv = scipy.linalg.solve_triangular(fac.r, np.eye(n), check_finite=False)
    inv_perm = np.empty(n, dtype=int)
    inv_perm[fac.perm] = np.arange(n)
    rinv = rinv[inv_perm]                      # rows back in the original column order
    inner = rinv @ rinv.T
    return inner / np.outer(fac.scale, fac.scale), fac
