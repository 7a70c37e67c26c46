"""Identification of ``u -> f -> G(s) -> h -> y`` (:class:`fohw.FractionalHW`) by simulation error.

Parameters: ``G``'s free coefficients and orders (named, fixed, tied and bounded exactly as in
:class:`fohw.FractionalTF`'s parameters: ``b0…``, ``beta0…``, ``a0…``, ``alpha0…``), the input-map
coefficients ``p2…`` (``p1 = 1``) and the output map's ``r2…`` or ``lower``, ``upper``.
``sum_k (y[k] - yhat[k])^2`` is minimised by :func:`scipy.optimize.least_squares` with the exact
Jacobian of the simulation, by the chain rule through the three blocks (``w = fbar(u)``,
``x = G w``, ``yhat = h(x)``):

- ``d yhat / d theta_G = h'(x) * d x / d theta_G`` (the exact GL sensitivities of
  :func:`jacobian_at`, with ``w`` as the input);
- ``d yhat / d p_j = h'(x) * G f_j(u)`` (``G`` is linear);
- ``d yhat / d r_k = x^k``; for the saturation ``d yhat / d lower = [x < lower]``,
  ``d yhat / d upper = [x > upper]`` and ``h'(x) = [lower < x < upper]`` (exact except on the
  kinks, a set of measure zero for continuous ``x``).

**Start**: ``G`` from the linear fit (simulation error of ``u -> y``, with a scan
of the orders), then ``p`` by linear least squares on ``G f_j(u)``; with a nonlinear ``f``, ``G`` is
fitted once more to ``fbar(u) -> y`` and ``p`` again; then ``h``'s parameters by linear least
squares on ``x^k`` (polynomial) or the range of ``y`` (saturation); then all together.
Standard errors ``s^2 (J^T J)^{-1}``, ``s^2 = SSE / (N - n_free)``; the Cramér–Rao bound for
white output noise of known ``sigma`` is ``sigma^2 (J^T J)^{-1}`` at the truth
(:func:`fractional_hw_crb`).
"""

from __future__ import annotations

import itertools
import numbers
import warnings
from dataclasses import dataclass

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from ..exceptions import ConvergenceWarning, DimensionError, ParameterError
from ..model.basis import as_basis
from ..model.fotf import FractionalTF, delay_samples, operator_weights
from ..model.fotf_hw import FractionalHW, OutputMap
from ..model.gl import gl_weights, gl_weights_derivative
from ..model.kernels import causal_product, series_divide, series_reciprocal

__all__ = ["fit_fractional_hw", "fractional_hw_crb", "FractionalHWFit", "HWParametrisation"]


