"""GL weights expanded in the order (fohw.model.gl_expansion) against exact references.

The weights and their derivatives are compared, weight by weight, with exact rational values
(``fractions``); the windows, at every sample, with the literal double sums of
``tests/reference.py``; the recursions' alpha paths with the reference implementation that
rebuilds each window from the weights (``tests/reference_estimators.py``).
"""

import warnings
from fractions import Fraction

import numpy as np
import pytest
import reference
from reference_estimators import ReferenceRLS, rebuilt_windows

import fohw
from fohw._validation import AlphaBounds
from fohw.estimators.hybrid import (
    HybridOptions,
    SingleInnovationGradientOptions,
    SingleInnovationLMOptions,
    run_alternation,
)
from fohw.exceptions import ParameterError
from fohw.model.gl import gl_weights_unchecked
from fohw.model.gl_expansion import ExpandedWindows, GLExpansion, StreamedWindows
from fohw.model.lagged.regressors import WindowKernel

U = np.finfo(float).eps / 2


def exact_weights(alpha, n):
    """``beta_j`` and ``d beta_j / d alpha`` as exact fractions, ``alpha`` rational, non-integer."""
    beta, dbeta = [Fraction(1)], [Fraction(0)]
    b, s = Fraction(1), Fraction(0)
    for i in range(1, n):
        b *= (i - 1 - alpha) / Fraction(i)
        s += 1 / (alpha + 1 - i)
        beta.append(b)
        dbeta.append(b * s)
    return np.array([float(v) for v in beta]), np.array([float(v) for v in dbeta])


ORDERS = [Fraction(1, 1000), Fraction(3, 10), Fraction(3, 5), Fraction(999, 1000)]


@pytest.mark.parametrize("lo, hi, alpha", [(lo, hi, a) for lo, hi in
                                           [(0.0, 1.001), (0.0, 2.1), (0.3, 0.7)]
                                           for a in ORDERS if lo <= a <= hi])
def test_weights_and_derivative_equal_exact_values_within_the_bound(lo, hi, alpha):
    n = 1500
    ex = GLExpansion(lo, hi, n)
    assert ex.error_bound <= 1e-16
    beta, dbeta = exact_weights(alpha, n)
    j = np.arange(n)
    deg = ex.degree
    # Rounding allowance (not part of the proven bound): each node weight carries at most
    # (2j + 1) roundings of relative size u, the Chebyshev interpolant amplifies node errors by
    # its Lebesgue constant (<= 2/pi log(deg + 1) + 1), and evaluating sum_m c_m T_m adds at most
    # 2 (deg + 1)^2 u of the largest node weight (derivative: one more factor deg^2 2/(hi - lo)).
    scale = np.max(np.abs([gl_weights_unchecked(a, n) for a in ex.nodes()]), axis=0)
    lebesgue = 2 / np.pi * np.log(deg + 1) + 1
    allowance = (lebesgue * (2 * j + 1) + 2 * (deg + 1) ** 2) * U * scale
    err = np.abs(ex.weights(float(alpha)) - beta)
    assert np.all(err <= ex.error_bound + allowance)
    assert err.sum() <= ex.error_bound + allowance.sum()
    d_allowance = allowance * deg**2 * 2 / (hi - lo)
    d_err = np.abs(ex.weights_derivative(float(alpha)) - dbeta)
    assert np.all(d_err <= ex.derivative_error_bound + d_allowance)


def test_weights_below_the_degree_are_interpolated_exactly():
    # beta_j is a polynomial of degree j: for j <= degree the interpolant is beta_j itself.
    ex = GLExpansion(0.0, 1.0, 10)
    assert ex.degree >= 9 and ex.error_bound == 0.0
    for alpha in (0.0, 0.25, 1.0):
        np.testing.assert_allclose(ex.weights(alpha), reference.gl_weights(alpha, 10),
                                   rtol=0, atol=1e-15)


