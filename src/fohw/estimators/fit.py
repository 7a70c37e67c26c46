"""One simulation-error fit for every model kind (:func:`fohw.fit`).

Output-error least squares: the free parameters of a :class:`fohw.Model` minimise
``sum_k (y[k] - yhat[k])^2`` where ``yhat`` is the model's free run for the input. The steps
are the same for every kind:

1. the record is checked (lengths, finite values, excitation, a non-constant output, a range
   of magnitudes doubles can square);
2. starts: the kind's :meth:`~fohw.Model.starts` and the user's, each with its free orders
   scanned on a grid inside their bounds, and each also with its linear parameters solved
   (:meth:`~fohw.Model.linear_start`), ranked by their simulation error;
3. the best few are refined by bounded least squares (:func:`bounded_least_squares`, the one
   wrapper every fohw estimator runs) with the kind's exact Jacobian, or central finite
   differences when it has none;
4. the status: a search that made no step from its start is ``FAILED``, one whose fitted model
   does not simulate plausibly on its own record (finite, inside the envelope
   :func:`fohw.compare` uses) is ``IMPLAUSIBLE`` naming the sample; an estimate on a bound with a
   zero projected gradient is ``CONVERGED``, the bound named, a
   rank-deficient Jacobian is ``RANK_DEFICIENT`` naming the parameters (through
   :mod:`fohw._linalg`), and the covariance ``s^2 (J^T J)^{-1}`` comes from the same
   factorisation.

Nesting: every start is a point the search never ends above (the trust-region method accepts
only steps that lower the criterion), so a fit started at a simpler model's estimate
(:func:`fohw.lr_test` does this) never ends above it.
"""

from __future__ import annotations

import hashlib
import inspect
import itertools
import warnings
from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

from .. import _linalg
from .._plausible import free_run_problem
from .._threads import thin_solves
from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import (
    ConvergenceWarning,
    DimensionError,
    FohwError,
    ModelHookError,
    ParameterError,
    RankDeficiencyWarning,
)
from ..fit_result import FitResult
from ..model.base import Model
from ..model.irregular import DEFAULT_REFINE, jacobian_at
from ..model.simulate import HOOK_REFUSALS, call_hook, hook_error, read_only
from ..record import UNIFORM_RTOL, Record, as_records, record_info
from ..results import Status
from ._common import bounded_least_squares, stationary
from .identify import fit_lagged

__all__ = ["fit", "order_grid_models", "prepare_data", "data_digest_of", "records_jacobian", "free_jacobian",
           "central_differences", "rank_rcond", "data_digest", "MAX_SCAN", "ESCAPE",
           "PENALTY", "FD_RCOND"]

#: Most starts the order scan may simulate (``order_grid ** n_orders`` per start model, summed
#: over the start models: a kind's :meth:`~fohw.Model.starts` may return several).
MAX_SCAN = 20_000

#: A free run beyond this many times the largest measured ``|y|`` is out of range: the search
#: treats it as a penalty (a residual of ``PENALTY`` times ``max |y|`` at every sample, larger
#: than any run inside the range). A fitted model is judged by the envelope ``fohw.compare``
#: uses (:func:`fohw._plausible.free_run_problem`): outside it, ``IMPLAUSIBLE``.
ESCAPE = 1e3
PENALTY = 1e4

#: Magnitudes of the data fohw fits without rescaling: beyond them sums of squares of the
#: simulation error overflow or underflow in double precision.
DATA_RANGE = (1e-150, 1e150)


def data_digest(u, y, dt, sample_weight=None):
    """A fingerprint of a record (lengths, values, ``dt``, weights) to check two fits used one record."""
    h = hashlib.sha1()
    arrays = [u, y] + ([] if sample_weight is None else [sample_weight])
    for a in arrays:
        a = np.ascontiguousarray(a, dtype=np.float64)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(repr(float(dt)).encode())
    return h.hexdigest()[:16]


def check_weight(sample_weight, y):
    """``sample_weight`` checked against ``y`` (non-negative, one per sample, some positive)."""
    w = check_array(sample_weight, "sample_weight")
    check_same_length(y, w, "y", "sample_weight")
    if np.any(w < 0) or not np.any(w > 0):
        raise ParameterError("`sample_weight` must be non-negative with at least one positive "
                             f"entry; got values from {w.min()!r} to {w.max()!r}.")
    return w


def _hook(model, hook, u, y, weight):
    """A kind's ``starts`` or ``linear_start``, with ``sample_weight`` if given and it takes one.

    What it returns is checked (:func:`_check_start`): ``starts`` a list of models of the kind,
    ``linear_start`` one or None; anything else, or an exception other than a refusal, is a
    :class:`~fohw.exceptions.ModelHookError` naming the hook.
    """
    method = getattr(model, hook)
    takes = weight is not None and "sample_weight" in inspect.signature(method).parameters
    out = call_hook(model, hook, u, y, **({"sample_weight": weight} if takes else {}))
    if hook == "linear_start":
        return None if out is None else _check_start(model, hook, out)
    if isinstance(out, (Model, str, bytes)) or not hasattr(out, "__iter__"):
        raise ModelHookError(f"{type(model).__name__}.starts returned {_described(out)}; it must "
                             "return a list of start models of the kind.", hook)
    return [_check_start(model, hook, m, k) for k, m in enumerate(out)]


def _described(x):
    """What a hook returned, in a few words (``a tuple of 3 entries``, ``an array of shape (5,)``)."""
    if isinstance(x, np.ndarray):
        return f"an array of shape {x.shape} (dtype {x.dtype})"
    if isinstance(x, (list, tuple)):
        return f"a {type(x).__name__} of {len(x)} entries"
    text = repr(x)
    return f"{type(x).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


def _check_start(model, hook, m, k=None):
    """A start model ``m`` returned by ``model``'s ``hook``: a Model with the kind's parameters."""
    what = f"{type(model).__name__}.{hook} returned" + ("" if k is None else f", as start {k},")
    if not isinstance(m, Model):
        raise ModelHookError(f"{what} {_described(m)}; a start must be a model of the kind "
                             f"(a {type(model).__name__}).", hook)
    names, own = m.parameters.names, model.parameters.names
    if names != own:
        raise ModelHookError(f"{what} a {type(m).__name__} with parameters {list(names)}; a start "
                             f"has the model's parameters {list(own)}.", hook)
    return m


def _with(model, values):
    """``model.with_parameters(values)``, checked to be a model (a kind's fault named)."""
    new = call_hook(model, "with_parameters", values)
    if not isinstance(new, Model):
        raise ModelHookError(f"{type(model).__name__}.with_parameters returned {_described(new)}; "
                             f"it must return a new model of the kind (a {type(model).__name__}).",
                             "with_parameters")
    return new


def _output(model, hook, yhat, n):
    """A kind's output ``yhat`` for ``n`` input samples as a float array of shape ``(n,)``, or raise."""
    kind = type(model).__name__
    if np.iscomplexobj(yhat):
        raise ModelHookError(f"{kind}.{hook} returned a complex output; it must return the real "
                             f"output, shape ({n},).", hook)
    try:
        arr = np.asarray(yhat, dtype=float)
    except (TypeError, ValueError):
        raise ModelHookError(f"{kind}.{hook} returned {_described(yhat)}, not numbers; it must "
                             f"return the output, an array of shape ({n},).", hook) from None
    if arr.shape != (n,):
        raise ModelHookError(f"{kind}.{hook} returned an output of shape {arr.shape} for an input "
                             f"of {n} samples; it must return the output, shape ({n},).", hook)
    return arr


