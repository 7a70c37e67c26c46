"""Saving and loading models and identification results as versioned JSON (never pickle).

Floats are written with Python's shortest round-trip representation, so every number reads
back bit for bit. Polynomial bases are stored by degree; any other basis is stored by the
names of its functions only (code is never serialised), and loading then needs the same basis
passed in, checked by those names.
"""

from __future__ import annotations

import json
import os
import tempfile

import numpy as np

from ..exceptions import DataFileError, ParameterError
from ..model.basis import MAX_POLYNOMIAL_DEGREE, Basis, as_basis, polynomial_basis
from ..model.orders import Orders
from ..model.structure import Structure
from ..model.system import HammersteinWiener

__all__ = ["save_model", "load_model", "load_result", "MODEL_FORMAT_VERSION",
           "RESULT_FORMAT_VERSION"]

#: Version of the model files this fohw writes (it reads the versions in ``_READS``): 2 added
#: the structure (orders per term, dt, offset, past levels, operating point).
MODEL_FORMAT_VERSION = 2
#: Version of the result files: 2 replaced ``n_iter``/``converged`` by ``status``/``nit``/``nfev``
#: and added the structure and its estimates (orders, offset, past, operating point).
RESULT_FORMAT_VERSION = 2
_READS = {"fohw-model": (1, 2), "fohw-result": (1, 2)}


def _basis_to_dict(basis: Basis) -> dict:
    if basis.is_polynomial:
        return {"kind": "polynomial", "degree": len(basis)}
    return {"kind": "custom", "names": list(basis.names)}


def _basis_from_dict(d: dict, given, name: str, path: str) -> Basis:
    if not isinstance(d, dict):
        raise DataFileError(f"{path}: field {name!r} must be an object such as "
                            f'{{"kind": "polynomial", "degree": 2}}; got {d!r}.')
    kind = d.get("kind")
    if kind == "polynomial":
        degree = d.get("degree")
        if isinstance(degree, bool) or not isinstance(degree, int) \
                or not 1 <= degree <= MAX_POLYNOMIAL_DEGREE:
            raise DataFileError(f"{path}: field {name!r}: 'degree' must be an integer from 1 to "
                                f"{MAX_POLYNOMIAL_DEGREE}; got {degree!r}.")
        stored = polynomial_basis(degree)
        if given is not None and as_basis(given, name) != stored:
            raise ParameterError(f"`{name}` does not match the polynomial basis of degree "
                                 f"{degree} stored in {path}.")
        return stored
    if kind != "custom":
        raise DataFileError(f"{path}: field {name!r} has kind {kind!r}; fohw writes 'polynomial' "
                            "(a degree) or 'custom' (names of functions passed again on loading).")
    names = d.get("names")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise DataFileError(f"{path}: field {name!r}: 'names' must be a non-empty list of "
                            f"strings; got {names!r}.")
    if given is None:
        raise ParameterError(f"{path} was saved with a custom `{name}` ({names}); its functions "
                             f"are code, which fohw never stores: load it in Python and pass the "
                             f"same basis, fohw.load_model(path, {name}=...) or "
                             f"fohw.load_result(path, {name}=...) (the command line cannot).")
    basis = as_basis(given, name)
    if list(basis.names) != names:
        raise ParameterError(f"`{name}` has functions {list(basis.names)}, but {path} was saved "
                             f"with {names}.")
    return basis


def _floats(a) -> list:
    return [float(x) for x in np.asarray(a, dtype=np.float64).ravel()]


def _structure_from_dict(d, f_basis, g_basis) -> Structure:
    return Structure(Orders.from_dict(d["orders"]), f_basis, g_basis, offset=d["offset"],
                     past=d["past"], dt=d["dt"])


