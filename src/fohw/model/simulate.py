"""``fohw.simulate``: the free run of any model, fit result or record, one front door.

:func:`simulate` runs a :class:`fohw.Model` of any kind (its own ``simulate``), a fit result
(its model), a :class:`fohw.Record` or a list of them (their inputs, at their sampling), and
the lagged kind's class with parameter values (a :class:`fohw.Structure` and ``params``,
through :mod:`fohw.model.lagged.simulation`). The helpers every verb uses to read records
(:func:`record_list`, :func:`check_record_sampling`, :func:`simulate_record`) live here too.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._types import ArrayLike, PairLike, RandomStateLike
from .._validation import check_array, unpack_pair
from ..exceptions import DimensionError, FohwError, ModelHookError, ParameterError
from .base import Model
from .lagged.simulation import (
    simulate_predictor,
)
from .lagged.structure import Structure

__all__ = ["simulate", "simulate_record", "check_record_sampling", "record_list", "own_dt",
           "generic_model", "measured_history", "read_only", "hook_error", "call_hook",
           "HOOK_REFUSALS"]


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
        layout of :class:`fohw.model.lagged.params.ThetaLayout`, any theta, not only ``[q ⊗ a, p ⊗ b]``; the
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
        initial=...)`` (:mod:`fohw.model.lagged.initial`; needed for a ``past="estimate"`` fit).

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