def _jacobian_pair(model, out, n):
    """A kind's ``jacobian`` output ``(yhat, J)`` checked (shapes, a finite ``J``), or None."""
    kind = type(model).__name__
    if out is None:
        return None
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise ModelHookError(f"{kind}.jacobian returned {_described(out)}; it must return a pair "
                             "(yhat, J) or None (then fohw uses finite differences).", "jacobian")
    yhat = _output(model, "jacobian", out[0], n)
    names = model.parameters.names
    try:
        jac = np.asarray(out[1], dtype=float)
    except (TypeError, ValueError):
        jac = None
    if jac is None or np.iscomplexobj(out[1]) or jac.shape != (n, len(names)):
        got = _described(out[1]) if jac is None else f"a J of shape {jac.shape}"
        raise ModelHookError(f"{kind}.jacobian returned {got}; J must have shape ({n}, "
                             f"{len(names)}): one row per sample, one column per parameter "
                             f"({', '.join(names)}), fixed and tied ones included.", "jacobian")
    if np.all(np.isfinite(yhat)) and not np.all(np.isfinite(jac)):
        cols = [names[j] for j in np.flatnonzero(~np.all(np.isfinite(jac), axis=0))]
        raise ModelHookError(f"{kind}.jacobian returned a J with NaN or inf entries (the columns "
                             f"of {', '.join(cols)}) where its output is finite; fix the kind's "
                             "jacobian, or fit with exact_jacobian=False (finite differences).",
                             "jacobian")
    return yhat, jac


def check_record(model, u, y):
    """``u`` (as the model takes it) and ``y`` checked for a fit; raises naming what is wrong."""
    if not isinstance(model, Model):
        raise ParameterError(f"`model` must be a fohw.Model (a model kind); got {type(model).__name__}.")
    u = model.check_input(u)
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    uu = u.reshape(u.shape[0], -1)
    if not np.any(uu):
        raise ParameterError("`u` is zero at every sample: the record has no excitation, so no "
                             "parameter of the model can be identified from it.")
    if np.ptp(y) == 0.0:
        raise ParameterError(f"`y` is constant ({float(y[0])!r} at all {y.size} samples): it carries "
                             "no information on the dynamics; fit a record in which the output "
                             "moves.")
    for name, x in (("u", uu), ("y", y)):
        big = float(np.max(np.abs(x)))
        if big > DATA_RANGE[1] or 0.0 < big < DATA_RANGE[0]:
            raise ParameterError(
                f"`{name}` has magnitudes near {big:.3g}, outside [{DATA_RANGE[0]:g}, "
                f"{DATA_RANGE[1]:g}], where squared simulation errors leave the range of doubles; "
                f"rescale `{name}` (e.g. to an RMS near 1): the model's parameters rescale with it.")
    return u, y


class _Experiment:
    """One record of a fit: its samples, weights, instants and how a model is run on it.

    ``t`` is ``None`` for a uniform record held between samples (the kind's own
    :meth:`~fohw.Model.simulate`); otherwise the instants the kind's
    :meth:`~fohw.Model.simulate_at` runs on (non-uniform ones, or a first-order hold).
    """

    def __init__(self, u, y, weight, *, t=None, intersample="zoh", warmup=0, name="",
                 refine=None):
        # the kind gets the input read-only: the caller's array is never changed
        self.u, self.y, self.weight, self.t = read_only(u), y, weight, t
        self.intersample, self.warmup, self.name = intersample, warmup, name
        self.refine = refine
        self.step = None
        if t is not None and warmup:
            # the fine step of the record's own instants: the warm-up's (at the mean step)
            # must not coarsen it
            self.step = float(np.median(np.diff(t))) / (refine or DEFAULT_REFINE)

    def _held(self):
        if not self.warmup:
            return self.u
        return np.concatenate([np.repeat(self.u[:1], self.warmup, axis=0), self.u])

    def _instants(self):
        t = self.t
        if self.warmup:
            step = (t[-1] - t[0]) / (t.size - 1)
            t = np.r_[t[0] - step * np.arange(self.warmup, 0, -1), t]
        return t

    def _grid(self):
        return ({"step": self.step} if self.step is not None else {"refine": self.refine})

    def simulate(self, model):
        """The model's free run on this record (after its warm-up), its shape checked."""
        held = self._held()
        if self.t is not None:
            # every kind has simulate_at: the fine-grid scheme, its own exact one, or a refusal
            # naming the alternative (the lagged kind, discrete in samples)
            hook = "simulate_at"
            yhat = call_hook(model, hook, held, self._instants(), intersample=self.intersample,
                             **self._grid())
        else:
            hook = "simulate"
            yhat = call_hook(model, hook, held)
        return _output(model, hook, yhat, held.shape[0])[self.warmup:]

    def jacobian(self, model, exact):
        """``(yhat, J)`` on this record: ``J`` over every parameter (:meth:`Model.jacobian`).

        Checked (:func:`_jacobian_pair`): a pair, ``J`` with a column per parameter, finite
        where the output is.
        """
        if exact:
            held = self._held()
            if self.t is None:
                out = call_hook(model, "jacobian", held)
            else:       # time stamps: the fine grid's, or None
                try:
                    out = jacobian_at(model, held, self._instants(), intersample=self.intersample,
                                      **self._grid())
                except HOOK_REFUSALS:
                    raise
                except Exception as exc:            # noqa: BLE001 - the kind's fault, named
                    raise hook_error(model, "jacobian", exc) from exc
            out = _jacobian_pair(model, out, held.shape[0])
            if out is not None:
                return out[0][self.warmup:], out[1][self.warmup:]
        return None


def _named(name):
    return f" {name!r}" if name else ""


class _Data:
    """The records of a fit as one criterion: residuals and Jacobians stacked record by record."""

    def __init__(self, experiments):
        self.experiments = experiments
        self.y = np.concatenate([e.y for e in experiments])
        weights = [e.weight for e in experiments]
        self.weight = None if all(w is None for w in weights) else np.concatenate(
            [np.ones(e.y.size) if e.weight is None else e.weight for e in experiments])
        self.bounds = np.cumsum([0] + [e.y.size for e in experiments])


#: Record fields that must agree across the records of one fit (one system, one set of units).
SHARED_FIELDS = ("input_names", "input_units", "output_name", "output_unit", "time_unit")


def prepare_data(model, u, y, sample_weight, warmup, refine=None):
    """The data of a fit as experiments, with the record check of each; and their info.

    Arrays ``u, y`` or a Record or a list of Records (``y`` None), as :func:`fit` takes them;
    :func:`data_digest_of` of the experiments is the fit's ``data_digest``.
    """
    u = _record_sequence(u)
    records = as_records(u, y, what="u")
    if records is None:
        experiment = _array_experiment(model, u, y, sample_weight, warmup, refine)
        _check_warmup(warmup, [experiment.y.size])
        return [experiment], None
    if not isinstance(model, Model):
        raise ParameterError(f"`model` must be a fohw.Model (a model kind); got "
                             f"{type(model).__name__}.")
    _check_warmup(warmup, [r.y.size for r in records])
    weights = _record_weights(records, sample_weight, several=isinstance(u, (list, tuple)))
    _check_shared_fields(records)
    _check_sampling(model, records)
    experiments = _record_experiments(model, records, weights, warmup, refine)
    u_all = np.concatenate([e.u.reshape(e.u.shape[0], -1) for e in experiments])
    y_all = np.concatenate([e.y for e in experiments])
    check_record(model, u_all if model.n_inputs > 1 else u_all[:, 0], y_all)
    return experiments, record_info(records)


