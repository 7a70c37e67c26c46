"""Fitting any model kind to a measured frequency response (:func:`fit_frequency_response`).

Not in the paper: the frequency-domain counterpart of :func:`fohw.fit`, for every
:class:`fohw.Model` whose kind has the :meth:`~fohw.Model.frequency_response` hook (a
fractional transfer function's ``G(j omega)``, the lagged kind's and the Wiener chain's linear
block, a circuit's impedance). FOMCON's frequency-domain identification of fractional transfer
functions (``fotfid``/``pfid`` with frequency data) is this fit for :class:`fohw.FractionalTF`.

The criterion is the complex error stacked as real numbers,
``r = [w Re(H_model - H), w Im(H_model - H)]`` (length ``2 m`` for ``m`` frequencies), minimised
over the model's free parameters by bounded nonlinear least squares
(:func:`fohw.estimators._common.bounded_least_squares`, trust-region reflective, the one wrapper
every fohw estimator runs). The weight ``w`` is, by default (``weight="relative"``),
``1 / |H|`` of the *measured* response: every frequency counts by its relative error (the
usual choice for data whose errors grow with ``|H|``, and for impedance spectra, "modulus
weighting"); ``"unit"`` leaves the absolute error; an array gives one positive weight per
frequency (e.g. ``1 / sigma`` of each measured point). The weights do not depend on the
parameters, so the criterion is a plain weighted least-squares problem and its covariance
``s^2 (J^T J)^{-1}`` (``s^2 = SSE / (2 m - p)``) is that of :func:`fohw.fit`.

The stages, each a function below that :mod:`fohw.estimators.impedance_fit` runs too:

1. the data are checked (positive finite frequencies, one finite complex value each, more
   real equations than free parameters; frequencies above the Nyquist frequency ``pi / dt``
   of a kind whose response is that of a sampled system are refused; an impedance with a
   negative real part at most frequencies is refused, naming the sign);
2. the parameters that do not enter the response (a static map's curvature, a circuit's OCV
   offset) are held at the model's values (fixed in the result, named in its message);
3. starts: the model and the user's ``start`` models, each with its free orders on a grid
   inside their bounds (``order_grid``, as :func:`fohw.fit`), and each also with the
   parameters that enter the response linearly (found numerically: a numerator's
   coefficients, a circuit's resistances) solved by bounded linear least squares; ranked by
   the criterion;
4. the best ``n_starts`` are refined; the Jacobian is by central differences of the closed-form
   response (a few dozen frequencies: they cost nothing beside a simulation);
5. the status and covariance as :func:`fohw.fit` gives them: ``FAILED`` for a search stuck at
   its start (:func:`fohw.estimators._common.stationary`), ``RANK_DEFICIENT`` naming the
   dependent parameters (through :mod:`fohw._linalg`), a :class:`fohw.FitResult`.
"""

from __future__ import annotations

import inspect
import math
import warnings

import numpy as np
import scipy  # submodules load on first use

from .. import _linalg
from .._threads import thin_solves
from .._validation import check_array, check_int, check_scalar
from ..exceptions import ConvergenceWarning, DataWarning, ParameterError, RankDeficiencyWarning
from ..fit_result import FitResult
from ..model.base import Model
from ..results import Status
from ._common import bounded_least_squares, stationary
from .fit import PENALTY, data_digest, order_grid_models, rank_rcond

__all__ = ["fit_frequency_response", "WEIGHTS", "AFFINE_RTOL", "FrequencyProblem", "response_weight",
           "idle_parameters", "check_equations", "check_impedance_signs", "rank_candidates",
           "refine", "starts_table", "held_note", "covariance_of", "finish", "frequency_result"]

#: The weightings of the residual: ``"relative"`` (divided by the measured ``|H|``, default),
#: ``"unit"`` (the absolute error); an array of one positive weight per frequency also works.
WEIGHTS = ("relative", "unit")

#: Relative tolerance of the numerical test that a parameter enters the response linearly
#: (the second difference of the response along it, against the response's size).
AFFINE_RTOL = 1e-9


