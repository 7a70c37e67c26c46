"""Identification of a fractional transfer function by simulation (output) error (FOMCON ``fid``).

The model ``G(s) = sum_j b_j s^{beta_j} / sum_i a_i s^{alpha_i} e^{-s tau}`` is simulated by the GL
discretisation of :class:`fohw.FractionalTF`, and ``sum_k (y[k] - yhat[k])^2`` is minimised over the
free coefficients and orders by :func:`scipy.optimize.least_squares` with the exact Jacobian:
with ``R = 1 / C`` (the power-series reciprocal of the denominator's GL weights) and ``W_nu`` the
GL weights of ``D^nu``,

- ``d yhat / d b_j = R * W_{beta_j} * u``,  ``d yhat / d beta_j = R * b_j (d W_{beta_j} / d beta_j) * u``,
- ``d yhat / d a_i = -R * W_{alpha_i} * yhat``,
  ``d yhat / d alpha_i = -R * a_i (d W_{alpha_i} / d alpha_i) * yhat``,

each a causal convolution evaluated by one zero-padded FFT product. The start comes from a scan
of the free orders (equation-error least squares for the coefficients at each grid point, ranked
by the simulation error); the best few are refined. Standard errors are ``s^2 (J^T J)^{-1}``
with ``s^2 = SSE / (N - p)``; the Cramér–Rao bound for white output noise of known ``sigma`` is
``sigma^2 (J^T J)^{-1}`` at the true parameters (:func:`fractional_tf_crb`).
"""

from __future__ import annotations

import itertools
import numbers
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from ..exceptions import ConvergenceWarning, DimensionError, ParameterError
from ..model.fotf import FractionalTF, delay_samples, operator_weights
from ..model.gl import gl_weights, gl_weights_derivative
from ..model.series_division import causal_product, series_divide, series_reciprocal

__all__ = ["fit_fractional_tf", "fractional_tf_crb", "FractionalTFFit", "TFParametrisation"]

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
    >>> from fohw.estimators.tf_fit import TFParametrisation
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


@dataclass(frozen=True)
class FractionalTFFit:
    """Result of :func:`fit_fractional_tf`.

    Attributes
    ----------
    model : FractionalTF
        The fitted transfer function (with ``dt`` and the chosen ``delay``).
    estimates : dict of str to float
        Every parameter (``b0…``, ``beta0…``, ``a0…``, ``alpha0…``), free, tied or fixed.
    free_names : tuple of str
        The estimated parameters, in the order of :attr:`covariance`.
    covariance : ndarray
        ``s^2 (J^T J)^{-1}`` of the free parameters, ``s^2 = SSE / (N - p)``.
    noise_std : float
        ``s``, the residual standard deviation.
    sse : float
        Sum of squared simulation errors.
    delay : float
        The delay used (the best of the candidates when several were given).
    converged : bool
        ``least_squares`` met a tolerance (``status > 0``).
    message : str
        The solver's message.
    nfev : int
        Simulations in the final refinement.
    scan : list of (dict, float)
        Scanned start orders and their simulation SSE, best first.
    residuals : ndarray
        ``y - yhat``.
    tied : dict
        Tied parameters: ``{target: (source, factor)}``.
    """

    model: FractionalTF
    estimates: dict
    free_names: tuple
    covariance: np.ndarray
    noise_std: float
    sse: float
    delay: float
    converged: bool
    message: str
    nfev: int
    scan: list = field(repr=False)
    residuals: np.ndarray = field(repr=False)
    tied: dict = field(default_factory=dict, repr=False)

    def standard_errors(self):
        """Standard errors of the free and tied parameters.

        Returns
        -------
        dict of str to float

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
        >>> u = np.random.default_rng(0).standard_normal(400)
        >>> y = G.simulate(u, dt=0.05) + 0.01 * np.random.default_rng(1).standard_normal(400)
        >>> fit = fohw.fit_fractional_tf(u, y, dt=0.05, num_orders=[0.0], den_orders=[0.5, 0.0])
        >>> sorted(fit.standard_errors())
        ['a0', 'alpha0', 'b0']
        """
        se = np.sqrt(np.diag(self.covariance))
        out = dict(zip(self.free_names, (float(v) for v in se)))
        for target, (source, factor) in self.tied.items():
            if source in out:
                out[target] = abs(factor) * out[source]
        return out

    def summary(self):
        """A text table of the estimates with standard errors.

        Returns
        -------
        str

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])
        >>> u = np.random.default_rng(0).standard_normal(300)
        >>> fit = fohw.fit_fractional_tf(u, G.simulate(u, dt=0.1), dt=0.1, num_orders=[0.0],
        ...                              den_orders=[1.0, 0.0], free=["b0", "a0"])
        >>> print(fit.summary().splitlines()[1])
          model: 1 / (s + 1)
        """
        se = self.standard_errors()
        lines = ["Fractional transfer function fit (output error)",
                 f"  model: {self.model}", f"  residual std {self.noise_std:.4g}, SSE {self.sse:.4g}, "
                 f"converged {self.converged} ({self.nfev} simulations)",
                 f"  {'parameter':<10} {'estimate':>14} {'std. error':>12}  status"]
        for name, value in self.estimates.items():
            status = "free" if name in self.free_names else ("tied" if name in self.tied else "fixed")
            err = f"{se[name]:12.4g}" if name in se else f"{'':12}"
            lines.append(f"  {name:<10} {value:14.6g} {err}  {status}")
        return "\n".join(lines)


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


