"""Independent references for the fractional transfer-function tests: no fohw code.

- the implicit GL recursion written as a literal O(N^2) loop, with weights from scipy's binomial;
- the Mittag-Leffler function E_a(z) by its power series (checked against closed forms);
- exact step and impulse responses of the test systems.
"""

import numpy as np
from scipy.special import binom, erfcx, gamma, rgamma


def gl_weights(alpha, n):
    j = np.arange(n)
    return (-1.0) ** j * binom(alpha, j)


def literal_simulation(num, num_orders, den, den_orders, u, h):
    """y[k] = (sum_m d[m] u[k-m] - sum_{j>=1} c[j] y[k-j]) / c[0], one sample at a time."""
    n = len(u)
    c = sum(a * h ** -al * gl_weights(al, n) for a, al in zip(den, den_orders))
    d = sum(b * h ** -be * gl_weights(be, n) for b, be in zip(num, num_orders))
    y = np.zeros(n)
    for k in range(n):
        f = sum(d[m] * u[k - m] for m in range(k + 1))
        past = sum(c[j] * y[k - j] for j in range(1, k + 1))
        y[k] = (f - past) / c[0]
    return y


def mittag_leffler(alpha, z, beta=1.0, terms=400):
    """E_{alpha,beta}(z) = sum_k z^k / Gamma(alpha k + beta) for moderate |z| (series in float)."""
    z = np.asarray(z, dtype=float)
    out = np.zeros_like(z)
    term_pow = np.ones_like(z)
    for k in range(terms):
        out += term_pow * rgamma(alpha * k + beta)
        term_pow = term_pow * z
        nxt = np.abs(term_pow) * rgamma(alpha * (k + 1) + beta)
        if k > 20 and np.all(nxt < 1e-17 * np.maximum(np.abs(out), 1e-300)):
            break
    return out


def step_ml(alpha, t):
    """Step response of 1/(s^alpha + 1): 1 - E_alpha(-t^alpha)."""
    return 1.0 - mittag_leffler(alpha, -np.asarray(t, float) ** alpha)


def impulse_ml(alpha, t):
    """Impulse response of 1/(s^alpha + 1): t^(alpha-1) E_{alpha,alpha}(-t^alpha)."""
    t = np.asarray(t, float)
    return t ** (alpha - 1) * mittag_leffler(alpha, -t ** alpha, beta=alpha)


# (name, FractionalTF args, exact step, exact impulse)
SYSTEMS = {
    "1/(s+1)": (([1.0], [0.0], [1.0, 1.0], [1.0, 0.0]),
                lambda t: 1 - np.exp(-t), lambda t: np.exp(-t)),
    "1/(s^0.5+1)": (([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
                    lambda t: 1 - erfcx(np.sqrt(t)), lambda t: 1 / np.sqrt(np.pi * t) - erfcx(np.sqrt(t))),
    "1/(s^0.7+1)": (([1.0], [0.0], [1.0, 1.0], [0.7, 0.0]),
                    lambda t: step_ml(0.7, t), lambda t: impulse_ml(0.7, t)),
    "1/(s^1.5+1)": (([1.0], [0.0], [1.0, 1.0], [1.5, 0.0]),
                    lambda t: step_ml(1.5, t), lambda t: impulse_ml(1.5, t)),
    "s^-0.5": (([1.0], [0.0], [1.0], [0.5]),
               lambda t: t ** 0.5 / gamma(1.5), lambda t: t ** -0.5 / gamma(0.5)),
    "s^-1.5": (([1.0], [-1.5], [1.0], [0.0]),
               lambda t: t ** 1.5 / gamma(2.5), lambda t: t ** 0.5 / gamma(1.5)),
}
