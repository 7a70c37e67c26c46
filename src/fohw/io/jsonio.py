"""Model and result files: versioned JSON (never pickle), validated field by field on reading.

A file is a header (``"format"``: ``"fohw-model"`` or ``"fohw-result"``, ``"version"``) and the
object's own dict (:meth:`fohw.HammersteinWiener.to_dict`,
:meth:`fohw.IdentificationResult.to_dict`), which stores each fact once. Floats are written
with Python's shortest round-trip representation, so every number reads back bit for bit.
Polynomial bases are stored by degree; any other basis by the names of its functions only (code
is never serialised), and loading then needs the same basis passed in, checked by those names.
Files are written atomically (:mod:`fohw.io.files`).

Reading checks every field for its type and, for numbers, finiteness (and the covariance for
symmetry and non-negative variances) before anything is built, and refuses a file whose facts
contradict each other: a :class:`~fohw.DataFileError` naming the file and the field, never a
result that fails later. Only the current version is read (fohw is unreleased: the layout of
version 2, which stored derived facts beside what they derive from, is gone).
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from ..estimators.identify import METHODS
from ..exceptions import DataFileError, DimensionError, ParameterError
from ..fit_result import FitResult
from ..model.base import Model
from ..model.basis import MAX_POLYNOMIAL_DEGREE, Basis
from ..model.lagged.structure import Structure
from ..model.lagged.system import HammersteinWiener
from ..model.orders import ORDER_RANGE
from ..result_checks import (
    bad_field,
    check_covariance,
    check_fit_result_dict,
    check_integer,
    check_model_dict,
    check_number,
    is_number,
    require_fields,
)
from ..results import IdentificationResult, Status
from .files import read_json, write_json

__all__ = ["save_model", "load_model", "save_result", "load_result", "model_from_dict",
           "result_from_dict", "MODEL_FORMAT_VERSION", "RESULT_FORMAT_VERSION"]

#: Version of the model files this fohw writes (it reads the versions in ``READS``): 3 stores
#: each fact once (2 also stored the offset and past flags beside the values they follow from).
MODEL_FORMAT_VERSION = 3
#: Version of the result files: 3 stores each fact once (the estimate, the structure with its
#: bases, the settings in ``options`` and the method's outputs in ``details``).
RESULT_FORMAT_VERSION = 3
#: The versions read, per format.
READS = {"fohw-model": (3,), "fohw-result": (3,)}
_HEADER = ("format", "version")


# ---- fields -----------------------------------------------------------------------------------
def _check_header(d, kind, path):
    if not isinstance(d, dict) or d.get("format") != kind:
        raise DataFileError(f"{path} is not a {kind} file (field 'format' must be {kind!r}).")
    version = d.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version not in READS[kind]:
        readable = " or ".join(str(v) for v in READS[kind])
        what = f"the string {version!r}" if isinstance(version, str) else repr(version)
        raise DataFileError(f"{path}: field 'version' is {what}; this fohw reads {kind} files "
                            f"of version {readable}, written as a JSON integer.")
    return version


def _require_fields(d, names, kind, version, path):
    """Exactly the fields ``names``: a missing one or one the format does not have is an error."""
    require_fields(d, names, f"a {kind} file of version {version}", path, header=_HEADER,
                   error=DataFileError)


def _bad(d, key, need, path):
    bad_field(d, key, need, path, DataFileError)


def _number(d, key, path, lower=None, optional=False):
    check_number(d, key, path, lower, optional, DataFileError)


def _integer(d, key, path, lower):
    check_integer(d, key, path, lower, DataFileError)


def _finite_pair(d, key, path, optional=False):
    value = d.get(key)
    if value is None and optional:
        return
    if not isinstance(value, list) or len(value) != 2 or not all(
            is_number(v) and np.isfinite(v) for v in value):
        raise DataFileError(f"{path}: field {key!r} must be a pair of finite numbers"
                            + (" or null" if optional else "") + f"; got {value!r}.")


def _inputs_pairs(d, path):
    """Several inputs (``operating_point[0]`` a list): check the per-input fields, True.

    ``operating_point`` is ``[[u0_1, …], y0]`` and ``input_range`` ``[[lo_1, …], [hi_1, …]]``
    (or null); the structure says how many inputs (checked against it later).
    """
    point = d.get("operating_point")
    if not (isinstance(point, list) and len(point) == 2 and isinstance(point[0], list)):
        return False

    def finite_list(value):
        return isinstance(value, list) and len(value) >= 2 and all(
            is_number(v) and np.isfinite(v) for v in value)
    if not finite_list(point[0]) or not (is_number(point[1]) and np.isfinite(point[1])):
        raise DataFileError(f"{path}: field 'operating_point' must be [[u0 per input], y0] of "
                            f"finite numbers; got {point!r}.")
    ranges = d.get("input_range")
    if ranges is not None and not (isinstance(ranges, list) and len(ranges) == 2
                                   and all(finite_list(r) for r in ranges)
                                   and len(ranges[0]) == len(ranges[1])):
        raise DataFileError(f"{path}: field 'input_range' must be [[smallest per input], "
                            f"[largest per input]] or null; got {ranges!r}.")
    if ranges is not None and len(ranges[0]) != len(point[0]):
        raise DataFileError(f"{path}: field 'operating_point' gives {len(point[0])} input levels but "
                            f"field 'input_range' gives {len(ranges[0])} inputs; each gives one entry "
                            "per input.")
    if ranges is not None and any(lo > hi for lo, hi in zip(*ranges)):
        raise DataFileError(f"{path}: field 'input_range' is reversed ({ranges!r}); it "
                            "is the (smallest, largest) input of the estimation record.")
    return True


def _finite_list(d, key, path):
    value = d.get(key)
    if not isinstance(value, list) or not value or not all(
            is_number(v) and np.isfinite(v) for v in value):
        _bad(d, key, "a non-empty list of finite numbers", path)


def _orders_field(d, key, path):
    orders = d.get(key)
    if not isinstance(orders, dict) or not all(
            is_number(v) and np.isfinite(v) for v in orders.values()):
        _bad(d, key, "an object of finite numbers (the estimated orders)", path)
    lo, hi = ORDER_RANGE
    for name, value in orders.items():
        if not lo <= value <= hi:
            raise DataFileError(f"{path}: field {key!r}: order {name!r} is {value!r}, outside "
                                f"[{lo:g}, {hi:g}], the orders fohw's models allow.")


def _array_field(d, key, path, *, name=None):
    """Check an array written as ``{"shape": [...], "data": [...]}`` (or null); return it."""
    name = name or key
    entry = d.get(key)
    if entry is None:
        return None
    if not isinstance(entry, dict) or set(entry) != {"shape", "data"} \
            or not isinstance(entry.get("data"), list) or not isinstance(entry.get("shape"), list):
        raise DataFileError(f"{path}: field {name!r} must be null or an object with 'shape' and "
                            "'data' lists.")
    data = entry["data"]
    if not all(is_number(v) for v in data):
        raise DataFileError(f"{path}: field {name!r} holds an entry that is not a number.")
    arr = np.array(data, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        i = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise DataFileError(f"{path}: field {name!r} holds a non-finite value ({float(arr[i])!r} "
                            f"at entry {i}).")
    if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in entry["shape"]) \
            or int(np.prod(entry["shape"])) != arr.size:
        raise DataFileError(f"{path}: field {name!r} has {arr.size} values, which do not fill "
                            f"its shape {entry['shape']!r}.")
    return arr.reshape(entry["shape"])


def _basis(d, given, name, path) -> Basis:
    """The basis stored as ``d`` (a custom one is ``given``, checked by its names)."""
    if not isinstance(d, dict):
        raise DataFileError(f"{path}: field {name!r} must be an object such as "
                            f'{{"kind": "polynomial", "degree": 2}}; got {d!r}.')
    kind = d.get("kind")
    if kind == "inputs" and name == "f_basis":       # several inputs: one basis per input
        parts = d.get("parts")
        if not isinstance(parts, list) or len(parts) < 2 or set(d) != {"kind", "parts"}:
            raise DataFileError(f"{path}: field {name!r}: 'parts' must be a list of one basis "
                                f"per input (at least 2); got {parts!r}.")
        given_parts = getattr(given, "parts", given)
        if given_parts is not None and (not isinstance(given_parts, (list, tuple))
                                        or len(given_parts) != len(parts)):
            raise ParameterError(f"{path}: `{name}` must give one basis per input "
                                 f"({len(parts)}); got {given!r}.")
        return [_basis(p, None if given_parts is None else given_parts[i], f"{name}[{i}]", path)
                for i, p in enumerate(parts)]
    if kind == "polynomial":
        degree = d.get("degree")
        if isinstance(degree, bool) or not isinstance(degree, int) \
                or not 1 <= degree <= MAX_POLYNOMIAL_DEGREE or set(d) != {"kind", "degree"}:
            raise DataFileError(f"{path}: field {name!r}: 'degree' must be an integer from 1 to "
                                f"{MAX_POLYNOMIAL_DEGREE}; got {degree!r}.")
    elif kind == "custom":
        names = d.get("names")
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise DataFileError(f"{path}: field {name!r}: 'names' must be a non-empty list of "
                                f"strings; got {names!r}.")
        if given is None:
            raise ParameterError(f"{path} was saved with a custom `{name}` ({names}); its "
                                 f"functions are code, which fohw never stores: load it in "
                                 f"Python and pass the same basis, fohw.load_model(path, "
                                 f"{name}=...) or fohw.load_result(path, {name}=...) (the "
                                 "command line cannot).")
    else:
        raise DataFileError(f"{path}: field {name!r} has kind {kind!r}; fohw writes 'polynomial' "
                            "(a degree) or 'custom' (names of functions passed again on loading).")
    try:
        return Basis.from_dict(d, given, name=name)
    except ParameterError as exc:            # `given` does not match what was saved
        raise ParameterError(f"{path}: {exc}") from None


# ---- models and results of any other kind (fohw.Model, fohw.FitResult) -------------------------
def _is_generic_model(body):
    return isinstance(body, dict) and "kind" in body


#: Fields only the lagged kind's result has: a result without them and without ``model`` is
#: a fit of another kind that lost its ``model`` field, not a lagged result.
_LAGGED_ONLY = ("method", "structure", "theta")
#: Fields only a fit of another kind has (:data:`fohw.result_checks.FIT_RESULT_FIELDS`).
_GENERIC_ONLY = ("model", "sse", "jacobian", "starts", "residuals", "data_digest")


def _is_generic_result(body):
    """A fit of a kind other than the lagged one (it may have lost its ``model`` field)."""
    return isinstance(body, dict) and ("model" in body or (
        not any(k in body for k in _LAGGED_ONLY) and any(k in body for k in _GENERIC_ONLY)))


def _generic_model_from_dict(body, version, path, field="the file"):
    """A Model of a registered kind from its ``{"kind", "config", "parameters"}``, checked."""
    if version != MODEL_FORMAT_VERSION:
        raise DataFileError(f"{path}: a model of kind {body['kind']!r} in a version-{version} "
                            f"file; models of any kind are written from version "
                            f"{MODEL_FORMAT_VERSION} on.")
    return check_model_dict(body, path, field=field, what=f"a fohw-model file of version {version}",
                            error=DataFileError)


def _generic_result_from_dict(body, version, path):
    """A FitResult of any kind but the lagged one, every field checked before it is built.

    The checks are :meth:`fohw.FitResult.from_dict`'s own
    (:func:`fohw.result_checks.check_fit_result_dict`), here naming the file.
    """
    check_fit_result_dict(body, where=path, what=f"a fohw-result file of version {version}",
                          error=DataFileError)
    try:
        return FitResult.from_dict(body)
    except (ParameterError, DimensionError, KeyError, TypeError, ValueError) as exc:
        raise DataFileError(f"{path}: malformed fohw-result file ({type(exc).__name__}: "
                            f"{exc})") from None


# ---- models -----------------------------------------------------------------------------------
def model_to_dict(model: HammersteinWiener | Model) -> dict:
    """The content of a model file: the header and the model's ``to_dict()``.

    :meth:`HammersteinWiener.to_dict` for the lagged kind, :meth:`fohw.Model.to_dict`
    (``kind``, ``config``, ``parameters``) for any other.
    """
    return {"format": "fohw-model", "version": MODEL_FORMAT_VERSION, **model.to_dict()}


def _no_bases(f_basis, g_basis, output_map, kind, path):
    for name, value in (("f_basis", f_basis), ("g_basis", g_basis), ("output_map", output_map)):
        if value is not None:
            raise ParameterError(f"`{name}` is for files of the lagged HammersteinWiener kind; "
                                 f"{path} holds a {kind!r} model; got {name}={value!r}.")


def model_from_dict(d: dict, *, f_basis=None, g_basis=None, path="<dict>") -> HammersteinWiener:
    """The model of a model file's content (:func:`model_to_dict`).

    A file with a ``kind`` field holds a model of that registered kind
    (:meth:`fohw.Model.from_dict`; its module must be imported first); the parameters it
    rebuilds must be the file's. Fields of the wrong type or value are a
    :class:`~fohw.DataFileError` naming the file.
    """
    version = _check_header(d, "fohw-model", path)
    body = {k: v for k, v in d.items() if k not in _HEADER}
    if _is_generic_model(body):
        _no_bases(f_basis, g_basis, None, body["kind"], path)
        return _generic_model_from_dict(body, version, path)
    _require_fields(body, HammersteinWiener.DICT_FIELDS, "fohw-model", version, path)
    for key in "abpq":
        _finite_list(body, key, path)
    _orders_field(body, "orders", path)
    _number(body, "dt", path)
    _number(body, "offset", path)
    _finite_pair(body, "past", path)
    _finite_pair(body, "operating_point", path)
    f = _basis(body["f_basis"], f_basis, "f_basis", path)
    g = _basis(body["g_basis"], g_basis, "g_basis", path)
    try:
        return HammersteinWiener.from_dict(body, f_basis=f, g_basis=g)
    except (TypeError, ValueError, AttributeError) as exc:    # ParameterError is a ValueError
        raise DataFileError(f"{path}: malformed fohw-model file: {exc}") from None


def save_model(model: HammersteinWiener | Model, path: str | os.PathLike) -> None:
    """Write a model to a JSON file (atomically; :func:`load_model` reads it back exactly).

    A :class:`fohw.HammersteinWiener` is written in its own layout; a :class:`fohw.Model` of
    any other kind as ``kind``, ``config`` and ``parameters`` (:meth:`fohw.Model.to_dict`),
    which :func:`load_model` rebuilds through the registry of kinds.

    Examples
    --------
    >>> import os, tempfile, fohw
    >>> m = fohw.datasets.paper_model()
    >>> with tempfile.TemporaryDirectory() as d:
    ...     fohw.save_model(m, os.path.join(d, "m.json"))
    ...     fohw.load_model(os.path.join(d, "m.json")) == m
    True
    """
    if not isinstance(model, (HammersteinWiener, Model)):
        raise ParameterError(f"`model` must be a fohw.Model (a HammersteinWiener or any other "
                             f"kind); got {type(model).__name__}.")
    _write(model_to_dict(model), path)


def _write(content, path):
    """:func:`write_json`, with a kind's settings that JSON cannot hold named."""
    try:
        write_json(content, path)
    except TypeError as exc:
        raise ParameterError(f"cannot save to {os.fspath(path)}: {exc} (a model kind's "
                             "`config()` must hold JSON values only); nothing was written.") \
            from None