def test_degree_grows_with_interval_and_length_and_errors_name_arguments():
    assert GLExpansion(0, 1, 10**4).degree < GLExpansion(0, 2, 10**4).degree
    assert GLExpansion(0, 1, 10**3).degree < GLExpansion(0, 1, 10**5).degree
    ex = GLExpansion(0.0, 1.0, 100)
    with pytest.raises(ParameterError, match=r"`alpha` must be in the expansion interval.*1\.5"):
        ex.basis(1.5)
    with pytest.raises(ParameterError, match="`lo` must be below `hi`; got lo=1.0, hi=0.5"):
        GLExpansion(1.0, 0.5, 100)


def literal_window(signals_gl, lags, k, P):
    """Rows phi[k], …, phi[k-P+1] (index >= 0) from differenced signals, written out."""
    rows = []
    for kk in range(k, max(k - P, -1), -1):
        row = []
        for d, lag in zip(signals_gl, lags):
            row += [d[kk - i] if kk - i >= 0 else 0.0 for i in range(1, lag + 1)]
        rows.append(row)
    return np.array(rows)


@pytest.mark.parametrize("max_bytes", [2**28, 20_000])       # one block; many blocks
def test_windows_equal_literal_sums_at_every_sample(max_bytes):
    d = fohw.datasets.paper_example(300, random_state=1)
    b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, na=2, nb=3, f_basis=2, g_basis=3)
    lags = [2, 2, 2, 3, 3]
    ex = GLExpansion(0.0, 1.0, 300)
    windows = ExpandedWindows(b.signals, lags, ex, 4, max_bytes=max_bytes)
    if max_bytes < 2**28:
        assert windows.block < 300
    alphas = [Fraction(3, 5), Fraction(1, 7)]
    ref, ref_dsum = {}, {}
    for a in alphas:
        beta, dbeta = exact_weights(a, 300)
        lit = lambda w: [np.convolve(row, w)[:300] for row in b.signals]   # noqa: E731
        ref[a] = (lit(beta), lit(dbeta))
        ref_dsum[a] = np.abs(np.array(dbeta, dtype=float)).sum()
    atol = 1e-12 * np.abs(b.signals).max()        # as for the FFT GL difference (test_gl.py)
    for k in range(300):
        a = alphas[k % 2]
        got = windows.rows(k, ex.basis_pair(float(a), sensitivity="exact"))
        np.testing.assert_allclose(got[0], literal_window(ref[a][0], lags, k, 4), rtol=0,
                                   atol=atol)
        # the derivative window sums |d beta_j| times the signal: its rounding scales with it
        np.testing.assert_allclose(got[1], literal_window(ref[a][1], lags, k, 4), rtol=0,
                                   atol=atol * max(1.0, float(np.abs(ref_dsum[a]))))
        fd = windows.rows(k, ex.basis_pair(float(a) * 0.999, delta_alpha=1e-3))
        direct = WindowKernel(lags).rows(b.signals, k, 4, [
            gl_weights_unchecked(float(a) * 0.999, max(k, 1)),
            (gl_weights_unchecked(float(a) * 0.999 + 1e-3, max(k, 1))
             - gl_weights_unchecked(float(a) * 0.999, max(k, 1))) / 1e-3])
        np.testing.assert_allclose(fd[0], direct[0], rtol=0, atol=atol)
        # both sides difference weights that agree to about 1e-16 * sum|beta| (<= 2e-16 for
        # alpha <= 1); over the step 1e-3 that is <= 2e-13 * max|x|, inside atol (measured 0.24)
        np.testing.assert_allclose(fd[1], direct[1], rtol=0, atol=atol)


