"""Does my model kind follow the :class:`fohw.Model` protocol? (the conformance checks).

A model kind (:class:`fohw.Model`, CONTRIBUTING.md's *How to add a model kind*) promises more
than its three abstract members: values that round-trip, copies that keep a fit's fixed flags and
bounds, a deterministic simulator that refuses a wrong input, files that rebuild it, and optional
hooks (an exact Jacobian, starts, a frequency response, a penalty) that agree with the rest. Every
verb of fohw relies on those promises; :func:`check_model` checks them, one named check at a time,
in a user's own tests as in fohw's (like scikit-learn's ``check_estimator``)::

    import fohw.testing

    def test_my_kind_follows_the_protocol():
        fohw.testing.check_model(MyKind)

:func:`iter_checks` and :func:`parametrize_with_checks` give one test per check. The module is
not loaded by ``import fohw`` (write ``import fohw.testing``, as ``numpy.testing``), and it needs
no pytest except for :func:`parametrize_with_checks`.
"""

from __future__ import annotations

import copy
import json
import math
import os
import tempfile

import numpy as np

from .exceptions import FohwError, ParameterError
from .io.jsonio import load_model, save_model
from .model.base import Model
from .model.parameters import Parameters

__all__ = ["CHECKS", "ModelCheckError", "check_model", "iter_checks", "parametrize_with_checks"]

_EPS = np.finfo(float).eps
#: A kind's stored value may differ from the value it was given by a few units in the last
#: place (a kind that keeps ``log(tau)`` returns ``exp(log(tau))``): 8 eps relative.
_VALUE_RTOL = 8 * _EPS
#: The rounding error of a simulator, relative to its largest output, that the difference
#: quotients allow for: 32 eps (the shipped kinds' errors are 0.2-4 eps of it).
_SIMULATION_EPS = 32 * _EPS


class ModelCheckError(FohwError, AssertionError):
    """A model kind failed a check of :func:`check_model`; the message names the check and why.

    An :class:`AssertionError` (a test that calls :func:`check_model` fails, not errors) and a
    :class:`fohw.FohwError`.

    Attributes
    ----------
    check : str
        The name of the check that failed (one of :data:`CHECKS`).
    kind : str
        The kind's registry name (:meth:`fohw.Model.kind_name`).
    reason : str
        What the check found.
    """

    def __init__(self, check, kind, reason):
        self.check, self.kind, self.reason = check, kind, reason
        super().__init__(f"{kind}: check {check!r} failed: {reason}")

    def __reduce__(self):
        return type(self), (self.check, self.kind, self.reason)


class _Failed(Exception):
    """Raised inside a check: the reason it failed."""


class _Context:
    """What every check gets: a fresh model per call, the input and the tolerance."""

    def __init__(self, factory, u, rtol):
        self.factory, self.given_u, self.rtol, self.kind = factory, u, rtol, None

    def model(self):
        if isinstance(self.factory, Model):
            return copy.deepcopy(self.factory)
        model = self.factory()
        if not isinstance(model, Model):
            raise ParameterError(f"`factory` must return a fohw.Model; it returned "
                                 f"{type(model).__name__}.")
        return model

    def input(self, model):
        """``u`` as given, or 100 standard normal samples in ``model.n_inputs`` columns (seed 0)."""
        if self.given_u is not None:
            return np.array(self.given_u, dtype=np.float64)
        n = model.n_inputs
        rng = np.random.default_rng(0)
        return rng.standard_normal(100) if n == 1 else rng.standard_normal((100, n))

    def about_u(self):
        """Said after a simulation error: where the input came from."""
        if self.given_u is not None:
            return ""
        return (" (the input was check_model's default, standard normal samples; pass `u` for a "
                "kind whose inputs need other ranges)")


def _fail(reason):
    raise _Failed(reason)


def _close(a, b):
    return a == b or abs(a - b) <= _VALUE_RTOL * max(abs(a), abs(b))