def load_model(path: str | os.PathLike, *, f_basis: Basis | None = None,
               g_basis: Basis | None = None) -> HammersteinWiener | Model:
    """Read a model written by :func:`save_model` (custom bases must be passed again).

    The file says which kind it holds; a kind of one's own must be defined (its module
    imported) before loading.
    """
    return model_from_dict(read_json(path), f_basis=f_basis, g_basis=g_basis,
                           path=os.fspath(path))


# ---- results ----------------------------------------------------------------------------------
#: ``output_map_params`` is written only for a structure with a series output map.
_OPTIONAL_RESULT_FIELDS = ("output_map_params", "data")
_RESULT_FIELDS = tuple(f.name for f in dataclasses.fields(IdentificationResult)
                       if f.init and f.name not in _OPTIONAL_RESULT_FIELDS)
_V2_HISTORIES = ("theta_history", "alpha_sample_history", "alpha_history", "J_history",
                 "alpha_profile")


def result_to_dict(result) -> dict:
    """The content of a result file: the header and the result's ``to_dict()``."""
    return {"format": "fohw-result", "version": RESULT_FORMAT_VERSION, **result.to_dict()}


def _check_result_fields(d, version, path):
    """Every field of a result's content has its type and a finite value, before use."""
    _require_fields(d, _RESULT_FIELDS + tuple(k for k in _OPTIONAL_RESULT_FIELDS if k in d),
                    "fohw-result", version, path)
    if "output_map_params" in d:
        params = d["output_map_params"]
        if not isinstance(params, dict) or not all(is_number(v) and np.isfinite(v)
                                                   for v in params.values()):
            _bad(d, "output_map_params", "an object of finite numbers", path)
        if "output_map" not in d["structure"]:
            raise DataFileError(f"{path}: field 'output_map_params' is given, but field "
                                "'structure' has no output map: the file contradicts itself.")
    for key in ("method", "message", "schedule"):
        if not isinstance(d[key], str):
            _bad(d, key, "a string", path)
    if d["method"] not in METHODS:
        _bad(d, "method", f"one of fohw's methods {METHODS}", path)
    _number(d, "J", path, lower=0.0)
    _number(d, "noise_variance", path, lower=0.0, optional=True)
    _integer(d, "n_samples", path, 1)
    _integer(d, "nit", path, 0)
    _integer(d, "nfev", path, 0)
    if isinstance(d["status"], bool) or d["status"] not in {int(s) for s in Status}:
        _bad(d, "status", f"one of {sorted(int(s) for s in Status)} (fohw.Status)", path)
    if not isinstance(d["alpha_at_bound"], bool):
        _bad(d, "alpha_at_bound", "true or false", path)
    _number(d, "offset", path)
    _orders_field(d, "orders", path)
    _finite_pair(d, "past", path)
    inputs = _inputs_pairs(d, path)
    if not inputs:
        _finite_pair(d, "operating_point", path)
        _finite_pair(d, "input_range", path, optional=True)
    if not inputs and d["input_range"] is not None and d["input_range"][0] > d["input_range"][1]:
        raise DataFileError(f"{path}: field 'input_range' is reversed ({d['input_range']!r}); it "
                            "is the (smallest, largest) input of the estimation record.")
    if _array_field(d, "theta", path) is None:
        raise DataFileError(f"{path}: field 'theta' is missing (null).")
    _array_field(d, "covariance", path)
    for key in ("structure", "options", "details") + (("data",) if "data" in d else ()):
        if not isinstance(d[key], dict):
            _bad(d, key, "an object", path)
    for key, value in d["details"].items():
        if isinstance(value, dict):
            _array_field(d["details"], key, path, name=f"details.{key}")
        elif isinstance(value, float) and not np.isfinite(value):
            raise DataFileError(f"{path}: field 'details.{key}' is {value!r}; JSON holds finite "
                                "numbers only.")
    for key in ("f_basis", "g_basis"):
        if key not in d["structure"]:
            raise DataFileError(f"{path}: malformed fohw-result file (field {key!r} missing or "
                                "not an object).")