#: The longest warm-up :func:`fit` takes: :data:`MAX_WARMUP_FACTOR` times the longest record's
#: samples, or :data:`MAX_WARMUP_FLOOR` samples if that is more. Every simulation of the search
#: runs through the warm-up, so its cost grows with it (a warm-up of 10**6 samples before two
#: records of 300 ran for minutes); a power-law memory has decayed to a few per cent of its
#: first sample's weight after ten record lengths.
MAX_WARMUP_FACTOR = 10
MAX_WARMUP_FLOOR = 10_000


def _check_warmup(warmup, lengths):
    """Raise unless ``warmup`` is within :data:`MAX_WARMUP_FACTOR` record lengths (or the floor)."""
    cap = max(MAX_WARMUP_FACTOR * max(lengths), MAX_WARMUP_FLOOR)
    if warmup > cap:
        raise ParameterError(f"`warmup` must be at most {cap} samples ({MAX_WARMUP_FACTOR} times "
                             f"the longest record, {max(lengths)} samples, or {MAX_WARMUP_FLOOR}); "
                             f"got {warmup}. Every simulation of the fit runs through the warm-up.")


def _record_sequence(u):
    """A numpy object array or an iterator (a generator) of Records as a list; others as given.

    ``fohw.fit(model, (r for r in records))`` and an object array of Records are the list of
    those records; an iterator of anything else is read into a list (then refused or taken
    as arrays, as a list would be).
    """
    if isinstance(u, np.ndarray) and u.dtype == object and u.ndim == 1 and u.size and \
            all(isinstance(r, Record) for r in u):
        return list(u)
    if isinstance(u, Iterator) and not isinstance(u, Record):
        return list(u)
    return u


def _array_experiment(model, u, y, sample_weight, warmup, refine):
    """The one experiment of arrays ``u, y`` (checked; ``refine`` refused: no time stamps)."""
    if y is None:
        raise ParameterError("`y` is missing: pass the output samples, or a fohw.Record (or "
                             "a list of Records) as the data.")
    if refine is not None:
        raise ParameterError(f"`refine` = {refine!r} is for records with time stamps or a "
                             "first-order hold; arrays are simulated at the model's own step.")
    uu, yy = check_record(model, u, y)
    weight = None if sample_weight is None else check_weight(sample_weight, yy)
    return _Experiment(uu, yy, weight, warmup=warmup)


def _record_weights(records, sample_weight, *, several):
    """One ``sample_weight`` entry (or None) per record; a list of records takes a list."""
    if sample_weight is None:
        return [None] * len(records)
    if not several:
        return [sample_weight]
    if not isinstance(sample_weight, (list, tuple)) or len(sample_weight) != len(records):
        got = (f"{len(sample_weight)} entries" if isinstance(sample_weight, (list, tuple))
               else type(sample_weight).__name__)
        raise ParameterError(f"`sample_weight` must be a list of one array (or None) per "
                             f"record ({len(records)}) for a list of records; got {got}.")
    return list(sample_weight)


def _check_shared_fields(records):
    """Raise unless the records agree on :data:`SHARED_FIELDS` (the first disagreement named)."""
    first = records[0]
    for k, r in enumerate(records[1:], 1):
        for field in SHARED_FIELDS:
            if getattr(r, field) != getattr(first, field):
                raise ParameterError(
                    f"record {k}{_named(r.name)} has {field} {getattr(r, field)!r}, record 0 "
                    f"{getattr(first, field)!r}: the records of one fit measure the same channels "
                    "in the same units (convert them first).")


def _check_sampling(model, records):
    """Raise unless the uniform records are sampled at the model's ``dt`` (or share one)."""
    has_dt = "dt" in model.config()
    model_dt = model.dt
    dts = []
    for k, r in enumerate(records):
        have = r.dt if r.uniform else None
        if have is None:
            continue
        dts.append(have)
        if has_dt and abs(have - model_dt) > UNIFORM_RTOL * have:
            raise ParameterError(
                f"record {k}{_named(r.name)} is sampled every {have!r} {r.time_unit}".rstrip()
                + f" but the {type(model).__name__} has dt = {model_dt!r}; build the model with "
                f"dt={have!r} (the record's sampling time): fohw does not change it silently.")
    if dts and not has_dt and max(dts) - min(dts) > UNIFORM_RTOL * max(dts):
        raise ParameterError(f"the records have different sampling times ({sorted(set(dts))}); a "
                             f"{type(model).__name__} runs in samples, so they must share one.")


def _record_experiments(model, records, weights, warmup, refine):
    """The experiments of the records, each checked (input, weights, a run on its instants)."""
    experiments = []
    for k, (r, w) in enumerate(zip(records, weights)):
        label = f"record {k}{_named(r.name)}"
        try:        # each record checked as one record is (a constant output, no excitation)
            uu = check_record(model, r.u, r.y)[0] if len(records) > 1 else model.check_input(r.u)
        except (ParameterError, DimensionError) as exc:
            raise type(exc)(f"{label}: {exc}") from None
        weight = None if w is None else check_weight(w, r.y)
        # a first-order hold needs a simulation between the samples even on uniform instants
        t = r.t if r.t is not None or r.intersample == "zoh" else r.time
        experiments.append(_Experiment(uu, r.y, weight, t=t, intersample=r.intersample,
                                       warmup=warmup, name=r.name, refine=refine))
        if t is not None:
            # a kind that cannot simulate on time stamps says so here, not as a failed search
            try:
                with np.errstate(all="ignore"):
                    experiments[-1].simulate(model)
            except ParameterError as exc:
                raise ParameterError(f"{label}: {exc}") from None
    if refine is not None and all(e.t is None for e in experiments):
        raise ParameterError(f"`refine` = {refine!r} is for records with time stamps or a "
                             "first-order hold; these records are uniform and held, simulated at "
                             "the model's own step.")
    return experiments


def data_digest_of(experiments, dt):
    """:func:`data_digest` of several records (one record: the same digest as its arrays)."""
    if len(experiments) == 1 and experiments[0].t is None and not experiments[0].warmup:
        e = experiments[0]
        return data_digest(e.u, e.y, dt, e.weight)
    h = hashlib.sha1()
    for e in experiments:
        h.update(data_digest(e.u, e.y, dt, e.weight).encode())
        if e.t is not None:     # where the model runs between samples, how it runs there
            h.update(np.ascontiguousarray(e.t, dtype=np.float64).tobytes())
            h.update(repr((e.intersample, e.refine, e.step)).encode())
        h.update(repr(e.warmup).encode())
    return h.hexdigest()[:16]