def _parameter_difference(got, want, *, exact_values=False):
    """A sentence naming the first difference of two Parameters, or None."""
    if not isinstance(got, Parameters):
        return f"`parameters` is a {type(got).__name__}, not a fohw.Parameters"
    if got.names != want.names:
        return f"the names are {list(got.names)}, not {list(want.names)}"
    for name in want.names:
        g, w = got[name], want[name]
        for field in ("bounds", "fixed", "tie", "order"):
            if getattr(g, field) != getattr(w, field):
                return f"{name!r} has {field} {getattr(g, field)!r}, not {getattr(w, field)!r}"
        if not (g.value == w.value if exact_values else _close(g.value, w.value)):
            return f"{name!r} has the value {g.value!r}, not {w.value!r}"
    return None


def _moved(par, fraction=1e-3):
    """A value of ``par`` moved by ``fraction`` of its scale, inside its bounds."""
    x, (lo, hi) = par.value, par.bounds
    step = min(fraction * max(abs(x), 1.0), (hi - lo) / 4)
    return x + step if x + step <= hi else x - step


def _perturbed(params):
    """``{name: new value}`` for every free parameter, each moved inside its bounds."""
    return {name: _moved(params[name]) for name in params.free_names}


def _settings(model):
    """``(settings, text)``: held settings for ``with_parameters``, and a phrase saying so.

    ``model``'s parameters with the first free one fixed and the last free one's bounds narrowed
    around a moved value (what a user or :func:`fohw.fit` hands ``with_parameters``);
    ``(None, "")`` without a free parameter.
    """
    params = model.parameters
    free = params.free_names
    if not free:
        return None, ""
    held = params.replace(free[0], fixed=True)
    par = params[free[-1]]
    x, (lo, hi) = par.value, par.bounds
    width = min(0.1 * max(abs(x), 1.0), (hi - lo) / 4)
    bounds = (x - width if x - width > lo else lo, x + width if x + width < hi else hi)
    value = x + width / 2 if x + width / 2 <= bounds[1] else x - width / 2
    text = f"{free[0]!r} fixed and {free[-1]!r} at {value:g} in the bounds ({bounds[0]:g}, {bounds[1]:g})"
    return held.replace(free[-1], bounds=bounds, value=value), text


def _simulate(model, u, ctx, what="simulate(u)"):
    try:
        return model.simulate(u)
    except Exception as exc:
        _fail(f"{what} raised {type(exc).__name__}: {exc}{ctx.about_u()}")


# --- the checks ---------------------------------------------------------------------------------
def _check_parameters(ctx):
    model = ctx.model()
    params = model.parameters
    if not isinstance(params, Parameters):
        _fail(f"`parameters` must be a fohw.Parameters; got {type(params).__name__}")
    if len(params) == 0:
        _fail("`parameters` is empty: a kind has at least one number to fit")
    if len(set(params.names)) != len(params):
        _fail(f"the names {list(params.names)} are not unique")
    again = model.parameters
    if again != params:
        _fail(f"two reads of `parameters` differ: {params!r} then {again!r}")


def _check_n_inputs(ctx):
    n = ctx.model().n_inputs
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
        _fail(f"`n_inputs` must be a positive integer (the input's columns); got {n!r}")


def _check_dt(ctx):
    dt = ctx.model().dt
    try:
        value = float(dt)
    except (TypeError, ValueError):
        _fail(f"`dt` must be a number; got {dt!r}")
    if not (math.isfinite(value) and value > 0):
        _fail(f"`dt` must be positive and finite; got {dt!r}")


def _check_simulate(ctx):
    model = ctx.model()
    u = ctx.input(model)
    y = _simulate(model, u, ctx)
    if not isinstance(y, np.ndarray):
        _fail(f"simulate(u) must return a numpy array; got {type(y).__name__}")
    if y.dtype.kind != "f":
        _fail(f"simulate(u) must return floats; got dtype {y.dtype}")
    if y.shape != (u.shape[0],):
        _fail(f"simulate(u) must return one value per sample, shape ({u.shape[0]},) for u of shape "
              f"{u.shape}; got shape {y.shape}")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        _fail(f"simulate(u) is not finite at {bad.size} sample(s), the first {int(bad[0])} "
              f"({y[bad[0]]!r}){ctx.about_u()}")


