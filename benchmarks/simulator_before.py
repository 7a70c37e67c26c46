"""The simulator's recursion before issue 15, kept for ``bench_simulator.py``'s "before" column.

A frozen copy of the simulator's recursion (``fohw.model.lagged.simulation.recursion``) at fe05e02:
leaves of 128 in pure Python, each merge a full zero-padded linear convolution with the weights'
spectrum computed every time. It is not part of the package; ``simulate_before`` runs it in place
of the current recursion.
"""

import math
from unittest import mock

import numpy as np

from fohw.exceptions import SimulationDivergedError
from fohw.model.gl import gl_weights
from fohw.model.kernels import causal_convolve
from fohw.model.lagged import simulation

LEAF = 128


def recursion(Q, A, out_terms, g_basis, w, threshold, leaf_size, h=1.0, y_fixed=None):
    """``fohw.model.lagged.simulation.recursion`` as it was before issue 15 (the benchmark's "before").

    ``y[k] = w[k] + sum_r sum_t A[r, t] (Delta_h^{nu_t} z_r)[k - lag_t]`` (Eqs. 14, 16).

    ``z_r(y) = sum_j Q[j, r] g_j(y)``: for a model ``Q = q``, ``A = a`` (one signal, gbar);
    for a general theta either ``Q = I, A = qa`` or ``Q = qa, A = I``. ``out_terms[t]`` is the
    ``(lag, order)`` of column ``t`` of ``A``. Every (signal, distinct order) pair has an
    accumulator of ``Delta^nu z_r``; order-0 accumulators have no memory (``z_r`` itself).

    O(N log^2 N) by divide and conquer over time: ``solve(l, r)`` first finishes ``[l, mid)``,
    then adds the contribution of ``z[:, l:mid]`` to the accumulators at ``[mid, r)`` with one
    FFT convolution per accumulator, then finishes ``[mid, r)``. Leaves of at most
    ``leaf_size`` samples run the recursion directly, one dot product per accumulator and
    sample; with ``leaf_size >= N`` that is the whole (direct, O(N^2)) simulation. The first
    ``len(y_fixed)`` outputs are not computed but taken from ``y_fixed`` (a measured history).
    """
    n = w.shape[0]
    R = Q.shape[1]
    nus = []
    for _, nu in out_terms:
        if nu not in nus:
            nus.append(nu)
    acc = [(r, nu) for r in range(R) for nu in nus]          # accumulator index -> (signal, nu)
    index = {key: a for a, key in enumerate(acc)}
    terms = [(index[r, nu], lag - 1, float(A[r, t]) * (1.0 if h == 1.0 else h**-nu))
             for r in range(R) for t, (lag, nu) in enumerate(out_terms)]
    betas = {nu: gl_weights(nu, n) for nu in nus if nu != 0.0}
    memory = [(a, r, betas[nu]) for a, (r, nu) in enumerate(acc) if nu != 0.0]
    memoryless = [(a, r) for a, (r, nu) in enumerate(acc) if nu == 0.0]
    zfun = simulation.output_terms(g_basis, Q)
    w = w.tolist()
    n_fixed = 0 if y_fixed is None else y_fixed.shape[0]
    fixed = [] if y_fixed is None else y_fixed.tolist()
    leaf_size = min(leaf_size, n)
    rev_leaf = {id(b): b[:leaf_size][::-1].copy() for _, _, b in memory}
    y = [0.0] * n
    z = np.zeros((R, n))
    dz = np.zeros((len(acc), n))      # contributions gathered so far
    dz_item = dz.item
    isfinite = math.isfinite
    zrows = list(z)                   # 1-D views, one per output signal
    dzrows = list(dz)
    dot = np.dot
    signals = range(R)
    leaf_memory = [(dzrows[a], r, rev_leaf[id(b)]) for a, r, b in memory]
    leaf_memoryless = [(dzrows[a], r) for a, r in memoryless]

    def leaf(lo, hi):
        for k in range(lo, hi):
            if k < n_fixed:
                yk = fixed[k]
            else:
                yk = w[k]
                for a, i, c in terms:
                    if i < k:
                        yk += c * dz_item(a, k - 1 - i)
                if not abs(yk) <= threshold:       # also catches nan
                    raise SimulationDivergedError(k, yk, threshold)
            zk = zfun(yk)
            if not all(isfinite(x) for x in zk):
                raise SimulationDivergedError(k, yk, threshold, "output_basis")
            y[k] = yk
            for r in signals:
                zrows[r][k] = zk[r]
            for row, r, b_rev in leaf_memory:
                row[k] += dot(zrows[r][lo:k + 1], b_rev[leaf_size - (k - lo + 1):])
            for row, r in leaf_memoryless:
                row[k] = zk[r]

    def solve(lo, hi):
        if hi - lo <= leaf_size:
            leaf(lo, hi)
            return
        mid = (lo + hi) // 2
        solve(lo, mid)
        # dz[t] += sum_{m in [lo, mid)} beta[t - m] z[m] for t in [mid, hi); z[mid:hi] is
        # still zero, so this is the causal convolution of z[lo:hi].
        for a, r, beta in memory:
            dz[a, mid:hi] += causal_convolve(z[r, lo:hi], beta[:hi - lo])[mid - lo:]
        solve(mid, hi)

    with np.errstate(over="ignore", invalid="ignore"):
        solve(0, n)
    return np.array(y)


def _as_recursion(Q, A, out_terms, g_basis, w, threshold, method="auto", h=1.0, y_fixed=None, *,
                  kernel=None, leaf_size=None):
    n = w.shape[0]
    if method == "auto":
        method = "fast" if n > simulation.FAST_SIMULATION_THRESHOLD else "direct"
    return recursion(Q, A, out_terms, g_basis, w, threshold, LEAF if method == "fast" else n,
                     h, y_fixed)


def simulate_before(run):
    """``run()`` with the simulator's recursion replaced by the one before issue 15."""
    with mock.patch.object(simulation, "recursion", _as_recursion):
        return run()