class HWParametrisation:
    """Free parameters of a :class:`fohw.FractionalHW`: ``G``'s, ``p2…`` and ``h``'s.

    Parameters
    ----------
    tf_terms : (num, num_orders, den, den_orders)
        ``G``'s start values, in the order that names them (``b0`` is ``num[0]``, …).
    p : array_like
        Input-map coefficients, ``p[0] = 1``.
    f_basis : Basis
    output_map : OutputMap
        Its parameters are start values.
    delay : float
        ``G``'s input delay.
    free : None or list of str, optional
        Names to estimate; ``None``: ``G``'s default (every coefficient but the lowest-order
        denominator one, every non-zero order), every ``p_j`` (``j >= 2``) and every map parameter.
    ties, bounds : dict, optional
        For ``G``'s parameters (:class:`TFParametrisation`); ``bounds`` may also bound map
        parameters.

    Examples
    --------
    >>> from fohw.estimators.fotf_hw_fit import HWParametrisation
    >>> from fohw.model.fotf_hw import OutputMap
    >>> import fohw
    >>> par = HWParametrisation(([1.0], [0.0], [2.0, 1.0], [0.5, 0.0]), [1.0, 0.3], fohw.as_basis(2),
    ...                         OutputMap("saturation", [-1, 1]), 0.0)
    >>> par.free_names
    ['b0', 'a0', 'alpha0', 'p2', 'lower', 'upper']
    """

    def __init__(self, tf_terms, p, f_basis, output_map, delay, *, free=None, ties=None, bounds=None):
        num, num_orders, den, den_orders = (np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in tf_terms)
        p = np.atleast_1d(np.asarray(p, dtype=np.float64))
        self.map_names = [f"p{j}" for j in range(2, p.size + 1)] + list(output_map.names)
        self.map_values = np.r_[p[1:], output_map.params]
        bounds = dict(bounds or {})
        m, k = num_orders.size, den_orders.size
        tf_names = ([f"b{j}" for j in range(m)] + [f"beta{j}" for j in range(m)]
                    + [f"a{i}" for i in range(k)] + [f"alpha{i}" for i in range(k)])
        if free is None:
            g_free, m_free = None, list(self.map_names)
        else:
            if isinstance(free, str):
                raise ParameterError(f"`free` must be None or a list of names; got {free!r}.")
            free = list(free)
            unknown = [n for n in free if n not in tf_names and n not in self.map_names]
            if unknown:
                raise ParameterError(f"`free`: unknown parameter(s) {unknown}; names are "
                                     f"{tf_names} and {self.map_names}.")
            g_free = [n for n in free if n in tf_names]
            m_free = [n for n in free if n in self.map_names]
        g_bounds = {k_: v for k_, v in bounds.items() if k_ in tf_names}
        m_bounds = {k_: v for k_, v in bounds.items() if k_ not in tf_names}
        for name in m_bounds:
            if name not in m_free:
                raise ParameterError(f"`bounds`: {name!r} is not a free parameter (free: {free}).")
        self.g_fixed = g_free == []
        # G entirely fixed: a parametrisation with one dummy free entry, never used as free
        self.tf = TFParametrisation(num, num_orders, den, den_orders,
                                    free=["b0"] if self.g_fixed else g_free,
                                    ties=None if self.g_fixed else ties, bounds=g_bounds)
        self.n_g = 0 if self.g_fixed else len(self.tf.free_names)
        self.m_free_idx = np.array([self.map_names.index(n) for n in m_free], dtype=int)
        self.free_names = ([] if self.g_fixed else list(self.tf.free_names)) + m_free
        if not self.free_names:
            raise ParameterError("`free` is empty: nothing to estimate.")
        lo = np.full(len(m_free), -np.inf)
        hi = np.full(len(m_free), np.inf)
        for j, name in enumerate(m_free):
            if name in m_bounds:
                try:
                    lo[j], hi[j] = (float(v) for v in m_bounds[name])
                except (TypeError, ValueError):
                    raise ParameterError(f"`bounds[{name!r}]` must be a pair (low, high); "
                                         f"got {m_bounds[name]!r}.") from None
        self.lower = np.r_[np.zeros(0) if self.g_fixed else self.tf.lower, lo]
        self.upper = np.r_[np.zeros(0) if self.g_fixed else self.tf.upper, hi]
        self.n_p = p.size - 1
        self.f_basis = f_basis
        self.kind = output_map.kind
        self.delay = float(delay)

    @classmethod
    def of_model(cls, model, **kwargs):
        """The parametrisation of a :class:`fohw.FractionalHW` (``G``'s terms in its stored order)."""
        G = model.G
        return cls((G.num, G.num_orders, G.den, G.den_orders), model.p, model.f_basis,
                   model.output_map, G.delay, **kwargs)

    @property
    def q0(self):
        """The free values at the start."""
        g_part = np.zeros(0) if self.g_fixed else self.tf.p0
        return np.r_[g_part, self.map_values[self.m_free_idx]]

    def model(self, q, dt):
        """The :class:`FractionalHW` at free values ``q``."""
        theta_g = self.tf.theta0 if self.g_fixed else self.tf.theta(q[:self.n_g])
        maps = self.map_values.copy()
        maps[self.m_free_idx] = q[self.n_g:]
        b, beta, a, alpha = self.tf.split(theta_g)
        G = FractionalTF(b, beta, a, alpha, dt=dt, delay=self.delay)
        params = maps[self.n_p:]
        return FractionalHW(G, p=np.r_[1.0, maps[:self.n_p]], f_basis=self.f_basis,
                            output_map=OutputMap(self.kind, params) if self.kind != "identity" else None)


def _simulate_and_jacobian(par, q, u, h, shift):
    """``yhat`` and ``d yhat / d q`` (exact chain rule through f, G, h)."""
    model = par.model(q, h)
    fu = par.f_basis.evaluate(u, "u")
    w = model.p @ fu
    x = model.G.simulate(w, h)
    hmap = model.output_map
    yhat = hmap(x)
    dh = hmap.derivative(x)
    cols = []
    if not par.g_fixed:
        wd = np.zeros_like(w)
        if shift < w.size:
            wd[shift:] = w[:w.size - shift]
        cols.append(dh[:, None] * jacobian_at(par.tf, q[:par.n_g], wd, h))
    map_cols = [dh * model.G.simulate(fu[j], h) for j in range(1, fu.shape[0])]
    pj = hmap.parameter_jacobian(x)
    map_cols += [pj[:, k] for k in range(pj.shape[1])]
    if map_cols:
        cols.append(np.column_stack(map_cols)[:, par.m_free_idx])
    return yhat, np.column_stack(cols)


@dataclass(frozen=True)
class FractionalHWFit:
    """Result of :func:`fit_fractional_hw`.

    Attributes
    ----------
    model : FractionalHW
    estimates : dict of str to float
        Every free parameter.
    free_names : tuple of str
    covariance : ndarray
        ``s^2 (J^T J)^{-1}`` of the free parameters (``nan`` rows for a parameter the data do
        not inform: a saturation limit the signal never reaches).
    noise_std, sse : float
    converged : bool
    message : str
    nfev : int
    start : FractionalHW
        The start (linear fit of ``G``, then the maps).
    residuals : ndarray
    """

    model: FractionalHW
    estimates: dict
    free_names: tuple
    covariance: np.ndarray
    noise_std: float
    sse: float
    converged: bool
    message: str
    nfev: int
    start: FractionalHW
    residuals: np.ndarray

    def standard_errors(self):
        """Standard errors of the free parameters, by name."""
        return dict(zip(self.free_names, (float(v) for v in np.sqrt(np.diag(self.covariance)))))

    def summary(self):
        """A text table of the estimates with standard errors."""
        se = self.standard_errors()
        lines = ["Fractional Hammerstein–Wiener fit (output error)", f"  model: {self.model}",
                 f"  residual std {self.noise_std:.4g}, SSE {self.sse:.4g}, converged {self.converged} "
                 f"({self.nfev} simulations)", f"  {'parameter':<10} {'estimate':>14} {'std. error':>12}"]
        lines += [f"  {n:<10} {self.estimates[n]:14.6g} {se[n]:12.4g}" for n in self.free_names]
        return "\n".join(lines)