def free_jacobian(model, u, *, exact=True):
    """``(yhat, J, how)``: the free run and ``d yhat / d free`` at ``model``'s values.

    ``how`` is ``"exact"`` when the kind's :meth:`~fohw.Model.jacobian` gave it, else
    ``"finite differences"`` (central, step ``eps**(1/3) max(|p|, 1)``, one-sided at a bound).
    """
    return records_jacobian(model, [_Experiment(u, None, None)], exact=exact)


def central_differences(run, x, lower, upper):
    """``(run(x), d run / d x)`` by central differences, one-sided at a bound.

    The step is ``eps**(1/3) max(|x_j|, 1)``; ``run`` maps a parameter vector to the output.
    """
    yhat = run(x)
    cols = []
    for j in range(x.size):
        step = np.finfo(float).eps ** (1 / 3) * max(abs(x[j]), 1.0)
        up, down = x.copy(), x.copy()
        up[j] = min(x[j] + step, upper[j])
        down[j] = max(x[j] - step, lower[j])
        cols.append((run(up) - run(down)) / (up[j] - down[j]))
    jac = np.column_stack(cols) if cols else np.zeros((yhat.size, 0))
    return yhat, jac


def records_jacobian(model, experiments, *, exact=True):
    """``(yhat, J, how)`` of :func:`free_jacobian` over the experiments of :func:`prepare_data`.

    Each record run as :func:`fit` runs it (warm-up, instants, hold); rows stacked record by
    record. Central differences where the kind gives no exact Jacobian on a record.
    """
    params = model.parameters
    t = params.tie_matrix()
    outs = [e.jacobian(model, exact) for e in experiments]
    if all(o is not None for o in outs):
        return (np.concatenate([o[0] for o in outs]),
                np.vstack([np.asarray(o[1], dtype=float) @ t for o in outs]), "exact")

    def run(v):
        m = _with(model, params.with_free(v))
        return np.concatenate([e.simulate(m) for e in experiments])

    yhat, jac = central_differences(run, params.free_values(), *params.free_bounds())
    return yhat, jac, "finite differences"


#: Relative rank tolerance of a Jacobian by central differences: their error is about
#: ``eps**(2/3)`` (4e-11) of a column, far above the default ``N eps`` of an exact one, so a
#: dependence between columns hidden by that noise is still found.
FD_RCOND = 1e-8


def rank_rcond(how, n_rows, n_cols):
    """The ``rcond`` of the rank decision for a Jacobian obtained ``how`` (see :data:`FD_RCOND`)."""
    exact = _linalg.rank_tolerance(n_rows, n_cols)
    return exact if how == "exact" else max(exact, FD_RCOND)


def penalty_terms(model, n_free=None, t_matrix=None):
    """``(r, J)`` of a kind's :meth:`~fohw.Model.penalty` (``J`` over the free parameters), or empty.

    The residuals a kind adds to the squared simulation error (a regularisation); ``J`` is
    ``d r / d free`` through the tie matrix.
    """
    out = model.penalty()
    params = model.parameters
    if t_matrix is None:
        t_matrix = params.tie_matrix()
    if out is None:
        return np.zeros(0), np.zeros((0, t_matrix.shape[1] if n_free is None else n_free))
    r, jac = (np.asarray(x, dtype=float) for x in out)
    return r, np.atleast_2d(jac).reshape(r.size, -1) @ t_matrix


def order_grid_models(model, grid, params=None):
    """``model`` with its free orders moved to each point of a grid inside their bounds.

    ``grid`` points at ``(k + 0.5) / grid`` of each free order's bounds (clipped to ``[-2, 2]``)
    and the order's own value, every combination; the bounds, fixed flags and ties are those of
    ``params`` (default: the model's own). At most :data:`MAX_SCAN` points, else a ParameterError.
    The scan of :func:`fit`'s starts and of :func:`fohw.fit_frequency_response`'s.
    """
    params = model.parameters if params is None else params
    orders = [n for n in params.free_names if params[n].order]
    if grid <= 1 or not orders:
        return [model]
    axes = []
    for name in orders:
        lo, hi = params[name].bounds
        lo, hi = max(lo, -2.0), min(hi, 2.0)
        values = lo + (hi - lo) * (np.arange(grid) + 0.5) / grid
        axes.append(np.unique(np.r_[values, model.parameters[name].value]))
    n_points = int(np.prod([a.size for a in axes], dtype=float))
    if n_points > MAX_SCAN:
        raise ParameterError(f"`order_grid` = {grid} scans {n_points} points for {len(orders)} free "
                             f"orders, more than {MAX_SCAN}; use a smaller grid (or give starts).")
    return [_with(model, params.with_values(dict(zip(orders, combo))))
            for combo in itertools.product(*axes)]