def _check_simulate_deterministic(ctx):
    model = ctx.model()
    u = ctx.input(model)
    first = _simulate(model, u, ctx)
    _simulate(model, u[::-1].copy(), ctx, "simulate(u reversed)")
    again = _simulate(model, u, ctx)
    if not np.array_equal(first, again):
        k = int(np.flatnonzero(~(first == again))[0])
        _fail(f"simulate(u) gave another output the second time (after simulating another "
              f"input): {first[k]!r} then {again[k]!r} at sample {k}")


def _check_simulate_leaves_input(ctx):
    model = ctx.model()
    u = ctx.input(model)
    given = u.copy()
    _simulate(model, given, ctx)
    if not np.array_equal(given, u):
        _fail("simulate(u) changed the caller's array `u`")


def _wrong_inputs(u, n):
    """Inputs with a wrong number of columns for a kind of ``n`` inputs."""
    if n == 1:
        return [np.column_stack([u, u])]
    return [u[:, :-1], np.column_stack([u, u[:, :1]])]


def _check_refuses_wrong_columns(ctx):
    model = ctx.model()
    u = ctx.input(model)
    for wrong in _wrong_inputs(u, model.n_inputs):
        for what, call in (("check_input", model.check_input), ("simulate", model.simulate)):
            try:
                call(wrong)
            except ValueError:
                continue
            except Exception as exc:
                _fail(f"{what}(u) with {wrong.shape[1]} columns (the kind takes {model.n_inputs}) "
                      f"raised {type(exc).__name__}, not a ValueError naming `u`: {exc}")
            _fail(f"{what}(u) took an input of shape {wrong.shape} ({wrong.shape[1]} columns; the "
                  f"kind takes {model.n_inputs}) instead of refusing it")


def _new(model, values, what):
    try:
        new = model.with_parameters(values)
    except Exception as exc:
        _fail(f"{what} raised {type(exc).__name__}: {exc}")
    if type(new) is not type(model):
        _fail(f"{what} returned a {type(new).__name__}, not a {type(model).__name__}")
    return new


def _check_with_parameters_values(ctx):
    model = ctx.model()
    params = model.parameters
    values = _perturbed(params)
    new = _new(model, values, "with_parameters({name: value})")
    difference = _parameter_difference(new.parameters, params.with_values(values))
    if difference:
        _fail(f"with_parameters({values!r}) gave a model whose parameters differ: {difference}")


def _check_with_parameters_settings(ctx):
    model = ctx.model()
    settings, text = _settings(model)
    if settings is None:
        return "not applicable: no free parameter"
    new = _new(model, settings, "with_parameters(Parameters)")
    difference = _parameter_difference(new.parameters, settings)
    if difference:
        _fail(f"with_parameters(Parameters) with {text} did not keep them: {difference}")
    # A fit moves the values of such a model by name: the settings stay.
    values = {n: settings[n].value for n in settings.free_names}
    again = _new(new, values, "with_parameters({name: value}) of a model with settings")
    difference = _parameter_difference(again.parameters, settings)
    if difference:
        _fail(f"a model with fixed flags or bounds lost them in with_parameters({{name: value}}): "
              f"{difference}")


def _check_with_parameters_does_not_mutate(ctx):
    model = ctx.model()
    u = ctx.input(model)
    before, config, y = model.parameters, copy.deepcopy(model.config()), _simulate(model, u, ctx)
    _new(model, _perturbed(before), "with_parameters({name: value})")
    settings, _ = _settings(model)
    if settings is not None:
        _new(model, settings, "with_parameters(Parameters)")
    difference = _parameter_difference(model.parameters, before, exact_values=True)
    if difference:
        _fail(f"with_parameters changed the original model: {difference}")
    if model.config() != config:
        _fail(f"with_parameters changed the original model's config: {config!r} -> "
              f"{model.config()!r}")
    if not np.array_equal(_simulate(model, u, ctx), y):
        _fail("with_parameters changed the original model's output")