def model_to_dict(model: HammersteinWiener) -> dict:
    """A JSON-ready dict of a model."""
    return {"format": "fohw-model", "version": MODEL_FORMAT_VERSION,
            "a": _floats(model.a), "b": _floats(model.b), "p": _floats(model.p),
            "q": _floats(model.q), "orders": dict(model.orders),
            "structure": model.structure.to_dict(), "offset": float(model.offset),
            "past": list(model.past), "operating_point": list(model.operating_point),
            "f_basis": _basis_to_dict(model.f_basis), "g_basis": _basis_to_dict(model.g_basis)}


def model_from_dict(d: dict, *, f_basis=None, g_basis=None, path="<dict>") -> HammersteinWiener:
    """Inverse of :func:`model_to_dict` (version 1 files: the paper's model).

    Fields of the wrong type or value are a :class:`~fohw.DataFileError` naming the file.
    """
    version = _check_header(d, "fohw-model", path)
    for key in ("f_basis", "g_basis"):
        if key not in d:
            raise DataFileError(f"{path}: missing field {key!r}.")
    f = _basis_from_dict(d["f_basis"], f_basis, "f_basis", path)
    g = _basis_from_dict(d["g_basis"], g_basis, "g_basis", path)
    try:
        if version == 1:
            return HammersteinWiener(d["a"], d["b"], d["p"], d["q"], d["alpha"], f_basis=f,
                                     g_basis=g)
        structure = _structure_from_dict(d["structure"], f, g)
        return HammersteinWiener(d["a"], d["b"], d["p"], d["q"], d["orders"], f_basis=f,
                                 g_basis=g, orders=structure.orders, dt=structure.dt,
                                 offset=d["offset"], past=tuple(d["past"]),
                                 operating_point=tuple(d["operating_point"]))
    except KeyError as exc:
        raise DataFileError(f"{path}: missing field {exc.args[0]!r}.") from None
    except (TypeError, ValueError, AttributeError) as exc:    # ParameterError is a ValueError
        raise DataFileError(f"{path}: malformed fohw-model file: {exc}") from None


def _check_header(d, kind, path):
    if not isinstance(d, dict) or d.get("format") != kind:
        raise DataFileError(f"{path} is not a {kind} file (field 'format' must be {kind!r}).")
    version = d.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version not in _READS[kind]:
        readable = " or ".join(str(v) for v in _READS[kind])
        what = f"the string {version!r}" if isinstance(version, str) else repr(version)
        raise DataFileError(f"{path}: field 'version' is {what}; this fohw reads {kind} files "
                            f"of version {readable}, written as a JSON integer.")
    return version


def _read_json(path) -> dict:
    path = os.fspath(path)
    if os.path.isdir(path):
        raise DataFileError(f"{path!r} is a directory, not a fohw JSON file.")
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except json.JSONDecodeError as exc:
        raise DataFileError(f"{path} is not valid JSON: {exc}.") from None
    except UnicodeDecodeError:
        raise DataFileError(f"{path} is not UTF-8 text, so not a fohw JSON file.") from None
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise DataFileError(f"{path}: cannot be read ({exc.strerror or exc}).") from None


def _non_finite(obj, where=""):
    """The first place in a JSON-ready object holding a NaN or an infinity, or None."""
    if isinstance(obj, float):
        return None if np.isfinite(obj) else (where or "the value", obj)
    if isinstance(obj, dict):
        items = obj.items()
        if set(obj) == {"shape", "data"}:           # an array: name it, not its 'data'
            items = [(None, obj["data"])]
    elif isinstance(obj, (list, tuple)):
        items = ((f"[{i}]", v) for i, v in enumerate(obj))
    else:
        return None
    for key, value in items:
        inner = where if key is None else (f"{where}.{key}" if where and not key.startswith("[")
                                           else f"{where}{key}")
        found = _non_finite(value, inner)
        if found is not None:
            return found
    return None


