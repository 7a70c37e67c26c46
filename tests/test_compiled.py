"""The compiled leaves (simulator, sensitivity) against their pure-Python leaves, and the FFT merge.

The compiled leaves (``fohw[fast]``, numba; issue 15) must give the numbers of the pure leaves
at every sample, raise the same divergence, and be replaceable by the pure leaves (no numba, or
switched off). The merge of the divide and conquer and the sensitivity's recursion are checked
against direct sums.
"""

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest
from models import MODELS

import fohw
from fohw.model import _compiled
from fohw.model.kernels import HalfMerge, divide_and_conquer
from fohw.model.lagged import sensitivity, simulation

# The comparisons need numba and the compiled leaf switched on (not FOHW_NO_NUMBA=1); the test
# extra installs numba, so CI runs them.
needs_numba = pytest.mark.skipif(importlib.util.find_spec("numba") is None
                                 or not _compiled.ENABLED,
                                 reason="numba not installed or FOHW_NO_NUMBA set")

EPS = np.finfo(float).eps


STRUCTURES = dict(MODELS, **{
    # an order above 1 on the output
    "order_1.4": lambda: fohw.HammersteinWiener([0.2, -0.1], [0.8], [1.0, 0.5], [1.0], 1.4,
                                                f_basis={"u": lambda x: x, "tanh": np.tanh}),
})


@pytest.fixture
def small_leaves(monkeypatch):
    """Divide and conquer from 100 samples on, with the same small leaves for both leaves."""
    monkeypatch.setattr(simulation, "FAST_SIMULATION_THRESHOLD", 100)
    monkeypatch.setattr(simulation, "LEAF_SIZE", 48)
    monkeypatch.setattr(simulation, "LEAF_SIZE_COMPILED", 48)
    assert _compiled.load() is not None


def both(fn, monkeypatch):
    """``fn()`` with the compiled leaf, then with the pure leaf (numba switched off)."""
    assert _compiled.available()
    compiled = fn()
    monkeypatch.setattr(_compiled, "ENABLED", False)
    assert _compiled.leaf_for(fohw.polynomial_basis(2), 10**9) is None
    pure = fn()
    monkeypatch.setattr(_compiled, "ENABLED", True)
    return compiled, pure


# The two leaves run the same IEEE operations in the same order (numba without fastmath does not
# contract a * b + c into an FMA), and each dot product of the leaf's own past is a BLAS ddot in
# both (numpy.dot, and numba's np.dot through SciPy's BLAS), with the merges shared. So the
# results are expected to be identical, not merely close: any difference would mean the two
# leaves do not compute the same thing.
@needs_numba
@pytest.mark.parametrize("name", sorted(STRUCTURES))
def test_compiled_leaf_equals_pure_leaf_at_every_sample(name, small_leaves, monkeypatch):
    model = STRUCTURES[name]()
    assert _compiled.leaf_for(model.g_basis, 1) is not None      # the compiled leaf does run
    rng = np.random.default_rng(11)
    u = rng.uniform(-1, 1, 1500) + model.operating_point[0]
    v = 0.05 * rng.standard_normal(1500)
    compiled, pure = both(lambda: fohw.simulate(model, u, noise=v), monkeypatch)
    np.testing.assert_array_equal(compiled, pure)
    assert np.max(np.abs(pure)) > 0.1                              # not a trivial output


@needs_numba
def test_compiled_leaf_general_theta_and_history(small_leaves, monkeypatch):
    # A general theta: several output signals (Q = I or Q = qa: the powers branch, not Horner).
    m = fohw.datasets.paper_model()
    rng = np.random.default_rng(2)
    theta = m.theta * (1 + 0.05 * rng.standard_normal(m.theta.shape[0]))
    u = rng.uniform(-1, 1, 1200)
    for na, g in ((2, 3), (4, 2)):       # n_g > na: Q = qa; n_g < na: Q = I
        th = np.r_[0.1 * rng.standard_normal(na * g), theta[-4:]]
        compiled, pure = both(lambda th=th, na=na, g=g: fohw.simulate(
            fohw.Structure.make(na=na, nb=2, f_basis=2, g_basis=g), u, params=np.r_[th, 0.6]),
            monkeypatch)
        np.testing.assert_array_equal(compiled, pure)
    # A measured history (the first outputs are fixed, not computed).
    model = STRUCTURES["past"]()
    hist = (rng.uniform(-1, 1, 300), rng.uniform(-1, 1, 300))
    compiled, pure = both(lambda: fohw.simulate(model, u, initial=hist), monkeypatch)
    np.testing.assert_array_equal(compiled, pure)


