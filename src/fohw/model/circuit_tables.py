"""An equivalent circuit whose parameters vary with state of charge and temperature (breakpoint tables).

The circuit of :class:`fohw.EquivalentCircuit` (``R0`` and RC/ZARC elements beside a known
open-circuit voltage), with every resistance, time constant and the voltage offset given at
breakpoints of the state of charge and the temperature, the way PyBaMM's equivalent-circuit
parameter sets are written (``R0(SOC, T)``, ``R1(SOC, T)``, ``tau1(SOC, T)``, ...), and
interpolated linearly between them (held at the end values outside the table, which
:meth:`CircuitTables.simulate` warns of), or, with
``temperature_interpolation="arrhenius"``, their logarithms linearly in SOC and ``1/T``. The orders of
the ZARC elements are shared by every breakpoint (one ``alpha`` per element).

The input has three columns, ``u = [current, soc, temperature]`` (``[A]``, fraction of the
capacity, ``[degC]``); the output is the terminal voltage. With ``p(k)`` the interpolated value
of a table at ``(soc[k], T[k])``:

``v[k] = OCV(soc[k]) + a(k) + R0(k) i[k] + sum_e R_e(k) z_e[k]``,

``z_e[k] + r_e[k] sum_{j=0}^{k} beta_j(alpha_e) z_e[k-j] = i[k]``, ``r_e[k] = (tau_e(k)/dt)^alpha_e``

(the GL discretisation of ``(tau s)^alpha z + z = i``, implicit, at rest before ``k = 0``;
``alpha = 1`` for an RC element: backward Euler), so ``z_e`` is the current through the
element's resistor and ``R_e(k) z_e[k]`` its voltage, as PyBaMM's ECM writes an RC pair. With
constant ``soc`` and ``T`` this is :class:`fohw.EquivalentCircuit` exactly.

A smoothing penalty keeps neighbouring breakpoints close (:meth:`CircuitTables.penalty`):
``smoothing * sum (ln p_b - ln p_b')^2`` over every pair of neighbours ``b, b'`` along either
axis of every resistance and time-constant table, added to the squared simulation error by
:func:`fohw.fit`. Its weight ``smoothing`` is in V^2 (the units of the squared error): with
``smoothing = 1e-4``, a 10 % step between neighbours (``ln 1.1 = 0.095``) costs ``9e-7`` V^2, as
much as one sample off by 0.95 mV. The offsets ``a`` are not smoothed (one per record, in
effect, when records sit at the breakpoints).
"""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import scipy

from .._threads import thin_solves
from .._validation import RANGE_TOLERANCE, check_array, check_int, check_scalar, input_in_range
from ..exceptions import ExtrapolationWarning, ParameterError
from .base import Model
from .circuit import CURRENT_SIGNS, RC, ZARC, EquivalentCircuit, OCVTable
from .gl import gl_weights_derivative, gl_weights_unchecked
from .kernels import HalfMerge, causal_product, divide_and_conquer
from .parameters import Parameter, Parameters

__all__ = ["CircuitTables", "table_weights", "varying_solve", "R_MIN", "SCAN_STARTS"]

#: Lower bound of every tabulated resistance [ohm]: the smoothing works on logarithms.
R_MIN = 1e-6

#: Scan starts :meth:`CircuitTables.starts` returns.
SCAN_STARTS = 4

_LEAF = 64


def _axis_weights(x, points):
    """``(N, m)`` linear-interpolation weights of ``x`` on ``points`` (end values held outside)."""
    m = points.shape[0]
    w = np.zeros((x.shape[0], m))
    if m == 1:
        w[:, 0] = 1.0
        return w
    xc = np.clip(x, points[0], points[-1])
    j = np.clip(np.searchsorted(points, xc, side="right") - 1, 0, m - 2)
    t = (xc - points[j]) / (points[j + 1] - points[j])
    rows = np.arange(x.shape[0])
    w[rows, j] = 1.0 - t
    w[rows, j + 1] += t
    return w


def table_weights(soc, temperature, soc_points, temperature_points, *, arrhenius=False):
    """Bilinear weights ``(N, n_soc * n_T)`` of every sample on the breakpoints (soc-major order).

    Outside the table the end values are held (no extrapolation). A table ``P`` (shape
    ``(n_soc, n_T)``) is then ``weights @ P.ravel()`` at every sample. With ``arrhenius``, the
    temperature coordinate is ``-1 / (T + 273.15)`` (degC in, kelvin inside) instead of ``T``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit_tables import table_weights
    >>> w = table_weights(np.array([0.4, 0.9]), np.array([10.0, 25.0]), np.array([0.3, 0.5]),
    ...                   np.array([0.0, 20.0]))
    >>> np.round(w, 3)          # (0.4, 10): the middle of the four; (0.9, 25): the corner
    array([[0.25, 0.25, 0.25, 0.25],
           [0.  , 0.  , 0.  , 1.  ]])
    """
    ws = _axis_weights(soc, soc_points)
    if arrhenius:
        temperature = -1.0 / (np.asarray(temperature) + 273.15)
        temperature_points = -1.0 / (np.asarray(temperature_points) + 273.15)
    wt = _axis_weights(temperature, temperature_points)
    return (ws[:, :, None] * wt[:, None, :]).reshape(soc.shape[0], -1)


