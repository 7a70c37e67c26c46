"""Literal reference implementations for the tests: the equations written out, no fohw code.

Double loops over samples and lags, GL weights from ``scipy.special.binom``; slow and obviously
right, so that fohw's fast paths can be checked against them at every sample. At the end, the
test harnesses that drive fohw's own engine on paths the package itself never takes.
"""

import numpy as np
from scipy.special import binom


def gl_weights(alpha, n):
    """``(-1)**j binom(alpha, j)``, ``j = 0..n-1`` (SciPy's binomial, not fohw's recurrence)."""
    j = np.arange(n)
    return (-1.0) ** j * binom(alpha, j)


def gl(x, alpha, h=1.0):
    """Eq. (4): ``h**-alpha sum_{j=0}^{k} beta_j x[k-j]`` as a double loop."""
    beta = gl_weights(alpha, len(x))
    return np.array([sum(beta[j] * x[k - j] for j in range(k + 1)) for k in range(len(x))]) \
        / h**alpha


def basis_values(basis, x):
    """Rows ``f_j(x)`` evaluated one sample at a time."""
    return np.array([[float(f(np.array([v]))[0]) for v in x] for f in basis.functions])


def one_step_prediction(u, y, theta, alpha, *, na, nb, f_basis, g_basis):
    """Eq. (19) written out: ``yhat[k] = sum_j sum_i theta[.] (Delta^alpha g_j(y))[k-i] + …``."""
    import fohw

    f_basis, g_basis = fohw.model.basis.as_basis(f_basis), fohw.model.basis.as_basis(g_basis)
    G = [gl(row, alpha) for row in basis_values(g_basis, y)]
    F = [gl(row, alpha) for row in basis_values(f_basis, u)]
    yhat = np.zeros(len(y))
    for k in range(len(y)):
        col = 0
        for Gj in G:
            for i in range(1, na + 1):
                yhat[k] += theta[col] * (Gj[k - i] if k - i >= 0 else 0.0)
                col += 1
        for Fj in F:
            for i in range(1, nb + 1):
                yhat[k] += theta[col] * (Fj[k - i] if k - i >= 0 else 0.0)
                col += 1
    return yhat


def partial_sums(nu, n):
    """``S_t = sum_{j<=t} (-1)**j binom(nu, j)`` by the closed form ``(-1)**t binom(nu-1, t)``."""
    t = np.arange(n)
    if nu == 0:          # weights [1, 0, 0, ...]; SciPy's binom(-1, t) is nan
        return np.ones(n)
    return (-1.0) ** t * binom(nu - 1.0, t)


def gl_with_past(x, nu, level, h=1.0):
    """GL difference of a signal that was ``level`` for all t < 0 (an infinite past at rest).

    ``sum_{j>=0} beta_j x[t-j]``: the finite part as a double loop, the infinite constant tail
    ``level * sum_{j>t} beta_j = level * (S_inf - S_t)`` by the closed-form partial sums, with
    ``S_inf = 1`` for ``nu = 0`` and 0 for ``nu > 0``. Returns the values for t = -1 .. N-1 as
    a function ``value(t)``.
    """
    n = len(x)
    beta = gl_weights(nu, n)
    s = partial_sums(nu, n)
    s_inf = 1.0 if nu == 0 else 0.0

    def value(t):
        if t < 0:
            return level * s_inf / h**nu
        finite = sum(beta[j] * x[t - j] for j in range(t + 1))
        return (finite + level * (s_inf - s[t])) / h**nu
    return value


def simulate_general(model, u, v, history=None):
    """A general HammersteinWiener written out: every term ``c (Delta_h^nu xbar)(k - i)``.

    Follows the definitions literally: deviations from the operating point, signals at their
    past levels before k = 0 (or the measured ``history`` before the record), the offset, and
    each term's own order with the GL sum recomputed from scratch at every sample.
    """
    u0, y0 = model.operating_point
    u_past, y_past = model.past
    out_nu, in_nu = model.structure.orders.values(model.orders)
    out_terms = [(t.lag, nu) for t, nu in zip(model.structure.orders.output, out_nu)]
    in_terms = [(t.lag, nu) for t, nu in zip(model.structure.orders.input, in_nu)]
    h = model.dt

    def fbar(x):
        return sum(p * float(f(np.array([x]))[0]) for p, f in zip(model.p, model.f_basis.functions))

    def gbar(x):
        return sum(q * float(g(np.array([x]))[0]) for q, g in zip(model.q, model.g_basis.functions))

    n_hist = 0
    uu = list(np.asarray(u, dtype=float) - u0)
    vv = list(v)
    fixed = []
    if history is not None:
        n_hist = len(history[0])
        uu = list(np.asarray(history[0], dtype=float) - u0) + uu
        vv = [0.0] * n_hist + vv
        fixed = list(np.asarray(history[1], dtype=float) - y0)
    n = len(uu)
    fu = [fbar(x) for x in uu]
    gy = []
    y = []
    for k in range(n):
        if k < n_hist:
            yk = fixed[k]
        else:
            yk = vv[k] + model.offset
            for (lag, nu), b in zip(in_terms, model.b):
                yk += b * gl_with_past(fu, nu, fbar(u_past), h)(k - lag)
            for (lag, nu), a in zip(out_terms, model.a):
                # gbar(y) is known up to k - 1; pad the list so the helper can index it.
                yk += a * gl_with_past(gy + [0.0] * (n - len(gy)), nu, gbar(y_past), h)(k - lag)
        y.append(yk)
        gy.append(gbar(yk))
    return np.array(y[n_hist:]) + y0


# ---- harnesses that drive fohw's own simulation engine (not independent references) ----------

def simulate_blocks(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold, method="auto"):
    """The paper's commensurate model in block form through the engine, by ``method``.

    ``method`` is ``"auto"``, ``"direct"`` (one leaf, O(N^2)) or ``"fast"`` (divide and conquer):
    the tests compare the two paths of :func:`fohw.model.lagged.simulation.recursion` on the same
    forcing. ``Q, A`` are the fed-back signals and their coefficients, ``pb`` the input blocks.
    """
    from fohw.model.lagged.simulation import forcing, recursion

    out_terms = [(i, alpha) for i in range(1, A.shape[1] + 1)]
    in_terms = [(i, alpha) for i in range(1, pb.shape[1] + 1)]
    w = forcing(pb, in_terms, None, out_terms, f_basis, g_basis, u, v, 1.0, 0.0, (0.0, 0.0))
    return recursion(Q, A, out_terms, g_basis, w, threshold, method)


def simulate_any_order(structure, theta, orders, u):
    """Free run of any theta at any finite orders: the engine's predictor, without the [0, 2] check.

    For test data the model class cannot express (a fractional *sum*, order < 0): ``orders``
    are the free orders' values in order; no offset, past levels at rest, no noise.
    """
    from fohw.model.lagged.simulation import simulate_predictor

    return simulate_predictor(structure, theta, orders, u)