def _check_data(u, y, dt):
    out = []
    for x, name in ((u, "u"), (y, "y")):
        try:
            arr = np.asarray(x, dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"`{name}` must be an array of real numbers; got "
                                 f"{type(x).__name__}.") from None
        if arr.ndim != 1 or arr.size < 2:
            raise DimensionError(f"`{name}` must be 1-D with at least 2 samples; got shape {arr.shape}.")
        if not np.all(np.isfinite(arr)):
            bad = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise ParameterError(f"`{name}` must contain only finite values; got {arr[bad]!r} at "
                                 f"index {bad}.")
        out.append(arr)
    if out[0].size != out[1].size:
        raise DimensionError(f"`u` and `y` must have the same length; got {out[0].size} and {out[1].size}.")
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.number)) or not np.isfinite(dt) \
            or dt <= 0:
        raise ParameterError(f"`dt` must be a positive finite number; got {dt!r}.")
    return out[0], out[1], float(dt)


def _start(u, y, h, *, num, num_orders, den, den_orders, f_basis, n_p, output_map, delay, free, ties,
           bounds, order_grid, rounds=2, tf_free=None):
    """A start: the linear fit of G (u -> y), p by least squares, once more from ``fbar(u)``, then h.

    The second round fits ``G`` to ``fbar(u) -> y``: the first round's ``G`` has to explain the
    even part of a polynomial ``f`` on its own and can land far away.
    """
    if tf_free is None:
        tf_free = None if free is None else [n for n in free if n[:1] in "ab"]
    tf_bounds = {k: v for k, v in (bounds or {}).items()
                 if k[:1] in "ab" and (tf_free is None or k in tf_free)}
    terms = (np.asarray(num, dtype=float), num_orders, np.asarray(den, dtype=float), den_orders)
    fu = f_basis.evaluate(u, "u")
    p = np.r_[1.0, np.zeros(n_p)]
    for _ in range(rounds if n_p else 1):
        if tf_free != []:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                est = _linear_tf_estimates(p @ fu, y, dt=h, num_orders=num_orders,
                                           den_orders=den_orders, num=num, den=den, free=tf_free,
                                           ties=ties, bounds=tf_bounds, delay=delay,
                                           order_grid=order_grid)
            m, k = num_orders.size, den_orders.size
            terms = tuple(np.array([est[f"{name}{i}"] for i in range(n)])
                          for name, n in (("b", m), ("beta", m), ("a", k), ("alpha", k)))
        G = FractionalTF(*terms, dt=h, delay=delay)
        cols = np.column_stack([G.simulate(fu[j], h) for j in range(fu.shape[0])])
        if n_p:
            p = np.r_[1.0, np.linalg.lstsq(cols[:, 1:], y - cols[:, 0], rcond=None)[0]]
    x = cols @ p
    if output_map.kind == "polynomial":
        d = output_map.params.size
        r = np.linalg.lstsq(np.column_stack([x ** k for k in range(2, d + 2)]), y - x, rcond=None)[0]
        output_map = OutputMap("polynomial", r)
    return terms, p, output_map


