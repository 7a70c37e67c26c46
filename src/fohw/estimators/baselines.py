"""A plain integer-order linear output-error baseline (for comparison on real data).

``y[k] = B(q) / F(q) u[k] + e[k]`` with ``B(q) = b_1 q^-1 + … + b_nb q^-nb`` and
``F(q) = 1 + f_1 q^-1 + … + f_nf q^-nf``, fitted by minimising the simulation error with
:func:`scipy.optimize.least_squares`, started from the ARX least-squares estimate with any
unstable pole reflected into the unit circle. Simulation is :func:`scipy.signal.lfilter`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_array, check_int, check_same_length

__all__ = ["LinearOutputError", "fit_linear_output_error"]


@dataclass(frozen=True)
class LinearOutputError:
    """A fitted linear output-error model ``B(q)/F(q)``.

    Attributes
    ----------
    b : ndarray, shape (nb,)
        ``b_1 … b_nb`` (one sample of delay).
    f : ndarray, shape (nf,)
        ``f_1 … f_nf``.
    sse : float
        Simulation sum of squared errors on the fitting data (after ``n_init``).
    converged : bool
    """

    b: np.ndarray
    f: np.ndarray
    sse: float
    converged: bool

    @property
    def n_params(self) -> int:
        """Number of estimated coefficients."""
        return self.b.shape[0] + self.f.shape[0]

    def simulate(self, u):
        """Free-run output for input ``u`` (zero initial conditions)."""
        return scipy.signal.lfilter(np.r_[0.0, self.b], np.r_[1.0, self.f], check_array(u, "u"))


def _stabilise(f):
    roots = np.roots(np.r_[1.0, f])
    outside = np.abs(roots) >= 1
    roots[outside] = 0.99 / np.conj(roots[outside])
    return np.real(np.poly(roots))[1:]


def fit_linear_output_error(u, y, *, nb, nf, n_init=0):
    """Fit ``B(q)/F(q)`` by simulation-error least squares.

    Parameters
    ----------
    u, y : array_like, shape (N,)
    nb, nf : int
        Numerator and denominator orders (``>= 1``).
    n_init : int
        Leading samples left out of the criterion.

    Returns
    -------
    LinearOutputError

    Examples
    --------
    >>> import numpy as np, scipy.signal
    >>> from fohw.estimators.baselines import fit_linear_output_error
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = scipy.signal.lfilter([0, 0.5], [1, -0.8], u)
    >>> m = fit_linear_output_error(u, y, nb=1, nf=1)
    >>> m.b.round(6), m.f.round(6)
    (array([0.5]), array([-0.8]))
    """
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    nb = check_int(nb, "nb", minimum=1)
    nf = check_int(nf, "nf", minimum=1)
    n_init = check_int(n_init, "n_init", minimum=0, maximum=y.shape[0] - 2)
    n = y.shape[0]
    cols = [np.r_[np.zeros(i), -y[: n - i]] for i in range(1, nf + 1)]
    cols += [np.r_[np.zeros(i), u[: n - i]] for i in range(1, nb + 1)]
    arx, *_ = np.linalg.lstsq(np.array(cols).T, y, rcond=None)
    x0 = np.r_[_stabilise(arx[:nf]), arx[nf:]]
    penalty = np.full(n - n_init, 10.0 * np.max(np.abs(y)))

    def residual(x):
        if np.any(np.abs(np.roots(np.r_[1.0, x[:nf]])) >= 1):
            return penalty
        return (y - scipy.signal.lfilter(np.r_[0.0, x[nf:]], np.r_[1.0, x[:nf]], u))[n_init:]

    ls = scipy.optimize.least_squares(residual, x0, method="trf", x_scale="jac")
    return LinearOutputError(b=ls.x[nf:].copy(), f=ls.x[:nf].copy(), sse=float(ls.fun @ ls.fun),
                             converged=ls.status > 0)