def response_weight(weight, h):
    """The weight ``w`` of each frequency: ``1 / |h|``, ones, or the user's positive array."""
    if isinstance(weight, str):
        if weight not in WEIGHTS:
            raise ParameterError(f"`weight` must be one of {', '.join(map(repr, WEIGHTS))} or an "
                                 f"array of one positive weight per frequency; got {weight!r}.")
        return 1.0 / np.abs(h) if weight == "relative" else np.ones(h.size)
    w = check_array(weight, "weight")
    if w.shape != h.shape or np.any(w <= 0):
        raise ParameterError(f"`weight` given as an array must hold one positive weight per "
                             f"frequency ({h.size}); got shape {w.shape}, values from "
                             f"{w.min()!r} to {w.max()!r}.")
    return w


def check_equations(names, m, what):
    """Raise unless something is free and ``2 m`` real equations outnumber the free parameters."""
    if not names:
        raise ParameterError(f"every parameter that enters {what} is fixed or tied: nothing to "
                             "fit. Free some with model.with_parameters(parameters).")
    if 2 * m <= len(names):
        raise ParameterError(f"the data have {m} frequencies (2 m = {2 * m} real equations) for "
                             f"{len(names)} free parameters ({', '.join(names)}); need more "
                             "equations than parameters.")


def check_impedance_signs(z, *, capacitive, name="z"):
    """Refuse (or warn about) an impedance in another sign convention, naming it.

    A passive one-port has ``Re Z >= 0``: a negative real part at more than half of the
    frequencies is ``-Z`` (the voltage or the current with the other sign), refused. A cell's
    circuit (RC, ZARC, Warburg elements, the OCV's capacitor) is capacitive, ``Im Z <= 0`` at
    every frequency: a positive imaginary part at more than half of them is the "-Im Z"
    convention of Nyquist plots (``conj(Z)`` given), refused when ``capacitive`` and warned
    about (:class:`fohw.DataWarning`) otherwise (a kind with an inductance may have it).
    """
    m = z.size
    negative = int(np.count_nonzero(z.real < 0))
    if 2 * negative > m:
        raise ParameterError(
            f"`{name}` has a negative real part at {negative} of its {m} frequencies: a passive "
            "impedance has Re Z >= 0, so this looks like -Z (the voltage or the current taken "
            f"with the other sign). Pass Z = V / I in the model's sign convention (-{name}).")
    inductive = int(np.count_nonzero(z.imag > 0))
    if 2 * inductive > m:
        text = (f"`{name}` has a positive imaginary part at {inductive} of its {m} frequencies, "
                "where a capacitive impedance (RC, ZARC and Warburg elements) has Im Z <= 0: this "
                "looks like the \"-Im Z\" convention of Nyquist plots (conj(Z) given). Pass the "
                f"impedance itself (np.conj({name}) undoes it).")
        if capacitive:
            raise ParameterError(text)
        warnings.warn(text, DataWarning, stacklevel=4)