@pytest.mark.parametrize("method, options", [
    ("hybrid", HybridOptions()),
    ("hybrid", HybridOptions(sensitivity="exact", innovation_length=3)),
    ("hybrid", HybridOptions(max_iter=2, forgetting=0.95)),
    ("single_innovation_gradient", SingleInnovationGradientOptions()),
    ("single_innovation_lm", SingleInnovationLMOptions()),
])
def test_recursive_methods_follow_the_reference_alpha_path(method, options):
    # The expanded weights change D by at most error_bound * max|x| (< 1e-16) plus rounding;
    # a wrong index or block would move alpha by far more than 1e-12.
    n = 1500
    d = fohw.datasets.paper_example(n, random_state=3)
    b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3)
    o = options.check(n_samples=n, bounds=(0.0, 1.0))
    with warnings.catch_warnings():     # max_iter=2 may stop at max_iter: not what is tested
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        with rebuilt_windows():
            slow = run_alternation(b, method, o, AlphaBounds((0.0, 1.0)))
        fast = run_alternation(b, method, o, AlphaBounds((0.0, 1.0)))
    assert np.ptp(slow.alpha_sample_history) > 1e-3            # alpha does move
    np.testing.assert_allclose(fast.alpha_sample_history, slow.alpha_sample_history, rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(fast.theta_history, slow.theta_history, rtol=0,
                               atol=1e-12 * np.abs(slow.theta_history).max())


@pytest.mark.parametrize("chunks", [[300], [1, 2, 61, 64, 172], [17] * 17 + [11]])
def test_streamed_windows_equal_literal_sums_at_every_sample(chunks):
    d = fohw.datasets.paper_example(300, random_state=2)
    b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, na=3, nb=2, f_basis=2, g_basis=3)
    lags = [3, 3, 3, 2, 2]
    sw = StreamedWindows(lags, 0.0, 1.0, 3, leaf=8)        # leaf 8: many levels in 300 samples
    ex = sw.expansion
    beta, dbeta = exact_weights(Fraction(2, 5), 300)
    lit = [[np.convolve(row, w)[:300] for row in b.signals] for w in (beta, dbeta)]
    atol = 1e-12 * np.abs(b.signals).max()        # as for the FFT GL difference (test_gl.py)
    dsum = float(np.abs(np.array(dbeta, dtype=float)).sum())   # rounding of the d-window
    v = np.vstack([ex.basis(0.4), ex.basis_derivative(0.4)])
    start = 0
    for c in chunks:
        sw.append(b.signals[:, start:start + c])
        for k in range(start, start + c):
            got = sw.rows(k, v)
            np.testing.assert_allclose(got[0], literal_window(lit[0], lags, k, 3), rtol=0,
                                       atol=atol)
            np.testing.assert_allclose(got[1], literal_window(lit[1], lags, k, 3), rtol=0,
                                       atol=atol * max(1.0, dsum))
        start += c


@pytest.mark.parametrize("P", [1, 3])
def test_rls_follows_the_reference_path_within_its_rounding_sensitivity(P):
    # MI-RLS from S(0) = 1e6 I amplifies rounding: perturbing u by one unit in the last place
    # moves the reference's own path by the amount measured here. The expanded windows must
    # stay within a small multiple of it (a wrong window moves alpha by 1e-2 or more).
    d = fohw.datasets.paper_example(2000, random_state=3)
    STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3, innovation_length=P)

    def run(u, reference):
        return (ReferenceRLS if reference else fohw.estimators.rls.MultiInnovationRLS)(**STRUCT).fit(u, d.y)

    ref = run(d.u, True)
    fast = run(d.u, False)
    assert np.ptp(ref.alpha_history_) > 1e-2
    sens_alpha = sens_theta = 0.0
    for seed in range(4):           # the largest of four one-ulp perturbations of u
        ulp = d.u * (1 + U * np.random.default_rng(seed).choice([-1.0, 1.0], d.u.shape[0]))
        wobble = run(ulp, True)
        sens_alpha = max(sens_alpha, np.abs(wobble.alpha_history_ - ref.alpha_history_).max())
        sens_theta = max(sens_theta, np.abs(wobble.theta_history_ - ref.theta_history_).max())
    assert 0 < sens_alpha < 1e-10
    # The expanded windows are a rounding-level change like those: measured ratios <= 1.06
    # (P = 1 and 3); 3x leaves room for other platforms' rounding, not for a wrong window.
    assert np.abs(fast.alpha_history_ - ref.alpha_history_).max() <= 3 * sens_alpha
    assert np.abs(fast.theta_history_ - ref.theta_history_).max() <= 3 * sens_theta
