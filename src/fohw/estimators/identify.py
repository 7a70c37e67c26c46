"""The one-call entry point :func:`fohw.identify` and its table of methods (dispatch only).

The paper's alternating method lives in :mod:`fohw.estimators.hybrid`; the estimators beyond
the paper in :mod:`~fohw.estimators.varpro`, :mod:`~fohw.estimators.structured`,
:mod:`~fohw.estimators.output_error` and :mod:`~fohw.estimators.rls`. Each method's settings
are its own options class (:mod:`fohw.estimators.options`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from .._validation import AlphaBounds, check_array, check_int, check_same_length, check_scalar
from ..exceptions import DataWarning, ParameterError
from ..model.regressors import RegressorBuilder
from ..model.structure import Structure
from ._common import rms_scale
from .hybrid import (
    HybridOptions,
    SingleInnovationGradientOptions,
    SingleInnovationLMOptions,
    run_alternation,
)
from .output_error import OutputErrorOptions, output_error_result
from .rls import RlsOptions, rls_result
from .structured import StructuredOptions, structured_result
from .varpro import VarproOptions, varpro_result

__all__ = ["identify", "METHODS", "OPTIONS"]


def _alternation(method):
    def run(builder, options, bounds, operating_point):
        bounds = _paper_bounds(method, builder, bounds)
        return run_alternation(builder, method, options.check(builder.n_samples, bounds), bounds,
                               operating_point=operating_point)
    return run


def _paper_bounds(method, builder, bounds):
    """The recursive methods implement the paper's commensurate model: its one order's bounds."""
    s = builder.structure
    if not s.is_paper_model:
        raise ParameterError(
            f"method {method!r} implements the paper's commensurate model (Eq. 16: one order for "
            "every term, no offset, rest before k = 0, dt = 1); this structure is "
            f"{s.describe()}. Use method='varpro', 'structured' or 'output_error' for it.")
    lo, hi = bounds
    return AlphaBounds((float(lo[0]), float(hi[0])))


def _varpro(builder, options, bounds, operating_point):
    return varpro_result(builder, options.check(), bounds, operating_point=operating_point)


def _output_error(builder, options, bounds, operating_point):
    return output_error_result(builder, options, bounds, operating_point=operating_point)


def _structured(builder, options, bounds, operating_point):
    return structured_result(builder, options, bounds, operating_point=operating_point)


def _rls(builder, options, bounds, operating_point):
    return rls_result(builder, options, _paper_bounds("rls", builder, bounds),
                      operating_point=operating_point)


#: Every method: its options class and the function that runs it.
_TABLE = {
    "varpro": (VarproOptions, _varpro),
    "output_error": (OutputErrorOptions, _output_error),
    "structured": (StructuredOptions, _structured),
    "hybrid": (HybridOptions, _alternation("hybrid")),
    "single_innovation_gradient": (SingleInnovationGradientOptions,
                                   _alternation("single_innovation_gradient")),
    "single_innovation_lm": (SingleInnovationLMOptions, _alternation("single_innovation_lm")),
    "rls": (RlsOptions, _rls),
}
#: ``operating_point`` spellings besides an explicit ``(u0, y0)``.
OPERATING_POINTS = ("initial", "mean")
#: The method names, the recommended one first.
METHODS = tuple(_TABLE)
#: ``{method: options class}``.
OPTIONS = {name: cls for name, (cls, _) in _TABLE.items()}


def identify(u, y, *, na, nb, f_basis, g_basis, method="varpro", orders="commensurate",
             offset=False, operating_point=None, past="rest", dt=1.0, alpha_bounds=(0.0, 1.0),
             options=None, **method_options):
    """Identify a fractional-order Hammerstein–Wiener model from input–output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records (zero before ``k = 0``).
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree).
    method : str, optional
        One of :data:`METHODS`:

        ``"varpro"`` (default, recommended)
            Separable least squares (:mod:`fohw.estimators.varpro`), beyond the paper: theta by
            linear least squares for each alpha, alpha by a grid scan and a bounded search, then
            a joint least-squares polish. Reaches the Cramér–Rao bound of theta; reports
            standard errors. Options: :class:`~fohw.estimators.varpro.VarproOptions`.
        ``"structured"``
            Beyond the paper: least squares over the model's own parameters
            ``(a, b, p2.., q2.., offset, orders)`` with exact Jacobians, started from the
            ``"varpro"`` estimate by a rank-one (SVD) recovery of ``q⊗a`` and ``p⊗b``
            (:mod:`fohw.estimators.structured`). Reaches the *structured* Cramér–Rao bound
            (``fohw.crb(..., parametrisation="structured")``), lower than the bound of the
            unstructured theta that ``"varpro"`` reaches; standard errors of ``a, b, p, q``.
            Options: :class:`~fohw.estimators.structured.StructuredOptions`.
        ``"output_error"``
            Beyond the paper: minimises the free-run *simulation* error over
            ``(theta, alpha)`` (:mod:`fohw.estimators.output_error`), started from the
            ``"varpro"`` estimate. Options:
            :class:`~fohw.estimators.output_error.OutputErrorOptions`.
        ``"hybrid"``
            The paper's method: MIGD for theta and MI-LM for alpha, alternately, under the
            schedule of Table 1 or of Steps 1–9 (:mod:`fohw.estimators.hybrid`). As printed it
            does not reach the accuracy of the paper's Table 2 (see ``docs/reproduction.md``).
            Options: :class:`~fohw.estimators.hybrid.HybridOptions`.
        ``"single_innovation_gradient"``, ``"single_innovation_lm"``
            The baselines of the paper's Fig. 6. Options:
            :class:`~fohw.estimators.hybrid.SingleInnovationGradientOptions`,
            :class:`~fohw.estimators.hybrid.SingleInnovationLMOptions`.
        ``"rls"``
            Beyond the paper: one pass of :class:`fohw.MultiInnovationRLS` (recursive least
            squares with recursive alpha). Options: :class:`~fohw.estimators.rls.RlsOptions`.
    orders : str, number, dict or Orders, optional
        Which term of the linear block has which order (:class:`fohw.Orders`):
        ``"commensurate"`` (default, the paper's Eq. 16), ``"per_lag"`` (Eq. 14: a free order per
        term), ``"mixed"`` (order 0 and a free order at every lag: a static gain beside
        fractional dynamics), a number (every order fixed), or per-lag orders.
    offset : bool, optional
        Estimate a constant ``c`` in the equation (default False).
    operating_point : None, "initial", "mean" or (u0, y0), optional
        Levels subtracted from ``u`` and ``y`` before fitting and added back by
        ``result.predict`` and ``result.simulate``: None (default) subtracts nothing;
        ``"initial"`` the first samples, ``"mean"`` the means. With ``past="rest"`` the model
        assumes the system rested at this point before ``k = 0``.
    past : {"rest", "estimate"}, optional
        ``"rest"`` (default): the signals were at the operating point before ``k = 0`` (zero
        GL memory of the unseen past). ``"estimate"``: the system rested at constant levels
        ``u_past``, ``y_past`` (relative to the operating point) before ``k = 0``, estimated
        with the other parameters (``"varpro"``, ``"structured"``, ``"output_error"``).
    dt : float, optional
        Sampling time ``h > 0`` (Eq. 4): coefficients and orders then have a continuous-time
        reading. Default 1.
    alpha_bounds : (float, float) or dict, optional
        Interval for every free order, ``0 <= low < high <= 2`` (default ``(0, 1)``, as in the
        paper), or ``{name: (low, high)}`` per free order. The batch methods may end on a bound
        (the result says so); the recursive ones hold alpha ``1e-3 * (high - low)`` inside it.
    options : mapping or MethodOptions, optional
        The method's options, as a mapping (``options={"innovation_length": 3}``) or an instance
        of its options class.
    **method_options
        The same options as keywords (``innovation_length=3``). A name the method does not have
        raises :class:`fohw.ParameterError` saying which methods have it.

    Returns
    -------
    IdentificationResult
        With ``status`` (:class:`fohw.Status`), ``nit``, ``nfev`` and ``converged``.

    Raises
    ------
    ParameterError, DimensionError
        Invalid settings or data, with the offending argument named.
    EstimationDivergedError
        The estimates became non-finite (badly scaled data, or an unstable recursion).

    Warns
    -----
    ConvergenceWarning
        The run stopped at its iteration limit, or a recursive method made its passes without
        testing convergence; the result then has ``converged=False``.
    RankDeficiencyWarning
        The information matrix is rank deficient: the message names the parameters that cannot
        be identified; ``status == Status.RANK_DEFICIENT``.

    Notes
    -----
    Eqs. (29)–(33) (MIGD), (41)–(48) (MI-LM), (39)–(40) (recovery of ``a, b, p, q``), Table 1
    and Steps 1–9 for the paper's methods.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(2000, random_state=0)
    >>> res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> res.method, res.status.name, round(res.alpha, 2)
    ('varpro', 'CONVERGED', 0.6)
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", fohw.ConvergenceWarning)
    ...     paper = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3,
    ...                           method="hybrid", innovation_length=3)
    >>> paper.status.name, paper.nit
    ('NOT_TESTED', 1)
    """
    if method not in _TABLE:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    options_class, run = _TABLE[method]
    if options is not None and method_options:
        if not isinstance(options, Mapping):
            raise ParameterError("pass a method's options either as keywords or as `options=`, "
                                 f"not both; got `options` and {sorted(method_options)}.")
        both = sorted(set(options) & set(method_options))
        if both:
            raise ParameterError(f"option(s) {both} given both as keywords and in `options`.")
        options = {**options, **method_options}
    elif method_options:
        options = method_options
    opts = options_class.build(method, options, others=OPTIONS)
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    point = _operating_point(operating_point, u, y)
    if not isinstance(offset, (bool, np.bool_)):
        raise ParameterError(f"`offset` must be True or False; got {offset!r}.")
    structure = Structure.make(na=check_int(na, "na", minimum=1), nb=check_int(nb, "nb", minimum=1),
                               f_basis=f_basis, g_basis=g_basis, orders=orders,
                               offset=bool(offset), past=past, dt=dt)
    bounds = _order_bounds(structure, alpha_bounds)
    u_dev = u - point[0] if point[0] else u
    y_dev = y - point[1] if point[1] else y
    _check_offset(structure, u_dev)
    if operating_point is None and not structure.offset:
        _warn_levels(u, y)
    _warn_tiny(y_dev)
    builder = RegressorBuilder(u_dev, y_dev, structure=structure)
    # Overflow is not left to NumPy's RuntimeWarning: every estimator checks its estimates
    # and criterion for finiteness and raises EstimationDivergedError with the reason.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        result = run(builder, opts, bounds, point)
    return replace(result, input_range=(float(u.min()), float(u.max())))


def _operating_point(spec, u, y):
    if spec is None:
        return (0.0, 0.0)
    if isinstance(spec, str):
        if spec == "initial":
            return (float(u[0]), float(y[0]))
        if spec == "mean":
            return (float(np.mean(u)), float(np.mean(y)))
        raise ParameterError(f"`operating_point` must be None, one of {OPERATING_POINTS} or a "
                             f"pair (u0, y0); got {spec!r}.")
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
            DataWarning, stacklevel=3)


def _warn_levels(u, y):
    """Warn when a signal sits far from 0 and the model has no way to represent the level."""
    for name, x in (("u", u), ("y", y)):
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
                DataWarning, stacklevel=3)


def _check_offset(structure, u):
    """An offset beside order-0 input terms needs an input that is not constant."""
    if not structure.offset:
        return
    if any(t.order == 0.0 for t in structure.orders.input) and np.ptp(u) == 0.0:
        raise ParameterError("`offset=True` cannot be estimated from this record: the input is "
                             "constant, so the offset cannot be told apart from the order-0 "
                             "input terms. Use a record where the input moves, or offset=False.")