@needs_numba
@pytest.mark.parametrize("threshold, cause", [(None, "growth"), (1e300, "output_basis")])
def test_compiled_leaf_reports_the_same_divergence(threshold, cause, small_leaves, monkeypatch):
    # A large step at k = 1000 drives the paper's model (cubic g) unstable within a few samples
    # (a sample inside a leaf that is not the first); with the bound at 1e300 the output first
    # overflows in g(y) = y + 0.7 y**2 + 0.35 y**3 (cause output_basis).
    m = fohw.datasets.paper_model()
    u = np.r_[np.random.default_rng(1).uniform(-1, 1, 1000), 4.0 * np.ones(2000)]
    errors = []

    def run():
        with pytest.raises(fohw.SimulationDivergedError) as info:
            fohw.simulate(m, u, divergence_threshold=threshold)
        errors.append(info.value)

    both(run, monkeypatch)
    a, b = errors
    assert (a.sample, a.cause, a.threshold) == (b.sample, b.cause, b.threshold)
    assert a.cause == cause and 1000 < a.sample < 1100
    assert a.value == b.value


@needs_numba
def test_default_leaves_are_equal(monkeypatch):
    # The default leaf sizes of the two simulator leaves are equal, so with the default settings
    # numba changes no simulated sample (above the divide-and-conquer threshold too).
    assert simulation.LEAF_SIZE == simulation.LEAF_SIZE_COMPILED
    m = fohw.datasets.paper_model()
    rng = np.random.default_rng(0)
    n = 20_000
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
    v = 0.1 * rng.standard_normal(n)
    assert n > simulation.FAST_SIMULATION_THRESHOLD and _compiled.load() is not None
    compiled, pure = both(lambda: fohw.simulate(m, u, noise=v), monkeypatch)
    np.testing.assert_array_equal(compiled, pure)


def test_pure_path_when_switched_off(monkeypatch):
    monkeypatch.setattr(_compiled, "ENABLED", False)
    assert not _compiled.available()
    m = fohw.datasets.paper_model()
    w = np.ones(600)
    out_terms = [(1, 0.6), (2, 0.6)]
    with pytest.raises(RuntimeError, match="not available"):
        simulation.recursion(m.q[:, None], m.a[None, :], out_terms, m.g_basis, w, 1e8, "fast",
                             kernel="compiled")
    # a non-polynomial output basis never gets the compiled leaf
    monkeypatch.setattr(_compiled, "ENABLED", True)
    assert _compiled.leaf_for(fohw.model.basis.as_basis([np.sin]), 10**9) is None


def _fresh_state(monkeypatch):
    monkeypatch.setattr(_compiled, "_state", dict(_compiled._state, kernel=None, feedback=None,
                                                  failed=False, error=None, pure_samples=0))


@needs_numba
def test_nowhere_to_write_numba_cache_compiles_without_it(monkeypatch):
    # A read-only install and no writable home: numba.njit(cache=True) raises "cannot cache
    # function ... no locator available"; the leaves are then compiled without a cache.
    import numba

    real = numba.njit
    asked = []

    def njit(*args, cache=False, **kw):
        asked.append(cache)
        if cache:
            raise RuntimeError("cannot cache function '_leaf': no locator available for file")
        return real(*args, cache=cache, **kw)

    _fresh_state(monkeypatch)
    monkeypatch.setattr(numba, "njit", njit)
    assert _compiled.load() is not None and not _compiled._state["failed"]
    assert asked == [True, False, False]
    m = fohw.datasets.paper_model()
    u = np.random.default_rng(1).uniform(-1, 1, 9000)
    compiled, pure = both(lambda: fohw.simulate(m, u), monkeypatch)
    np.testing.assert_array_equal(compiled, pure)


