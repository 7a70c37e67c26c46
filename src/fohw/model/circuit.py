"""Fractional equivalent circuits of a battery cell: OCV map, series resistance, RC/ZARC/Warburg elements.

The terminal voltage of a cell driven by a current ``i`` is written term by term (in the equations
``i`` is positive on charge; :class:`EquivalentCircuit` takes the measured current in either sign
convention, its ``current_sign``),

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
the step ``dt``, with the current sample on both sides (implicit, as ``fohw.FractionalTF``):
``(tau/dt)^alpha Δ^alpha x[k] + x[k] = R i[k]`` for the ZARC (for ``alpha = 1`` this is the
backward Euler step of the RC element, which :class:`RC` uses), and
``x[k] = sigma dt^alpha Δ^-alpha i[k]`` for the Warburg element. The elements start at rest: the
current before ``t = 0`` is zero (the stated assumption; the cell's known initial state of
charge enters through ``soc``).

:class:`EquivalentCircuit` is a model kind (:class:`fohw.Model`): its input has two columns,
``u = [i, soc]``, its step is ``dt``, and :func:`fohw.fit` fits it, starting from the circuit's
own scan of the time constants and orders (:meth:`EquivalentCircuit.starts`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import KW_ONLY, dataclass, field

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import ParameterError
from .base import Model
from .frequency_response import gl_operator_response, operator_response
from .gl import gl_weights_derivative, gl_weights_unchecked
from .kernels import causal_product, series_divide
from .parameters import Parameter, Parameters

__all__ = ["RC", "ZARC", "Warburg", "EquivalentCircuit", "OCVTable", "ELEMENT_KINDS",
           "impedance_error", "CURRENT_SIGNS", "SIGN_T", "make_element", "scan_combinations",
           "check_spectrum"]


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
                             "integrates the current (a pole at s = 0, or at a multiple of 1/dt for the "
                             "discretised model). Give frequencies above 0.")
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
    ``tau (x[k] - x[k-1]) / dt + x[k] = R i[k]``, ``x[-1] = 0``: the GL discretisation of
    :class:`ZARC` at ``alpha = 1`` (the nested integer limit used by the likelihood-ratio test).

    Examples
    --------
    >>> from fohw.model.circuit import RC
    >>> RC(R=0.01, tau=1.0).response([1.0, 1.0, 0.0], dt=1.0)
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

    def impedance(self, f, dt=None):
        """Impedance at frequencies ``f`` [Hz]: ``R / (1 + tau s)``, ``s = j 2 pi f``.

        With ``dt``, the discretised element's response: ``s`` replaced by ``(1 - e^{-s dt}) / dt``.
        """
        return ZARC(self.R, self.tau, 1.0).impedance(f, dt)

    def unit_response(self, i, dt):
        """``x / R``: the response of ``1 / (1 + tau s)`` to ``i``."""
        r = self.tau / dt
        return scipy.signal.lfilter([1.0 / (1.0 + r)], [1.0, -r / (1.0 + r)], i)

    def response(self, i, dt):
        """Element voltage for the current ``i`` at the step ``dt`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        dt = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
        return self.R * self.unit_response(i, dt)

    def derivatives(self, i, dt):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact)."""
        w = self.unit_response(i, dt)
        x = self.R * w
        # C x = R i with C = (1 + r) - r q^-1, r = tau/dt: dC/dtau = (1 - q^-1)/dt, so
        # dx/dtau = -C^-1 (Delta x) / dt.
        dx = np.diff(x, prepend=0.0)
        dtau = -self.unit_response(dx, dt) / dt
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
    ``(tau/dt)^alpha sum_{j=0}^{k} beta_j(alpha) x[k-j] + x[k] = R i[k]`` (``beta`` the GL weights,
    paper Eq. 3), solved for all ``k`` at once by power-series division
    (:func:`fohw.model.kernels.series_divide`, ``O(N log^2 N)``).

    Examples
    --------
    >>> from fohw.model.circuit import ZARC
    >>> ZARC(R=0.01, tau=1.0, alpha=1.0).response([1.0, 1.0, 0.0], dt=1.0)
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
    #: Bounds of the order in a fit (the circuit's ``alpha`` parameters): 1 is the RC element.
    order_bounds = (0.05, 1.0)

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

    def impedance(self, f, dt=None):
        """Impedance at frequencies ``f`` [Hz]: ``R / (1 + (tau s)^alpha)``, ``s = j 2 pi f``.

        With ``dt``, the GL-discretised element's response: ``s^alpha`` replaced by
        ``((1 - e^{-s dt}) / dt)^alpha``.
        """
        omega = _omega(f)
        scale = self.tau ** self.alpha
        if dt is None:
            op = operator_response([scale], [self.alpha], omega)
        else:
            op = gl_operator_response([scale], [self.alpha], omega, dt)
        return self.R / (1.0 + op)

    def _weights(self, n, dt):
        r = (self.tau / dt) ** self.alpha
        beta = gl_weights_unchecked(self.alpha, n)
        c = r * beta
        c[0] += 1.0
        return r, beta, c

    def unit_response(self, i, dt):
        """``x / R``: the response of ``1 / (1 + (tau s)^alpha)`` to ``i``."""
        _, _, c = self._weights(i.shape[0], dt)
        return series_divide(i, c)

    def response(self, i, dt):
        """Element voltage for the current ``i`` at the step ``dt`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        dt = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
        return self.R * self.unit_response(i, dt)

    def derivatives(self, i, dt):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact series derivatives).

        From ``C x = R i``: ``dx/dp = -C^{-1} (dC/dp * x)`` with ``dC/dtau = (alpha/tau) r beta``
        and ``dC/dalpha = r (log(tau/dt) beta + dbeta/dalpha)``, ``r = (tau/dt)^alpha``.
        """
        n = i.shape[0]
        r, beta, c = self._weights(n, dt)
        w = series_divide(i, c)
        x = self.R * w
        bx = causal_product(beta, x, n)
        dtau = -(self.alpha / self.tau) * r * series_divide(bx, c)
        dbeta = gl_weights_derivative(self.alpha, n)
        dc_x = math.log(self.tau / dt) * bx + causal_product(dbeta, x, n)
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
    ``x[k] = sigma dt^alpha sum_{j=0}^{k} beta_j(-alpha) i[k-j]``: the GL fractional sum, an
    ``O(N log N)`` causal convolution. It has no DC limit: a constant current makes ``x`` grow
    like ``t^alpha``.

    Examples
    --------
    >>> from fohw.model.circuit import Warburg
    >>> Warburg(sigma=1.0, alpha=0.5).response([1.0, 0.0, 0.0], dt=1.0)
    array([1.   , 0.5  , 0.375])
    """

    sigma: float
    alpha: float
    kind = "warburg"
    names = ("sigma", "alpha")
    #: Bounds of the order in a fit: below 1 (order 1 is a capacitor, the ``b soc`` term).
    order_bounds = (0.05, 0.95)

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_scalar(self.sigma, "sigma", lower=0.0))
        object.__setattr__(self, "alpha", check_scalar(self.alpha, "alpha", lower=0.0, upper=1.0,
                                                       lower_inclusive=False,
                                                       upper_inclusive=False))

    @property
    def values(self):
        """The parameters in the order of :attr:`names`."""
        return (self.sigma, self.alpha)

    def impedance(self, f, dt=None):
        """Impedance at frequencies ``f`` [Hz]: ``sigma s^-alpha`` (GL-discretised with ``dt``)."""
        omega = _omega(f)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if dt is None:
                z = operator_response([self.sigma], [-self.alpha], omega)
            else:
                z = gl_operator_response([self.sigma], [-self.alpha], omega, dt)
        return _finite_impedance(z, f, "a Warburg element")

    def unit_response(self, i, dt):
        """``x / sigma``: the GL fractional sum of ``i`` of order ``alpha`` at the step ``dt``."""
        n = i.shape[0]
        return dt ** self.alpha * causal_product(gl_weights_unchecked(-self.alpha, n), i, n)

    def response(self, i, dt):
        """Element voltage for the current ``i`` at the step ``dt`` (at rest before ``k = 0``)."""
        i = _check_signal(i, "i")
        dt = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
        return self.sigma * self.unit_response(i, dt)

    def derivatives(self, i, dt):
        """``x`` and ``{name: d x / d name}`` for each parameter (exact)."""
        n = i.shape[0]
        w = self.unit_response(i, dt)
        # d/dalpha [dt^alpha beta(-alpha)] = dt^alpha (log(dt) beta(-alpha) - beta'(-alpha)).
        dbeta = gl_weights_derivative(-self.alpha, n)
        dw = math.log(dt) * w - dt ** self.alpha * causal_product(dbeta, i, n)
        return self.sigma * w, {"sigma": w, "alpha": self.sigma * dw}