@thin_solves
def fit(model, u, y=None, *, method=None, options=None, start=None, sample_weight=None,
        order_grid=5, n_starts=3, max_nfev=200, tol=1e-10, exact_jacobian=True, per_record=(),
        warmup=0, refine=None):
    """Fit any :class:`fohw.Model` to a record (or several) by simulation (output) error.

    Parameters
    ----------
    model : Model
        The kind, its start values, and which parameters are free, fixed, tied or bounded (its
        :attr:`~fohw.Model.parameters`; pass ``model.with_parameters(parameters)`` to change
        them).
    method : str, optional
        None (default): this engine, for every kind. Or a method of :func:`fohw.identify`'s
        table (``"varpro"``, ``"output_error"``, ``"structured"``, ``"hybrid"``, …;
        :data:`fohw.estimators.identify.METHODS`) for the kind those methods fit, a
        :class:`fohw.ThetaHW` (any other kind is refused, naming the engine): the model gives
        the class, the operating point and its orders' bounds, the method its own starts, and
        the result is an :class:`fohw.IdentificationResult`, exactly as ``identify`` with the
        same class and bounds gives (``"output_error"`` there is the lagged kind's own search,
        with its chain of nested starts). The engine's keywords below are then not taken.
    options : mapping, optional
        The method's options (as ``fohw.identify``'s keywords), with ``method`` only.
    u : array_like, Record or list of Record
        Input, as the kind takes it (1-D, or ``(N, m)`` for ``m`` input columns; a circuit takes
        ``[current, state of charge]``); or a :class:`fohw.Record` (then ``y`` is not given:
        the record carries it, and its names, units and sampling reach the result); or a list
        of Records (or a tuple, a generator, a numpy object array of them): several
        experiments of one system, fitted as one data set (one model, the criterion summed over
        the records, each record simulated from its own start), each record checked as one
        record is. A record with non-uniform time stamps is simulated on them by the kind's
        ``simulate_at``. The kind gets the samples read-only: the caller's arrays are never
        changed.
    y : array_like, shape (N,), optional
        Measured output (with array ``u``).
    start : Model or sequence of Model, optional
        Further start models of the same kind (e.g. a simpler model's estimate: the fit never
        ends above the best start).
    sample_weight : array_like, shape (N,), optional
        Non-negative weights of the squared errors (default 1); one array per record for a list
        of records. Zeros hold samples back from the criterion while the simulation still runs
        through them (a held-back block inside the record). The kind's
        :meth:`~fohw.Model.starts` and :meth:`~fohw.Model.linear_start` get them when they take
        a ``sample_weight`` keyword.
    order_grid : int, optional
        Scan points per free order for each start (its own value is always among them); 1 skips
        the scan. At most ``MAX_SCAN`` points in all (over every start model).
    n_starts : int, optional
        How many of the best-ranked starts are refined by least squares.
    max_nfev : int, optional
        Simulation budget of each refinement.
    tol : float, optional
        ``ftol``, ``xtol`` and ``gtol`` of :func:`scipy.optimize.least_squares`, in ``(0, 1)``.
    exact_jacobian : bool, optional
        Use the kind's exact Jacobian where it has one (default); False forces finite differences.
    per_record : str or sequence of str, optional
        Free parameters estimated once per record (nuisance parts such as an output offset;
        None or ``()``: none); the others are shared. The result's
        :attr:`~fohw.FitResult.per_record` holds each record's value and standard error; its
        model holds the first record's; the covariance of the shared parameters accounts for
        the per-record ones.
    warmup : int, optional
        Samples of each record's first input held before it (0: each record starts from rest).
        A record that starts where the system had settled under its first input (a step test
        from an operating point) is simulated from that state this way; a fractional kind
        settles slowly (its memory decays like a power of time), so give it a long warm-up. At
        most ``MAX_WARMUP_FACTOR`` (10) times the longest record, or ``MAX_WARMUP_FLOOR``
        (10 000) samples if that is more: every simulation of the search runs through it.
    refine : int, optional
        For records with non-uniform instants: fine-grid steps per median step of the
        Grünwald–Letnikov kinds' scheme (:func:`fohw.model.irregular.simulate_at`; default 8).
        The scheme converges at first order: at 8 a fit of a fractional order is biased by a
        few standard errors on a low-noise record (docs/irregular_time.md); raise it there.

    Returns
    -------
    FitResult

    Raises
    ------
    ParameterError, DimensionError
        Bad input (named): no excitation, a constant output (in any record), data beyond the
        range of doubles, fewer samples than free parameters, nothing free, a warm-up beyond
        its cap, or no start with a finite simulation.
    fohw.exceptions.ModelHookError
        The kind broke the :class:`fohw.Model` protocol (named: the hook and what it returned):
        an output of the wrong shape, a Jacobian that is not ``(yhat, J)`` with one column per
        parameter or has NaN where the output is finite, a start or ``with_parameters`` result
        that is not a model of the kind, or an exception from a hook other than fohw's own and
        arithmetic ones (a write into its read-only input among them).

    Warns
    -----
    ConvergenceWarning
        The search used its budget, or failed (stuck at its start, or a fitted model that
        does not simulate finitely). Stuck with the kind's exact Jacobian, that Jacobian is
        probed against central differences and named when they disagree.
    RankDeficiencyWarning
        Some free parameters are not identifiable from the record (named).

    Examples
    --------
    See :class:`fohw.Model` for a kind written in a dozen lines and fitted with this function.
    """
    if method is not None:
        given = {name: value for name, value, default in (
            ("start", start, None), ("sample_weight", sample_weight, None),
            ("order_grid", order_grid, 5), ("n_starts", n_starts, 3), ("max_nfev", max_nfev, 200),
            ("tol", tol, 1e-10), ("exact_jacobian", exact_jacobian, True),
            ("per_record", per_record, ()), ("warmup", warmup, 0), ("refine", refine, None))
            if not (value is default or (isinstance(value, (int, float, tuple))
                                         and value == default))}
        if given:
            raise ParameterError(
                f"{sorted(given)} are the engine's settings (method=None); method {method!r} "
                "takes its own, as options={...} (fohw.identify's keywords of that method).")
        return fit_lagged(model, u, y, method=method, options=options)
    if options is not None:
        raise ParameterError("`options` are a method's (with `method=`); the engine "
                             "(method=None) takes its settings as keywords.")
    refine = None if refine is None else check_int(refine, "refine", minimum=1)
    experiments, info = prepare_data(model, u, y, sample_weight,
                                     check_int(warmup, "warmup", minimum=0), refine)
    data = _Data(experiments)
    u_hook = (np.concatenate([e.u for e in experiments]) if len(experiments) > 1
              else experiments[0].u)
    order_grid = check_int(order_grid, "order_grid", minimum=1)
    n_starts = check_int(n_starts, "n_starts", minimum=1)
    max_nfev = check_int(max_nfev, "max_nfev", minimum=1)
    tol = check_scalar(tol, "tol", lower=np.finfo(float).eps, upper=1.0, upper_inclusive=False)
    params = model.parameters
    per_record = _check_free(params, per_record, data)
    bases = _start_models(model, params, start, u_hook, data)
    problem = _Problem(model, params, data, per_record, exact_jacobian)
    table = _ranked_starts(problem, _candidates(model, params, bases, order_grid, u_hook, data))
    estimate = _search(problem, table, n_starts=n_starts, tol=tol, max_nfev=max_nfev)
    fitted = problem.at(estimate.x)
    verdict = _verdict(problem, estimate, max_nfev)
    warning = _warning(type(model).__name__, verdict)
    if warning is not None:
        # issued here, not in a stage, so that the stack above is fixed: 1 is this line, 2
        # thin_solves's wrapper, 3 the caller's line (the one the warning names)
        warnings.warn(warning[0], warning[1], stacklevel=3)
    options = dict(order_grid=order_grid, n_starts=n_starts, max_nfev=max_nfev, tol=tol,
                   exact_jacobian=exact_jacobian,
                   sample_weight=None if data.weight is None else data.weight.tolist(),
                   per_record=list(per_record), warmup=experiments[0].warmup, refine=refine)
    return _result(problem, fitted, table, estimate.x, verdict, options=options, info=info)


def _check_free(params, per_record, data):
    """``per_record`` checked (:func:`_check_per_record`), with the model's free parameters.

    Raises naming what is wrong: nothing free, or no more samples (of positive weight) than
    free values (the shared ones and each per-record one's copies for records 1, 2, ...).
    """
    names = params.free_names
    if not names:
        raise ParameterError("every parameter of the model is fixed or tied: nothing to fit. Free "
                             "some with model.with_parameters(parameters) (Parameter(fixed=False)).")
    n_rec = len(data.experiments)
    per_record = _check_per_record(per_record, params, n_rec)
    extra_names = _extra_names(per_record, n_rec)
    n_used = _n_used(data)
    n_x = len(names) + len(extra_names)
    if n_used <= n_x:
        raise DimensionError(f"`y` has {n_used} samples"
                             f"{'' if data.weight is None else ' of positive weight'} "
                             f"for {n_x} free parameters ({', '.join(list(names) + extra_names)}); "
                             "need more samples than parameters.")
    return per_record


def _extra_names(per_record, n_rec):
    """The per-record values beyond record 0's, named ``name[r]``: each name's records in turn."""
    return [f"{n}[{r}]" for n in per_record for r in range(1, n_rec)]


def _n_used(data):
    """Samples in the criterion: all, or those of positive weight."""
    return data.y.size if data.weight is None else int(np.count_nonzero(data.weight))


def _start_models(model, params, start, u, data):
    """The kind's starts (:meth:`~fohw.Model.starts`), then the user's ``start`` models.

    Each with the user's settings (fixed flags, bounds, ties: those of ``params``), which hold
    for every start. Raises if a ``start`` is not of the model's kind and parameters.
    """
    extra = [] if start is None else [start] if isinstance(start, Model) else list(start)
    for s in extra:
        if type(s) is not type(model) or s.parameters.names != params.names:
            raise ParameterError(f"`start` must hold models of the same kind and parameters as "
                                 f"`model` ({type(model).__name__}); got {type(s).__name__}.")
    return [_with(m, params.with_values(m.parameters.valuesdict()))
            for m in _hook(model, "starts", u, data.y, data.weight) + extra]


