"""Fitting an equivalent circuit to a measured impedance spectrum, alone or with a time record.

Not in the paper: the frequency-domain counterpart of :func:`fohw.fit` for
:class:`fohw.EquivalentCircuit`. The circuit's impedance about zero current is
``Z(f) = R0 + sum_e Z_e(j 2 pi f)`` (:meth:`fohw.EquivalentCircuit.impedance`; with ``capacity``
the open-circuit voltage's capacitor ``(dOCV/dsoc + b) / (3600 Q s)`` is added). Both fits run on
the engine every fohw fit runs on: bounded nonlinear least squares
(:func:`fohw.estimators._common.bounded_least_squares`, trust-region reflective) from the best
points of a scan, the covariance ``s^2 (J^T J)^{-1}`` from the rank-revealing QR of
:mod:`fohw._linalg`, and the result a :class:`fohw.FitResult`.

The spectrum's residual (``weight="relative"``, the default) is the model's error relative to
the measured modulus, real and imaginary parts stacked:
``r = [Re(Z_model - Z) / |Z|, Im(Z_model - Z) / |Z|]`` ("modulus weighting", the usual choice for
impedance data, whose errors grow with ``|Z|``): every frequency counts by its relative error,
the quantity :func:`fohw.model.circuit.impedance_error` reports.

The joint fit (:func:`fit_record_and_impedance`) stacks the record's simulation error and the spectrum's
residual, each divided by its own noise level,
``r = [sqrt(w) (y - yhat) / sigma_time, r_spectrum / sigma_spectrum]``: the Gaussian likelihood of
two independent parts with their own variances. By default each ``sigma`` is the RMS residual
of that part's own fit (``sqrt(SSE / (n - p))``, from :func:`fohw.fit` and
:func:`fit_impedance` run first), so each part counts by its number of points, as in a
likelihood: a record of thousands of samples outweighs a spectrum of a few dozen frequencies
unless the spectrum fits far better than the record. Pass ``noise=(sigma_time, sigma_spectrum)``
to set them (e.g. multiply ``sigma_spectrum`` by ``sqrt(2 m / N)`` to give the two parts equal
total weight).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy  # submodules load on first use

from .. import _linalg
from .._threads import thin_solves
from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import ConvergenceWarning, ParameterError, RankDeficiencyWarning
from ..fit_result import FitResult
from ..model.circuit import EquivalentCircuit, check_spectrum, scan_combinations, unit_columns
from ..results import Status
from ._common import bounded_least_squares
from .fit import PENALTY, check_weight, data_digest, fit, free_jacobian, rank_rcond

__all__ = ["fit_impedance", "fit_record_and_impedance", "spectrum_residual", "WEIGHTS"]

#: The weightings of the spectrum's residual: ``"relative"`` (divided by ``|Z|``, default),
#: ``"unit"`` (ohms, unweighted); an array of one positive weight per frequency also works.
WEIGHTS = ("relative", "unit")


def _spectrum_weight(weight, z):
    if isinstance(weight, str):
        if weight not in WEIGHTS:
            raise ParameterError(f"`weight` must be one of {', '.join(map(repr, WEIGHTS))} or an "
                                 f"array of one positive weight per frequency; got {weight!r}.")
        return 1.0 / np.abs(z) if weight == "relative" else np.ones(z.size)
    w = check_array(weight, "weight")
    if w.shape != z.shape or np.any(w <= 0):
        raise ParameterError(f"`weight` given as an array must hold one positive weight per "
                             f"frequency ({z.size}); got shape {w.shape}, values from "
                             f"{w.min()!r} to {w.max()!r}.")
    return w


def spectrum_residual(model, f, z, w, *, discrete=False, capacity=None, ocv_slope=0.0):
    """``[w Re(Z_model - z), w Im(Z_model - z)]``: the spectrum's residual (length ``2 m``)."""
    zm = model.impedance(f, discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)
    d = (zm - z) * w
    return np.concatenate([d.real, d.imag])


def _enters(name, capacity):
    """Whether a circuit parameter enters the impedance (``a``, ``c3`` never; ``b`` with capacity)."""
    return name not in ("a", "c3") and (name != "b" or capacity is not None)


def _check_circuit(model):
    if not isinstance(model, EquivalentCircuit):
        raise ParameterError(f"`model` must be an EquivalentCircuit; got {type(model).__name__}.")