#: Element classes by kind.
ELEMENT_KINDS = {"rc": RC, "zarc": ZARC, "warburg": Warburg}

#: Scan starts :meth:`EquivalentCircuit.starts` returns (the best grid points, distinct).
SCAN_STARTS = 5

#: The sign conventions of the measured current ``u[:, 0]`` (:class:`EquivalentCircuit`'s
#: ``current_sign``): ``"charge_positive"`` (a charge current is positive, a discharge negative:
#: the shipped LG M50LT record, ``fohw.datasets.battery_cell()``) and ``"discharge_positive"``
#: (PyBaMM's and most cyclers' convention).
CURRENT_SIGNS = ("charge_positive", "discharge_positive")

#: The sign check of :meth:`EquivalentCircuit.starts` refuses a record whose voltage steps fall
#: with the current's steps (as the circuit counts it) with a t-statistic below ``-SIGN_T``: the
#: slope of ``diff(v - OCV)`` on ``diff(i)`` is ``R0`` plus the elements' share, positive for any
#: passive cell, and noise alone reaches ``-SIGN_T`` standard errors with probability below 3e-7.
SIGN_T = 5.0

#: Most combinations of grid points the start scan (:meth:`EquivalentCircuit.starts`) may
#: solve: about 30 us each (4 ZARCs at the default grid, 43 750 of them, take 1.3 s); five ZARCs
#: at the default grid would need 175 000 and are refused, naming ``n_tau`` and ``n_alpha``.
MAX_GRID_STARTS = 50_000

#: Without a grid point of non-negative resistances, the scan projects its best
#: ``PROJECTED_STARTS * SCAN_STARTS`` points onto the feasible set (:meth:`EquivalentCircuit.starts`).
PROJECTED_STARTS = 4


class OCVTable:
    """A tabulated open-circuit voltage ``OCV(soc)``: linear interpolation between points.

    The form of the OCV map that a model file can hold (a Python function cannot be written to
    JSON). A state of charge outside the table is refused, never extrapolated.

    Parameters
    ----------
    soc : array_like, shape (m,)
        States of charge, strictly increasing, ``m >= 2``.
    volts : array_like, shape (m,)
        The open-circuit voltage [V] at each.

    Examples
    --------
    >>> from fohw.model.circuit import OCVTable
    >>> ocv = OCVTable([0.0, 0.5, 1.0], [3.0, 3.7, 4.2])
    >>> ocv([0.25, 0.75])
    array([3.35, 3.95])
    """

    __slots__ = ("soc", "volts")

    def __init__(self, soc, volts):
        soc = check_array(soc, "soc", min_length=2)
        volts = check_array(volts, "volts", min_length=2)
        check_same_length(soc, volts, "soc", "volts")
        if np.any(np.diff(soc) <= 0):
            k = int(np.flatnonzero(np.diff(soc) <= 0)[0])
            raise ParameterError(f"`soc` of an OCVTable must increase strictly; got {float(soc[k])!r} "
                                 f"then {float(soc[k + 1])!r} at points {k} and {k + 1}.")
        soc.setflags(write=False)
        volts.setflags(write=False)
        self.soc, self.volts = soc, volts

    def __call__(self, soc):
        """The open-circuit voltage [V] at ``soc`` (linear interpolation; outside the table: raises)."""
        s = np.asarray(soc, dtype=np.float64)
        if not np.all(np.isfinite(s)) or np.any((s < self.soc[0]) | (s > self.soc[-1])):
            raise ParameterError(f"the OCV table covers soc in [{self.soc[0]:g}, {self.soc[-1]:g}]; "
                                 f"got values from {float(np.nanmin(s))!r} to {float(np.nanmax(s))!r}.")
        return np.interp(s, self.soc, self.volts)

    def to_dict(self) -> dict:
        """``{"soc": [...], "volts": [...]}`` (JSON-ready)."""
        return {"soc": self.soc.tolist(), "volts": self.volts.tolist()}

    @classmethod
    def from_dict(cls, d) -> OCVTable:
        """Inverse of :meth:`to_dict`."""
        if not isinstance(d, dict) or set(d) != {"soc", "volts"}:
            raise ParameterError(f"an OCV table is a mapping with 'soc' and 'volts'; got {d!r}.")
        return cls(d["soc"], d["volts"])

    def __eq__(self, other):
        if not isinstance(other, OCVTable):
            return NotImplemented
        return np.array_equal(self.soc, other.soc) and np.array_equal(self.volts, other.volts)

    __hash__ = None

    def __repr__(self):
        return (f"OCVTable({self.soc.size} points, soc {self.soc[0]:g} to {self.soc[-1]:g}, "
                f"{self.volts.min():.4g} to {self.volts.max():.4g} V)")


def _placeholder(kind, tau):
    if kind == "rc":
        return RC(0.0, tau)
    if kind == "zarc":
        return ZARC(0.0, tau, 0.5)
    return Warburg(0.0, 0.5)


