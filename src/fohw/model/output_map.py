"""The series output block ``y = h(z)`` after the fractional HW recursion — beyond the paper.

The paper's class (Eq. 16) feeds the output nonlinearity ``g`` back inside the recursion, so a
sensor that saturates (``y = sat(x)``) is not in it. A *series* output map ``h`` acts on the
output ``z`` of the whole model instead: ``y[k] = h(z[k]; eta)``, ``z`` being the recursion of
Eq. 14/16 (SPEC §3). With ``h`` the identity this is today's model; with ``g`` the identity it
is the classical series Hammerstein–Wiener model ``u -> f -> linear fractional block -> h``
(MATLAB's ``nlhw``).

**Units.** ``h`` acts in the *data's units*: ``z`` is the model's output after the operating
point ``y0`` has been added back, and ``h(z)`` is the measured output, so saturation limits and
dead zones are in volts (or whatever ``y`` is measured in). Inside the estimators, which work on
deviations ``y - y0``, the map is applied as ``h(z_dev + y0) - y0``.

Maps (each with named parameters ``h_*``, their derivative in ``z`` and in the parameters,
a start that makes ``h`` the identity over the data, and a JSON form):

* :class:`Saturation` ``clip(z, lower, upper)``: limits free or fixed;
* :class:`DeadZone`: ``0`` on ``[lower, upper]``, ``z - upper`` above, ``z - lower`` below;
* :class:`PiecewiseLinear`: linear interpolation through ``(z_i, v_i)``, extrapolated with
  the end slopes; values free, breakpoints fixed or free;
* :class:`PolynomialMap` ``z + c_2 z^2 + … + c_n z^n`` (the gain and level of ``z`` belong
  to the linear block), or monotone ``∫_0^z (1 + p_1 t + … + p_m t^m)^2 dt`` (degree ``2m+1``);
* :class:`CustomMap`: a user's function with its derivatives (stored by name only: code is
  never serialised, as for a custom :class:`fohw.Basis`).

:func:`as_output_map` turns ``None | "saturation" | "deadzone" | "piecewise_linear" | int |
SeriesMap`` into a map.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Union

import numpy as np

from .._validation import check_array, check_int, check_scalar
from ..exceptions import DimensionError, ParameterError

__all__ = ["SeriesMap", "Saturation", "DeadZone", "PiecewiseLinear", "PolynomialMap", "CustomMap",
           "as_output_map", "output_map_from_dict", "OutputMapLike", "OUTPUT_MAP_NAMES",
           "MAX_MAP_DEGREE"]

#: The ``output_map`` strings.
OUTPUT_MAP_NAMES = ("saturation", "deadzone", "piecewise_linear")
#: The highest degree of a polynomial map (as for :func:`fohw.polynomial_basis`, 100).
MAX_MAP_DEGREE = 100
#: Breakpoints of ``"piecewise_linear"`` when given as a string.
DEFAULT_BREAKPOINTS = 5


def _limit(value, name, infinite):
    """A fixed limit (a finite number, or the one infinity ``infinite`` that means none), or None."""
    if value is None:
        return None
    if isinstance(value, str) and value in ("inf", "-inf"):      # the JSON form of infinity
        value = float(value)
    if isinstance(value, (float, np.floating)) and value == infinite:
        return float(value)
    return check_scalar(value, name)


class SeriesMap:
    """Base class of the series output maps ``y = h(z; eta)`` (data units; module notes).

    Subclasses define :attr:`kind`, :attr:`names` (the free parameters ``eta``),
    :meth:`evaluate`, :meth:`derivative` (``dh/dz``), :meth:`param_jacobian`
    (``dh/deta``), :meth:`start` and :meth:`to_dict`.
    """

    kind = "output_map"

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the free parameters (``h_*``)."""
        raise NotImplementedError

    @property
    def n_params(self) -> int:
        """Number of free parameters."""
        return len(self.names)

    def evaluate(self, z, params) -> np.ndarray:
        """``h(z; params)`` elementwise."""
        raise NotImplementedError

    def derivative(self, z, params) -> np.ndarray:
        """``dh/dz`` elementwise."""
        raise NotImplementedError

    def param_jacobian(self, z, params) -> np.ndarray:
        """``dh/dparams``, shape ``(len(z), n_params)``."""
        raise NotImplementedError

    def resolve(self, y) -> SeriesMap:
        """The map with anything chosen from the data fixed (breakpoints); itself by default."""
        return self

    def check_data(self, y) -> None:
        """Refuse a map that cannot describe a record with output ``y`` (data units)."""

    def start(self, z, y) -> np.ndarray:
        """Parameters that make ``h`` the identity (or a clip to the data) over the record.

        ``z``: the free run of the model without ``h``; ``y``: the measured output (both in
        data units).
        """
        return np.zeros(0)

    def scale(self, y) -> np.ndarray:
        """Typical size of each parameter for a record with output ``y`` (data units).

        The output's RMS (limits, values, breakpoints: data units) by default.
        """
        return np.full(self.n_params, max(float(np.sqrt(np.mean(np.square(y)))), 1e-300))

    def transform(self, params0, y):
        """``(T, lower, upper)``: the solver works on ``w`` with ``params = T @ w``, bounded.

        Identity and unbounded by default; ordered parameters (limits, breakpoints) are
        searched as the first one and non-negative increments, so they never cross.
        """
        n = self.n_params
        return np.eye(n), np.full(n, -np.inf), np.full(n, np.inf)

    def inverse(self, y, params) -> np.ndarray:
        """A ``z`` with ``h(z) = y`` (used for a measured history); not every map has one."""
        raise ParameterError(f"the output map {self.describe()} has no inverse, so a measured "
                             "history `(u_hist, y_hist)` cannot be turned into the model's "
                             "internal output z: simulate without `history`.")

    def describe(self) -> str:
        """One short line."""
        return self.kind

    def formula(self, params) -> str:
        """``h`` at the parameter values ``params`` as one line.

        Examples
        --------
        >>> from fohw.model.output_map import DeadZone, PolynomialMap, Saturation
        >>> Saturation().formula([-1.0, 1.0]), PolynomialMap(3).formula([-0.2, 0.0])
        ('h(z) = clip(z, -1, 1)', 'h(z) = z - 0.2 z^2')
        >>> DeadZone().formula([-0.5, 0.5])
        'h = deadzone(lower=free, upper=free) with h_lower = -0.5, h_upper = 0.5'
        """
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        values = ", ".join(f"{n} = {v:g}" for n, v in zip(self.names, params))
        return f"h = {self.describe()}" + (f" with {values}" if values else "")

    def to_dict(self) -> dict:
        """A JSON-ready description (no parameter values: those are the result's)."""
        raise NotImplementedError

    def check_params(self, params, name="output map parameters") -> np.ndarray:
        """``params`` as a finite vector of :attr:`n_params` entries."""
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        if params.shape != (self.n_params,):
            raise DimensionError(f"the {name} {self.names} need {self.n_params} value(s); got "
                                 f"shape {params.shape}.")
        if not np.all(np.isfinite(params)):
            raise ParameterError(f"the {name} must be finite; got {params}.")
        return params

    def __eq__(self, other):
        return type(self) is type(other) and self.to_dict() == other.to_dict()

    def __hash__(self):
        return hash(repr(self.to_dict()))

    def __repr__(self):
        return f"{type(self).__name__}({self.describe()})"