def fit_fractional_hw(u, y, *, dt, num_orders, den_orders, num=None, den=None, f_basis=1,
                      output_map="identity", free=None, ties=None, bounds=None, delay=0.0,
                      order_grid=5, n_refine=3, start=None, max_nfev=200, tol=1e-10):
    """Fit ``u -> fbar -> G(s) -> h -> y`` (:class:`fohw.FractionalHW`) by simulation error.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output at ``t_k = k dt`` (zero initial conditions of ``G``).
    dt : float
        Sampling time.
    num_orders, den_orders : array_like
        ``G``'s orders (start values where free).
    num, den : array_like, optional
        ``G``'s start coefficients (default 1).
    f_basis : Basis, int or callables, optional
        The input map's basis (default 1: ``fbar(u) = u``); ``p_1 = 1``, the rest estimated.
    output_map : str, int, tuple or OutputMap, optional
        ``"identity"`` (default); a polynomial degree ``d`` (its ``r2…`` start from linear least
        squares) or ``("polynomial", [r2, …])`` (the same; the values only fix the degree);
        ``"saturation"`` (limits start at the range of ``y``) or ``("saturation", [lower,
        upper])`` (start there).
    free : None or list of str, optional
        Names to estimate (``G``'s ``b0…``, ``beta0…``, ``a0…``, ``alpha0…``; ``p2…``; ``r2…``
        or ``lower``, ``upper``); default as :class:`HWParametrisation`. Fixed ones keep the
        start value.
    ties : dict, optional
        Ties between ``G``'s parameters, ``{"alpha1": ("alpha0", 2.0)}``.
    bounds : dict of str to (float, float), optional
        Bounds of free parameters (``G``'s orders default to ``[-3, 3]``/``[0, 3]``).
    delay : float, optional
        Input delay of ``G`` (a multiple of ``dt``).
    order_grid : int, optional
        Scan points per free order of ``G``: in the linear start fit
        and, for the whole model, a start at every grid point (orders held there while ``G``'s
        coefficients, ``p`` and ``h`` are fitted as in the linear start). 0 or 1: no scan.
    n_refine : int, optional
        How many of the best starts (by simulation error) are refined jointly; the lowest SSE wins.
    start : FractionalHW, optional
        Start here instead of the linear fit then the maps (``G``'s parameters are then named in
        its stored order, decreasing orders: ``FractionalTF.num_orders``, ``den_orders``).
    max_nfev : int, optional
        Simulation budget of the joint refinement.
    tol : float, optional
        ``ftol``, ``xtol``, ``gtol`` of :func:`scipy.optimize.least_squares`.

    Returns
    -------
    FractionalHWFit

    Warns
    -----
    ConvergenceWarning
        The refinement used its budget.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    >>> true = fohw.FractionalHW(G, p=[1.0, 0.5], output_map=("polynomial", [-0.2]))
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-1, 1, 600)
    >>> y = true.simulate(u, dt=0.05) + 0.005 * rng.standard_normal(600)
    >>> fit = fohw.fit_fractional_hw(u, y, dt=0.05, num_orders=[0.0], den_orders=[0.5, 0.0],
    ...                              f_basis=2, output_map=2)
    >>> print(np.round([fit.estimates[n] for n in ("a0", "alpha0", "p2", "r2")], 1))
    [ 2.   0.6  0.5 -0.2]
    """
    u, y, h = _check_data(u, y, dt)
    f_basis = as_basis(f_basis, "f_basis")
    if isinstance(output_map, str) and output_map == "saturation":     # start at the range of y
        if not np.min(y) < np.max(y):
            raise ParameterError("`output_map`='saturation' starts its limits at the range of `y`, "
                                 "which is a single value; give ('saturation', [lower, upper]).")
        output_map = OutputMap("saturation", [float(np.min(y)), float(np.max(y))])
    output_map = OutputMap.make(output_map)
    shift = delay_samples(delay, h)
    num_orders = np.atleast_1d(np.asarray(num_orders, dtype=np.float64))
    den_orders = np.atleast_1d(np.asarray(den_orders, dtype=np.float64))
    num = np.ones(num_orders.size) if num is None else num
    den = np.ones(den_orders.size) if den is None else den
    if start is None:
        kw = dict(f_basis=f_basis, n_p=len(f_basis) - 1, output_map=output_map, delay=float(delay),
                  free=free, ties=ties, bounds=bounds)
        starts = [_start(u, y, h, num=num, num_orders=num_orders, den=den, den_orders=den_orders,
                         order_grid=order_grid, **kw)]
        starts += [_start(u, y, h, num=num, den=den, order_grid=0, **grid_kw, **kw)
                   for grid_kw in _order_scan(num, num_orders, den, den_orders, free, ties, bounds,
                                              order_grid)]
        pars = [HWParametrisation(t, p_, f_basis, om, float(delay), free=free, ties=ties, bounds=bounds)
                for t, p_, om in starts]
    elif isinstance(start, FractionalHW):
        pars = [HWParametrisation.of_model(start, free=free, ties=ties, bounds=bounds)]
    else:
        raise ParameterError(f"`start` must be a FractionalHW; got {type(start).__name__}.")
    n_free = len(pars[0].free_names)
    if y.size <= n_free:
        raise DimensionError(f"`y` has {y.size} samples for {n_free} free parameters; need more samples.")
    y_scale = max(float(np.max(np.abs(y))), 1e-300)

    def residuals(q, par):
        try:
            with np.errstate(all="ignore"):
                yhat = par.model(q, h).simulate(u, h)
        except (ParameterError, FloatingPointError, ArithmeticError):
            return np.full(y.size, 1e4 * y_scale)
        if not np.all(np.isfinite(yhat)) or np.max(np.abs(yhat)) > 1e8 * y_scale:
            return np.full(y.size, 1e4 * y_scale)
        return y - yhat

    def jacobian(q, par):
        try:
            with np.errstate(all="ignore"):
                _, jac = _simulate_and_jacobian(par, q, u, h, shift)
        except (ParameterError, ArithmeticError):
            return np.zeros((y.size, n_free))
        return -jac if np.all(np.isfinite(jac)) else np.zeros((y.size, n_free))

    ranked = sorted(((float(np.sum(residuals(np.clip(par.q0, par.lower, par.upper), par) ** 2)), i)
                     for i, par in enumerate(pars)))
    best = None
    for _, i in ranked[:max(int(n_refine), 1)]:
        par = pars[i]
        res = scipy.optimize.least_squares(residuals, np.clip(par.q0, par.lower, par.upper), jac=jacobian,
                                           bounds=(par.lower, par.upper), args=(par,), method="trf",
                                           x_scale="jac", ftol=tol, xtol=tol, gtol=tol, max_nfev=max_nfev)
        if best is None or res.cost < best[0].cost:
            best = (res, par)
    res, par = best
    if res.status == 0:
        warnings.warn(f"fit_fractional_hw: the refinement used its budget of {max_nfev} simulations "
                      "before meeting `tol`; raise `max_nfev`.", ConvergenceWarning, stacklevel=2)
    model = par.model(res.x, h)
    _, jac = _simulate_and_jacobian(par, res.x, u, h, shift)
    sse = 2.0 * float(res.cost)
    s2 = sse / (y.size - n_free)
    covariance = _covariance(jac, s2)
    return FractionalHWFit(model=model, estimates=dict(zip(par.free_names, map(float, res.x))),
                           free_names=tuple(par.free_names), covariance=covariance,
                           noise_std=float(np.sqrt(s2)), sse=sse, converged=bool(res.status > 0),
                           message=str(res.message), nfev=int(res.nfev),
                           start=par.model(np.clip(par.q0, par.lower, par.upper), h),
                           residuals=np.array(res.fun))