class _Problem:
    """The criterion of one fit: the free vector, its models, residual and Jacobian.

    The free vector ``x`` holds the model's free values (``names``), then each per-record
    parameter's values for records 1, 2, ... (``extra_names``; record 0's is among ``names``):
    :meth:`column` says where, :meth:`at` makes the model of a record, :meth:`extend` makes a
    vector from the model's free values. :meth:`residual` and :meth:`jacobian` are those the
    search runs on: the weighted simulation errors of every record, stacked, then the kind's
    penalty rows (:meth:`~fohw.Model.penalty`); a run that fails or leaves the range
    (:data:`ESCAPE`) has the constant residual ``escaped``. ``nfev`` counts the residuals.
    """

    def __init__(self, model, params, data, per_record, exact_jacobian):
        self.model, self.params, self.data = model, params, data
        self.experiments = data.experiments
        self.y, self.weight = data.y, data.weight
        self.names = names = params.free_names
        self.n_rec = n_rec = len(data.experiments)
        self.per_record = per_record
        self.extra_names = _extra_names(per_record, n_rec)
        self.sw = 1.0 if self.weight is None else np.sqrt(self.weight)
        self.n_used = _n_used(data)
        self.n_x = len(names) + len(self.extra_names)
        self.y_scale = max(float(np.max(np.abs(self.y))), 1e-300)
        # A kind's regularisation (Model.penalty): its residuals follow the records'.
        self.n_pen = penalty_terms(model)[0].size
        self.escaped = np.full(self.y.size + self.n_pen, PENALTY * self.y_scale)
        self.lower0, self.upper0 = params.free_bounds()
        self.pr_index = [names.index(n) for n in per_record]
        self.lower = self.extend(self.lower0)
        self.upper = self.extend(self.upper0)
        self.nfev = 0
        self.has_exact = exact_jacobian and type(model).jacobian is not Model.jacobian
        self.t_matrix = params.tie_matrix()
        # In the local search the solver asks for the Jacobian at (nearly) every point whose
        # residual it computed; a kind's exact Jacobian comes with its output, so both are
        # computed at once there and the Jacobian kept for the solver's call at the same x.
        self._last = {}

    def column(self, i, r):
        """Index in the full vector of per-record parameter ``i``'s value for record ``r``."""
        return self.pr_index[i] if r == 0 else len(self.names) + i * (self.n_rec - 1) + r - 1

    def at(self, x, r=0):
        """The model of record ``r`` at the full vector ``x`` (shared, then per-record values)."""
        x = np.clip(x, self.lower, self.upper)
        free = x[:len(self.names)].copy()
        for i in range(len(self.per_record)):
            free[self.pr_index[i]] = x[self.column(i, r)]
        return _with(self.model, self.params.with_free(free))

    def extend(self, x0):
        """A shared-parameter vector with each per-record copy at its record-0 value."""
        x0 = np.asarray(x0, dtype=float)
        return np.r_[x0, np.repeat(x0[self.pr_index], self.n_rec - 1)]

    def run(self, x, with_jacobian):
        """``(yhat, J)`` over every record at ``x`` (``J`` over the full vector, or ``None``)."""
        parts, jacs = [], []
        m = None
        for r, e in enumerate(self.experiments):
            if m is None or self.per_record:
                m = self.at(x, r)
            out = e.jacobian(m, self.has_exact) if with_jacobian else None
            if with_jacobian and out is None:
                return None, None
            if out is None:
                parts.append(e.simulate(m))
            else:
                parts.append(out[0])
                jacs.append(out[1] @ self.t_matrix)
        yhat = np.concatenate(parts)
        if not with_jacobian:
            return yhat, None
        return yhat, self._stack(jacs)

    def _stack(self, jacs):
        """The records' Jacobians (over the model's free values) as one over the full vector."""
        n_names = len(self.names)
        jac = np.zeros((self.y.size, self.n_x))
        for r, j in enumerate(jacs):
            rows = slice(self.data.bounds[r], self.data.bounds[r + 1])
            jac[rows, :n_names] = j
            for i in range(len(self.per_record)):
                if r:
                    jac[rows, self.column(i, r)] = j[:, self.pr_index[i]]
                    jac[rows, self.pr_index[i]] = 0.0
        return jac

    def full_jacobian(self, x):
        """``(yhat, J, how)`` at ``x``: exact where the kind gives it, else central differences."""
        if self.has_exact:
            yhat, jac = self.run(x, True)
            if jac is not None:
                return yhat, jac, "exact"
        yhat, jac = central_differences(lambda v: self.run(v, False)[0], x, self.lower, self.upper)
        return yhat, jac, "finite differences"

    def residual(self, x, with_jacobian=False):
        """The search's residual at ``x`` (``escaped`` where the run fails or leaves the range).

        With ``with_jacobian`` the kind's exact Jacobian is computed with the run and kept for
        :meth:`jacobian` at the same ``x``.
        """
        self.nfev += 1
        try:
            with np.errstate(all="ignore"):
                yhat, jac = self.run(x, with_jacobian and self.has_exact)
                if jac is not None:
                    self._last["x"], self._last["jac"] = np.array(x, dtype=float), jac
                elif yhat is None:
                    yhat, _ = self.run(x, False)
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return self.escaped
        if not np.all(np.isfinite(yhat)) or np.max(np.abs(yhat)) > ESCAPE * self.y_scale:
            return self.escaped
        if self.n_pen:
            return np.concatenate([(self.y - yhat) * self.sw, self.penalty_at(x)[0]])
        return (self.y - yhat) * self.sw

    def sse(self, r):
        """``r @ r`` of a :meth:`residual`; ``inf`` for ``escaped``."""
        return float(r @ r) if r is not self.escaped else np.inf

    def penalty_at(self, x):
        """The kind's penalty at the first record's model: ``(r, J)``, ``J`` over the full vector."""
        r, j = penalty_terms(self.at(np.asarray(x, dtype=float)), len(self.names), self.t_matrix)
        return r, np.concatenate([j, np.zeros((r.size, self.n_x - len(self.names)))], axis=1)

    def jacobian(self, x):
        """``d residual / d x`` (zeros where it is not finite or cannot be computed)."""
        zeros = (self.y.size + self.n_pen, self.n_x)
        try:
            with np.errstate(all="ignore"):
                if "x" in self._last and np.array_equal(self._last["x"], x):
                    jac = self._last["jac"]
                else:
                    jac = self.full_jacobian(np.asarray(x, dtype=float))[1]
        except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
            return np.zeros(zeros)
        if self.weight is not None:
            jac = jac * self.sw[:, None]
        if self.n_pen:
            jac = np.concatenate([jac, -self.penalty_at(x)[1]])
        return -jac if np.all(np.isfinite(jac)) else np.zeros(zeros)

    def where(self, k):
        """Sample ``k`` of the stacked records, named by its record."""
        r = int(np.searchsorted(self.data.bounds, k, side="right")) - 1
        return f"sample k = {int(k - self.data.bounds[r])}" + (
            f" of record {r}" if self.n_rec > 1 else "")