def make_element(kind, R, tau, alpha):
    """The element of ``kind`` ("rc", "zarc" or "warburg") with these values."""
    if kind == "rc":
        return RC(R, tau)
    if kind == "zarc":
        return ZARC(R, tau, alpha)
    return Warburg(R, alpha)


@dataclass(frozen=True, eq=False)
class EquivalentCircuit(Model):
    """A fractional equivalent circuit: ``v = OCV(soc) + a + b soc + R0 i + c3 i^3 + sum_e x_e``.

    A :class:`fohw.Model`: its input ``u`` has two columns, the current ``i`` [A] and the state
    of charge ``soc`` (``u[:, 0]``, ``u[:, 1]``), its output is the terminal voltage [V], and
    :func:`fohw.fit` fits it by simulation error. The current's sign is the ``current_sign``
    argument (default: positive = charge); a fit checks the record against it.

    Parameters
    ----------
    elements : sequence of RC, ZARC, Warburg or {"rc", "zarc", "warburg"}
        The dynamic elements, in series. A kind's name stands for an element with placeholder
        values (resistance 0; a structure to fit).
    r0 : float, optional
        Series resistance ``R0`` [ohm], ``>= 0`` (default 0).
    a, b : float, optional
        Correction ``a + b soc`` of the open-circuit voltage [V] (default 0).
    c3 : float or None, optional
        Coefficient of the static current map ``c3 i^3`` [V/A^3]; ``None`` (default): no map.
    ocv : OCVTable, callable or None, optional
        The known open-circuit voltage ``OCV(soc)`` [V]: an :class:`OCVTable` (which model files
        can hold), any vectorised callable (which they cannot), or ``None``: zero (then ``v`` is
        the overpotential ``a + b soc + ...``).
    dt : float, optional
        Sampling time [s] (default 1).
    current_sign : {"charge_positive", "discharge_positive"}, optional
        The sign convention of the measured current ``u[:, 0]``. ``"charge_positive"``
        (default): a charge current is positive and a discharge negative, the convention of
        the LG M50LT record shipped with fohw (``fohw.datasets.battery_cell()``), in which the
        voltage rises with the current. ``"discharge_positive"``: a discharge current is
        positive (PyBaMM's ``"Current [A]"``, most cyclers' exports); the circuit then counts
        ``-u[:, 0]``. The parameters mean the same in both (``R0 >= 0`` whatever the sign),
        and so does the state of charge column, which the user computes. :func:`fohw.fit`
        checks the record against the convention (:meth:`starts`; a record whose voltage steps
        fall with the current's steps is refused, naming the other convention).
    tau_bounds : (float, float), optional
        Bounds of every time constant in a fit [s]; default ``(dt, inf)`` (a time constant
        below the step is not resolved: it merges with ``R0``). The scan of
        :meth:`starts` covers ``tau_bounds``; with the default (an infinite upper bound) it
        runs from ``dt`` up to the duration of the record it is given, ``N dt`` (for a pulse
        with its relaxation, the relaxation's time constants up to the record's length; a
        time constant beyond the record makes an element an integrator over it, its ``R`` and
        ``tau`` not separately identifiable), and the local search is free beyond.
    n_tau, n_alpha : int, optional
        The scan's grid (:meth:`starts`): log-spaced time constants and orders per element
        (default 8 and 5). The scan visits every combination of the elements' grid points (same-kind
        elements in increasing order), at most ``MAX_GRID_STARTS`` (50 000) of them: a fit
        beyond is refused before it starts, naming ``n_tau`` and ``n_alpha``.

    Notes
    -----
    The parameters (:attr:`parameters`, in this order): ``a, b, R0``, ``c3`` with the current
    map, then each element's with its 1-based index (``R1, tau1`` of an RC; ``R1, tau1,
    alpha1`` of a ZARC; ``sigma1, alpha1`` of a Warburg element). Resistances are ``>= 0``,
    time constants inside ``tau_bounds``, orders inside their element's ``order_bounds``
    (ZARC ``[0.05, 1]``, Warburg ``[0.05, 0.95]``), the rest unbounded; change any of them,
    or fix one, with ``circuit.with_parameters(circuit.parameters.replace(name, ...))``.

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
    >>> cell.parameters.names
    ('a', 'b', 'R0', 'R1', 'tau1', 'alpha1')
    >>> v = cell.simulate(np.column_stack([-np.ones(4), np.full(4, 0.5)]))
    >>> bool(np.all(np.diff(v) < 0)), round(float(v[0]), 4)   # 3.7 - 0.015 - 0.01/(1 + 50**0.5)
    (True, 3.6838)
    """

    elements: tuple
    r0: float = 0.0
    a: float = 0.0
    b: float = 0.0
    c3: float | None = None
    ocv: object = field(default=None, repr=False)
    _: KW_ONLY
    dt: float = 1.0
    tau_bounds: tuple | None = None
    n_tau: int = 8
    n_alpha: int = 5
    current_sign: str = "charge_positive"

    def __post_init__(self):
        dt = check_scalar(self.dt, "dt", lower=0.0, lower_inclusive=False)
        object.__setattr__(self, "dt", dt)
        if not (isinstance(self.current_sign, str) and self.current_sign in CURRENT_SIGNS):
            raise ParameterError(f"`current_sign` must be one of {', '.join(map(repr, CURRENT_SIGNS))} "
                                 f"(the sign of a charge current in u[:, 0]); got "
                                 f"{self.current_sign!r}.")
        if self.tau_bounds is not None:
            try:
                lo, hi = (float(x) for x in self.tau_bounds)
            except (TypeError, ValueError):
                raise ParameterError(f"`tau_bounds` must be a pair (low, high); got "
                                     f"{self.tau_bounds!r}.") from None
            if not (0.0 < lo < hi) or math.isnan(hi):
                raise ParameterError(f"`tau_bounds` must be increasing with 0 < low; got "
                                     f"{self.tau_bounds!r}.")
            object.__setattr__(self, "tau_bounds", (lo, hi))
        object.__setattr__(self, "n_tau", check_int(self.n_tau, "n_tau", minimum=1))
        object.__setattr__(self, "n_alpha", check_int(self.n_alpha, "n_alpha", minimum=1))
        if isinstance(self.elements, (str, RC, ZARC, Warburg)):
            raise ParameterError(f"`elements` must be a sequence of elements; got {self.elements!r} "
                                 "(write [element] for one).")
        elements = []
        lo, hi = self.tau_range
        for k, e in enumerate(self.elements):
            if isinstance(e, str) and e in ELEMENT_KINDS:
                e = _placeholder(e, math.sqrt(lo * hi) if math.isfinite(hi) else lo)
            elif not isinstance(e, (RC, ZARC, Warburg)):
                raise ParameterError(f"`elements[{k}]` must be an RC, ZARC or Warburg element or "
                                     f"one of {', '.join(ELEMENT_KINDS)}; got {e!r}.")
            elements.append(e)
        object.__setattr__(self, "elements", tuple(elements))
        object.__setattr__(self, "r0", check_scalar(self.r0, "r0", lower=0.0))
        object.__setattr__(self, "a", check_scalar(self.a, "a"))
        object.__setattr__(self, "b", check_scalar(self.b, "b"))
        if self.c3 is not None:
            object.__setattr__(self, "c3", check_scalar(self.c3, "c3"))
        if isinstance(self.ocv, dict):
            object.__setattr__(self, "ocv", OCVTable.from_dict(self.ocv))
        if self.ocv is not None and not callable(self.ocv):
            raise ParameterError(f"`ocv` must be an OCVTable, a callable (soc -> volts) or None; "
                                 f"got {self.ocv!r}.")

    # --- structure ---------------------------------------------------------------------------
    @property
    def n_inputs(self) -> int:
        """Two input columns: current and state of charge."""
        return 2

    @property
    def tau_range(self):
        """``(low, high)``: the default bounds of every time constant (``tau_bounds`` or ``(dt, inf)``)."""
        return self.tau_bounds if self.tau_bounds is not None else (self.dt, math.inf)

    @property
    def kinds(self):
        """The elements' kinds, e.g. ``("rc", "zarc")``."""
        return tuple(e.kind for e in self.elements)

    def _names(self):
        out = ["a", "b", "R0"] + (["c3"] if self.c3 is not None else [])
        for k, e in enumerate(self.elements, start=1):
            out += [f"{n}{k}" for n in e.names]
        return tuple(out)

    # --- the Model protocol ---------------------------------------------------------------------
    @property
    def parameters(self) -> Parameters:
        """``a, b, R0, [c3,]`` then each element's parameters, with their bounds (see Notes)."""
        out = [Parameter("a", self.a), Parameter("b", self.b),
               Parameter("R0", self.r0, bounds=(0.0, math.inf))]
        if self.c3 is not None:
            out.append(Parameter("c3", self.c3))
        for k, e in enumerate(self.elements, start=1):
            if e.kind == "warburg":
                out.append(Parameter(f"sigma{k}", e.sigma, bounds=(0.0, math.inf)))
            else:
                out += [Parameter(f"R{k}", e.R, bounds=(0.0, math.inf)),
                        Parameter(f"tau{k}", e.tau, bounds=self.tau_range)]
            if e.kind != "rc":
                out.append(Parameter(f"alpha{k}", e.alpha, bounds=e.order_bounds, order=True))
        return Parameters(out)

    def check_settings(self, parameters):
        """Refuse an element's order bounds beyond its domain, naming the parameter.

        A ZARC's order lies in ``(0, 1]`` (order 1 is an RC element), a Warburg element's in
        ``(0, 1)`` (order 1 is a capacitor, the ``b soc`` term).
        """
        for k, e in enumerate(self.elements, start=1):
            if e.kind == "rc":
                continue
            name = f"alpha{k}"
            lo, hi = parameters[name].bounds
            top_ok = hi <= 1.0 if e.kind == "zarc" else hi < 1.0
            if not (lo > 0.0 and top_ok):
                domain, what = (("(0, 1]", "ZARC") if e.kind == "zarc" else
                                ("(0, 1), below 1", "Warburg"))
                raise ParameterError(f"the bounds of {name!r} ({lo:g}, {hi:g}) leave the order "
                                     f"domain {domain} of a {what} element; give bounds inside it.")

    def with_parameters(self, values) -> EquivalentCircuit:
        """The same structure with new parameter values (a mapping ``name -> float``, or Parameters)."""
        if isinstance(values, Parameters) and values.names == self._names():
            v = values.valuesdict()         # checked by its own Parameter objects (fohw.fit)
        else:
            v = self.parameters.with_values(values).valuesdict()
        elements = []
        for k, e in enumerate(self.elements, start=1):
            if e.kind == "warburg":
                elements.append(Warburg(v[f"sigma{k}"], v[f"alpha{k}"]))
            elif e.kind == "zarc":
                elements.append(ZARC(v[f"R{k}"], v[f"tau{k}"], v[f"alpha{k}"]))
            else:
                elements.append(RC(v[f"R{k}"], v[f"tau{k}"]))
        return dataclasses.replace(self, elements=elements, r0=v["R0"], a=v["a"], b=v["b"],
                                   c3=v["c3"] if self.c3 is not None else None)

    def _signals(self, u):
        u = self.check_input(u)
        soc = u[:, 1]
        bad = np.flatnonzero((soc < 0.0) | (soc > 1.0))
        if bad.size:
            k = int(bad[0])
            raise ParameterError(f"the state of charge `u[:, 1]` must be in [0, 1] (a fraction of the "
                                 f"capacity); got {float(soc[k])!r} at sample {k} (values from "
                                 f"{float(soc.min())!r} to {float(soc.max())!r}). Check its units "
                                 "and the initial state of charge of the coulomb count.")
        i = u[:, 0] if self.current_sign == "charge_positive" else -u[:, 0]
        return np.ascontiguousarray(i), np.ascontiguousarray(soc)

    def ocv_values(self, soc):
        """``OCV(soc)`` [V] from the circuit's map, checked: one finite value per sample (0 without a map)."""
        if self.ocv is None:
            return np.zeros_like(soc)
        try:
            out = np.asarray(self.ocv(soc), dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise ParameterError(f"`ocv` ({self.ocv!r}) must map the state of charge to volts; "
                                 f"it returned something that is not an array of numbers ({err}).") \
                from None
        if out.shape != soc.shape:
            raise ParameterError(f"`ocv` ({self.ocv!r}) must return one voltage per sample of the "
                                 f"state of charge: shape {soc.shape} for {soc.size} samples; got "
                                 f"shape {out.shape}.")
        bad = np.flatnonzero(~np.isfinite(out))
        if bad.size:
            k = int(bad[0])
            raise ParameterError(f"`ocv` ({self.ocv!r}) returned {out[k]!r} at sample {k} (soc = "
                                 f"{float(soc[k])!r}), {bad.size} non-finite value(s) in all: the "
                                 "open-circuit voltage must be finite wherever the record goes.")
        return out

    def static_part(self, i, soc):
        """``OCV(soc) + a + b soc + R0 i + c3 i^3``: the terms without memory."""
        v = self.a + self.b * soc + self.r0 * i
        if self.ocv is not None:
            v = v + self.ocv_values(soc)
        if self.c3 is not None:
            v = v + self.c3 * i ** 3
        return v

    def simulate(self, u, *, initial=None):
        """Terminal voltage [V] for ``u = [current, state of charge]`` (elements at rest at k = 0).

        Parameters
        ----------
        u : array_like, shape (N, 2)
            Current [A] (``u[:, 0]``) and state of charge (``u[:, 1]``, the record's coulomb count).
        initial : None or "rest", optional
            The elements start at rest (the only state the circuit takes: nothing is known
            about the cell before the record except its state of charge, which is in ``u``).

        Returns
        -------
        ndarray, shape (N,)
        """
        _check_rest(initial)
        i, soc = self._signals(u)
        v = self.static_part(i, soc)
        for e in self.elements:
            v = v + e.response(i, self.dt)
        return v

    def simulate_at(self, u, t, *, intersample="zoh", refine=None, step=None):
        """Terminal voltage [V] at non-uniform instants ``t`` (:func:`fohw.model.irregular.simulate_at`).

        The static part (``OCV(soc) + a + b soc + R0 i + c3 i^3``) is read at the instants
        and the RC elements are solved exactly for the held current at any steps
        (:func:`fohw.model.irregular.rc_response_at`); ZARC and Warburg elements are simulated
        on the fine grid (``refine``, ``step``) and read at the instants. The first sample
        stands for the interval before ``t[0]`` of the first step's length, the elements at rest
        before it (:mod:`fohw.model.irregular`).
        """
        from . import irregular

        irregular.check_intersample(intersample)
        i, soc = self._signals(u)
        t = irregular.check_instants(t, i.size)
        v = self.static_part(i, soc)
        grid = None
        for e in self.elements:
            if e.kind == "rc":
                v = v + irregular.rc_response_at(e.R, e.tau, i, t, intersample)
                continue
            if grid is None:
                grid = irregular.fine_grid(t, refine=refine, step=step)
                fine = grid.hold(i, t, intersample)
            v = v + grid.read(e.response(fine, grid.step), t)
        return v

    def jacobian(self, u):
        """The simulated voltage and its exact derivatives by every parameter (:attr:`parameters` order).

        Returns
        -------
        v : ndarray, shape (N,)
        jac : ndarray, shape (N, n_parameters)
        """
        i, soc = self._signals(u)
        v = self.static_part(i, soc)
        cols = [np.ones_like(i), soc, i] + ([i ** 3] if self.c3 is not None else [])
        for e in self.elements:
            x, d = e.derivatives(i, self.dt)
            v = v + x
            cols += [d[n] for n in e.names]
        return v, np.column_stack(cols)

    def element_grid(self, k, params, fixed, tau_range):
        """The scan's ``(tau, alpha)`` points of element ``k`` (counted from 1).

        ``n_tau`` time constants log-spaced over ``tau_range``, ``n_alpha`` orders inside their
        bounds (from 0.2), fixed ones held; a Warburg element has no time constant (``None``).
        """
        kind = self.kinds[k - 1]
        if kind == "warburg":
            taus = [None]
        else:
            lo, hi = tau_range
            taus = np.geomspace(lo, hi, self.n_tau) if self.n_tau > 1 else \
                np.array([math.sqrt(lo * hi)])
        if kind == "rc":
            alphas = [1.0]
        else:
            lo, hi = params[f"alpha{k}"].bounds
            if self.n_alpha > 1:
                alphas = np.linspace(max(lo, 0.2), hi, self.n_alpha)
            else:
                alphas = np.array([hi if kind == "zarc" else 0.5 * (lo + hi)])
        g = [(t, a) for t in taus for a in alphas]
        if f"tau{k}" in fixed:
            g = [(fixed[f"tau{k}"], a) for a in sorted({a for _, a in g})]
        if f"alpha{k}" in fixed:
            g = [(t, fixed[f"alpha{k}"]) for t in sorted({t for t, _ in g}, key=lambda t: t or 0)]
        return g

    def starts(self, u, y, *, sample_weight=None):
        """Start circuits from a scan of the time constants and orders (linear parameters solved).

        For every combination of the elements' time constants (``n_tau`` log-spaced in their
        bounds) and orders (``n_alpha`` in their bounds, from 0.2 up), the parameters that enter
        linearly (``a, b, R0, c3`` and the resistances) are solved by linear least squares from
        one Gram matrix of all the grid's unit responses; combinations with a negative
        resistance are dropped (unless every one has one: then those, clipped to 0), same-kind
        elements keep increasing time constants (orders for Warburg elements), and fixed
        parameters keep their values. ``sample_weight`` (from :func:`fohw.fit`) weights the
        squares. The best ``SCAN_STARTS`` are returned (:func:`fohw.fit` refines its
        ``n_starts`` best). Without the scan, local searches of RC + ZARC mixtures were seen to
        end at ``alpha -> 1`` or ``alpha -> 0``. When no combination has non-negative
        resistances, the best few are projected onto the feasible set: their linear parameters
        re-solved by least squares with the resistances bounded below by 0
        (:func:`scipy.optimize.lsq_linear`), the nearest feasible point in the criterion's own
        metric, and ranked by their sum of squares there.

        Refused, each with its own message: a record whose current is zero at every sample (no
        excitation), a constant current (``R0 i`` is then the offset ``a``) unless ``a`` or
        ``R0`` is fixed, a record whose voltage falls with the current as the circuit counts it
        (:meth:`check_sign`: the other ``current_sign``), and a grid of more than
        ``MAX_GRID_STARTS`` combinations. (A constant voltage, and fewer samples than free
        parameters, are refused by :func:`fohw.fit` before the scan.)
        """
        i, soc = self._signals(u)
        y = check_array(y, "y")
        if not np.any(i):
            raise ParameterError("the current `u[:, 0]` is zero at every sample: the record has no "
                                 "excitation, so no resistance or time constant of the circuit can "
                                 "be identified from it.")
        params = self.parameters
        fixed = {n: p.value for n, p in params.items() if p.fixed}
        if np.ptp(i) == 0.0 and "a" not in fixed and "R0" not in fixed:
            raise ParameterError(
                f"the current `u[:, 0]` is constant ({float(i[0])!r} A at all {i.size} samples): "
                "R0 i is then a constant, which the offset `a` already is, so R0 cannot be "
                "identified; give a record in which the current changes (e.g. a rest before the "
                "pulse), or fix `a` or `R0` (circuit.parameters.replace(name, fixed=True)).")
        sw = np.ones(i.size) if sample_weight is None else np.sqrt(check_array(sample_weight,
                                                                                 "sample_weight"))
        ocv_v = self.ocv_values(soc)
        self.check_sign(i, y - ocv_v, sw)
        grids = []
        for k, kind in enumerate(self.kinds, start=1):
            lo, hi = params[f"tau{k}"].bounds if kind != "warburg" else (None, None)
            if kind != "warburg" and not math.isfinite(hi):   # the record's duration
                hi = max(i.size * self.dt, lo)
            grids.append(self.element_grid(k, params, fixed, (lo, hi)))
        n_combos = sum(1 for _ in itertools.islice(scan_combinations(self.kinds, grids, fixed),
                                                   MAX_GRID_STARTS + 1))
        if n_combos > MAX_GRID_STARTS:
            raise ParameterError(
                f"the start scan of this circuit (elements {', '.join(self.kinds)}) would solve "
                f"more than MAX_GRID_STARTS = {MAX_GRID_STARTS} combinations of grid points "
                f"(`n_tau` = {self.n_tau} time constants and `n_alpha` = {self.n_alpha} orders per "
                "element); lower `n_tau` or `n_alpha`, use fewer elements, or fix some time "
                "constants or orders.")
        found = _scan(self.kinds, self.c3 is not None, i, soc, y - ocv_v, self.dt, fixed, grids,
                      SCAN_STARTS, sw)
        tied = {n for n, p in params.items() if p.tie is not None}
        out = []
        for combo, coef in found:
            values = {n: x for n, x in coef.items()}
            for e, (kind, (tau, alpha)) in enumerate(zip(self.kinds, combo), start=1):
                r = f"sigma{e}" if kind == "warburg" else f"R{e}"
                values[r] = max(coef[r], 0.0)
                if kind != "warburg":
                    values[f"tau{e}"] = tau
                if kind != "rc":
                    values[f"alpha{e}"] = alpha
            values["R0"] = max(values["R0"], 0.0)
            out.append(self.with_parameters({n: x for n, x in values.items() if n not in tied}))
        return out

    def check_sign(self, i, v, sample_weight=None):
        """Refuse a record whose voltage falls when the current, as ``current_sign`` counts it, rises.

        The least-squares slope of the voltage's steps ``diff(v)`` on the current's steps
        ``diff(i)`` is ``R0`` plus the elements' share of the step (``Re Z > 0`` for a passive
        cell): positive. A slope below ``-SIGN_T`` standard errors (from the scatter of the
        steps about it) says the current is counted with the wrong sign; the error names the
        other convention. Steps between samples of zero weight are left out.

        Parameters
        ----------
        i : ndarray, shape (N,)
            The current as the circuit counts it (positive = charge).
        v : ndarray, shape (N,)
            The terminal voltage less the OCV map [V].
        sample_weight : ndarray, shape (N,), optional
            The steps where both ends have a positive weight are used.

        Raises
        ------
        ParameterError
            Naming both conventions, the slope and its t-statistic.
        """
        di, dv = np.diff(i), np.diff(v)
        if sample_weight is not None:
            keep = (sample_weight[1:] > 0) & (sample_weight[:-1] > 0)
            di, dv = di[keep], dv[keep]
        sxx = float(di @ di)
        if di.size < 3 or sxx == 0.0:
            return
        slope = float(di @ dv) / sxx
        scatter = dv - slope * di
        se = math.sqrt(float(scatter @ scatter) / (di.size - 1) / sxx)
        t = slope / se if se > 0 else (-math.inf if slope < 0 else math.inf)
        if t < -SIGN_T:
            other = CURRENT_SIGNS[1 - CURRENT_SIGNS.index(self.current_sign)]
            counted = ("a charge current positive" if self.current_sign == "charge_positive" else
                       "a discharge current positive")
            raise ParameterError(
                f"the voltage falls when the current rises: with current_sign="
                f"{self.current_sign!r} ({counted}), the slope of the voltage's steps on the "
                f"current's steps is {slope:.4g} V/A (t = {t:.3g} over {di.size} steps), where a "
                "cell's is positive (R0 plus its elements). The current `u[:, 0]` is given in the "
                f"other convention: build the circuit with current_sign={other!r}"
                + (" (PyBaMM's and most cyclers' convention)" if other == "discharge_positive"
                   else " (the shipped LG M50LT record's)") + ".")

    def check_fitted(self, u, y):
        """A sentence when every resistance ended at 0 (the voltage does not answer the current)."""
        rs = [self.r0] + [e.sigma if e.kind == "warburg" else e.R for e in self.elements]
        if any(r > 0 for r in rs):
            return None
        other = CURRENT_SIGNS[1 - CURRENT_SIGNS.index(self.current_sign)]
        return ("Every resistance of the fitted circuit is 0: its voltage does not answer the "
                f"current as a cell's does (a charge current raises it; with current_sign="
                f"{self.current_sign!r} a charge current is u[:, 0] "
                f"{'> 0' if self.current_sign == 'charge_positive' else '< 0'}). Check the sign "
                f"convention (current_sign={other!r}?) and the units of the current.")

    def config(self) -> dict:
        """The structure and settings: element kinds, current map, OCV table, ``dt``, scan grid.

        Raises
        ------
        ParameterError
            When the OCV map is a Python callable: it cannot be written to a file. Give an
            :class:`OCVTable` (``fohw.datasets.battery_cell().ocv_table()`` for the shipped cell).
        """
        if self.ocv is not None and not isinstance(self.ocv, OCVTable):
            raise ParameterError(
                f"this EquivalentCircuit's `ocv` is a Python callable ({self.ocv!r}), which cannot "
                "be written to a file; build the circuit with a tabulated OCV, "
                "ocv=fohw.OCVTable(soc, volts) (for the shipped cell: "
                "fohw.datasets.battery_cell().ocv_table()).")
        return {"elements": list(self.kinds), "current_map": self.c3 is not None,
                "ocv": None if self.ocv is None else self.ocv.to_dict(), "dt": self.dt,
                "tau_bounds": None if self.tau_bounds is None else list(self.tau_bounds),
                "n_tau": self.n_tau, "n_alpha": self.n_alpha, "current_sign": self.current_sign}

    @classmethod
    def from_config(cls, config) -> EquivalentCircuit:
        """A circuit of :meth:`config`'s structure with placeholder values."""
        config = dict(config)
        current_map = config.pop("current_map", False)
        if not isinstance(current_map, bool):
            raise ParameterError(f"`current_map` of a circuit's config must be true or false (with "
                                 f"or without the c3 i^3 term); got {current_map!r}.")
        elements = config.pop("elements")
        return cls(elements, c3=0.0 if current_map else None, **config)

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return (_same_map(self.ocv, other.ocv) and self.kinds == other.kinds and self.dt == other.dt
                and self.tau_bounds == other.tau_bounds and (self.n_tau, self.n_alpha) ==
                (other.n_tau, other.n_alpha) and self.current_sign == other.current_sign
                and self.parameters == other.parameters)

    __hash__ = None

    # --- frequency domain ------------------------------------------------------------------------
    def impedance(self, f, *, discrete=False, capacity=None, ocv_slope=0.0):
        """Impedance ``R0 + sum_e Z_e`` at frequencies ``f`` [Hz] (about zero current).

        Parameters
        ----------
        f : array_like
            Finite frequencies [Hz] (NaN and inf are refused; ``f = 0`` is refused where the
            impedance is infinite: a Warburg element, or the OCV's capacitor with ``capacity``).
        discrete : bool, optional
            True: the response of the model discretised at its step ``dt`` (the GL symbol in
            place of ``s``); default False: the continuous circuit.
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
        dt = self.dt if discrete else None
        f = check_array(f, "f", ndim=None, min_length=0)
        omega = _omega(f)
        z = np.full(omega.shape, self.r0, dtype=np.complex128)
        for e in self.elements:
            z = z + e.impedance(f, dt)
        if capacity is not None:
            capacity = check_scalar(capacity, "capacity", lower=0.0, lower_inclusive=False)
            slope = check_scalar(ocv_slope, "ocv_slope") + self.b
            with np.errstate(divide="ignore", invalid="ignore"):
                if dt is None:
                    integrator = 1.0 / (1j * omega)
                else:   # the coulomb count sums the current before the sample: dt z^-1 / (1 - z^-1)
                    zinv = np.exp(-1j * omega * dt)
                    integrator = dt * zinv / (1.0 - zinv)
                z = z + slope / (3600.0 * capacity) * integrator
            z = _finite_impedance(z, f, "the open-circuit voltage (capacity=)")
        return z

    #: :meth:`frequency_response` is an impedance (ohm): Nyquist plots draw the impedance plane.
    response_kind = "impedance"

    def frequency_response(self, omega, *, discrete=False, capacity=None, ocv_slope=0.0):
        """The impedance ``Z(j omega) = R0 + sum_e Z_e(j omega)`` [ohm] at angular frequencies [rad/s].

        The :meth:`fohw.Model.frequency_response` hook: :meth:`impedance` at ``f = omega / (2
        pi)``, about zero current (the cubic map ``c3 i^3`` has zero slope there; the
        parameters do not depend on the state of charge, so there is no other operating point).
        By default the continuous circuit without the OCV's capacitor; the keywords are those
        of :meth:`impedance`. :meth:`bode` and :meth:`nyquist` draw it (the Nyquist plot in the
        impedance plane, :attr:`response_kind`).

        Parameters
        ----------
        omega : array_like
            Finite angular frequencies [rad/s] (``omega = 0`` is refused where ``Z`` is infinite).
        discrete, capacity, ocv_slope
            As in :meth:`impedance` (defaults: continuous, no OCV capacitor, slope 0).

        Returns
        -------
        ndarray of complex, shape of ``omega``

        Examples
        --------
        >>> import numpy as np
        >>> from fohw.model.circuit import EquivalentCircuit, ZARC
        >>> cell = EquivalentCircuit([ZARC(0.01, 50.0, 1.0)], r0=0.015)
        >>> z = cell.frequency_response([1 / 50.0])           # R0 + R / (1 + j)
        >>> bool(np.isclose(z[0], 0.015 + 0.01 / (1 + 1j), rtol=1e-14, atol=0))
        True
        """
        omega = check_array(omega, "omega", ndim=None, min_length=0)
        try:
            return self.impedance(omega / (2.0 * np.pi), discrete=discrete, capacity=capacity,
                                  ocv_slope=ocv_slope)
        except ParameterError as err:
            if not str(err).startswith("`f` = "):
                raise
            raise ParameterError(f"`omega` = 2 pi f: {err}") from None

    def default_frequencies(self, n=400):
        """Two decades either side of the elements' corners ``1 / tau`` (the Model's grid without any)."""
        n = check_int(n, "n", minimum=2, maximum=1_000_000)
        taus = [e.tau for e in self.elements if e.kind != "warburg"]
        if not taus:
            return super().default_frequencies(n)
        return np.logspace(-np.log10(max(taus)) - 2.0, -np.log10(min(taus)) + 2.0, n)

    def response_label(self):
        """The curve's name in :meth:`bode` and :meth:`nyquist`."""
        return f"impedance Z(jω), {'+'.join(self.kinds) or 'R0 only'}"

    def __str__(self):
        parts = [f"{n} = {v:.6g}" for n, v in self.parameters.valuesdict().items()]
        return f"EquivalentCircuit({'+'.join(self.kinds) or 'R0 only'}: {', '.join(parts)})"

    def description(self):
        """The elements, the step and whether there is an OCV map (above the parameters' table)."""
        return [f"elements: {'+'.join(self.kinds) or 'R0 only'}",
                f"dt = {self.dt:g} s; OCV map: " + ("given" if self.ocv is not None else "none")]


