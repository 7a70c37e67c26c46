"""What every estimator does at the end of a run: checks, warnings and the result object."""

from __future__ import annotations

import warnings

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .. import _linalg
from .._plausible import free_run_problem
from ..exceptions import (
    ConvergenceWarning,
    DimensionError,
    EstimationDivergedError,
    ParameterError,
    RankDeficiencyWarning,
    SimulationDivergedError,
)
from ..model.lagged.simulation import simulate_predictor
from ..results import IdentificationResult, Status, recover_model

__all__: list[str] = []


def rms_scale(x):
    """The RMS of a signal, or 1 for a zero signal: a scale for residuals and parameters.

    Where ``x * x`` overflows (data of size 1e200) or underflows to 0 (1e-170) it is computed
    as ``m * rms(x / m)`` with ``m = max|x|``.
    """
    with np.errstate(over="ignore", under="ignore"):
        value = float(np.sqrt(np.mean(x * x)))
    if not 0 < value < np.inf:
        m = float(np.max(np.abs(x))) if np.size(x) else 0.0
        if not 0 < m < np.inf:
            return 1.0
        value = m * float(np.sqrt(np.mean(np.square(x / m))))
    return value


#: A parameter whose natural size (:func:`natural_sizes`) is within ``2**±WORKING_RANGE`` of 1
#: is searched as it is; one beyond is searched in units of its size (a power of 2), so that
#: the solver's tolerance on the steps (relative to ``||x||``) means the same in every unit.
WORKING_RANGE = 20
#: Natural sizes beyond ``2**±REPRESENTABLE`` (about 1e±301) leave too little room (1e7) for
#: the estimates themselves and the products the estimators form: the units are refused.
REPRESENTABLE = 1000
#: Variances are squares of the sizes: beyond ``2**±VARIANCE_RANGE`` (1e±150) they are not
#: doubles, and the covariance is left out.
VARIANCE_RANGE = 500


def natural_sizes(builder):
    """``log2`` of each parameter's natural size: linear (theta, offset), orders, past levels.

    A theta entry multiplies a regressor made from one basis signal; its size is that of ``y``
    over that signal's (RMS over the record: the units, not the estimate). The offset is in
    the units of ``y``, the orders have none, the past levels those of ``u`` and ``y``.
    Rescaling ``u`` and ``y`` moves these and nothing else.
    """
    s = builder.structure
    log_y = np.log2(rms_scale(builder.y))
    n_g = len(s.g_basis)
    out = []
    for i, row in enumerate(builder.signals):
        terms = (s.orders.output if i < n_g else
                 s.orders.input_terms(builder.signal_inputs[i - n_g]))
        out += [log_y - np.log2(rms_scale(row))] * len(terms)
    if s.offset:
        out.append(log_y)
    out += [0.0] * len(s.orders.free)
    if s.past == "estimate":
        out += [np.log2(rms_scale(builder.u)), log_y]
    return np.array(out, dtype=float)


def working_scale(log_sizes):
    """Powers of 2 near the natural sizes beyond ``2**±WORKING_RANGE``, 1 elsewhere."""
    log_sizes = np.asarray(log_sizes, dtype=float)
    return np.where(np.abs(log_sizes) > WORKING_RANGE, np.exp2(np.round(log_sizes)), 1.0)


def check_units(builder):
    """Refuse data whose units put a parameter beyond what doubles can hold, naming it.

    Raises
    ------
    ParameterError
        A parameter's natural size (:func:`natural_sizes`) is beyond ``2**±REPRESENTABLE``.
    """
    s = builder.structure
    names = s.linear_names + s.nonlinear_names
    for name, size in zip(names, natural_sizes(builder)):
        if abs(size) > REPRESENTABLE:
            raise ParameterError(
                f"in the units of the data the parameter {name!r} would be about "
                f"1e{size * np.log10(2.0):+.0f} (the RMS of `y` over that of its regressor), "
                "beyond the range doubles hold with room for the products the estimators "
                "form (1e±301). Rescale `u` and `y` (e.g. to an RMS near 1): fohw's estimates "
                "rescale with the data.")


def scaled_problem(residual, jacobian, x0, lower, upper, scale):
    """``residual``, ``jacobian``, start and bounds in ``z = x / scale`` (``scale``: powers of 2).

    With every scale 1 the functions are returned as they are (the same numbers as before).
    """
    if np.all(scale == 1.0):
        return residual, jacobian, x0, lower, upper

    def res(z):
        return residual(z * scale)

    def jac(z):
        return jacobian(z * scale) * scale

    return res, jac, None if x0 is None else x0 / scale, lower / scale, upper / scale