#: The methods that give standard errors (a covariance and a noise variance).
_COVARIANCE_METHODS = ("varpro", "output_error", "structured")
#: What each known entry of ``details`` must be: ``(dimensions or "text", (low, high) of its values)``.
_DETAILS = {"alpha_history": (1, ORDER_RANGE), "alpha_sample_history": (1, ORDER_RANGE),
            "J_history": (1, (0.0, np.inf)), "theta_history": (2, None),
            "alpha_profile": (2, None), "simulation_sse": (0, (0.0, np.inf)), "start": ("text", None),
            "starts": ("starts", None), "n_starts_agreed": ("count", None),
            "integer_sse": (0, (0.0, np.inf)), "identity_sse": (0, (0.0, np.inf))}
#: The fields of each entry of ``details["starts"]`` (output_error's chain of starts).
_START_FIELDS = {"start", "orders", "start_sse", "sse", "status", "nfev"}


def _contradiction(path, text):
    raise DataFileError(f"{path}: {text}: the file contradicts itself.")


def _structure_field(body, f, g, path, output_map=None):
    """The stored model class, or a DataFileError naming ``structure``."""
    try:
        return Structure.from_dict(body["structure"], f_basis=f, g_basis=g,
                                   output_map=output_map)
    except ParameterError as exc:
        raise DataFileError(f"{path}: field 'structure' is not a model class fohw can read: "
                            f"{exc}") from None