def check_spectrum(f, z):
    """``(f, z)``: positive frequencies [Hz] and one finite, non-zero complex impedance each."""
    f = check_array(f, "f", min_length=1)
    bad = np.flatnonzero(f <= 0)
    if bad.size:
        raise ParameterError(f"`f` must be positive frequencies [Hz]; got {float(f[bad[0]])!r} at "
                             f"index {int(bad[0])}.")
    try:
        z = np.asarray(z, dtype=np.complex128).ravel()
    except (TypeError, ValueError):
        raise ParameterError(f"`z` must be an array of complex impedances [ohm]; got "
                             f"{type(z).__name__}.") from None
    if z.shape != f.shape:
        raise ParameterError(f"`z` must have one value per frequency; got {z.shape[0]} values for "
                             f"{f.shape[0]} frequencies.")
    bad = np.flatnonzero(~np.isfinite(z) | (z == 0))
    if bad.size:
        k = int(bad[0])
        raise ParameterError(f"`z` must be finite and non-zero at every frequency (a relative "
                             f"error needs |z| > 0); got {z[k]!r} at index {k} (f = {f[k]:g} Hz), "
                             f"{bad.size} such value(s) in all. Drop those frequencies.")
    return f, z


def impedance_error(circuit, f, z, band=None, *, discrete=False, capacity=None, ocv_slope=0.0):
    """Relative error ``|Z_model - Z| / |Z|`` of a circuit's impedance against a measured spectrum.

    Parameters
    ----------
    circuit : EquivalentCircuit or FitResult
        The circuit, or a :func:`fohw.fit` result of one (its fitted ``model``).
    f : array_like, shape (m,)
        Frequencies [Hz], finite and positive.
    z : array_like of complex, shape (m,)
        Measured impedance [ohm], finite and non-zero (a NaN is refused, never scored).
    band : (float, float), optional
        Keep the frequencies in ``[low, high]`` [Hz]; default all.
    discrete : bool, optional
        Use the GL-discretised model's response at its ``dt`` (see
        :meth:`EquivalentCircuit.impedance`).
    capacity, ocv_slope : float, optional
        Add the OCV's capacitor (see :meth:`EquivalentCircuit.impedance`).

    Returns
    -------
    f, model, rel : ndarray
        The frequencies kept, the model's impedance there and the relative errors; the RMS
        relative error is ``sqrt(mean(rel**2))``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit import EquivalentCircuit, ZARC, impedance_error
    >>> cell = EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015)
    >>> f = np.logspace(-3, 0, 7)
    >>> kept, zm, rel = impedance_error(cell, f, 1.1 * cell.impedance(f), band=(1e-3, 0.1))
    >>> kept.size, np.round(rel, 4)          # |Z - 1.1 Z| / |1.1 Z| = 0.1 / 1.1
    (5, array([0.0909, 0.0909, 0.0909, 0.0909, 0.0909]))
    """
    if not isinstance(circuit, EquivalentCircuit):
        model = getattr(circuit, "model", None)         # a FitResult of a circuit
        if not isinstance(model, EquivalentCircuit):
            what = type(circuit).__name__ + ("" if model is None else f" of a {type(model).__name__}")
            raise ParameterError(f"`circuit` must be an EquivalentCircuit or a fohw.fit result of "
                                 f"one; got {what}.")
        circuit = model
    f, z = check_spectrum(f, z)
    keep = np.ones(f.shape, dtype=bool)
    if band is not None:
        try:
            low, high = (float(x) for x in band)
        except (TypeError, ValueError):
            raise ParameterError(f"`band` must be a pair (low, high) [Hz]; got {band!r}.") from None
        if not low <= high:
            raise ParameterError(f"`band` must be (low, high) with low <= high; got {band!r}.")
        keep = (f >= low) & (f <= high)
        if not keep.any():
            raise ParameterError(f"`band` {band!r} holds none of the frequencies "
                                 f"({f.min():g} to {f.max():g} Hz).")
    model = circuit.impedance(f[keep], discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)
    return f[keep], model, np.abs(model - z[keep]) / np.abs(z[keep])


