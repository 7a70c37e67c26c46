"""Fitting an equivalent circuit to a measured impedance spectrum, alone or with a time record.

Not in the paper: the frequency-domain counterpart of :func:`fohw.fit` for
:class:`fohw.EquivalentCircuit`. The circuit's impedance about zero current is
``Z(f) = R0 + sum_e Z_e(j 2 pi f)`` (:meth:`fohw.EquivalentCircuit.impedance`; with ``capacity``
the open-circuit voltage's capacitor ``(dOCV/dsoc + b) / (3600 Q s)`` is added).
:func:`fit_impedance` is :func:`fohw.fit_frequency_response` for a circuit, run on the same
stages (:mod:`fohw.estimators.frequency_fit`: held parameters, ranking, bounded nonlinear least
squares by :func:`fohw.estimators._common.bounded_least_squares`, the covariance ``s^2 (J^T
J)^{-1}`` from the rank-revealing QR of :mod:`fohw._linalg`, the status, a
:class:`fohw.FitResult`) with the circuit's conventions: frequencies in Hz, the circuit's own
scan of time constants over the spectrum's band as starts, and refusals named after the
conventions a spectrum may come in (frequencies above the Nyquist frequency with
``discrete=True``; ``-Z``; ``conj(Z)``, the "-Im Z" of Nyquist plots, which no circuit of
capacitive elements can follow).

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
total weight). When a part's scaled squared error at the joint estimate is far beyond its
noise level (:data:`DISAGREE_P`), the two data do not describe one circuit, and the fit says
so (:class:`fohw.DataWarning`, with the ratio of the spectrum to the record's own fit's
impedance: a factor of 10 is a unit error).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy  # submodules load on first use

from .._threads import thin_solves
from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import ConvergenceWarning, DataWarning, ParameterError, RankDeficiencyWarning
from ..fit_result import FitResult
from ..model.circuit import EquivalentCircuit, check_spectrum, scan_combinations, unit_columns
from ..results import Status
from .fit import PENALTY, check_weight, data_digest, fit, free_jacobian
from .frequency_fit import (
    WEIGHTS,
    FrequencyProblem,
    check_equations,
    check_impedance_signs,
    covariance_of,
    finish,
    frequency_result,
    held_note,
    idle_parameters,
    rank_candidates,
    refine,
    response_weight,
    starts_table,
)

__all__ = ["fit_impedance", "fit_record_and_impedance", "spectrum_residual", "WEIGHTS"]

#: The tail probability below which the joint fit says its two parts disagree: a part whose
#: weighted squared error at the joint estimate exceeds the chi-squared quantile of its number
#: of values at this level (its noise level being its own fit's RMS residual).
DISAGREE_P = 1e-6


def spectrum_residual(model, f, z, w, *, discrete=False, capacity=None, ocv_slope=0.0):
    """``[w Re(Z_model - z), w Im(Z_model - z)]``: the spectrum's residual (length ``2 m``)."""
    zm = model.impedance(f, discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)
    d = (zm - z) * w
    return np.concatenate([d.real, d.imag])


def _check_circuit(model):
    if not isinstance(model, EquivalentCircuit):
        raise ParameterError(f"`model` must be an EquivalentCircuit; got {type(model).__name__}. "
                             "Other kinds with a frequency response: fohw.fit_frequency_response.")


def _check_conventions(model, f, z, discrete):
    """The circuit's conventions: no frequency above Nyquist when discrete, Z's signs (named)."""
    if discrete:
        nyquist = 0.5 / model.dt
        above = int(np.count_nonzero(f > nyquist))
        if above:
            raise ParameterError(
                f"`f` has {above} of its {f.size} frequencies above the Nyquist frequency "
                f"1 / (2 dt) = {nyquist:g} Hz of the circuit (dt = {model.dt!r} s; the highest is "
                f"{float(f.max()):g} Hz): with discrete=True the model is the sampled circuit, "
                "whose impedance repeats every 1 / dt Hz, so it cannot follow a spectrum measured "
                "beyond 1 / (2 dt). Drop those frequencies, fit the continuous impedance "
                "(discrete=False), or build the circuit with a smaller dt.")
    check_impedance_signs(z, capacitive=True)