def _check_equality(ctx):
    model = ctx.model()
    twin = copy.deepcopy(model)
    if (model == twin) is not True or (model != twin) is not False:
        _fail(f"a deep copy is not equal to the model (model == copy gave {model == twin!r})")
    same = _new(model, model.parameters.valuesdict(), "with_parameters(its own values)")
    if (same == model) is not True:
        _fail("with_parameters(its own values) gave a model not equal to it")
    if model.parameters.free_names:
        other = _new(model, _perturbed(model.parameters), "with_parameters({name: value})")
        if (other == model) is not False:
            _fail("a model with other parameter values compares equal to it")
    if (model == object()) is not False:
        _fail("a model compares equal to an object that is not a model")


def _check_config_json(ctx):
    config = ctx.model().config()
    if not isinstance(config, dict):
        _fail(f"config() must return a dict (keyword arguments of the constructor); got "
              f"{type(config).__name__}")
    try:
        json.dumps(config, allow_nan=False)
    except (TypeError, ValueError) as exc:
        _fail(f"config() must hold JSON values only (it goes to the model file): {exc}")


def _round_trip(model):
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "model.json")
        try:
            save_model(model, path)
            return load_model(path)
        except Exception as exc:
            _fail(f"fohw.save_model/load_model raised {type(exc).__name__}: {exc}")


def _check_save_load(ctx):
    model = ctx.model()
    u = ctx.input(model)
    back = _round_trip(model)
    if type(back) is not type(model):
        _fail(f"fohw.load_model gave a {type(back).__name__}, not a {type(model).__name__}")
    difference = _parameter_difference(back.parameters, model.parameters, exact_values=True)
    if difference:
        _fail(f"the model read back has other parameters: {difference}")
    if (back == model) is not True:
        _fail("the model read back is not equal (==) to the model written")
    y, y_back = _simulate(model, u, ctx), _simulate(back, u, ctx, "the model read back's simulate(u)")
    if not np.array_equal(y, y_back):
        k = int(np.flatnonzero(~(y == y_back))[0])
        _fail(f"the model read back simulates another output: {y_back[k]!r}, not {y[k]!r}, at "
              f"sample {k}")


def _check_save_load_settings(ctx):
    model = ctx.model()
    settings, text = _settings(model)
    if settings is None:
        return "not applicable: no free parameter"
    held = _new(model, settings, "with_parameters(Parameters)")
    difference = _parameter_difference(_round_trip(held).parameters, held.parameters,
                                       exact_values=True)
    if difference:
        _fail(f"a model with {text}, written and read back, lost them: {difference}")


def _difference_column(run, model, name, par, scale, reference):
    """``d run / d value`` of ``name`` by a difference quotient inside its bounds, and its rounding.

    See :func:`check_model`'s Notes.
    """
    x, (lo, hi) = par.value, par.bounds
    h = _EPS ** (1 / 3) * (abs(x) if x != 0 else 1.0)
    h = min(h, (hi - lo) / 4)

    def at(v):
        try:
            return np.asarray(run(model.with_parameters({name: v})), dtype=np.float64)
        except Exception as exc:
            _fail(f"the model with {name} = {v!r} (a difference step inside its bounds) could not "
                  f"be evaluated: {type(exc).__name__}: {exc}")

    if lo <= x - h and x + h <= hi:
        column, weight = (at(x + h) - at(x - h)) / (2 * h), 1.0
    elif x + 2 * h <= hi:                       # at the lower bound: one-sided, second order
        column, weight = (-3 * reference + 4 * at(x + h) - at(x + 2 * h)) / (2 * h), 4.0
    else:                                       # at the upper bound
        column, weight = (3 * reference - 4 * at(x - h) + at(x - 2 * h)) / (2 * h), 4.0
    return column, weight * _SIMULATION_EPS * scale / h