def varying_solve(r, beta, f):
    """Solve ``z[k] + r[k] sum_{j=0}^{k} beta[j] z[k-j] = f[k]`` for one or more forcings ``f``.

    The GL element with a coefficient ``r[k]`` that changes from sample to sample (a time
    constant that follows the state of charge and the temperature), by the online convolution
    of :func:`fohw.model.kernels.divide_and_conquer` (``O(N log^2 N)``): blocks of samples are
    solved as lower-triangular systems ``(I + diag(r) T_beta) z = f - r * past``.

    Parameters
    ----------
    r : ndarray, shape (N,)
    beta : ndarray, shape (N,)
        The GL weights (``beta[0] = 1``).
    f : ndarray, shape (N,) or (N, m)

    Returns
    -------
    ndarray, the shape of ``f``

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit_tables import varying_solve
    >>> varying_solve(np.array([1.0, 1.0, 1.0]), np.array([1.0, -1.0, 0.0]), np.ones(3))
    array([0.5  , 0.75 , 0.875])
    """
    f = np.asarray(f, dtype=np.float64)
    one = f.ndim == 1
    f2 = f[:, None] if one else f
    n = f2.shape[0]
    z = np.zeros((1,) + f2.shape)
    past = np.zeros((1,) + f2.shape)
    size = max(1, min(_LEAF, n))
    toeplitz = scipy.linalg.toeplitz(beta[:size], np.zeros(size))
    merge = HalfMerge([beta], [(0, 0, 0)])

    def leaf(lo, hi):
        m = hi - lo
        a = np.eye(m) + r[lo:hi, None] * toeplitz[:m, :m]
        rhs = f2[lo:hi] - r[lo:hi, None] * past[0, lo:hi]
        z[0, lo:hi] = scipy.linalg.solve_triangular(a, rhs, lower=True, check_finite=False)

    divide_and_conquer(n, size, leaf, lambda lo, mid, hi: merge(z, past, lo, mid, hi))
    return z[0, :, 0] if one else z[0]


def _table_names(table, soc_points, temperature_points):
    return [f"{table}_s{s:g}_T{t:g}" for s in soc_points for t in temperature_points]