def _check_agreement(body, structure, path):
    """The stored facts agree with each other and with the structure (before the result is built).

    Checked: the orders are exactly the structure's free orders and lie inside the run's
    ``alpha_bounds``; theta has the structure's entries; the record was longer than the lags;
    ``schedule`` is the run's; a covariance and a noise variance only from a method that gives
    them and not for a rank-deficient fit; the known ``details`` are of their kind.
    """
    free = list(structure.orders.free)
    if sorted(body["orders"]) != sorted(free):
        _contradiction(path, f"field 'orders' gives the orders {sorted(body['orders'])}, but "
                       f"field 'structure' has the free orders {free}")
    n_theta = structure.layout.n_params
    shape = body["theta"]["shape"]
    if shape != [n_theta]:
        _contradiction(path, f"field 'theta' has shape {shape}, but field 'structure' has "
                       f"{n_theta} entries ({', '.join(structure.layout.names)})")
    lags = structure.max_lag
    if body["n_samples"] <= lags:
        _contradiction(path, f"field 'n_samples' is {body['n_samples']}, but field 'structure' "
                       f"has lags up to {lags}, which need a longer record")
    _check_bounds(body, free, path)
    method, schedule = body["method"], body["schedule"]
    expected = body["options"].get("schedule", "recursive" if method == "rls" else "")
    if schedule != expected:
        _contradiction(path, f"field 'schedule' is {schedule!r}, but method {method!r} "
                       f"was run with {expected!r}" if expected else
                       f"field 'schedule' is {schedule!r}, but method {method!r} has no schedule")
    for key in ("covariance", "noise_variance"):
        if body[key] is None:
            continue
        if method not in _COVARIANCE_METHODS:
            _contradiction(path, f"field {key!r} is given, but method {method!r} gives no "
                           f"standard errors (only {', '.join(_COVARIANCE_METHODS)} do)")
        if body["status"] == int(Status.RANK_DEFICIENT):
            _contradiction(path, f"field {key!r} is given, but field 'status' says the fit is "
                           "rank deficient, which has none")
    for key, value in body["details"].items():
        _check_detail(key, value, path)