def _compare_columns(model, jac, run, reference, rtol, what):
    params = model.parameters
    scale = float(np.max(np.abs(reference))) if reference.size else 0.0
    for j, (name, par) in enumerate(params.items()):
        if par.tie is not None:
            continue                            # it follows its source; no value of its own
        column, rounding = _difference_column(run, model, name, par, scale, reference)
        size = max(float(np.max(np.abs(column), initial=0.0)),
                   float(np.max(np.abs(jac[:, j]), initial=0.0)))
        error = float(np.max(np.abs(jac[:, j] - column), initial=0.0))
        if error > rtol * size + rounding:
            k = int(np.argmax(np.abs(jac[:, j] - column)))
            _fail(f"{what} column {j} ({name!r}) differs from the difference quotient by {error:.3g} "
                  f"(at row {k}: {jac[k, j]!r} against {column[k]!r}); allowed {rtol:g} of the "
                  f"column's largest entry {size:.3g} plus rounding {rounding:.3g}")


def _pair(out, what, shape0, n_parameters):
    if not (isinstance(out, tuple) and len(out) == 2):
        _fail(f"{what} must return None or a pair (values, J); got {type(out).__name__}")
    values, jac = (np.asarray(a, dtype=np.float64) for a in out)
    if values.ndim != 1 or (shape0 is not None and values.shape != (shape0,)):
        want = f"({shape0},)" if shape0 is not None else "1-D"
        _fail(f"{what}'s values must have shape {want}; got {values.shape}")
    if jac.shape != (values.size, n_parameters):
        _fail(f"{what}'s J must have shape {(values.size, n_parameters)} (one column per parameter, "
              f"fixed and tied included); got {jac.shape}")
    for label, a in (("values", values), ("J", jac)):
        if not np.all(np.isfinite(a)):
            _fail(f"{what}'s {label} are not all finite")
    return values, jac


def _check_jacobian(ctx):
    model = ctx.model()
    u = ctx.input(model)
    try:
        out = model.jacobian(u)
    except Exception as exc:
        _fail(f"jacobian(u) raised {type(exc).__name__}: {exc}{ctx.about_u()}")
    if out is None:
        return "not applicable: the kind has no exact jacobian"
    yhat, jac = _pair(out, "jacobian(u)", u.shape[0], len(model.parameters))
    y = np.asarray(_simulate(model, u, ctx), dtype=np.float64)
    scale = float(np.max(np.abs(y)))
    error = float(np.max(np.abs(yhat - y)))
    if error > _SIMULATION_EPS * scale:
        _fail(f"jacobian(u)'s output differs from simulate(u) by {error:.3g} (allowed the rounding "
              f"{_SIMULATION_EPS:.3g} of its largest value {scale:.3g})")
    _compare_columns(model, jac, lambda m: m.simulate(u), y, ctx.rtol, "jacobian(u)'s")


def _same_kind(model, other, what):
    if type(other) is not type(model):
        _fail(f"{what} gave a {type(other).__name__}, not a {type(model).__name__}")
    names = other.parameters.names
    if names != model.parameters.names:
        _fail(f"{what} gave a model with the parameters {list(names)}, not "
              f"{list(model.parameters.names)}")


def _check_starts(ctx):
    model = ctx.model()
    u = ctx.input(model)
    y = _simulate(model, u, ctx)
    try:
        starts = list(model.starts(u, y))
    except Exception as exc:
        _fail(f"starts(u, y) raised {type(exc).__name__}: {exc}")
    if not starts:
        _fail("starts(u, y) gave no start (the default is [model])")
    for k, start in enumerate(starts):
        _same_kind(model, start, f"starts(u, y)[{k}]")


def _check_linear_start(ctx):
    model = ctx.model()
    u = ctx.input(model)
    y = _simulate(model, u, ctx)
    try:
        start = model.linear_start(u, y)
    except Exception as exc:
        _fail(f"linear_start(u, y) raised {type(exc).__name__}: {exc}")
    if start is None:
        return "not applicable: the kind has no linear start"
    _same_kind(model, start, "linear_start(u, y)")