class CircuitTables(Model):
    """A battery cell's equivalent circuit with parameters tabulated over state of charge and temperature.

    A :class:`fohw.Model`: ``u = [current, soc, temperature]`` (``u[:, 0]`` in A, in the sign
    ``current_sign`` says, as :class:`fohw.EquivalentCircuit`; ``u[:, 1]`` the coulomb-counted
    state of charge; ``u[:, 2]`` in degC), output the terminal voltage [V].

    Parameters
    ----------
    elements : sequence of {"rc", "zarc"}
        The dynamic elements, in series.
    soc_points, temperature_points : sequence of float
        The breakpoints (strictly increasing; one point makes the tables constant along that axis).
    values : mapping, optional
        Start values: a table name (``"a"``, ``"R0"``, ``"R1"``, ``"tau1"``, ...) to a scalar or
        an array of shape ``(n_soc, n_T)``, and ``"alpha1"``, ... to a scalar. Defaults: ``a``
        0, resistances 10 mOhm, time constants the geometric middle of ``tau_bounds``, orders 0.5.
    ocv : OCVTable, callable or None, optional
        The known open-circuit voltage ``OCV(soc)`` [V] (as :class:`fohw.EquivalentCircuit`).
    dt : float, optional
        Sampling time [s].
    tau_bounds : (float, float), optional
        Bounds of every time constant [s]; default ``(dt, 1000 dt)``.
    smoothing : float, optional
        Weight [V^2] of the penalty that keeps neighbouring breakpoints close (module
        docstring); 0 (default): none.
    n_tau, n_alpha : int, optional
        The start scan's grid (:meth:`starts`).
    current_sign : {"charge_positive", "discharge_positive"}, optional
        The sign convention of ``u[:, 0]`` (default: a charge current is positive); a fit checks
        the record against it (:meth:`fohw.EquivalentCircuit.check_sign`).
    temperature_interpolation : {"linear", "arrhenius"}, optional
        ``"linear"`` (default, as PyBaMM's tables): every table linear in SOC and temperature
        between breakpoints. ``"arrhenius"``: the logarithm of every resistance and time constant
        linear in SOC and in ``1 / T`` (kelvin), so a parameter that follows
        ``exp(E / (R T))`` between two temperature breakpoints is interpolated exactly; the
        offsets stay linear (in SOC and ``1 / T``).

    Notes
    -----
    Parameters, in order: the table ``a`` (one ``a_s{soc}_T{T}`` per breakpoint), ``R0``, then
    each element's ``R{e}`` and ``tau{e}`` tables and, for a ZARC, its ``alpha{e}``.
    Resistances are at least ``R_MIN`` (their logarithms are smoothed), time constants inside
    ``tau_bounds``, orders in ``[0.05, 1]``; an order's value and any bounds given to it lie in a
    ZARC's domain ``(0, 1]`` (as :class:`fohw.EquivalentCircuit`'s), else refused.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit_tables import CircuitTables
    >>> cell = CircuitTables(["zarc"], soc_points=[0.5], temperature_points=[0.0, 40.0],
    ...                      values={"R0": [[0.03, 0.01]], "R1": 0.01, "tau1": 5.0, "alpha1": 0.6})
    >>> u = np.column_stack([np.r_[0.0, -5.0, -5.0], np.full(3, 0.5), np.full(3, 20.0)])
    >>> np.round(cell.simulate(u) * 1e3, 3)   # mV: R0(20 degC) = 20 mOhm; r = 5**0.6 = 2.6265:
    array([   0.   , -113.787, -119.779])

    (``-100 - 10 * 5 / (1 + r)`` and ``-100 + 10 (-5 - 0.6 r * 5 / (1 + r)) / (1 + r)`` mV.)
    """

    def __init__(self, elements, *, soc_points, temperature_points, values=None, ocv=None, dt=1.0,
                 tau_bounds=None, smoothing=0.0, n_tau=6, n_alpha=5,
                 temperature_interpolation="linear", current_sign="charge_positive"):
        if isinstance(elements, str):
            raise ParameterError(f"`elements` must be a sequence of 'rc' or 'zarc'; got {elements!r} "
                                 "(write [element] for one).")
        kinds = tuple(elements)
        for k, e in enumerate(kinds):
            if e not in ("rc", "zarc"):
                raise ParameterError(f"`elements[{k}]` must be 'rc' or 'zarc'; got {e!r}.")
        self.kinds = kinds
        self.soc_points = self._points(soc_points, "soc_points")
        self.temperature_points = self._points(temperature_points, "temperature_points")
        if self.temperature_points[0] <= -273.15:
            raise ParameterError(f"`temperature_points` are in degC and must lie above absolute zero "
                                 f"(-273.15 degC); got {self.temperature_points.tolist()!r} (the "
                                 "Arrhenius interpolation works in 1 / (T + 273.15)).")
        self.step = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
        if tau_bounds is None:
            tau_bounds = (self.dt, 1000.0 * self.dt)
        try:
            lo, hi = (float(x) for x in tau_bounds)
        except (TypeError, ValueError):
            raise ParameterError(f"`tau_bounds` must be a pair (low, high); got "
                                 f"{tau_bounds!r}.") from None
        if not 0.0 < lo < hi < math.inf:
            raise ParameterError(f"`tau_bounds` must be finite and increasing with 0 < low; got "
                                 f"{tau_bounds!r}.")
        self.tau_bounds = (lo, hi)
        self.smoothing = check_scalar(smoothing, "smoothing", lower=0.0)
        self.n_tau = check_int(n_tau, "n_tau", minimum=1)
        self.n_alpha = check_int(n_alpha, "n_alpha", minimum=1)
        if temperature_interpolation not in ("linear", "arrhenius"):
            raise ParameterError(f"`temperature_interpolation` must be 'linear' or 'arrhenius'; got "
                                 f"{temperature_interpolation!r}.")
        self.temperature_interpolation = temperature_interpolation
        if not (isinstance(current_sign, str) and current_sign in CURRENT_SIGNS):
            raise ParameterError(f"`current_sign` must be one of {', '.join(map(repr, CURRENT_SIGNS))} "
                                 f"(the sign of a charge current in u[:, 0]); got {current_sign!r}.")
        self.current_sign = current_sign
        if isinstance(ocv, dict):
            ocv = OCVTable.from_dict(ocv)
        if ocv is not None and not callable(ocv):
            raise ParameterError(f"`ocv` must be an OCVTable, a callable (soc -> volts) or None; "
                                 f"got {ocv!r}.")
        self.ocv = ocv
        shape = (self.soc_points.size, self.temperature_points.size)
        defaults = {"a": 0.0, "R0": 0.01}
        for e, kind in enumerate(kinds, start=1):
            defaults[f"R{e}"] = 0.01
            defaults[f"tau{e}"] = math.sqrt(lo * hi)
            if kind == "zarc":
                defaults[f"alpha{e}"] = 0.5
        values = dict(values or {})
        unknown = sorted(set(values) - set(defaults))
        if unknown:
            raise ParameterError(f"`values` has no tables or orders named {unknown}; this circuit's "
                                 f"are {sorted(defaults)}.")
        self.tables, self.alphas = {}, {}
        for name, default in defaults.items():
            v = values.get(name, default)
            if name.startswith("alpha"):
                # a ZARC's order domain, (0, 1], as fohw.model.circuit.ZARC checks it
                self.alphas[name] = check_scalar(v, f"values[{name!r}]", lower=0.0, upper=1.0,
                                                 lower_inclusive=False)
                continue
            arr = np.asarray(v, dtype=np.float64)
            if arr.ndim == 0:
                arr = np.full(shape, float(arr))
            if arr.shape != shape:
                raise ParameterError(f"`values[{name!r}]` must be a scalar or of shape {shape} (soc "
                                     f"points x temperature points); got shape {arr.shape}.")
            self.tables[name] = arr.copy()

    @staticmethod
    def _points(points, name):
        p = check_array(points, name, min_length=1)
        if np.any(np.diff(p) <= 0):
            raise ParameterError(f"`{name}` must increase strictly; got {p.tolist()!r}.")
        return p

    # --- the Model protocol -------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Sampling time [s]."""
        return self.step

    @property
    def n_inputs(self) -> int:
        """Three input columns: current, state of charge, temperature."""
        return 3

    def _table_order(self):
        out = ["a", "R0"]
        for e, kind in enumerate(self.kinds, start=1):
            out += [f"R{e}", f"tau{e}"] + ([f"alpha{e}"] if kind == "zarc" else [])
        return out

    def check_settings(self, parameters):
        """Refuse a ZARC order's bounds beyond its domain ``(0, 1]``, naming the parameter.

        The rule of :meth:`fohw.EquivalentCircuit.check_settings` (applied by it, to a circuit of
        the same elements): a ZARC of order 0 is outside the class, order 1 is an RC element.
        """
        EquivalentCircuit([ZARC(1.0, 1.0, 1.0) if kind == "zarc" else RC(1.0, 1.0)
                           for kind in self.kinds]).check_settings(parameters)

    @property
    def parameters(self) -> Parameters:
        """The tables' breakpoint values and the orders (see Notes)."""
        out = []
        for name in self._table_order():
            if name.startswith("alpha"):
                out.append(Parameter(name, self.alphas[name], bounds=ZARC.order_bounds, order=True))
                continue
            bounds = (None if name == "a" else self.tau_bounds if name.startswith("tau")
                      else (R_MIN, math.inf))
            for pname, v in zip(_table_names(name, self.soc_points, self.temperature_points),
                                self.tables[name].ravel()):
                out.append(Parameter(pname, v, bounds=bounds))
        return Parameters(out)

    def with_parameters(self, values) -> CircuitTables:
        """The same circuit with new breakpoint values (a mapping ``name -> float``, or Parameters)."""
        v = self.parameters.with_values(values).valuesdict()
        shape = (self.soc_points.size, self.temperature_points.size)
        new = {}
        for name in self._table_order():
            if name.startswith("alpha"):
                new[name] = v[name]
            else:
                new[name] = np.array([v[p] for p in _table_names(name, self.soc_points,
                                                                 self.temperature_points)]).reshape(shape)
        return CircuitTables(self.kinds, soc_points=self.soc_points,
                             temperature_points=self.temperature_points, values=new, ocv=self.ocv,
                             dt=self.dt, tau_bounds=self.tau_bounds, smoothing=self.smoothing,
                             n_tau=self.n_tau, n_alpha=self.n_alpha,
                             temperature_interpolation=self.temperature_interpolation,
                             current_sign=self.current_sign)

    def config(self) -> dict:
        """Structure and settings (JSON values); the OCV map must be an :class:`fohw.OCVTable`."""
        if self.ocv is not None and not isinstance(self.ocv, OCVTable):
            raise ParameterError(f"this CircuitTables' `ocv` is a Python callable ({self.ocv!r}), which "
                                 "cannot be written to a file; give ocv=fohw.OCVTable(soc, volts).")
        return {"elements": list(self.kinds), "soc_points": self.soc_points.tolist(),
                "temperature_points": self.temperature_points.tolist(),
                "ocv": None if self.ocv is None else self.ocv.to_dict(), "dt": self.dt,
                "tau_bounds": list(self.tau_bounds), "smoothing": self.smoothing,
                "n_tau": self.n_tau, "n_alpha": self.n_alpha,
                "temperature_interpolation": self.temperature_interpolation,
                "current_sign": self.current_sign}

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        same_ocv = self.ocv is other.ocv or (isinstance(self.ocv, OCVTable) and self.ocv == other.ocv)
        settings = ("kinds", "step", "tau_bounds", "smoothing", "n_tau", "n_alpha",
                    "temperature_interpolation", "current_sign")
        return (same_ocv and all(getattr(self, n) == getattr(other, n) for n in settings)
                and np.array_equal(self.soc_points, other.soc_points)
                and np.array_equal(self.temperature_points, other.temperature_points)
                and self.parameters == other.parameters)

    __hash__ = None

    # --- simulation ---------------------------------------------------------------------------
    def _signals(self, u):
        u = self.check_input(u)
        i, soc, temp = (np.ascontiguousarray(u[:, j]) for j in range(3))
        if self.current_sign == "discharge_positive":
            i = -i
        bad = np.flatnonzero((soc < 0.0) | (soc > 1.0))
        if bad.size:
            k = int(bad[0])
            raise ParameterError(f"the state of charge `u[:, 1]` must be in [0, 1]; got "
                                 f"{float(soc[k])!r} at sample {k}. The columns are [current, soc, "
                                 "temperature].")
        bad = np.flatnonzero((temp < -100.0) | (temp > 200.0))
        if bad.size:
            k = int(bad[0])
            raise ParameterError(f"the temperature `u[:, 2]` must be in degC (-100 to 200); got "
                                 f"{float(temp[k])!r} at sample {k} (kelvin? subtract 273.15).")
        return i, soc, temp

    @staticmethod
    def _check_within(x, points, what, name):
        """Warn (ExtrapolationWarning) when ``x`` leaves the breakpoints (the end values held).

        Beyond them by more than ``RANGE_TOLERANCE`` of their span (the rule of the lagged
        kind's estimation range: a record at an end breakpoint drifts past it a little).
        """
        if points.size < 2 or input_in_range(x, (points[0], points[-1])):
            return                          # one point: the tables are constant along this axis
        slack = RANGE_TOLERANCE * (points[-1] - points[0])
        outside = np.flatnonzero((x < points[0] - slack) | (x > points[-1] + slack))
        k = int(outside[0])
        warnings.warn(ExtrapolationWarning(
            f"{what} leaves the breakpoints `{name}` [{points[0]:g}, {points[-1]:g}] (by more "
            f"than {RANGE_TOLERANCE:.0%} of their span) at {outside.size} of {x.size} samples "
            f"(first: {float(x[k]):g} at sample {k}); the tables are held at their end values "
            "there, not extrapolated: check the simulation before trusting it, or add "
            "breakpoints that cover the record."), stacklevel=3)

    def weights(self, u):
        """``(N, n_soc * n_T)`` interpolation weights of the record's samples (:func:`table_weights`)."""
        _, soc, temp = self._signals(u)
        return self._weights(soc, temp)

    def _weights(self, soc, temp):
        return table_weights(soc, temp, self.soc_points, self.temperature_points,
                             arrhenius=self.temperature_interpolation == "arrhenius")

    def _ocv(self, soc):
        if self.ocv is None:
            return np.zeros_like(soc)
        out = np.asarray(self.ocv(soc), dtype=np.float64)
        if out.shape != soc.shape or not np.all(np.isfinite(out)):
            raise ParameterError(f"`ocv` ({self.ocv!r}) must return one finite voltage per sample.")
        return out

    def value(self, name, w):
        """Table ``name`` at the samples of interpolation weights ``w`` (``temperature_interpolation``)."""
        flat = self.tables[name].ravel()
        if self.temperature_interpolation == "arrhenius" and name != "a":
            return np.exp(w @ np.log(flat))
        return w @ flat

    def _dvalue(self, name, w, p):
        """``d value / d breakpoint``, ``(N, n_breakpoints)``, given the values ``p``."""
        if self.temperature_interpolation == "arrhenius" and name != "a":
            return p[:, None] * w / self.tables[name].ravel()
        return w

    def element_current(self, e, i, w, *, derivatives=False):
        """``z`` of element ``e`` (1-based): the current through its resistor, for weights ``w``.

        With ``derivatives``, also ``dz`` by each of its time-constant breakpoints and (a ZARC)
        its order, as columns; else ``None``.
        """
        kind = self.kinds[e - 1]
        alpha = self.alphas.get(f"alpha{e}", 1.0)
        tau = self.value(f"tau{e}", w)
        n = i.shape[0]
        r = (tau / self.dt) ** alpha
        beta = gl_weights_unchecked(alpha, n) if kind == "zarc" else np.r_[1.0, -1.0, np.zeros(n - 2)][:n]
        if not derivatives:
            return varying_solve(r, beta, i), None
        z = varying_solve(r, beta, i)
        bz = causal_product(beta, z, n)
        dr_tau = (alpha * r / tau)[:, None] * self._dvalue(f"tau{e}", w, tau)   # d r / d tau_b
        forcing = [-dr_tau * bz[:, None]]
        if kind == "zarc":
            dbeta = gl_weights_derivative(alpha, n)
            dr_alpha = r * np.log(tau / self.dt)
            forcing.append((-dr_alpha * bz - r * causal_product(dbeta, z, n))[:, None])
        dz = varying_solve(r, beta, np.concatenate(forcing, axis=1))
        return z, dz

    def simulate(self, u, *, initial=None):
        """Terminal voltage [V] for ``u = [current, soc, temperature]`` (elements at rest at k = 0).

        Warns (:class:`fohw.ExtrapolationWarning`) when the state of charge or the temperature
        leaves the breakpoints (by more than ``RANGE_TOLERANCE``, 5 %, of their span): the
        tables are held at their end values there.
        """
        if initial is not None and not (isinstance(initial, str) and initial == "rest"):
            raise ParameterError(f"a CircuitTables starts at rest (`initial` None or 'rest'); got "
                                 f"{initial!r}.")
        i, soc, temp = self._signals(u)
        self._check_within(soc, self.soc_points, "the state of charge `u[:, 1]`", "soc_points")
        self._check_within(temp, self.temperature_points, "the temperature `u[:, 2]`",
                           "temperature_points")
        w = self._weights(soc, temp)
        v = self._ocv(soc) + self.value("a", w) + self.value("R0", w) * i
        for e in range(1, len(self.kinds) + 1):
            z, _ = self.element_current(e, i, w)
            v = v + self.value(f"R{e}", w) * z
        return v

    @thin_solves
    def jacobian(self, u):
        """The voltage and its exact derivatives by every parameter (:attr:`parameters` order)."""
        i, soc, temp = self._signals(u)
        w = self._weights(soc, temp)
        r0 = self.value("R0", w)
        v = self._ocv(soc) + self.value("a", w) + r0 * i
        cols = [w, self._dvalue("R0", w, r0) * i[:, None]]
        for e, kind in enumerate(self.kinds, start=1):
            z, dz = self.element_current(e, i, w, derivatives=True)
            rk = self.value(f"R{e}", w)
            v = v + rk * z
            nb = w.shape[1]
            cols += [self._dvalue(f"R{e}", w, rk) * z[:, None], rk[:, None] * dz[:, :nb]]
            if kind == "zarc":
                cols.append(rk[:, None] * dz[:, nb:])
        return v, np.concatenate(cols, axis=1)

    # --- regularisation -----------------------------------------------------------------------
    def _pairs(self):
        """``(first, second)`` flat indices of the neighbouring breakpoints (SOC pairs first)."""
        ns, nt = self.soc_points.size, self.temperature_points.size
        idx = np.arange(ns * nt).reshape(ns, nt)
        return (np.concatenate([idx[:-1, :].ravel(), idx[:, :-1].ravel()]),
                np.concatenate([idx[1:, :].ravel(), idx[:, 1:].ravel()]))

    def penalty(self):
        """``(r, J)``: the smoothing residuals ``sqrt(smoothing) (ln p_b - ln p_b')`` and their Jacobian.

        One residual per pair of neighbouring breakpoints (along either axis) of every
        resistance and time-constant table; ``J`` has a column per parameter
        (:attr:`parameters` order). ``None`` when ``smoothing`` is 0 or the tables have one
        breakpoint. :func:`fohw.fit` adds ``r @ r`` to the squared simulation error.
        """
        first, second = self._pairs()
        if self.smoothing == 0.0 or not first.size:
            return None
        names = list(self.parameters.names)
        c = math.sqrt(self.smoothing)
        rows, jac = [], []
        for table in self._table_order():
            if table == "a" or table.startswith("alpha"):
                continue
            flat = self.tables[table].ravel()
            col0 = names.index(_table_names(table, self.soc_points, self.temperature_points)[0])
            rows.append(c * (np.log(flat[first]) - np.log(flat[second])))
            j = np.zeros((first.size, len(names)))
            j[np.arange(first.size), col0 + first] = c / flat[first]
            j[np.arange(first.size), col0 + second] = -c / flat[second]
            jac.append(j)
        return np.concatenate(rows), np.concatenate(jac)

    # --- starts -------------------------------------------------------------------------------
    @thin_solves
    def starts(self, u, y, *, sample_weight=None):
        """Starts from a scan: every time constant at one grid value per element, orders on a grid.

        For each combination (``n_tau`` log-spaced time constants per element inside the bounds
        of its table's parameters, ``n_alpha`` orders per ZARC inside its order's bounds, from
        0.2 up), the tables that enter linearly (``a``, ``R0`` and the resistances) are solved by
        least squares, resistances clipped to ``R_MIN``; the best ``SCAN_STARTS`` are returned.
        (With ``"arrhenius"`` interpolation the values between breakpoints are taken as linear
        in the breakpoints' for this step: exact at the breakpoints, a start elsewhere.)
        A time-constant table with a fixed entry keeps its values, as does a fixed order.
        """
        i, soc, temp = self._signals(u)
        y = check_array(y, "y")
        if not np.any(i):
            raise ParameterError("the current `u[:, 0]` is zero at every sample: the record has no "
                                 "excitation, so no resistance or time constant can be identified.")
        sw = np.ones(i.size) if sample_weight is None else np.sqrt(check_array(sample_weight,
                                                                                 "sample_weight"))
        w = self._weights(soc, temp)
        overpotential = y - self._ocv(soc)
        # the record against the current's sign convention (the circuit's own check)
        EquivalentCircuit([], current_sign=self.current_sign).check_sign(i, overpotential, sw)
        target = overpotential * sw
        params = self.parameters
        grids = []
        for e, kind in enumerate(self.kinds, start=1):
            names = _table_names(f"tau{e}", self.soc_points, self.temperature_points)
            if any(params[n].fixed or params[n].tie is not None for n in names):
                taus = [None]                   # the table as it is
            else:
                lo = max(params[n].bounds[0] for n in names)
                hi = min(params[n].bounds[1] for n in names)
                taus = np.geomspace(lo, hi, self.n_tau) if self.n_tau > 1 else [math.sqrt(lo * hi)]
            if kind == "rc":
                alphas = [1.0]
            elif params[f"alpha{e}"].fixed or params[f"alpha{e}"].tie is not None:
                alphas = [self.alphas[f"alpha{e}"]]
            else:
                lo, hi = params[f"alpha{e}"].bounds
                alphas = np.linspace(max(lo, 0.2), hi, self.n_alpha) if self.n_alpha > 1 and \
                    max(lo, 0.2) < hi else [0.5 * (lo + hi)]
            grids.append([(t, a) for t in taus for a in alphas])
        base = np.concatenate([w, w * i[:, None]], axis=1)
        cache = {}
        found = []
        for combo in itertools.product(*grids):
            if any(combo[k][0] is not None and combo[k + 1][0] is not None
                   and combo[k][0] >= combo[k + 1][0] for k in range(len(combo) - 1)
                   if self.kinds[k] == self.kinds[k + 1]):
                continue                        # same-kind elements: increasing time constants
            cols = [base]
            for e, (kind, (tau, alpha)) in enumerate(zip(self.kinds, combo), start=1):
                key = (e if tau is None else kind, tau, alpha)
                if key not in cache:
                    if tau is None:             # the held table: the varying solve
                        probe = self._with_tables({f"alpha{e}": alpha} if kind == "zarc" else {})
                        cache[key] = probe.element_current(e, i, w)[0]
                    else:
                        el = RC(1.0, tau) if kind == "rc" else ZARC(1.0, tau, alpha)
                        cache[key] = el.unit_response(i, self.dt)
                cols.append(w * cache[key][:, None])
            x = np.concatenate(cols, axis=1) * sw[:, None]
            coef, *_ = np.linalg.lstsq(x, target, rcond=None)
            rss = float(np.sum((x @ coef - target) ** 2))
            found.append((rss, combo, coef))
        found.sort(key=lambda t: t[0])
        nb = w.shape[1]
        out = []
        for _, combo, coef in found[:SCAN_STARTS]:
            values = {"a": coef[:nb].reshape(self.tables["a"].shape),
                      "R0": np.maximum(coef[nb:2 * nb], R_MIN).reshape(self.tables["a"].shape)}
            for e, (kind, (tau, alpha)) in enumerate(zip(self.kinds, combo), start=1):
                seg = coef[(1 + e) * nb:(2 + e) * nb]
                values[f"R{e}"] = np.maximum(seg, R_MIN).reshape(self.tables["a"].shape)
                if tau is not None:
                    values[f"tau{e}"] = tau
                if kind == "zarc":
                    values[f"alpha{e}"] = alpha
            out.append(self._with_tables(values))
        return out

    def _with_tables(self, values):
        shape = (self.soc_points.size, self.temperature_points.size)
        flat = {}
        for name, v in values.items():
            if name.startswith("alpha"):
                flat[name] = float(v)
            else:
                arr = np.broadcast_to(np.asarray(v, dtype=float), shape)
                flat.update(zip(_table_names(name, self.soc_points, self.temperature_points),
                                arr.ravel().tolist()))
        params = self.parameters
        return self.with_parameters({n: x for n, x in flat.items() if not params[n].fixed
                                     and params[n].tie is None})

    def table(self, name):
        """The table ``name`` (``"R0"``, ``"tau1"``, ...) as an ``(n_soc, n_T)`` array (a copy)."""
        if name not in self.tables:
            raise ParameterError(f"no table {name!r}; this circuit's are {sorted(self.tables)}.")
        return self.tables[name].copy()

    # --- frequency domain -----------------------------------------------------------------------
    #: :meth:`frequency_response` is an impedance (ohm): Nyquist plots draw the impedance plane.
    response_kind = "impedance"

    def at(self, soc=None, temperature=None):
        """The :class:`fohw.EquivalentCircuit` of the tables at one state of charge and temperature.

        With ``soc`` and ``T`` held, the model is that circuit exactly (module docstring): its
        ``R0`` and its elements' resistances and time constants are the tables' interpolated
        values there (``temperature_interpolation``), its orders the shared ones.

        Parameters
        ----------
        soc : float, optional
            State of charge in ``[0, 1]``. Needed when the tables have more than one SOC
            breakpoint; default the single one.
        temperature : float, optional
            Temperature [degC]. Needed when the tables have more than one temperature
            breakpoint; default the single one.

        Returns
        -------
        EquivalentCircuit
            Without the offset table and the OCV (they do not enter the impedance), at the same
            ``dt``.

        Examples
        --------
        >>> from fohw.model.circuit_tables import CircuitTables
        >>> cell = CircuitTables(["rc"], soc_points=[0.5], temperature_points=[0.0, 40.0],
        ...                      values={"R0": [[0.03, 0.01]], "R1": 0.01, "tau1": 5.0})
        >>> round(cell.at(temperature=10.0).r0, 6)               # 3/4 of 0.03 + 1/4 of 0.01
        0.025
        """
        point = {}
        for name, value, points, low, high, unit in (
                ("soc", soc, self.soc_points, 0.0, 1.0, "a fraction of the capacity"),
                ("temperature", temperature, self.temperature_points, -100.0, 200.0, "degC")):
            if value is None:
                if points.size > 1:
                    raise ParameterError(
                        f"the tables of this CircuitTables vary with `{name}` (breakpoints "
                        f"{points.tolist()}), so its impedance needs the operating point: give "
                        f"{name}=... ({unit}).")
                value = float(points[0])
            point[name] = check_scalar(value, name, lower=low, upper=high)
        w = self._weights(np.array([point["soc"]]), np.array([point["temperature"]]))
        elements = []
        for e, kind in enumerate(self.kinds, start=1):
            R, tau = float(self.value(f"R{e}", w)[0]), float(self.value(f"tau{e}", w)[0])
            elements.append(ZARC(R, tau, self.alphas[f"alpha{e}"]) if kind == "zarc" else RC(R, tau))
        return EquivalentCircuit(elements, r0=float(self.value("R0", w)[0]), dt=self.dt,
                                 tau_bounds=self.tau_bounds, current_sign=self.current_sign)

    def frequency_response(self, omega, *, soc=None, temperature=None, discrete=False):
        """The impedance ``Z(j omega)`` [ohm] at angular frequencies [rad/s], at ``(soc, temperature)``.

        The :meth:`fohw.Model.frequency_response` hook: ``R0 + sum_e R_e / (1 + (j omega
        tau_e)^alpha_e)`` with the tables' values at the operating point (:meth:`at`), about
        zero current. ``soc`` and ``temperature`` default to the tables' single breakpoint
        along an axis that has one, and are required along an axis with several (refused
        naming them). ``discrete``: the GL-discretised model's response at its ``dt``
        (:meth:`fohw.EquivalentCircuit.impedance`). :meth:`bode` and :meth:`nyquist` pass their
        keywords on (``cell.bode(soc=0.5, temperature=25.0)``).

        Returns
        -------
        ndarray of complex, shape of ``omega``
        """
        return self.at(soc, temperature).frequency_response(omega, discrete=discrete)

    def default_frequencies(self, n=400):
        """Two decades either side of the corners ``1 / tau`` over every breakpoint of the tables."""
        n = check_int(n, "n", minimum=2, maximum=1_000_000)
        taus = np.concatenate([self.tables[f"tau{e}"].ravel() for e in range(1, len(self.kinds) + 1)]
                              or [np.array([self.dt])])
        return np.logspace(-np.log10(taus.max()) - 2.0, -np.log10(taus.min()) + 2.0, n)

    def response_label(self):
        """The curve's name in :meth:`bode` and :meth:`nyquist`."""
        return f"impedance Z(jω), {'+'.join(self.kinds) or 'R0 only'}"

    def description(self):
        """The elements, the breakpoints and the step (above the parameters' table)."""
        return [f"elements: {'+'.join(self.kinds) or 'R0 only'}; soc points "
                f"{self.soc_points.tolist()}, temperature points {self.temperature_points.tolist()} degC",
                f"dt = {self.dt:g} s; temperature interpolation {self.temperature_interpolation}; "
                f"OCV map: {'given' if self.ocv is not None else 'none'}"]

    def __repr__(self):
        return (f"CircuitTables({'+'.join(self.kinds) or 'R0 only'}, soc points "
                f"{self.soc_points.tolist()}, temperature points {self.temperature_points.tolist()}, "
                f"{len(self.parameters)} parameters)")

