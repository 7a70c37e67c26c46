"""Simulation-focused (output-error) fitting — beyond the paper.

The paper's estimators, like every equation-error method, minimise the *one-step* prediction
error (Eq. 41). A model can predict one step ahead very well and still simulate badly (or be
unstable) in free run, which is how users of identification tools judge a model (MATLAB's
``compare``, the fit index of nonlinear benchmarks). This module minimises the free-run
simulation error instead:

``min over (theta, alpha)  sum_{k >= n_init} (y[k] - ysim[k; theta, alpha])**2``

with a trust-region reflective least-squares solver (:func:`scipy.optimize.least_squares`),
started from the equation-error estimate. Its Jacobian is ``-S``, with ``S`` the exact
sensitivity of the free run (:func:`fohw.model.lagged.sensitivity.simulation_jacobian`: one simulation
and one linear recursion of the same cost class, instead of the ``d + 1`` simulations of finite
differences over ``d`` parameters). The standard errors are ``s^2 (S^T S)^{-1}`` at the
estimate, ``S`` being also the Jacobian of the output-noise Cramér–Rao bound (:func:`fohw.crb`
with ``noise="output"``), which the fit reaches when the noise is added to the measured output.
Candidate models whose simulation escapes (beyond ten times the largest measured ``|y|``) get a
large constant residual, so the solver steps back from them (the Jacobian there is zero, the
derivative of that constant); an unstable starting model is first made stable by shrinking its
output-feedback block.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .. import _linalg
from .._threads import thin_solves
from .._validation import check_array, check_scalar
from ..exceptions import DimensionError, ParameterError, SimulationDivergedError
from ..model.lagged.regressors import RegressorBuilder
from ..model.lagged.sensitivity import simulation_jacobian
from ..model.lagged.simulation import simulate_predictor
from ..results import IdentificationResult, Status
from ._common import (
    bound_note,
    bounded_least_squares,
    bounds_record,
    check_enough_samples,
    finish,
    joint_levels_note,
    kept_above_zero,
    rms_scale,
    stationary,
)
from .options import N_GRID, Anything, Integer, Method, MethodOptions
from .profile import parameter_covariance
from .starts import AGREEMENT_RTOL, Start, agreement, multi_start, nested_structure
from .varpro import VarproOptions
from .varpro_search import separable_least_squares

__all__ = ["OutputErrorOptions", "fit_output_error", "SimulationResidual", "METHOD"]


@dataclass(frozen=True, kw_only=True)
class OutputErrorOptions(MethodOptions):
    """Options of ``method="output_error"``.

    Attributes
    ----------
    n_init : int
        Leading samples left out of the simulation-error criterion (the start-up transient of
        a zero-initial-condition model on data that did not start at rest; default 0).
    start : IdentificationResult, (linear, nonlinear) or None
        Starting point: a result for the same structure, or the linear parameters (theta, then
        the offset) and the nonlinear ones (free orders, then past levels); for the paper's
        model ``(theta, alpha)``. Default (None): the ``"varpro"`` estimate.
    n_grid : int
        Points of the coarse alpha scan of the ``"varpro"`` start (default 41).
    max_nfev : int
        Residual evaluations allowed to :func:`scipy.optimize.least_squares` (default 300,
        as scipy counts them: the Jacobian evaluations, one simulation and its sensitivity
        each, come on top; :attr:`IdentificationResult.nfev` counts both). Per local search.
        Sized on the docs' cascaded-tanks grid (36 mixed and per-lag candidates, 768
        samples): 19 stopped at MAX_ITER with 100, 14 with 300, 10 with 1000 (8 of them
        mixed, whose near-duplicate columns make a long flat valley); 300 costs 1.8 times
        the simulations of 100 there, 1000 3.9 times.
    n_starts : int
        Local searches of the default chain (:mod:`fohw.estimators.starts`, used when
        ``start`` is None and the class has free orders): the candidates (the nested integer
        models, the equation-error estimate, a scan of the orders) are ranked by their
        free-run criterion; the best is searched, then (``n_starts >= 2``) the
        equation-error estimate whatever its rank, then the next best (on ``executor`` when
        :func:`fohw.identify` has one); the best result is kept. Default 2. The fit never
        ends above the nested integer model's criterion, whatever ``n_starts``.
    """

    constraints = {"n_init": Integer(0, lambda c: c.n_samples - 2), "start": Anything(),
                   "n_grid": N_GRID, "max_nfev": Integer(1), "n_starts": Integer(1, 1000)}

    n_init: int = 0
    start: object = None
    n_grid: int = 41
    max_nfev: int = 300
    n_starts: int = 2


@dataclass
class _OEFit:
    linear: np.ndarray
    params: np.ndarray
    sse: float
    start_shrink: float
    status: Status
    message: str
    covariance: np.ndarray | None
    noise_variance: float
    nit: int
    nfev: int
    at_lower: np.ndarray
    at_upper: np.ndarray
    start_sse: float = np.inf
    stuck: bool = False


class SimulationResidual:
    """The simulation-error residual ``(y - ysim(x))[n_init:]`` and its exact Jacobian.

    ``x`` is ``(linear, params)``. A candidate whose free run escapes (``|ysim|`` beyond
    ``guard``, ten times the largest measured ``|y|``) gets the constant residual ``2 guard``
    on every sample, so the solver steps back from it; the Jacobian there is zero, the
    derivative of that constant. Elsewhere the Jacobian is ``-S[n_init:]`` with ``S`` the
    exact sensitivity of the free run (:func:`~fohw.model.lagged.sensitivity.simulation_jacobian`),
    which says the run escapes exactly when the residual does (the same recursion, the same
    ``guard``). Should the sensitivity's own simulation stop where the residual's did not (its
    default divergence threshold, ``1e8`` times the model's drive, below ``guard``: a gain
    beyond about 1e7), the Jacobian falls back to forward differences of the residual.
    :attr:`n_simulations` counts free runs, those inside Jacobians included.
    """

    def __init__(self, structure, u, y, n_init, lower, upper):
        self.structure, self.u, self.y = structure, u, y
        self.guard = 10.0 * float(np.max(np.abs(y)))
        self.window = slice(n_init, None)
        self.penalty = np.full(y.shape[0] - n_init, 2.0 * self.guard)
        self.lower, self.upper = lower, upper
        self.n_simulations = 0
        self.n_jacobians = 0
        self._last = None                   # (x as bytes, residual) of the latest residual

    def simulate(self, x):
        """Free run at ``x``; :class:`SimulationDivergedError` beyond ``guard``."""
        self.n_simulations += 1
        n = self.structure.n_linear
        return simulate_predictor(self.structure, x[:n], x[n:], self.u,
                                  divergence_threshold=self.guard)

    def residual(self, x):
        """``(y - ysim(x))[n_init:]``, or the constant penalty if the run escapes."""
        try:
            r = (self.y - self.simulate(x))[self.window]
        except SimulationDivergedError:
            r = self.penalty
        self._last = (x.tobytes(), r)
        return r

    def jacobian(self, x):
        """``d residual / dx``: ``-S[n_init:]``, or zeros where the residual is the penalty."""
        self.n_jacobians += 1
        self.n_simulations += 1
        n = self.structure.n_linear
        try:
            ysim, sens = simulation_jacobian(self.structure, x[:n], x[n:], self.u)
        except SimulationDivergedError:
            ysim = sens = None
        if ysim is not None and np.max(np.abs(ysim)) <= self.guard:
            return -sens[self.window]
        r = self._last[1] if self._last and self._last[0] == x.tobytes() else self.residual(x)
        if r is self.penalty or ysim is not None:
            return np.zeros((self.penalty.shape[0], x.shape[0]))
        return self._forward_difference(x, r)

    def scaled(self, scale, y_scale):
        """``(residual, jacobian)`` of ``z = x / scale``, the residual divided by ``y_scale``."""

        def residual(z):
            return self.residual(z * scale) / y_scale

        def jacobian(z):
            return self.jacobian(z * scale) * (scale / y_scale)

        return residual, jacobian

    def _forward_difference(self, x, r):
        step = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(x), 1.0)
        step = np.where(x + step > self.upper, -step, step)
        cols = []
        for i in range(x.shape[0]):
            xi = x.copy()
            xi[i] += step[i]
            cols.append((self.residual(xi) - r) / (xi[i] - x[i]))
        return np.column_stack(cols)


def fit_output_error(builder, linear0, params0, *, lower, upper, n_init=0, max_nfev=None,
                     held=None):
    """Fit the linear and nonlinear parameters to minimise the free-run simulation error.

    Parameters
    ----------
    builder : RegressorBuilder
        The record (deviations from the operating point) and the model class.
    linear0, params0 : ndarray
        Starting point (usually the equation-error estimate).
    lower, upper : ndarray
        Bounds of the free orders.
    n_init : int
        Leading samples left out of the criterion (start-up transient of a zero-initial-
        condition model on data that did not start at rest).
    max_nfev : int, optional
        Limit on residual evaluations, passed to :func:`scipy.optimize.least_squares`
        (Jacobian evaluations are not counted).
    held : ndarray of bool, optional
        Linear parameters held at their start values (:func:`held_columns`: the columns of the
        information matrix that depend on the others on this record); the search runs over
        the rest, a reduced class that simulates every model of the full one the record can
        tell apart.

    Returns
    -------
    _OEFit
    """
    s = builder.structure
    u, y = builder.u, builder.y
    n_lin, n_free = s.n_linear, len(s.orders.free)
    n_past = s.n_nonlinear - n_free
    window = slice(n_init, None)
    m = y.shape[0] - n_init
    bound_lo = np.r_[np.full(n_lin, -np.inf), lower, np.full(n_past, -np.inf)]
    bound_hi = np.r_[np.full(n_lin, np.inf), upper, np.full(n_past, np.inf)]
    crit = SimulationResidual(s, u, y, n_init, bound_lo, bound_hi)

    x0 = np.r_[np.asarray(linear0, dtype=np.float64), np.asarray(params0, dtype=np.float64)]
    k = s.layout.n_output_params
    shrink = 1.0
    sse0 = np.inf
    for _ in range(60):
        try:
            r0 = (y - crit.simulate(x0))[window]
            sse0 = float(r0 @ r0)
            break
        except SimulationDivergedError:
            shrink *= 0.8
            x0[:k] *= 0.8
    x0 = np.clip(x0, bound_lo, bound_hi)
    # The solver works on dimensionless z = x / scale and a residual divided by the RMS output,
    # so that its steps and tolerances mean the same in every unit.
    scale = _parameter_scale(x0, s, u, y)
    y_scale = rms_scale(y)

    residual, jacobian = crit.scaled(scale, y_scale)
    keep = kept_above_zero(s, n_lin, lower)
    fixed = np.zeros(x0.shape[0], dtype=bool)
    if held is not None:
        fixed[:n_lin] = held
    z, status, ls = _least_squares_pinned(residual, jacobian, x0 / scale, fixed,
                                          lower=bound_lo / scale, upper=bound_hi / scale,
                                          keep=keep, max_nfev=max_nfev)
    pinned = keep & (x0 == bound_lo)
    if np.any(pinned) and not float(ls.fun @ ls.fun) * y_scale ** 2 <= sse0:
        # An order started exactly on a lower bound of 0 with estimated past levels: the model
        # jumps at 0 (kept_above_zero) and the solver starts 1e-10 inside its bounds, so it
        # searched from the nu -> 0+ model, not the one it was given, and ended above the
        # start (cascaded tanks, per-lag from its orders-0 fit: 86.8 -> 4227). Search again
        # with those orders held at 0 and keep the better of the two.
        again = _least_squares_pinned(residual, jacobian, x0 / scale, pinned | fixed,
                                      lower=bound_lo / scale, upper=bound_hi / scale,
                                      keep=keep, max_nfev=max_nfev)
        if float(again[2].fun @ again[2].fun) < float(ls.fun @ ls.fun):
            z, status, ls = again
    x = z * scale
    fun = ls.fun * y_scale
    sse = float(fun @ fun)
    # The solver's last residual is the (scaled) penalty: the start escaped even after
    # shrinking, and the zero Jacobian there stopped scipy.
    escaped = np.array_equal(ls.fun, crit.penalty / y_scale)
    if escaped:
        status = Status.FAILED
    # Standard errors from the exact sensitivity of the free run at the estimate (the
    # Jacobian of the output-noise bound, fohw.crb(noise="output")), at x with the orders put
    # on an active bound (the solver's last Jacobian is at its own x, ~1e-10 inside).
    try:
        ysim, sens = simulation_jacobian(s, x[:n_lin], x[n_lin:], u)
        jac = sens[window]
        r_x = (y - ysim)[window]
    except SimulationDivergedError:
        jac, r_x = ls.jac * y_scale / scale, None
    # Stuck: the solver gave up on shrinking its trust region (xtol) without lowering the
    # criterion from the start, and the start is not stationary within the bounds: it is no
    # minimum it found, only where it stopped. A start on a bound whose projected gradient
    # is zero (the nested integer model at orders 0, when the data are integer-order) is a
    # minimum: CONVERGED, and the bound is named (bound_note). An order on a lower bound of 0
    # with estimated past levels (kept_above_zero) is the nested model there: the model jumps
    # at 0, so its one-sided derivative says nothing, and the search above 0 found no lower
    # criterion; the other parameters must be stationary.
    smooth = ~(keep & (x - bound_lo <= 1e-8)) & ~fixed
    stuck = (not escaped and ls.status == 3 and not sse < sse0 * (1.0 - 1e-9)
             and (r_x is None or not stationary(jac[:, smooth], r_x, x[smooth],
                                                bound_lo[smooth], bound_hi[smooth])))
    if stuck:
        status = Status.FAILED
    cov, s2 = parameter_covariance(jac, sse, m)
    active = ls.active_mask[n_lin:n_lin + n_free]
    how = (f"{crit.n_simulations} simulations, {crit.n_jacobians} of them with the exact "
           "sensitivity")
    message = f"output-error fit (scipy.optimize.least_squares): {ls.message} ({how})"
    if escaped:
        message = ("output-error fit failed: the free run of the estimate escapes (beyond ten "
                   "times the largest measured |y|), as did the start after shrinking its "
                   f"output parameters 60 times; {message}. Give a start whose simulation "
                   "stays bounded.")
    elif stuck:
        message = ("output-error fit stuck at its start: the local search made no step that "
                   f"lowered the simulation error ({message}), so the estimate is where it "
                   "started, not a minimum.")
    return _OEFit(linear=x[:n_lin].copy(), params=x[n_lin:].copy(), sse=sse, start_shrink=shrink,
                  status=status, message=message, covariance=cov, noise_variance=s2,
                  nit=int(ls.njev), nfev=crit.n_simulations, at_lower=active < 0,
                  at_upper=active > 0, start_sse=sse0, stuck=stuck)


def _least_squares_pinned(residual, jacobian, z0, pinned, *, lower, upper, keep, max_nfev):
    """:func:`bounded_least_squares` over the entries not ``pinned`` (those stay at ``z0``).

    The solver's result has ``x``, ``jac`` and ``active_mask`` over every entry again, the
    pinned ones reported active on their lower bound.
    """
    if not np.any(pinned):
        return bounded_least_squares(residual, z0, jac=jacobian, lower=lower, upper=upper,
                                     keep=keep, max_nfev=max_nfev)
    free = ~pinned

    def full(zf):
        z = z0.copy()
        z[free] = zf
        return z

    zf, status, ls = bounded_least_squares(
        lambda zf: residual(full(zf)), z0[free], jac=lambda zf: jacobian(full(zf))[:, free],
        lower=lower[free], upper=upper[free], keep=keep[free], max_nfev=max_nfev)
    jac = np.zeros((ls.fun.shape[0], z0.shape[0]))
    jac[:, free] = ls.jac
    active = np.full(z0.shape[0], -1, dtype=int)
    active[free] = ls.active_mask
    ls.x, ls.jac, ls.active_mask = full(ls.x), jac, active
    return full(zf), status, ls


def _parameter_scale(x0, structure, u, y):
    """Typical size of each parameter.

    ``|x0|`` for theta's entries (a zero entry takes its block's largest), the offset's and
    the past levels' own scale (the RMS of y or u), 1 for the orders (dimensionless).
    """
    layout = structure.layout
    scale = np.abs(x0).astype(float)
    k, n = layout.n_output_params, layout.n_params
    for block in (slice(0, k), slice(k, n)):
        part = scale[block]
        part[part == 0] = part.max() if part.max() > 0 else 1.0
    pos = n
    if structure.offset:
        scale[pos] = max(scale[pos], rms_scale(y))
        pos += 1
    n_free = len(structure.orders.free)
    scale[pos:pos + n_free] = 1.0
    if structure.past == "estimate":
        scale[pos + n_free] = rms_scale(u)
        scale[pos + n_free + 1] = rms_scale(y)
    return scale


def _start(builder, options, lower, upper):
    """``(linear0, params0, J0, description)``: the varpro estimate or the given start."""
    start = options.start
    s = builder.structure
    if start is None:
        vp = separable_least_squares(builder, bounds=(lower, upper),
                                     options=VarproOptions(n_grid=options.n_grid))
        return vp.linear, vp.params, vp.rss / builder.n_samples, "the varpro estimate"
    if isinstance(start, IdentificationResult):
        if start.structure != s:
            raise ParameterError("`start` is a result for another model structure "
                                 f"({start.structure.describe()}); this fit is "
                                 f"{s.describe()}.")
        linear0, params0 = start.linear, start.nonlinear
    else:
        try:
            linear0, params0 = start
        except (TypeError, ValueError):
            raise ParameterError("`start` must be an IdentificationResult or a pair "
                                 f"(linear, nonlinear) of parameter vectors; got {start!r}."
                                 ) from None
        linear0 = check_array(linear0, "start linear parameters")
        if linear0.shape[0] != s.n_linear:
            raise DimensionError(f"`start` linear parameters must have {s.n_linear} entries "
                                 f"({', '.join(s.linear_names)}); got {linear0.shape[0]}.")
        params0 = np.atleast_1d(np.asarray(params0, dtype=np.float64))
        if params0.shape[0] != s.n_nonlinear:
            raise DimensionError(f"`start` nonlinear parameters must have {s.n_nonlinear} "
                                 f"entries ({', '.join(s.nonlinear_names)}); got "
                                 f"{params0.shape[0]}.")
    for j, name in enumerate(s.orders.free):    # a result's orders too: never clipped silently
        check_scalar(params0[j], f"start {name}", lower=lower[j], upper=upper[j])
    J0 = float(np.mean((builder.y - builder.matrix(params0) @ linear0) ** 2))
    return np.array(linear0, dtype=float), np.array(params0, dtype=float), J0, "the given start"


def local_search(builder, linear0, params0, lower, upper, n_init, max_nfev, held=None):
    """One local search of the default chain (a task for an executor): :func:`fit_output_error`."""
    return fit_output_error(builder, linear0, params0, lower=lower, upper=upper, n_init=n_init,
                            max_nfev=max_nfev, held=held)


def held_columns(builder, params):
    """``(mask, factor)``: the linear parameters whose columns depend on the others, or None.

    The information matrix at ``params`` factorised by :func:`fohw._linalg.factor`; where it
    is rank deficient the columns it names dependent are held at their start values by the
    simulation-error search (:func:`fit_output_error`), which then runs over the rest instead
    of drifting along the null space. ``mask`` is None at full rank.
    """
    fac = _linalg.factor(builder.matrix(params), with_q=False)
    if fac.rank == fac.n_columns:
        return None, fac
    mask = np.zeros(fac.n_columns, dtype=bool)
    mask[list(fac.dependent)] = True
    return mask, fac


def _mid_params(structure, lower, upper):
    """The free orders in the middle of their bounds, the other nonlinear parameters 0."""
    return np.r_[(lower + upper) / 2, np.zeros(structure.n_nonlinear - len(structure.orders.free))]


class _Chain:
    """The default chain of one record (:func:`fohw.estimators.starts.multi_start`) and its costs."""

    def __init__(self, builder, options, executor):
        self.builder, self.options, self.executor = builder, options, executor
        self.n_simulations = 0          # scan, nested fits and the searches, all counted
        self.nested = {}                # structure -> (linear, params, sse) or None

    def criterion(self, structure):
        y, window = self.builder.y, slice(self.options.n_init, None)
        guard = 10.0 * float(np.max(np.abs(y)))

        def sse(linear, params):
            self.n_simulations += 1
            n = structure.n_linear
            x = np.r_[linear, params]
            try:
                r = (y - simulate_predictor(structure, x[:n], x[n:], self.builder.u,
                                            divergence_threshold=guard))[window]
            except SimulationDivergedError:
                return np.inf
            value = float(r @ r)
            return value if np.isfinite(value) else np.inf
        return sse

    def nested_fit(self, structure):
        """``(linear, params, sse)`` of the simulation-error fit of a contained class."""
        if structure not in self.nested:
            sub = RegressorBuilder(self.builder.u, self.builder.y, structure=structure)
            n_free = len(structure.orders.free)
            lo, hi = self.bounds
            bounds = (np.full(n_free, lo[0]), np.full(n_free, hi[0]))
            got = self.fit(sub, bounds)
            self.nested[structure] = None if got is None else (got[0].linear, got[0].params,
                                                               got[0].sse)
        return self.nested[structure]

    def fit(self, builder, bounds):
        """``(fit, start, searches, n_candidates)`` of one class.

        A rank-deficient class is searched with its dependent columns held
        (:func:`held_columns`), so every contained class is a start of the richer one.
        """
        options, s = self.options, builder.structure
        lower, upper = bounds
        if s.orders.free:
            self.bounds = bounds
            held, _ = held_columns(builder, _mid_params(s, lower, upper))

            def equation_error():
                vp = separable_least_squares(builder, bounds=bounds,
                                             options=VarproOptions(n_grid=options.n_grid))
                return vp.linear, vp.params

            chain = multi_start(builder, bounds, nested_fit=self.nested_fit,
                                equation_error=equation_error, criterion=self.criterion(s),
                                search=local_search,
                                search_args=(options.n_init, options.max_nfev, held),
                                n_starts=options.n_starts,
                                executor=self.executor if builder is self.builder else None)
            self.n_simulations += sum(f.nfev for _, f in chain.searches if f is not None)
            return chain.fit, chain.start, chain.searches, chain.n_candidates
        linear0, params0, _, origin = _start(builder, options, lower, upper)
        held, _ = held_columns(builder, params0)
        fit = fit_output_error(builder, linear0, params0, lower=lower, upper=upper,
                               n_init=options.n_init, max_nfev=options.max_nfev, held=held)
        self.n_simulations += fit.nfev
        return fit, Start(origin, linear0, params0, fit.start_sse), [], 1


def _advice(options, fit, structure):
    """What to try next, among what the user has not done already."""
    tips = []
    if fit.status == Status.MAX_ITER:
        tips.append(f"raise max_nfev (it was {options.max_nfev})")
    if options.start is None and structure.orders.free:
        tips.append(f"raise n_starts (it was {options.n_starts})")
    elif options.start is not None:
        tips.append("fit without `start` (the default chain of starts)")
    if structure.orders.free:
        tips.append("fix the orders (orders=0, or a number) to compare")
    return "; ".join(tips)


@thin_solves
def output_error_result(builder, options, bounds, *, operating_point=(0.0, 0.0), executor=None):
    """The default chain of starts (or a given start), then the simulation-error fit.

    ``options`` are checked (:meth:`OutputErrorOptions.check`). Without ``start``, a class
    with free orders is fitted from the best candidates of :func:`~fohw.estimators.starts.
    multi_start` (nested integer models, the equation-error estimate, a scan of the orders);
    ``executor`` runs its local searches.
    """
    s = builder.structure
    if s.output_map is not None:
        return series_result(builder, options, bounds, operating_point=operating_point,
                             executor=executor)
    check_enough_samples(builder.n_samples - options.n_init, s,
                         after=f" after n_init = {options.n_init}" if options.n_init else "")
    lower, upper = bounds
    record = dict(options.as_dict(), alpha_bounds=bounds_record(s, lower, upper))
    details = {} if options.start is None else {"start": "the given start"}
    # A start that is rank deficient (a duplicated basis function, two inputs moved together)
    # is never handed back as the estimate: its dependent columns are held and the
    # rest searched (held_columns), in the default chain as on a single start.
    if not np.any(builder.y):
        # The simulation-error minimum is known: the zero model simulates y = 0 exactly. It is
        # the estimate (not another method's), and the record identifies no parameter.
        details["simulation_sse"] = 0.0
        return finish(builder, method="output_error", linear=np.zeros(s.n_linear),
                      params=_mid_params(s, lower, upper), status=Status.RANK_DEFICIENT,
                      nit=0, nfev=0, options=record, details=details,
                      operating_point=operating_point,
                      message="the output is zero (after the operating point is removed): the "
                              "zero model (every coefficient 0) simulates it exactly, with "
                              "simulation error 0, and the record identifies no parameter.")
    held_note = ""
    if options.start is None and s.orders.free:
        chain = _Chain(builder, options, executor)
        fit, first, searches, n_candidates = chain.fit(builder, bounds)
        linear0, params0, origin = first.linear, first.params, first.name
        J0 = float(np.mean((builder.y - builder.matrix(params0) @ linear0) ** 2))
        nfev = chain.n_simulations
        done = [f.sse for _, f in searches if f is not None]
        agreed = agreement(done)
        details["starts"] = [
            {"start": c.name, "orders": dict(zip(s.orders.free, map(float, c.params))),
             "start_sse": c.sse, "sse": None if f is None else f.sse,
             "status": None if f is None else f.status.name,
             "nfev": None if f is None else f.nfev} for c, f in searches]
        details["n_starts_agreed"] = agreed
        integer = chain.nested.get(nested_structure(s, 0.0))
        if integer is not None:
            details["integer_sse"] = float(integer[2])
        chain_note = (f" Default chain: {n_candidates} candidate starts (nested integer models, "
                      f"the equation-error estimate, a scan of the orders), the best "
                      f"{len(searches)} searched; {agreed} of {len(done)} ended within "
                      f"{AGREEMENT_RTOL:g} of the best criterion; {nfev} simulations in all.")
    else:
        linear0, params0, J0, origin = _start(builder, options, lower, upper)
        held, _ = held_columns(builder, params0)
        fit = fit_output_error(builder, linear0, params0, lower=lower, upper=upper,
                               n_init=options.n_init, max_nfev=options.max_nfev, held=held)
        nfev, chain_note = fit.nfev, ""
    held, _ = held_columns(builder, _mid_params(s, lower, upper) if s.orders.free and
                           options.start is None else params0)
    if held is not None:
        names = [n for n, h in zip(s.linear_names, held) if h]
        joint = joint_levels_note(s, builder.u, operating_point[0])
        held_note = (f" The start is rank deficient on this record: {', '.join(names)} "
                     "depend on the other columns, so they were held at their start values "
                     "and the simulation error was minimised over the rest (a reduced class "
                     "that simulates every model the record can tell apart)."
                     + (f" Why: {joint}." if joint else ""))
    message = fit.message
    first = ", ".join(f"{n} = {v:.6g}" for n, v in zip(s.nonlinear_names, params0))
    message += (f" Started from {origin}" + (f" ({first})" if first else "")
                + (f", its output-feedback block shrunk by {fit.start_shrink:.3g} to make it "
                   "stable." if fit.start_shrink < 1 else "."))
    message += (f" Simulation error criterion from sample {options.n_init} on." + chain_note
                + held_note)
    for j, name in enumerate(s.orders.free):
        if fit.at_lower[j] or fit.at_upper[j]:
            message += bound_note(name, lower[j], upper[j], fit.at_lower[j], fit.at_upper[j],
                                  value=fit.params[j])
    if fit.status in (Status.MAX_ITER, Status.FAILED):
        tips = _advice(options, fit, s)
        if tips:
            message += f" To try: {tips}."
    details["simulation_sse"] = fit.sse
    Phi = builder.matrix(fit.params)
    J = float(np.mean((builder.y - Phi @ fit.linear) ** 2))
    alpha_history = [params0[0], fit.params[0]] if s.orders.free else None
    return finish(builder, method="output_error", linear=fit.linear, params=fit.params,
                  status=fit.status, nit=fit.nit, nfev=nfev, message=message,
                  alpha_at_bound=bool(np.any(fit.at_lower) or np.any(fit.at_upper)),
                  options=record, details=details, Phi=Phi, covariance=fit.covariance,
                  noise_variance=fit.noise_variance, alpha_history=alpha_history,
                  J_history=[J0, J] if alpha_history else None,
                  operating_point=operating_point)


class SeriesResidual:
    """The simulation-error residual of a structure with a series output map, exact Jacobian.

    ``x = (linear, inner nonlinear, h_*)``: the residual is ``(y - (h(z(x) + y0) - y0))`` on
    the criterion's samples, ``z`` the free run of :attr:`Structure.inner` (deviations) and
    ``y0`` the output's operating point (``h`` acts in the data's units). Its Jacobian is
    ``-[h'(z + y0) S_z, dh/dh_*]`` (:func:`~fohw.model.lagged.sensitivity.simulation_jacobian`). A run
    that escapes (``|z|`` beyond ``guard``, ten times the largest measured ``|y - y0|``) gets the
    constant residual ``2 guard`` and a zero Jacobian, as in :class:`SimulationResidual`.
    """

    def __init__(self, structure, u, y, n_init, y0):
        self.structure, self.u, self.y, self.y0 = structure, u, y, y0
        self.guard = 10.0 * float(np.max(np.abs(y)))
        self.window = slice(n_init, None)
        self.penalty = np.full(y.shape[0] - n_init, 2.0 * self.guard)
        self.n_simulations = 0
        self.n_jacobians = 0

    def model_output(self, x):
        """``h(z(x) + y0) - y0``; :class:`SimulationDivergedError` when ``z`` escapes."""
        self.n_simulations += 1
        n = self.structure.n_linear
        return simulate_predictor(self.structure, x[:n], x[n:], self.u,
                                  operating_point=(0.0, self.y0),
                                  divergence_threshold=self.guard) - self.y0

    def residual(self, x):
        """The residual on the criterion's samples, or the penalty."""
        try:
            r = (self.y - self.model_output(x))[self.window]
        except SimulationDivergedError:
            return self.penalty
        return r if np.all(np.isfinite(r)) else self.penalty

    def jacobian(self, x):
        """``d residual / dx``, exact (zeros where the residual is the penalty)."""
        self.n_jacobians += 1
        self.n_simulations += 1
        n = self.structure.n_linear
        try:
            ysim, G = simulation_jacobian(self.structure, x[:n], x[n:], self.u, y0=self.y0)
        except SimulationDivergedError:
            return np.zeros((self.penalty.shape[0], x.shape[0]))
        if not np.all(np.isfinite(G)) or np.max(np.abs(ysim)) > 10 * self.guard:
            return np.zeros((self.penalty.shape[0], x.shape[0]))
        return -G[self.window]


def fit_series(builder, linear0, params0, *, lower, upper, y0, n_init=0, max_nfev=None):
    """Fit a structure with a series output map by simulation error, from a start.

    ``builder``: the record (deviations) and the structure (with its map, resolved);
    ``linear0, params0``: the start (inner nonlinear parameters, then the map's); ``lower``,
    ``upper``: bounds of the free orders; ``y0``: the output's operating point. The map's
    ordered parameters are searched through
    :meth:`~fohw.model.output_map.SeriesMap.transform` (they never cross). The result never
    has a larger criterion than its start (else the start is returned).

    Returns
    -------
    _OEFit
    """
    s = builder.structure
    hmap, inner = s.output_map, s.inner
    u, y = builder.u, builder.y
    n_lin, n_free, n_eta = s.n_linear, len(s.orders.free), hmap.n_params
    n_in = n_lin + inner.n_nonlinear
    window = slice(n_init, None)
    m = y.shape[0] - n_init
    crit = SeriesResidual(s, u, y, n_init, y0)
    x0 = np.r_[np.asarray(linear0, dtype=np.float64), np.asarray(params0, dtype=np.float64)]
    y_data = y + y0
    T, w_lo, w_hi = hmap.transform(x0[n_in:], y_data)
    w0 = np.linalg.solve(T, x0[n_in:]) if n_eta else np.zeros(0)
    n_past = inner.n_nonlinear - n_free
    lo = np.r_[np.full(n_lin, -np.inf), lower, np.full(n_past, -np.inf), w_lo]
    hi = np.r_[np.full(n_lin, np.inf), upper, np.full(n_past, np.inf), w_hi]
    v0 = np.clip(np.r_[x0[:n_in], w0], lo, hi)

    def to_x(v):
        return np.r_[v[:n_in], T @ v[n_in:]]

    r0 = crit.residual(to_x(v0))
    sse0 = np.inf if r0 is crit.penalty else float(r0 @ r0)
    scale = np.r_[_parameter_scale(x0[:n_in], inner, u, y),
                  np.maximum(np.abs(w0), hmap.scale(y_data)) if n_eta else np.zeros(0)]
    y_scale = rms_scale(y)

    def residual(z):
        return crit.residual(to_x(z * scale)) / y_scale

    def jacobian(z):
        G = crit.jacobian(to_x(z * scale))
        return np.hstack([G[:, :n_in], G[:, n_in:] @ T]) * (scale / y_scale)

    keep = np.r_[kept_above_zero(inner, n_lin, lower), np.zeros(n_eta, dtype=bool)]
    zs, status, ls = bounded_least_squares(residual, v0 / scale, jac=jacobian, lower=lo / scale,
                                           upper=hi / scale, keep=keep, max_nfev=max_nfev)
    v = zs * scale
    x = to_x(v)
    r = crit.residual(x)
    sse = np.inf if r is crit.penalty else float(r @ r)
    fell_back = not sse <= sse0
    if fell_back and np.isfinite(sse0):       # never above the start (nested models: docs)
        v, x, sse = v0, to_x(v0), sse0
    escaped = not np.isfinite(sse)
    if escaped:
        status = Status.FAILED
    unidentified = ""
    try:
        _, G = simulation_jacobian(s, x[:n_lin], x[n_lin:], u, y0=y0)
        cov, s2 = parameter_covariance(G[window], sse, m)
        if cov is None and not escaped:
            # A limit outside the data's range (its column is 0), or a zone of width 0 beside
            # an offset: the record does not identify every parameter at the estimate.
            status = Status.RANK_DEFICIENT
            names = s.linear_names + s.nonlinear_names
            zero = [n for n, col in zip(names, G[window].T) if not np.any(col)]
            unidentified = (" Not identified at the estimate (singular information matrix): "
                            + (", ".join(zero) + " (no effect on the output)" if zero else
                               "dependent parameters") + "; a map's limits outside the "
                            "data's range, or a zone of width 0 beside an offset, do this")
    except SimulationDivergedError:
        cov, s2 = None, sse / max(m - x.shape[0], 1)
    active = ls.active_mask[n_lin:n_lin + n_free]
    message = (f"output-error fit with the series output map {hmap.describe()} "
               f"(scipy.optimize.least_squares): {ls.message} ({crit.n_simulations} "
               f"simulations, {crit.n_jacobians} of them with the exact sensitivity through h)")
    if escaped:
        message = ("output-error fit failed: the free run of the estimate and of its start "
                   f"escape (beyond ten times the largest measured |y|); {message}.")
    elif fell_back:
        message += ("; the search ended above its start's criterion, so the start is kept "
                    "(the fit never ends above the model it nests)")
    message += unidentified
    return _OEFit(linear=x[:n_lin].copy(), params=x[n_lin:].copy(), sse=sse, start_shrink=1.0,
                  status=status, message=message, covariance=cov, noise_variance=s2,
                  nit=int(ls.njev), nfev=crit.n_simulations,
                  at_lower=(active < 0) if not fell_back else np.zeros(n_free, dtype=bool),
                  at_upper=(active > 0) if not fell_back else np.zeros(n_free, dtype=bool),
                  start_sse=sse0)


def _series_start(builder, s, options, bounds, operating_point, executor):
    """``(linear0, params0, origin, identity)``: the fit without h, then h's start from the data.

    ``identity``: ``(sse, status name)`` of the fit without ``h`` (None for a given start).
    """
    start = options.start
    u, y0 = builder.u, operating_point[1]
    if isinstance(start, IdentificationResult) and start.structure == s:
        return start.linear, start.nonlinear, "the given start", None
    inner = s.inner
    inner_builder = RegressorBuilder(u, builder.y, structure=inner)
    with warnings.catch_warnings(record=True) as caught:    # said once, by the final fit
        warnings.simplefilter("always")
        got = output_error_result(inner_builder, options, bounds,
                                  operating_point=operating_point, executor=executor)
    del caught
    z = simulate_predictor(inner, got.linear, got.nonlinear, u) + y0
    eta0 = s.output_map.start(z, builder.y + y0)
    origin = ("the fit without the output map (h the identity"
              + (", limits at the measured output's range)" if s.output_map.kind == "saturation"
                 else ")"))
    identity = (float(got.details.get("simulation_sse", np.nan)), got.status.name)
    return got.linear, np.r_[got.nonlinear, eta0], origin, identity


def series_result(builder, options, bounds, *, operating_point=(0.0, 0.0), executor=None):
    """``method="output_error"`` for a structure with a series output map ``y = h(z)``.

    First the same structure without ``h`` (today's model, its default chain of starts), then
    ``h``'s parameters from the data (:meth:`~fohw.model.output_map.SeriesMap.start`: the
    identity, a saturation's limits at the measured output's range), then every parameter
    together by simulation error with the exact Jacobian through ``h`` (:func:`fit_series`).
    The series model therefore never ends with a larger criterion than the model without ``h``
    it contains (exactly for a saturation, whose start clip only moves ``z`` toward ``y``; to
    rounding for the other maps, whose start is the identity).
    """
    s = builder.structure
    y0 = operating_point[1]
    y_data = builder.y + y0
    hmap = s.output_map.resolve(y_data)
    hmap.check_data(y_data)
    if hmap is not s.output_map:
        s = s.with_output_map(hmap)
        builder = RegressorBuilder(builder.u, builder.y, structure=s)
    check_enough_samples(builder.n_samples - options.n_init, s,
                         after=f" after n_init = {options.n_init}" if options.n_init else "")
    lower, upper = bounds
    record = dict(options.as_dict(), alpha_bounds=bounds_record(s, lower, upper))
    linear0, params0, origin, identity = _series_start(builder, s, options, bounds,
                                                       operating_point, executor)
    fit = fit_series(builder, linear0, params0, lower=lower, upper=upper, y0=y0,
                     n_init=options.n_init, max_nfev=options.max_nfev)
    details = {"start": origin, "simulation_sse": fit.sse}
    message = fit.message + f". Started from {origin}"
    if identity is not None:
        details["identity_sse"] = identity[0]
        message += (f", whose simulation error sum of squares was {identity[0]:.6g} "
                    f"({identity[1]}); now {fit.sse:.6g}")
    message += f". Simulation error criterion from sample {options.n_init} on."
    n_free = len(s.orders.free)
    for j, name in enumerate(s.orders.free):
        if fit.at_lower[j] or fit.at_upper[j]:
            message += bound_note(name, lower[j], upper[j], fit.at_lower[j], fit.at_upper[j],
                                  value=fit.params[j])
    inner_params = fit.params[:fit.params.shape[0] - hmap.n_params]
    Phi = RegressorBuilder(builder.u, builder.y, structure=s.inner).matrix(inner_params)
    return finish(builder, method="output_error", linear=fit.linear, params=fit.params,
                  status=fit.status, nit=fit.nit, nfev=fit.nfev, message=message,
                  alpha_at_bound=bool(np.any(fit.at_lower[:n_free]) or np.any(fit.at_upper)),
                  options=record, details=details, Phi=Phi, covariance=fit.covariance,
                  noise_variance=fit.noise_variance, operating_point=operating_point)


#: ``method="output_error"`` as :func:`fohw.identify` dispatches it (every structure).
METHOD = Method("output_error", OutputErrorOptions, output_error_result, parallel=True,
                output_map=True)