def _check_frequency_response(ctx):
    model = ctx.model()
    response = getattr(model, "frequency_response", None)
    if not callable(response):
        return "not applicable: the kind has no frequency_response"
    omega = np.geomspace(1e-3, 1.0, 9) * math.pi / float(model.dt)   # up to the Nyquist frequency
    try:
        g = response(omega)
    except Exception as exc:
        _fail(f"frequency_response(omega) raised {type(exc).__name__}: {exc}")
    if g is None:               # fohw.Model's default: the kind has none
        return "not applicable: the kind has no frequency_response"
    if not isinstance(g, np.ndarray) or not np.iscomplexobj(g):
        _fail(f"frequency_response(omega) must return a complex array; got "
              f"{getattr(g, 'dtype', type(g).__name__)}")
    if g.shape != omega.shape:
        _fail(f"frequency_response(omega) must have omega's shape {omega.shape}; got {g.shape}")
    if not np.all(np.isfinite(g)):
        _fail(f"frequency_response(omega) is not finite at omega = {omega[~np.isfinite(g)]}")


def _check_penalty(ctx):
    model = ctx.model()
    out = model.penalty()
    if out is None:
        return "not applicable: the kind has no penalty"
    r, jac = _pair(out, "penalty()", None, len(model.parameters))
    _compare_columns(model, jac, lambda m: m.penalty()[0], r, ctx.rtol, "penalty()'s")


#: ``name -> check``, in the order :func:`check_model` runs them.
_CHECKS = {
    "parameters": _check_parameters,
    "n_inputs": _check_n_inputs,
    "dt": _check_dt,
    "simulate": _check_simulate,
    "simulate_deterministic": _check_simulate_deterministic,
    "simulate_leaves_input": _check_simulate_leaves_input,
    "refuses_wrong_columns": _check_refuses_wrong_columns,
    "with_parameters_values": _check_with_parameters_values,
    "with_parameters_settings": _check_with_parameters_settings,
    "with_parameters_does_not_mutate": _check_with_parameters_does_not_mutate,
    "equality": _check_equality,
    "config_json": _check_config_json,
    "save_load": _check_save_load,
    "save_load_settings": _check_save_load_settings,
    "jacobian": _check_jacobian,
    "starts": _check_starts,
    "linear_start": _check_linear_start,
    "frequency_response": _check_frequency_response,
    "penalty": _check_penalty,
}

#: The names of the checks, in the order :func:`check_model` runs them (see its Notes).
CHECKS = tuple(_CHECKS)


def _selected(checks):
    if checks is None:
        return CHECKS
    if isinstance(checks, str):
        checks = [checks]
    checks = list(checks)
    unknown = [c for c in checks if c not in _CHECKS]
    if unknown:
        raise ParameterError(f"`checks` has unknown check(s) {unknown}; known: {list(CHECKS)}.")
    return tuple(c for c in CHECKS if c in checks)


def _context(factory, u, rtol):
    if not (isinstance(factory, Model) or callable(factory)):
        raise ParameterError(f"`factory` must be a fohw.Model or a callable returning one; got "
                             f"{type(factory).__name__}.")
    rtol = float(rtol)
    if not (math.isfinite(rtol) and rtol > 0):
        raise ParameterError(f"`rtol` must be positive and finite; got {rtol!r}.")
    ctx = _Context(factory, u, rtol)
    ctx.kind = type(ctx.model()).kind_name()    # a factory that gives no model: refused now
    return ctx


def _run(ctx, name):
    """Run one check; its outcome (``"passed"`` or ``"not applicable: ..."``), or raise."""
    try:
        outcome = _CHECKS[name](ctx)
    except _Failed as failed:
        raise ModelCheckError(name, ctx.kind, str(failed)) from None
    except Exception as exc:
        raise ModelCheckError(name, ctx.kind, f"{type(exc).__name__}: {exc}") from exc
    return outcome or "passed"