class _Problem:
    """The free parameters of a circuit and the residual blocks of a fit (spectrum, record)."""

    def __init__(self, model, params):
        self.model, self.params = model, params
        self.names = params.free_names
        self.lower, self.upper = params.free_bounds()
        self.tie = params.tie_matrix()

    def at(self, x):
        return self.model.with_parameters(self.params.with_free(np.clip(x, self.lower, self.upper)))

    def spectrum_jacobian(self, x, residual):
        """Central differences of ``residual(model)`` in the free parameters (one-sided at a bound).

        The impedance is a closed form evaluated at a few dozen frequencies: the differences cost
        nothing beside a simulation, and their step ``eps**(1/3) max(|x|, 1e-6)`` gives about
        ten accurate digits (the impedance is linear in the resistances, where ``x`` may be 0).
        """
        cols = []
        for j in range(x.size):
            step = np.finfo(float).eps ** (1 / 3) * max(abs(x[j]), 1e-6)
            hi = min(x[j] + step, self.upper[j])
            lo = max(x[j] - step, self.lower[j])
            xp, xm = x.copy(), x.copy()
            xp[j], xm[j] = hi, lo
            cols.append((residual(self.at(xp)) - residual(self.at(xm))) / (hi - lo))
        return np.column_stack(cols)


def _covariance(jac, sse, n, names, how):
    inverse, fac = _linalg.inverse_gram(jac, rcond=rank_rcond(how, *jac.shape))
    if inverse is None:
        cols = ", ".join(names[i] for i in fac.dependent)
        return None, (f"Rank deficient: rank {fac.rank} of {fac.n_columns}; the columns of {cols} "
                      "are linear combinations of the others, so those parameters are not "
                      "identifiable from these data (fix one of them).")
    return sse / max(n - len(names), 1) * inverse, None


def _finish(kind, status, messages, rank_note):
    where = f"fohw.estimators.impedance_fit.{kind}(EquivalentCircuit)"
    if rank_note:
        status = Status.RANK_DEFICIENT if status != Status.FAILED else status
        messages.append(rank_note)
        warnings.warn(f"{where}: {rank_note}", RankDeficiencyWarning, stacklevel=3)
    elif status in (Status.MAX_ITER, Status.FAILED):
        warnings.warn(f"{where}: {' '.join(messages[1:])}", ConvergenceWarning, stacklevel=3)
    return status, " ".join(messages)