def _same_map(a, b):
    """Whether two OCV maps are one: the same object, equal tables, or ``==`` callables.

    A function equals only itself; a bound method equals the same method of the same object
    (``cell.ocv == cell.ocv``), though each access makes a new one.
    """
    if a is b:
        return True
    try:
        return bool(a == b)
    except (TypeError, ValueError):     # a callable whose == gives an array
        return False


def _check_rest(initial):
    if initial is not None and not (isinstance(initial, str) and initial == "rest"):
        raise ParameterError(f"an EquivalentCircuit starts at rest (`initial` None or 'rest'); got "
                             f"{initial!r}. Its slow state, the state of charge, is the input "
                             "column u[:, 1].")


def unit_columns(kinds, grids, column):
    """``{(kind, tau, alpha): column(element)}`` for every distinct grid point, unit resistance.

    The linear columns the grid scans share (a held ``tau`` of ``None`` builds with 1).
    """
    out = {}
    for kind, g in zip(kinds, grids):
        for tau, alpha in g:
            if (kind, tau, alpha) not in out:
                out[(kind, tau, alpha)] = column(
                    make_element(kind, 1.0, tau if tau is not None else 1.0, alpha))
    return out


def scan_combinations(kinds, grids, fixed):
    """The combinations of grid points the scan visits, generated without the skipped ones.

    Same-kind elements are interchangeable: their time constants (Warburg: orders) increase
    along the circuit, except those the user holds.
    """
    key = []
    for e, kind in enumerate(kinds):
        name = f"{'alpha' if kind == 'warburg' else 'tau'}{e + 1}"
        key.append(None if name in fixed else 1 if kind == "warburg" else 0)
    prefix = []

    def visit(e, last):
        if e == len(kinds):
            yield tuple(prefix)
            return
        j, kind = key[e], kinds[e]
        for point in grids[e]:
            if j is not None and kind in last and not point[j] > last[kind]:
                continue
            prefix.append(point)
            yield from visit(e + 1, last if j is None else {**last, kind: point[j]})
            prefix.pop()

    yield from visit(0, {})