def check_model(factory, *, u=None, checks=None, rtol=1e-6):
    """Check that a model kind follows the :class:`fohw.Model` protocol, naming a failed check.

    Parameters
    ----------
    factory : callable or fohw.Model
        A zero-argument callable returning a model of the kind (the class itself, when its
        constructor has defaults), or a model (each check then gets a deep copy). Each check
        gets a fresh model, so one check's damage cannot hide in another.
    u : array_like, optional
        An input the kind takes, shape ``(N,)`` or ``(N, n_inputs)``. The default is 100
        standard normal samples (seed 0) in ``n_inputs`` columns; pass one for a kind whose
        inputs need other ranges (a circuit's ``[current, soc]`` with ``soc`` in [0, 1]).
    checks : iterable of str, optional
        The names of the checks to run (of :data:`CHECKS`); default all.
    rtol : float, default 1e-6
        The tolerance of the exact Jacobian and the penalty's Jacobian against difference
        quotients, relative to the column's largest entry (see Notes).

    Returns
    -------
    dict
        ``{check: "passed" or "not applicable: why"}`` in the order run (a hook the kind does not
        have, such as an exact Jacobian, is not applicable).

    Raises
    ------
    ModelCheckError
        The first check that fails, by name, with what it found (an :class:`AssertionError`).
    fohw.ParameterError
        ``factory`` gives no model, ``checks`` names an unknown check, ``rtol`` is not positive.

    Notes
    -----
    The checks, in order (:data:`CHECKS`):

    ``parameters``
        ``parameters`` is a :class:`fohw.Parameters` (unique names), not empty, the same on
        every read.
    ``n_inputs``, ``dt``
        A positive integer; a positive finite number.
    ``simulate``
        ``simulate(u)`` is a float ``ndarray`` of shape ``(N,)``, finite.
    ``simulate_deterministic``
        Simulating ``u`` again, after another input, gives the same output bit for bit.
    ``simulate_leaves_input``
        ``simulate`` does not write into the caller's ``u``.
    ``refuses_wrong_columns``
        ``check_input`` and ``simulate`` refuse an input with one column too few or too many
        with a ``ValueError`` (:class:`fohw.DimensionError`).
    ``with_parameters_values``
        ``with_parameters({name: value})`` (every free parameter moved by 1e-3 of its scale,
        inside its bounds) gives a model of the same class with those values (to 8 eps) and
        the same bounds, fixed flags, ties and order flags.
    ``with_parameters_settings``
        ``with_parameters(parameters)`` with the first free parameter fixed and the last one's
        bounds narrowed keeps those settings, and a later ``with_parameters({name: value})``
        (what a fit does) keeps them too.
    ``with_parameters_does_not_mutate``
        Neither form of ``with_parameters`` changes the original's parameters, config or output.
    ``equality``
        A deep copy and ``with_parameters`` of its own values are ``==`` the model; other values
        and a non-model are not.
    ``config_json``
        ``config()`` is a dict of JSON values.
    ``save_load``
        :func:`fohw.save_model` and :func:`fohw.load_model` through a temporary file give a model
        of the same class, ``==``, with exactly the same parameters and output.
    ``save_load_settings``
        The same for a model with a fixed parameter and narrowed bounds: they are read back.
    ``jacobian``
        Where ``jacobian(u)`` is not ``None``: its output is ``simulate(u)`` (to the rounding
        below) and every column (fixed ones included; tied ones follow their source and are
        skipped) agrees with a difference quotient of ``simulate`` at the kind's own scale: the
        step is ``eps^(1/3) |value|`` (``eps^(1/3)`` at 0), central inside the bounds and
        one-sided of second order at a bound. Its truncation error is of order ``eps^(2/3)``
        (4e-11) of the column, far below ``rtol``; its rounding is bounded as that of a
        simulator accurate to ``32 eps`` of its largest output, ``32 eps max|y| / step`` (4 times
        that one-sided). A column passes when it is within ``rtol`` of its largest entry plus
        that rounding.
    ``starts``, ``linear_start``
        ``starts(u, y)`` (``y`` the model's own output) is a non-empty list of models of the same
        class and parameter names; ``linear_start(u, y)`` is ``None`` or such a model.
    ``frequency_response``
        Where the kind has one: at 9 frequencies up to the Nyquist frequency ``pi / dt``, a
        complex array of omega's shape, finite.
    ``penalty``
        Where ``penalty()`` is not ``None``: a pair ``(r, J)``, ``r`` 1-D, ``J`` one column per
        parameter, finite, ``J`` against difference quotients of ``r`` as for ``jacobian``.

    Examples
    --------
    The first-order lag of :class:`fohw.Model`'s example follows the protocol:

    >>> import numpy as np
    >>> import fohw
    >>> import fohw.testing
    >>> class Lag(fohw.Model):
    ...     def __init__(self, a=0.5, b=1.0):
    ...         self.a, self.b = a, b
    ...     @property
    ...     def parameters(self):
    ...         return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
    ...                                 fohw.Parameter("b", self.b)])
    ...     def with_parameters(self, values):
    ...         v = self.parameters.with_values(values).valuesdict()
    ...         return type(self)(v["a"], v["b"])
    ...     def simulate(self, u, *, initial=None):
    ...         u = self.check_input(u)
    ...         y = np.zeros_like(u)
    ...         for k in range(1, u.size):
    ...             y[k] = self.a * y[k - 1] + self.b * u[k - 1]
    ...         return y
    >>> report = fohw.testing.check_model(Lag)
    >>> report["simulate"], report["jacobian"]
    ('passed', 'not applicable: the kind has no exact jacobian')

    A lag whose copies forget the new values fails, naming the check:

    >>> class Forgetful(Lag):
    ...     def with_parameters(self, values):
    ...         return Forgetful(self.a, self.b)
    >>> fohw.testing.check_model(Forgetful)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fohw.testing.ModelCheckError: Forgetful: check 'with_parameters_values' failed: ...
    gave a model whose parameters differ: 'a' has the value 0.5, not 0.501
    """
    ctx = _context(factory, u, rtol)
    return {name: _run(ctx, name) for name in _selected(checks)}


