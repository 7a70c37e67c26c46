"""Closed-form responses on non-uniform instants for tests/test_irregular.py: no fohw code.

The input of a record on instants ``t_0 < … < t_{N-1}``, at rest before
``t_{-1} = t_0 - (t_1 - t_0)``, ``u_0`` held on ``(t_{-1}, t_0]`` (fohw's sample alignment):

- zero-order hold: ``u(t) = u_k`` on ``(t_{k-1}, t_k]``: steps of size ``u_0`` at ``t_{-1}`` and
  ``u_k - u_{k-1}`` at ``t_{k-1}``; the response is the sum of shifted step responses ``S``;
- first-order hold: a step of ``u_0`` at ``t_{-1}`` and ramps whose slope changes at each
  instant (slope 0 on the first interval); the response adds shifted ramp responses
  ``Q(x) = int_0^x S``.

Step responses: the RC element ``R (1 - exp(-x / tau))``; one fractional element
``1 / ((tau s)^alpha + 1)``: ``1 - E_alpha(-(x / tau)^alpha)``, at alpha = 1/2
``1 - erfcx(sqrt(x / tau))`` (scipy), whose integral is
``x - tau (erfcx(sqrt(x / tau)) - 1 + 2 sqrt(x / (pi tau)))``; any alpha by the Mittag-Leffler
series summed in 50-digit arithmetic (mpmath).
"""

import math

import numpy as np
from scipy.special import erfcx


def half_step(x, tau):
    """Step response of 1 / ((tau s)^0.5 + 1): 1 - erfcx(sqrt(x / tau)) for x > 0, else 0."""
    x = np.asarray(x, dtype=float)
    r = np.sqrt(np.maximum(x, 0.0) / tau)
    return np.where(x > 0, 1.0 - erfcx(r), 0.0)


def half_ramp(x, tau):
    """Ramp response (integral of half_step): x - tau (erfcx(r) - 1 + 2 r / sqrt(pi)), r = sqrt(x / tau)."""
    x = np.asarray(x, dtype=float)
    r = np.sqrt(np.maximum(x, 0.0) / tau)
    return np.where(x > 0, x - tau * (erfcx(r) - 1.0 + 2.0 * r / math.sqrt(math.pi)), 0.0)


def rc_step(R, tau):
    return lambda x: np.where(np.asarray(x) > 0, R * -np.expm1(-np.maximum(x, 0.0) / tau), 0.0)


def rc_ramp(R, tau):
    """R (x - tau (1 - exp(-x/tau))) = R tau (z + expm1(-z)), z = x / tau; its series below z = 0.5
    (the two terms cancel there)."""
    def ramp(x):
        z = np.maximum(np.asarray(x, dtype=float), 0.0) / tau
        series = sum((-z) ** n / math.factorial(n) for n in range(2, 24))
        return np.where(z > 0, R * tau * np.where(z < 0.5, series, z + np.expm1(-z)), 0.0)
    return ramp


def ml_step(alpha, tau, digits=50):
    """Step response 1 - E_alpha(-(x/tau)^alpha) by the series in `digits`-digit arithmetic."""
    mpmath = __import__("mpmath")

    def one(x):
        if x <= 0:
            return 0.0
        with mpmath.workdps(digits):
            z = -mpmath.mpf(x / tau) ** alpha
            total, k = mpmath.mpf(0), 0
            while True:
                term = z ** k / mpmath.gamma(alpha * k + 1)
                total += term
                if k > 10 and abs(term) < mpmath.mpf(10) ** (-30):
                    break
                k += 1
            return float(1 - total)
    return lambda x: np.array([one(float(v)) for v in np.ravel(x)]).reshape(np.shape(x))


def _extended(t, u):
    t, u = np.asarray(t, float), np.asarray(u, float)
    return np.concatenate([[2 * t[0] - t[1]], t]), np.concatenate([u[:1], u])


def zoh_response(t, u, step, magnitude=False):
    """Output at t of the zero-order-held input (module notes), `step` the step response."""
    t0 = np.asarray(t, float)
    t, u = _extended(t, u)
    jumps = np.diff(np.concatenate([[0.0], u[1:]]))         # at t_0, t_1, ..., t_{N-2}
    if magnitude:                   # sum of |terms|: the reference's rounding is eps times it
        return np.array([np.sum(np.abs(jumps * step(tk - t[:-1]))) for tk in t0])
    return np.array([np.sum(jumps * step(tk - t[:-1])) for tk in t0])


def foh_response(t, u, step, ramp, magnitude=False):
    """Output at t of the first-order-held input: a step u_0 at t_{-1} and ramps (module notes)."""
    t0 = np.asarray(t, float)
    t, u = _extended(t, u)
    slopes = np.diff(u) / np.diff(t)                       # on (t_{k-1}, t_k]
    changes = np.diff(np.concatenate([[0.0], slopes]))     # at t_0, ..., t_{N-2}
    if magnitude:
        return np.array([abs(u[0] * step(tk - t[0])) + np.sum(np.abs(changes * ramp(tk - t[:-1])))
                         for tk in t0])
    return np.array([u[0] * step(tk - t[0]) + np.sum(changes * ramp(tk - t[:-1])) for tk in t0])


def instants(n, seed, low=0.05, high=0.15):
    """Irregular instants: t_0 = 0, steps uniform in [low, high]."""
    rng = np.random.default_rng(seed)
    return np.concatenate([[0.0], np.cumsum(rng.uniform(low, high, n - 1))])