@needs_numba
def test_a_compile_error_falls_back_to_the_pure_leaf_with_one_warning(monkeypatch):
    import numba

    def njit(*args, **kw):
        raise TypeError("a typing error from another numba release")

    _fresh_state(monkeypatch)
    monkeypatch.setattr(numba, "njit", njit)
    with pytest.warns(RuntimeWarning, match="could not compile the leaves .*pure-Python"):
        assert _compiled.load() is None
    assert _compiled._state["failed"] and not _compiled.available()
    assert _compiled.load() is None                     # no second attempt, no second warning
    m = fohw.datasets.paper_model()
    y = fohw.simulate(m, np.random.default_rng(1).uniform(-1, 1, 2**18))   # above LOAD_AFTER
    assert np.all(np.isfinite(y))


@needs_numba
def test_environment_variable_turns_the_compiled_leaf_off():
    code = ("import fohw.model._compiled as c, numpy as np, fohw;"
            "m = fohw.datasets.paper_model();"
            "fohw.simulate(m, np.zeros(300_000));"          # above LOAD_AFTER
            "print(c.available(), c._state['kernel'] is None)")
    env = dict(os.environ, FOHW_NO_NUMBA="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


@pytest.mark.parametrize("n, leaf", [(1000, 64), (777, 50), (4097, 128)])
def test_half_merge_equals_direct_sums(n, leaf):
    # divide_and_conquer + HalfMerge with a leaf that adds the leaf's own past directly gives
    # every convolution sample D[a, t] = sum_{m <= t} w_a[t - m] z[s_a, m] (two signals, three
    # accumulators, two weight vectors, a trailing axis of 2). The FFT sizes are next_fast_len
    # of the segment, smaller than a linear convolution needs: no wrap-around may reach the
    # samples used. Bound: eps * log2(n) * ||z|| ||w|| per sample (as above), about 1e-13.
    rng = np.random.default_rng(n)
    z = rng.standard_normal((2, n, 2))
    w = [fohw.gl_weights(0.6, n), fohw.gl_weights(1.3, n)]
    pairs = [(0, 0, 0), (1, 1, 0), (2, 1, 1)]
    dz = np.zeros((3, n, 2))
    merge = HalfMerge(w, pairs)
    seen = []

    def leaf_fn(lo, hi):
        seen.append((lo, hi))
        for a, s, k in pairs:
            for t in range(lo, hi):
                dz[a, t] += w[k][:t - lo + 1][::-1] @ z[s, lo:t + 1]

    divide_and_conquer(n, leaf, leaf_fn, lambda lo, mid, hi: merge(z, dz, lo, mid, hi))
    assert seen[0][0] == 0 and seen[-1][1] == n and max(h - lo for lo, h in seen) <= leaf
    for a, s, k in pairs:
        for c in range(2):
            want = np.convolve(z[s, :, c], w[k])[:n]
            np.testing.assert_allclose(dz[a, :, c], want, rtol=0, atol=1e-12)


# ---- the sensitivity's compiled leaf (fohw.model.lagged.sensitivity._solve_feedback) ---------------

SENSITIVITY_STRUCTURES = dict(STRUCTURES, **{
    # a non-polynomial output basis: the simulator runs its pure leaf, the sensitivity compiled
    "tanh_output": lambda: fohw.HammersteinWiener(
        [0.4, -0.1], [1.0, 0.5], [1.0, 0.3], [1.0, 0.3], 0.6,
        g_basis={"y": lambda x: x, "tanh": np.tanh}),
})


@pytest.fixture
def small_sensitivity_leaves(small_leaves, monkeypatch):
    """The simulator's small leaves, and leaves of 48 for both sensitivity leaves."""
    monkeypatch.setattr(sensitivity, "LEAF_SIZE", 48)
    monkeypatch.setattr(sensitivity, "LEAF_SIZE_COMPILED", 48)


def both_feedback(fn, monkeypatch):
    """``fn()`` with the compiled sensitivity leaf (counting its calls), then with the pure one."""
    assert _compiled.load() is not None
    calls = []
    kernel = _compiled._state["feedback"]

    def counted(*args):
        calls.append(args[:2])
        return kernel(*args)

    counts = []

    def run():
        out = fn()
        counts.append(len(calls))
        return out

    monkeypatch.setitem(_compiled._state, "feedback", counted)
    compiled, pure = both(run, monkeypatch)
    assert counts[0] > 0, "the compiled sensitivity leaf did not run"
    assert counts[1] == counts[0], "the pure run called the compiled sensitivity leaf"
    return compiled, pure, calls[:counts[0]]


# Same reasoning as for the simulator: the two leaves do the same IEEE operations in the same
# order, the leaf's own past through the same BLAS call (dgemv for d >= 2 columns, ddot for one,
# which is what NumPy's ``rev @ Z`` calls for these shapes), so S must be identical.
@needs_numba
@pytest.mark.parametrize("name", sorted(SENSITIVITY_STRUCTURES))
def test_compiled_sensitivity_leaf_equals_pure_leaf_at_every_sample(
        name, small_sensitivity_leaves, monkeypatch):
    model = SENSITIVITY_STRUCTURES[name]()
    rng = np.random.default_rng(5)
    u = rng.uniform(-1, 1, 1500)

    def run():
        return sensitivity.simulation_jacobian(model.structure, model.linear, model.nonlinear, u)

    (y_c, S_c), (y_p, S_p), segments = both_feedback(run, monkeypatch)
    np.testing.assert_array_equal(y_c, y_p)
    np.testing.assert_array_equal(S_c, S_p)
    assert len(segments) > 16 and max(hi - lo for lo, hi in segments) <= 48
    assert S_p.shape[1] == len(model.linear) + len(model.nonlinear)
    # not trivial: the feedback moves S away from the one-step Jacobian E (S != E) everywhere
    builder = fohw.model.lagged.regressors.RegressorBuilder(u, y_p, structure=model.structure)
    E = builder.jacobian(model.linear, model.nonlinear)
    assert np.all(np.max(np.abs(S_p - E), axis=0) > 1e-3 * np.max(np.abs(S_p), axis=0))


def direct_feedback(E, lags, betas, coefs):
    """The recursion of ``_solve_feedback`` by its definition, one sample at a time (O(N^2))."""
    n, d = E.shape
    S = E.copy()
    for k in range(n):
        for lag, b, c in zip(lags, betas, coefs):
            if k >= lag:
                m = np.arange(k - lag + 1)
                S[k] += (b[k - lag - m] * c[m]) @ S[m]
    return S


@needs_numba
@pytest.mark.parametrize("d", [1, 2, 7])
def test_compiled_sensitivity_leaf_on_the_recursion_itself(d, monkeypatch):
    # _solve_feedback with random E (d = 1 takes the ddot branch), three terms (two sharing an
    # order, one of order 0, lags 1, 2, 3), several leaf sizes: compiled == pure exactly, and
    # both equal the direct sums to rounding. The recursion is stable here (|c| <= 0.3, the
    # weights' absolute sums at most 2), so the error is that of the sums: per sample at most
    # about eps * log2(n) * sum |terms| (FFT merges and dot products), bounded below by
    # eps * n * max|S| * sum_t max|c_t| * sum|beta_t| (a generous multiple of the first).
    rng = np.random.default_rng(d)
    n = 700
    E = rng.standard_normal((n, d))
    b06 = fohw.gl_weights(0.6, n)
    betas = [b06, b06, fohw.gl_weights(0.0, n)]
    lags = [1, 2, 3]
    coefs = [0.3 * rng.uniform(-1, 1, n), -0.2 * rng.uniform(0, 1, n), 0.1 * np.ones(n)]
    want = direct_feedback(E, lags, betas, coefs)
    bound = (EPS * n * np.max(np.abs(want))
             * sum(np.max(np.abs(c)) * np.sum(np.abs(b)) for b, c in zip(betas, coefs)))
    assert bound < 1e-10
    assert _compiled.load() is not None
    for leaf in (1, 16, 100, 128, 700):
        pure = sensitivity._solve_feedback(E, lags, betas, coefs, kernel="pure", leaf_size=leaf)
        compiled = sensitivity._solve_feedback(E, lags, betas, coefs, kernel="compiled",
                                               leaf_size=leaf)
        np.testing.assert_array_equal(compiled, pure)
        np.testing.assert_allclose(pure, want, rtol=0, atol=bound)
    assert np.max(np.abs(want - E)) > 0.1                  # the feedback is not negligible
    # no output terms: S = E
    np.testing.assert_array_equal(sensitivity._solve_feedback(E, [], [], [], kernel="compiled"),
                                  E)


@needs_numba
def test_output_error_and_crb_are_the_same_with_either_sensitivity_leaf(
        small_sensitivity_leaves, monkeypatch):
    # The entries that use the sensitivity: identify(method="output_error") (its Jacobian and
    # standard errors, with n_init) and crb(noise="output"), on the offset / dt = 4 structure.
    d = fohw.datasets.paper_example(1200, random_state=3)
    model = STRUCTURES["offset_dt_point"]()
    u = np.random.default_rng(4).uniform(-1, 1, 1200) + model.operating_point[0]

    def run():
        res = fohw.identify(d.u, d.y, method="output_error", na=2, nb=2, f_basis=2, g_basis=3,
                            n_init=50)
        return res, fohw.crb(model, u, 0.01, noise="output", parametrisation="structured")

    (r_c, b_c), (r_p, b_p), _ = both_feedback(run, monkeypatch)
    np.testing.assert_array_equal(r_c.theta, r_p.theta)
    np.testing.assert_array_equal(r_c.alpha, r_p.alpha)
    np.testing.assert_array_equal(r_c.covariance, r_p.covariance)
    assert r_c.nit == r_p.nit and r_c.nfev == r_p.nfev
    np.testing.assert_array_equal(b_c.covariance, b_p.covariance)


@needs_numba
def test_sensitivity_default_leaves_are_equal(monkeypatch):
    # The default leaf sizes of the two sensitivity leaves are equal, so with the default
    # settings numba changes no number of the sensitivity (nor of the simulator's, above).
    assert sensitivity.LEAF_SIZE == sensitivity.LEAF_SIZE_COMPILED
    m = fohw.datasets.paper_model()
    u = np.random.default_rng(0).uniform(-1, 1, 3000)
    _, E, lags, betas, coefs = sensitivity._feedback_problem(m.structure, m.linear,
                                                             m.nonlinear, u)
    compiled, pure = both(lambda: sensitivity._solve_feedback(E, lags, betas, coefs),
                          monkeypatch)
    np.testing.assert_array_equal(compiled, pure)


def test_sensitivity_pure_path_when_switched_off(monkeypatch):
    monkeypatch.setattr(_compiled, "ENABLED", False)
    assert _compiled.feedback_leaf_for(10**9) is None
    E = np.ones((300, 2))
    with pytest.raises(RuntimeError, match="not available"):
        sensitivity._solve_feedback(E, [1], [fohw.gl_weights(0.5, 300)], [np.ones(300)],
                                    kernel="compiled")
    # the pure path still solves it: S[k] = 1 + sum_{m <= k-1} beta[k-1-m] S[m]
    S = sensitivity._solve_feedback(E, [1], [fohw.gl_weights(0.5, 300)], [0.5 * np.ones(300)])
    np.testing.assert_allclose(S, direct_feedback(E, [1], [fohw.gl_weights(0.5, 300)],
                                                  [0.5 * np.ones(300)]), rtol=1e-12)


def test_sensitivity_leaf_loads_by_the_same_rule(monkeypatch):
    # Not loaded: a short solve stays pure; a solve of LOAD_AFTER / FEEDBACK_WEIGHT samples, or
    # enough pure samples so far, loads it.
    monkeypatch.setitem(_compiled._state, "kernel", None)
    monkeypatch.setitem(_compiled._state, "feedback", None)
    monkeypatch.setitem(_compiled._state, "pure_samples", 0)
    monkeypatch.setattr(_compiled, "load", lambda: "loaded")
    monkeypatch.setattr(_compiled, "available", lambda: True)
    short = -(-_compiled.LOAD_AFTER // _compiled.FEEDBACK_WEIGHT) - 1     # ceil - 1
    assert _compiled.feedback_leaf_for(short) is None
    _compiled.count_pure(_compiled.LOAD_AFTER)
    monkeypatch.setitem(_compiled._state, "feedback", "feedback kernel")
    assert _compiled.feedback_leaf_for(short) == "feedback kernel"
    monkeypatch.setitem(_compiled._state, "pure_samples", 0)
    assert _compiled.feedback_leaf_for(short + 1) == "feedback kernel"