def kept_above_zero(structure, n_linear, lower):
    """Mask of the entries of ``(linear..., params)`` never put on a lower bound of 0.

    With estimated past levels the model jumps at an order of exactly 0: a term of order 0
    sees the level itself before ``k = 0`` (``S_inf(0) = 1``), a term of order ``nu > 0``
    forgets it entirely (``S_inf(nu) = 0``) however small ``nu`` is, and its partial sums
    ``S_t(nu) ~ t**-nu`` are still about 1 over any record. A solver that stops just above 0
    has fitted the limit ``nu -> 0+``, a different model from ``nu = 0``: its order stays
    where the solver evaluated it. ``lower`` are the bounds of the free orders.
    """
    mask = np.zeros(n_linear + structure.n_nonlinear, dtype=bool)
    if structure.past == "estimate":
        n_free = len(structure.orders.free)
        mask[n_linear:n_linear + n_free] = np.asarray(lower, dtype=float) == 0.0
    return mask


def bounded_least_squares(residual, x0, *, jac, lower, upper, keep=None, **options):
    """Bounded nonlinear least squares as every fohw estimator runs it.

    :func:`scipy.optimize.least_squares` (trust-region reflective, ``x_scale="jac"``) from
    ``x0`` clipped into the bounds; the entries the solver reports on an active bound are put
    on it (it stops about 1e-10 inside; not those in ``keep``), and its status is mapped to
    :class:`fohw.Status`.
    Used by varpro's polish, ``"structured"`` and ``"output_error"``.

    Parameters
    ----------
    residual : callable
        ``x -> r(x)``.
    x0 : ndarray
        Start.
    jac : callable or str
        The Jacobian of ``residual``, or a finite-difference scheme (``"2-point"``).
    lower, upper : ndarray
        Bounds of every entry of ``x`` (``-inf``/``inf`` for unbounded ones).
    keep : ndarray of bool, optional
        Entries left where the solver evaluated them even when active on their lower bound
        (:func:`kept_above_zero`: the model is not continuous there).
    **options
        ``ftol``, ``xtol``, ``gtol``, ``max_nfev`` of :func:`scipy.optimize.least_squares`.

    Returns
    -------
    x : ndarray
        The solution, active entries on their bound.
    status : Status
        ``CONVERGED`` (a tolerance was met), ``MAX_ITER`` (``max_nfev`` reached) or ``FAILED``.
    ls : scipy.optimize.OptimizeResult
        The solver's result (``fun``, ``jac``, ``nfev``, ``njev``, ``active_mask``, ``message``).
    """
    ls = scipy.optimize.least_squares(residual, np.clip(x0, lower, upper), jac=jac,
                                      method="trf", bounds=(lower, upper), x_scale="jac",
                                      **options)
    at_lower = ls.active_mask < 0
    if keep is not None:
        at_lower = at_lower & ~keep
    x = np.where(at_lower, lower, np.where(ls.active_mask > 0, upper, ls.x))
    return x, solver_status(ls), ls


def solver_status(ls):
    """:class:`fohw.Status` of a :func:`scipy.optimize.least_squares` result."""
    return (Status.CONVERGED if ls.status > 0 else Status.MAX_ITER if ls.status == 0 else
            Status.FAILED)


def check_enough_samples(n_equations, structure, *, after=""):
    """Least squares needs more equations than parameters: a DimensionError naming both.

    Called by every least-squares entry (varpro on the record; output_error on the part its
    criterion covers, ``after`` naming what was left out), so a short record is refused before
    any solve, never a singular matrix or a division by ``N - d = 0`` later.
    """
    n_params = structure.n_linear + structure.n_nonlinear
    if n_equations <= n_params:
        raise DimensionError(
            f"least squares needs more samples than parameters: the record has {n_equations} "
            f"samples{after} for {n_params} parameters ({structure.n_linear} linear, "
            f"{structure.n_nonlinear} nonlinear: orders, levels); use a longer record, or fewer "
            "lags or basis functions.")


def dependent_columns_note(fac, names):
    """A sentence naming the columns a rank-revealing factorisation found dependent."""
    cols = [names[i] for i in fac.dependent]
    return (f"rank deficient: rank {fac.rank} of {fac.n_columns}; the columns of "
            f"{', '.join(cols)} are linear combinations of the others, so those parameters are "
            "not identifiable from this record (remove a basis function or a lag, or use a "
            "richer input).")