def _scan_starts(model, params, f, z, w, keep, *, discrete, capacity, ocv_slope):
    """Grid starts for a spectrum: the elements' (tau, alpha) on a grid, linear parameters solved.

    The time constants are log-spaced over ``1 / (2 pi f)`` of the spectrum's band (inside their
    bounds), the orders as :meth:`EquivalentCircuit.starts` spaces them; ``R0``, the
    resistances (``sigma`` of a Warburg element) and, with ``capacity``, ``b`` enter the
    impedance linearly and are solved by least squares with the resistances ``>= 0``
    (:func:`scipy.optimize.lsq_linear`), fixed ones held.
    """
    kinds = model.kinds
    fixed = {n: p.value for n, p in params.items() if p.fixed or p.tie is not None}
    band = (1.0 / (2 * math.pi * f.max()), 1.0 / (2 * math.pi * f.min()))
    dt = model.dt if discrete else None
    grids = []
    for k, kind in enumerate(kinds, start=1):
        lo = hi = None
        if kind != "warburg":
            lo, hi = params[f"tau{k}"].bounds
            lo, hi = max(lo, band[0]), min(hi, band[1])
            if lo > hi:
                lo = hi = min(max(math.sqrt(band[0] * band[1]), params[f"tau{k}"].bounds[0]),
                              params[f"tau{k}"].bounds[1])
        grids.append(model.element_grid(k, params, fixed, (lo, hi)))
    # Linear columns: R0 (1), b (the capacitor's unit), each element's unit impedance.
    base_names, base_cols = ["R0"], [np.ones(f.size, dtype=complex)]
    offset = np.zeros(f.size, dtype=complex)
    if capacity is not None:
        # The capacitor alone: a circuit without elements, R0 = b = 0, OCV slope 1.
        unit = EquivalentCircuit((), dt=model.dt).impedance(f, discrete=discrete, capacity=capacity,
                                                           ocv_slope=1.0)
        base_names.append("b")
        base_cols.append(unit)
        offset = offset + ocv_slope * unit
    units = unit_columns(kinds, grids, lambda e: e.impedance(f, dt))
    names = base_names + [f"{'sigma' if kind == 'warburg' else 'R'}{e}"
                          for e, kind in enumerate(kinds, start=1)]
    found = []
    for combo in scan_combinations(kinds, grids, fixed):
        cols = base_cols + [units[(kinds[e], t, a)] for e, (t, a) in enumerate(combo)]
        target = z - offset
        free = []
        for n, c in zip(names, cols):
            if n in fixed:
                target = target - fixed[n] * c
            else:
                free.append((n, c))
        if not free:
            continue
        a = np.column_stack([c for _, c in free]) * w[:, None]
        a = np.vstack([a.real, a.imag])
        rhs = target * w
        rhs = np.concatenate([rhs.real, rhs.imag])
        lower = [0.0 if n != "b" else -np.inf for n, _ in free]
        sol = scipy.optimize.lsq_linear(a, rhs, bounds=(lower, np.inf))
        values = {n: max(float(v), 0.0) if lo == 0.0 else float(v)
                  for (n, _), v, lo in zip(free, sol.x, lower)}
        for e, (kind, (tau, alpha)) in enumerate(zip(kinds, combo), start=1):
            if kind != "warburg" and f"tau{e}" not in fixed:
                values[f"tau{e}"] = tau
            if kind != "rc" and f"alpha{e}" not in fixed:
                values[f"alpha{e}"] = alpha
        found.append((2.0 * float(sol.cost), values))
    found.sort(key=lambda t: t[0])
    return [model.with_parameters(params.with_values(v)) for _, v in found[:keep]]


def _orders_of(problem, ranked):
    """``FitResult.starts``: each ranked start's free orders and its sum of squares, best first."""
    orders = [(j, n) for j, n in enumerate(problem.names) if problem.params[n].order]
    return tuple(({n: float(x[j]) for j, n in orders}, sse) for sse, x in ranked)


def _refine(problem, candidates, residual, jacobian, n_starts, max_nfev, tol):
    """Rank the candidates by their residual, refine the best ``n_starts``; the best result."""
    ranked = []
    for m in candidates:
        x = m.parameters.free_values()
        if np.any(x < problem.lower) or np.any(x > problem.upper):
            continue
        try:
            with np.errstate(all="ignore"):
                r = residual(x)
        except (ArithmeticError, ParameterError):
            continue
        if np.all(np.isfinite(r)):
            ranked.append((float(r @ r), x))
    ranked.sort(key=lambda t: t[0])
    best = None
    for sse0, x0 in ranked[:n_starts]:
        x, status, ls = bounded_least_squares(residual, x0, jac=jacobian, lower=problem.lower,
                                              upper=problem.upper, ftol=tol, xtol=tol, gtol=tol,
                                              max_nfev=max_nfev)
        r = residual(x)
        sse = float(r @ r)
        if best is None or sse < best[0]:
            best = (sse, x, status, ls, sse0)
    return best, ranked