def _order_scan(num, num_orders, den, den_orders, free, ties, bounds, grid):
    """Start settings at each point of a grid of ``G``'s free orders.

    Each is ``{num_orders, den_orders, tf_free}``: the orders held there while the start fit
    estimates the coefficients.
    """
    if grid <= 1:
        return []
    tf_free = None if free is None else [n for n in free if n[:1] in "ab"]
    if tf_free == []:
        return []
    tf_bounds = {k: v for k, v in (bounds or {}).items() if k[:1] in "ab"}
    par = TFParametrisation(num, num_orders, den, den_orders, free=tf_free, ties=ties, bounds=tf_bounds)
    axes = [(j, n) for j, n in enumerate(par.free_names) if n.startswith(("alpha", "beta"))]
    coef_free = [n for n in par.free_names if not n.startswith(("alpha", "beta"))]
    if not axes or not coef_free:
        return []
    values = [par.lower[j] + (par.upper[j] - par.lower[j]) * (np.arange(grid) + 0.5) / grid for j, _ in axes]
    out = []
    for combo in itertools.product(*values):
        p = par.p0
        for (j, _), v in zip(axes, combo):
            p[j] = v
        theta = par.theta(p)
        b, beta, a, alpha = par.split(theta)
        out.append(dict(num_orders=beta, den_orders=alpha, tf_free=coef_free))
    return out


def _covariance(jac, s2):
    """``s2 (J^T J)^{-1}``, with ``nan`` rows for a parameter the data do not inform.

    Its Jacobian column is zero (a saturation limit never reached).
    """
    dead = ~np.any(jac != 0.0, axis=0)
    live = ~dead
    out = np.full((jac.shape[1], jac.shape[1]), np.nan)
    m = jac[:, live].T @ jac[:, live]
    try:
        inv = np.linalg.inv(m)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(m)
    out[np.ix_(live, live)] = s2 * inv
    return out


def fractional_hw_crb(u, model, *, dt, noise_std, free=None, ties=None):
    """Cramér–Rao bound of the free parameters of a :class:`fohw.FractionalHW` for white output noise.

    Parameters
    ----------
    u : array_like, shape (N,)
        The input record.
    model : FractionalHW
        The true model.
    dt : float
        Sampling time.
    noise_std : float
        ``sigma`` of the white Gaussian output noise.
    free, ties : optional
        As in :func:`fit_fractional_hw` (same names).

    Returns
    -------
    names : list of str
    covariance : ndarray
        ``sigma^2 (J^T J)^{-1}``, ``J = d yhat / d q`` at the truth.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> from fohw.estimators.fotf_hw_fit import fractional_hw_crb
    >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    >>> m = fohw.FractionalHW(G, p=[1.0, 0.5], output_map=("polynomial", [-0.2]))
    >>> names, cov = fractional_hw_crb(np.random.default_rng(0).uniform(-1, 1, 500), m, dt=0.05,
    ...                                noise_std=0.01)
    >>> names
    ['b0', 'a0', 'alpha0', 'p2', 'r2']
    """
    u = np.asarray(u, dtype=np.float64)
    if not isinstance(model, FractionalHW):
        raise ParameterError(f"`model` must be a FractionalHW; got {type(model).__name__}.")
    sigma = float(noise_std)
    if not np.isfinite(sigma) or sigma <= 0:
        raise ParameterError(f"`noise_std` must be positive and finite; got {noise_std!r}.")
    u, _, h = _check_data(u, u, dt)
    par = HWParametrisation.of_model(model, free=free, ties=ties)
    _, jac = _simulate_and_jacobian(par, par.q0, u, h, delay_samples(model.G.delay, h))
    return list(par.free_names), _covariance(jac, sigma ** 2)


# G's parametrisation, simulation, Jacobian and linear start fit, used by this module only.

DEFAULT_ORDER_BOUNDS = {"num": (-3.0, 3.0), "den": (0.0, 3.0)}
FREE_PRESETS = ("all", "coefficients", "orders")

def _signal(x, name):
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be an array of real numbers; got {type(x).__name__}.") from None
    if arr.ndim != 1 or arr.size < 2:
        raise DimensionError(f"`{name}` must be 1-D with at least 2 samples; got shape {arr.shape}.")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ParameterError(f"`{name}` must contain only finite values; got {arr[bad]!r} at index {bad}.")
    return arr