def _scan(kinds, cubic, i, soc, y, dt, fixed, grids, keep, sw):
    """Best grid points by linear least squares of the linear parameters: ``[(combo, coef)]``."""
    base = [np.ones_like(i), soc, i] + ([i ** 3] if cubic else [])
    base_names = ["a", "b", "R0"] + (["c3"] if cubic else [])
    responses = unit_columns(kinds, grids, lambda e: e.unit_response(i, dt))
    keys = list(responses)
    cols = np.column_stack(base + [responses[k] for k in keys]) * sw[:, None]
    y = y * sw
    scale = np.sqrt(np.sum(cols ** 2, axis=0))
    scale[scale == 0] = 1.0
    cols = cols / scale
    gram = cols.T @ cols
    rhs = cols.T @ y
    yy = float(y @ y)
    nb = len(base)
    index = {k: nb + j for j, k in enumerate(keys)}
    names = base_names + [f"R{e + 1}" if kinds[e] != "warburg" else f"sigma{e + 1}"
                          for e in range(len(kinds))]
    found, negative = [], []
    for combo in scan_combinations(kinds, grids, fixed):
        idx = list(range(nb)) + [index[(kinds[e], t, a)] for e, (t, a) in enumerate(combo)]
        free = [j for j, n in zip(idx, names) if n not in fixed]
        fix = [(j, fixed[n]) for j, n in zip(idx, names) if n in fixed]
        r = rhs[free] - sum((gram[free, j] * v * scale[j] for j, v in fix), np.zeros(len(free)))
        sub = gram[np.ix_(free, free)]
        try:
            c = np.linalg.solve(sub, r)
        except np.linalg.LinAlgError:       # e.g. two elements held at one time constant
            c = np.linalg.lstsq(sub, r, rcond=None)[0]
        coef = dict(zip([n for n in names if n not in fixed], c / scale[free]))
        bad = coef.get("R0", 0.0) < 0 or any(coef[n] < 0 for n in coef if n[0] in "Rs" and n != "R0")
        if bad and found:
            continue
        full = np.zeros(len(idx))
        for p, (j, n) in enumerate(zip(idx, names)):
            full[p] = fixed[n] * scale[j] if n in fixed else coef[n] * scale[j]
        gsub = gram[np.ix_(idx, idx)]
        rss = yy - 2 * float(full @ rhs[idx]) + float(full @ gsub @ full)
        (negative if bad else found).append(
            (rss, tuple(combo), {**{n: fixed[n] for n in names if n in fixed}, **coef}))
    if not found:
        # No point of non-negative resistances (e.g. an order held where the record does not
        # want it): the best few, projected onto the feasible set (their linear parameters
        # re-solved with the resistances >= 0), ranked by their sum of squares there.
        negative.sort(key=lambda t: t[0])
        for _, combo, _ in negative[:PROJECTED_STARTS * keep]:
            idx = list(range(nb)) + [index[(kinds[e], t, a)] for e, (t, a) in enumerate(combo)]
            free = [(j, n) for j, n in zip(idx, names) if n not in fixed]
            target = y - sum((cols[:, j] * scale[j] * fixed[n] for j, n in zip(idx, names)
                              if n in fixed), np.zeros(y.size))
            lower = [0.0 if n == "R0" or n[0] in "Rs" else -np.inf for _, n in free]
            sol = scipy.optimize.lsq_linear(cols[:, [j for j, _ in free]], target,
                                            bounds=(lower, np.inf))
            coef = {n: max(float(c) / scale[j], 0.0) if lo == 0.0 else float(c) / scale[j]
                    for (j, n), c, lo in zip(free, sol.x, lower)}
            found.append((2.0 * float(sol.cost), tuple(combo),
                          {**{n: fixed[n] for n in names if n in fixed}, **coef}))
    found.sort(key=lambda t: t[0])
    return [(combo, coef) for _, combo, coef in found[:keep]]