class FrequencyProblem:
    """The free parameters of a model and the weighted residual of its response.

    ``respond(model)`` is the model's complex response at the data's frequencies, ``target``
    the measured one and ``weight`` the weight of each frequency. :meth:`residual` is
    ``[w Re(respond - target), w Im(respond - target)]`` at a free vector ``x`` (a run that
    fails or is not finite gives the constant ``escaped``, larger than any finite one);
    :meth:`jacobian` its central differences, step ``eps**(1/3) max(|x_j|, step_floor)``
    (one-sided at a bound; :func:`fohw.estimators.fit.central_differences` is this rule with
    ``step_floor = 1``).
    """

    def __init__(self, model, params, respond, target, weight, *, step_floor=1.0):
        self.model, self.params, self.respond = model, params, respond
        self.target, self.weight, self.step_floor = target, weight, step_floor
        self.names = params.free_names
        self.lower, self.upper = params.free_bounds()
        scale = float(np.max(np.abs(target * weight)))
        self.escaped = np.full(2 * target.size, PENALTY * max(scale, 1e-300))

    def at(self, x):
        """The model at the free vector ``x`` (clipped into the bounds)."""
        return self.model.with_parameters(self.params.with_free(np.clip(x, self.lower, self.upper)))

    def of_model(self, m):
        """The residual of model ``m`` (raises what its response raises)."""
        d = (self.respond(m) - self.target) * self.weight
        return np.concatenate([d.real, d.imag])

    def residual(self, x):
        """The residual at ``x``; ``escaped`` where the response fails or is not finite."""
        try:
            with np.errstate(all="ignore"):
                r = self.of_model(self.at(x))
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return self.escaped
        return r if np.all(np.isfinite(r)) else self.escaped

    def jacobian(self, x):
        """Central differences of :meth:`residual` in the free parameters (zeros where they fail).

        As :func:`fohw.fit`'s Jacobian: where the response cannot be computed or is not finite
        at a difference point, the search gets zeros (no direction) rather than an exception.
        """
        zeros = np.zeros((2 * self.target.size, len(self.names)))
        try:
            with np.errstate(all="ignore"):
                jac = self.jacobian_of(x, self.of_model)
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return zeros
        return jac if np.all(np.isfinite(jac)) else zeros

    def jacobian_of(self, x, of_model):
        """Central differences of ``of_model(self.at(x))`` in the free parameters.

        The response is a closed form evaluated at a few dozen frequencies: the differences
        cost nothing beside a simulation, and their step gives about ten accurate digits (a
        parameter that enters linearly, where ``x`` may be 0, exactly).
        """
        cols = []
        for j in range(x.size):
            step = np.finfo(float).eps ** (1 / 3) * max(abs(x[j]), self.step_floor)
            hi = min(x[j] + step, self.upper[j])
            lo = max(x[j] - step, self.lower[j])
            xp, xm = x.copy(), x.copy()
            xp[j], xm[j] = hi, lo
            cols.append((of_model(self.at(xp)) - of_model(self.at(xm))) / (hi - lo))
        return np.column_stack(cols) if cols else np.zeros((2 * self.target.size, 0))

    # --- parameters that enter linearly ----------------------------------------------------
    def _moved(self, x, j, scale=0.5):
        """A second value of ``x[j]`` inside its bounds, ``scale * max(|x_j|, 1)`` away."""
        lo, hi = self.lower[j], self.upper[j]
        step = scale * max(abs(x[j]), 1.0)
        for v in (x[j] + step, x[j] - step):
            if lo <= v <= hi:
                return v
        return 0.5 * (lo + hi) if x[j] != 0.5 * (lo + hi) else lo + 0.25 * (hi - lo)

    def affine(self, points):
        """Indices of the free parameters the response is jointly affine in at every point."""
        idx = []
        try:
            with np.errstate(all="ignore"):
                for j in range(len(self.names)):
                    if self.params[self.names[j]].order:
                        continue                    # an order never enters linearly
                    if all(self._affine_along(x, j) for x in points):
                        idx.append(j)
                if idx and not all(self._jointly_affine(x, idx) for x in points):
                    return []
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return []
        return idx

    def _affine_along(self, x, j):
        v1 = self._moved(x, j)
        v2 = x[j] + 2 * (v1 - x[j])
        if not self.lower[j] <= v2 <= self.upper[j]:
            v2 = x[j] + 0.5 * (v1 - x[j])
        h = []
        for v in (x[j], v1, v2):
            xv = x.copy()
            xv[j] = v
            h.append(self.respond(self.at(xv)))
        t = (v2 - x[j]) / (v1 - x[j])
        second = h[2] - h[0] - t * (h[1] - h[0])
        size = sum(float(np.max(np.abs(a))) for a in h)
        return (np.all(np.isfinite(second)) and np.any(h[1] != h[0])
                and float(np.max(np.abs(second))) <= AFFINE_RTOL * size)

    def _jointly_affine(self, x, idx):
        h0 = self.respond(self.at(x))
        x_all = x.copy()
        pred = h0.copy()
        for j in idx:
            xv = x.copy()
            xv[j] = self._moved(x, j)
            pred = pred + (self.respond(self.at(xv)) - h0)
            x_all[j] = xv[j]
        h = self.respond(self.at(x_all))
        return float(np.max(np.abs(h - pred))) <= AFFINE_RTOL * (float(np.max(np.abs(h)))
                                                                  + float(np.max(np.abs(h0))))

    def linear_solve(self, m, idx):
        """``m`` with the affine parameters ``idx`` solved by bounded linear least squares, or None."""
        x = np.clip(m.parameters.free_values(), self.lower, self.upper)
        try:
            with np.errstate(all="ignore"):
                h0 = self.respond(self.at(x))
                cols = []
                for j in idx:
                    xv = x.copy()
                    xv[j] = self._moved(x, j, scale=1.0)
                    cols.append((self.respond(self.at(xv)) - h0) / (xv[j] - x[j]))
                a = np.column_stack(cols) * self.weight[:, None]
                rhs = (self.target - h0) * self.weight
                a, rhs = np.vstack([a.real, a.imag]), np.concatenate([rhs.real, rhs.imag])
                if not (np.all(np.isfinite(a)) and np.all(np.isfinite(rhs))):
                    return None
                sol = scipy.optimize.lsq_linear(a, rhs, bounds=(self.lower[idx] - x[idx],
                                                                 self.upper[idx] - x[idx]))
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError, ValueError):
            return None
        x = x.copy()
        x[idx] = x[idx] + sol.x
        return self.at(x)