def _vector(x, name, n=None, default=None):
    if x is None:
        return np.full(n, default, dtype=np.float64)
    arr = np.atleast_1d(np.asarray(x, dtype=np.float64))
    if arr.ndim != 1 or (n is not None and arr.size != n) or arr.size == 0:
        want = f"length {n}" if n is not None else "a non-empty 1-D sequence"
        raise DimensionError(f"`{name}` must have {want}; got shape {arr.shape}.")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"`{name}` must contain only finite values; got {arr.tolist()}.")
    return arr


class TFParametrisation:
    """Map between the free parameter vector ``p`` and all coefficients and orders.

    Names: ``b0, b1, …`` (numerator coefficients in the order given), ``beta0, …`` (their orders),
    ``a0, …`` (denominator coefficients), ``alpha0, …`` (their orders). ``theta = base + T p``:
    fixed entries stay at their start value, free ones are ``p``, and a tie ``target = factor *
    source`` copies a scaled free (or fixed) parameter.

    Parameters
    ----------
    num, num_orders, den, den_orders : array_like
        Start values (and values of the fixed parameters).
    free : None, {"all", "coefficients", "orders"} or iterable of str
        Which parameters are estimated. ``None`` means ``"all"``: every coefficient except one
        normalising denominator coefficient (the one of the lowest order) and every order that is
        not 0. ``"coefficients"``/``"orders"``: only those (same normaliser). A list names them.
    ties : dict of str to (str, float), optional
        ``{"alpha1": ("alpha0", 2.0)}`` holds ``alpha1 = 2 alpha0``.
    bounds : dict of str to (float, float), optional
        Bounds of free parameters; orders default to ``[-3, 3]`` (numerator) and ``[0, 3]``
        (denominator), coefficients to none.

    Examples
    --------
    >>> from fohw.estimators.fotf_hw_fit import TFParametrisation
    >>> par = TFParametrisation([1.0], [0.0], [2.0, 1.0], [0.5, 0.0])
    >>> par.free_names
    ['b0', 'a0', 'alpha0']
    """

    def __init__(self, num, num_orders, den, den_orders, *, free=None, ties=None, bounds=None):
        num_orders = _vector(num_orders, "num_orders")
        den_orders = _vector(den_orders, "den_orders")
        m, k = num_orders.size, den_orders.size
        num = _vector(num, "num", m, 1.0)
        den = _vector(den, "den", k, 1.0)
        self.m, self.k = m, k
        self.names = ([f"b{j}" for j in range(m)] + [f"beta{j}" for j in range(m)]
                      + [f"a{i}" for i in range(k)] + [f"alpha{i}" for i in range(k)])
        self.index = {name: i for i, name in enumerate(self.names)}
        self.theta0 = np.concatenate([num, num_orders, den, den_orders])
        coef_names = self.names[:m] + self.names[2 * m:2 * m + k]
        order_names = self.names[m:2 * m] + self.names[2 * m + k:]
        ties = dict(ties or {})
        for target, spec in ties.items():
            if target not in self.index:
                raise ParameterError(f"`ties`: unknown parameter {target!r}; names are {self.names}.")
            try:
                source, factor = spec
                factor = float(factor)
            except (TypeError, ValueError):
                raise ParameterError(f"`ties[{target!r}]` must be (source_name, factor); "
                                     f"got {spec!r}.") from None
            if source not in self.index or source in ties:
                raise ParameterError(f"`ties[{target!r}]`: the source {source!r} must be a parameter that "
                                     "is not itself tied.")
        normaliser = self.names[2 * m + int(np.argmin(den_orders))]
        if free is None or (isinstance(free, str) and free in FREE_PRESETS):
            preset = "all" if free is None else free
            chosen = []
            if preset in ("all", "coefficients"):
                chosen += [n for n in coef_names if n != normaliser]
            if preset in ("all", "orders"):
                chosen += [n for n in order_names if self.theta0[self.index[n]] != 0.0]
            free = [n for n in chosen if n not in ties]
        elif isinstance(free, str):
            raise ParameterError(f"`free` must be None, one of {FREE_PRESETS} or a list of names; "
                                 f"got {free!r}.")
        free = list(free)
        for name in free:
            if name not in self.index:
                raise ParameterError(f"`free`: unknown parameter {name!r}; names are {self.names}.")
            if name in ties:
                raise ParameterError(f"`free`: {name!r} is tied (in `ties`); it cannot also be free.")
        if len(set(free)) != len(free):
            raise ParameterError(f"`free` names a parameter twice: {free}.")
        if not free:
            raise ParameterError("`free` is empty: nothing to estimate.")
        if all(n in free or n in ties for n in coef_names):
            raise ParameterError("every coefficient is free or tied: numerator and denominator can be "
                                 "scaled together without changing G; fix one (e.g. the denominator's "
                                 f"constant term {normaliser!r}).")
        self.free_names = free
        self.free_idx = np.array([self.index[n] for n in free], dtype=int)
        self.ties = [(self.index[t], self.index[s], float(f)) for t, (s, f) in ties.items()]
        self.tied_names = list(ties)
        for t, s, f in self.ties:
            self.theta0[t] = f * self.theta0[s]
        lower = np.full(len(free), -np.inf)
        upper = np.full(len(free), np.inf)
        for j, name in enumerate(free):
            if name.startswith("beta"):
                lower[j], upper[j] = DEFAULT_ORDER_BOUNDS["num"]
            elif name.startswith("alpha"):
                lower[j], upper[j] = DEFAULT_ORDER_BOUNDS["den"]
        for name, bound in dict(bounds or {}).items():
            if name not in free:
                raise ParameterError(f"`bounds`: {name!r} is not a free parameter (free: {free}).")
            try:
                lo, hi = (float(v) for v in bound)
            except (TypeError, ValueError):
                raise ParameterError(f"`bounds[{name!r}]` must be a pair (low, high); "
                                     f"got {bound!r}.") from None
            if not lo < hi:
                raise ParameterError(f"`bounds[{name!r}]` must have low < high; got {bound!r}.")
            j = free.index(name)
            lower[j], upper[j] = lo, hi
        self.lower, self.upper = lower, upper
        p0 = self.theta0[self.free_idx]
        outside = (p0 < lower) | (p0 > upper)
        if np.any(outside):
            j = int(np.flatnonzero(outside)[0])
            raise ParameterError(f"the start value of {free[j]!r} ({p0[j]!r}) is outside its bounds "
                                 f"[{lower[j]:g}, {upper[j]:g}]; pass a start inside them.")
        self.T = np.zeros((self.theta0.size, len(free)))
        self.T[self.free_idx, np.arange(len(free))] = 1.0
        for t, s, f in self.ties:
            self.T[t] = f * self.T[s]

    @property
    def p0(self):
        """Start values of the free parameters."""
        return self.theta0[self.free_idx].copy()

    def theta(self, p):
        """All parameters (in :attr:`names` order) for the free values ``p``."""
        theta = self.theta0.copy()
        theta[self.free_idx] = p
        for t, s, f in self.ties:
            theta[t] = f * theta[s]
        return theta

    def split(self, theta):
        """``(num, num_orders, den, den_orders)`` of a full parameter vector."""
        m, k = self.m, self.k
        return theta[:m], theta[m:2 * m], theta[2 * m:2 * m + k], theta[2 * m + k:]