def _check_bounds(body, free, path):
    bounds = body["options"].get("alpha_bounds")
    if bounds is None:
        return
    pairs = bounds if isinstance(bounds, dict) else {n: bounds for n in free}
    for name in free:
        pair = pairs.get(name)
        if not isinstance(pair, list) or len(pair) != 2 or not all(is_number(v) for v in pair) \
                or not ORDER_RANGE[0] <= pair[0] < pair[1] <= ORDER_RANGE[1]:
            raise DataFileError(f"{path}: field 'options.alpha_bounds' must be a pair (low, high) "
                                f"with 0 <= low < high <= 2, or such a pair per free order; got "
                                f"{bounds!r}.")
        value = body["orders"][name]
        if not pair[0] <= value <= pair[1]:
            _contradiction(path, f"field 'orders': order {name!r} is {value!r}, outside "
                           f"field 'options.alpha_bounds' = {pair!r}, the bounds the run kept "
                           "it in")


def _check_detail(key, value, path):
    if key not in _DETAILS:
        raise DataFileError(f"{path}: field 'details.{key}' is not part of a fohw-result file "
                            f"(its details are {', '.join(sorted(_DETAILS))}).")
    ndim, limits = _DETAILS[key]
    if ndim == "text":
        if not isinstance(value, str):
            _bad({key: value}, f"details.{key}", "a string", path)
        return
    if ndim == "count":
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            _bad({key: value}, f"details.{key}", "a non-negative integer", path)
        return
    if ndim == "starts":
        _check_starts(value, path)
        return
    if ndim == 0:
        ok = is_number(value) and limits[0] <= value <= limits[1]
    elif isinstance(value, dict):
        arr = _array_field({key: value}, key, path, name=f"details.{key}")
        ok = arr.ndim == ndim and (limits is None or bool(
            np.all((arr >= limits[0]) & (arr <= limits[1]))))
    else:
        ok = False
    if not ok:
        need = {0: "a number", 1: "a 1-D array", 2: "a 2-D array"}[ndim]
        within = "" if limits is None else f" in [{limits[0]:g}, {limits[1]:g}]"
        raise DataFileError(f"{path}: field 'details.{key}' must be {need} of values{within}; "
                            f"got {value!r}."[:400])