def check_finite_estimate(method, theta, alpha, where=""):
    """Raise :class:`EstimationDivergedError` unless the estimates are finite."""
    if not (np.all(np.isfinite(theta)) and np.all(np.isfinite(alpha))):
        raise EstimationDivergedError(
            f"fohw.identify({method!r}): the estimates became non-finite{where} (theta or alpha "
            "overflowed), so there is no estimate. The data may be badly scaled (max |y| is "
            "what enters the regressors through the output basis) or the method's gain too "
            "large; rescale the data or use method='varpro'.")


def finish(builder, *, method, linear, params, status, nit, nfev, message, alpha_at_bound=False,
           schedule="", options=None, Phi=None, rank_factor=None, covariance=None,
           noise_variance=None, theta_history=None, alpha_sample_history=None,
           alpha_history=None, J_history=None, alpha_profile=None, details=None,
           operating_point=(0.0, 0.0), stacklevel=5):
    """Check an estimate, say what the user must know, and wrap it as an IdentificationResult.

    ``linear`` are the linear parameters of the builder's structure (theta, then the offset)
    and ``params`` its nonlinear ones (the free orders, then the past levels). The one-step
    criterion ``J`` (Eq. 41) is computed here at the final estimate; a rank-deficient
    information matrix (``rank_factor``, or a factorisation of ``Phi`` made here) turns the
    status into ``RANK_DEFICIENT`` with a :class:`RankDeficiencyWarning` naming the dependent
    columns; a run that did not converge warns :class:`ConvergenceWarning`, and so does an
    estimate whose free run on its own estimation input is absurd
    (:func:`own_free_run_problem`): its status is then ``IMPLAUSIBLE``, whatever the method.

    ``options`` are the run's settings; the histories, the profile and ``details`` (other
    method-specific outputs: ``simulation_sse``, ``start``) go to the result's ``details``.
    A history that only repeats the final estimate (``alpha_history == [alpha]``,
    ``J_history == [J]``) is not stored: the result derives it.
    """
    structure = builder.structure
    linear = np.asarray(linear, dtype=np.float64)
    params = np.atleast_1d(np.asarray(params, dtype=np.float64))
    check_finite_estimate(method, linear, params)
    if Phi is None:
        Phi = builder.matrix(params)
    J = float(np.mean((builder.y - Phi @ linear) ** 2))
    if not np.isfinite(J):
        raise EstimationDivergedError(
            f"fohw.identify({method!r}): the mean squared one-step error J overflows (max |y| = "
            f"{np.max(np.abs(builder.y)):.3g}, max |Phi| = {np.max(np.abs(Phi)):.3g}): the data "
            "are too large for floating point once squared or passed through the basis "
            "functions; rescale u and y (the estimates rescale with them).")
    if covariance is not None:
        sizes = natural_sizes(builder)
        if np.any(np.abs(sizes) > VARIANCE_RANGE) or not np.all(np.isfinite(covariance)):
            covariance = None
            message += (" No standard errors: in the units of the data the variances of "
                        "some parameters are beyond the range of doubles (rescale u and y, "
                        "e.g. to an RMS near 1, to have them).")
    absurd = own_free_run_problem(builder, linear, params, operating_point)
    if rank_factor is None:
        rank_factor = _linalg.factor(Phi, with_q=False)
    if rank_factor.rank < rank_factor.n_columns:
        status = Status.RANK_DEFICIENT
        names = structure.linear_names
        if rank_factor.n_columns > len(names):          # a Jacobian: then the nonlinear ones
            names = names + structure.nonlinear_names
        note = dependent_columns_note(rank_factor, names)
        message = f"{message} {note[0].upper()}{note[1:]}"
        covariance = noise_variance = None
        warnings.warn(f"fohw.identify({method!r}): {note}", RankDeficiencyWarning,
                      stacklevel=stacklevel)
    if absurd:                         # never CONVERGED: a model absurd on its own data
        status = Status.IMPLAUSIBLE
        message = f"{message} {absurd}"
    if status in (Status.MAX_ITER, Status.FAILED, Status.IMPLAUSIBLE):
        warnings.warn(f"fohw.identify({method!r}" + (f", schedule={schedule!r}" if schedule else "")
                      + f"): {message}", ConvergenceWarning, stacklevel=stacklevel)
    n_theta = structure.layout.n_params
    theta, offset = linear[:n_theta], (float(linear[n_theta]) if structure.offset else 0.0)
    orders, past = structure.split_nonlinear(params)
    alpha = next(iter(orders.values()), None)
    _, note = recover_model(structure, theta, orders, offset=offset, past=past,
                            operating_point=operating_point)
    histories = dict(theta_history=theta_history, alpha_sample_history=alpha_sample_history,
                     alpha_history=alpha_history, J_history=J_history, alpha_profile=alpha_profile)
    out = {}
    for key, value in histories.items():
        if value is not None:
            out[key] = np.array(value, dtype=float)
            out[key].setflags(write=False)
    derived = {"alpha_history": [] if alpha is None else [alpha], "J_history": [J]}
    for key, value in derived.items():       # a history that only repeats the estimate
        if key in out and np.array_equal(out[key], value):
            del out[key]
    out.update(details or {})
    return IdentificationResult(
        method=method, schedule=schedule, structure=structure, theta=theta, orders=orders,
        offset=offset, past=past, operating_point=operating_point, J=J, status=status,
        nit=int(nit), nfev=int(nfev), message=message + note,
        alpha_at_bound=bool(alpha_at_bound), n_samples=builder.n_samples,
        options=dict(options or {}), covariance=covariance, noise_variance=noise_variance,
        details=out, output_map_params=({} if structure.output_map is None else dict(zip(
            structure.output_map.names, structure.output_map_params(params).tolist()))))