def _simulate(par, theta, ud, h, jacobian=False):
    """Output (and, if asked, d yhat / d theta for all parameters) of the GL-discretised model."""
    with np.errstate(over="ignore", invalid="ignore"):
        return _simulate_quiet(par, theta, ud, h, jacobian)


def _simulate_quiet(par, theta, ud, h, jacobian):
    b, beta, a, alpha = par.split(theta)
    n = ud.size
    c = operator_weights(a, alpha, h, n)
    if c[0] == 0.0 or not np.isfinite(c[0]):
        return None, None
    d = operator_weights(b, beta, h, n)
    yhat = series_divide(causal_product(d, ud, n), c)
    if not jacobian:
        return yhat, None
    r = series_reciprocal(c, n)
    nfft = scipy.fft.next_fast_len(3 * n - 2, real=True)
    rr = scipy.fft.rfft(r, nfft)
    uu = rr * scipy.fft.rfft(ud, nfft)
    yy = -rr * scipy.fft.rfft(yhat, nfft)
    log_h = np.log(h)
    cols = []
    for coefs, orders, x in ((b, beta, uu), (a, alpha, yy)):
        scale = h ** (-orders)
        block_c, block_o = [], []
        for cf, nu, s in zip(coefs, orders, scale):
            w = gl_weights(nu, n)
            dw = gl_weights_derivative(nu, n) - log_h * w
            block_c.append(scipy.fft.irfft(x * scipy.fft.rfft(s * w, nfft), nfft)[:n])
            block_o.append(scipy.fft.irfft(x * scipy.fft.rfft(cf * s * dw, nfft), nfft)[:n])
        cols += block_c + block_o
    return yhat, np.column_stack(cols)


def _shifted(u, shift):
    ud = np.zeros_like(u)
    if shift < u.size:
        ud[shift:] = u[:u.size - shift]
    return ud


def _equation_error_start(par, theta, ud, y, h):
    """Coefficients from the linear equation error ``sum a_i W_{alpha_i} y - sum b_j W_{beta_j} u``."""
    m, k = par.m, par.k
    coef_idx = np.r_[0:m, 2 * m:2 * m + k]
    t_coef = par.T[coef_idx]
    order_idx = np.r_[m:2 * m, 2 * m + k:2 * m + 2 * k]
    free_coef = np.flatnonzero(np.any(t_coef != 0, axis=0))
    if free_coef.size == 0 or np.any(par.T[np.ix_(order_idx, free_coef)] != 0):
        return theta
    b, beta, a, alpha = par.split(theta)
    n = y.size
    cols = [-causal_product(operator_weights([1.0], [nu], h, n), ud, n) for nu in beta]
    cols += [causal_product(operator_weights([1.0], [nu], h, n), y, n) for nu in alpha]
    M = np.column_stack(cols)
    base = theta[coef_idx] - t_coef[:, free_coef] @ theta[par.free_idx[free_coef]]
    A = M @ t_coef[:, free_coef]
    rhs = -M @ base
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    sol = np.linalg.lstsq(A / scale, rhs, rcond=None)[0] / scale
    out = theta.copy()
    p = out[par.free_idx]
    p[free_coef] = np.clip(sol, par.lower[free_coef], par.upper[free_coef])
    return par.theta(np.where(np.isfinite(p), p, theta[par.free_idx]))