def _jitter(params):
    """The free vector moved by ``0.1 max(|x_j|, 1)`` (alternating in sign) inside the bounds."""
    x = params.free_values()
    lower, upper = params.free_bounds()
    y = x.copy()
    for j in range(x.size):
        step = 0.1 * max(abs(x[j]), 1.0) * (1 if j % 2 == 0 else -1)
        for v in (x[j] + step, x[j] - step):
            if lower[j] <= v <= upper[j]:
                y[j] = v
                break
        else:
            y[j] = 0.5 * (lower[j] + upper[j])
    return y


def idle_parameters(model, respond):
    """The free, untied parameters whose change moves ``respond(model)`` at neither of two points.

    The points: the model's values, and each free value moved by ``0.1 max(|x|, 1)`` inside its
    bounds (where a parameter that is 0 at the start, a resistance or a coefficient, no longer
    hides the ones it multiplies). A parameter is moved alone, by ``0.1 max(|x|, 1)``;
    "does not move" is bit-for-bit: a parameter the response does not read. A response that
    raises at a probe counts as moved.
    """
    params = model.parameters
    names = params.free_names
    lower, upper = params.free_bounds()
    points = [np.clip(params.free_values(), lower, upper), _jitter(params)]
    moved = set()
    for x in points:
        try:
            with np.errstate(all="ignore"):
                h0 = respond(model.with_parameters(params.with_free(x)))
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return []
        for j, name in enumerate(names):
            if name in moved:
                continue
            xv = x.copy()
            step = 0.1 * max(abs(x[j]), 1.0)
            xv[j] = x[j] + step if x[j] + step <= upper[j] else x[j] - step
            if not lower[j] <= xv[j] <= upper[j]:
                xv[j] = 0.5 * (lower[j] + upper[j])
            try:
                with np.errstate(all="ignore"):
                    h = respond(model.with_parameters(params.with_free(xv)))
            except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
                moved.add(name)
                continue
            if not np.array_equal(h, h0):
                moved.add(name)
    return [n for n in names if n not in moved]


def rank_candidates(problem, candidates, residual):
    """``[(sse, x)]`` of the candidates inside the bounds with a finite residual, lowest first."""
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
        if np.all(np.isfinite(r)) and r is not getattr(problem, "escaped", None):
            ranked.append((float(r @ r), x))
    ranked.sort(key=lambda t: t[0])
    return ranked