def fit_fractional_tf(u, y, *, dt, num_orders, den_orders, num=None, den=None, free=None, ties=None,
                      bounds=None, delay=0.0, order_grid=5, n_refine=3, max_nfev=200, tol=1e-10):
    """Fit ``G(s) = sum_j b_j s^{beta_j} / sum_i a_i s^{alpha_i} e^{-s delay}`` to sampled data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output samples at ``t_k = k dt`` (zero initial conditions: remove the
        operating point first). Alignment as in :class:`fohw.FractionalTF`.
    dt : float
        Sampling time.
    num_orders, den_orders : array_like
        Orders of the numerator and denominator terms (start values where free). Numerator orders
        may be negative (a Warburg term ``s^{-1/2}``).
    num, den : array_like, optional
        Start values of the coefficients (default all 1); fixed ones keep these values.
    free : None, {"all", "coefficients", "orders"} or list of str, optional
        The estimated parameters by name (``b0…``, ``beta0…``, ``a0…``, ``alpha0…``, indexed in the
        order given); default every coefficient but the denominator's lowest-order one (the scale
        normaliser) and every non-zero order. See :class:`TFParametrisation`.
    ties : dict of str to (str, float), optional
        ``{"alpha1": ("alpha0", 2.0)}`` holds ``alpha1 = 2 alpha0`` (e.g. commensurate orders).
    bounds : dict of str to (float, float), optional
        Bounds of free parameters (e.g. ``{"a0": (0, inf)}`` for a time constant). Orders default
        to ``[-3, 3]`` (numerator) and ``[0, 3]`` (denominator).
    delay : float or sequence of float, optional
        Input delay, a multiple of ``dt``; with several candidates each is fitted and the lowest
        SSE kept.
    order_grid : int, optional
        Scan points per free order for the start (plus the given start); 0 or 1 skips the scan.
    n_refine : int, optional
        How many of the best scanned starts are refined by least squares.
    max_nfev : int, optional
        Simulation budget of each refinement.
    tol : float, optional
        ``ftol``, ``xtol`` and ``gtol`` of :func:`scipy.optimize.least_squares`.

    Returns
    -------
    FractionalTFFit

    Raises
    ------
    ParameterError, DimensionError
        Bad input (named), or no start with a finite simulation.

    Warns
    -----
    ConvergenceWarning
        The refinement used its simulation budget.

    Notes
    -----
    Output-error least squares (see the module docstring for the exact Jacobian). With white
    output noise the estimates reach the Cramér–Rao bound (:func:`fractional_tf_crb`), measured
    in ``docs/transfer_functions.md``.

    Examples
    --------
    >>> import numpy as np
    >>> import fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])       # 1 / (2 s^0.6 + 1)
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(500)
    >>> y = G.simulate(u, dt=0.05) + 0.01 * rng.standard_normal(500)
    >>> fit = fohw.fit_fractional_tf(u, y, dt=0.05, num_orders=[0.0], den_orders=[0.5, 0.0])
    >>> print(np.round([fit.estimates["a0"], fit.estimates["alpha0"]], 2))
    [2.  0.6]
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
    res, dly, ud = best
    p = res.x
    theta = par.theta(p)
    jac = jacobian_at(par, p, ud, h)
    sse = 2.0 * float(res.cost)
    dof = y.size - n_free
    s2 = sse / dof
    covariance = s2 * _inverse(jac.T @ jac)
    if res.status == 0:
        warnings.warn(f"fit_fractional_tf: the refinement used its budget of {max_nfev} simulations "
                      "before meeting `tol`; raise `max_nfev` or check the start.", ConvergenceWarning,
                      stacklevel=2)
    b, beta, a, alpha = par.split(theta)
    model = FractionalTF(b, beta, a, alpha, dt=h, delay=float(dly))
    scan_table.sort(key=lambda row: row[1])
    return FractionalTFFit(model=model, estimates={n: float(v) for n, v in zip(par.names, theta)},
                           free_names=tuple(par.free_names), covariance=covariance,
                           noise_std=float(np.sqrt(s2)), sse=sse, delay=float(dly),
                           converged=bool(res.status > 0), message=str(res.message),
                           nfev=int(res.nfev), scan=scan_table, residuals=np.array(res.fun),
                           tied={t: tuple(v) for t, v in (ties or {}).items()})


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
    >>> from fohw.estimators.tf_fit import TFParametrisation, jacobian_at
    >>> par = TFParametrisation([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], free=["b0"])
    >>> jacobian_at(par, par.p0, np.ones(3), 1.0).ravel()     # d yhat / d b0 = yhat / b0
    array([0.5  , 0.75 , 0.875])
    """
    _, jac = _simulate(par, par.theta(p), ud, h, jacobian=True)
    if jac is None:
        raise ParameterError("the implicit GL step is singular at these parameters.")
    return jac @ par.T