def _check_starts(value, path):
    """``details.starts``: one object per searched start, each with :data:`_START_FIELDS`."""
    if not isinstance(value, list):
        _bad({"starts": value}, "details.starts", "a list of objects", path)
    for i, entry in enumerate(value):
        where = f"details.starts[{i}]"
        if not isinstance(entry, dict) or set(entry) != _START_FIELDS:
            got = sorted(entry) if isinstance(entry, dict) else entry
            raise DataFileError(f"{path}: field '{where}' must be an object with the fields "
                                f"{sorted(_START_FIELDS)}; got {got!r}."[:400])
        numbers = [entry["start_sse"]] + ([] if entry["sse"] is None else [entry["sse"]])
        if not (isinstance(entry["start"], str) and isinstance(entry["orders"], dict)
                and all(is_number(v) for v in entry["orders"].values())
                and all(is_number(v) and v >= 0 for v in numbers)
                and (entry["status"] is None or entry["status"] in Status.__members__)
                and (entry["nfev"] is None or (isinstance(entry["nfev"], int)
                                               and not isinstance(entry["nfev"], bool)
                                               and entry["nfev"] >= 0))):
            raise DataFileError(f"{path}: field '{where}' is malformed (a start's name, its orders, "
                                f"criteria >= 0, a status name and a count); got {entry!r}."[:400])