class _TwoLimits(SeriesMap):
    """Saturation and dead zone: two limits, each free (None) or fixed (a number)."""

    def __init__(self, lower=None, upper=None):
        self.lower = _limit(lower, f"{self.kind} lower", -np.inf)
        self.upper = _limit(upper, f"{self.kind} upper", np.inf)
        if self.lower is not None and self.upper is not None and not self.lower < self.upper:
            raise ParameterError(f"the {self.kind} limits must satisfy lower < upper; got lower = "
                                 f"{self.lower!r}, upper = {self.upper!r}.")

    @property
    def names(self):
        return tuple(n for n, v in (("h_lower", self.lower), ("h_upper", self.upper))
                     if v is None)

    def limits(self, params):
        """``(lower, upper)`` with the free ones from ``params``."""
        params = np.atleast_1d(params)
        it = iter(params.tolist())
        lo = next(it) if self.lower is None else self.lower
        hi = next(it) if self.upper is None else self.upper
        return lo, hi

    def transform(self, params0, y):
        n = self.n_params
        if n == 2:                             # lower, and upper - lower >= 0
            return (np.array([[1.0, 0.0], [1.0, 1.0]]), np.array([-np.inf, 0.0]),
                    np.array([np.inf, np.inf]))
        lo, hi = np.full(n, -np.inf), np.full(n, np.inf)
        if n == 1 and self.lower is None:
            hi[0] = self.upper
        elif n == 1:
            lo[0] = self.lower
        return np.eye(n), lo, hi

    def describe(self):
        def one(v):
            return "free" if v is None else f"{v:g}"
        return f"{self.kind}(lower={one(self.lower)}, upper={one(self.upper)})"

    def to_dict(self):
        def one(v):                    # JSON holds no infinity: "-inf" / "inf"
            return v if v is None or np.isfinite(v) else str(v)
        return {"kind": self.kind, "lower": one(self.lower), "upper": one(self.upper)}