def _candidates(model, params, bases, order_grid, u, data):
    """The start candidates: each base, its orders on a grid, each also with its linear part solved.

    Raises if the scans of the bases together exceed :data:`MAX_SCAN` points.
    """
    candidates = []
    scanned = 0
    for base in bases:
        grid = order_grid_models(base, order_grid)
        scanned += len(grid)
        if scanned > MAX_SCAN:
            raise ParameterError(
                f"`order_grid` = {order_grid} scans more than {MAX_SCAN} points over the "
                f"{len(bases)} start models of the {type(model).__name__} ({len(grid)} for one); "
                "use a smaller grid (order_grid=1 skips the scan).")
        for m in grid:
            candidates.append(m)
            solved = _linear_start(m, params, u, data)
            if solved is not None:
                candidates.append(solved)
    return candidates


def _linear_start(m, params, u, data):
    """``m`` with its linear parameters solved (:meth:`~fohw.Model.linear_start`), or None."""
    try:
        with np.errstate(all="ignore"):
            solved = _hook(m, "linear_start", u, data.y, data.weight)
    except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
        solved = None
    if solved is None:
        return None
    return _with(solved, params.with_values(
        {n: v for n, v in solved.parameters.valuesdict().items() if params[n].tie is None}))


def _ranked_starts(problem, candidates):
    """``[(sse, x)]``: the candidates' free vectors inside the bounds by simulation error, lowest first.

    A free vector met twice keeps its first SSE; one whose run fails ranks last, at ``inf``.
    Every candidate inside the bounds is simulated (and counted in ``problem.nfev``).
    """
    ranked = {}
    for m in candidates:
        x = m.parameters.free_values()
        if np.any(x < problem.lower0) or np.any(x > problem.upper0):
            continue
        sse = problem.sse(problem.residual(problem.extend(x)))
        ranked.setdefault(tuple(x.tolist()), sse)
    return sorted(((sse, x) for x, sse in ranked.items()), key=lambda row: row[0])


class _Estimate(NamedTuple):
    """The best refinement of :func:`_search`."""

    sse: float              # the search's criterion at x (penalty rows included)
    x: np.ndarray           # the full vector, active entries on their bound
    status: Status          # bounded_least_squares's
    ls: object              # scipy's OptimizeResult
    sse0: float             # the criterion at its start


def _search(problem, table, *, n_starts, tol, max_nfev):
    """Bounded least squares from each of the ``n_starts`` best finite starts; the lowest end.

    Raises if no start of ``table`` (:func:`_ranked_starts`) has a finite simulation error.
    """
    best = None
    for sse0, x0 in table[:n_starts]:
        if not np.isfinite(sse0):
            continue
        x, status, ls = bounded_least_squares(lambda x: problem.residual(x, True),
                                              problem.extend(x0), jac=problem.jacobian,
                                              lower=problem.lower, upper=problem.upper, ftol=tol,
                                              xtol=tol, gtol=tol, max_nfev=max_nfev)
        # The solver's last residual is at ls.x; x differs only where it was put on a bound.
        r = ls.fun if np.array_equal(x, ls.x) else problem.residual(x)
        sse = problem.sse(r)
        if best is None or sse < best.sse:
            best = _Estimate(sse, x, status, ls, sse0)
    if best is None:
        raise ParameterError(
            f"no start of the {type(problem.model).__name__} gave a finite simulation of this "
            f"record ({len(table)} tried); give a start whose free run stays bounded (`start=`), "
            "or narrower bounds on its parameters.")
    return best


def _estimate_jacobian(problem, x):
    """``problem.full_jacobian(x)`` at the estimate; a kind's failure there named.

    The search treats a run that raises as one that escaped; at the estimate (and its finite
    difference steps) the run must work: a Python exception of the kind's own (a
    ``ZeroDivisionError``, not a fohw error) is a :class:`~fohw.exceptions.ModelHookError`.
    """
    try:
        with np.errstate(all="ignore"):
            return problem.full_jacobian(x)
    except (ArithmeticError, np.linalg.LinAlgError) as exc:
        if isinstance(exc, FohwError):
            raise
        raise hook_error(problem.model, "jacobian" if problem.has_exact else "simulate",
                         exc) from exc


#: Relative difference (per column) between a kind's exact Jacobian and central differences
#: beyond which :func:`_jacobian_probe` names the exact one as suspect: central differences err
#: by about ``eps**(2/3)`` (4e-11) of a column times the curvature, a wrong derivative by O(1).
PROBE_RTOL = 1e-3


def _jacobian_probe(problem, x):
    """``[sentence]`` when the kind's exact Jacobian at ``x`` disagrees with central differences.

    Run where the search is stuck at its start with the kind's exact Jacobian; ``[]`` when they
    agree (each column within :data:`PROBE_RTOL` of the larger of the two).
    """
    try:
        with np.errstate(all="ignore"):
            _, exact = problem.run(x, True)
            _, fd = central_differences(lambda v: problem.run(v, False)[0], x, problem.lower,
                                        problem.upper)
    except (ArithmeticError, ParameterError, np.linalg.LinAlgError):
        return []
    if exact is None or not (np.all(np.isfinite(exact)) and np.all(np.isfinite(fd))):
        return []
    size = np.maximum(np.linalg.norm(exact, axis=0), np.linalg.norm(fd, axis=0))
    off = np.linalg.norm(exact - fd, axis=0) / np.where(size > 0, size, 1.0)
    bad = np.flatnonzero(off > PROBE_RTOL)
    if not bad.size:
        return []
    names = list(problem.names) + problem.extra_names
    kind = type(problem.model).__name__
    return [f"The exact Jacobian ({kind}.jacobian) disagrees with central finite differences "
            f"at the start: the columns of {', '.join(names[j] for j in bad)} differ by up to "
            f"{100 * float(off[bad].max()):.3g} % of their size, and a wrong Jacobian stops the "
            f"search. Check {kind}.jacobian, or fit with exact_jacobian=False (finite "
            "differences)."]


class _Verdict(NamedTuple):
    """What :func:`_verdict` concludes about an estimate."""

    status: Status
    messages: list          # the solver's message first, then one sentence per finding
    sse: float              # the records' squared error (the penalty's rows left out)
    yhat: np.ndarray        # the free run at the estimate, records stacked
    how: str                # how the Jacobian was obtained ("exact" or "finite differences")
    full_cov: np.ndarray    # the covariance of the full vector, or None