def _enters(name, capacity):
    """Whether a circuit parameter enters the impedance (``a``, ``c3`` never; ``b`` with capacity)."""
    return name not in ("a", "c3") and (name != "b" or capacity is not None)


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
        The measured impedance [ohm] (``Z = V / I``: positive real part, negative imaginary
        part for a cell; a spectrum with Re z < 0 or Im z > 0 at more than half of its
        frequencies is refused, naming ``-Z`` or the "-Im Z" convention).
    weight : {"relative", "unit"} or array_like, optional
        The residual's weighting (see the module's docstring): ``"relative"`` (default) divides
        by ``|z|``; ``"unit"`` leaves ohms; an array gives one positive weight per frequency.
    discrete : bool, optional
        Fit the impedance of the model discretised at its ``dt`` (default: the continuous one);
        frequencies above the Nyquist frequency ``1 / (2 dt)`` are then refused.
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
    ``n_starts`` are refined by :func:`~fohw.estimators._common.bounded_least_squares`. The
    parameters held are those the impedance does not read
    (:func:`fohw.estimators.frequency_fit.idle_parameters`). The stages after the starts are
    :func:`fohw.fit_frequency_response`'s, which fits a circuit too (given ``omega = 2 pi f``)
    from its own starts (the order grid and the linear parameters solved) instead of the scan.

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
    _check_conventions(model, f, z, discrete)
    w = response_weight(weight, z)
    n_starts = check_int(n_starts, "n_starts", minimum=1)
    max_nfev = check_int(max_nfev, "max_nfev", minimum=1)
    tol = check_scalar(tol, "tol", lower=np.finfo(float).eps, upper=1.0, upper_inclusive=False)
    options = dict(discrete=discrete, capacity=capacity, ocv_slope=ocv_slope)

    def respond(m):
        return m.impedance(f, **options)

    held = idle_parameters(model, respond)
    params = model.parameters
    for n in held:
        params = params.replace(n, fixed=True)
    problem = FrequencyProblem(model.with_parameters(params), params, respond, z, w, step_floor=1e-6)
    check_equations(problem.names, f.size, "the circuit's impedance")
    extra = [] if start is None else [start] if isinstance(start, EquivalentCircuit) else list(start)
    candidates = [problem.model] + [problem.model.with_parameters(params.with_values(
        s.parameters.valuesdict())) for s in extra]
    candidates += _scan_starts(problem.model, params, f, z, w, n_starts + 2, **options)
    ranked = rank_candidates(problem, candidates, problem.residual)
    if not ranked:
        raise ParameterError("no start of the circuit gave a finite impedance at these "
                             "frequencies; give a start (`start=`).")
    best = refine(problem, ranked, problem.residual, problem.jacobian, n_starts, max_nfev, tol)
    return frequency_result(
        problem, best, ranked, label="impedance fit",
        caller="fohw.estimators.impedance_fit.fit_impedance",
        held_note=held_note(held, "the impedance"),
        max_nfev=max_nfev, digest=data_digest(f, np.concatenate([z.real, z.imag]), model.dt),
        options=dict(data="impedance", n_starts=n_starts, max_nfev=max_nfev, tol=tol,
                     weight=weight if isinstance(weight, str) else w.tolist(), **options))


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

    Raises
    ------
    ParameterError
        As :func:`fit_impedance` for the spectrum (its conventions included), and
        :func:`fohw.fit` for the record; bad noise levels.

    Warns
    -----
    DataWarning
        The record and the spectrum disagree: at the joint estimate a part's scaled squared
        error is beyond the chi-squared tail :data:`DISAGREE_P` of its number of values and its
        RMS error more than 1.5 times its noise level (the message gives the ratio of ``|z|``
        to the impedance of the record's own fit).

    Notes
    -----
    Starts: the separate fits' estimates (the spectrum's with ``a``, ``b``, ``c3`` of the
    record's fit) and the model's values; the best ``n_starts`` by the joint criterion are
    refined. The weighting is the Gaussian likelihood of two independent parts, each with its
    own variance; see the module's docstring for what it implies and how to change it.
    """
    _check_circuit(model)
    f, z = check_spectrum(f, z)
    _check_conventions(model, f, z, discrete)
    w = response_weight(weight, z)
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
    problem = FrequencyProblem(model, params, lambda m: m.impedance(f, **options), z, w,
                               step_floor=1e-6)
    tie = params.tie_matrix()
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
            jt = last["jac"] @ tie
        else:
            jt = free_jacobian(problem.at(x), u)[1]
        jt = -(sw[:, None] * jt) / s_time
        return np.vstack([jt, problem.jacobian_of(x, spec)])

    t_values = time_fit.parameters.valuesdict()
    mixed = {**spec_fit.parameters.valuesdict(),
             **{n: t_values[n] for n in ("a", "b", "c3") if n in t_values and not _enters(n, capacity)}}
    candidates = [model] + [model.with_parameters(params.with_values(v)) for v in (t_values, mixed)]
    ranked = rank_candidates(problem, candidates, residual)
    if not ranked:
        raise ParameterError("no start of the circuit gave a finite joint residual.")
    best = refine(problem, ranked, residual, jacobian, n_starts, max_nfev, tol)
    sse, x, status, ls, _ = best
    fitted = problem.at(x)
    r = residual(x)
    jac = jacobian(x)
    n = n_used + 2 * f.size
    covariance, rank_note = covariance_of(jac, sse, n, problem.names)
    t_part, s_part = r[:y.size], r[y.size:]
    rms_time = s_time * math.sqrt(float(t_part @ t_part) / n_used)
    rms_spec = s_spec * math.sqrt(float(s_part @ s_part) / (2 * f.size))
    messages = [f"joint record + spectrum fit (scipy.optimize.least_squares): {ls.message}",
                f"Noise levels: record {s_time:.4g} V, spectrum {s_spec:.4g}; at the estimate the "
                f"record's RMSE is {rms_time:.4g} V and the spectrum's RMS weighted error "
                f"{rms_spec:.4g}."]
    if status == Status.MAX_ITER:
        messages.append(f"The search used its budget of {max_nfev} evaluations; raise `max_nfev`.")
    disagree = _disagreement(t_part, s_part, n_used, time_fit, f, z, options)
    if disagree:
        messages.append(disagree)
        warnings.warn(f"fohw.estimators.impedance_fit.fit_record_and_impedance: {disagree}",
                      DataWarning, stacklevel=3)
    status, message = finish("fohw.estimators.impedance_fit.fit_record_and_impedance(EquivalentCircuit)",
                             status, messages, rank_note, stacklevel=3)
    return FitResult(model=fitted, parameters=fitted.parameters, covariance=covariance,
                     status=status, sse=sse, n_samples=n, message=message, nfev=int(ls.nfev),
                     jacobian="exact (record), finite differences (spectrum)",
                     starts=starts_table(problem, ranked), residuals=r,
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



def _disagreement(t_part, s_part, n_used, time_fit, f, z, options):
    """A sentence when the record and the spectrum disagree at the joint estimate, else None.

    Each part's scaled squared error at the joint estimate (its residual divided by its noise
    level) is referred to the chi-squared distribution of its number of values: beyond its
    :data:`DISAGREE_P` tail, and with the part's RMS error more than 1.5 times its noise level
    (so that noise levels at rounding, from exact data, do not count), the two data sets do not
    describe one circuit (or a noise level is far too small). The sentence gives the median of
    ``|z|`` over the impedance of the record's own fit: a factor of 10 is a unit or scale error.
    """
    parts = []
    for name, r, n in (("record", t_part, n_used), ("spectrum", s_part, s_part.size)):
        ss = float(r @ r)
        if ss > scipy.stats.chi2.isf(DISAGREE_P, n) and ss > 1.5 ** 2 * n:
            parts.append(f"the {name}'s RMS error is {math.sqrt(ss / n):.3g} times its noise level")
    if not parts:
        return None
    ratio = float(np.median(np.abs(z) / np.abs(time_fit.model.impedance(f, **options))))
    return (f"The record and the spectrum disagree: at the joint estimate {' and '.join(parts)} "
            f"(chi-squared tail below {DISAGREE_P:g}), so no one circuit fits both, or a noise "
            f"level is far too small. |z| is on median {ratio:.3g} times the impedance of the "
            "record's own fit at these frequencies (a factor such as 10 or 1000 is a scale or "
            "unit error). Fit each part alone to see which one the model follows.")