class Saturation(_TwoLimits):
    """``h(z) = clip(z, lower, upper)``: a sensor or actuator saturation (data units).

    Parameters
    ----------
    lower, upper : float or None
        Fixed limits, or None for a free limit (estimated; named ``h_lower``, ``h_upper``).
        The start puts a free limit at the measured output's smallest or largest value.
        ``lower=-numpy.inf`` (or ``upper=numpy.inf``) is a one-sided saturation, e.g. a level
        sensor that saturates at its top only: ``Saturation(lower=-numpy.inf)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.output_map import Saturation
    >>> sat = Saturation(upper=10.0)
    >>> sat.names, sat.evaluate(np.array([-1.0, 5.0, 12.0]), [0.0])
    (('h_lower',), array([ 0.,  5., 10.]))
    """

    kind = "saturation"

    def evaluate(self, z, params):
        """As :meth:`SeriesMap.evaluate`."""
        lo, hi = self.limits(params)
        return np.clip(np.asarray(z, dtype=np.float64), lo, hi)

    def derivative(self, z, params):
        """As :meth:`SeriesMap.derivative`."""
        lo, hi = self.limits(params)
        z = np.asarray(z, dtype=np.float64)
        return ((z > lo) & (z < hi)).astype(np.float64)

    def param_jacobian(self, z, params):
        """As :meth:`SeriesMap.param_jacobian`."""
        lo, hi = self.limits(params)
        z = np.asarray(z, dtype=np.float64)
        cols = []
        if self.lower is None:
            cols.append((z <= lo).astype(np.float64))
        if self.upper is None:
            cols.append((z >= hi).astype(np.float64))
        return np.column_stack(cols) if cols else np.zeros((z.shape[0], 0))

    def check_data(self, y):
        """As :meth:`SeriesMap.check_data`."""
        lo, hi = float(np.min(y)), float(np.max(y))
        if self.lower is not None and self.lower >= hi or self.upper is not None \
                and self.upper <= lo:
            raise ParameterError(f"`output_map` {self.describe()} leaves the measured output "
                                 f"(from {lo:.6g} to {hi:.6g}) entirely at one limit: nothing "
                                 "of the model's output would be seen. Check the limits "
                                 "(they are in the data's units).")

    def start(self, z, y):
        """As :meth:`SeriesMap.start`."""
        out = []
        if self.lower is None:
            out.append(float(np.min(y)) if self.upper is None else min(float(np.min(y)),
                                                                           self.upper))
        if self.upper is None:
            out.append(float(np.max(y)) if self.lower is None else max(float(np.max(y)),
                                                                           self.lower))
        return np.array(out, dtype=np.float64)

    def inverse(self, y, params):
        """As :meth:`SeriesMap.inverse`: the identity, exact only inside the limits.

        A measured history that sits at a limit does not tell the model output ``z`` behind
        it (any ``z`` beyond the limit gives the same ``y``); the history then continues from
        ``z = y`` there, an approximation (0.2 % of the output's range in a test that
        continued a saturated noise-free record).
        """
        return np.asarray(y, dtype=np.float64).copy()     # within the limits h is the identity

    def formula(self, params):
        """As :meth:`SeriesMap.formula`."""
        lo, hi = self.limits(params)
        return f"h(z) = clip(z, {lo:g}, {hi:g})"


