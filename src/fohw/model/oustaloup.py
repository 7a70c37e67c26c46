"""Integer-order approximation of fractional transfer functions in a frequency band (Oustaloup).

FOMCON's ``oustapp``: every term ``c s^{nu}`` is split as ``s^{fix(nu)} s^{r}`` with the
fractional part ``r = nu - fix(nu)`` in ``(-1, 1)``, ``s^{r}`` is replaced by a rational filter, and
numerator and denominator are summed as rational functions. Two filters for ``s^r`` in
``(omega_b, omega_h)`` with ``2N + 1`` zero/pole pairs:

- Oustaloup (FOMCON ``oustafod``): ``K prod_{k=-N}^{N} (s + w'_k) / (s + w_k)`` with
  ``w'_k = omega_b mu^{(k + N + (1 - r)/2) / (2N + 1)}``,
  ``w_k = omega_b mu^{(k + N + (1 + r)/2) / (2N + 1)}``,
  ``mu = omega_h / omega_b`` and ``K = omega_h^r``;
- refined Oustaloup (Xue, Zhao & Chen 2006; FOMCON ``new_fod`` with ``b = 10, d = 9``): the same
  product times ``(d / b)^r (d s^2 + b omega_h s) / (d (1 - r) s^2 + b omega_h s + d r)``.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._validation import check_array, check_int, unpack_pair
from ..exceptions import ParameterError

__all__ = ["oustaloup_filter", "oustaloup_approximation", "OustaloupApproximation"]

METHODS = ("oustaloup", "refined")
#: The largest ``N``: already at ``N = 80`` the polynomial coefficients of a six-decade band leave
#: double precision (measured), and ``np.poly`` of ``2N + 1`` roots costs ``O(N^2)``.
MAX_ORDER = 100
REFINED_B = 10.0
REFINED_D = 9.0


def _check_band(band):
    if isinstance(band, Mapping):
        unpack_pair(band, "band", "(omega_b, omega_h)")
    try:
        lo, hi = (float(v) for v in band)
    except (TypeError, ValueError):
        raise ParameterError(f"`band` must be a pair (omega_b, omega_h); got {band!r}.") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo < hi):
        raise ParameterError(f"`band` must satisfy 0 < omega_b < omega_h < inf; got {band!r}.")
    return lo, hi


def oustaloup_filter(r, band, order, method="oustaloup"):
    """Rational approximation of ``s^r``, ``-1 < r < 1``, as polynomial coefficients.

    Parameters
    ----------
    r : float
        Order of the operator.
    band : (float, float)
        ``(omega_b, omega_h)``.
    order : int
        ``N``; the Oustaloup filter has ``2N + 1`` zeros and poles (the refined one two more).
    method : {"oustaloup", "refined"}, optional
        See the module docstring.

    Returns
    -------
    num, den : ndarray
        Polynomials in ``s``, highest power first (for :func:`numpy.polyval`).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.oustaloup import oustaloup_filter
    >>> num, den = oustaloup_filter(0.5, (1e-2, 1e2), 3)
    >>> g = np.polyval(num, 1j) / np.polyval(den, 1j)
    >>> bool(abs(g / 1j ** 0.5 - 1) < 1e-2)
    True
    """
    if method not in METHODS:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    _check_order(order)
    lo, hi = _check_band(band)
    r = float(r)
    if not -1.0 < r < 1.0:
        raise ParameterError(f"`r` must be in (-1, 1); got {r!r}.")
    n = int(order)
    mu = hi / lo
    k = np.arange(-n, n + 1)
    w_zero = lo * mu ** ((k + n + 0.5 * (1.0 - r)) / (2 * n + 1))
    w_pole = lo * mu ** ((k + n + 0.5 * (1.0 + r)) / (2 * n + 1))
    with np.errstate(over="ignore", invalid="ignore"):
        num = hi ** r * np.poly(-w_zero)
        den = np.poly(-w_pole)
        if method == "refined":
            b, d = REFINED_B, REFINED_D
            num = (d / b) ** r * np.polymul(num, [d, b * hi, 0.0])
            den = np.polymul(den, [d * (1.0 - r), b * hi, d * r])
    if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise ParameterError(_wide_band_text(band, lo, hi, order, "its polynomial coefficients overflow"))
    return num, den


def _check_order(order):
    if isinstance(order, (bool, np.bool_)) or not isinstance(order, (numbers.Integral, np.integer)) \
            or not 1 <= order <= MAX_ORDER:
        raise ParameterError(f"`order` must be an integer from 1 to {MAX_ORDER}; got {order!r}.")


def _wide_band_text(band, lo, hi, order, what):
    return (f"`band` = {band!r} spans {np.log10(hi) - np.log10(lo):.4g} decades: with order N = {order} the "
            f"approximation cannot be represented in double precision ({what}); give a narrower "
            "band around the frequencies of interest (or a lower order).")


def _rational_sum(terms):
    """Sum of rational functions ``P/Q`` (polynomials highest power first)."""
    num, den = np.array([0.0]), np.array([1.0])
    for p, q in terms:
        if q.shape == den.shape and np.array_equal(q, den):
            num = np.polyadd(num, p)
        else:
            num = np.polyadd(np.polymul(num, q), np.polymul(p, den))
            den = np.polymul(den, q)
    return num, den


def _term_rational(c, nu, band, order, method):
    whole = float(np.fix(nu))
    frac = nu - whole
    p, q = (np.array([1.0]), np.array([1.0])) if frac == 0.0 \
        else oustaloup_filter(frac, band, order, method)
    power = np.zeros(int(abs(whole)) + 1)
    power[0] = 1.0
    if whole >= 0:
        p = np.polymul(p, power)
    else:
        q = np.polymul(q, power)
    return c * p, q


@dataclass(frozen=True)
class OustaloupApproximation:
    """An integer-order transfer function approximating a :class:`~fohw.FractionalTF` in a band.

    Attributes
    ----------
    num, den : ndarray
        Polynomials in ``s`` (highest power first).
    band : tuple of float
        ``(omega_b, omega_h)``.
    order : int
        ``N`` (``2N + 1`` zero/pole pairs per fractional power).
    method : str
        ``"oustaloup"`` or ``"refined"``.
    source : FractionalTF
        The approximated model.
    """

    num: np.ndarray
    den: np.ndarray
    band: tuple
    order: int
    method: str
    source: object

    def frequency_response(self, omega):
        """``num(j omega) / den(j omega)`` times the source's delay factor.

        Parameters
        ----------
        omega : array_like
            Angular frequencies.

        Returns
        -------
        ndarray of complex

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])
        >>> G.oustaloup().frequency_response([1.0])                 # integer orders: exact
        array([0.5-0.5j])
        """
        omega = check_array(omega, "omega", ndim=None, min_length=0)
        s = 1j * omega
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            g = np.asarray(np.polyval(self.num, s) / np.polyval(self.den, s))
        bad = np.flatnonzero(~np.isfinite(g.ravel()))
        if bad.size:
            w = float(omega.ravel()[bad[0]])
            raise ParameterError(f"`omega` = {w!r}: the integer-order approximation's response is not "
                                 "finite there (a pole at s = 0 of an integrator, or its polynomials of "
                                 f"degree {len(self.den) - 1} overflow at |s| = {abs(w):.3g}).")
        delay = self.source.delay
        return g * np.exp(-1j * omega * delay) if delay else g

    def band_frequencies(self, band=None, points_per_decade=100):
        """A logarithmic grid over ``band`` (default the approximation band).

        Parameters
        ----------
        band : (float, float), optional
            Frequency interval.
        points_per_decade : int, optional
            Grid density.

        Returns
        -------
        ndarray

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> G.oustaloup((1.0, 10.0)).band_frequencies(points_per_decade=2)
        array([ 1.        ,  3.16227766, 10.        ])
        """
        lo, hi = _check_band(self.band if band is None else band)
        points_per_decade = check_int(points_per_decade, "points_per_decade", minimum=1, maximum=10_000)
        n = max(int(np.ceil(points_per_decade * (np.log10(hi) - np.log10(lo)))), 1) + 1
        return np.logspace(np.log10(lo), np.log10(hi), n)

    def errors(self, band=None, points_per_decade=100):
        """Approximation error against the exact ``G(j omega)`` over a band.

        Parameters
        ----------
        band : (float, float), optional
            Default: the approximation band.
        points_per_decade : int, optional
            Grid density.

        Returns
        -------
        dict
            ``max_relative`` (of ``|G_approx - G| / |G|``), ``max_magnitude_db`` and
            ``max_phase_deg`` (largest absolute differences), and the grid ``omega``.

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> e = G.oustaloup((1e-3, 1e3), order=5).errors()
        >>> sorted(e)
        ['max_magnitude_db', 'max_phase_deg', 'max_relative', 'omega']
        """
        omega = self.band_frequencies(band, points_per_decade)
        exact = self.source.frequency_response(omega)
        approx = self.frequency_response(omega)
        ratio = approx / exact
        return {
            "max_relative": float(np.max(np.abs(ratio - 1.0))),
            "max_magnitude_db": float(np.max(np.abs(20 * np.log10(np.abs(ratio))))),
            "max_phase_deg": float(np.max(np.abs(np.degrees(np.angle(ratio))))),
            "omega": omega,
        }

    def max_relative_error(self, band=None, points_per_decade=100):
        """``max |G_approx(j w) - G(j w)| / |G(j w)|`` over ``band`` (default the approximation band).

        Parameters
        ----------
        band : (float, float), optional
            Frequency interval.
        points_per_decade : int, optional
            Grid density.

        Returns
        -------
        float

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> approx = G.oustaloup((1e-3, 1e3), 5)
        >>> round(approx.max_relative_error(), 2), round(approx.max_relative_error((0.1, 10.0)), 4)
        (0.44, 0.0036)
        """
        return self.errors(band, points_per_decade)["max_relative"]

    def to_control(self):
        """The approximation as a ``control.TransferFunction`` (needs ``pip install fohw[control]``).

        Returns
        -------
        control.TransferFunction

        Raises
        ------
        ImportError
            python-control is not installed.
        ParameterError
            The source has a delay (approximate it with ``control.pade`` yourself).

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> sys = G.oustaloup((1e-2, 1e2), 3).to_control()     # doctest: +SKIP
        """
        if self.source.delay:
            raise ParameterError(f"the model has a delay ({self.source.delay!r}); python-control's "
                                 "TransferFunction has none: multiply by control.pade(...) yourself.")
        try:
            import control
        except ImportError:
            raise ImportError("to_control() needs python-control: pip install 'fohw[control]'.") from None
        return control.TransferFunction(self.num, self.den)


def oustaloup_approximation(model, band=(1e-3, 1e3), order=5, method="oustaloup"):
    """Integer-order approximation of a fractional transfer function (FOMCON ``oustapp``).

    Parameters
    ----------
    model : FractionalTF
        The model.
    band : (float, float), optional
        ``(omega_b, omega_h)``.
    order : int, optional
        ``N`` of :func:`oustaloup_filter`.
    method : {"oustaloup", "refined"}, optional
        Filter for each fractional power.

    Returns
    -------
    OustaloupApproximation

    Examples
    --------
    >>> import fohw
    >>> from fohw.model.oustaloup import oustaloup_approximation
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    >>> approx = oustaloup_approximation(G, (1e-2, 1e2), order=3)
    >>> len(approx.den) - 1                                 # 2N + 1 poles
    7
    """
    if method not in METHODS:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    band = _check_band(band)
    _check_order(order)
    nums = [_term_rational(c, o, band, order, method) for c, o in zip(model.num, model.num_orders)]
    dens = [_term_rational(c, o, band, order, method) for c, o in zip(model.den, model.den_orders)]
    pn, qn = _rational_sum(nums)
    pd, qd = _rational_sum(dens)
    num = np.polymul(pn, qd)
    den = np.polymul(qn, pd)
    num = np.trim_zeros(num, "f") if np.any(num) else np.array([0.0])
    den = np.trim_zeros(den, "f")
    scale = den[0]
    approx = OustaloupApproximation(num / scale, den / scale, band, int(order), method, model)
    omega = approx.band_frequencies(points_per_decade=10)
    try:
        approx.frequency_response(omega)
    except ParameterError:
        raise ParameterError(_wide_band_text(band, *band, order, "its response in the band is not "
                                             "finite")) from None
    return approx
