"""fohw._linalg: which columns a rank-deficient least-squares problem names dependent."""

import numpy as np

from fohw import _linalg

EPS = np.finfo(float).eps


def _orthonormal(n, k, seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((n, k)))
    return q.T


def test_of_identical_columns_the_later_is_named():
    c0, c1, c2 = _orthonormal(500, 3, 0)
    a = np.c_[c0, c1, 3.0 * c0, c2, c1]                 # columns 2 and 4 repeat 0 and 1
    b = c0 + 2.0 * c1 - c2
    x, rss, fac = _linalg.lstsq(a, b)
    assert fac.rank == 3 and list(fac.dependent) == [2, 4]
    np.testing.assert_allclose(x, [1.0, 2.0, 0.0, -1.0, 0.0], atol=10 * EPS)
    assert rss <= (10 * EPS) ** 2 * 6


def test_a_nearly_independent_column_does_not_tie_with_a_dependent_one():
    # c2 = c0 + 6e-13 e is independent at rcond = N eps = 2.2e-13, c1 = c0 exactly is not. An
    # absolute tie window of 2**-40 = 9e-13 made the two tie after the first step, the earlier
    # (dependent) one was taken as pivot, and the solve returned rss 1.0 instead of ~0.
    n = 1000
    c0, e = _orthonormal(n, 2, 1)
    a = np.c_[c0, c0, c0 + 6e-13 * e]
    b = c0 + e                                          # = (1 - s) c0 + s c2, s = 1 / 6e-13
    x, rss, fac = _linalg.lstsq(a, b)
    assert fac.rank == 2 and list(fac.dependent) == [1]
    s = 1.0 / 6e-13
    # The columns' condition number is about s: the solution is good to a few s eps.
    np.testing.assert_allclose(x[2], s, rtol=10 * s * EPS)
    assert x[1] == 0.0
    assert rss <= (10 * s * EPS) ** 2                   # b lies in the span of c0 and c2


def test_rank_is_the_leading_run_of_large_pivots():
    r = np.diag([1.0, 1e-20, 1e-3])                     # a later large entry does not count
    assert _linalg._rank(r, 1e-10) == 1
    assert _linalg._rank(np.diag([2.0, 1.0]), 1e-10) == 2
    assert _linalg._rank(np.zeros((2, 2)), 1e-10) == 0