def own_free_run_problem(builder, linear, params, operating_point=(0.0, 0.0)):
    """Why the fitted predictor's free run on its own estimation input is absurd, or "".

    The run from the fit's own initial state (the estimated levels of ``past="estimate"``,
    else rest) and, for ``past="estimate"``, also from rest (the levels at the operating
    point: a model that explodes from there is unstable): each must stay finite and inside
    the envelope :func:`fohw.compare` uses (:func:`fohw._plausible.free_run_problem`), judged
    against the measured output. The sentence names the sample.
    """
    s = builder.structure
    runs = [("", np.asarray(params, dtype=float))]
    if s.past == "estimate":
        rest = runs[0][1].copy()
        n_free = len(s.orders.free)
        rest[n_free:n_free + 2] = 0.0
        runs.append((" (from rest: the past levels at the operating point, not the fitted "
                     "ones)", rest))
    y0 = float(operating_point[1]) if s.output_map is not None else 0.0
    for what, p in runs:
        try:
            with np.errstate(all="ignore"):
                if s.output_map is None:
                    ysim = simulate_predictor(s, linear, p, builder.u)
                else:
                    ysim = simulate_predictor(s, linear, p, builder.u,
                                              operating_point=(0.0, y0)) - y0
        except SimulationDivergedError as exc:
            return (f"The fitted model's free run on its own estimation input{what} diverges: "
                    f"{exc}")
        why = free_run_problem(ysim, builder.y)
        if why:
            return why.replace("estimation input", "estimation input" + what, 1)
    return ""


def joint_levels_note(structure, u, u0=0.0):
    """Why the input maps are not identified on the joint levels ``u`` visits ("" if they are).

    The rows of ``u`` (one per sample: every input at once) take ``L`` distinct values, the
    *joint* levels; the input bases of all inputs together have ``M`` columns. Evaluated on
    the levels they form an ``L x M`` matrix; where its rank is below ``M`` a combination of
    the input maps is zero at every sample (every lag, every order): not identified whatever
    the dynamics. With a constant beside them (an offset, or the static gain of order-0
    terms) the test is the rank of ``[1, F]``. Two inputs each at four levels can visit only
    four joint levels (moved together), which a per-input count does not see. ``u`` are the
    deviations the model sees (from the operating point ``u0``, added back to show the levels
    in the data's units).
    """
    u = np.asarray(u, dtype=float)
    rows = u.reshape(u.shape[0], -1)
    levels = np.unique(rows, axis=0)
    n_levels = levels.shape[0]
    f_basis = structure.f_basis
    m = len(f_basis)
    if n_levels > 4 * m + 8:               # far more levels than columns: full rank in practice
        return ""
    with np.errstate(all="ignore"):
        F = np.asarray(f_basis.evaluate(levels if u.ndim == 2 else levels[:, 0]), float).T
    if not np.all(np.isfinite(F)):
        return ""
    data = levels + np.broadcast_to(np.asarray(u0, dtype=float).ravel(), levels.shape[1:])
    shown = ", ".join("(" + ", ".join(f"{v:.4g}" for v in row) + ")" if row.size > 1
                      else f"{row[0]:.4g}" for row in data[:6]) + (", …" if n_levels > 6 else "")
    what = "joint levels of the inputs" if rows.shape[1] > 1 else "levels of the input"
    rank = int(np.linalg.matrix_rank(F)) if n_levels else 0
    n_cols, extra = m, ""
    if rank == m:
        rank = int(np.linalg.matrix_rank(np.c_[np.ones(n_levels), F]))
        if rank > m:
            return ""
        n_cols, extra = m + 1, " and a constant (an offset, or the static gain of order-0 terms)"
    return (f"the record visits only {n_levels} {what} ({shown}), on which the input maps' "
            f"{m} columns ({', '.join(f_basis.names)}){extra} have rank {rank} of {n_cols}: a "
            "combination of them takes the same value at every sample, so it is not identified "
            f"whatever the dynamics (use input bases of fewer columns in all, or a record "
            "whose inputs visit more joint levels)")


