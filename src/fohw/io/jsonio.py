"""Saving and loading models and identification results as versioned JSON (never pickle).

Floats are written with Python's shortest round-trip representation, so every number reads
back bit for bit. Polynomial bases are stored by degree; any other basis is stored by the
names of its functions only (code is never serialised), and loading then needs the same basis
passed in, checked by those names.
"""

from __future__ import annotations

import json
import os

import numpy as np

from ..exceptions import DataFileError, ParameterError
from ..model.basis import Basis, as_basis, polynomial_basis
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
    if d.get("kind") == "polynomial":
        stored = polynomial_basis(int(d["degree"]))
        if given is not None and as_basis(given, name) != stored:
            raise ParameterError(f"`{name}` does not match the polynomial basis of degree "
                                 f"{d['degree']} stored in {path}.")
        return stored
    if given is None:
        raise ParameterError(f"{path} was saved with a custom `{name}` ({d.get('names')}); "
                             f"pass the same basis: load_…(path, {name}=...).")
    basis = as_basis(given, name)
    if list(basis.names) != list(d.get("names", [])):
        raise ParameterError(f"`{name}` has functions {list(basis.names)}, but {path} was saved "
                             f"with {d.get('names')}.")
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
    """Inverse of :func:`model_to_dict` (version 1 files: the paper's model)."""
    version = _check_header(d, "fohw-model", path)
    try:
        f = _basis_from_dict(d["f_basis"], f_basis, "f_basis", path)
        g = _basis_from_dict(d["g_basis"], g_basis, "g_basis", path)
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


def _check_header(d, kind, path):
    if not isinstance(d, dict) or d.get("format") != kind:
        raise DataFileError(f"{path} is not a {kind} file (field 'format' must be {kind!r}).")
    version = d.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version not in _READS[kind]:
        readable = " or ".join(str(v) for v in _READS[kind])
        raise DataFileError(f"{path}: field 'version' is {version!r}; this fohw reads {kind} "
                            f"files of version {readable} (an integer).")
    return version


def _read_json(path) -> dict:
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except json.JSONDecodeError as exc:
        raise DataFileError(f"{path} is not valid JSON: {exc}.") from None


def _write_json(obj, path):
    with open(os.fspath(path), "w", encoding="utf-8") as fh:
        json.dump(obj, fh, indent=1, allow_nan=False)
        fh.write("\n")


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


def result_from_dict(d: dict, *, f_basis=None, g_basis=None, path="<dict>"):
    """Inverse of :func:`result_to_dict`."""
    from ..results import IdentificationResult, Status, recover_model

    version = _check_header(d, "fohw-result", path)
    for key in ("f_basis", "g_basis"):
        if not isinstance(d.get(key), dict):
            raise DataFileError(f"{path}: malformed fohw-result file (field {key!r} missing or "
                                "not an object).")
    f = _basis_from_dict(d["f_basis"], f_basis, "f_basis", path)
    g = _basis_from_dict(d["g_basis"], g_basis, "g_basis", path)
    try:
        arrays = {k: (None if d[k] is None else
                      np.array(d[k]["data"], dtype=np.float64).reshape(d[k]["shape"]))
                  for k in _ARRAYS}
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
        return IdentificationResult(
            method=d["method"], schedule=d["schedule"], alpha=d["alpha"], model=model, J=d["J"],
            status=status, nit=nit, nfev=nfev, message=d["message"],
            alpha_at_bound=d["alpha_at_bound"], layout=structure.layout, f_basis=f, g_basis=g,
            n_samples=d["n_samples"], options=opts, noise_variance=d["noise_variance"],
            structure=structure, orders=orders, offset=offset, past=past, operating_point=point,
            input_range=None if d.get("input_range") is None else tuple(d["input_range"]),
            **arrays)
    except (KeyError, TypeError, ValueError) as exc:
        raise DataFileError(f"{path}: malformed fohw-result file ({type(exc).__name__}: "
                            f"{exc}).") from None


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