class DeadZone(_TwoLimits):
    """``h(z) = 0`` on ``[lower, upper]``, ``z - upper`` above and ``z - lower`` below.

    Parameters
    ----------
    lower, upper : float or None
        Fixed ends of the dead zone, or None for a free one (``h_lower``, ``h_upper``),
        in the data's units. The start is the identity, a zone of width 0 at 0 (a free end next
        to a fixed one starts at the fixed one).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.output_map import DeadZone
    >>> DeadZone().evaluate(np.array([-2.0, 0.5, 3.0]), [-1.0, 1.0])
    array([-1.,  0.,  2.])
    """

    kind = "deadzone"

    def evaluate(self, z, params):
        """As :meth:`SeriesMap.evaluate`."""
        lo, hi = self.limits(params)
        z = np.asarray(z, dtype=np.float64)
        return np.where(z > hi, z - hi, np.where(z < lo, z - lo, 0.0))

    def derivative(self, z, params):
        """As :meth:`SeriesMap.derivative`."""
        lo, hi = self.limits(params)
        z = np.asarray(z, dtype=np.float64)
        return ((z > hi) | (z < lo)).astype(np.float64)

    def param_jacobian(self, z, params):
        """As :meth:`SeriesMap.param_jacobian`."""
        lo, hi = self.limits(params)
        z = np.asarray(z, dtype=np.float64)
        cols = []
        if self.lower is None:
            cols.append(-(z < lo).astype(np.float64))
        if self.upper is None:
            cols.append(-(z > hi).astype(np.float64))
        return np.column_stack(cols) if cols else np.zeros((z.shape[0], 0))

    def check_data(self, y):
        """As :meth:`SeriesMap.check_data`."""
        lo, hi = float(np.min(y)), float(np.max(y))
        if self.lower is not None and self.upper is not None and self.lower <= lo \
                and self.upper >= hi:
            raise ParameterError(f"`output_map` {self.describe()} is wider than the data: the "
                                 f"measured output lies from {lo:.6g} to {hi:.6g}, inside the "
                                 "dead zone, so a model output near it would be mapped to 0 "
                                 "everywhere. Check the limits (they are in the data's units).")
        if self.lower is not None and self.lower > hi or self.upper is not None and self.upper < lo:
            side = "above" if self.lower is not None and self.lower > hi else "below"
            raise ParameterError(f"`output_map` {self.describe()} lies entirely {side} the measured "
                                 f"output (from {lo:.6g} to {hi:.6g}): the data never reach the dead "
                                 "zone, so it is not seen in them and the fit would only shift the "
                                 "output. Check the limits (they are in the data's units).")

    def start(self, z, y):
        """As :meth:`SeriesMap.start`."""
        if self.lower is None and self.upper is None:
            return np.zeros(2)
        if self.lower is None:
            return np.array([min(0.0, self.upper)])
        return np.array([max(0.0, self.lower)])

    def inverse(self, y, params):
        """As :meth:`SeriesMap.inverse`."""
        lo, hi = self.limits(params)
        y = np.asarray(y, dtype=np.float64)
        return np.where(y > 0, y + hi, np.where(y < 0, y + lo, 0.5 * (lo + hi)))


