"""Fractional equivalent circuits of a battery cell: OCV map, series resistance, RC/ZARC/Warburg elements.

The terminal voltage of a cell driven by a current ``i`` (positive = charge) is written term by
term,

``v[k] = OCV(soc[k]) + a + b soc[k] + R0 i[k] + c3 i[k]^3 + sum_e x_e[k]``,

with ``soc`` the coulomb-counted state of charge (a known signal), ``OCV`` a known map (the
electrodes' open-circuit potentials), ``a + b soc`` a correction of it, ``R0`` the series
resistance (direct feedthrough), ``c3 i^3`` an optional static current map (the Hammerstein
block: a charge-transfer overpotential that grows faster than the current, Butler–Volmer-like)
and ``x_e`` the voltage of each element:

- :class:`RC`: ``R / (1 + tau s)``;
- :class:`ZARC`: ``R / (1 + (tau s)^alpha)``, ``0 < alpha <= 1`` (constant-phase element in
  parallel with a resistance; ``alpha = 1`` is the RC element);
- :class:`Warburg`: ``sigma s^-alpha``, ``0 < alpha < 1`` (semi-infinite diffusion: a fractional
  integrator, unbounded at DC).

Each element is the Grünwald–Letnikov discretisation of its fractional differential equation at
the step ``h``, with the current sample on both sides (implicit, as ``fohw.FractionalTF``):
``(tau/h)^alpha Δ^alpha x[k] + x[k] = R i[k]`` for the ZARC (for ``alpha = 1`` this is the
backward Euler step of the RC element, which :class:`RC` uses), and
``x[k] = sigma h^alpha Δ^-alpha i[k]`` for the Warburg element. The elements start at rest: the
current before ``t = 0`` is zero (the stated assumption; the cell's known initial state of
charge enters through ``soc``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from .._validation import check_array, check_same_length, check_scalar
from ..exceptions import ParameterError
from .frequency_response import gl_operator_response, operator_response
from .gl import gl_weights_derivative, gl_weights_unchecked
from .series_division import causal_product, series_divide

__all__ = ["RC", "ZARC", "Warburg", "EquivalentCircuit", "ELEMENT_KINDS"]


def _omega(f):
    """``2 pi f`` for finite real frequencies ``f`` [Hz] (NaN, inf, strings are refused naming `f`)."""
    return 2.0 * np.pi * check_array(f, "f", ndim=None, min_length=0)


def _finite_impedance(z, f, what):
    """``z``, or a ParameterError at the first frequency where it is infinite (a pole at s = 0)."""
    bad = np.flatnonzero(~np.isfinite(np.ravel(z)))
    if bad.size:
        i = int(bad[0])
        fi = float(np.ravel(np.asarray(f, dtype=np.float64))[i])
        raise ParameterError(f"`f` = {fi!r} (index {i}): the impedance of {what} is infinite there: it "
                             "integrates the current (a pole at s = 0, or at a multiple of 1/h for the "
                             "discretised model with `h`). Give frequencies above 0.")
    return z


def _check_signal(x, name):
    return check_array(x, name)


@dataclass(frozen=True)
class RC:
    """An RC element ``R / (1 + tau s)``, discretised by backward Euler.

    Parameters
    ----------
    R : float
        Resistance [ohm], ``>= 0``.
    tau : float
        Time constant [s], ``> 0``.

    Notes
    -----
    ``tau (x[k] - x[k-1]) / h + x[k] = R i[k]``, ``x[-1] = 0``: the GL discretisation of
    :class:`ZARC` at ``alpha = 1`` (the nested integer limit used by the likelihood-ratio test).

    Examples
    --------
    >>> from fohw.model.circuit import RC
    >>> RC(R=0.01, tau=1.0).response([1.0, 1.0, 0.0], h=1.0)
    array([0.005  , 0.0075 , 0.00375])
    """

    R: float
    tau: float
    kind = "rc"
    names = ("R", "tau")

    def __post_init__(self):
        object.__setattr__(self, "R", check_scalar(self.R, "R", lower=0.0))
        object.__setattr__(self, "tau", check_scalar(self.tau, "tau", lower=0.0,
                                                     lower_inclusive=False))

    @property
    def values(self):
        """The parameters in the order of :attr:`names`."""
        return (self.R, self.tau)

    @property
    def alpha(self):
        """The order, 1."""
        return 1.0

    def impedance(self, f, h=None):
        """Impedance at frequencies ``f`` [Hz]: ``R / (1 + tau s)``, ``s = j 2 pi f``.

        With ``h``, the discretised element's response: ``s`` replaced by ``(1 - e^{-s h}) / h``.
        """
        return ZARC(self.R, self.tau, 1.0).impedance(f, h)

    def unit_response(self, i, h):
        """``x / R``: the response of ``1 / (1 + tau s)`` to ``i``."""
        r = self.tau / h
        return scipy.signal.lfilter([1.0 / (1.0 + r)], [1.0, -r / (1.0 + r)], i)

    def response(self, i, h):
        """Element voltage for the current ``i`` at the step ``h`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
        return self.R * self.unit_response(i, h)

    def derivatives(self, i, h):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact)."""
        w = self.unit_response(i, h)
        x = self.R * w
        # C x = R i with C = (1 + r) - r q^-1, r = tau/h: dC/dtau = (1 - q^-1)/h, so
        # dx/dtau = -C^-1 (Delta x) / h.
        dx = np.diff(x, prepend=0.0)
        dtau = -self.unit_response(dx, h) / h
        return x, {"R": w, "tau": dtau}


@dataclass(frozen=True)
class ZARC:
    """A ZARC element ``R / (1 + (tau s)^alpha)``, discretised by Grünwald–Letnikov.

    Parameters
    ----------
    R : float
        Resistance [ohm], ``>= 0``.
    tau : float
        Characteristic time [s], ``> 0``.
    alpha : float
        Order, ``0 < alpha <= 1``.

    Notes
    -----
    ``(tau/h)^alpha sum_{j=0}^{k} beta_j(alpha) x[k-j] + x[k] = R i[k]`` (``beta`` the GL weights,
    paper Eq. 3), solved for all ``k`` at once by power-series division
    (:func:`fohw.model.series_division.series_divide`, ``O(N log^2 N)``).

    Examples
    --------
    >>> from fohw.model.circuit import ZARC
    >>> ZARC(R=0.01, tau=1.0, alpha=1.0).response([1.0, 1.0, 0.0], h=1.0)
    array([0.005  , 0.0075 , 0.00375])
    >>> z = ZARC(R=0.01, tau=100.0, alpha=0.5).impedance([1 / (200 * 3.141592653589793)])
    >>> round(float(abs(z[0])) * 1e3, 4)   # tau omega = 1: |R / (1 + (1 + j) / sqrt(2))|
    5.412
    """

    R: float
    tau: float
    alpha: float
    kind = "zarc"
    names = ("R", "tau", "alpha")

    def __post_init__(self):
        object.__setattr__(self, "R", check_scalar(self.R, "R", lower=0.0))
        object.__setattr__(self, "tau", check_scalar(self.tau, "tau", lower=0.0,
                                                     lower_inclusive=False))
        object.__setattr__(self, "alpha", check_scalar(self.alpha, "alpha", lower=0.0, upper=1.0,
                                                       lower_inclusive=False))

    @property
    def values(self):
        """The parameters in the order of :attr:`names`."""
        return (self.R, self.tau, self.alpha)

    def impedance(self, f, h=None):
        """Impedance at frequencies ``f`` [Hz]: ``R / (1 + (tau s)^alpha)``, ``s = j 2 pi f``.

        With ``h``, the GL-discretised element's response: ``s^alpha`` replaced by
        ``((1 - e^{-s h}) / h)^alpha``.
        """
        omega = _omega(f)
        scale = self.tau ** self.alpha
        if h is None:
            op = operator_response([scale], [self.alpha], omega)
        else:
            op = gl_operator_response([scale], [self.alpha], omega, h)
        return self.R / (1.0 + op)

    def _weights(self, n, h):
        r = (self.tau / h) ** self.alpha
        beta = gl_weights_unchecked(self.alpha, n)
        c = r * beta
        c[0] += 1.0
        return r, beta, c

    def unit_response(self, i, h):
        """``x / R``: the response of ``1 / (1 + (tau s)^alpha)`` to ``i``."""
        _, _, c = self._weights(i.shape[0], h)
        return series_divide(i, c)

    def response(self, i, h):
        """Element voltage for the current ``i`` at the step ``h`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
        return self.R * self.unit_response(i, h)

    def derivatives(self, i, h):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact series derivatives).

        From ``C x = R i``: ``dx/dp = -C^{-1} (dC/dp * x)`` with ``dC/dtau = (alpha/tau) r beta``
        and ``dC/dalpha = r (log(tau/h) beta + dbeta/dalpha)``, ``r = (tau/h)^alpha``.
        """
        n = i.shape[0]
        r, beta, c = self._weights(n, h)
        w = series_divide(i, c)
        x = self.R * w
        bx = causal_product(beta, x, n)
        dtau = -(self.alpha / self.tau) * r * series_divide(bx, c)
        dbeta = gl_weights_derivative(self.alpha, n)
        dc_x = math.log(self.tau / h) * bx + causal_product(dbeta, x, n)
        dalpha = -r * series_divide(dc_x, c)
        return x, {"R": w, "tau": dtau, "alpha": dalpha}


@dataclass(frozen=True)
class Warburg:
    """A Warburg-type element ``sigma s^-alpha`` (a fractional integrator), discretised by GL.

    Parameters
    ----------
    sigma : float
        Coefficient [ohm s^-alpha], ``>= 0``.
    alpha : float
        Order, ``0 < alpha < 1`` (``alpha = 1`` is a capacitor ``1 / (C s)``, which duplicates the
        ``b soc`` term of the circuit; ``alpha = 0.5`` is the classical Warburg impedance).

    Notes
    -----
    ``x[k] = sigma h^alpha sum_{j=0}^{k} beta_j(-alpha) i[k-j]``: the GL fractional sum, an
    ``O(N log N)`` causal convolution. It has no DC limit: a constant current makes ``x`` grow
    like ``t^alpha``.

    Examples
    --------
    >>> from fohw.model.circuit import Warburg
    >>> Warburg(sigma=1.0, alpha=0.5).response([1.0, 0.0, 0.0], h=1.0)
    array([1.   , 0.5  , 0.375])
    """

    sigma: float
    alpha: float
    kind = "warburg"
    names = ("sigma", "alpha")

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_scalar(self.sigma, "sigma", lower=0.0))
        object.__setattr__(self, "alpha", check_scalar(self.alpha, "alpha", lower=0.0, upper=1.0,
                                                       lower_inclusive=False,
                                                       upper_inclusive=False))

    @property
    def values(self):
        """The parameters in the order of :attr:`names`."""
        return (self.sigma, self.alpha)

    def impedance(self, f, h=None):
        """Impedance at frequencies ``f`` [Hz]: ``sigma s^-alpha`` (GL-discretised with ``h``)."""
        omega = _omega(f)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if h is None:
                z = operator_response([self.sigma], [-self.alpha], omega)
            else:
                z = gl_operator_response([self.sigma], [-self.alpha], omega, h)
        return _finite_impedance(z, f, "a Warburg element")

    def unit_response(self, i, h):
        """``x / sigma``: the GL fractional sum of ``i`` of order ``alpha`` at the step ``h``."""
        n = i.shape[0]
        return h ** self.alpha * causal_product(gl_weights_unchecked(-self.alpha, n), i, n)

    def response(self, i, h):
        """Element voltage for the current ``i`` at the step ``h`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
        return self.sigma * self.unit_response(i, h)

    def derivatives(self, i, h):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact)."""
        n = i.shape[0]
        w = self.unit_response(i, h)
        # d/dalpha [h^alpha beta(-alpha)] = h^alpha (log(h) beta(-alpha) - beta'(-alpha)).
        dbeta = gl_weights_derivative(-self.alpha, n)
        dw = math.log(h) * w - h ** self.alpha * causal_product(dbeta, i, n)
        return self.sigma * w, {"sigma": w, "alpha": self.sigma * dw}


#: Element classes by kind.
ELEMENT_KINDS = {"rc": RC, "zarc": ZARC, "warburg": Warburg}


@dataclass(frozen=True)
class EquivalentCircuit:
    """A fractional equivalent circuit: ``v = OCV(soc) + a + b soc + R0 i + c3 i^3 + sum_e x_e``.

    Parameters
    ----------
    elements : sequence of RC, ZARC or Warburg
        The dynamic elements, in series.
    r0 : float
        Series resistance ``R0`` [ohm], ``>= 0``.
    a, b : float, optional
        Correction ``a + b soc`` of the open-circuit voltage [V] (default 0).
    c3 : float or None, optional
        Coefficient of the static current map ``c3 i^3`` [V/A^3]; ``None`` (default): no map.
    ocv : callable or None, optional
        The known open-circuit voltage ``OCV(soc)`` [V], vectorised; ``None``: zero (then ``v``
        is the overpotential ``a + b soc + ...``).

    Notes
    -----
    The simulation is the sum of independent terms, each exact for its discretisation (see
    the module's docstring): the elements start at rest at ``k = 0``; the state of charge, the
    circuit's only slow state, is the known signal ``soc`` (coulomb counting from the known
    initial state of charge). The impedance of the circuit, linearised about zero current, is
    ``R0 + sum_e Z_e(s)`` (the cubic map has zero slope there).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit import EquivalentCircuit, ZARC
    >>> cell = EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015, a=3.7)
    >>> cell.names
    ('a', 'b', 'R0', 'R1', 'tau1', 'alpha1')
    >>> v = cell.simulate(-np.ones(4), soc=np.full(4, 0.5), h=1.0)
    >>> bool(np.all(np.diff(v) < 0)), round(float(v[0]), 4)   # 3.7 - 0.015 - 0.01/(1 + 50**0.5)
    (True, 3.6838)
    """

    elements: tuple
    r0: float
    a: float = 0.0
    b: float = 0.0
    c3: float | None = None
    ocv: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        elements = tuple(self.elements)
        for k, e in enumerate(elements):
            if not isinstance(e, (RC, ZARC, Warburg)):
                raise ParameterError(f"`elements[{k}]` must be an RC, ZARC or Warburg element; "
                                     f"got {e!r}.")
        object.__setattr__(self, "elements", elements)
        object.__setattr__(self, "r0", check_scalar(self.r0, "r0", lower=0.0))
        object.__setattr__(self, "a", check_scalar(self.a, "a"))
        object.__setattr__(self, "b", check_scalar(self.b, "b"))
        if self.c3 is not None:
            object.__setattr__(self, "c3", check_scalar(self.c3, "c3"))
        if self.ocv is not None and not callable(self.ocv):
            raise ParameterError(f"`ocv` must be callable (soc -> volts) or None; got {self.ocv!r}.")

    @property
    def kinds(self):
        """The elements' kinds, e.g. ``("rc", "zarc")``."""
        return tuple(e.kind for e in self.elements)

    @property
    def names(self):
        """Parameter names: ``a, b, R0, [c3,]`` then each element's with its 1-based index."""
        out = ["a", "b", "R0"] + (["c3"] if self.c3 is not None else [])
        for k, e in enumerate(self.elements, start=1):
            out += [f"{n}{k}" for n in e.names]
        return tuple(out)

    @property
    def values(self):
        """Parameter values in the order of :attr:`names`."""
        out = [self.a, self.b, self.r0] + ([self.c3] if self.c3 is not None else [])
        for e in self.elements:
            out += list(e.values)
        return np.array(out)

    @property
    def n_params(self):
        """Number of parameters."""
        return len(self.names)

    def with_values(self, values):
        """The same structure with the parameter vector ``values`` (order of :attr:`names`)."""
        values = [float(x) for x in np.asarray(values, dtype=np.float64).ravel()]
        if len(values) != self.n_params:
            raise ParameterError(f"`values` must have {self.n_params} entries ({', '.join(self.names)}); "
                                 f"got {len(values)}.")
        a, b, r0 = values[:3]
        pos = 3
        c3 = None
        if self.c3 is not None:
            c3 = values[3]
            pos = 4
        elements = []
        for e in self.elements:
            m = len(e.names)
            elements.append(type(e)(*values[pos:pos + m]))
            pos += m
        return EquivalentCircuit(elements, r0=r0, a=a, b=b, c3=c3, ocv=self.ocv)

    def _checked(self, i, soc, h):
        i = _check_signal(i, "i")
        soc = _check_signal(soc, "soc")
        check_same_length(i, soc, "i", "soc")
        h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
        return i, soc, h

    def static_part(self, i, soc):
        """``OCV(soc) + a + b soc + R0 i + c3 i^3``: the terms without memory."""
        v = self.a + self.b * soc + self.r0 * i
        if self.ocv is not None:
            v = v + np.asarray(self.ocv(soc), dtype=np.float64)
        if self.c3 is not None:
            v = v + self.c3 * i ** 3
        return v

    def simulate(self, i, soc, h):
        """Terminal voltage for the current ``i`` and state of charge ``soc`` at the step ``h``.

        Parameters
        ----------
        i, soc : array_like, shape (N,)
            Current [A] and state of charge (the record's coulomb count).
        h : float
            Sampling time [s].

        Returns
        -------
        ndarray, shape (N,)
        """
        i, soc, h = self._checked(i, soc, h)
        v = self.static_part(i, soc)
        for e in self.elements:
            v = v + e.response(i, h)
        return v

    def jacobian(self, i, soc, h):
        """The simulated voltage and its exact derivatives with respect to :attr:`values`.

        Returns
        -------
        v : ndarray, shape (N,)
        jac : ndarray, shape (N, n_params)
        """
        i, soc, h = self._checked(i, soc, h)
        v = self.static_part(i, soc)
        cols = [np.ones_like(i), soc, i] + ([i ** 3] if self.c3 is not None else [])
        for e in self.elements:
            x, d = e.derivatives(i, h)
            v = v + x
            cols += [d[n] for n in e.names]
        return v, np.column_stack(cols)

    def impedance(self, f, h=None, *, capacity=None, ocv_slope=0.0):
        """Impedance ``R0 + sum_e Z_e`` at frequencies ``f`` [Hz] (about zero current).

        Parameters
        ----------
        f : array_like
            Finite frequencies [Hz] (NaN and inf are refused; ``f = 0`` is refused where the
            impedance is infinite: a Warburg element, or the OCV's capacitor with ``capacity``).
        h : float, optional
            Give the step to get the discretised model's response (GL symbol in place of ``s``);
            default: the continuous circuit.
        capacity : float, optional
            The cell's capacity [Ah]. Given, the open-circuit voltage's own impedance is added:
            ``soc`` integrates the current, so ``OCV(soc) + b soc`` acts as a capacitor
            ``(ocv_slope + b) / (3600 capacity s)`` (at 1 mHz about 5 mOhm for a 5 Ah cell
            whose OCV rises 0.6 V over the full SOC: not negligible against ``R0``).
        ocv_slope : float, optional
            ``dOCV/dsoc`` [V] at the state of charge of interest (default 0).

        Returns
        -------
        ndarray of complex, shape of ``f``
        """
        if h is not None:
            h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
        f = check_array(f, "f", ndim=None, min_length=0)
        omega = _omega(f)
        z = np.full(omega.shape, self.r0, dtype=np.complex128)
        for e in self.elements:
            z = z + e.impedance(f, h)
        if capacity is not None:
            capacity = check_scalar(capacity, "capacity", lower=0.0, lower_inclusive=False)
            slope = check_scalar(ocv_slope, "ocv_slope") + self.b
            with np.errstate(divide="ignore", invalid="ignore"):
                if h is None:
                    integrator = 1.0 / (1j * omega)
                else:   # the coulomb count sums the current before the sample: h z^-1 / (1 - z^-1)
                    zinv = np.exp(-1j * omega * h)
                    integrator = h * zinv / (1.0 - zinv)
                z = z + slope / (3600.0 * capacity) * integrator
            z = _finite_impedance(z, f, "the open-circuit voltage (capacity=)")
        return z

    def __str__(self):
        parts = [f"{n} = {v:.6g}" for n, v in zip(self.names, self.values)]
        return f"EquivalentCircuit({'+'.join(self.kinds) or 'R0 only'}: {', '.join(parts)})"
