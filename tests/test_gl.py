"""The GL kernel against independent references at every sample (SPEC §2)."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import binom

import fohw
from fohw.model.gl import past_transient
from fohw.model.kernels import _DIRECT_MAX_LENGTH, _DIRECT_MAX_MEMORY

ALPHAS = [0.1, 0.5, 0.6, 0.999, 1.0, 1.3, 1.75, 1.999]
# Lengths on both sides of the direct/FFT switch, including non-"fast" FFT sizes.
LENGTHS = [1, 2, 7, _DIRECT_MAX_LENGTH, _DIRECT_MAX_LENGTH + 1, 500, 1031]


def direct_gl(x, alpha, memory=None):
    """Literal double sum of Eq. (5) with weights from exact binomials."""
    n = len(x)
    L = n if memory is None else min(memory, n)
    beta = np.array([(-1) ** j * binom(alpha, j) for j in range(L)])
    out = np.zeros(n)
    for k in range(n):
        for j in range(min(k, L - 1) + 1):
            out[k] += beta[j] * x[k - j]
    return out


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("n", LENGTHS)
def test_gl_difference_equals_direct_sum_at_every_sample(alpha, n):
    x = np.random.default_rng(n).standard_normal(n)
    got = fohw.gl_difference(x, alpha)
    np.testing.assert_allclose(got, direct_gl(x, alpha), rtol=0, atol=1e-12 * np.abs(x).max())


@pytest.mark.parametrize("memory", [1, 3, _DIRECT_MAX_MEMORY, _DIRECT_MAX_MEMORY + 1, 400])
def test_short_memory_equals_truncated_sum(memory):
    x = np.random.default_rng(memory).standard_normal(700)
    got = fohw.gl_difference(x, 0.6, memory=memory)
    np.testing.assert_allclose(got, direct_gl(x, 0.6, memory), rtol=0, atol=1e-12 * np.abs(x).max())


def test_memory_longer_than_signal_is_full_memory():
    x = np.random.default_rng(0).standard_normal(300)
    np.testing.assert_allclose(fohw.gl_difference(x, 0.4, memory=10_000), fohw.gl_difference(x, 0.4),
                               rtol=0, atol=1e-14)


def test_no_circular_wraparound():
    # A single spike at the last sample: every earlier output is exactly zero for a linear
    # convolution; a circular (unpadded) FFT convolution would spread it to the start.
    x = np.zeros(4096)
    x[-1] = 1.0
    d = fohw.gl_difference(x, 0.6)
    assert np.max(np.abs(d[:-1])) < 1e-14
    assert d[-1] == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("axis", [0, 1, 2, -1, -2])
def test_batched_along_any_axis(axis):
    rng = np.random.default_rng(3)
    x = rng.standard_normal((5, 200, 3))
    got = fohw.gl_difference(x, 0.7, axis=axis)
    moved = np.moveaxis(x, axis, -1)
    ref = np.apply_along_axis(direct_gl, -1, moved, 0.7)
    np.testing.assert_allclose(np.moveaxis(got, axis, -1), ref, rtol=0, atol=1e-12 * np.abs(x).max())
    assert got.shape == x.shape


@pytest.mark.parametrize("n", [5, 300])
def test_alpha_zero_is_identity_and_integers_are_differences(n):
    x = np.random.default_rng(1).standard_normal(n)
    np.testing.assert_allclose(fohw.gl_difference(x, 0.0), x, rtol=0, atol=1e-14)
    first = np.diff(x, prepend=0.0)
    np.testing.assert_allclose(fohw.gl_difference(x, 1.0), first, rtol=0, atol=1e-13)
    np.testing.assert_allclose(fohw.gl_difference(x, 2.0), np.diff(first, prepend=0.0), rtol=0,
                               atol=1e-13)


def test_sampling_time_scales_by_h_power_alpha():
    x = np.random.default_rng(2).standard_normal(400)
    np.testing.assert_allclose(fohw.gl_difference(x, 0.6, h=0.1), fohw.gl_difference(x, 0.6) / 0.1**0.6,
                               rtol=1e-13)


@settings(max_examples=40, deadline=None)
@given(alpha=st.floats(0.0, 2.0), c1=st.floats(-10, 10), c2=st.floats(-10, 10),
       n=st.integers(1, 400), seed=st.integers(0, 2**32 - 1))
def test_linearity(alpha, c1, c2, n, seed):
    rng = np.random.default_rng(seed)
    x, y = rng.standard_normal((2, n))
    lhs = fohw.gl_difference(c1 * x + c2 * y, alpha)
    rhs = c1 * fohw.gl_difference(x, alpha) + c2 * fohw.gl_difference(y, alpha)
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-11 * (1 + abs(c1) + abs(c2)))


def test_weights_match_exact_rational_binomials():
    # alpha = 3/5 in exact arithmetic: beta_j = (-1)^j * alpha (alpha-1) ... (alpha-j+1) / j!
    alpha = Fraction(3, 5)
    exact = []
    num = Fraction(1)
    for j in range(60):
        if j > 0:
            num *= alpha - (j - 1)
        exact.append((-1) ** j * num / math.factorial(j))
    np.testing.assert_allclose(fohw.gl_weights(0.6, 60), [float(e) for e in exact], rtol=1e-13,
                               atol=0)


def _exact_weights_and_derivative(alpha, n):
    """beta_j and d beta_j / d alpha in rational arithmetic at the double ``alpha``."""
    a = Fraction(alpha)
    beta, dbeta = [Fraction(1)], [Fraction(0)]
    for j in range(1, n):
        c = (j - 1 - a) / j                       # beta_j = beta_{j-1} c_j, dc_j/dalpha = -1/j
        beta.append(beta[-1] * c)
        dbeta.append(dbeta[-1] * c - beta[-2] / j)
    return beta, dbeta


@pytest.mark.parametrize("alpha", [1e-12, -1e-9, 0.999999, 1 - 1e-10, 1 + 1e-10, 2 + 3e-13, 0.6,
                                   1.0, 2.0])
def test_weights_near_integer_orders_have_no_cancellation(alpha):
    # Each factor (j - 1 - alpha)/j costs at most 2 roundings (the subtraction, the division)
    # and the product one more: |beta_j - exact| <= 3 j eps |exact|. The old factors
    # 1 - (alpha + 1)/j lost up to 4e11 eps at alpha = 1e-12 (beta_1 = -alpha to 1e-4).
    n = 60
    exact, dexact = _exact_weights_and_derivative(alpha, n)
    beta = fohw.gl_weights(alpha, n)
    eps = np.finfo(float).eps
    for j in range(n):
        assert abs(Fraction(float(beta[j])) - exact[j]) <= 3 * j * eps * abs(exact[j]), j
    # d beta_j / d alpha = sum_i (prod_{k != i} c_k) (-1/i): each term is within a few j roundings
    # of itself, so the error is bounded by j eps times the sum of the terms' magnitudes (4 j eps:
    # the products, the 1/(i - 1 - alpha) and the running sum). This half is a regression bound:
    # the derivative sets the one factor that can vanish apart, so it had no cancellation before
    # either (the old code passes it; the weights above are what changed).
    a = Fraction(alpha)
    c = [abs((k - 1 - a) / k) for k in range(1, n)]
    dbeta = fohw.model.gl.gl_weights_derivative(alpha, n)
    for j in range(1, n):
        size = Fraction(0)
        for i in range(1, j + 1):
            others = Fraction(1)
            for k in range(1, j + 1):
                if k != i:
                    others *= c[k - 1]
            size += others / i
        assert abs(Fraction(float(dbeta[j])) - dexact[j]) <= 4 * j * eps * size, j


@pytest.mark.parametrize("alpha", ALPHAS + [0.0, 2.0, -0.5])
def test_weights_match_scipy_binom(alpha):
    j = np.arange(200)
    np.testing.assert_allclose(fohw.gl_weights(alpha, 200), (-1.0) ** j * binom(alpha, j),
                               rtol=1e-11, atol=1e-300)


def test_integer_alpha_weights_vanish_exactly():
    assert np.all(fohw.gl_weights(1.0, 50)[2:] == 0)
    assert np.all(fohw.gl_weights(0.0, 50)[1:] == 0)
    np.testing.assert_array_equal(fohw.gl_weights(2.0, 5), [1.0, -2.0, 1.0, 0.0, 0.0])


@pytest.mark.parametrize("alpha", [0.05, 0.3, 0.6, 0.97, 0.9999999, 1.0, 1.0000001, 1.4, 1.95, 2.0])
def test_weight_derivative_matches_central_difference(alpha):
    n, eps = 300, 1e-6
    fd = (fohw.gl_weights(alpha + eps, n) - fohw.gl_weights(alpha - eps, n)) / (2 * eps)
    exact = fohw.model.gl.gl_weights_derivative(alpha, n)
    # Truncation error of the central difference is O(eps**2), rounding O(1e-16 / eps).
    np.testing.assert_allclose(exact, fd, rtol=1e-7, atol=1e-9)


def test_weight_derivative_closed_forms_at_integers():
    j = np.arange(2, 100)
    # alpha = 0: beta_j = -alpha/j + O(alpha^2)  =>  dbeta_j = -1/j for j >= 1.
    d0 = fohw.model.gl.gl_weights_derivative(0.0, 100)
    assert d0[0] == 0
    np.testing.assert_allclose(d0[1:], -1.0 / np.arange(1, 100), rtol=1e-14)
    # alpha = 1: dbeta_1 = -1 and dbeta_j = 1 / (j (j - 1)) for j >= 2.
    d1 = fohw.model.gl.gl_weights_derivative(1.0, 100)
    assert d1[1] == -1.0
    np.testing.assert_allclose(d1[2:], 1.0 / (j * (j - 1)), rtol=1e-14)


def test_accuracy_at_one_million_samples_against_exact_sums():
    n = 10**6
    rng = np.random.default_rng(42)
    x = rng.standard_normal(n)
    alpha = 0.6
    d = fohw.gl_difference(x, alpha)
    # Independent weights (SciPy's binomial). Its relative error grows for large j, but there
    # the weights are below 1e-9 (they decay like j**-1.6), so the sums are exact to 1e-13.
    beta = (-1.0) ** np.arange(n) * binom(alpha, np.arange(n))
    scale = np.abs(x).max()
    for k in [0, 1, 2, 999, 123_457, 500_000, n - 2, n - 1]:
        exact = math.fsum(beta[: k + 1] * x[k::-1])
        assert abs(d[k] - exact) <= 1e-12 * scale, k


@pytest.mark.parametrize("bad", [np.nan, np.inf, "0.5", None])
def test_bad_alpha(bad):
    with pytest.raises(fohw.ParameterError, match="`alpha`"):
        fohw.gl_difference(np.ones(5), bad)


def test_bad_signal_and_options():
    with pytest.raises(fohw.ParameterError, match=r"`x` must contain only finite values.*index 2"):
        fohw.gl_difference([1.0, 2.0, np.nan], 0.5)
    with pytest.raises(fohw.DimensionError, match="`axis`"):
        fohw.gl_difference(np.ones((2, 3)), 0.5, axis=2)
    with pytest.raises(fohw.ParameterError, match="`memory` must be at least 1; got 0"):
        fohw.gl_difference(np.ones(5), 0.5, memory=0)
    with pytest.raises(fohw.ParameterError, match="`h`"):
        fohw.gl_difference(np.ones(5), 0.5, h=0.0)
    with pytest.raises(fohw.DimensionError, match="scalar"):
        fohw.gl_difference(3.0, 0.5)
    with pytest.raises(fohw.ParameterError, match="`n` must be at least 1"):
        fohw.gl_weights(0.5, 0)


def test_input_is_not_modified():
    x = np.random.default_rng(0).standard_normal(300)
    x0 = x.copy()
    fohw.gl_difference(x, 0.5)
    np.testing.assert_array_equal(x, x0)


def test_a_scale_beyond_float_range_names_h():
    """Issue 28 #5: h**-alpha overflowing was a bare OverflowError."""
    with pytest.raises(fohw.ParameterError, match=r"`h` = 1e-300 with the order 2.0 gives the "
                       r"scale h\*\*-order = 10\*\*600, beyond the largest double"):
        fohw.gl_difference(np.ones(10), 2.0, h=1e-300)
    with pytest.raises(fohw.ParameterError, match=r"`h` = 1e-300"):
        past_transient(2.0, 1, 10, h=1e-300)
    # Sums that overflow although the scale does not: named as well, no RuntimeWarning.
    with pytest.raises(fohw.ParameterError, match=r"overflows: with max \|x\| = 1e\+308"):
        fohw.gl_difference(np.full(10, 1e308), -1.0)
    # An underflowing scale is the correctly rounded result 0.
    assert np.array_equal(fohw.gl_difference(np.ones(3), 2.0, h=1e300), np.zeros(3))


@pytest.mark.parametrize("call", [fohw.gl_weights, fohw.model.gl.gl_weights_derivative])
def test_weights_beyond_memory_are_refused_naming_n(call):
    """Issue 28 #5: gl_weights(0.5, 10**12) was numpy's bare MemoryError."""
    with pytest.raises(fohw.ParameterError, match=r"`n` = 1000000000000 needs \d.* TB of "
                       r"memory .*more than this machine's"):
        call(0.5, 10**12)
