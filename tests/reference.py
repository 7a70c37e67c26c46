"""Literal reference implementations for the tests: the equations written out, no fohw code.

Double loops over samples and lags, GL weights from ``scipy.special.binom``; slow and obviously
right, so that fohw's fast paths can be checked against them at every sample.
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

    f_basis, g_basis = fohw.as_basis(f_basis), fohw.as_basis(g_basis)
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