class PiecewiseLinear(SeriesMap):
    """Linear interpolation through ``(z_i, v_i)``, extrapolated with the end segments' slopes.

    Parameters
    ----------
    breakpoints : int or sequence of float
        The breakpoints ``z_i`` (increasing, at least 2), or how many: then placed evenly over
        the measured output's range when the model is fitted (:meth:`resolve`).
    free_breakpoints : bool
        Estimate the breakpoints too (named ``h_z1``…; they stay ordered). Default False.

    Notes
    -----
    The values ``v_i`` (``h_v1``…) are always free; they start at ``v_i = z_i`` (the identity).

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.output_map import PiecewiseLinear
    >>> h = PiecewiseLinear([0.0, 1.0, 2.0])
    >>> h.evaluate(np.array([-1.0, 0.5, 3.0]), [0.0, 2.0, 2.0])
    array([-2.,  1.,  2.])
    """

    kind = "piecewise_linear"

    def __init__(self, breakpoints=DEFAULT_BREAKPOINTS, free_breakpoints=False):
        if not isinstance(free_breakpoints, (bool, np.bool_)):
            raise ParameterError(f"`free_breakpoints` must be True or False; got "
                                 f"{free_breakpoints!r}.")
        self.free_breakpoints = bool(free_breakpoints)
        if isinstance(breakpoints, (int, np.integer)) and not isinstance(breakpoints, bool):
            self.n_breakpoints = check_int(breakpoints, "breakpoints", minimum=2, maximum=1000)
            self.breakpoints = None
        else:
            bp = check_array(breakpoints, "breakpoints", min_length=2)
            if not np.all(np.diff(bp) > 0):
                raise ParameterError(f"`breakpoints` must be increasing; got {bp.tolist()}.")
            self.breakpoints = bp
            self.n_breakpoints = bp.shape[0]

    @property
    def names(self):
        """Names of the free parameters (``h_*``)."""
        n = self.n_breakpoints
        return (tuple(f"h_v{i + 1}" for i in range(n))
                + (tuple(f"h_z{i + 1}" for i in range(n)) if self.free_breakpoints else ()))

    def resolve(self, y):
        """As :meth:`SeriesMap.resolve`."""
        if self.breakpoints is not None:
            return self
        lo, hi = float(np.min(y)), float(np.max(y))
        if not lo < hi:
            raise ParameterError("`output_map` 'piecewise_linear' places its breakpoints over "
                                 f"the measured output's range, but the output is constant "
                                 f"({lo!r}): give the breakpoints.")
        return PiecewiseLinear(np.linspace(lo, hi, self.n_breakpoints), self.free_breakpoints)

    def _parts(self, params):
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        n = self.n_breakpoints
        if self.breakpoints is None:
            raise ParameterError("the piecewise-linear map has no breakpoints yet (an int "
                                 "places them on the data when fitted): give them.")
        v = params[:n]
        b = params[n:2 * n] if self.free_breakpoints else self.breakpoints
        return v, b

    def _segments(self, z, params):
        v, b = self._parts(params)
        z = np.asarray(z, dtype=np.float64)
        i = np.clip(np.searchsorted(b, z, side="right") - 1, 0, b.shape[0] - 2)
        width = b[i + 1] - b[i]
        t = (z - b[i]) / width
        slope = (v[i + 1] - v[i]) / width
        return v, b, i, t, slope

    def evaluate(self, z, params):
        """As :meth:`SeriesMap.evaluate`."""
        v, _, i, t, _ = self._segments(z, params)
        return v[i] + t * (v[i + 1] - v[i])

    def derivative(self, z, params):
        """As :meth:`SeriesMap.derivative`."""
        return self._segments(z, params)[4]

    def param_jacobian(self, z, params):
        """As :meth:`SeriesMap.param_jacobian`."""
        v, b, i, t, slope = self._segments(z, params)
        n, rows = self.n_breakpoints, np.arange(t.shape[0])
        J = np.zeros((t.shape[0], self.n_params))
        J[rows, i] += 1.0 - t
        J[rows, i + 1] += t
        if self.free_breakpoints:
            J[rows, n + i] += -slope * (1.0 - t)
            J[rows, n + i + 1] += -slope * t
        return J

    def check_data(self, y):
        """As :meth:`SeriesMap.check_data`: fixed breakpoints must not all lie on one side of ``y``."""
        if self.breakpoints is None or self.free_breakpoints:
            return
        lo, hi = float(np.min(y)), float(np.max(y))
        b = self.breakpoints
        if hi <= b[0] or lo >= b[-1]:
            side = "above" if hi <= b[0] else "below"
            raise ParameterError(f"`output_map` {self.describe()} has every breakpoint {side} the "
                                 f"measured output (from {lo:.6g} to {hi:.6g}): the data see one "
                                 "straight end segment, so the values at the other breakpoints "
                                 "cannot be estimated. Check the breakpoints (they are in the "
                                 "data's units) or let fohw place them (an int).")

    def start(self, z, y):
        """As :meth:`SeriesMap.start`."""
        b = self.breakpoints
        return np.r_[b, b] if self.free_breakpoints else b.copy()

    def transform(self, params0, y):
        """As :meth:`SeriesMap.transform`."""
        n, m = self.n_breakpoints, self.n_params
        if not self.free_breakpoints:
            return np.eye(m), np.full(m, -np.inf), np.full(m, np.inf)
        T = np.eye(m)
        T[n:, n:] = np.tril(np.ones((n, n)))          # z_1, then increments
        span = float(np.ptp(params0[n:])) or 1.0
        lo = np.r_[np.full(n + 1, -np.inf), np.full(n - 1, 1e-6 * span / n)]
        return T, lo, np.full(m, np.inf)

    def describe(self):
        """As :meth:`SeriesMap.describe`."""
        if self.breakpoints is None:
            where = f"{self.n_breakpoints} breakpoints on the data's range"
        else:
            where = "breakpoints " + ", ".join(f"{x:g}" for x in self.breakpoints)
        return f"piecewise_linear({where}{', free' if self.free_breakpoints else ''})"

    def to_dict(self):
        """As :meth:`SeriesMap.to_dict`."""
        bp = self.n_breakpoints if self.breakpoints is None else self.breakpoints.tolist()
        return {"kind": self.kind, "breakpoints": bp, "free_breakpoints": self.free_breakpoints}