@thin_solves
def fit_impedance(model, f, z, *, weight="relative", discrete=False, capacity=None, ocv_slope=0.0,
                  start=None, n_starts=3, max_nfev=200, tol=1e-10):
    """Fit an :class:`fohw.EquivalentCircuit` to a measured impedance spectrum.

    Parameters
    ----------
    model : EquivalentCircuit
        The structure, its settings (fixed parameters, bounds) and a start.
    f : array_like, shape (m,)
        Frequencies [Hz], positive.
    z : array_like of complex, shape (m,)
        The measured impedance [ohm] (``Z = V / I``, positive real part for a cell).
    weight : {"relative", "unit"} or array_like, optional
        The residual's weighting (see the module's docstring): ``"relative"`` (default) divides
        by ``|z|``; ``"unit"`` leaves ohms; an array gives one positive weight per frequency.
    discrete : bool, optional
        Fit the impedance of the model discretised at its ``dt`` (default: the continuous one).
    capacity : float, optional
        The cell's capacity [Ah]: the open-circuit voltage's capacitor enters the model (and
        ``b`` with it); see :meth:`fohw.EquivalentCircuit.impedance`.
    ocv_slope : float, optional
        ``dOCV/dsoc`` [V] at the spectrum's state of charge (with ``capacity``).
    start : EquivalentCircuit or sequence, optional
        Further starts (the model's own values are always one).
    n_starts, max_nfev, tol : optional
        As :func:`fohw.fit`.

    Returns
    -------
    FitResult
        ``residuals`` are the weighted spectrum residuals ``[Re, Im]`` (length ``2 m``),
        ``sse`` their sum of squares, ``n_samples = 2 m``; ``options["data"] == "impedance"``.
        ``a`` and ``c3`` (and ``b`` without ``capacity``) do not enter the impedance: they are
        held at the model's values (fixed in the result's parameters; the message says so).
        The Jacobian is by central differences of the closed-form impedance.

    Notes
    -----
    Starts: the model's values (when its resistances are not all 0) and the best points of a
    scan of the elements' time constants over ``1 / (2 pi f)`` of the band and their orders,
    the parameters that enter linearly solved by bounded linear least squares; the best
    ``n_starts`` are refined by :func:`~fohw.estimators._common.bounded_least_squares`.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> from fohw.estimators.impedance_fit import fit_impedance
    >>> true = fohw.EquivalentCircuit([fohw.RC(0.004, 2.0), fohw.ZARC(0.01, 80.0, 0.55)], r0=0.02)
    >>> f = np.logspace(-3, 1, 30)
    >>> res = fit_impedance(fohw.EquivalentCircuit(["rc", "zarc"]), f, true.impedance(f))
    >>> {k: round(v, 6) for k, v in res.parameters.valuesdict().items() if k != "b"}
    {'a': 0.0, 'R0': 0.02, 'R1': 0.004, 'tau1': 2.0, 'R2': 0.01, 'tau2': 80.0, 'alpha2': 0.55}
    """
    _check_circuit(model)
    f, z = check_spectrum(f, z)
    w = _spectrum_weight(weight, z)
    n_starts = check_int(n_starts, "n_starts", minimum=1)
    max_nfev = check_int(max_nfev, "max_nfev", minimum=1)
    tol = check_scalar(tol, "tol", lower=np.finfo(float).eps, upper=1.0, upper_inclusive=False)
    held = [n for n in model.parameters.names if not _enters(n, capacity)
            and not model.parameters[n].fixed and model.parameters[n].tie is None]
    params = model.parameters
    for n in held:
        params = params.replace(n, fixed=True)
    problem = _Problem(model.with_parameters(params), params)
    if not problem.names:
        raise ParameterError("every parameter of the circuit that enters its impedance is fixed or "
                             "tied: nothing to fit.")
    if 2 * f.size <= len(problem.names):
        raise ParameterError(f"the spectrum has {f.size} frequencies (2 m = {2 * f.size} real "
                             f"equations) for {len(problem.names)} free parameters "
                             f"({', '.join(problem.names)}); need more equations than parameters.")
    options = dict(discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)

    def of_model(m):
        return spectrum_residual(m, f, z, w, **options)

    def residual(x):
        return of_model(problem.at(x))

    def jacobian(x):
        return problem.spectrum_jacobian(x, of_model)

    extra = [] if start is None else [start] if isinstance(start, EquivalentCircuit) else list(start)
    candidates = [problem.model] + [problem.model.with_parameters(params.with_values(
        s.parameters.valuesdict())) for s in extra]
    candidates += _scan_starts(problem.model, params, f, z, w, n_starts + 2, **options)
    best, ranked = _refine(problem, candidates, residual, jacobian, n_starts, max_nfev, tol)
    if best is None:
        raise ParameterError("no start of the circuit gave a finite impedance at these "
                             "frequencies; give a start (`start=`).")
    sse, x, status, ls, _ = best
    fitted = problem.at(x)
    jac = jacobian(x)
    r = residual(x)
    covariance, rank_note = _covariance(jac, sse, r.size, problem.names, "finite differences")
    messages = [f"impedance fit (scipy.optimize.least_squares): {ls.message}"]
    if held:
        names = " and ".join([", ".join(held[:-1]), held[-1]] if len(held) > 1 else held)
        messages.append(f"{names} {'do' if len(held) > 1 else 'does'} not enter the impedance: "
                        "held at the model's values.")
    if status == Status.MAX_ITER:
        messages.append(f"The search used its budget of {max_nfev} evaluations; raise `max_nfev`.")
    status, message = _finish("fit_impedance", status, messages, rank_note)
    return FitResult(model=fitted, parameters=fitted.parameters, covariance=covariance,
                     status=status, sse=sse, n_samples=r.size, message=message,
                     nfev=int(ls.nfev), jacobian="finite differences",
                     starts=_orders_of(problem, ranked), residuals=r,
                     data_digest=data_digest(f, np.concatenate([z.real, z.imag]), model.dt),
                     options=dict(data="impedance", n_starts=n_starts, max_nfev=max_nfev, tol=tol,
                                  weight=weight if isinstance(weight, str) else w.tolist(),
                                  **options))


