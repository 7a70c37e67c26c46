"""The simulator's compiled leaf against its pure-Python leaf, and the shared FFT merge (issue 15).

The compiled leaf (``fohw[fast]``, numba) must give the numbers of the pure leaf at every
sample, raise the same divergence, and be replaceable by the pure leaf (no numba, or switched
off). The merge of the divide and conquer is checked against direct sums.
"""

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

import fohw
from fohw.model import _compiled, system
from fohw.model._online import HalfMerge, divide_and_conquer

# The comparisons need numba and the compiled leaf switched on (not FOHW_NO_NUMBA=1); the test
# extra installs numba, so CI runs them.
needs_numba = pytest.mark.skipif(importlib.util.find_spec("numba") is None
                                 or not _compiled.ENABLED,
                                 reason="numba not installed or FOHW_NO_NUMBA set")

EPS = np.finfo(float).eps


def lin():
    return fohw.polynomial_basis(1)


STRUCTURES = {
    "paper": fohw.datasets.paper_model,
    # several orders, one accumulator each
    "per_lag": lambda: fohw.HammersteinWiener(
        [0.3, -0.1], [1.0, 0.4], [1.0, 0.2], [1.0, -0.05],
        {"alpha_a1": 0.3, "alpha_a2": 0.7, "alpha_b1": 0.5, "alpha_b2": 1.2}, orders="per_lag"),
    # order-0 (memoryless) and fractional accumulators on the same signal
    "mixed": lambda: fohw.HammersteinWiener(
        [0.5, 0.2, -0.1, 0.05], [1.0, 0.4, 0.3, -0.2], [1.0], [1.0], 0.45, orders="mixed"),
    # dt != 1, an offset and an operating point
    "offset_dt_point": lambda: fohw.HammersteinWiener(
        [0.5, 0.2], [1.0, 0.3], [1.0], [1.0], 0.35, orders="mixed", dt=4.0, offset=0.7,
        operating_point=(2.0, 5.0)),
    # past levels, dt = 0.5, a fixed order 0 and a free order per lag
    "past": lambda: fohw.HammersteinWiener(
        [0.3, 0.2, 0.1, -0.1], [1.0, 0.5], [1.0, 0.2], [1.0, 0.1], {"alpha": 0.55},
        orders=fohw.Orders([(1, 0.0), (1, "alpha"), (2, 0.0), (2, "alpha")],
                           [(1, 0.0), (1, "alpha")]),
        past=(0.6, -0.4), dt=0.5),
    # an order above 1 on the output
    "order_1.4": lambda: fohw.HammersteinWiener([0.2, -0.1], [0.8], [1.0, 0.5], [1.0], 1.4,
                                                f_basis={"u": lambda x: x, "tanh": np.tanh}),
}


@pytest.fixture
def small_leaves(monkeypatch):
    """Divide and conquer from 100 samples on, with the same small leaves for both leaves."""
    monkeypatch.setattr(system, "FAST_SIMULATION_THRESHOLD", 100)
    monkeypatch.setattr(system, "_LEAF", 48)
    monkeypatch.setattr(system, "_LEAF_COMPILED", 48)
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
        compiled, pure = both(lambda: fohw.simulate_theta(
            th, 0.6, u, na=na, nb=2, f_basis=2, g_basis=g), monkeypatch)
        np.testing.assert_array_equal(compiled, pure)
    # A measured history (the first outputs are fixed, not computed).
    model = STRUCTURES["past"]()
    hist = (rng.uniform(-1, 1, 300), rng.uniform(-1, 1, 300))
    compiled, pure = both(lambda: fohw.simulate(model, u, history=hist), monkeypatch)
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
def test_default_leaves_agree_to_fft_rounding(monkeypatch):
    # The default leaf sizes differ (pure 256, compiled 512), so the merges cut the record
    # differently and round differently. One FFT convolution sample errs by at most about
    # eps * log2(nfft) * ||z|| * ||beta|| (2-norms); each accumulator sample gathers one merge
    # per level (log2(N / leaf) of them) and y[k] weighs two accumulator samples by |a_i|.
    m = fohw.datasets.paper_model()
    rng = np.random.default_rng(0)
    n = 20_000
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
    v = 0.1 * rng.standard_normal(n)
    assert _compiled.load() is not None
    compiled, pure = both(lambda: fohw.simulate(m, u, noise=v), monkeypatch)
    z = m.g_basis.combine(m.q, pure)
    levels = np.log2(n / 128)
    bound = (np.sum(np.abs(m.a)) * levels * EPS * np.log2(2 * n) * np.linalg.norm(z)
             * np.linalg.norm(fohw.gl_weights(m.alpha, n)))
    assert 1e-13 < bound < 1e-10                  # the bound is a rounding level, not a fudge
    np.testing.assert_allclose(compiled, pure, rtol=0, atol=bound)


def test_pure_path_when_switched_off(monkeypatch):
    monkeypatch.setattr(_compiled, "ENABLED", False)
    assert not _compiled.available()
    m = fohw.datasets.paper_model()
    w = np.ones(600)
    out_terms = [(1, 0.6), (2, 0.6)]
    with pytest.raises(RuntimeError, match="not available"):
        system._recursion(m.q[:, None], m.a[None, :], out_terms, m.g_basis, w, 1e8, "fast",
                          kernel="compiled")
    # a non-polynomial output basis never gets the compiled leaf
    monkeypatch.setattr(_compiled, "ENABLED", True)
    assert _compiled.leaf_for(fohw.as_basis([np.sin]), 10**9) is None


@needs_numba
def test_environment_variable_turns_the_compiled_leaf_off():
    code = ("import fohw.model._compiled as c, fohw.model.system as s, numpy as np, fohw;"
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