def _check_covariance(cov, n_estimates, path):
    check_covariance(cov, n_estimates, path, DataFileError)


def result_from_dict(d: dict, *, f_basis=None, g_basis=None, output_map=None, path="<dict>"):
    """The result of a result file's content (:func:`result_to_dict`).

    Every field is checked for its type and, for numbers, finiteness before use (the estimates,
    orders, offset, past levels, operating point and input range included; a covariance must
    also be symmetric with a non-negative diagonal), and the facts must agree with each other
    (orders in ``[0, 2]`` and those of the structure, an offset only where one is fitted, a
    known method, ``input_range`` in order, the orders those the structure frees and inside the
    run's ``alpha_bounds``, theta as long as the structure's, a record longer than the lags,
    ``schedule`` the run's, standard errors only from a method that gives them and not for a
    rank-deficient fit, ``details`` of their kinds): a file edited or damaged by hand is a
    :class:`~fohw.DataFileError` naming the field, never a result that fails later.
    """
    version = _check_header(d, "fohw-result", path)
    body = {k: v for k, v in d.items() if k not in _HEADER}
    if _is_generic_result(body):
        kind = body["model"].get("kind") if isinstance(body.get("model"), dict) else None
        _no_bases(f_basis, g_basis, output_map, kind, path)
        return _generic_result_from_dict(body, version, path)
    _check_result_fields(body, version, path)
    f = _basis(body["structure"]["f_basis"], f_basis, "f_basis", path)
    g = _basis(body["structure"]["g_basis"], g_basis, "g_basis", path)
    _check_agreement(body, _structure_field(body, f, g, path, output_map), path)
    try:
        result = IdentificationResult.from_dict(body, f_basis=f, g_basis=g,
                                                output_map=output_map)
    except (ParameterError, DimensionError) as exc:      # one fact against another
        raise DataFileError(f"{path}: inconsistent fohw-result file: {exc}") from None
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise DataFileError(f"{path}: malformed or inconsistent fohw-result file "
                            f"({type(exc).__name__}: {exc})") from None
    _check_covariance(result.covariance, len(result.estimate_names), path)
    return result


