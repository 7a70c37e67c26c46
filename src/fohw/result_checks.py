"""Is a fit's dict sound? One validator for :meth:`fohw.FitResult.from_dict` and the result files.

A :class:`fohw.FitResult` of any kind is written as :meth:`~fohw.FitResult.to_dict` and read
back by :meth:`~fohw.FitResult.from_dict`, directly or through :func:`fohw.load_result`. Both
paths check the dict here, field by field, before anything is built: each field's type and, for
numbers, finiteness and range; a covariance square, of the free parameters' size, symmetric and
without a negative variance; residuals one per sample (at least ``n_samples``, the samples in
the criterion); per-record estimates of free parameters of the model, one value per record, as
many as ``n_per_record`` counts. A bad field is an error naming it (a
:class:`~fohw.ParameterError` for a dict, a :class:`~fohw.DataFileError` naming the file for
:func:`fohw.load_result`), never a result that fails or misleads later.
"""

from __future__ import annotations

import numpy as np

from ._status import Status
from .exceptions import DimensionError, ParameterError
from .model.base import Model
from .model.parameters import Parameters

__all__ = ["check_fit_result_dict", "check_model_dict", "FIT_RESULT_FIELDS", "FIT_RESULT_OPTIONAL",
           "MODEL_DICT_FIELDS", "DATA_FIELDS", "bad_field", "is_number", "check_number",
           "check_integer", "require_fields", "number_list", "check_covariance"]

#: The fields of a model of a kind other than the lagged one (:meth:`fohw.Model.to_dict`).
MODEL_DICT_FIELDS = ("kind", "config", "parameters")
#: The fields of a fit of such a kind (:meth:`fohw.FitResult.to_dict`).
FIT_RESULT_FIELDS = ("model", "covariance", "status", "sse", "n_samples", "message", "nfev",
                     "jacobian", "starts", "residuals", "data_digest", "options")
#: Fields a fit may have besides those: what the data were (names, units, sampling of the
#: records) and the per-record estimates of a fit to several records.
FIT_RESULT_OPTIONAL = ("data", "per_record", "n_per_record")
#: The keys of a fit's ``data`` field (:attr:`fohw.FitResult.data`).
DATA_FIELDS = ("input_names", "input_units", "output_name", "output_unit", "time_unit", "dt",
               "records")


def bad_field(d, key, need, where, error=ParameterError):
    """Raise ``error``: ``"{where}: field {key!r} must be {need}; got {value!r}."``."""
    value = d.get(key) if isinstance(d, dict) else d
    raise error(f"{where}: field {key!r} must be {need}; got {value!r}."[:600])


