"""The one-call entry point :func:`fohw.identify` and its table of methods (dispatch only).

Each method is declared in its own module (a :class:`~fohw.estimators.options.Method`: its
name, options class, run and the structures it supports): the paper's alternating methods in
:mod:`fohw.estimators.hybrid`, the estimators beyond the paper in
:mod:`~fohw.estimators.varpro`, :mod:`~fohw.estimators.structured`,
:mod:`~fohw.estimators.output_error` and :mod:`~fohw.estimators.rls`. The record and the model
class are checked by :mod:`fohw.estimators.problem`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from typing import Any

from .._parallel import heartbeat
from .._types import ArrayLike, PairLike
from ..exceptions import ParameterError
from ..model.basis import BasisLike
from ..model.lagged.theta_hw import ThetaHW
from ..model.orders import OrdersLike
from ..model.output_map import OutputMapLike
from ..record import check_sampling, record_data, record_info
from ..results import IdentificationResult
from . import hybrid, output_error, rls, structured, varpro
from .options import MethodOptions
from .problem import OPERATING_POINTS, fit_method

__all__ = ["identify", "fit_lagged", "METHODS", "OPTIONS", "OPERATING_POINTS"]

#: Every method, the recommended one first.
_TABLE = {m.name: m for m in (varpro.METHOD, output_error.METHOD, structured.METHOD,
                              *hybrid.METHODS, rls.METHOD)}
#: The method names, the recommended one first.
METHODS = tuple(_TABLE)
#: ``{method: options class}``.
OPTIONS = {name: m.options for name, m in _TABLE.items()}


def identify(u: ArrayLike, y: ArrayLike | None = None, *, na: int, nb: int, f_basis: BasisLike,
             g_basis: BasisLike, method: str = "varpro", orders: OrdersLike = "commensurate",
             offset: bool = False, operating_point: str | PairLike | None = None,
             past: str = "rest", dt: float | None = None,
             alpha_bounds: PairLike | Mapping[str, PairLike] = (0.0, 1.0),
             output_map: OutputMapLike = None,
             options: Mapping[str, Any] | MethodOptions | None = None,
             executor: Executor | None = None, nk: int | Sequence[int] = 1,
             inputs: Sequence[str] | None = None, progress: bool | None = None,
             **method_options: Any) -> IdentificationResult:
    """Identify a fractional-order Hammerstein–Wiener model from input–output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records (zero before ``k = 0``). ``u`` of shape ``(N, m)``, or a
        pandas DataFrame of ``m`` columns (whose names then name the inputs), is a model with
        ``m`` inputs: ``y[k] = A-terms + sum_i B_i-terms of fbar_i(u_i) + …``, each input with
        its own basis, lags, delay and orders (``nb``, ``nk`` and ``f_basis`` one per input as
        lists, or one value for every input; a list or tuple ``f_basis`` is then always one
        basis per input). Its coefficients are named ``<input>.b<lag>``, ``<input>.p2b<lag>``.
        A 1-D ``u`` (or one column) is the single-input model, exactly as before.
        Or a :class:`fohw.Record` as ``u`` (``y`` omitted): its samples, its sampling time as
        ``dt``, its input names as ``inputs``; its names and units are kept in
        ``result.data``. A DataFrame without ``y`` is refused (say its columns with
        :meth:`fohw.Record.from_dataframe`); several records are fitted by :func:`fohw.fit`
        with a :class:`fohw.HammersteinWiener` model.
    na, nb : int
        Output and input lag orders: output terms at lags ``1 … na``, input terms at lags
        ``nk … nk + nb - 1``. ``nb``: one per input (a list) with several inputs, or one for all.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree); ``f_basis`` one per
        input (a list) with several inputs, or one for all.
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
            Beyond the paper: one pass of :class:`fohw.estimators.rls.MultiInnovationRLS` (recursive least
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
        reading. Default: the record's sampling time for a :class:`fohw.Record` (another
        ``dt`` is refused), else 1.
    alpha_bounds : (float, float) or dict, optional
        Interval for every free order, ``0 <= low < high <= 2`` (default ``(0, 1)``, as in the
        paper), or ``{name: (low, high)}`` per free order. The batch methods may end on a bound
        (the result says so); the recursive ones hold alpha ``1e-3 * (high - low)`` inside it.
    output_map : None, "saturation", "deadzone", "piecewise_linear", int or SeriesMap, optional
        A series output block ``y = h(z)`` after the model (``z`` its output, in the data's
        units: a saturation's limits are in the units of ``y``; :mod:`fohw.model.output_map`):
        a saturation or a dead zone with both limits free, a piecewise-linear map (5
        breakpoints over the output's range), a polynomial of that degree, or a map object
        (fixed limits, a monotone polynomial, a user's function). None (default): today's
        model. Fitted by ``method="output_error"`` only (the fit without ``h`` first, then
        ``h`` from the data, then all together with exact Jacobians through ``h``); the
        equation-error methods refuse it.
    options : mapping or MethodOptions, optional
        The method's options, as a mapping (``options={"innovation_length": 3}``) or an instance
        of its options class.
    nk : int, optional
        Input delay in samples, an integer ``>= 0`` (MATLAB's ``nk``). Default 1: the paper's
        input lags ``1 … nb``. ``nk = 0`` is direct feedthrough (a term ``b0`` of the present
        input, as a D term of a state-space model); ``nk = 3`` a dead time of 3 samples
        (terms ``b3 … b{nb+2}``). The input coefficients are named by their lag. The paper's
        methods (``"hybrid"``, the baselines, ``"rls"``) implement ``nk = 1`` only. Several
        inputs: one per input (a list), or one for all.
    inputs : sequence of str, optional
        Names of the inputs of a 2-D ``u`` (default: a DataFrame's column names, else ``u1,
        u2, …``). The paper's methods take one input only.
    executor : concurrent.futures.Executor, optional
        Where ``method="output_error"`` runs its local searches (its option ``n_starts``): a
        :class:`~concurrent.futures.ProcessPoolExecutor` or dask's ``Client.get_executor()``;
        default (None) serially. The result is the same. Other methods refuse one.
    progress : bool, optional
        The elapsed time on stderr while the fit runs (a tqdm bar if tqdm is installed, else a
        line every 10 s) and its duration at the end: True from the start, False never; default
        (None) once the fit has run for 2 s (never inside ``select_structure``'s or
        ``identify_many``'s own progress, nor in a worker process).
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
        The run stopped at its iteration limit or failed; the result then has
        ``converged=False``. A recursive pass that does not test convergence by design (the
        paper's Table 1, ``"rls"``) does not warn: its status is ``NOT_TESTED``.
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
    >>> paper = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3,
    ...                       method="hybrid", innovation_length=3)
    >>> paper.status.name, paper.nit
    ('NOT_TESTED', 1)
    """
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
    return _run(u, y, method=method, options=options, executor=executor, progress=progress,
                dt=dt, inputs=inputs, na=na, nb=nb, f_basis=f_basis, g_basis=g_basis,
                orders=orders, offset=offset, operating_point=operating_point, past=past,
                alpha_bounds=alpha_bounds, output_map=output_map, nk=nk)


def _run(u, y, *, method, options, executor, progress, dt, inputs, **model):
    """One method of the table on one record (a Record or arrays): identify's and fit's path.

    ``model`` holds :func:`~fohw.estimators.problem.prepare`'s keywords (the class by its
    keywords, or ``structure=``), the operating point and the order bounds.
    """
    records, u, y = record_data(u, y, what="u", several=False)
    info = {}
    if records is not None:
        rec = records[0]
        if not rec.uniform:
            raise ParameterError(
                f"the record{f' {rec.name!r}' if rec.name else ''} has non-uniform time stamps; "
                "the lagged kind runs on a uniform grid: resample it with "
                "fohw.model.irregular.resample(rec.t, rec.u, rec.y, dt=...), or fit a kind that "
                "simulates on time stamps with fohw.fit.")
        if rec.dt is not None:
            if dt is not None:
                check_sampling(records, float(dt), what="`dt`")
            dt = rec.dt
        if inputs is None and rec.n_inputs > 1:
            inputs = rec.input_names
        info = record_info(records)
    elif y is None:
        raise ParameterError("`y` is missing: pass the output samples, or a fohw.Record as `u`.")
    dt = 1.0 if dt is None else dt
    if method not in _TABLE:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    declared = _TABLE[method]
    opts = declared.options.build(method, options, others=OPTIONS)
    if progress is not None and not isinstance(progress, bool):
        raise ParameterError(f"`progress` must be True, False or None; got {progress!r}.")
    if "structure" in model:
        model.pop("inputs", None)
    else:
        model.update(dt=dt, inputs=inputs)
    with heartbeat(f"identify ({method})", progress):
        result = fit_method(declared, opts, u, y, executor=executor, **model)
    return dataclasses.replace(result, data=info) if info else result


def fit_lagged(model, u, y=None, *, method, options=None):
    """``fohw.fit(model, data, method=name)`` for a method of :func:`fohw.identify`'s table.

    The model (a :class:`fohw.ThetaHW`) gives the class (its structure), the operating point
    and the bounds of its free orders (its :class:`fohw.Parameters`, the one statement of
    them); the method makes its own starts, so the model's values are not a start. Every
    other parameter must be as the method estimates it: free, untied and unbounded (a
    method of the table estimates theta by least squares over all of it).

    Raises
    ------
    ParameterError
        ``model`` is not a ThetaHW (naming the kinds the method fits), or a parameter is
        fixed, tied or bounded where the method cannot honour it (named).
    """
    if method not in _TABLE:
        raise ParameterError(f"`method` must be None (the engine, every kind) or one of "
                             f"{METHODS} (the lagged kind, fohw.ThetaHW); got {method!r}.")
    if not isinstance(model, ThetaHW):
        raise ParameterError(
            f"method {method!r} fits {', '.join('fohw.' + k for k in _TABLE[method].kinds)} "
            f"(the lagged kind's identification form); a {type(model).__name__} is fitted by "
            "the engine, fohw.fit(model, data) (method=None).")
    s = model.structure
    params = model.parameters
    bounds = {}
    for name, par in params.items():
        if par.order and name in s.orders.free:
            if par.fixed or par.tie is not None:
                raise ParameterError(
                    f"the order {name!r} is {'fixed' if par.fixed else 'tied'} in the model's "
                    f"Parameters, which method {method!r} cannot honour: fix or tie orders in "
                    "the Structure (its `orders`), or fit with the engine (method=None).")
            bounds[name] = par.bounds
        elif par.fixed or par.tie is not None or par.bounds != (-math.inf, math.inf):
            how = ("fixed" if par.fixed else "tied" if par.tie is not None
                   else f"bounded to {par.bounds}")
            raise ParameterError(
                f"{name!r} is {how} in the model's Parameters; method {method!r} estimates "
                "every coefficient freely. Fit with the engine, fohw.fit(model, data) "
                "(method=None), which honours fixed, tied and bounded parameters.")
    return _run(u, y, method=method, options=options, executor=None, progress=None, dt=s.dt,
                inputs=None, structure=s, operating_point=model.operating_point,
                alpha_bounds=bounds or (0.0, 1.0))