class PolynomialMap(SeriesMap):
    """A polynomial output map of degree ``n`` in the data's units, the identity at its start.

    ``h(z) = z + c_2 z^2 + … + c_n z^n`` (``h_c2``…); the gain and the level of ``z`` belong to
    the linear block. ``monotone=True`` (odd degree ``n = 2m + 1``) is
    ``h(z) = ∫_0^z (1 + p_1 t + … + p_m t^m)^2 dt`` (``h_p1``…), increasing whatever the
    parameters, since ``h'(z) = (1 + p_1 z + …)^2 >= 0``.

    Parameters
    ----------
    degree : int
        ``1 <= degree <= 100`` (1: the identity, no parameter).
    monotone : bool
        Default False.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.output_map import PolynomialMap
    >>> PolynomialMap(3).evaluate(np.array([1.0, 2.0]), [0.5, 0.1])
    array([1.6, 4.8])
    >>> PolynomialMap(3, monotone=True).names
    ('h_p1',)
    """

    kind = "polynomial"

    def __init__(self, degree, monotone=False):
        self.degree = check_int(degree, "output_map degree", minimum=1, maximum=MAX_MAP_DEGREE)
        if not isinstance(monotone, (bool, np.bool_)):
            raise ParameterError(f"`monotone` must be True or False; got {monotone!r}.")
        self.monotone = bool(monotone)
        if self.monotone and self.degree % 2 == 0:
            raise ParameterError(f"a monotone polynomial output map has an odd degree 2m + 1 "
                                 f"(the integral of a squared polynomial); got degree "
                                 f"{self.degree}.")

    @property
    def names(self):
        """Names of the free parameters (``h_*``)."""
        if self.monotone:
            return tuple(f"h_p{i}" for i in range(1, (self.degree - 1) // 2 + 1))
        return tuple(f"h_c{j}" for j in range(2, self.degree + 1))

    def coefficients(self, params):
        """Coefficients ``[c_0, c_1, …, c_n]`` of ``h`` in powers of ``z``."""
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        if not self.monotone:
            return np.r_[0.0, 1.0, params]
        q = np.r_[1.0, params]
        q2 = np.convolve(q, q)
        return np.r_[0.0, q2 / np.arange(1, q2.shape[0] + 1)]

    def evaluate(self, z, params):
        """As :meth:`SeriesMap.evaluate`."""
        return np.polynomial.polynomial.polyval(np.asarray(z, dtype=np.float64),
                                                self.coefficients(params))

    def derivative(self, z, params):
        """As :meth:`SeriesMap.derivative`."""
        c = self.coefficients(params)
        return np.polynomial.polynomial.polyval(np.asarray(z, dtype=np.float64),
                                                np.polynomial.polynomial.polyder(c))

    def param_jacobian(self, z, params):
        """As :meth:`SeriesMap.param_jacobian`."""
        z = np.asarray(z, dtype=np.float64)
        if not self.monotone:
            return np.column_stack([z**j for j in range(2, self.degree + 1)]) \
                if self.n_params else np.zeros((z.shape[0], 0))
        q = np.r_[1.0, np.atleast_1d(np.asarray(params, dtype=np.float64))]
        cols = []
        for i in range(1, q.shape[0]):           # d/dp_i ∫ q^2 = ∫ 2 q t^i
            c = np.zeros(q.shape[0] + i)
            c[i:] = 2.0 * q
            cols.append(np.polynomial.polynomial.polyval(
                z, np.r_[0.0, c / np.arange(1, c.shape[0] + 1)]))
        return np.column_stack(cols) if cols else np.zeros((z.shape[0], 0))

    def start(self, z, y):
        """As :meth:`SeriesMap.start`."""
        return np.zeros(self.n_params)

    def scale(self, y):
        """As :meth:`SeriesMap.scale`."""
        r = max(float(np.sqrt(np.mean(np.square(y)))), 1e-300)
        return r ** -np.arange(1.0, self.n_params + 1.0)      # c_j z^j ~ z: c_j ~ r^(1-j)

    def describe(self):
        """As :meth:`SeriesMap.describe`."""
        return f"polynomial(degree={self.degree}{', monotone' if self.monotone else ''})"

    def formula(self, params):
        """As :meth:`SeriesMap.formula` (the coefficients of ``h`` in powers of ``z``)."""
        c = self.coefficients(params)
        terms = " + ".join(f"{v:g} z^{j}" for j, v in enumerate(c[2:], start=2) if v != 0)
        return ("h(z) = z" + (" + " + terms if terms else "")).replace("+ -", "- ")

    def to_dict(self):
        """As :meth:`SeriesMap.to_dict`."""
        return {"kind": self.kind, "degree": self.degree, "monotone": self.monotone}


class CustomMap(SeriesMap):
    """A user's output map with its derivatives (code: stored in files by its name only).

    Parameters
    ----------
    function : callable
        ``function(z, params) -> h`` elementwise (``z`` a 1-D array in the data's units).
    derivative : callable
        ``derivative(z, params) -> dh/dz``.
    param_derivative : callable, optional
        ``param_derivative(z, params) -> (len(z), n_params)`` array of ``dh/dparams``;
        required when there are parameters.
    names : sequence of str
        The parameters' names (``h_`` is prefixed when missing).
    start : sequence of float
        Their starting values (ideally where ``h`` is near the identity over the data).
    name : str
        How the map is named in files and messages.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.output_map import CustomMap
    >>> h = CustomMap(lambda z, p: p[0] * np.tanh(z / p[0]),
    ...               lambda z, p: 1.0 / np.cosh(z / p[0]) ** 2,
    ...               lambda z, p: (np.tanh(z / p[0]) - z / p[0] / np.cosh(z / p[0]) ** 2)[:, None],
    ...               names=["scale"], start=[10.0], name="soft_saturation")
    >>> h.names
    ('h_scale',)
    """

    kind = "custom"

    def __init__(self, function, derivative, param_derivative=None, *, names=(), start=(),
                 name="custom"):
        for value, arg in ((function, "function"), (derivative, "derivative")):
            if not callable(value):
                raise ParameterError(f"`{arg}` of a custom output map must be callable; got "
                                     f"{value!r}.")
        if not isinstance(name, str) or not name:
            raise ParameterError(f"`name` of a custom output map must be a non-empty string; "
                                 f"got {name!r}.")
        if isinstance(names, str) or not isinstance(names, Sequence) or not all(
                isinstance(n, str) and n for n in names):
            raise ParameterError(f"`names` must be a sequence of non-empty strings; got "
                                 f"{names!r}.")
        names = tuple(n if n.startswith("h_") else f"h_{n}" for n in names)
        if len(set(names)) != len(names):
            raise ParameterError(f"`names` must be distinct; got {names}.")
        start = np.atleast_1d(np.asarray(start, dtype=np.float64)) if len(names) else np.zeros(0)
        if start.shape != (len(names),) or not np.all(np.isfinite(start)):
            raise ParameterError(f"`start` must give one finite value per parameter {names}; got "
                                 f"{start.tolist()}.")
        if names and not callable(param_derivative):
            raise ParameterError("a custom output map with parameters needs `param_derivative` "
                                 f"(dh/dparams); got {param_derivative!r}.")
        self.function, self._derivative, self._param_derivative = (function, derivative,
                                                                   param_derivative)
        self.name, self._names, self.start_values = name, names, start

    @property
    def names(self):
        """Names of the free parameters (``h_*``)."""
        return self._names

    def _call(self, f, z, params, what, shape):
        z = np.asarray(z, dtype=np.float64)
        with np.errstate(all="ignore"):
            out = np.asarray(f(z, np.atleast_1d(np.asarray(params, dtype=np.float64))),
                             dtype=np.float64)
        if out.shape != shape(z):
            raise DimensionError(f"the custom output map {self.name!r}: `{what}` returned shape "
                                 f"{out.shape} for z of shape {z.shape}; expected {shape(z)}.")
        return out

    def evaluate(self, z, params):
        """As :meth:`SeriesMap.evaluate`."""
        return self._call(self.function, z, params, "function", np.shape)

    def derivative(self, z, params):
        """As :meth:`SeriesMap.derivative`."""
        return self._call(self._derivative, z, params, "derivative", np.shape)

    def param_jacobian(self, z, params):
        """As :meth:`SeriesMap.param_jacobian`."""
        if not self.n_params:
            return np.zeros((np.shape(z)[0], 0))
        return self._call(self._param_derivative, z, params, "param_derivative",
                          lambda z: (z.shape[0], self.n_params))

    def start(self, z, y):
        """As :meth:`SeriesMap.start`."""
        return self.start_values.copy()

    def scale(self, y):
        """As :meth:`SeriesMap.scale`."""
        return np.maximum(np.abs(self.start_values), 1.0)

    def describe(self):
        """As :meth:`SeriesMap.describe`."""
        return f"custom({self.name})"

    def to_dict(self):
        """As :meth:`SeriesMap.to_dict`."""
        return {"kind": self.kind, "name": self.name, "names": list(self.names)}

    def __eq__(self, other):
        return (isinstance(other, CustomMap) and other.to_dict() == self.to_dict()
                and other.function is self.function)

    def __hash__(self):
        return hash((self.name, self.names))


#: An output map as the public API accepts it (:func:`as_output_map`).
OutputMapLike = Union[None, str, int, SeriesMap]


def as_output_map(spec, name="output_map"):
    """``None`` or a :class:`SeriesMap` from what :func:`fohw.identify` accepts.

    Parameters
    ----------
    spec : None, str, int or SeriesMap
        ``"saturation"`` (both limits free), ``"deadzone"`` (both ends free),
        ``"piecewise_linear"`` (5 breakpoints over the output's range, values free), an int (a
        polynomial degree, :class:`PolynomialMap`) or a map.

    Examples
    --------
    >>> from fohw.model.output_map import as_output_map
    >>> as_output_map("saturation")
    Saturation(saturation(lower=free, upper=free))
    >>> as_output_map(3).names
    ('h_c2', 'h_c3')
    """
    if spec is None or isinstance(spec, SeriesMap):
        return spec
    if isinstance(spec, str):
        if spec == "saturation":
            return Saturation()
        if spec == "deadzone":
            return DeadZone()
        if spec == "piecewise_linear":
            return PiecewiseLinear()
        raise ParameterError(f"`{name}` must be None, one of {OUTPUT_MAP_NAMES}, an int (a "
                             f"polynomial degree) or a SeriesMap; got {spec!r}.")
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, (bool, np.bool_)):
        if spec < 1:
            raise ParameterError(f"`{name}` as a polynomial degree must be at least 1; got "
                                 f"{int(spec)}.")
        return PolynomialMap(int(spec))
    raise ParameterError(f"`{name}` must be None, one of {OUTPUT_MAP_NAMES}, an int (a "
                         f"polynomial degree) or a SeriesMap; got {spec!r}.")


def output_map_from_dict(d, output_map=None, *, name="output_map"):
    """Inverse of :meth:`SeriesMap.to_dict` (a custom map passed again, checked by name)."""
    kind = d.get("kind") if isinstance(d, Mapping) else None
    fields = {"saturation": {"kind", "lower", "upper"}, "deadzone": {"kind", "lower", "upper"},
              "piecewise_linear": {"kind", "breakpoints", "free_breakpoints"},
              "polynomial": {"kind", "degree", "monotone"}, "custom": {"kind", "name", "names"}}
    if kind not in fields or set(d) != fields[kind]:
        raise ParameterError(f"`{name}` must be described as one of {sorted(fields)} with "
                             f"their fields; got {d!r}.")
    if kind == "custom":
        if output_map is None:
            raise ParameterError(f"`{name}` is a custom map ({d['name']!r}); its functions are "
                                 "code, which fohw never stores: pass the same map again "
                                 "(output_map=...).")
        if not isinstance(output_map, CustomMap) or output_map.to_dict() != d:
            raise ParameterError(f"`{name}` passed does not match the custom map stored, {d!r}.")
        return output_map
    if kind == "polynomial":
        stored = PolynomialMap(d["degree"], d["monotone"])
    elif kind == "piecewise_linear":
        stored = PiecewiseLinear(d["breakpoints"], d["free_breakpoints"])
    else:
        stored = (Saturation if kind == "saturation" else DeadZone)(d["lower"], d["upper"])
    if output_map is not None and as_output_map(output_map, name) != stored:
        raise ParameterError(f"`{name}` passed does not match the map stored, {d!r}.")
    return stored
