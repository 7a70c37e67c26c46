"""The simulator: the output of any fractional-order Hammerstein–Wiener model (Eqs. 14, 16).

:func:`simulate` runs a :class:`fohw.HammersteinWiener`, an identification result (its fitted
predictor, any theta) or a :class:`fohw.Structure` with parameter values, through one engine:

* :func:`forcing`: everything in ``y[k]`` that does not feed back (noise, offset, the input
  branch by FFT, the transients of past levels);
* :func:`recursion`: the output feedback, sample by sample in leaves (pure Python, or compiled by
  :mod:`fohw.model._compiled`) joined by FFT merges (:mod:`fohw.model.kernels`), ``O(N log^2 N)``;
* :func:`free_run`: the two in deviation coordinates, with a measured history and the divergence
  test (:data:`FAST_SIMULATION_THRESHOLD`, :data:`LEAF_SIZE`, :data:`LEAF_SIZE_COMPILED`).

Every order is checked against one rule, the closed interval
:data:`fohw.model.orders.ORDER_RANGE` ``= [0, 2]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from .._types import ArrayLike, PairLike, RandomStateLike
from .._validation import (
    check_array,
    check_inputs,
    check_pair,
    check_random_state,
    check_same_length,
    check_scalar,
    unpack_pair,
)
from ..exceptions import (
    DimensionError,
    FohwError,
    ModelHookError,
    ParameterError,
    SimulationDivergedError,
)
from . import _compiled
from .base import Model
from .gl import gl_weights, gl_weights_unchecked, past_transient
from .kernels import HalfMerge, causal_convolve, divide_and_conquer
from .structure import Structure

__all__ = ["simulate", "simulate_record", "check_record_sampling", "record_list", "own_dt",
           "generic_model", "read_only", "hook_error", "call_hook", "HOOK_REFUSALS",
           "simulate_predictor", "equation_noise", "free_run",
           "forcing", "recursion", "accumulators", "output_terms", "Accumulators", "apply_output_map",
           "check_input_point", "FAST_SIMULATION_THRESHOLD", "LEAF_SIZE", "LEAF_SIZE_COMPILED"]

#: Below this record length the simulator runs the recursion directly (one dot product per
#: output signal and sample); above it, by divide and conquer (:func:`recursion`).
FAST_SIMULATION_THRESHOLD = 8192
#: Leaf sizes of the divide and conquer for the pure-Python and the compiled leaf, chosen by
#: ``benchmarks/bench_simulator.py --leaves`` (64 to 1024 measured at N = 10**5 and 10**6):
#: 256 is the fastest pure leaf; the compiled one is about 10 % faster at 512, but equal sizes
#: make the two leaves give identical numbers, so installing numba (or loading it part-way
#: through a process) changes no simulation.
LEAF_SIZE = 256
LEAF_SIZE_COMPILED = 256


def simulate(model: Model | Structure | Any, u: ArrayLike, *,
             params: ArrayLike | Mapping[str, float] | None = None,
             operating_point: PairLike | None = None, noise: ArrayLike | None = None,
             noise_std: float = 0.0, random_state: RandomStateLike = None,
             divergence_threshold: float | None = None,
             initial: Any = None) -> np.ndarray:
    """Simulate the output of a fractional-order Hammerstein–Wiener model.

    Parameters
    ----------
    model : Model, FitResult, HammersteinWiener, IdentificationResult or Structure
        What to simulate: a model (its ``a, b, p, q``); an identification result (its fitted
        predictor: theta itself, the offset, orders and past levels, in the data's units; the
        same as ``result.simulate(u)``; anything with ``structure``, ``linear`` and
        ``nonlinear`` is accepted); or a :class:`fohw.Structure`, whose parameter values are
        then given by ``params``. A :class:`fohw.Model` of any other kind (or a
        :class:`fohw.FitResult`: its fitted model) is simulated by its own
        ``simulate(u, initial=initial)``; the keywords below other than ``initial`` are for
        the lagged kind and are refused with it, by name.
    u : array_like, shape (N,)
        Input signal, finite, in the model's units (its operating point is subtracted inside
        and the output's added back). Shape ``(N, m)`` for a structure (or result) with ``m``
        inputs (:attr:`Structure.n_inputs`; its ``operating_point`` then ``((u0_1, …), y0)``).
        Or a :class:`fohw.Record`: its input, at its sampling time (a record sampled at
        another step than the model's is refused; non-uniform instants need a kind that
        simulates on them); or a list of Records (a list of outputs, one per record).
    params : array_like or dict, optional
        With a Structure only (and required): its linear parameters, then its nonlinear ones
        (:attr:`Structure.linear_names` then :attr:`Structure.nonlinear_names`: theta in the
        layout of :class:`fohw.model.params.ThetaLayout`, any theta, not only ``[q ⊗ a, p ⊗ b]``; the
        offset; the free orders, each in ``[0, 2]``; the past levels), as a vector in that
        order or a dict by name.
    operating_point : (float, float), optional
        With a Structure only: ``(u0, y0)``. Default ``(0, 0)``. A model or a result carries
        its own.
    noise : array_like, shape (N,), optional
        The equation noise ``v[k]`` added at every sample. Mutually exclusive with
        ``noise_std > 0``.
    noise_std : float, optional
        Standard deviation of white Gaussian ``v[k]`` drawn from ``random_state``. Default 0.
    random_state : None, int or numpy.random.Generator, optional
        Source of the noise when ``noise_std > 0``.
    divergence_threshold : float, optional
        The output is declared divergent when ``|y[k]|`` (deviation from the operating point)
        exceeds this or is not finite. Default: ``1e8`` times the largest magnitude that drives
        the recursion (input branch, noise, offset, past levels, history), so the test means the
        same in every unit.
    initial : tuple, str or InitialState, optional
        A measured history ``(u_past, y_past)`` just before ``u`` (same units): the simulation
        continues from it, its GL memory holding that history, in free run from the first
        sample of ``u`` (the model's past levels, if any, apply before the history). With an
        identification result, any of its initial states, as ``result.simulate(u,
        initial=...)`` (:mod:`fohw.model.initial`; needed for a ``past="estimate"`` fit).

    Returns
    -------
    y : ndarray, shape (N,)
        The output. To keep the noise realisation, draw it yourself and pass ``noise``.

    Raises
    ------
    SimulationDivergedError
        The output escaped; ``err.sample`` is the first offending index of ``u``.

    Warns
    -----
    ExtrapolationWarning
        For a result whose estimation input ``u`` leaves (``result.simulate``).

    Notes
    -----
    The exact recursion of Eq. (16) (Eq. 14 for a general :class:`fohw.Orders`) with
    full memory: ``y[k]`` uses ``(Delta^nu gbar(y))[k-i]`` for every output term, each the GL
    sum over all of ``gbar(y[0..k-i])``. The input branch is computed once by FFT. Up to
    ``N = 8192`` the output memory is one dot product per sample (``O(N**2)``); above,
    finished halves of the record enter later samples through FFT convolutions
    (``O(N log^2 N)``), equal to the direct recursion to rounding: 0.38 s at ``N = 10**5`` and
    3.9 s at ``10**6`` with the per-sample loop in Python, 0.078 s and 0.88 s when the optional
    ``fast`` extra (numba) compiles it for a polynomial output basis (identical numbers; loaded
    once per process, for simulations of at least ``2**18`` samples or once that many have
    run; docs/performance.md, measured on an idle 2-core machine).

    A structure with a series output map (:attr:`Structure.output_map`) gives
    ``h(z; h_*)``, ``z`` the recursion's output in the data's units (the operating point added
    back), with the map's parameters last in ``params``; a measured ``history`` enters the
    recursion through the map's inverse.

    A model is simulated through its rank-one blocks (``gbar`` fed back once); a result or a
    structure through theta's blocks, one signal per basis function or per output term,
    whichever is fewer. The two agree to rounding for a theta of the form ``[q ⊗ a, p ⊗ b]``.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> model = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
    >>> u = np.array([1.0, 0.0, 0.0, 0.0])
    >>> fohw.simulate(model, u).round(4)
    array([ 0.    , -0.6   ,  0.0176,  0.1945])

    Any theta of a structure, with the order after it (``structure.linear_names``, then
    ``structure.nonlinear_names``):

    >>> s = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3)
    >>> u = np.random.default_rng(0).uniform(-1, 1, 300)
    >>> y = fohw.simulate(s, u, params=np.r_[model.theta, 0.6])
    >>> bool(np.max(np.abs(y - fohw.simulate(model, u))) < 1e-13)
    True
    """
    kinds = ("a HammersteinWiener, an identification result or a Structure with `params` (or "
             "a fohw.Model of any other kind, or its fohw.FitResult)")
    records = record_list(u)
    if records is not None:
        kwargs = dict(params=params, operating_point=operating_point, noise=noise,
                      noise_std=noise_std, random_state=random_state,
                      divergence_threshold=divergence_threshold, initial=initial)
        out = [simulate_record(model, r, **kwargs) for r in records]
        return out if isinstance(u, (list, tuple)) else out[0]
    other = generic_model(model)
    if other is not None:
        lagged = {"params": params, "operating_point": operating_point, "noise": noise,
                  "noise_std": noise_std or None, "random_state": random_state,
                  "divergence_threshold": divergence_threshold}
        given = [f"{k}={v!r}" for k, v in lagged.items() if v is not None]
        if given:
            raise ParameterError(f"{', '.join(given)}: these keywords are for the lagged "
                                 f"HammersteinWiener kind; a {type(other).__name__} is simulated "
                                 "by its own simulate(u, initial=...) (add noise to the output "
                                 "yourself).")
        # the caller's array read-only: a kind never changes it
        return call_hook(other, "simulate", read_only(u), initial=initial)
    if (isinstance(initial, str) and initial == "estimate") or (
            isinstance(initial, tuple) and initial and isinstance(initial[0], str)
            and initial[0] == "estimate"):
        raise ParameterError("initial='estimate' fits the record's initial state to its "
                             "measured output, which fohw.simulate does not take: use "
                             "result.simulate(u, initial='estimate', y=y) or "
                             "fohw.compare(result, u, y, initial='estimate').")
    result = callable(getattr(model, "initial_state", None))
    history = None if result else measured_history(initial, type(model).__name__)
    if isinstance(model, Model):        # a model kind (the lagged HammersteinWiener among them)
        _only_for_structure(params, operating_point, f"a {type(model).__name__}")
        return model.simulate(read_only(u), noise=noise, noise_std=noise_std, random_state=random_state,
                              divergence_threshold=divergence_threshold, initial=history)
    if isinstance(model, Structure):
        if params is None:
            raise ParameterError("simulating a Structure needs its parameter values `params` "
                                 f"{model.linear_names + model.nonlinear_names}.")
        linear, nonlinear = _split_params(model, params)
        return simulate_predictor(
            model, linear, nonlinear, u,
            operating_point=(0.0, 0.0) if operating_point is None else operating_point,
            noise=noise, noise_std=noise_std, random_state=random_state,
            divergence_threshold=divergence_threshold, history=history)
    if all(hasattr(model, name) for name in ("structure", "linear", "nonlinear")) \
            and isinstance(model.structure, Structure):
        _only_for_structure(params, operating_point, "an identification result")
        kwargs = dict(noise=noise, noise_std=noise_std, random_state=random_state,
                      divergence_threshold=divergence_threshold)
        own = getattr(model, "simulate", None)
        if callable(own):          # a result: its own checks (input range), then this engine
            return own(u, **kwargs) if initial is None else own(u, initial=initial, **kwargs)
        return simulate(model.structure, u, params=np.r_[model.linear, model.nonlinear],
                        operating_point=getattr(model, "operating_point", (0.0, 0.0)), **kwargs)
    raise ParameterError(f"`model` must be {kinds}; got {type(model).__name__}.")


#: What a kind's hook may raise as a refusal that fohw's engines handle themselves (fohw's own
#: errors: values the kind refuses, a run that diverges; arithmetic and linear-algebra failures).
#: Anything else a hook raises is a fault of the kind (:func:`hook_error`).
HOOK_REFUSALS = (FohwError, ArithmeticError, np.linalg.LinAlgError)


def read_only(a):
    """``a`` as a read-only view when it is a writable ndarray (else as it is).

    What fohw hands a kind of the caller's data: a kind that writes into its input then fails
    (:func:`hook_error` says so) instead of changing the caller's array.
    """
    if isinstance(a, np.ndarray) and a.flags.writeable:
        a = a.view()
        a.flags.writeable = False
    return a


def hook_error(model, hook, exc):
    """The :class:`fohw.exceptions.ModelHookError` for ``exc``, raised by ``model``'s ``hook``.

    Raise it ``from exc`` (the kind's traceback stays attached). A write into the read-only
    input (:func:`read_only`) is named as such.
    """
    kind = type(model).__name__
    text = str(exc).strip()
    said = f"{kind}.{hook} raised {type(exc).__name__}" + (f": {text}" if text else "")
    if isinstance(exc, ValueError) and "read-only" in text:
        advice = (f"fohw hands a kind the caller's data read-only, so that it is never changed: "
                  f"{kind}.{hook} must not write into its input; copy it first (np.array(u)).")
    else:
        advice = (f"A kind refuses values with fohw's ParameterError (or returns an output that "
                  f"diverges); any other exception is a fault of the kind: fix {kind}.{hook} "
                  "(fohw.testing.check_model tests a kind).")
    return ModelHookError(f"{said.rstrip('.')}. {advice}", hook)


def call_hook(model, hook, *args, **kwargs):
    """``model.<hook>(*args, **kwargs)``, a kind's fault named.

    An exception other than a refusal (:data:`HOOK_REFUSALS`) becomes a
    :class:`fohw.exceptions.ModelHookError` naming the kind and the hook.
    """
    try:
        return getattr(model, hook)(*args, **kwargs)
    except HOOK_REFUSALS:
        raise
    except Exception as exc:                    # noqa: BLE001 - the kind's fault, named
        raise hook_error(model, hook, exc) from exc


def record_list(data):
    """``data`` as a list of :class:`fohw.Record`, or ``None`` when it is not one or a list of them.

    The Record lives in a layer above the model's; it is known here by its fields.
    """
    def is_record(obj):
        return all(hasattr(obj, n) for n in ("u", "y", "t", "dt", "intersample", "input_names"))

    if is_record(data):
        return [data]
    if isinstance(data, (list, tuple)) and data and all(is_record(r) for r in data):
        return list(data)
    return None


def own_dt(model):
    """The step a model (or result, or structure) keeps as a setting; None for one in samples."""
    structure = model if isinstance(model, Structure) else getattr(model, "structure", None)
    if isinstance(structure, Structure):
        return float(structure.dt)
    other = generic_model(model)
    if other is None:
        return None
    try:
        config = other.config()
    except ParameterError:                      # a setting no file holds (a Python OCV map)
        return None if type(other).dt is Model.dt else float(other.dt)
    return float(other.dt) if "dt" in config else None


def check_record_sampling(model, record):
    """A record's sampling checked against ``model``: its ``simulate_at`` on instants, or None.

    Refuses a :class:`fohw.Record` sampled at another step than ``model``'s, and non-uniform
    instants where the kind has no ``simulate_at``. fohw never changes a sampling time
    silently: a record at 4 s and a model at 1 s are two different systems.
    """
    dt = own_dt(model)
    named = f" {record.name!r}" if record.name else ""
    # 1e-6: fohw.record.UNIFORM_RTOL (a layer above the model's), the tolerance fohw.fit uses
    if record.t is None and record.dt is not None and dt is not None \
            and abs(record.dt - dt) > 1e-6 * record.dt:
        raise ParameterError(
            f"the record{named} is sampled every {record.dt!r} {record.time_unit}".rstrip()
            + f" but the model has dt = {dt!r}; use a model at dt={record.dt!r} (the record's "
            "sampling time): fohw does not change it silently.")
    if record.t is None and record.intersample == "zoh":
        return None                     # held between uniform samples: the kind's simulate
    other = generic_model(model)
    simulate_at = getattr(other, "simulate_at", None)
    if simulate_at is None:
        raise ParameterError(
            f"the record{named} has non-uniform time stamps (or a first-order hold) and a "
            f"{type(other or model).__name__} has no simulator between samples (`simulate_at`); "
            "resample the record to a uniform grid (e.g. numpy.interp at t[0] + k*dt) or use a "
            "kind that simulates on time stamps.")
    return simulate_at


def simulate_record(model, record, **kwargs):
    """:func:`simulate` on a :class:`fohw.Record`: its input, at its sampling.

    The sampling is checked by :func:`check_record_sampling`; non-uniform instants (and a
    first-order hold) are run by the kind's ``simulate_at`` with the record's ``intersample``,
    from rest, as :func:`fohw.fit` runs them.
    """
    simulate_at = check_record_sampling(model, record)
    if simulate_at is not None:
        given = [k for k, v in kwargs.items() if (v if k == "noise_std" else v is not None)]
        if given:
            raise ParameterError(f"{', '.join(given)}: not taken on time stamps (the kind's "
                                 "simulate_at runs from rest, noise-free).")
        u = generic_model(model).check_input(record.u)
        return np.asarray(simulate_at(u, np.asarray(record.time), intersample=record.intersample),
                          dtype=float)
    return simulate(model, record.u, **kwargs)


def measured_history(initial, what):
    """``initial`` of a model or a structure: ``None`` or a measured pair ``(u_past, y_past)``.

    The other initial states (``"rest"``, ``"fitted"``, ``"estimate"``, an InitialState) belong
    to an identification result, whose fitted levels they read.
    """
    if initial is None:
        return None
    if isinstance(initial, Mapping):
        unpack_pair(initial, "initial", "(u_past, y_past) of measured records")
    if isinstance(initial, str) or not isinstance(initial, (tuple, list)) or len(initial) != 2:
        raise ParameterError(f"`initial` of a {what} is a measured history (u_past, y_past); "
                             f"the initial states {initial!r}-like belong to an identification "
                             "result (result.simulate(u, initial=...), or fohw.compare).")
    return tuple(initial)


def generic_model(obj):
    """The :class:`fohw.Model` behind ``obj`` when it is not of the lagged kind, else None.

    ``obj`` a model of any kind but :class:`fohw.HammersteinWiener`, or a fit result of one
    (anything but an :class:`fohw.IdentificationResult` whose ``model`` is a Model, e.g. a
    :class:`fohw.FitResult`, whatever its kind): the verbs' generic branches take it; a
    HammersteinWiener, a Structure and an IdentificationResult keep the lagged paths.
    """
    if isinstance(obj, Structure) or isinstance(getattr(obj, "structure", None), Structure):
        return None                    # the lagged kind: a Structure, a model or a result of one
    if isinstance(obj, Model):
        return obj
    inner = getattr(obj, "model", None)
    return inner if isinstance(inner, Model) else None


def _only_for_structure(params, operating_point, what):
    for value, name in ((params, "params"), (operating_point, "operating_point")):
        if value is not None:
            raise ParameterError(f"`{name}` is for a Structure; {what} carries its own; got "
                                 f"{value!r}.")


def _split_params(structure, params):
    """``(linear, nonlinear)`` from ``params`` (a vector or a dict by name), checked."""
    names = structure.linear_names + structure.nonlinear_names
    if isinstance(params, Mapping):
        missing = [n for n in names if n not in params]
        extra = [n for n in params if n not in names]
        if missing or extra:
            raise ParameterError(f"`params` must give the parameters {names}; missing {missing}, "
                                 f"unknown {extra}.")
        params = [params[n] for n in names]
    params = check_array(params, "params")
    if params.shape[0] != len(names):
        raise DimensionError(f"`params` must have {len(names)} entries {names}; got "
                             f"{params.shape[0]}.")
    k = structure.n_linear
    values, _ = structure.split_nonlinear(params[k:])
    structure.orders.free_mapping(values, "params")          # the one rule: each order in [0, 2]
    return params[:k], params[k:]


def simulate_model(model, u, *, noise=None, noise_std=0.0, random_state=None,
                   divergence_threshold=None, history=None):
    """A model through its rank-one blocks: ``gbar`` is the one output signal fed back."""
    u = check_array(u, "u")
    v = equation_noise(u.shape[0], noise, noise_std, random_state)
    return free_run(model.structure, model.q[:, None], model.a[None, :],
                    np.outer(model.q, model.a), np.outer(model.p, model.b), model.orders, u, v,
                    offset=model.offset, past=model.past, operating_point=model.operating_point,
                    threshold=_check_threshold(divergence_threshold), history=history)


def simulate_predictor(structure, linear, nonlinear, u, *, operating_point=(0.0, 0.0), noise=None,
                       noise_std=0.0, random_state=None, divergence_threshold=None,
                       history=None):
    """Any theta of a structure (the predictor an estimator fitted, before Eqs. 39–40).

    :func:`simulate` of a Structure, for callers inside the package that checked the orders
    themselves (an estimator inside its bounds): they are used as given, any finite order (as
    :func:`fohw.gl_weights` allows), so that a finite difference may step across a bound.
    ``linear``, ``nonlinear``: :attr:`Structure.linear_names`, :attr:`Structure.nonlinear_names`.
    """
    layout = structure.layout
    linear = check_array(linear, "linear")
    nonlinear = np.atleast_1d(check_array(nonlinear, "params", ndim=None, min_length=0))
    for value, names, name in ((linear, structure.linear_names, "linear"),
                               (nonlinear, structure.nonlinear_names, "params")):
        if value.shape[0] != len(names):
            raise DimensionError(f"`{name}` must have {len(names)} entries {names}; got "
                                 f"{value.shape[0]}.")
    qa, pb = layout.blocks(linear[:layout.n_params])
    offset = float(linear[layout.n_params]) if structure.offset else 0.0
    values, past = structure.split_nonlinear(nonlinear)
    u = check_inputs(u, structure.n_inputs, names=structure.inputs)
    v = equation_noise(u.shape[0], noise, noise_std, random_state)
    Q, A = _output_representation(qa)
    hmap = structure.output_map
    if hmap is not None:
        eta = hmap.check_params(structure.output_map_params(nonlinear))
        if history is not None:            # the recursion's memory holds z, not y = h(z)
            u_hist, y_hist = _check_history(history)
            history = (u_hist, hmap.inverse(y_hist, eta))
    point = (check_pair(operating_point, "operating_point") if structure.n_inputs == 1 else
             check_input_point(operating_point, structure.n_inputs))
    z = free_run(structure, Q, A, qa, pb, values, u, v, offset=offset, past=past,
                 operating_point=point,
                 threshold=_check_threshold(divergence_threshold), history=history)
    return z if hmap is None else apply_output_map(hmap, eta, z)


def apply_output_map(output_map, params, z):
    """``y = h(z; params)`` of a series output map (data units), checked to be finite."""
    y = output_map.evaluate(z, params)
    if y.shape != z.shape or not np.all(np.isfinite(y)):
        k = int(np.flatnonzero(~np.isfinite(y))[0]) if y.shape == z.shape else 0
        raise ParameterError(f"the output map {output_map.describe()} returned "
                             f"{'shape ' + str(y.shape) if y.shape != z.shape else y[k]!r} for the "
                             f"model output z{'' if y.shape != z.shape else f'[{k}] = {z[k]!r}'}: "
                             "it must return a finite value per sample.")
    return y


def forcing(pb, in_terms, qa, out_terms, f_basis, g_basis, u, v, h, offset, past):
    """Everything in y[k] that does not feed back: noise, offset, input branch, past levels.

    ``in_terms`` and ``out_terms`` are sequences of ``(lag, order)``; ``pb`` is ``(n_f, n_in)``
    and ``qa`` is ``(n_g, n_out)``, the coefficient of basis function ``j`` in term ``t``.
    """
    n = u.shape[0]
    w = v.copy()
    if offset != 0.0:
        w += offset
    F = f_basis.evaluate(u, "u")
    diffs = {}
    for t, (lag, nu) in enumerate(in_terms):
        if nu not in diffs:
            d = F if nu == 0.0 else causal_convolve(F, gl_weights_unchecked(nu, n))
            diffs[nu] = d if h == 1.0 or nu == 0.0 else d * h**-nu
        if lag < n:
            w[lag:] += pb[:, t] @ diffs[nu][:, : n - lag]
    u_past, y_past = past
    if u_past != 0.0 or y_past != 0.0:
        lf = f_basis.evaluate(np.array([u_past]), "u_past")[:, 0]
        lg = g_basis.evaluate(np.array([y_past]), "y_past")[:, 0]
        for coef, levels, terms in ((pb, lf, in_terms), (qa, lg, out_terms)):
            for t, (lag, nu) in enumerate(terms):
                w += (coef[:, t] @ levels) * past_transient(nu, lag, n, h)
    return w


class Accumulators(NamedTuple):
    """The memories of the output feedback (:func:`accumulators`).

    ``count``: how many; ``terms``: ``(accumulator, lag - 1, coefficient)`` per output term
    and signal; ``memory``: ``(accumulator, signal, index into betas)`` of the accumulators
    with an order > 0; ``memoryless``: ``(accumulator, signal)`` of those of order 0;
    ``betas``: the GL weights of each distinct order > 0.
    """

    count: int
    terms: list
    memory: list
    memoryless: list
    betas: list


def accumulators(A, out_terms, h, n):
    """One accumulator of ``Delta^nu z_r`` per (signal ``r``, distinct order ``nu``) pair.

    ``A[r, t]`` is the coefficient of signal ``r`` in output term ``t`` of ``(lag, order)``
    ``out_terms[t]``; ``h`` the sampling time and ``n`` the record length.
    """
    R = A.shape[0]
    nus = []
    for _, nu in out_terms:
        if nu not in nus:
            nus.append(nu)
    acc = [(r, nu) for r in range(R) for nu in nus]          # accumulator index -> (signal, nu)
    index = {key: a for a, key in enumerate(acc)}
    terms = [(index[r, nu], lag - 1, float(A[r, t]) * (1.0 if h == 1.0 else h**-nu))
             for r in range(R) for t, (lag, nu) in enumerate(out_terms)]
    mem_nus = [nu for nu in nus if nu != 0.0]
    betas = [gl_weights(nu, n) for nu in mem_nus]
    memory = [(a, r, mem_nus.index(nu)) for a, (r, nu) in enumerate(acc) if nu != 0.0]
    memoryless = [(a, r) for a, (r, nu) in enumerate(acc) if nu == 0.0]
    return Accumulators(len(acc), terms, memory, memoryless, betas)


def _leaf_kernel(g_basis, n, kernel):
    """The compiled leaf kernel for ``kernel`` ``"auto"``/``"compiled"``, or ``None`` (pure)."""
    if kernel not in ("auto", "compiled", "pure"):
        raise ParameterError(f"`kernel` must be 'auto', 'compiled' or 'pure'; got {kernel!r}.")
    if kernel == "pure":
        return None
    compiled = _compiled.leaf_for(g_basis, n if kernel == "auto" else _compiled.LOAD_AFTER)
    if compiled is None and kernel == "compiled":
        raise RuntimeError("the compiled leaf is not available (numba missing or disabled, "
                           "or a non-polynomial output basis).")
    return compiled


def recursion(Q, A, out_terms, g_basis, w, threshold, method="auto", h=1.0, y_fixed=None, *,
              kernel="auto", leaf_size=None):
    """``y[k] = w[k] + sum_r sum_t A[r, t] (Delta_h^{nu_t} z_r)[k - lag_t]`` (Eqs. 14, 16).

    ``z_r(y) = sum_j Q[j, r] g_j(y)``: for a model ``Q = q``, ``A = a`` (one signal, gbar);
    for a general theta either ``Q = I, A = qa`` or ``Q = qa, A = I``. ``out_terms[t]`` is the
    ``(lag, order)`` of column ``t`` of ``A``. Every (signal, distinct order) pair has an
    accumulator of ``Delta^nu z_r`` (:func:`accumulators`); order-0 accumulators have no memory
    (``z_r`` itself).

    O(N log^2 N) by divide and conquer over time (:mod:`fohw.model.kernels`): once the first
    half of ``[lo, hi)`` is finished, its contribution to the accumulators on the second half
    is added by FFT (one transform per signal and one inverse per accumulator, the weights'
    spectra computed once per level). Leaves run the recursion sample by sample, one dot
    product per accumulator and sample for the leaf's own past. ``method``: ``"direct"`` is one
    leaf of ``N`` samples (O(N^2)), ``"fast"`` the divide and conquer, ``"auto"`` the latter
    above :data:`FAST_SIMULATION_THRESHOLD` samples. The first ``len(y_fixed)`` outputs are not
    computed but taken from ``y_fixed`` (a measured history).

    ``kernel`` chooses the leaf: ``"auto"`` the compiled leaf (:mod:`fohw.model._compiled`,
    polynomial output bases, numba installed and loaded) or else the pure-Python one;
    ``"pure"``; ``"compiled"`` (an error if it is not available). ``leaf_size`` overrides the
    leaf size of the divide and conquer (:data:`LEAF_SIZE` for the pure leaf,
    :data:`LEAF_SIZE_COMPILED` for the compiled one).
    """
    n = w.shape[0]
    if method == "auto":
        method = "fast" if n > FAST_SIMULATION_THRESHOLD else "direct"
    compiled = _leaf_kernel(g_basis, n, kernel)
    if method == "direct":
        leaf_size = n
    elif leaf_size is None:
        leaf_size = LEAF_SIZE_COMPILED if compiled is not None else LEAF_SIZE
    leaf_size = max(1, min(leaf_size, n))

    acc = accumulators(A, out_terms, h, n)
    merge = HalfMerge(acc.betas, acc.memory)
    y = np.zeros(n)
    z = np.zeros((Q.shape[1], n))
    dz = np.zeros((acc.count, n))      # contributions gathered so far
    rev = np.array([acc.betas[k][:leaf_size][::-1] for _, _, k in acc.memory]).reshape(
        len(acc.memory), leaf_size)
    if compiled is not None:
        leaf = _compiled_leaf(compiled, Q, acc.terms, acc.memory, acc.memoryless, rev, w, y, z,
                              dz, threshold, y_fixed)
    else:
        leaf = _pure_leaf(output_terms(g_basis, Q), acc.terms, acc.memory, acc.memoryless, rev,
                          w, y, z, dz, threshold, y_fixed)
        _compiled.count_pure(n)
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            divide_and_conquer(n, leaf_size, leaf, lambda lo, mid, hi: merge(z, dz, lo, mid, hi))
    except SimulationDivergedError as err:
        if err.cause == "output_basis" and _basis_overflows(g_basis, err.value):
            raise SimulationDivergedError(err.sample, err.value, err.threshold, err.cause,
                                          overflow=True) from None
        raise
    return y


def _basis_overflows(g_basis, y):
    """Whether ``g`` is non-finite at the finite ``y`` by overflow (no function left its domain)."""
    if not np.isfinite(y):
        return False
    x = np.array([float(y)])
    for f in getattr(g_basis, "functions", ()):
        try:
            with np.errstate(over="ignore", invalid="raise", divide="raise"):
                value = np.asarray(f(x), dtype=np.float64)
        except FloatingPointError:
            return False                    # invalid or divide: sqrt, log of a bad value
        except (OverflowError, ArithmeticError):
            continue
        except Exception:                   # a user's function failing otherwise: not known
            return False
        if np.any(np.isnan(value)):
            return False
    return True


def _pure_leaf(zfun, terms, memory, memoryless, rev, w, y, z, dz, threshold, y_fixed):
    """The leaf of :func:`recursion` in Python: ``leaf(lo, hi)`` finishes samples lo..hi-1."""
    import math

    R = z.shape[0]
    L = rev.shape[1]
    w = w.tolist()
    n_fixed = 0 if y_fixed is None else y_fixed.shape[0]
    fixed = [] if y_fixed is None else y_fixed.tolist()
    dz_item = dz.item
    isfinite = math.isfinite
    zrows = list(z)                   # 1-D views, one per output signal
    dzrows = list(dz)
    dot = np.dot
    signals = range(R)
    leaf_memory = [(dzrows[a], r, rev[j]) for j, (a, r, _) in enumerate(memory)]
    leaf_memoryless = [(dzrows[a], r) for a, r in memoryless]

    def leaf(lo, hi):
        for k in range(lo, hi):
            if k < n_fixed:
                yk = fixed[k]
            else:
                yk = w[k]
                for a, i, c in terms:
                    if i < k:
                        yk += c * dz_item(a, k - 1 - i)
                if not abs(yk) <= threshold:       # also catches nan
                    raise SimulationDivergedError(k, yk, threshold)
            zk = zfun(yk)
            for x in zk:
                if not isfinite(x):
                    raise SimulationDivergedError(k, yk, threshold, "output_basis")
            y[k] = yk
            for r in signals:
                zrows[r][k] = zk[r]
            for row, r, b_rev in leaf_memory:
                row[k] += dot(zrows[r][lo:k + 1], b_rev[L - (k - lo + 1):])
            for row, r in leaf_memoryless:
                row[k] = zk[r]
    return leaf


def _compiled_leaf(kernel, Q, terms, memory, memoryless, rev, w, y, z, dz, threshold, y_fixed):
    """The leaf of :func:`recursion` by the compiled ``kernel`` (:mod:`fohw.model._compiled`)."""
    intp = np.intp
    args = (w, y, z, dz,
            np.array([a for a, _, _ in terms], dtype=intp),
            np.array([i for _, i, _ in terms], dtype=intp),
            np.array([c for _, _, c in terms], dtype=np.float64),
            np.array([a for a, _, _ in memory], dtype=intp),
            np.array([r for _, r, _ in memory], dtype=intp),
            np.ascontiguousarray(rev),
            np.array([a for a, _ in memoryless], dtype=intp),
            np.array([r for _, r in memoryless], dtype=intp),
            np.array(Q, dtype=np.float64, order="C"), Q.shape[1] == 1,    # writable copies:
            np.zeros(0) if y_fixed is None else np.array(y_fixed, dtype=np.float64),  # one type
            float(threshold), np.zeros(Q.shape[0]))

    def leaf(lo, hi):
        status, k, yk = kernel(lo, hi, *args)
        if status == _compiled.GROWTH:
            raise SimulationDivergedError(k, yk, threshold)
        if status == _compiled.OUTPUT_BASIS:
            raise SimulationDivergedError(k, yk, threshold, "output_basis")
    return leaf


def output_terms(g_basis, Q):
    """Return ``y -> [z_1, …, z_R]`` with ``z_r = sum_j Q[j, r] g_j(y)``, for one float.

    The rank-one polynomial case (a model's ``gbar``) is a Horner scheme.
    """
    n_g, R = Q.shape
    cols = [[float(Q[j, r]) for j in range(n_g)] for r in range(R)]
    if g_basis.is_polynomial and R == 1:
        rev = cols[0][::-1]

        def horner(y):
            acc = 0.0
            for c in rev:
                acc = acc * y + c
            return [acc * y]
        return horner
    if g_basis.is_polynomial:
        def powers(y):
            g, p = [], y
            for _ in range(n_g):
                g.append(p)
                p *= y
            return [sum(c * gj for c, gj in zip(col, g)) for col in cols]
        return powers
    funcs = g_basis.functions

    def general(y):
        arr = np.array([y])
        g = [float(np.asarray(f(arr), dtype=np.float64)[0]) for f in funcs]
        return [sum(c * gj for c, gj in zip(col, g)) for col in cols]
    return general


def free_run(structure, Q, A, qa, pb, order_values, u, v, *, offset, past, operating_point,
             threshold, history, method="auto", kernel="auto", leaf_size=None):
    """Simulate any structure from its coefficient blocks (deviation coordinates inside).

    ``Q, A``: the fed-back signals and their coefficients (:func:`recursion`); ``qa``, ``pb``:
    the ``(n_g, n_out)`` and ``(n_f, n_in)`` coefficients of basis function and term
    (:func:`forcing`); ``order_values``: ``{free order: value}``, already checked; ``u``,
    ``v``: input (data units) and equation noise; ``threshold``: the divergence bound or
    ``None`` (the default of :func:`simulate`). ``method``, ``kernel``, ``leaf_size`` as for
    :func:`recursion`.
    """
    u0, y0 = operating_point
    out_nu, in_nu = structure.orders.values(order_values, check=False)
    out_terms = [(term.lag, nu) for term, nu in zip(structure.orders.output, out_nu)]
    in_terms = [(term.lag, nu) for term, nu in zip(structure.orders.input, in_nu)]
    n_hist, y_fixed = 0, None
    if history is not None:
        u_hist, y_hist = _check_history(history, structure.n_inputs)
        n_hist = u_hist.shape[0]
        u = np.r_[u_hist, u]
        v = np.r_[np.zeros(n_hist), v]
        y_fixed = y_hist - y0 if y0 != 0.0 else y_hist
    if np.any(np.asarray(u0) != 0.0):
        u = u - np.asarray(u0)
    w = forcing(pb, in_terms, qa, out_terms, structure.f_basis, structure.g_basis, u, v,
                structure.dt, offset, past)
    if threshold is None:
        threshold = _default_threshold(w, y_fixed)
    try:
        y = recursion(Q, A, out_terms, structure.g_basis, w, threshold, method,
                      structure.dt, y_fixed, kernel=kernel, leaf_size=leaf_size)
    except SimulationDivergedError as err:
        raise SimulationDivergedError(err.sample - n_hist, err.value + y0, err.threshold,
                                      err.cause, overflow=err.overflow) from None
    y = y[n_hist:]
    return y + y0 if y0 != 0.0 else y


def _output_representation(qa):
    """``(Q, A)`` with the fewer output signals: ``z_j = g_j(y)`` or one signal per term."""
    if qa.shape[0] <= qa.shape[1]:      # fewer g-signals than terms: z_j = g_j(y)
        return np.eye(qa.shape[0]), qa
    return qa, np.eye(qa.shape[1])     # fewer terms: z_t = sum_j qa[j, t] g_j(y)


def _default_threshold(w, y_fixed):
    """1e8 times the largest magnitude that drives the recursion.

    The drive is the input branch, noise, offset, past levels and history: an output beyond
    1e8 times it has been amplified by the feedback and is escaping, in any units.
    """
    drive = float(np.max(np.abs(w))) if w.size else 0.0
    if y_fixed is not None and y_fixed.size:
        drive = max(drive, float(np.max(np.abs(y_fixed))))
    return 1e8 * max(drive, np.finfo(float).tiny)


def equation_noise(n, noise=None, noise_std=0.0, random_state=None):
    """The equation noise ``v`` of a simulation: ``noise`` itself, white Gaussian, or zeros.

    Parameters
    ----------
    n : int
        Number of samples.
    noise : array_like, shape (n,), optional
        Given noise (mutually exclusive with ``noise_std > 0``).
    noise_std : float, optional
        Standard deviation of white Gaussian noise drawn from ``random_state``. Default 0.
    random_state : None, int or numpy.random.Generator, optional
        Source of the drawn noise.

    Returns
    -------
    v : ndarray, shape (n,)
    """
    noise_std = check_scalar(noise_std, "noise_std", lower=0.0)
    if noise is not None:
        if noise_std > 0:
            raise ParameterError("pass either `noise` or `noise_std` > 0, not both.")
        v = check_array(noise, "noise")
        if v.shape[0] != n:
            raise DimensionError(f"`noise` and `u` must have the same length; got {v.shape[0]} "
                                 f"and {n}.")
        return v
    if noise_std > 0:
        return noise_std * check_random_state(random_state).standard_normal(n)
    return np.zeros(n)


def check_input_point(operating_point, n_inputs):
    """``(u0, y0)`` of a model with several inputs: ``u0`` one level per input (a tuple)."""
    u0, y0 = unpack_pair(operating_point, "operating_point", "(u0, y0)")
    if np.ndim(u0) == 0:
        u0 = [check_scalar(u0, "operating_point[0]")] * n_inputs
    u0 = check_array(u0, "operating_point[0]")
    if u0.shape[0] != n_inputs:
        raise DimensionError(f"`operating_point[0]` must give {n_inputs} input levels (one per "
                             f"input); got {u0.shape[0]}.")
    return tuple(float(x) for x in u0), check_scalar(y0, "operating_point[1]")


def _check_history(history, n_inputs=1):
    u_hist, y_hist = unpack_pair(history, "history", "(u_past, y_past) of measured records")
    u_hist = check_inputs(u_hist, n_inputs, "history u")
    y_hist = check_array(y_hist, "history y")
    check_same_length(u_hist, y_hist, "history u", "history y")
    return u_hist, y_hist


def _check_threshold(divergence_threshold):
    if divergence_threshold is None:
        return None
    return check_scalar(divergence_threshold, "divergence_threshold", lower=0.0,
                        lower_inclusive=False)