def refine(problem, ranked, residual, jacobian, n_starts, max_nfev, tol):
    """Bounded least squares from the best ``n_starts`` of ``ranked``: ``(sse, x, status, ls, sse0)``."""
    best = None
    for sse0, x0 in ranked[:n_starts]:
        x, status, ls = bounded_least_squares(residual, x0, jac=jacobian, lower=problem.lower,
                                              upper=problem.upper, ftol=tol, xtol=tol, gtol=tol,
                                              max_nfev=max_nfev)
        r = residual(x)
        sse = float(r @ r)
        if best is None or sse < best[0]:
            best = (sse, x, status, ls, sse0)
    return best


def starts_table(problem, ranked):
    """``FitResult.starts``: each ranked start's free orders and its criterion, best first."""
    orders = [(j, n) for j, n in enumerate(problem.names) if problem.params[n].order]
    return tuple(({n: float(x[j]) for j, n in orders}, sse) for sse, x in ranked)


def held_note(held, what):
    """The result's sentence on the parameters held because they do not enter ``what`` (or None)."""
    if not held:
        return None
    names = " and ".join([", ".join(held[:-1]), held[-1]] if len(held) > 1 else held)
    return (f"{names} {'do' if len(held) > 1 else 'does'} not enter {what}: held at the "
            "model's values.")


def covariance_of(jac, sse, n, names):
    """``(covariance, rank_note)``: ``s^2 (J^T J)^{-1}`` (``s^2 = sse / (n - p)``), or None and a note.

    The rank decision is that of a Jacobian by central differences
    (:func:`fohw.estimators.fit.rank_rcond`); the note names the dependent parameters.
    """
    inverse, fac = _linalg.inverse_gram(jac, rcond=rank_rcond("finite differences", *jac.shape))
    if inverse is None:
        cols = ", ".join(names[i] for i in fac.dependent)
        return None, (f"Rank deficient: rank {fac.rank} of {fac.n_columns}; the columns of {cols} "
                      "are linear combinations of the others, so those parameters are not "
                      "identifiable from these data (fix one of them).")
    return sse / max(n - len(names), 1) * inverse, None


def finish(where, status, messages, rank_note, stacklevel=4):
    """``(status, message)`` with the rank note; warns as :func:`fohw.fit` does (``where`` names the verb)."""
    if rank_note:
        status = Status.RANK_DEFICIENT if status != Status.FAILED else status
        messages.append(rank_note)
        warnings.warn(f"{where}: {rank_note}", RankDeficiencyWarning, stacklevel=stacklevel)
    elif status in (Status.MAX_ITER, Status.FAILED):
        warnings.warn(f"{where}: {' '.join(messages[1:])}", ConvergenceWarning, stacklevel=stacklevel)
    return status, " ".join(messages)


def frequency_result(problem, best, ranked, *, label, caller, held_note, max_nfev, digest, options):
    """The :class:`fohw.FitResult` of the best refinement: status, messages, covariance, warnings.

    ``FAILED`` for a search that made no step from its start and is not at a stationary point;
    ``RANK_DEFICIENT`` (the parameters named) for a Jacobian without full column rank; the
    covariance ``s^2 (J^T J)^{-1}``, ``s^2 = SSE / (2 m - p)``. ``caller`` names the verb in
    the warnings.
    """
    sse, x, status, ls, sse0 = best
    fitted = problem.at(x)
    jac = problem.jacobian(x)
    r = problem.residual(x)
    messages = [f"{label} (scipy.optimize.least_squares): {ls.message}"]
    if held_note:
        messages.append(held_note)
    if status == Status.MAX_ITER:
        messages.append(f"The search used its budget of {max_nfev} evaluations; raise `max_nfev`.")
    if ls.status == 3 and not sse < sse0 * (1.0 - 1e-9) and \
            not stationary(-jac, r, x, problem.lower, problem.upper):
        status = Status.FAILED
        messages.append("The search is stuck at its start: it made no step that lowered the "
                        "criterion, so the estimate is where it started, not a minimum.")
    covariance, rank_note = covariance_of(jac, sse, r.size, problem.names)
    status, message = finish(f"{caller}({type(problem.model).__name__})", status, messages,
                             rank_note, stacklevel=5)
    return FitResult(model=fitted, parameters=fitted.parameters, covariance=covariance,
                     status=status, sse=sse, n_samples=r.size, message=message,
                     nfev=int(ls.nfev), jacobian="finite differences",
                     starts=starts_table(problem, ranked), residuals=r, data_digest=digest,
                     options=options)