def check_output_path(path, what="the output") -> str:
    """Check, before any work, that a file can be written at ``path``; return it as a string.

    Raises
    ------
    DataFileError
        ``path`` is a directory, its folder does not exist, or the folder is not writable.
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        raise DataFileError(f"{what} {path!r} is a directory; give a file name.")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise DataFileError(f"{what} {path!r}: the folder {folder!r} does not exist.")
    if not os.access(folder, os.W_OK):
        raise DataFileError(f"{what} {path!r}: the folder {folder!r} is not writable.")
    return path


def _write_json(obj, path):
    """Write ``obj`` as JSON, atomically (see :func:`_write_text`).

    Non-finite numbers are refused before anything is written (JSON has none).
    """
    path = check_output_path(path, "the JSON file")
    bad = _non_finite(obj)
    if bad is not None:
        raise ParameterError(f"cannot save to {path}: field {bad[0]!r} is {bad[1]!r}, and JSON "
                             "holds finite numbers only; nothing was written (an existing file "
                             "is unchanged).")
    _write_text(json.dumps(obj, indent=1, allow_nan=False) + "\n", path)


def _write_text(text, path):
    """Write ``text`` to ``path`` atomically: all of it, or nothing.

    The text goes to a temporary file in the same folder, flushed to disk, which then replaces
    ``path`` in one step (:func:`os.replace`), so an interrupted or failed save never truncates
    a file: an existing one survives byte for byte. A symbolic link is written through (its
    target is replaced, the link kept); a read-only file is refused.
    """
    path = check_output_path(path, "the output file")
    path = os.path.realpath(path)             # write through a symbolic link, not over it
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise DataFileError(f"{path!r} is read-only; fohw does not replace it.")
    folder, name = os.path.split(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        if os.path.exists(path):                    # keep the permissions the file had
            os.chmod(tmp, os.stat(path).st_mode & 0o7777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def save_model(model, path):
    """Write a model to a JSON file.

    Examples
    --------
    >>> import os, tempfile, fohw
    >>> m = fohw.datasets.paper_model()
    >>> with tempfile.TemporaryDirectory() as d:
    ...     fohw.save_model(m, os.path.join(d, "m.json"))
    ...     fohw.load_model(os.path.join(d, "m.json")) == m
    True
    """
    if not isinstance(model, HammersteinWiener):
        raise ParameterError(f"`model` must be a HammersteinWiener; got {type(model).__name__}.")
    _write_json(model_to_dict(model), path)


def load_model(path, *, f_basis=None, g_basis=None):
    """Read a model written by :func:`save_model` (custom bases must be passed again)."""
    return model_from_dict(_read_json(path), f_basis=f_basis, g_basis=g_basis,
                           path=os.fspath(path))


_ARRAYS = ("theta", "theta_history", "alpha_sample_history", "alpha_history", "J_history",
           "covariance", "alpha_profile")


def result_to_dict(result) -> dict:
    """A JSON-ready dict of an :class:`fohw.IdentificationResult`."""
    d = {"format": "fohw-result", "version": RESULT_FORMAT_VERSION}
    for key in ("method", "schedule", "alpha", "J", "nit", "nfev", "message",
                "alpha_at_bound", "n_samples", "noise_variance"):
        value = getattr(result, key)
        d[key] = value.item() if isinstance(value, np.generic) else value
    d["status"] = int(result.status)
    for key in _ARRAYS:
        value = getattr(result, key)
        d[key] = None if value is None else {"shape": list(value.shape), "data": _floats(value)}
    d["layout"] = {"na": result.layout.na, "nb": result.layout.nb}
    d["f_basis"] = _basis_to_dict(result.f_basis)
    d["g_basis"] = _basis_to_dict(result.g_basis)
    d["structure"] = result.structure.to_dict()
    d["orders"] = dict(result.orders)
    d["offset"] = result.offset
    d["past"] = list(result.past)
    d["operating_point"] = list(result.operating_point)
    d["input_range"] = None if result.input_range is None else list(result.input_range)
    d["options"] = {k: _jsonable(v) for k, v in result.options.items()
                    if isinstance(v, (int, float, str, bool, tuple, dict, type(None)))}
    d["parameter_names"] = list(result.parameter_names)
    return d


def _jsonable(value):
    if isinstance(value, tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    return value


def _from_json(value):
    if isinstance(value, list):
        return tuple(_from_json(v) for v in value)
    if isinstance(value, dict):
        return {k: _from_json(v) for k, v in value.items()}
    return value


def _check_fields(d, path, version):
    """Every scalar field of a result file has its type and a finite value, before use."""
    from ..results import Status

    def bad(key, need):
        raise DataFileError(f"{path}: field {key!r} must be {need}; got {d.get(key)!r}.")

    def number(key, lower=None, optional=False):
        value = d.get(key)
        if value is None and optional:
            return
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not np.isfinite(value) or (lower is not None and value < lower):
            bad(key, "a finite number" + ("" if lower is None else f" >= {lower:g}")
                + (" or null" if optional else ""))

    def integer(key, lower):
        value = d.get(key)
        if isinstance(value, bool) or not isinstance(value, int) or value < lower:
            bad(key, f"an integer >= {lower}")

    for key in ("method", "message"):
        if not isinstance(d.get(key), str):
            bad(key, "a string")
    if d.get("schedule") is not None and not isinstance(d["schedule"], str):
        bad("schedule", "a string or null")
    number("J", lower=0.0)
    number("alpha", optional=True)
    number("noise_variance", lower=0.0, optional=True)
    integer("n_samples", 1)
    if not isinstance(d.get("alpha_at_bound"), bool):
        bad("alpha_at_bound", "true or false")
    if version == 1:
        integer("n_iter", 0)
        if not isinstance(d.get("converged"), bool):
            bad("converged", "true or false")
    else:
        integer("nit", 0)
        integer("nfev", 0)
        if isinstance(d.get("status"), bool) or d.get("status") not in {int(s) for s in Status}:
            bad("status", f"one of {sorted(int(s) for s in Status)} (fohw.Status)")
        number("offset", optional=True)
        orders = d.get("orders")
        if not isinstance(orders, dict) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
                for v in orders.values()):
            bad("orders", "an object of finite numbers (the estimated orders)")
        for key in ("past", "operating_point"):
            _finite_pair(d, key, path, optional=False)
    _finite_pair(d, "input_range", path, optional=True)


def _finite_pair(d, key, path, optional):
    value = d.get(key)
    if value is None and optional:
        return
    if not isinstance(value, list) or len(value) != 2 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
            for v in value):
        raise DataFileError(f"{path}: field {key!r} must be a pair of finite numbers"
                            + (" or null" if optional else "") + f"; got {value!r}.")


def _array_field(d, key, path):
    entry = d.get(key)
    if entry is None:
        return None
    if not isinstance(entry, dict) or not isinstance(entry.get("data"), list) \
            or not isinstance(entry.get("shape"), list):
        raise DataFileError(f"{path}: field {key!r} must be null or an object with 'shape' and "
                            "'data' lists.")
    data = entry["data"]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in data):
        raise DataFileError(f"{path}: field {key!r} holds an entry that is not a number.")
    arr = np.array(data, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        i = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise DataFileError(f"{path}: field {key!r} holds a non-finite value ({float(arr[i])!r} at "
                            f"entry {i}).")
    try:
        return arr.reshape(entry["shape"])
    except (TypeError, ValueError):
        raise DataFileError(f"{path}: field {key!r} has {arr.size} values, which do not fill "
                            f"its shape {entry['shape']!r}.") from None


def _check_covariance(cov, n_estimates, path):
    if cov is None:
        return
    if cov.shape != (n_estimates, n_estimates):
        raise DataFileError(f"{path}: field 'covariance' has shape {cov.shape}; the estimates "
                            f"need ({n_estimates}, {n_estimates}).")
    if not np.allclose(cov, cov.T, rtol=1e-10, atol=0.0):
        raise DataFileError(f"{path}: field 'covariance' is not symmetric.")
    if np.any(np.diag(cov) < 0):
        i = int(np.flatnonzero(np.diag(cov) < 0)[0])
        raise DataFileError(f"{path}: field 'covariance' has a negative variance "
                            f"({float(cov[i, i])!r} on its diagonal at {i}); a covariance matrix has "
                            "none.")


def result_from_dict(d: dict, *, f_basis=None, g_basis=None, path="<dict>"):
    """Inverse of :func:`result_to_dict`.

    Every field is checked for its type and, for numbers, finiteness before use (the estimates,
    orders, offset, past levels, operating point and input range included; a covariance must
    also be symmetric with a non-negative diagonal): a file edited or damaged by hand is a
    :class:`~fohw.DataFileError` naming the field, never a result that fails later.
    """
    from ..results import IdentificationResult, Status, recover_model

    version = _check_header(d, "fohw-result", path)
    for key in ("f_basis", "g_basis"):
        if not isinstance(d.get(key), dict):
            raise DataFileError(f"{path}: malformed fohw-result file (field {key!r} missing or "
                                "not an object).")
    _check_fields(d, path, version)
    f = _basis_from_dict(d["f_basis"], f_basis, "f_basis", path)
    g = _basis_from_dict(d["g_basis"], g_basis, "g_basis", path)
    try:
        arrays = {k: _array_field(d, k, path) for k in _ARRAYS}
        if arrays["theta"] is None:
            raise DataFileError(f"{path}: field 'theta' is missing (null).")
        if version == 1:        # the paper's model; n_iter and converged, no status or nfev
            structure = Structure(Orders.preset("commensurate", na=d["layout"]["na"],
                                                nb=d["layout"]["nb"]), f, g)
            status = Status.CONVERGED if d["converged"] else Status.MAX_ITER
            nit = nfev = d["n_iter"]
            orders, offset, past, point = {"alpha": d["alpha"]}, None, (0.0, 0.0), (0.0, 0.0)
        else:
            structure = _structure_from_dict(d["structure"], f, g)
            status, nit, nfev = Status(d["status"]), d["nit"], d["nfev"]
            orders, offset = d["orders"], d["offset"]
            past, point = tuple(d["past"]), tuple(d["operating_point"])
        model, _ = recover_model(structure, arrays["theta"], orders, offset=offset, past=past,
                                 operating_point=point)
        opts = {k: _from_json(v) for k, v in d["options"].items()}
        result = IdentificationResult(
            method=d["method"], schedule=d["schedule"], alpha=d["alpha"], model=model, J=d["J"],
            status=status, nit=nit, nfev=nfev, message=d["message"],
            alpha_at_bound=d["alpha_at_bound"], layout=structure.layout, f_basis=f, g_basis=g,
            n_samples=d["n_samples"], options=opts, noise_variance=d["noise_variance"],
            structure=structure, orders=orders, offset=offset, past=past, operating_point=point,
            input_range=None if d.get("input_range") is None else tuple(d["input_range"]),
            **arrays)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, DataFileError):
            raise
        raise DataFileError(f"{path}: malformed fohw-result file ({type(exc).__name__}: "
                            f"{exc}).") from None
    _check_covariance(result.covariance, len(result.estimate_names), path)
    return result


def load_result(path, *, f_basis=None, g_basis=None):
    """Read an identification result written by ``IdentificationResult.to_json``.

    Parameters
    ----------
    path : str or os.PathLike
    f_basis, g_basis : Basis, optional
        Needed (and checked by name) when the result used custom basis functions.

    Returns
    -------
    IdentificationResult
    """
    return result_from_dict(_read_json(path), f_basis=f_basis, g_basis=g_basis,
                            path=os.fspath(path))