class _Check:
    """One check of one kind, as a zero-argument callable (raises :class:`ModelCheckError`)."""

    def __init__(self, ctx, label, name):
        self._ctx, self.label, self.name = ctx, label, name

    def __call__(self):
        return _run(self._ctx, self.name)

    def __repr__(self):
        return f"{self.label}-{self.name}"


def _label(factory):
    name = getattr(factory, "__name__", None)
    if isinstance(name, str) and not isinstance(factory, Model):
        return name
    model = factory if isinstance(factory, Model) else factory()
    return type(model).kind_name()


def iter_checks(factory, *, u=None, checks=None, rtol=1e-6):
    """The checks of :func:`check_model`, one callable each, to run or parametrize separately.

    Parameters
    ----------
    factory, u, checks, rtol
        As for :func:`check_model`.

    Yields
    ------
    check : callable
        A zero-argument callable that runs one check on a fresh model and returns its outcome
        (``"passed"`` or ``"not applicable: why"``) or raises :class:`ModelCheckError`. Its
        ``name`` is the check's, its ``label`` the factory's name and its ``repr``
        ``"label-name"``.

    Examples
    --------
    >>> import fohw, fohw.testing
    >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    >>> outcomes = {check.name: check() for check in fohw.testing.iter_checks(G)}
    >>> outcomes["jacobian"], outcomes["penalty"]
    ('passed', 'not applicable: the kind has no penalty')
    """
    ctx = _context(factory, u, rtol)
    label = _label(factory)
    for name in _selected(checks):
        yield _Check(ctx, label, name)


def parametrize_with_checks(factories, *, checks=None, rtol=1e-6):
    """A ``pytest.mark.parametrize`` decorator: one test per kind and check.

    Needs pytest (imported here, not by fohw).

    Parameters
    ----------
    factories : iterable
        Each a factory or model as for :func:`check_model`, or a pair ``(factory, u)`` for a kind
        whose input needs other ranges.
    checks, rtol
        As for :func:`check_model`.

    Returns
    -------
    decorator
        Parametrizes the argument ``model_check``: call it in the test (it raises
        :class:`ModelCheckError` on a failure). Test ids are ``"factory-check"``.

    Examples
    --------
    In a test module::

        import fohw.testing

        @fohw.testing.parametrize_with_checks([MyKind, (my_circuit, u_cell)])
        def test_my_kinds(model_check):
            model_check()
    """
    import pytest

    params = []
    for entry in factories:
        factory, u = entry if isinstance(entry, tuple) else (entry, None)
        params.extend(iter_checks(factory, u=u, checks=checks, rtol=rtol))
    return pytest.mark.parametrize("model_check", params, ids=[repr(p) for p in params])