def _check_hook(model, where):
    """Raise unless ``model`` is a Model whose kind has the hook and takes the keywords ``where``."""
    if not isinstance(model, Model):
        raise ParameterError(f"`model` must be a fohw.Model (a model kind); got {type(model).__name__}.")
    kind = type(model).__name__
    if type(model).frequency_response is Model.frequency_response:
        raise ParameterError(
            f"a {kind} has no frequency response: its kind does not define the fohw.Model hook "
            "`frequency_response(omega)`, so it cannot be fitted to one. Fit it to a time record "
            "with fohw.fit, or give the kind a `frequency_response` method.")
    sig = inspect.signature(model.frequency_response)
    takes_any = any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())
    known = [n for n, p in sig.parameters.items() if p.kind == p.KEYWORD_ONLY or
             (p.kind == p.POSITIONAL_OR_KEYWORD and n != "omega")]
    for key in where:
        if not takes_any and key not in known:
            raise ParameterError(
                f"`{key}` is neither an argument of fit_frequency_response nor a keyword of "
                f"{kind}.frequency_response (it takes {', '.join(map(repr, known)) or 'none'}).")


def _check_data(omega, response):
    omega = check_array(omega, "omega", min_length=1)
    bad = np.flatnonzero(omega <= 0)
    if bad.size:
        raise ParameterError(f"`omega` must be positive angular frequencies; got "
                             f"{float(omega[bad[0]])!r} at index {int(bad[0])}.")
    try:
        h = np.asarray(response, dtype=np.complex128).ravel()
    except (TypeError, ValueError):
        raise ParameterError(f"`response` must be an array of complex numbers; got "
                             f"{type(response).__name__}.") from None
    if h.shape != omega.shape:
        raise ParameterError(f"`response` must have one value per frequency; got {h.size} values "
                             f"for {omega.size} frequencies.")
    bad = np.flatnonzero(~np.isfinite(h))
    if bad.size:
        raise ParameterError(f"`response` must be finite at every frequency; got {h[bad[0]]!r} at "
                             f"index {int(bad[0])} (omega = {omega[bad[0]]:g}).")
    return omega, h


def _check_nyquist(model, omega, respond_at):
    """Refuse frequencies above ``pi / dt`` when the model's response is a sampled system's.

    The test is the mirror symmetry of a sampled real system, ``H(2 pi / dt - omega) =
    conj(H(omega))``, at the lowest measured frequency above ``pi / dt`` (a continuous response
    has no such symmetry), on the model with its free values moved off the start (where
    resistances or coefficients of 0 may make any response constant), or on the model itself.
    ``respond_at(model, omega)`` is the response.
    """
    dt = model.dt
    if dt is None or not np.isfinite(dt) or dt <= 0:
        return
    nyquist = math.pi / float(dt)
    above = omega > nyquist * (1 + 1e-12)
    if not np.any(above):
        return
    probe = float(omega[above].min())
    probe = probe % (2 * nyquist) if probe >= 2 * nyquist else probe
    if probe <= nyquist * (1 + 1e-12):
        return
    params = model.parameters
    sampled = None
    for m in (model.with_parameters(params.with_free(_jitter(params))), model):
        try:
            with np.errstate(all="ignore"):
                hp = np.asarray(respond_at(m, np.array([probe])), dtype=complex)
                hm = np.asarray(respond_at(m, np.array([2 * nyquist - probe])), dtype=complex)
        except (ArithmeticError, ParameterError):
            continue
        if np.all(np.isfinite(hp)) and np.all(np.isfinite(hm)) and not np.allclose(hp, hm, rtol=1e-9,
                                                                                    atol=0.0):
            sampled = np.allclose(hp, np.conj(hm), rtol=1e-9, atol=0.0)
            break
    if sampled:
        raise ParameterError(
            f"`omega` has {int(np.count_nonzero(above))} of its {omega.size} frequencies above the "
            f"Nyquist frequency pi / dt = {nyquist:.6g} of this {type(model).__name__} (dt = {dt!r}; "
            f"the highest is {float(omega.max()):.6g}): its response is a sampled system's, "
            "periodic in omega with period 2 pi / dt, so beyond pi / dt it repeats (aliases) and "
            "cannot follow a response measured there. Drop those frequencies, or use a model "
            "with a smaller dt (or its continuous response, where the kind has one).")