def save_result(result: IdentificationResult | FitResult, path: str | os.PathLike) -> None:
    """Write an identification result, or a fit of any kind, to a JSON file (atomically).

    :func:`load_result` reads it back with every float exact. Settings without a JSON form (a
    ``start`` result) are left out of ``options``. A :class:`fohw.FitResult` of another kind
    is written as :meth:`fohw.FitResult.to_dict` (its model as ``kind``, ``config`` and
    ``parameters``).

    Raises
    ------
    ParameterError
        ``result`` is not an :class:`~fohw.IdentificationResult`, or holds a non-finite number
        (nothing is written then; an existing file is unchanged).
    DataFileError
        ``path`` cannot be written.

    Examples
    --------
    >>> import os, tempfile, fohw
    >>> data = fohw.datasets.paper_example(300, random_state=0)
    >>> res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     fohw.save_result(res, os.path.join(d, "r.json"))
    ...     back = fohw.load_result(os.path.join(d, "r.json"))
    >>> back.alpha == res.alpha and bool((back.theta == res.theta).all())
    True
    """
    if not isinstance(result, (IdentificationResult, FitResult)):
        raise ParameterError(f"`result` must be an IdentificationResult or a fohw.FitResult; "
                             f"got {type(result).__name__}.")
    _write(result_to_dict(result), path)


def load_result(path: str | os.PathLike, *, f_basis: Basis | None = None,
                g_basis: Basis | None = None, output_map=None) -> IdentificationResult | FitResult:
    """Read an identification result (or a fit of any kind) written by :func:`save_result`.

    Parameters
    ----------
    path : str or os.PathLike
    f_basis, g_basis : Basis, optional
        Needed (and checked by name) when the result used custom basis functions.
    output_map : SeriesMap, optional
        Needed (and checked by name) when the result has a custom series output map
        (:class:`fohw.model.output_map.CustomMap`: code is never stored).

    Returns
    -------
    IdentificationResult or FitResult
        As the file says (a fit of a kind other than the lagged one is a FitResult; its kind
        must be defined before loading).

    Raises
    ------
    DataFileError
        The file is not a fohw-result file, a field is of the wrong kind, or two stored facts
        disagree (:func:`result_from_dict` lists the checks); the message names the field.
    """
    return result_from_dict(read_json(path), f_basis=f_basis, g_basis=g_basis,
                            output_map=output_map, path=os.fspath(path))
