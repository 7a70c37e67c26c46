"""Poles and stability of a fractional transfer function's denominator ``D(s) = sum_i a_i s^{alpha_i}``.

Two methods, each a plain function:

- **Commensurate orders** (Matignon 1996): if every order is an integer multiple of a base
  ``q``, ``D(s) = P(lambda)`` is a polynomial in ``lambda = s^q``, and the system is stable iff
  every root of ``P`` satisfies ``|arg lambda| > q pi / 2``. The base is found from rational
  approximations of the orders with a bounded denominator (:func:`commensurate_base`).
- **Any orders** (the argument principle on the principal Riemann sheet): the number of zeros of
  ``D`` in the closed right half-plane is ``Z = (alpha_top pi - 2 Delta) / (2 pi)``, with
  ``Delta`` the continuous change of ``arg D(j omega)`` for ``omega`` from ``0`` to ``inf`` and
  ``alpha_top pi`` the change along the large half-circle, where the highest-order term rules
  (:func:`rhp_zero_count`). For commensurate orders both verdicts agree (a test checks it).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..exceptions import ParameterError
from .frequency_response import operator_response

__all__ = ["commensurate_base", "commensurate_polynomial", "matignon_roots", "rhp_zero_count"]

MAX_DEGREE = 400


def commensurate_base(orders, *, max_denominator=100, tol=1e-9):
    """The largest ``q <= 1`` of which every order is an integer multiple, or ``None``.

    Parameters
    ----------
    orders : array_like of float
        Non-negative orders.
    max_denominator : int, optional
        Each order is replaced by its best rational approximation ``n/d`` with ``d <=
        max_denominator`` (:meth:`fractions.Fraction.limit_denominator`); the orders count as
        commensurate only if every approximation is within ``tol`` of the order.
    tol : float, optional
        Absolute tolerance of that rational approximation.

    Returns
    -------
    float or None
        ``q = gcd(numerators) / lcm(denominators)``, divided by ``ceil(q)`` when larger than 1
        (so that ``0 < q <= 1``); ``1.0`` when every order is 0; ``None`` when an order has no
        rational approximation within ``tol``.

    Examples
    --------
    >>> from fohw.model.transfer_stability import commensurate_base
    >>> commensurate_base([1.5, 0.5, 0.0])
    0.5
    >>> commensurate_base([2.0, 1.0]), commensurate_base([2 ** 0.5, 1.0]) is None
    (1.0, True)
    """
    fracs = []
    for a in np.asarray(orders, dtype=np.float64).ravel():
        f = Fraction(float(a)).limit_denominator(int(max_denominator))
        if abs(float(f) - a) > tol:
            return None
        if f != 0:
            fracs.append(f)
    if not fracs:
        return 1.0
    num = 0
    den = 1
    for f in fracs:
        num = math.gcd(num, abs(f.numerator))
        den = den * f.denominator // math.gcd(den, f.denominator)
    q = Fraction(num, den)
    if q > 1:
        q = q / math.ceil(q)
    return float(q)


def commensurate_polynomial(coefs, orders, q):
    """Coefficients (highest power first) of ``P(lambda)`` with ``D(s) = P(s^q)``.

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Terms of ``D(s) = sum_i coefs[i] s^orders[i]``, orders integer multiples of ``q``.
    q : float
        Commensurate base.

    Returns
    -------
    ndarray
        For :func:`numpy.roots`.

    Examples
    --------
    >>> from fohw.model.transfer_stability import commensurate_polynomial
    >>> commensurate_polynomial([1.0, 3.0, 2.0], [1.0, 0.5, 0.0], 0.5)
    array([1., 3., 2.])
    """
    degrees = np.rint(np.asarray(orders, dtype=np.float64) / q).astype(int)
    top = int(degrees.max())
    if top > MAX_DEGREE:
        raise ParameterError(f"the denominator is a polynomial of degree {top} in s^{q:g}; at most "
                             f"{MAX_DEGREE} is handled (use the argument principle instead).")
    poly = np.zeros(top + 1)
    for c, d in zip(coefs, degrees):
        poly[top - d] += c
    return poly


def matignon_roots(coefs, orders, q):
    """Roots ``lambda`` of the polynomial in ``s^q`` and Matignon's verdict.

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Terms of the denominator.
    q : float
        Commensurate base (:func:`commensurate_base`).

    Returns
    -------
    roots : ndarray of complex
        Roots of ``P(lambda)``.
    stable : bool
        ``True`` iff every root has ``|arg lambda| > q pi / 2`` (a root at 0 counts as unstable).

    Examples
    --------
    >>> from fohw.model.transfer_stability import matignon_roots
    >>> roots, stable = matignon_roots([1.0, 1.0], [0.5, 0.0], 0.5)   # s^0.5 + 1: lambda = -1
    >>> roots, stable
    (array([-1.]), True)
    """
    poly = commensurate_polynomial(coefs, orders, q)
    roots = np.roots(poly)
    stable = bool(np.all(np.abs(np.angle(roots)) > q * np.pi / 2)) if roots.size else True
    return roots, stable


def rhp_zero_count(coefs, orders, *, points_per_decade=200, max_points=2_000_000):
    """Zeros of ``D(s) = sum_i coefs[i] s^orders[i]`` in ``Re s >= 0`` (principal sheet, s != 0).

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Terms of ``D``; orders non-negative. A common factor ``s^min(orders)`` is divided out
        first (it is a zero at the origin, which the caller handles).
    points_per_decade : int, optional
        Starting density of the logarithmic frequency grid; it is refined until no step of
        ``arg D(j omega)`` exceeds ``pi / 8``.
    max_points : int, optional
        Upper limit of the grid size.

    Returns
    -------
    count : int
        Number of zeros with ``Re s > 0`` on the principal sheet; ``-1`` when ``D(j omega)``
        vanishes (to within ``1e-10`` of its scale) somewhere on the imaginary axis.

    Notes
    -----
    The frequency grid runs from where the lowest-order term exceeds all others by ``10^6``
    to where the highest-order term does; ``Delta`` is the change of the unwrapped
    ``arg D(j omega)`` over it.

    Examples
    --------
    >>> from fohw.model.transfer_stability import rhp_zero_count
    >>> rhp_zero_count([1.0, 1.0], [0.5, 0.0]), rhp_zero_count([1.0, -1.0], [0.5, 0.0])
    (0, 1)
    """
    coefs = np.asarray(coefs, dtype=np.float64)
    orders = np.asarray(orders, dtype=np.float64)
    keep = coefs != 0.0
    coefs, orders = coefs[keep], orders[keep] - orders[keep].min()
    if coefs.size == 1:
        return 0
    lo = int(np.argmin(orders))
    top = int(np.argmax(orders))
    m = coefs.size
    small = 1e-6 / m
    log_c = np.log10(np.abs(coefs))                 # in logs: the corners may leave the doubles
    log_lo = min((np.log10(small) + log_c[lo] - log_c[i]) / orders[i] for i in range(m) if i != lo)
    log_hi = max((log_c[i] - np.log10(small) - log_c[top]) / (orders[top] - orders[i])
                 for i in range(m) if i != top)
    if log_lo < -300.0 or log_hi * orders[top] > 300.0:     # omega, omega^order stay doubles
        raise ParameterError(
            f"the argument principle needs the frequencies 10**{log_lo:.4g} to 10**{log_hi:.4g} "
            f"(where the lowest and the highest term of the denominator dominate), beyond double "
            f"precision for the orders {orders.tolist()}: the coefficients {coefs.tolist()} span "
            "too many decades. Rescale the time unit, or drop a negligible term.")
    decades = max(log_hi - log_lo, 1.0)
    n = int(points_per_decade * decades) + 1
    while True:
        omega = np.logspace(log_lo, log_hi, n)
        d = operator_response(coefs, orders, omega)
        scale = sum(abs(c) * omega ** a for c, a in zip(coefs, orders))
        if np.min(np.abs(d) / scale) < 1e-10:
            return -1
        phase = np.unwrap(np.angle(d))
        if np.max(np.abs(np.diff(phase))) < np.pi / 8 or 4 * n > max_points:
            break
        n *= 4
    delta = phase[-1] - phase[0]
    return int(round((orders[top] * np.pi - 2.0 * delta) / (2.0 * np.pi)))