@thin_solves
def fit_frequency_response(model, omega, response, *, weight="relative", start=None, order_grid=5,
                           n_starts=3, max_nfev=200, tol=1e-10, **where):
    """Fit any :class:`fohw.Model` with a frequency response to a measured one.

    Parameters
    ----------
    model : Model
        The kind (it must have :meth:`~fohw.Model.frequency_response`), its start values, and
        which parameters are free, fixed, tied or bounded (its :attr:`~fohw.Model.parameters`,
        honoured as :func:`fohw.fit` honours them).
    omega : array_like, shape (m,)
        Angular frequencies, positive, in radians per unit of the model's time (rad/s for a
        circuit, whose ``dt`` is in seconds; ``2 pi f`` for frequencies ``f`` in Hz).
    response : array_like of complex, shape (m,)
        The measured response ``H(j omega)`` (a circuit's: its impedance ``V / I`` [ohm]).
    weight : {"relative", "unit"} or array_like, optional
        The residual's weighting (see the module's docstring): ``"relative"`` (default) divides
        the complex error by the measured ``|H|``; ``"unit"`` leaves it absolute; an array
        gives one positive weight per frequency.
    start : Model or sequence of Model, optional
        Further start models of the same kind and parameters.
    order_grid : int, optional
        Scan points per free order for each start (its own value always among them); 1 skips
        the scan. At most ``MAX_SCAN`` points per start model.
    n_starts, max_nfev, tol : optional
        As :func:`fohw.fit`: how many of the best-ranked starts are refined, the evaluation
        budget of each, and ``ftol = xtol = gtol`` of :func:`scipy.optimize.least_squares`.
    **where
        Keywords of the kind's :meth:`~fohw.Model.frequency_response` (an operating point, e.g.
        ``soc=`` and ``temperature=`` of :class:`fohw.CircuitTables`; ``discrete=True`` for a
        circuit's GL-discretised response); a keyword the hook does not take is refused.

    Returns
    -------
    FitResult
        ``residuals`` are the weighted residuals ``[Re, Im]`` (length ``2 m``), ``sse`` their
        sum of squares, ``n_samples = 2 m``; ``options["data"] == "frequency response"``.
        Parameters that do not enter the response are held at the model's values (fixed in
        the result's parameters; the message names them). The Jacobian is by central
        differences.

    Raises
    ------
    ParameterError
        The kind has no ``frequency_response`` (named); frequencies not positive; a response
        not finite or of another length; as many free parameters as real equations;
        frequencies above the Nyquist frequency of a kind whose response is sampled; an
        impedance (:attr:`~fohw.Model.response_kind` ``"impedance"``) with a negative real part
        at most frequencies (``-Z``).

    Warns
    -----
    ConvergenceWarning
        The search used its budget or is stuck at its start.
    RankDeficiencyWarning
        Some free parameters are not identifiable from the response (named).
    DataWarning
        An impedance whose imaginary part is positive at most frequencies (the "-Im Z"
        plotting convention?).

    Notes
    -----
    The starts, the held parameters and the status are described in the module's docstring;
    :func:`fohw.estimators.impedance_fit.fit_impedance` is this fit for a circuit with the
    circuit's own conventions (frequencies in Hz, its scan of time constants and orders).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> true = fohw.FractionalTF([2.0], [0.0], [1.5, 1.0], [0.8, 0.0])       # 2 / (1.5 s^0.8 + 1)
    >>> w = np.logspace(-2, 2, 30)
    >>> res = fohw.fit_frequency_response(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
    ...                                   w, true.frequency_response(w))
    >>> res.status.name, {k: round(v, 6) for k, v in res.parameters.valuesdict().items()}
    ('CONVERGED', {'b0': 2.0, 'beta0': 0.0, 'a0': 1.5, 'a1': 1.0, 'alpha0': 0.8, 'alpha1': 0.0})
    """
    _check_hook(model, where)
    omega, h = _check_data(omega, response)
    w = response_weight(weight, h)
    if isinstance(weight, str) and weight == "relative" and np.any(h == 0):
        k = int(np.flatnonzero(h == 0)[0])
        raise ParameterError(f"`response` is 0 at index {k} (omega = {omega[k]:g}): a relative "
                             "error needs |H| > 0; drop that frequency or use weight=\"unit\".")
    order_grid = check_int(order_grid, "order_grid", minimum=1)
    n_starts = check_int(n_starts, "n_starts", minimum=1)
    max_nfev = check_int(max_nfev, "max_nfev", minimum=1)
    tol = check_scalar(tol, "tol", lower=np.finfo(float).eps, upper=1.0, upper_inclusive=False)
    kind = type(model).__name__
    h0 = model.frequency_response(omega, **where)
    if h0 is None:
        raise ParameterError(f"this {kind}'s frequency_response returned None: it has no "
                             "frequency response to fit.")
    if np.shape(h0) != omega.shape:
        raise ParameterError(f"{kind}.frequency_response returned shape {np.shape(h0)} for "
                             f"{omega.size} frequencies; it must return one value per frequency.")
    _check_nyquist(model, omega, lambda m, o: m.frequency_response(o, **where))
    if model.response_kind == "impedance":
        check_impedance_signs(h, capacitive=False, name="response")

    def respond(m):
        return np.asarray(m.frequency_response(omega, **where), dtype=complex)

    extra = [] if start is None else [start] if isinstance(start, Model) else list(start)
    params = model.parameters
    for s in extra:
        if type(s) is not type(model) or s.parameters.names != params.names:
            raise ParameterError(f"`start` must hold models of the same kind and parameters as "
                                 f"`model` ({kind}); got {type(s).__name__}.")
    held = idle_parameters(model, respond)
    for n in held:
        params = params.replace(n, fixed=True)
    base = model.with_parameters(params)
    problem = FrequencyProblem(base, params, respond, h, w)
    check_equations(problem.names, omega.size, "the frequency response")
    affine = problem.affine([np.clip(params.free_values(), problem.lower, problem.upper),
                             _jitter(params)])
    candidates = []
    for s in [base] + [base.with_parameters(params.with_values(s.parameters.valuesdict()))
                       for s in extra]:
        for m in order_grid_models(s, order_grid, params):
            candidates.append(m)
            solved = problem.linear_solve(m, affine) if affine else None
            if solved is not None:
                candidates.append(solved)
    ranked = rank_candidates(problem, candidates, problem.residual)
    if not ranked:
        raise ParameterError(f"no start of the {kind} gave a finite response at these "
                             f"frequencies ({len(candidates)} tried); give a start (`start=`).")
    best = refine(problem, ranked, problem.residual, problem.jacobian, n_starts, max_nfev, tol)
    return frequency_result(
        problem, best, ranked, label="frequency-response fit", caller="fohw.fit_frequency_response",
        held_note=held_note(held, "the frequency response"), max_nfev=max_nfev,
        digest=data_digest(omega, np.concatenate([h.real, h.imag]),
                           float("nan") if model.dt is None else model.dt),
        options=dict(data="frequency response", order_grid=order_grid, n_starts=n_starts,
                     max_nfev=max_nfev, tol=tol,
                     weight=weight if isinstance(weight, str) else w.tolist(), **where))