def _order_candidates(par, grid):
    """Grid values of each free order (``grid`` interior points of its bounds) plus the start."""
    axes = []
    for j, name in enumerate(par.free_names):
        if not name.startswith(("alpha", "beta")):
            axes.append(None)
            continue
        lo, hi = par.lower[j], par.upper[j]
        values = lo + (hi - lo) * (np.arange(grid) + 0.5) / grid
        axes.append(np.unique(np.r_[values, par.p0[j]]))
    order_axes = [(j, v) for j, v in enumerate(axes) if v is not None]
    if not order_axes:
        return [par.p0]
    out = []
    for combo in itertools.product(*(v for _, v in order_axes)):
        p = par.p0
        for (j, _), value in zip(order_axes, combo):
            p[j] = value
        out.append(p)
    return out


def _prepare(u, y, dt, delay):
    u = _signal(u, "u")
    if y is not None:
        y = _signal(y, "y")
        if y.size != u.size:
            raise DimensionError(f"`u` and `y` must have the same length; got {u.size} and {y.size}.")
    if isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (numbers.Real, np.number)) \
            or not np.isfinite(dt) or dt <= 0:
        raise ParameterError(f"`dt` must be a positive finite number; got {dt!r}.")
    delays = np.atleast_1d(np.asarray(delay, dtype=np.float64))
    if delays.ndim != 1 or delays.size == 0 or not np.all(np.isfinite(delays)) or np.any(delays < 0):
        raise ParameterError(f"`delay` must be a non-negative number or a sequence of them; got {delay!r}.")
    shifts = [delay_samples(d, float(dt)) for d in delays]
    return u, y, float(dt), delays, shifts


def _linear_tf_estimates(u, y, *, dt, num_orders, den_orders, num=None, den=None, free=None, ties=None,
                         bounds=None, delay=0.0, order_grid=5, n_refine=3, max_nfev=200, tol=1e-10):
    """``G``'s parameters (``{name: value}``) fitted to ``u -> y`` by simulation error.

    The start of :func:`fit_fractional_hw`: a scan of the free orders with equation-error
    coefficients, the best ``n_refine`` refined by least squares.
    """
    u, y, h, delays, shifts = _prepare(u, y, dt, delay)
    par = TFParametrisation(num, num_orders, den, den_orders, free=free, ties=ties, bounds=bounds)
    n_free = len(par.free_names)
    if y.size <= n_free:
        raise DimensionError(f"`y` has {y.size} samples for {n_free} free parameters; need more samples.")
    y_scale = max(float(np.max(np.abs(y))), 1e-300)
    best = None
    scan_table = []
    for dly, shift in zip(delays, shifts):
        ud = _shifted(u, shift)

        def residuals(p, ud=ud):
            yhat, _ = _simulate(par, par.theta(p), ud, h)
            if yhat is None or not np.all(np.isfinite(yhat)) or np.max(np.abs(yhat)) > 1e8 * y_scale:
                return np.full(y.size, 1e4 * y_scale)
            return y - yhat

        def jacobian(p, ud=ud):
            yhat, jac = _simulate(par, par.theta(p), ud, h, jacobian=True)
            if jac is None or not np.all(np.isfinite(jac)):
                return np.zeros((y.size, n_free))
            return -(jac @ par.T)

        starts = []
        for p in (_order_candidates(par, order_grid) if order_grid > 1 else [par.p0]):
            for theta in (par.theta(p), _equation_error_start(par, par.theta(p), ud, y, h)):
                q = theta[par.free_idx]
                sse = float(np.sum(residuals(q) ** 2))
                starts.append((sse, tuple(q)))
        starts.sort()
        unique = list(dict.fromkeys(starts))
        scan_table += [({name: v for name, v in zip(par.free_names, q)
                         if name.startswith(("alpha", "beta"))}, sse) for sse, q in unique]
        for sse, q in unique[:max(int(n_refine), 1)]:
            if not np.isfinite(sse):
                continue
            res = scipy.optimize.least_squares(residuals, np.array(q), jac=jacobian,
                                               bounds=(par.lower, par.upper),
                                               method="trf", x_scale="jac", ftol=tol, xtol=tol, gtol=tol,
                                               max_nfev=max_nfev)
            if best is None or res.cost < best[0].cost:
                best = (res, dly, ud)
    if best is None:
        raise ParameterError("no start gave a finite simulation; give starts (`num`, `den`) or bounds.")
    res = best[0]
    return {n: float(v) for n, v in zip(par.names, par.theta(res.x))}


def jacobian_at(par, p, ud, h):
    """``d yhat / d p`` (shape ``(N, n_free)``) at the free values ``p`` for the delayed input ``ud``.

    Parameters
    ----------
    par : TFParametrisation
        The parametrisation.
    p : ndarray
        Free parameter values.
    ud : ndarray
        Input already shifted by the delay.
    h : float
        Sampling time.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.fotf_hw_fit import TFParametrisation, jacobian_at
    >>> par = TFParametrisation([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], free=["b0"])
    >>> jacobian_at(par, par.p0, np.ones(3), 1.0).ravel()     # d yhat / d b0 = yhat / b0
    array([0.5  , 0.75 , 0.875])
    """
    _, jac = _simulate(par, par.theta(p), ud, h, jacobian=True)
    if jac is None:
        raise ParameterError("the implicit GL step is singular at these parameters.")
    return jac @ par.T
