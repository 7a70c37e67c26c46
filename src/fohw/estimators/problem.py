"""One identification problem: the record and model class checked, then a method run on it.

:func:`prepare` turns what :func:`fohw.identify` is given (the data, the structure keywords,
``operating_point`` and ``alpha_bounds``) into a :class:`Problem`: the regressor builder of the
deviations from the operating point and the bounds of the free orders, with the warnings about
the data said once. :func:`fit_method` runs one declared :class:`~fohw.estimators.options.Method`
on it. Both :func:`fohw.identify` and the estimator classes (:class:`fohw.estimators.hybrid.HybridIdentifier`)
call it, so the estimator modules never import :mod:`fohw.estimators.identify`.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np

from .._validation import (
    AlphaBounds,
    check_array,
    check_inputs,
    check_int,
    check_same_length,
    check_scalar,
    unpack_pair,
)
from ..exceptions import DataWarning, DimensionError, ParameterError
from ..model.lagged.regressors import RegressorBuilder
from ..model.lagged.structure import Structure
from ._common import check_units, rms_scale

__all__ = ["Problem", "prepare", "fit_method", "OPERATING_POINTS"]

#: ``operating_point`` spellings besides an explicit ``(u0, y0)``.
OPERATING_POINTS = ("initial", "mean")


@dataclass(frozen=True)
class Problem:
    """A record ready for estimation.

    Attributes
    ----------
    builder : RegressorBuilder
        The deviations of ``u`` and ``y`` from the operating point, and the structure.
    bounds : (ndarray, ndarray)
        Lower and upper bounds of each free order.
    operating_point : (float, float)
        ``(u0, y0)`` removed from the data.
    input_range : (float, float)
        ``(min u, max u)`` of the record as given (several inputs: ``(mins, maxs)``, a tuple
        per input each).
    """

    builder: RegressorBuilder
    bounds: tuple
    operating_point: tuple
    input_range: tuple

    @property
    def structure(self):
        """The model class (:class:`fohw.Structure`)."""
        return self.builder.structure


def prepare(u, y, *, na=None, nb=None, f_basis=None, g_basis=None, orders="commensurate",
            offset=False, operating_point=None, past="rest", dt=1.0, alpha_bounds=(0.0, 1.0),
            output_map=None, nk=1, inputs=None, structure=None):
    """Check a record and a model class; warn about the data once; return the :class:`Problem`.

    The keywords are those of :func:`fohw.identify`. ``u`` of shape ``(N, m)`` (or a pandas
    DataFrame, whose column names name the inputs) has ``m`` inputs; ``nb``, ``nk`` and
    ``f_basis`` are then one per input (a list) or one for all. Or the class itself,
    ``structure`` (a :class:`fohw.Structure`, e.g. a :class:`fohw.ThetaHW`'s): then the
    keywords that make one (``na`` … ``inputs``) are not given.
    """
    if structure is None:
        u, inputs = split_inputs(u, names=inputs)
    else:
        u, _ = split_inputs(u, names=structure.inputs if structure.n_inputs > 1 else None)
        if (u.ndim == 2) != (structure.n_inputs > 1):
            raise DimensionError(f"the model has {structure.n_inputs} input(s); `u` has "
                                 f"{1 if u.ndim == 1 else u.shape[1]} column(s).")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if structure is None:
        if not isinstance(offset, (bool, np.bool_)):
            raise ParameterError(f"`offset` must be True or False; got {offset!r}.")
        if inputs is None:
            if not isinstance(nb, (list, tuple, np.ndarray)):
                nb = check_int(nb, "nb", minimum=1)
            _check_single_basis(f_basis)
        structure = Structure.make(na=check_int(na, "na", minimum=1), nb=nb, f_basis=f_basis,
                                   g_basis=g_basis, orders=orders, offset=bool(offset), past=past,
                                   dt=dt, nk=nk, inputs=inputs, output_map=output_map)
    inputs = structure.inputs if structure.n_inputs > 1 else None
    point = _operating_point(operating_point, u, y)
    bounds = _order_bounds(structure, alpha_bounds)
    if inputs is None:
        u_dev = u - point[0] if point[0] else u
        u_range = (float(u.min()), float(u.max()))
    else:
        u_dev = u - np.asarray(point[0]) if any(point[0]) else u
        u_range = (tuple(float(x) for x in u.min(axis=0)),
                   tuple(float(x) for x in u.max(axis=0)))
    y_dev = y - point[1] if point[1] else y
    _check_offset(structure, u_dev)
    if operating_point is None and not structure.offset:
        _warn_levels(u, y)
    _warn_tiny(y_dev)
    builder = RegressorBuilder(u_dev, y_dev, structure=structure)
    check_units(builder)
    return Problem(builder, bounds, point, u_range)


def _check_single_basis(f_basis):
    """One input: a list of bases (ints, Basis objects) is one per input, so the wrong length."""
    from ..model.basis import Basis

    if isinstance(f_basis, (list, tuple)) and len(f_basis) > 1 and all(
            isinstance(b, (int, np.integer, Basis)) and not isinstance(b, bool) for b in f_basis):
        raise DimensionError(f"`f_basis` gives {len(f_basis)} bases (one per input), but `u` has "
                             "1 column (a single input).")


def split_inputs(u, name="u", names=None):
    """``(u, input names)``: a 1-D input and ``None``, or ``(N, m)`` and ``m`` names.

    ``names`` if given, else a pandas DataFrame's column names (``u1, u2, …`` otherwise); a
    single column, ``(N, 1)``, is the single-input model of a 1-D ``u``.
    """
    columns = getattr(u, "columns", None) if type(u).__module__.startswith("pandas") else None
    if np.ndim(u) == 2 and np.shape(u)[1] == 0:
        raise DimensionError(f"`{name}` has no columns (shape ({np.shape(u)[0]}x0)): give one column per "
                             "input.")
    if np.ndim(u) == 2 and np.shape(u)[1] > 1:
        arr = check_inputs(u, np.shape(u)[1], name)
        if names is None:
            names = (tuple(str(c) for c in columns) if columns is not None else
                     tuple(f"u{i}" for i in range(1, arr.shape[1] + 1)))
        elif isinstance(names, (str, bytes)) or len(names) != arr.shape[1]:
            raise DimensionError(f"`inputs` must name the {arr.shape[1]} columns of `{name}`; "
                                 f"got {names!r}.")
        return arr, tuple(names)
    if names is not None and (isinstance(names, (str, bytes)) or len(names) != 1):
        raise DimensionError(f"`inputs` must name the 1 column of `{name}`; got {names!r}.")
    u = np.asarray(u)[:, 0] if np.ndim(u) == 2 else u
    return check_inputs(u, 1, name), None


def fit_method(method, options, u, y, executor=None, **model):
    """Run one method on a record: :func:`prepare`, the method's own checks, then its run.

    Parameters
    ----------
    method : Method
        The declared method (:class:`fohw.estimators.options.Method`).
    options : MethodOptions
        Its options, names already checked (:meth:`MethodOptions.build`); their values are
        checked here against the record.
    u, y : array_like
        The record.
    executor : concurrent.futures.Executor, optional
        Where a method with independent starts (``method.parallel``) runs them; an error for
        any other method (nothing is ignored).
    **model
        The keywords of :func:`prepare`.

    Returns
    -------
    IdentificationResult
    """
    extra = {}
    if executor is not None:
        if not method.parallel:
            raise ParameterError(f"method {method.name!r} runs nothing in parallel, so it takes "
                                 f"no `executor`; got {type(executor).__name__}. `executor` is "
                                 "used by method='output_error' (its starts).")
        if not isinstance(executor, Executor):
            raise ParameterError("`executor` must be a concurrent.futures.Executor (e.g. a "
                                 "ProcessPoolExecutor, or dask's Client.get_executor()) or "
                                 f"None; got {type(executor).__name__}.")
        extra["executor"] = executor
    problem = prepare(u, y, **model)
    if problem.structure.output_map is not None and not method.output_map:
        raise ParameterError(
            f"method {method.name!r} cannot fit a series `output_map` "
            f"({problem.structure.output_map.describe()}): it minimises the one-step "
            "(equation) error, and y = h(z) puts the unmeasured z inside the equation. Use "
            "method='output_error' (simulation error), or fit without output_map first.")
    reason = method.supports(problem.structure)
    if reason:
        raise ParameterError(f"method {method.name!r} {reason}")
    options = options.check(n_samples=problem.builder.n_samples, bounds=problem.bounds)
    # Overflow is not left to NumPy's RuntimeWarning: every estimator checks its estimates
    # and criterion for finiteness and raises EstimationDivergedError with the reason.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        result = method.run(problem.builder, options, problem.bounds,
                            operating_point=problem.operating_point, **extra)
    return replace(result, input_range=problem.input_range)


def _operating_point(spec, u, y):
    if u.ndim == 2:                  # several inputs: u0 one level per input
        from ..model.lagged.simulation import check_input_point

        m = u.shape[1]
        if spec is None:
            return (0.0,) * m, 0.0
        if spec == "initial":
            return tuple(float(x) for x in u[0]), float(y[0])
        if spec == "mean":
            return tuple(float(x) for x in np.mean(u, axis=0)), float(np.mean(y))
        if isinstance(spec, str):
            raise ParameterError(f"`operating_point` must be None, one of {OPERATING_POINTS} or "
                                 f"a pair (u0, y0); got {spec!r}.")
        return check_input_point(spec, m)
    if spec is None:
        return (0.0, 0.0)
    if isinstance(spec, str):
        if spec == "initial":
            return (float(u[0]), float(y[0]))
        if spec == "mean":
            return (float(np.mean(u)), float(np.mean(y)))
        raise ParameterError(f"`operating_point` must be None, one of {OPERATING_POINTS} or a "
                             f"pair (u0, y0); got {spec!r}.")
    if isinstance(spec, Mapping):
        unpack_pair(spec, "operating_point", "(u0, y0)")
    try:
        u0, y0 = spec
    except (TypeError, ValueError):
        raise ParameterError(f"`operating_point` must be None, one of {OPERATING_POINTS} or a "
                             f"pair (u0, y0); got {spec!r}.") from None
    return (check_scalar(u0, "operating_point[0]"), check_scalar(y0, "operating_point[1]"))


def _order_bounds(structure, alpha_bounds):
    """``(lower, upper)`` arrays over the free orders from a pair or a dict by name."""
    free = structure.orders.free
    if isinstance(alpha_bounds, Mapping):
        unknown = sorted(set(alpha_bounds) - set(free))
        missing = [n for n in free if n not in alpha_bounds]
        if unknown or missing:
            raise ParameterError(f"`alpha_bounds` by name must give exactly the free orders "
                                 f"{list(free)}; unknown {unknown}, missing {missing}.")
        pairs = [AlphaBounds(alpha_bounds[n], name=f"alpha_bounds[{n!r}]") for n in free]
    else:                   # a pair is checked even when nothing is free: never ignored
        b = AlphaBounds(alpha_bounds)
        pairs = [b] * len(free)
    return np.array([b.lo for b in pairs]), np.array([b.hi for b in pairs])


def _warn_tiny(y):
    """Warn when squares of ``y`` underflow: J, the noise variance and the covariance cannot."""
    scale = rms_scale(y)
    if np.any(y) and scale * scale < np.finfo(np.float64).tiny:
        warnings.warn(
            f"fohw.identify: `y` has RMS {scale:.3g}, whose square is below the smallest normal "
            "double (2.2e-308): J, the noise variance and the standard errors are squares of "
            "it and come out 0 or NaN (basis columns such as y**3 may underflow as well). "
            "Rescale the data (e.g. y * 1e150; fohw's models follow a change of units).",
            DataWarning, stacklevel=5)


def _warn_levels(u, y):
    """Warn when a signal sits far from 0 and the model has no way to represent the level."""
    signals = [("u", u)] if u.ndim == 1 else [(f"u[:, {i}]", u[:, i]) for i in range(u.shape[1])]
    for name, x in signals + [("y", y)]:
        scale = float(np.max(np.abs(x)))
        if scale == 0.0:
            continue
        mean, sd = float(np.mean(x / scale)), float(np.std(x / scale))   # no overflow
        if abs(mean) > sd:
            mean *= scale
            ratio = (f"{abs(mean) / sd:.1f} times its standard deviation" if sd > 0
                     else "and it is constant")
            warnings.warn(
                f"fohw.identify: `{name}` has mean {mean:.4g}, {ratio}, "
                "and the model has neither `offset` nor `operating_point`: it then assumes the "
                "signals rested at 0 before k = 0 and must explain the level with its dynamics, "
                "which commonly drives the fractional orders to 0. Pass operating_point='mean' "
                "(or 'initial', or (u0, y0)) or offset=True (docs/real_data.md).",
                DataWarning, stacklevel=5)


def _check_offset(structure, u):
    """An offset beside order-0 input terms needs an input that is not constant."""
    if not structure.offset:
        return
    if any(t.order == 0.0 for t in structure.orders.input) and np.any(np.ptp(u, axis=0) == 0.0):
        raise ParameterError("`offset=True` cannot be estimated from this record: the input is "
                             "constant, so the offset cannot be told apart from the order-0 "
                             "input terms. Use a record where the input moves, or offset=False.")