def is_number(v) -> bool:
    """A real number (int or float, not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def check_number(d, key, where, lower=None, optional=False, error=ParameterError):
    """``d[key]`` is a finite number (``>= lower``; or None when ``optional``), or raise."""
    value = d.get(key)
    if value is None and optional:
        return
    if not is_number(value) or not np.isfinite(value) or (lower is not None and value < lower):
        bad_field(d, key, "a finite number" + ("" if lower is None else f" >= {lower:g}")
                  + (" or null" if optional else ""), where, error)


def check_integer(d, key, where, lower, error=ParameterError):
    """``d[key]`` is an integer ``>= lower`` (not a bool, not a float), or raise."""
    value = d.get(key)
    if isinstance(value, bool) or not isinstance(value, int) or value < lower:
        bad_field(d, key, f"an integer >= {lower}", where, error)


def require_fields(d, names, what, where, *, header=(), error=ParameterError):
    """Exactly the fields ``names`` (and ``header``): a missing or an unknown one is an error."""
    for key in names:
        if key not in d:
            raise error(f"{where}: missing field {key!r}.")
    unknown = sorted(set(d) - set(names) - set(header))
    if unknown:
        raise error(f"{where}: field {unknown[0]!r} is not part of {what} (it stores each fact "
                    f"once, in the fields {', '.join(sorted(names))}).")


def number_list(d, key, where, ndim, error=ParameterError):
    """A list (of equal lists, for ``ndim`` 2) of finite numbers as an array, or raise."""
    value = d[key]
    rows = value if ndim == 2 else [value]
    if not isinstance(value, list) or not all(
            isinstance(r, list) and all(is_number(v) and np.isfinite(v) for v in r)
            for r in rows) or len({len(r) for r in rows}) > 1:
        need = "a list of finite numbers" if ndim == 1 else "a matrix (list of equal rows)"
        raise error(f"{where}: field {key!r} must be null or {need} of finite numbers; got "
                    f"{value!r}."[:600])
    if ndim == 1:
        return np.array(value, dtype=np.float64)
    return np.array(value, dtype=np.float64).reshape(-1, len(rows[0]) if rows else 0)


def check_covariance(cov, n_estimates, where, error=ParameterError):
    """A covariance of ``n_estimates`` estimates: square, symmetric, no negative variance."""
    if cov is None:
        return
    if cov.shape != (n_estimates, n_estimates):
        raise error(f"{where}: field 'covariance' has shape {cov.shape}; the estimates "
                    f"need ({n_estimates}, {n_estimates}).")
    if not np.allclose(cov, cov.T, rtol=1e-10, atol=0.0):
        raise error(f"{where}: field 'covariance' is not symmetric.")
    if np.any(np.diag(cov) < 0):
        i = int(np.flatnonzero(np.diag(cov) < 0)[0])
        raise error(f"{where}: field 'covariance' has a negative variance "
                    f"({float(cov[i, i])!r} on its diagonal at {i}); a covariance matrix has "
                    "none.")


def check_model_dict(body, where, *, field="the file", what="a fohw-model file",
                     error=ParameterError) -> Model:
    """The model of a registered kind from its ``{"kind", "config", "parameters"}``, checked.

    The model is rebuilt through the registry (:meth:`fohw.Model.from_dict`) and its
    parameters must be those stored.
    """
    if not isinstance(body, dict):
        raise error(f"{where}: {field} must be an object with the fields "
                    f"{', '.join(MODEL_DICT_FIELDS)}; got {body!r}."[:600])
    require_fields(body, MODEL_DICT_FIELDS, what, where, error=error)
    if not isinstance(body["kind"], str):
        bad_field(body, "kind", "the name of a registered model kind (a string)", where, error)
    if not isinstance(body["config"], dict):
        bad_field(body, "config", "an object (the kind's settings)", where, error)
    if not isinstance(body["parameters"], dict) or not body["parameters"]:
        bad_field(body, "parameters", "an object name -> parameter", where, error)
    try:
        stored = Parameters.from_dict(body["parameters"])
        model = Model.from_dict(body)
    except (ParameterError, DimensionError, TypeError, ValueError, KeyError,
            AttributeError) as exc:
        raise error(f"{where}: cannot rebuild the {body['kind']!r} model of {field}: "
                    f"{exc}") from None
    if model.parameters != stored:
        raise error(f"{where}: the {body['kind']!r} model rebuilt from {field} has the "
                    f"parameters {model.parameters!r}, not the stored {stored!r}: the kind "
                    "or the stored model disagree.")
    return model


def _check_data(body, where, error):
    """The ``data`` field: empty, or every key of :data:`DATA_FIELDS` with a list of records."""
    data = body["data"]
    if not isinstance(data, dict):
        bad_field(body, "data", "an object", where, error)
    if not data:
        return
    if set(data) != set(DATA_FIELDS):
        bad_field(body, "data", f"an object with the keys {', '.join(DATA_FIELDS)}", where, error)
    if not (isinstance(data["records"], list) and data["records"] and all(
            isinstance(r, dict) and isinstance(r.get("n_samples"), int)
            and not isinstance(r.get("n_samples"), bool) and r["n_samples"] >= 1
            for r in data["records"])):
        bad_field(body, "data", "an object whose 'records' is a list of {name, n_samples, t0, "
                  "uniform, dt}", where, error)


def _check_per_record(body, model, where, error):
    """``per_record`` and ``n_per_record``: what a fit to several records wrote, consistent."""
    per = body.get("per_record", {})
    n_extra = body.get("n_per_record", 0)
    if not isinstance(per, dict):
        bad_field(body, "per_record", "an object", where, error)
    free = model.parameters.free_names
    lengths = set()
    for name, entry in per.items():
        values = entry.get("values") if isinstance(entry, dict) else None
        se = entry.get("standard_errors") if isinstance(entry, dict) else None
        ok = isinstance(entry, dict) and set(entry) == {"values", "standard_errors"} and \
            isinstance(values, list) and len(values) >= 2 and \
            all(is_number(v) and np.isfinite(v) for v in values) and \
            (se is None or (isinstance(se, list) and len(se) == len(values)
                            and all(is_number(v) and np.isfinite(v) and v >= 0 for v in se)))
        if not ok:
            bad_field(body, "per_record", f"an object name -> {{values: [a finite number per "
                      f"record, at least 2], standard_errors: [as many numbers >= 0] or null}} "
                      f"(entry {name!r})", where, error)
        if name not in free:
            raise error(f"{where}: field 'per_record' has an entry {name!r}, which is not a free "
                        f"parameter of the model (its free parameters: {', '.join(free)}).")
        lengths.add(len(values))
    if len(lengths) > 1:
        raise error(f"{where}: field 'per_record' gives {sorted(lengths)} values for different "
                    "parameters; each gives one value per record.")
    records = (body.get("data") or {}).get("records")
    if lengths and records and lengths != {len(records)}:
        raise error(f"{where}: field 'per_record' gives {lengths.pop()} values per parameter, but "
                    f"field 'data' lists {len(records)} records.")
    counted = sum(len(e["values"]) - 1 for e in per.values())
    if n_extra != counted:
        raise error(f"{where}: field 'n_per_record' is {n_extra}, but field 'per_record' holds "
                    f"{counted} values besides the first record's (each per-record parameter's "
                    "copies for the records after the first).")


def check_fit_result_dict(d, *, where="FitResult.from_dict(d)", what="a FitResult dict",
                          error=ParameterError) -> Model:
    """Check a fit's dict (:meth:`fohw.FitResult.to_dict`) field by field; its model, rebuilt.

    Parameters
    ----------
    d : dict
        The fit's content (a result file's, without its header).
    where : str
        What the messages start with (the file's path for :func:`fohw.load_result`).
    what : str
        What ``d`` is, for the message on a field it does not have.
    error : type
        The exception raised (:class:`~fohw.DataFileError` for a file).

    Returns
    -------
    Model
        The fitted model, rebuilt from ``d["model"]`` (:func:`check_model_dict`).

    Raises
    ------
    ParameterError (or ``error``)
        ``d`` is not an object; a field is missing or unknown, of the wrong type, not finite,
        out of range (``sse`` < 0, ``n_samples`` < 1, ``nfev`` or ``n_per_record`` < 0), or
        contradicts another (the covariance's size, symmetry and variances, ``residuals``
        fewer than ``n_samples`` or not one per sample of the records, ``per_record``
        against the model, the records and ``n_per_record``). The message names the field.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> d = fohw.fit(G, u, G.simulate(u), n_starts=1).to_dict()
    >>> try:
    ...     fohw.FitResult.from_dict({**d, "sse": -1.0})
    ... except fohw.ParameterError as exc:
    ...     print(exc)
    FitResult.from_dict(d): field 'sse' must be a finite number >= 0; got -1.0.
    """
    if not isinstance(d, dict):
        raise error(f"{where}: a fit's content must be an object (a dict, as FitResult.to_dict "
                    f"makes) with the fields {', '.join(FIT_RESULT_FIELDS)}; got "
                    f"{type(d).__name__}.")
    require_fields(d, FIT_RESULT_FIELDS + tuple(k for k in FIT_RESULT_OPTIONAL if k in d),
                   what, where, error=error)
    if "n_per_record" in d:
        check_integer(d, "n_per_record", where, 0, error)
    if "data" in d:
        _check_data(d, where, error)
    model = check_model_dict(d["model"], where, field="field 'model'", what=what, error=error)
    if not isinstance(d["status"], str) or d["status"] not in Status.__members__:
        bad_field(d, "status", f"one of {list(Status.__members__)}", where, error)
    check_number(d, "sse", where, lower=0.0, error=error)
    check_integer(d, "n_samples", where, 1, error)
    check_integer(d, "nfev", where, 0, error)
    for key in ("message", "jacobian", "data_digest"):
        if not isinstance(d[key], str):
            bad_field(d, key, "a string", where, error)
    if not isinstance(d["options"], dict):
        bad_field(d, "options", "an object", where, error)
    starts = d["starts"]
    if not isinstance(starts, list) or not all(
            isinstance(r, list) and len(r) == 2 and isinstance(r[0], dict)
            and all(is_number(v) for v in r[0].values())
            and (r[1] is None or is_number(r[1])) for r in starts):
        bad_field(d, "starts", "a list of [order values, sse or null]", where, error)
    if d["covariance"] is not None:
        check_covariance(number_list(d, "covariance", where, 2, error),
                         len(model.parameters.free_names), where, error)
    if d["residuals"] is not None:
        # one per sample: n_samples counts those in the criterion (a sample_weight of 0 leaves
        # one out), the records' n_samples all of them
        res = number_list(d, "residuals", where, 1, error)
        records = (d.get("data") or {}).get("records")
        total = sum(r["n_samples"] for r in records) if records else None
        if res.size < d["n_samples"] or (total is not None and res.size != total):
            each = "" if total is None else f" and the records' {total} samples"
            raise error(f"{where}: field 'residuals' has {res.size} values for n_samples = "
                        f"{d['n_samples']}{each} (one per sample): the fit contradicts itself.")
    _check_per_record(d, model, where, error)
    return model