def _verdict(problem, estimate, max_nfev):
    """The status, messages and covariance of an estimate.

    ``FAILED`` for a search that made no step from its start and does not end at a stationary
    point (:func:`stationary`) or whose model the kind's :meth:`~fohw.Model.check_fitted`
    refuses; ``IMPLAUSIBLE`` for a free run outside the envelope; ``RANK_DEFICIENT`` for a
    Jacobian without full column rank (the parameters named). Otherwise the estimate's status.
    """
    x, status = estimate.x, estimate.status
    messages = [f"simulation-error fit (scipy.optimize.least_squares): {estimate.ls.message}"]
    if status == Status.MAX_ITER:
        messages.append(f"The search used its budget of {max_nfev} simulations before meeting "
                        "`tol`; raise `max_nfev` or give a better start.")
    y, sw, sse = problem.y, problem.sw, estimate.sse
    yhat, jac, how = _estimate_jacobian(problem, np.asarray(x, dtype=float))
    if problem.weight is not None:                  # the criterion's Jacobian and residual
        jac = jac * sw[:, None]
    crit_r = (y - yhat) * sw
    if problem.n_pen:   # the regularised criterion: its rows join the covariance's Gram matrix
        pen_r, pen_j = problem.penalty_at(x)
        messages.append(f"Regularisation ({type(problem.model).__name__}.penalty): "
                        f"{float(pen_r @ pen_r):.6g} added to the squared error; the covariance "
                        "is s^2 (J^T J + P^T P)^-1.")
        jac, crit_r = np.concatenate([jac, -pen_j]), np.concatenate([crit_r, pen_r])
        sse = float(np.sum(((y - yhat) * sw) ** 2))     # the records' part only
    if estimate.ls.status == 3 and not float(crit_r @ crit_r) < estimate.sse0 * (1.0 - 1e-9) and \
            not stationary(jac, crit_r, x, problem.lower, problem.upper):
        status = Status.FAILED
        messages.append("The search is stuck at its start: it made no step that lowered the "
                        "simulation error, so the estimate is where it started, not a minimum.")
        if how == "exact":          # a wrong exact Jacobian sends the search the wrong way
            messages.extend(_jacobian_probe(problem, np.asarray(x, dtype=float)))
    absurd = free_run_problem(yhat, y, where=problem.where)
    if absurd:
        return _Verdict(Status.IMPLAUSIBLE, messages + [absurd], sse, yhat, how, None)
    status, notes, full_cov = _covariance(problem, x, jac, sse, how, status)
    return _Verdict(status, messages + notes, sse, yhat, how, full_cov)


def _covariance(problem, x, jac, sse, how, status):
    """``(status, notes, full_cov)``: the kind's check of its fitted models, then the covariance.

    ``s^2 (J^T J)^-1`` of the criterion's Jacobian ``jac`` (``s^2`` the records' ``sse`` over
    the degrees of freedom); ``None`` and ``RANK_DEFICIENT`` (``FAILED`` after a refusal of
    :meth:`~fohw.Model.check_fitted`) when ``jac`` has dependent columns, named.
    """
    notes = []
    note = None
    for r, e in enumerate(problem.experiments):
        note = problem.at(x, r).check_fitted(e.u, e.y)
        if note:
            note = note if problem.n_rec == 1 else f"Record {r}: {note}"
            break
    if note:
        status = Status.FAILED
        notes.append(note)
    inverse, fac = _linalg.inverse_gram(jac, rcond=rank_rcond(how, *jac.shape))
    if inverse is None:
        # the kind's own sentence (check_fitted) names the cause: it stays FAILED, first
        status = Status.FAILED if note else Status.RANK_DEFICIENT
        all_names = list(problem.names) + problem.extra_names
        cols = ", ".join(all_names[i] for i in fac.dependent)
        notes.append(f"Rank deficient: rank {fac.rank} of {fac.n_columns}; the columns of "
                     f"{cols} are linear combinations of the others (the output's "
                     "sensitivities to the free parameters), so those parameters are not "
                     "identifiable from this record (fix one of them, or fit a record "
                     "whose input excites them).")
        return status, notes, None
    return status, notes, sse / (problem.n_used - problem.n_x) * inverse


def _warning(kind, verdict):
    """``(text, category)`` of the warning a fit with this verdict raises, or None."""
    if verdict.status == Status.RANK_DEFICIENT:
        return f"fohw.fit({kind}): {verdict.messages[-1]}", RankDeficiencyWarning
    if verdict.status in (Status.MAX_ITER, Status.FAILED, Status.IMPLAUSIBLE):
        return f"fohw.fit({kind}): {' '.join(verdict.messages[1:])}", ConvergenceWarning
    return None


def _result(problem, fitted, table, x, verdict, *, options, info):
    """The :class:`~fohw.FitResult` of an estimate ``x`` and its verdict."""
    names, full_cov = problem.names, verdict.full_cov
    per = {}
    for i, n in enumerate(problem.per_record):
        idx = [problem.column(i, r) for r in range(problem.n_rec)]
        per[n] = {"values": [float(x[j]) for j in idx],
                  "standard_errors": None if full_cov is None else
                  [float(np.sqrt(full_cov[j, j])) for j in idx]}
    order_names = [n for n in names if problem.params[n].order]
    starts = tuple(({n: x0[names.index(n)] for n in order_names}, sse) for sse, x0 in table)
    return FitResult(model=fitted, parameters=fitted.parameters,
                     covariance=None if full_cov is None else full_cov[:len(names), :len(names)],
                     status=verdict.status, sse=verdict.sse, n_samples=problem.n_used,
                     message=_message(problem, x, verdict), nfev=problem.nfev,
                     jacobian=verdict.how, starts=starts, residuals=problem.y - verdict.yhat,
                     data_digest=data_digest_of(problem.experiments, problem.model.dt),
                     options=options, data=info or {}, per_record=per,
                     n_per_record=len(problem.extra_names))


def _message(problem, x, verdict):
    """The result's message: the verdict's sentences, then the free values on a bound."""
    message = " ".join(verdict.messages)
    at_bound = [f"{n} = {v:.6g} (its {'lower' if v <= lo else 'upper'} bound)"
                for n, v, lo, hi in zip(problem.names, x, problem.lower, problem.upper)
                if v <= lo or v >= hi]
    if at_bound:
        message += (" At a bound" + (", where the criterion's gradient points outside the "
                                     "bounds (a minimum within them)"
                                     if verdict.status == Status.CONVERGED else "")
                    + f": {', '.join(at_bound)}.")
    return message


def _check_per_record(per_record, params, n_records):
    """``per_record`` as a tuple of free, untied parameter names no other parameter is tied to."""
    if per_record is None:          # None: none, as ()
        per_record = ()
    if isinstance(per_record, str):
        per_record = (per_record,)
    try:
        per_record = tuple(per_record)
    except TypeError:
        raise ParameterError(f"`per_record` must be a parameter name or a sequence of names (() "
                             f"for none); got {type(per_record).__name__} {per_record!r}.") from None
    bad = [n for n in per_record if not isinstance(n, str)]
    if bad:
        raise ParameterError(f"`per_record` must hold parameter names (strings); got {bad[0]!r}.")
    for n in per_record:
        if n not in params:
            raise ParameterError(f"`per_record`: {n!r} is not a parameter of the model "
                                 f"({', '.join(params)}).")
        if n not in params.free_names:
            raise ParameterError(f"`per_record`: {n!r} is fixed or tied; only free parameters "
                                 "can be estimated per record.")
        tied = [m for m, p in params.items() if p.tie is not None and p.tie[0] == n]
        if tied:
            raise ParameterError(f"`per_record`: {', '.join(tied)} is tied to {n!r}; untie it "
                                 "first (a tie to a per-record value has no single meaning).")
    if len(set(per_record)) != len(per_record):
        raise ParameterError(f"`per_record` names a parameter twice: {per_record!r}.")
    if per_record and n_records < 2:
        raise ParameterError("`per_record` needs several records (a list of fohw.Record).")
    return per_record
