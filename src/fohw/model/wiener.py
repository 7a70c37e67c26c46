"""A Hammerstein–Wiener model around a fractional transfer function: ``u -> f -> G(s) -> h -> y``.

The model as the fractional-order literature writes it (e.g. FOMCON-style ``fotf`` blocks between
static maps):

.. math:: w[k] = \\bar f(u[k]) = \\sum_j p_j f_j(u[k]), \\quad x = G(s)\\,w, \\quad y[k] = h(x[k]),

- ``f``: a :class:`fohw.Basis` with coefficients ``p``, **normalised by** ``p_1 = 1`` (the gain
  lives in ``G``, whose lowest-order denominator coefficient is held fixed as the normaliser);
- ``G``: a :class:`fohw.FractionalTF`, simulated by its GL discretisation with the current
  sample on both sides (implicit; sample alignment of :mod:`fohw.model.transfer`);
- ``h``: a series output map of :mod:`fohw.model.output_map` (the family the lagged kind uses:
  :class:`~fohw.model.output_map.Saturation`, :class:`~fohw.model.output_map.DeadZone`,
  :class:`~fohw.model.output_map.PiecewiseLinear`, :class:`~fohw.model.output_map.PolynomialMap`,
  :class:`~fohw.model.output_map.CustomMap`), or none (the identity).

It is a :class:`fohw.Model`: :func:`fohw.fit` fits it by simulation error with the exact
Jacobian of :meth:`FractionalHW.jacobian` (the chain rule through the three blocks):

- ``d yhat / d theta_G = h'(x) * d x / d theta_G``, the GL sensitivities of ``G`` with ``w``
  as its input (with ``R = 1 / C`` the power-series reciprocal of the denominator's GL weights
  and ``W_nu`` those of ``D^nu``: ``d x / d b_j = R * W_{beta_j} * w``,
  ``d x / d beta_j = R * b_j (d W_{beta_j} / d beta_j) * w``, ``d x / d a_i = -R * W_{alpha_i} * x``,
  ``d x / d alpha_i = -R * a_i (d W_{alpha_i} / d alpha_i) * x``; causal products by FFT);
- ``d yhat / d p_j = h'(x) * G f_j(u)`` (``G`` is linear);
- ``d yhat / d eta = dh/d eta (x)``, the map's own parameter Jacobian (for a saturation
  ``[x <= lower]``, ``[x >= upper]``, exact off the kinks, a set of measure zero for
  continuous ``x``).

This is *not* the paper's lagged model (Eq. 16), whose output map acts inside the recursion on
lags ``>= 1``; ``docs/transfer_functions.md`` says where the two classes coincide and where they
differ.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules (scipy.fft, ...) load on first use: import time

from .._validation import check_int
from ..exceptions import DimensionError, ParameterError
from .base import Model
from .basis import Basis, as_basis
from .kernels import causal_product, series_divide
from .output_map import (
    CustomMap,
    PiecewiseLinear,
    PolynomialMap,
    Saturation,
    SeriesMap,
    as_output_map,
    output_map_from_dict,
)
from .parameters import ORDER_RANGE, Parameter, Parameters
from .transfer import NUM_ORDER_RANGE, FractionalTF, delay_samples, operator_weights, tf_sensitivities

__all__ = ["FractionalHW"]

#: Rounds of :meth:`FractionalHW.linear_start` (G's coefficients, then b and p, then the map).
ROUNDS = 2
#: Simulation budget and tolerances of each coefficient fit in :meth:`FractionalHW.linear_start`
#: (a start: 1e-4 gave the same starts as 1e-8 to 3 digits on the tests' 13 fits, 25 % fewer
#: simulations).
START_NFEV = 30
START_TOL = 1e-4



def _terms(G):
    return tuple(np.array(v, dtype=np.float64) for v in (G.num, G.num_orders, G.den, G.den_orders))


def _shifted(w, shift):
    out = np.zeros_like(w)
    if shift < w.shape[0]:
        out[shift:] = w[:w.shape[0] - shift]
    return out


class FractionalHW(Model):
    """``u -> fbar -> G(s) -> h -> y``: a Hammerstein–Wiener model around a fractional transfer function.

    Parameters
    ----------
    G : FractionalTF
        The linear block (its ``dt`` is the default sampling time, its ``delay`` the input delay).
        Its terms are the model's parameters in ``G``'s stored order (decreasing orders):
        ``b0…``, ``beta0…`` (numerator), ``a0…``, ``alpha0…`` (denominator).
    p : array_like, optional
        Coefficients of the input basis, ``p[0] == 1`` (normalisation; not a parameter); the rest
        are the parameters ``p2…``. Default ``[1]``.
    f_basis : Basis, int or callables, optional
        Input basis (default the polynomial basis of degree ``len(p)``: ``u, u^2, …``).
    output_map : None, str, int or SeriesMap, optional
        ``h``, any map :func:`fohw.model.output_map.as_output_map` accepts: ``None`` (default,
        the identity), ``"saturation"``, ``"deadzone"``, an int (a polynomial degree) or a map
        (:class:`~fohw.model.output_map.Saturation`, :class:`~fohw.model.output_map.DeadZone`,
        :class:`~fohw.model.output_map.PiecewiseLinear` with its breakpoints,
        :class:`~fohw.model.output_map.PolynomialMap`, :class:`~fohw.model.output_map.CustomMap`).
        Its parameters keep the family's names (``h_lower``, ``h_upper``, ``h_c2``, …).
    output_params : array_like, optional
        Values of the map's parameters (``output_map.names`` order). Default: the map's identity
        start (zeros of a polynomial or dead zone, ``v_i = z_i`` of a piecewise-linear map);
        a saturation with free limits has no such start and needs them.
    dt : float, optional
        Sampling time (default ``G.dt``); :func:`fohw.fit` needs one.

    Attributes
    ----------
    G : FractionalTF
    p : ndarray
    f_basis : Basis
    output_map : SeriesMap or None
    output_params : ndarray

    Notes
    -----
    :meth:`simulate` computes ``w = fbar(u)`` at every sample, ``x = G.simulate(w)`` (the implicit
    GL recursion ``sum_j c_j x[k-j] = sum_j d_j w[k-j-n_delay]``, solved in ``O(N log^2 N)``) and
    ``y = h(x)``; the tests compare every sample with the literal per-sample loop.

    Parameters (:attr:`parameters`): every term of ``G`` (orders ``order=True``, numerator orders
    bounded by :data:`fohw.model.transfer.NUM_ORDER_RANGE`, denominator orders by ``ORDER_RANGE``, each
    widened to reach a value given beyond them), ``p2…`` and the map's. Fixed by default: the
    denominator coefficient of the lowest order (the scale normaliser) and every order that is
    0 in the ``G`` given (a constant term). Change that with ``model.with_parameters(parameters)``.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])           # 1 / (s + 1)
    >>> m = fohw.FractionalHW(G, p=[1.0, 0.5], output_map="saturation", output_params=[-1.0, 1.0],
    ...                       dt=1.0)
    >>> print(m)
    u -> 1·x + 0.5·x^2 -> 1 / (s + 1) -> h(z) = clip(z, -1, 1)
    >>> m.simulate([1.0, 1.0, 1.0])          # w = 1.5; x = 0.75, 1.125, 1.3125
    array([0.75, 1.  , 1.  ])
    >>> list(m.parameters.free_names)
    ['b0', 'a0', 'alpha0', 'p2', 'h_lower', 'h_upper']
    """

    def __init__(self, G, *, p=(1.0,), f_basis=None, output_map=None, output_params=None, dt=None):
        if not isinstance(G, FractionalTF):
            raise ParameterError(f"`G` must be a FractionalTF; got {type(G).__name__}.")
        try:
            p = np.atleast_1d(np.asarray(p, dtype=np.float64)).ravel()
        except (TypeError, ValueError):
            raise ParameterError(f"`p` must be a sequence of real numbers; got {p!r}.") from None
        if p.size == 0 or not np.all(np.isfinite(p)):
            raise ParameterError(f"`p` must be a non-empty sequence of finite numbers; got {p.tolist()}.")
        if p[0] != 1.0:
            raise ParameterError(f"`p[0]` must be exactly 1 (the gain is G's); got {p[0]!r}.")
        basis = as_basis(p.size if f_basis is None else f_basis, "f_basis")
        if len(basis) != p.size:
            raise DimensionError(f"`p` must have one entry per f-basis function ({len(basis)}); "
                                 f"got {p.size}.")
        hmap = as_output_map(output_map, "output_map")
        if isinstance(hmap, PiecewiseLinear) and hmap.breakpoints is None:
            raise ParameterError(f"`output_map` {hmap.describe()}: a FractionalHW needs the "
                                 "breakpoints themselves (PiecewiseLinear([z1, z2, ...])), not "
                                 "how many.")
        if dt is None:
            dt = G.dt
        elif isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (int, float, np.number)) \
                or not np.isfinite(dt) or dt <= 0:
            raise ParameterError(f"`dt` must be a positive finite number; got {dt!r}.")
        if dt is not None:
            delay_samples(G.delay, float(dt))
        num, num_orders, den, den_orders = _terms(G)
        fixed = {f"beta{j}" for j, v in enumerate(num_orders) if v == 0.0}
        fixed |= {f"alpha{i}" for i, v in enumerate(den_orders) if v == 0.0}
        fixed.add(f"a{int(np.argmin(den_orders))}")
        self._init(num, num_orders, den, den_orders, None if dt is None else float(dt),
                   float(G.delay), p, basis, hmap, self._map_values(hmap, output_params),
                   frozenset(fixed))
        self._G = G if G.dt == self._dt else None

    @staticmethod
    def _map_values(hmap, values):
        if hmap is None:
            if values is not None and np.size(values):
                raise DimensionError(f"`output_params` given ({values!r}) but there is no "
                                     "`output_map`.")
            return np.zeros(0)
        if values is None:
            if isinstance(hmap, Saturation) and hmap.n_params:
                raise ParameterError(f"`output_params`: the {hmap.describe()} has no default for "
                                     f"its free limits {hmap.names}; give them (e.g. the range of "
                                     "the measured output).")
            values = hmap.start(None, None)
        return hmap.check_params(values, "`output_params`").copy()

    def _init(self, num, num_orders, den, den_orders, dt, delay, p, basis, hmap, eta, fixed):
        self._num, self._num_orders, self._den, self._den_orders = num, num_orders, den, den_orders
        self._dt, self._delay = dt, delay
        self.p = p
        self.f_basis: Basis = basis
        self.output_map: SeriesMap | None = hmap
        self.output_params = eta
        self._fixed = fixed
        self._G = None
        for arr in (num, num_orders, den, den_orders, p, eta):
            arr.setflags(write=False)

    def _copy(self, **changes):
        new = object.__new__(type(self))
        state = dict(num=self._num, num_orders=self._num_orders, den=self._den,
                     den_orders=self._den_orders, dt=self._dt, delay=self._delay, p=self.p,
                     basis=self.f_basis, hmap=self.output_map, eta=self.output_params,
                     fixed=self._fixed)
        state.update(changes)
        new._init(**state)
        return new

    # ------------------------------------------------------------------ Model protocol
    @property
    def dt(self):
        """The sampling time (``G.dt`` unless given), or None."""
        return self._dt

    @property
    def terms(self):
        """``(num, num_orders, den, den_orders)`` of ``G`` as the parameters hold them (unmerged)."""
        return self._num, self._num_orders, self._den, self._den_orders

    @property
    def G(self) -> FractionalTF:
        """The linear block as a :class:`fohw.FractionalTF` (equal orders merged)."""
        if self._G is None:
            self._G = FractionalTF(self._num, self._num_orders, self._den, self._den_orders,
                                   dt=self._dt, delay=self._delay)
        return self._G

    def _names(self):
        m, k = self._num.size, self._den.size
        return ([f"b{j}" for j in range(m)], [f"beta{j}" for j in range(m)],
                [f"a{i}" for i in range(k)], [f"alpha{i}" for i in range(k)],
                [f"p{j}" for j in range(2, self.p.size + 1)],
                list(() if self.output_map is None else self.output_map.names))

    @property
    def parameters(self) -> Parameters:
        """``G``'s terms, ``p2…`` and the output map's parameters (class notes)."""
        b, beta, a, alpha, pn, hn = self._names()
        out = []

        def order_bounds(v, default):
            return (min(default[0], v), max(default[1], v))

        for names, values, kind in ((b, self._num, None), (beta, self._num_orders, NUM_ORDER_RANGE),
                                    (a, self._den, None), (alpha, self._den_orders, ORDER_RANGE),
                                    (pn, self.p[1:], None), (hn, self.output_params, None)):
            for n, v in zip(names, values.tolist()):
                if kind is None:
                    out.append(Parameter(n, v, fixed=n in self._fixed))
                else:
                    out.append(Parameter(n, v, bounds=order_bounds(v, kind), fixed=n in self._fixed,
                                         order=True))
        return Parameters(out)

    def with_parameters(self, values) -> FractionalHW:
        """A new model with new values (mapping ``name -> float`` or :class:`fohw.Parameters`)."""
        if isinstance(values, Parameters):
            own = self.parameters
            if set(values) != set(own):
                missing = sorted(set(own) - set(values))
                raise ParameterError(f"the parameters do not match the FractionalHW's: missing "
                                     f"{missing}, unknown {sorted(set(values) - set(own))}.")
            v = values.valuesdict()
        else:
            v = self.parameters.with_values(values).valuesdict()
        b, beta, a, alpha, pn, hn = self._names()

        def take(names):
            return np.array([v[n] for n in names], dtype=np.float64)

        return self._copy(num=take(b), num_orders=take(beta), den=take(a), den_orders=take(alpha),
                          p=np.r_[1.0, take(pn)], eta=take(hn))

    def _need_dt(self, dt=None):
        if dt is not None:
            return dt
        if self._dt is None:
            raise ParameterError("`dt` is needed: pass dt=... to FractionalHW(...) or to its G.")
        return self._dt

    def input_signal(self, u):
        """``w = fbar(u) = sum_j p_j f_j(u)``."""
        return self.p @ self.f_basis.evaluate(np.asarray(u, dtype=np.float64), "u")

    def _map(self, x):
        if self.output_map is None:
            return x.copy()
        y = self.output_map.evaluate(x, self.output_params)
        if y.shape != x.shape or not np.all(np.isfinite(y)):
            k = int(np.flatnonzero(~np.isfinite(y))[0]) if y.shape == x.shape else 0
            raise ParameterError(f"`output_map` {self.output_map.describe()} returned a non-finite "
                                 f"value or shape {y.shape} for x[{k}] = {x[k]!r}.")
        return y

    def simulate(self, u, *, initial=None, dt=None, states=False, divergence_threshold=None):
        """Output for the input ``u`` (zero initial conditions of ``G``).

        Parameters
        ----------
        u : array_like, shape (N,)
            Input samples (alignment of :class:`fohw.FractionalTF`).
        initial : None, optional
            Only rest (zero initial conditions) is defined for this kind.
        dt : float, optional
            Sampling time (default :attr:`dt`).
        states : bool, optional
            Also return ``w = fbar(u)`` and ``x = G w``.
        divergence_threshold : float, optional
            The bound on ``|x|`` of :meth:`fohw.FractionalTF.simulate` (default: ``1e8`` times
            the output scale of a bounded response; ``np.inf``: no bound).

        Returns
        -------
        y : ndarray, shape (N,)
            Or ``(w, x, y)`` with ``states=True``.
        """
        if initial is not None and not (isinstance(initial, str) and initial == "rest"):
            raise ParameterError(f"`initial`: a FractionalHW simulates from rest (zero initial "
                                 f"conditions of G) only; got {initial!r}.")
        u = self.check_input(u)
        w = self.input_signal(u)
        x = self.G.simulate(w, self._need_dt(dt), divergence_threshold=divergence_threshold)
        y = self._map(x)
        return (w, x, y) if states else y

    def jacobian(self, u):
        """``(yhat, J)``, ``J`` the exact ``d yhat / d`` every parameter (module notes)."""
        u = self.check_input(u)
        h = self._need_dt()
        fu = self.f_basis.evaluate(u, "u")
        w = self.p @ fu
        G = self.G
        x = G.simulate(w, h, divergence_threshold=np.inf)      # the free run, as fit scores it
        yhat = self._map(x)
        wd = _shifted(w, delay_samples(self._delay, h))
        with np.errstate(over="ignore", invalid="ignore"):
            jg = tf_sensitivities(*self.terms, wd, x, h)
        if self.output_map is None:
            dh = np.ones_like(x)
            jh = np.zeros((x.size, 0))
        else:
            dh = self.output_map.derivative(x, self.output_params)
            jh = self.output_map.param_jacobian(x, self.output_params)
        cols = [dh[:, None] * jg]
        if fu.shape[0] > 1:
            cols.append(dh[:, None] * np.column_stack([G.simulate(fu[j], h)
                                                       for j in range(1, fu.shape[0])]))
        cols.append(jh)
        return yhat, np.column_stack(cols)

    def starts(self, u, y):
        """The model itself (``dt`` and the map checked against the record)."""
        self._need_dt()
        if self.output_map is not None:
            self.output_map.check_data(np.asarray(y, dtype=np.float64))
        return [self]

    def linear_start(self, u, y):
        """A start with the orders held: ``G``'s coefficients, ``p`` and the map solved for ``y``.

        Twice when there is a ``p`` (once otherwise): ``G``'s free coefficients by simulation
        error on ``fbar(u) -> y`` (the map taken as the identity; from the better of the current
        values and the linear equation error ``sum_i a_i W_{alpha_i} y - sum_j b_j W_{beta_j}
        fbar(u)``, at most :data:`START_NFEV` simulations), then the numerator and ``p2…``
        together by linear least squares (``x`` is linear in ``b ⊗ p`` for a fixed denominator;
        their best rank-one split, ``p_1 = 1``). Then a polynomial map's free coefficients by
        least squares on ``x^k``, any other map's free parameters at its start for the record (a
        saturation's limits at the range of ``y``). None where a step fails. This is the start
        the kind's own fitter made before ``fohw.fit`` (a fit of ``G`` then the maps at each point
        of the order grid), with a linear step where it had a second nonlinear one.
        """
        try:
            with np.errstate(all="ignore"):
                return self._linear_start(self.check_input(u), np.asarray(y, dtype=np.float64))
        except (ArithmeticError, ParameterError, DimensionError, np.linalg.LinAlgError, ValueError):
            return None

    def _linear_start(self, u, y):
        params = self.parameters
        h = self._need_dt()
        fu = self.f_basis.evaluate(u, "u")
        model = self
        for _ in range(ROUNDS if fu.shape[0] > 1 else 1):
            model = FractionalHW._fit_coefficients(model, params, fu, y, h)
            model = FractionalHW._solve_p(model, params, fu, y, h)
        return FractionalHW._solve_map(model, params, fu, y, h)

    def _sse(self, fu, y, h):
        try:
            r = y - self.G.simulate(self.p @ fu, h)
        except (ParameterError, ArithmeticError):
            return np.inf
        return float(r @ r) if np.all(np.isfinite(r)) else np.inf

    def _fit_coefficients(self, params, fu, y, h) -> FractionalHW:
        """``G``'s free coefficients by simulation error on ``fbar(u) -> y``, orders held.

        From the better of the model's and the equation error's; the map taken as the identity.
        """
        candidates = [self, FractionalHW._solve_coefficients(self, params, fu, y, h),
                      FractionalHW._solve_joint(self, params, fu, y, h)]
        model = min(candidates, key=lambda m: FractionalHW._sse(m, fu, y, h))
        b, _, a, _, _, _ = self._names()
        names = [n for n in b + a if params[n].free]
        if not names or any(p.tie is not None and p.tie[0] in names for p in params.values()):
            return model
        cols = [b.index(n) if n in b else len(b) + a.index(n) for n in names]  # tf_sensitivities'
        lower = np.array([params[n].bounds[0] for n in names])
        upper = np.array([params[n].bounds[1] for n in names])
        w = model.p @ fu
        wd = _shifted(w, delay_samples(self._delay, h))
        penalty = np.full(y.size, 1e4 * max(float(np.max(np.abs(y))), 1e-300))
        cache = {}

        def at(q):
            key = q.tobytes()
            if key not in cache:
                cache.clear()
                cache[key] = model.with_parameters(dict(zip(names, q.tolist())))
            return cache[key]

        def residual(q):
            try:
                x = at(q).G.simulate(w, h)
            except (ParameterError, ArithmeticError):
                return penalty
            return y - x if np.all(np.isfinite(x)) and np.max(np.abs(x)) < 1e8 * penalty[0] \
                else penalty

        def jacobian(q):
            g = at(q)
            try:
                x = g.G.simulate(w, h)
                jac = tf_sensitivities(*g.terms, wd, x, h, orders=False)
            except (ParameterError, ArithmeticError):
                return np.zeros((y.size, len(names)))
            jac = -jac[:, cols]
            return jac if np.all(np.isfinite(jac)) else np.zeros((y.size, len(names)))

        q0 = np.clip([model.parameters[n].value for n in names], lower, upper)
        res = scipy.optimize.least_squares(residual, q0, jac=jacobian, bounds=(lower, upper),
                                           method="trf", x_scale="jac", max_nfev=START_NFEV,
                                           ftol=START_TOL, xtol=START_TOL, gtol=START_TOL)
        if not 2.0 * res.cost < FractionalHW._sse(model, fu, y, h):
            return model
        return FractionalHW._solved(model, params, names, res.x)

    def _solved(self, params, names, values):
        """The model with ``names`` set to ``values`` (clipped to their bounds), or itself."""
        values = np.asarray(values, dtype=np.float64)
        if not names or not np.all(np.isfinite(values)):
            return self
        clipped = {n: float(np.clip(v, *params[n].bounds)) for n, v in zip(names, values)}
        return self.with_parameters(clipped)

    def _solve_coefficients(self, params, fu, y, h) -> FractionalHW:
        t = params.tie_matrix()
        names = list(params)
        b, _, a, _, _, _ = self._names()
        coef_rows = [names.index(n) for n in b + a]
        free = params.free_names
        other_rows = [i for i in range(len(names)) if i not in coef_rows]
        cols = np.flatnonzero(np.any(t[coef_rows] != 0, axis=0))
        if cols.size == 0 or np.any(t[np.ix_(other_rows, cols)] != 0):    # tied to a non-coefficient
            return self
        n = y.size
        wd = _shifted(self.p @ fu, delay_samples(self._delay, h))
        c = operator_weights(self._den, self._den_orders, h, n)        # prefilter 1 / A (current)
        wd, yf = series_divide(wd, c), series_divide(y, c)
        M = np.column_stack([-causal_product(operator_weights([1.0], [nu], h, n), wd, n)
                             for nu in self._num_orders]
                            + [causal_product(operator_weights([1.0], [nu], h, n), yf, n)
                               for nu in self._den_orders])
        current = self.parameters.valuesdict()          # this step's values (params: the settings)
        x_free = np.array([current[n] for n in free])
        values = np.r_[self._num, self._den]
        tc = t[coef_rows][:, cols]
        base = values - tc @ x_free[cols]
        A = M @ tc
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        sol = np.linalg.lstsq(A / scale, -M @ base, rcond=None)[0] / scale
        return self._solved(params, [free[j] for j in cols], sol)

    def _solve_joint(self, params, fu, y, h) -> FractionalHW:
        """The denominator and ``theta = b ⊗ p`` together by the linear equation error.

        ``sum_i a_i W_{alpha_i} y = sum_k sum_j theta_kj W_{beta_k} f_j(u)`` is linear in the
        free ``a_i`` and ``theta`` (both sides filtered by the current ``1 / A``); ``b`` and ``p``
        (``p_1 = 1``) from ``theta``'s best rank-one approximation. Only when every ``b_k``, every
        ``p_j`` and every free ``a_i`` is free and untied (else the model itself).
        """
        b, _, a, _, pn, _ = self._names()
        plain = b + pn
        free_a = [n for n in a if params[n].free]
        if not pn or not all(params[n].free for n in plain) or any(
                p.tie is not None for p in params.values()):
            return self
        n = y.size
        shift = delay_samples(self._delay, h)
        c = operator_weights(self._den, self._den_orders, h, n)
        yf = series_divide(y, c)
        cols = [causal_product(operator_weights([1.0], [nu], h, n), yf, n)
                for name, nu in zip(a, self._den_orders) if name in free_a]
        rhs = -sum((coef * causal_product(operator_weights([1.0], [nu], h, n), yf, n)
                    for name, coef, nu in zip(a, self._den, self._den_orders)
                    if name not in free_a), np.zeros(n))
        for beta in self._num_orders:
            wk = operator_weights([1.0], [beta], h, n)
            cols += [-causal_product(wk, series_divide(_shifted(f, shift), c), n) for f in fu]
        A = np.column_stack(cols)
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        sol = np.linalg.lstsq(A / scale, rhs, rcond=None)[0] / scale
        theta = sol[len(free_a):].reshape(len(b), fu.shape[0])
        left, sv, right = np.linalg.svd(theta)
        if right[0, 0] == 0.0:
            return self
        values = np.r_[sol[:len(free_a)], sv[0] * right[0, 0] * left[:, 0],
                       (right[0] / right[0, 0])[1:]]
        return FractionalHW._solved(self, params, free_a + plain, values)

    def _solve_p(self, params, fu, y, h) -> FractionalHW:
        """Numerator and ``p`` by simulation-error least squares, ``G``'s denominator held.

        ``x = sum_k sum_j b_k p_j (s^{beta_k} / A(s)) f_j(u)`` is linear in ``theta = b ⊗ p``:
        solved for ``theta``, then ``b`` and ``p`` (``p_1 = 1``) from its best rank-one
        approximation. Only ``p`` (``G`` held) when a numerator coefficient is not free.
        """
        b, _, _, _, pn, _ = self._names()
        if any(params[n].tie is not None for n in pn) or any(
                p.tie is not None and p.tie[0] in b + pn for p in params.values()):
            return self
        free_b = [params[n].free for n in b]
        free_p = [params[n].free for n in pn]
        if all(free_b) and all(free_p):
            shift = delay_samples(self._delay, h)
            n = y.size
            c = operator_weights(self._den, self._den_orders, h, n)
            cols = []
            for beta in self._num_orders:
                d = operator_weights([1.0], [beta], h, n)
                cols += [series_divide(causal_product(d, _shifted(f, shift), n), c) for f in fu]
            theta = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]
            left, sv, right = np.linalg.svd(theta.reshape(len(b), fu.shape[0]))
            if right[0, 0] == 0.0:
                return self
            p_row = right[0] / right[0, 0]
            return self._solved(params, b + pn, np.r_[sv[0] * right[0, 0] * left[:, 0], p_row[1:]])
        if not pn or not all(free_p):
            return self
        cols = np.column_stack([self.G.simulate(f, h) for f in fu])
        sol = np.linalg.lstsq(cols[:, 1:], y - cols[:, 0], rcond=None)[0]
        return self._solved(params, pn, sol)

    def _solve_map(self, params, fu, y, h) -> FractionalHW:
        hmap = self.output_map
        if hmap is None or not hmap.n_params:
            return self
        names = list(hmap.names)
        free = [params[n].free for n in names]
        x = self.G.simulate(self.p @ fu, h)
        if isinstance(hmap, PolynomialMap) and not hmap.monotone:
            if not all(free):
                return self
            powers = np.column_stack([x ** k for k in range(2, hmap.degree + 1)])
            return self._solved(params, names, np.linalg.lstsq(powers, y - x, rcond=None)[0])
        start = hmap.start(x, y)
        keep = [j for j, f in enumerate(free) if f]
        return self._solved(params, [names[j] for j in keep], start[keep])

    # ------------------------------------------------------------------ files
    def config(self) -> dict:
        """``dt``, ``delay``, the number of terms of ``G``, ``f_basis`` and ``output_map``."""
        return {"dt": self._dt, "delay": self._delay, "n_num": int(self._num.size),
                "n_den": int(self._den.size), "f_basis": self.f_basis.to_dict(),
                "output_map": None if self.output_map is None else self.output_map.to_dict()}

    @classmethod
    def from_config(cls, config) -> FractionalHW:
        """A model of :meth:`config`'s shape (values at placeholders; custom code refused).

        A custom input basis or a :class:`~fohw.model.output_map.CustomMap` is stored by name only
        (code is never written): rebuild such a model with its constructor and ``with_parameters``.
        """
        known = {"dt", "delay", "n_num", "n_den", "f_basis", "output_map"}
        if set(config) != known:
            raise ParameterError(f"a FractionalHW config needs exactly {sorted(known)}; got "
                                 f"{sorted(config)}.")
        basis = config["f_basis"]
        if isinstance(basis, dict) and basis.get("kind") == "custom":
            raise ParameterError(f"`f_basis` {basis!r} is custom code, which fohw never stores: "
                                 "rebuild the FractionalHW with its basis and call with_parameters.")
        basis = Basis.from_dict(basis, name="f_basis")
        for key in ("n_num", "n_den"):
            check_int(config[key], key, minimum=1)
        spec = config["output_map"]
        if isinstance(spec, dict) and spec.get("kind") == CustomMap.kind:
            raise ParameterError(f"`output_map` {spec!r} is custom code, which fohw never stores: "
                                 "rebuild the FractionalHW with its map and call with_parameters.")
        hmap = None if spec is None else output_map_from_dict(spec)
        m, k = int(config["n_num"]), int(config["n_den"])
        eta = np.zeros(0 if hmap is None else hmap.n_params)
        new = object.__new__(cls)
        new._init(np.ones(m), np.zeros(m), np.ones(k), np.zeros(k),
                  None if config["dt"] is None else float(config["dt"]), float(config["delay"]),
                  np.r_[1.0, np.zeros(len(basis) - 1)], basis, hmap, eta, frozenset())
        return new

    # ------------------------------------------------------------------ views
    def _map_text(self):
        return "h(z) = z" if self.output_map is None else self.output_map.formula(self.output_params)

    def __str__(self):
        f = " + ".join(f"{c:g}·{n}" for c, n in zip(self.p, self.f_basis.names)).replace("+ -", "- ")
        return f"u -> {f} -> {self.G} -> {self._map_text()}"

    def __repr__(self):
        return (f"FractionalHW({self.G!r}, p={self.p.tolist()!r}, f_basis={self.f_basis!r}, "
                f"output_map={self.output_map!r}, output_params={self.output_params.tolist()!r}, "
                f"dt={self._dt!r})")

    def frequency_response(self, omega):
        """The linear block's exact ``G(j omega)`` (:meth:`fohw.FractionalTF.frequency_response`).

        The :meth:`fohw.Model.frequency_response` hook: the response of ``G`` alone, not of the
        chain ``h(G f(u))``, whose static maps have no frequency response (for small signals
        about 0 the chain is ``G`` times :meth:`linearised_gain`). :meth:`bode` and
        :meth:`nyquist` draw it.

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], dt=0.1)
        >>> fohw.FractionalHW(G, p=[1.0, 0.3]).frequency_response([1.0])      # 1 / (j + 1)
        array([0.5-0.5j])
        """
        return self.G.frequency_response(omega)

    def default_frequencies(self, n=400):
        """``G``'s grid (:meth:`fohw.FractionalTF.default_frequencies`)."""
        return self.G.default_frequencies(n)

    def response_label(self):
        """The curve's name in :meth:`bode` and :meth:`nyquist`: the linear block ``G(s)``."""
        return f"linear block G(s) = {self.G}"

    def linearised_gain(self):
        """``f'(0) h'(0)``: the slope of the static maps at 0, multiplying ``G`` for small signals."""
        if self.f_basis.is_polynomial:
            fs = float(self.p[0])
        else:
            step = 1e-6
            v = self.input_signal(np.array([-step, step]))
            fs = float((v[1] - v[0]) / (2 * step))
        if self.output_map is None:
            return fs
        return fs * float(self.output_map.derivative(np.array([0.0]), self.output_params)[0])