@thin_solves
def fit_record_and_impedance(model, u, y, f, z, *, noise=None, sample_weight=None, weight="relative",
              discrete=False, capacity=None, ocv_slope=0.0, n_starts=3, max_nfev=200, tol=1e-10):
    """Fit an :class:`fohw.EquivalentCircuit` to a time record and an impedance spectrum at once.

    The stacked residual ``[sqrt(sample_weight) (y - yhat) / sigma_time,
    r_spectrum / sigma_spectrum]`` (``r_spectrum`` as :func:`fit_impedance` weights it) is
    minimised by bounded least squares, with the circuit's exact Jacobian for the record and
    central differences for the spectrum.

    Parameters
    ----------
    model : EquivalentCircuit
        The structure, its settings and a start.
    u, y : array_like
        The record: ``u = [current, soc]`` (N, 2), the terminal voltage ``y`` (N,).
    f, z : array_like
        The spectrum: frequencies [Hz] and complex impedance [ohm].
    noise : (float, float), optional
        ``(sigma_time [V], sigma_spectrum)``, the noise level of each part's residual (the
        spectrum's in the units of its weighting: relative by default). Default: each part's
        RMS residual ``sqrt(SSE / (n - p))`` from its own fit (:func:`fohw.fit` of the record,
        with ``order_grid=1`` since the circuit's own scan covers the orders, and
        :func:`fit_impedance` of the spectrum), run first.
    sample_weight : array_like, optional
        Weights of the record's squared errors, as in :func:`fohw.fit`.
    weight, discrete, capacity, ocv_slope : optional
        The spectrum's weighting and model, as in :func:`fit_impedance`.
    n_starts, max_nfev, tol : optional
        As :func:`fohw.fit`.

    Returns
    -------
    FitResult
        ``residuals`` is the stacked, scaled residual (``N`` record samples then ``2 m``
        spectrum values; ``n_samples`` counts both), ``sse`` its sum of squares (near
        ``n_samples - n_free`` when the noise levels are right); ``options`` holds the
        ``noise`` used, and ``options["separate"]`` the SSE of each part at the estimate.

    Notes
    -----
    Starts: the separate fits' estimates (the spectrum's with ``a``, ``b``, ``c3`` of the
    record's fit) and the model's values; the best ``n_starts`` by the joint criterion are
    refined. The weighting is the Gaussian likelihood of two independent parts, each with its
    own variance; see the module's docstring for what it implies and how to change it.
    """
    _check_circuit(model)
    f, z = check_spectrum(f, z)
    w = _spectrum_weight(weight, z)
    u = model.check_input(u)
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    sw = np.ones(y.size) if sample_weight is None else np.sqrt(check_weight(sample_weight, y))
    options = dict(discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)
    params = model.parameters
    if noise is not None:
        try:
            s_time, s_spec = (float(s) for s in noise)
        except (TypeError, ValueError):
            raise ParameterError(f"`noise` must be a pair (sigma_time, sigma_spectrum); got "
                                 f"{noise!r}.") from None
        if not (s_time > 0 and s_spec > 0 and math.isfinite(s_time) and math.isfinite(s_spec)):
            raise ParameterError(f"`noise` must hold two positive, finite noise levels; got "
                                 f"{noise!r}.")
    # The separate fits: the joint fit's starts, and the default noise levels. Their own
    # warnings are not the joint fit's business (its result has its own status).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", (ConvergenceWarning, RankDeficiencyWarning))
        time_fit = fit(model, u, y, sample_weight=sample_weight, order_grid=1, n_starts=n_starts,
                       max_nfev=max_nfev, tol=tol)
        spec_fit = fit_impedance(model, f, z, weight=weight, n_starts=n_starts,
                                 max_nfev=max_nfev, tol=tol, **options)
    if noise is None:
        s_time = math.sqrt(time_fit.sse / max(time_fit.n_samples - time_fit.n_free, 1))
        s_spec = math.sqrt(spec_fit.sse / max(spec_fit.n_samples - spec_fit.n_free, 1))
    problem = _Problem(model, params)
    n_used = int(np.count_nonzero(sw))
    if n_used + 2 * f.size <= len(problem.names):
        raise ParameterError(f"{n_used} samples and {f.size} frequencies are too few for "
                             f"{len(problem.names)} free parameters.")
    last = {}
    penalty = np.full(y.size + 2 * f.size, PENALTY * max(float(np.max(np.abs(y))), 1e-300) / s_time)

    def spec(m):
        return spectrum_residual(m, f, z, w, **options) / s_spec

    def residual(x):
        m = problem.at(x)
        try:
            with np.errstate(all="ignore"):
                yhat, jac = m.jacobian(u)
        except (ArithmeticError, ParameterError):
            return penalty
        last["x"], last["jac"] = np.array(x, dtype=float), jac
        return np.concatenate([sw * (y - yhat) / s_time, spec(m)])

    def jacobian(x):
        if "x" in last and np.array_equal(last["x"], x):
            jt = last["jac"] @ problem.tie
        else:
            jt = free_jacobian(problem.at(x), u)[1]
        jt = -(sw[:, None] * jt) / s_time
        return np.vstack([jt, problem.spectrum_jacobian(x, spec)])

    t_values = time_fit.parameters.valuesdict()
    mixed = {**spec_fit.parameters.valuesdict(),
             **{n: t_values[n] for n in ("a", "b", "c3") if n in t_values and not _enters(n, capacity)}}
    candidates = [model] + [model.with_parameters(params.with_values(v)) for v in (t_values, mixed)]
    best, ranked = _refine(problem, candidates, residual, jacobian, n_starts, max_nfev, tol)
    if best is None:
        raise ParameterError("no start of the circuit gave a finite joint residual.")
    sse, x, status, ls, _ = best
    fitted = problem.at(x)
    r = residual(x)
    jac = jacobian(x)
    n = n_used + 2 * f.size
    covariance, rank_note = _covariance(jac, sse, n, problem.names, "finite differences")
    t_part, s_part = r[:y.size], r[y.size:]
    rms_time = s_time * math.sqrt(float(t_part @ t_part) / n_used)
    rms_spec = s_spec * math.sqrt(float(s_part @ s_part) / (2 * f.size))
    messages = [f"joint record + spectrum fit (scipy.optimize.least_squares): {ls.message}",
                f"Noise levels: record {s_time:.4g} V, spectrum {s_spec:.4g}; at the estimate the "
                f"record's RMSE is {rms_time:.4g} V and the spectrum's RMS weighted error "
                f"{rms_spec:.4g}."]
    if status == Status.MAX_ITER:
        messages.append(f"The search used its budget of {max_nfev} evaluations; raise `max_nfev`.")
    status, message = _finish("fit_record_and_impedance", status, messages, rank_note)
    return FitResult(model=fitted, parameters=fitted.parameters, covariance=covariance,
                     status=status, sse=sse, n_samples=n, message=message, nfev=int(ls.nfev),
                     jacobian="exact (record), finite differences (spectrum)",
                     starts=_orders_of(problem, ranked), residuals=r,
                     data_digest=data_digest(u, np.concatenate([y, f, z.real, z.imag]), model.dt,
                                             sample_weight),
                     options=dict(data="record and impedance", noise=[s_time, s_spec],
                                  n_starts=n_starts, max_nfev=max_nfev, tol=tol,
                                  weight=weight if isinstance(weight, str) else w.tolist(),
                                  sample_weight=None if sample_weight is None else
                                  np.asarray(sample_weight, dtype=float).tolist(),
                                  separate={"time": float(t_part @ t_part) * s_time ** 2,
                                            "spectrum": float(s_part @ s_part) * s_spec ** 2},
                                  **options))

