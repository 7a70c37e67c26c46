"""Frequency responses of fractional operators, exact and Grünwald–Letnikov-discretised.

Two kernels, each a plain function of arrays:

- :func:`operator_response`: the continuous ``sum_i c_i (j omega)^{nu_i}`` on the principal
  branch, ``(j omega)^nu = |omega|^nu exp(j nu pi/2 sign(omega))``;
- :func:`gl_operator_response`: its Grünwald–Letnikov discretisation with sampling time ``h``,
  ``sum_i c_i ((1 - e^{-j omega h}) / h)^{nu_i}``, the z-domain expression of the GL difference
  (paper Eq. 4) on the unit circle. Any model that is a polynomial in the lag operator and in
  ``(1 - q^{-1})/h`` has its frequency response assembled from these (multiply a term by
  ``e^{-j omega h i}`` for a lag ``i``).
"""

from __future__ import annotations

import numpy as np

from .._validation import check_array
from ..exceptions import DimensionError

__all__ = ["operator_response", "gl_operator_response"]


def _as_terms(coefs, orders):
    coefs = np.atleast_1d(np.asarray(coefs, dtype=np.float64))
    orders = np.atleast_1d(np.asarray(orders, dtype=np.float64))
    if coefs.shape != orders.shape or coefs.ndim != 1:
        raise DimensionError(f"`coefs` and `orders` must be 1-D of the same length; got shapes "
                         f"{coefs.shape} and {orders.shape}.")
    return coefs, orders


def _polar_power(modulus, angle, nu):
    """``(modulus e^{j angle})^nu`` by the polar form; ``0^0 = 1``, ``0^nu = 0`` (nu > 0), inf (nu < 0)."""
    with np.errstate(divide="ignore"):
        mag = np.power(modulus, nu) if nu != 0.0 else np.ones_like(modulus)
    phase = nu * angle
    return mag * (np.cos(phase) + 1j * np.sin(phase))


def operator_response(coefs, orders, omega):
    """``sum_i coefs[i] * (j omega)^orders[i]`` with the principal branch of the power.

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Coefficients and (real) orders of the terms.
    omega : array_like
        Angular frequencies in rad per unit time; negative values give the complex conjugate.

    Returns
    -------
    ndarray of complex, shape of ``omega``

    Notes
    -----
    ``(j omega)^nu = |omega|^nu (cos(nu pi/2) + j sign(omega) sin(nu pi/2))``, evaluated in polar
    form so that the result is exact to rounding (no complex ``log``/``exp`` round trip).

    Examples
    --------
    >>> from fohw.model.frequency_response import operator_response
    >>> operator_response([1.0, 1.0], [1.0, 0.0], [2.0])      # j 2 + 1
    array([1.+2.j])
    """
    coefs, orders = _as_terms(coefs, orders)
    omega = check_array(omega, "omega", ndim=None, min_length=0)
    modulus = np.abs(omega)
    angle = np.sign(omega) * (np.pi / 2)
    out = np.zeros(omega.shape, dtype=complex)
    for c, nu in zip(coefs, orders):
        out += c * _polar_power(modulus, angle, nu)
    return out


def gl_operator_response(coefs, orders, omega, h):
    """``sum_i coefs[i] * ((1 - exp(-j omega h)) / h)^orders[i]``: the GL-discretised operator.

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Coefficients and orders of the terms.
    omega : array_like
        Angular frequencies (rad per unit time), ``|omega| h < 2 pi``.
    h : float
        Sampling time, ``h > 0``.

    Returns
    -------
    ndarray of complex, shape of ``omega``

    Notes
    -----
    ``1 - e^{-j theta} = 2 sin(theta/2) e^{j (pi - theta)/2}`` for ``0 < theta < 2 pi``, so the
    principal power is taken in polar form with modulus ``2 |sin(theta/2)| / h`` and argument
    ``sign(theta) (pi - |theta|)/2``. As ``h -> 0`` it tends to :func:`operator_response`.

    Examples
    --------
    >>> from fohw.model.frequency_response import gl_operator_response
    >>> import cmath
    >>> z = gl_operator_response([1.0], [1.0], [0.5], 0.1)   # (1 - e^{-j 0.05}) / 0.1
    >>> bool(abs(z[0] - (1 - cmath.exp(-0.05j)) / 0.1) < 1e-14)
    True
    """
    coefs, orders = _as_terms(coefs, orders)
    omega = check_array(omega, "omega", ndim=None, min_length=0)
    theta = omega * float(h)
    modulus = 2.0 * np.abs(np.sin(theta / 2.0)) / float(h)
    angle = np.sign(theta) * (np.pi - np.abs(theta)) / 2.0
    out = np.zeros(omega.shape, dtype=complex)
    for c, nu in zip(coefs, orders):
        out += c * _polar_power(modulus, angle, nu)
    return out