def bound_note(name, lo, hi, at_lower, at_upper, value=None):
    """Advice when a free order ends at the edge of its bounds, advice that can be followed.

    ``value``: the order where it ended when it was kept just above a lower bound of 0
    (:func:`kept_above_zero`).
    """
    if at_lower and lo == 0.0 and value is not None and value != 0.0:
        return (f" {name} ended at {value:.3g}, on the lower bound 0 as far as the solver can "
                "go: with estimated past levels order 0 is another model (a term of order 0 "
                "keeps the past level, one of any order above 0 forgets it), so the order "
                "stays where the fit was evaluated. orders='mixed' keeps order-0 terms "
                "beside the fractional ones.")
    if at_lower and lo == 0.0:
        return (f" {name} ended at the lower bound 0: the data favour integer-order (memoryless) "
                "terms. The commensurate model has no static gain for an order > 0, so records "
                "with a static response drive it to 0; orders='mixed' keeps order-0 terms "
                "beside the fractional ones.")
    if at_upper and hi == 2.0:
        return f" {name} ended at the upper bound 2, the largest order fohw's models allow."
    side = "lower" if at_lower else "upper"
    limit = "0" if at_lower else "2"
    return (f" {name} ended at the {side} bound of alpha_bounds = ({lo:g}, {hi:g}); widen that "
            f"bound (towards {limit}, the widest fohw allows) if the order may lie beyond it.")


def paper_model_only(structure):
    """``supports`` of the recursive methods: the paper's commensurate model (Eq. 16) only."""
    if structure.is_paper_model:
        return None
    if structure.n_inputs > 1:
        return (f"implements the paper's single-input model; `u` has {structure.n_inputs} "
                f"columns (inputs {', '.join(structure.inputs)}). Use method='varpro', "
                "'structured' or 'output_error' for several inputs.")
    return ("implements the paper's commensurate model (Eq. 16: one order for every term, no "
            f"offset, rest before k = 0, dt = 1); this structure is {structure.describe()}. Use "
            "method='varpro', 'structured' or 'output_error' for it.")


def bounds_record(structure, lo, hi):
    """``alpha_bounds`` as given back in the result: a pair, or one pair per free order."""
    if len(set(zip(lo.tolist(), hi.tolist()))) <= 1 and lo.size:
        return (float(lo[0]), float(hi[0]))
    return {name: (float(a), float(b)) for name, a, b in zip(structure.orders.free, lo, hi)}


def stationary(jac, r, x, lower, upper, rtol=1e-6):
    """Whether ``x`` is a stationary point of ``||r||^2`` within its bounds (Gauss–Newton).

    The reduction a Gauss–Newton step predicts, ``||P r||^2`` (``P`` the projection onto the
    columns of ``jac`` not held at an active bound), is below ``rtol`` times ``||r||^2``: a
    search that ends where it started there has converged (an estimate on a bound with a zero
    projected gradient included); elsewhere it is stuck.
    """
    g = jac.T @ r                                   # d (||r||^2 / 2) / d x is -g
    free = ~(((x <= lower) & (g < 0)) | ((x >= upper) & (g > 0)))
    if not np.any(free):
        return True
    # The projection onto the columns' numerical range (equilibrated, singular values above
    # the rank tolerance of _linalg): a plain QR of nearly dependent columns (estimated past
    # levels beside a slow pole: condition 1e19) projects onto rounding noise as well.
    a = jac[:, free]
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0] = 1.0
    basis, sv, _ = np.linalg.svd(a / norms, full_matrices=False)
    kept = sv > (sv[0] if sv.size else 0.0) * _linalg.rank_tolerance(*a.shape)
    pred = float(np.sum((basis[:, kept].T @ r) ** 2))
    return pred <= rtol * float(r @ r)