def _inverse(m):
    try:
        return np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(m)


def fractional_tf_crb(u, *, dt, num, num_orders, den, den_orders, noise_std, free=None, ties=None,
                      delay=0.0):
    """Cramér–Rao bound of the free parameters for white Gaussian output noise of known std.

    Parameters
    ----------
    u : array_like, shape (N,)
        The input record.
    dt : float
        Sampling time.
    num, num_orders, den, den_orders : array_like
        The true parameters.
    noise_std : float
        Standard deviation ``sigma`` of the output noise.
    free, ties : optional
        As in :func:`fit_fractional_tf` (the same parametrisation and names).
    delay : float, optional
        Input delay (a multiple of ``dt``).

    Returns
    -------
    names : list of str
        The free parameters.
    covariance : ndarray
        ``sigma^2 (J^T J)^{-1}``, ``J = d yhat / d p`` at the truth.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.tf_fit import fractional_tf_crb
    >>> u = np.random.default_rng(0).standard_normal(1000)
    >>> names, cov = fractional_tf_crb(u, dt=0.05, num=[1.0], num_orders=[0.0], den=[2.0, 1.0],
    ...                                den_orders=[0.6, 0.0], noise_std=0.1)
    >>> names
    ['b0', 'a0', 'alpha0']
    """
    u, _, h, delays, shifts = _prepare(u, None, dt, delay)
    sigma = float(noise_std)
    if not np.isfinite(sigma) or sigma <= 0:
        raise ParameterError(f"`noise_std` must be positive and finite; got {noise_std!r}.")
    par = TFParametrisation(num, num_orders, den, den_orders, free=free, ties=ties)
    jac = jacobian_at(par, par.p0, _shifted(u, shifts[0]), h)
    return list(par.free_names), sigma ** 2 * _inverse(jac.T @ jac)
