"""The result of an identification run (returned by :func:`fohw.identify`): its data.

:class:`IdentificationResult` stores each fact of an estimate once and derives the rest
(``alpha`` from ``orders``; ``layout``, ``f_basis``, ``g_basis`` from ``structure``; ``model``
from both and ``theta``). How it reads (summary, repr, plot) is :mod:`fohw.presentation`; how
it is written to a file is :mod:`fohw.io.jsonio` (this module imports neither file nor CLI).
"""

from __future__ import annotations

import dataclasses
import types
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ._status import Status
from ._validation import RANGE_TOLERANCE, check_inputs, check_scalar, input_in_range
from .exceptions import DimensionError, ExtrapolationWarning, ParameterError
from .fit_result import FitResult
from .lr_statistic import order_test
from .model.basis import Basis
from .model.lagged.hw_frequency import linear_block
from .model.lagged.initial import initial_state, simulate_from
from .model.lagged.params import ThetaLayout
from .model.lagged.simulation import check_input_point
from .model.lagged.structure import Structure
from .model.lagged.system import HammersteinWiener
from .model.lagged.theta_hw import ThetaHW
from .model.parameters import Parameters
from .model.simulate import check_record_sampling, record_list
from .presentation import ResultPresentation

__all__ = ["IdentificationResult", "Status", "recover_model", "DETAIL_KEYS"]


#: The method-specific outputs fohw's estimators put in :attr:`IdentificationResult.details`;
#: the five histories and profiles are also read as attributes of the result.
DETAIL_KEYS = ("theta_history", "alpha_sample_history", "alpha_history", "J_history",
               "alpha_profile", "simulation_sse", "start", "starts", "n_starts_agreed",
               "integer_sse", "identity_sse")


def _readonly(a):
    """A read-only float64 copy of ``a`` (no copy if it already is one)."""
    if a is None:
        return None
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and not a.flags.writeable:
        return a
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


def _pair(value, name):
    try:
        a, b = value
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be a pair of numbers; got {value!r}.") from None
    return check_scalar(a, f"{name}[0]"), check_scalar(b, f"{name}[1]")


def _array_to_dict(a) -> dict:
    return {"shape": list(a.shape), "data": [float(x) for x in a.ravel()]}


def _array_from_dict(entry, name):
    if not isinstance(entry, Mapping) or set(entry) != {"shape", "data"}:
        raise ParameterError(f"`{name}` must be an array written as {{'shape': [...], "
                             f"'data': [...]}}; got {entry!r}.")
    data = np.array(entry["data"], dtype=np.float64)
    try:
        return data.reshape(entry["shape"])
    except (TypeError, ValueError):
        raise DimensionError(f"`{name}` has {data.size} values, which do not fill its shape "
                             f"{entry['shape']!r}.") from None


def _detail_to_json(value):
    if isinstance(value, np.ndarray):
        return _array_to_dict(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        return [_detail_to_json(v) for v in value]
    return value


def _detail_from_json(value, name):
    if isinstance(value, Mapping) and set(value) == {"shape", "data"}:
        return _array_from_dict(value, name)
    return value


def _setting_to_json(value):
    """A setting as JSON, or ``...`` when it has no JSON form (a Python object, an array)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        items = [_setting_to_json(v) for v in value]
        return ... if any(v is ... for v in items) else items
    if isinstance(value, Mapping):
        items = {str(k): _setting_to_json(v) for k, v in value.items()}
        return ... if any(v is ... for v in items.values()) else items
    return ...


def _setting_from_json(value):
    if isinstance(value, list):
        return tuple(_setting_from_json(v) for v in value)
    if isinstance(value, Mapping):
        return {k: _setting_from_json(v) for k, v in value.items()}
    return value


@dataclass(frozen=True, repr=False, eq=False, kw_only=True)
class IdentificationResult(ResultPresentation, FitResult):
    """Estimates, diagnostics and histories of one identification run: a :class:`fohw.FitResult`.

    The subclass adds what the paper's methods have (theta, the histories, the iterations) to
    the vocabulary every fit shares; :attr:`model` (the fitted :class:`fohw.ThetaHW`),
    :attr:`parameters` (its :class:`fohw.Parameters`) and :attr:`sse` (the simulation error
    where the method fits it, ``J * n_samples`` otherwise) are FitResult's fields, derived here.

    Each fact is stored once: the fields below are the estimate and the run's diagnostics;
    ``alpha``, ``layout``, ``f_basis``, ``g_basis`` and ``model`` are derived from them (read-only
    properties, so ``dataclasses.replace(result, orders=...)`` moves ``alpha`` and ``model``
    with it, and ``replace(result, alpha=...)`` is a ``TypeError``). Method-specific outputs
    live in the one mapping :attr:`details` and are also read as attributes
    (:attr:`theta_history`, :attr:`alpha_history`, …).

    Attributes
    ----------
    method : str
        ``"hybrid"``, ``"single_innovation_gradient"``, ``"single_innovation_lm"``, ….
    structure : Structure
        The model class that was fitted (orders, bases, whether an offset is fitted, past, dt).
    theta : ndarray, shape (n,)
        Estimated ``[q ⊗ a, p ⊗ b]``.
    orders : mapping
        The estimated free orders, ``{name: value}`` in :attr:`Orders.free` order (the
        commensurate model: ``{"alpha": alpha}``); each in ``[0, 2]``.
    J : float
        Eq. (41): mean squared one-step error over the record at (``theta``, ``orders``).
    status : Status
        Why the run stopped (an ``int``; see :class:`Status`).
    nit : int
        Iterations of the method's outer loop: passes over the record (``"hybrid"``, the
        single-innovation baselines, ``"rls"``), or iterations of the optimiser (``"varpro"``:
        the scalar alpha search plus the least-squares polish; ``"output_error"``: the
        least-squares solver).
    nfev : int
        Evaluations of the model over the whole record: ``J`` (one per pass) for the recursive
        methods, ``J(alpha)`` profiles and polish residuals for ``"varpro"``, free-run
        simulations for ``"output_error"`` (one per residual and one per Jacobian, the exact
        sensitivity of the free run).
    message : str
        Why the run stopped, and anything the user must know about the estimates.
    n_samples : int
        ``N``.
    schedule : str
        ``"recursive"`` (Table 1) or ``"iterative"`` (Steps 1–9); ``""`` where not applicable.
    offset : float
        The estimated constant ``c`` of the equation, as :attr:`HammersteinWiener.offset`:
        ``0.0`` when the structure fits none (``structure.offset`` is the flag saying whether
        an offset is fitted; ``identify(offset=True)`` sets it).
    past : (float, float)
        The estimated levels ``(u_past, y_past)`` of the unseen past (deviations from the
        operating point; ``(0, 0)`` under ``past="rest"``).
    operating_point : (float, float)
        ``(u0, y0)`` removed before fitting; :meth:`predict` and :meth:`simulate` add it back.
    alpha_at_bound : bool
        Whether a free order was held at an end of ``alpha_bounds`` at least once.
    covariance : ndarray, shape (d, d), or None
        Asymptotic covariance ``s^2 (G^T G)^{-1}`` of the ``d`` estimates in
        :attr:`estimate_names` order (the paper's model: ``(theta, alpha)``, ``alpha`` last),
        with ``G`` the Jacobian of the fitted residual (one-step predictor for ``"varpro"``,
        free-run simulation for ``"output_error"``); only for these least-squares estimates.
        For ``"structured"`` it is the covariance ``C`` of the structured parameters mapped to
        ``(theta, nonlinear)``, ``M C M^T`` (:meth:`fohw.Structure.structured_jacobian`; rank
        deficient), so that :meth:`standard_errors` gives ``C``'s own entries for ``a, b, p, q``.
        ``None`` where the estimator is not a least-squares optimum, since standard errors
        would then be meaningless.
    noise_variance : float or None
        ``s^2 = RSS / (N - d)``, with ``covariance``.
    input_range : (float, float) or None
        The smallest and largest input of the estimation record (data units), set by
        :func:`fohw.identify`; :meth:`simulate` warns (:class:`fohw.ExtrapolationWarning`) on an
        input that goes beyond it by more than 5 % of its span.
    options : mapping
        The settings of the run (innovation length, bounds, …), nothing it computed.
    output_map_params : mapping
        The estimated parameters of the structure's series output map ``y = h(z)``,
        ``{name: value}`` in :attr:`~fohw.model.output_map.SeriesMap.names` order (``h_lower``,
        …; data units);
        empty without an output map.
    data : mapping
        What the record was when :func:`fohw.identify` was given a :class:`fohw.Record`:
        channel names and units (``input_names``, ``input_units``, ``output_name``,
        ``output_unit``, ``time_unit``), ``dt`` and the record's ``name``, ``n_samples``,
        ``t0`` (as :attr:`fohw.FitResult.data`); empty for arrays. The sampling time the
        model uses is ``structure.dt``.
    details : mapping
        Method-specific outputs (read-only), keyed by :data:`DETAIL_KEYS` where they apply:
        ``theta_history``, ``alpha_sample_history``, ``alpha_history``, ``J_history``,
        ``alpha_profile`` (see the properties of those names), ``simulation_sse`` (the
        simulation-error sum of squares of ``"output_error"``), ``start`` (which start an
        ``"output_error"`` or ``"structured"`` fit began from), ``starts`` and
        ``n_starts_agreed`` (its default chain's local searches), ``integer_sse`` (the
        simulation-error sum of squares of the integer class it contains, every order 0,
        fitted by that chain: :meth:`order_test`) and ``identity_sse`` (that of the fit
        without the series output map, which the fit with it starts from).

    Notes
    -----
    ``covariance`` and :meth:`standard_errors` are ordered as :attr:`estimate_names`: the
    linear parameters (theta's, then ``offset``) and the nonlinear ones (the free orders, then
    ``u_past``, ``y_past``, then the output map's ``h_*``).
    """

    method: str
    structure: Structure
    theta: np.ndarray
    orders: Mapping = field(default_factory=dict)
    J: float
    status: Status
    nit: int
    nfev: int
    message: str
    n_samples: int
    schedule: str = ""
    offset: float = 0.0
    past: tuple = (0.0, 0.0)
    operating_point: tuple = (0.0, 0.0)
    alpha_at_bound: bool = False
    covariance: np.ndarray | None = None
    noise_variance: float | None = None
    input_range: tuple | None = None
    options: Mapping = field(default_factory=dict)
    details: Mapping = field(default_factory=dict)
    output_map_params: Mapping = field(default_factory=dict)
    data: Mapping = field(default_factory=dict)
    # What FitResult stores and this result derives from the fields above (set by
    # __post_init__, so dataclasses.replace moves them with theta and the orders).
    model: ThetaHW = field(init=False, default=None)
    parameters: Parameters = field(init=False, default=None)
    sse: float = field(init=False, default=float("nan"))
    jacobian: str = field(init=False, default="")
    starts: tuple = field(init=False, default=())
    residuals: np.ndarray | None = field(init=False, default=None)
    data_digest: str = field(init=False, default="")
    per_record: Mapping = field(init=False, default_factory=dict)
    n_per_record: int = field(init=False, default=0)

    def __post_init__(self):
        def put(name, value):
            object.__setattr__(self, name, value)

        s = self.structure
        if not isinstance(s, Structure):
            raise ParameterError(f"`structure` must be a Structure; got {type(s).__name__}.")
        put("status", Status(self.status))
        put("theta", _readonly(self.theta))
        if self.theta.shape != (s.layout.n_params,):
            raise DimensionError(f"`theta` must have {s.layout.n_params} entries "
                                 f"({', '.join(s.layout.names)}); got shape {self.theta.shape}.")
        put("orders", types.MappingProxyType(s.orders.free_mapping(self.orders, "orders")))
        if s.offset:
            put("offset", check_scalar(self.offset, "offset"))
        elif self.offset != 0.0:
            raise ParameterError(f"`offset` is {self.offset!r}, but the structure fits no offset "
                                 "(structure.offset is False): it must be 0.")
        else:
            put("offset", 0.0)
        put("past", _pair(self.past, "past"))
        if s.past == "rest" and self.past != (0.0, 0.0):
            raise ParameterError(f"`past` is {self.past}, but the structure has past='rest': "
                                 "it must be (0, 0).")
        if s.n_inputs > 1:
            put("operating_point", check_input_point(self.operating_point, s.n_inputs))
        else:
            put("operating_point", _pair(self.operating_point, "operating_point"))
        if self.input_range is not None:
            if s.n_inputs > 1:
                lo, hi = (check_input_point((r, 0.0), s.n_inputs)[0] for r in self.input_range)
                put("input_range", (lo, hi))
                reversed_ = any(a > b for a, b in zip(lo, hi))
            else:
                put("input_range", _pair(self.input_range, "input_range"))
                reversed_ = self.input_range[0] > self.input_range[1]
            if reversed_:
                raise ParameterError(f"`input_range` must be (smallest, largest) input; got "
                                     f"{self.input_range} (reversed).")
        put("covariance", _readonly(self.covariance))
        d = s.n_linear + s.n_nonlinear
        if self.covariance is not None and self.covariance.shape != (d, d):
            raise DimensionError(f"`covariance` must have shape ({d}, {d}) (the estimates "
                                 f"{', '.join(self.estimate_names)}); got {self.covariance.shape}.")
        put("options", types.MappingProxyType(dict(self.options)))
        names = () if s.output_map is None else s.output_map.names
        given = dict(self.output_map_params)
        if list(given) != list(names):
            raise ParameterError(f"`output_map_params` must give the output map's parameters "
                                 f"{list(names)} in that order; got {list(given)}.")
        put("output_map_params", types.MappingProxyType(
            {n: check_scalar(v, f"output_map_params[{n!r}]") for n, v in given.items()}))
        put("data", types.MappingProxyType(dict(self.data)))
        put("details", types.MappingProxyType(
            {k: _readonly(v) if isinstance(v, np.ndarray) else v
             for k, v in self.details.items()}))
        put("per_record", types.MappingProxyType({}))
        model = self._fitted_model()
        put("model", model)
        put("parameters", model.parameters)
        put("sse", float(self.details["simulation_sse"]) if "simulation_sse" in self.details
            else float(self.J * self.n_samples))
        put("jacobian", "" if self.covariance is None else "exact")

    def __reduce__(self):
        # the mappings are read-only views, which pickle cannot store: rebuild from plain dicts
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.init}
        values.update(orders=dict(self.orders), options=dict(self.options),
                      details=dict(self.details), output_map_params=dict(self.output_map_params),
                      data=dict(self.data))
        return (_rebuild, (type(self), values))

    # ---- derived facts ------------------------------------------------------------------------
    @property
    def alpha(self) -> float | None:
        """The first estimated free order (the paper's alpha); ``None`` when every order is fixed."""
        return next(iter(self.orders.values()), None)

    @property
    def layout(self) -> ThetaLayout:
        """Names and blocks of theta (``structure.layout``)."""
        return self.structure.layout

    @property
    def f_basis(self) -> Basis:
        """The input basis functions (``structure.f_basis``)."""
        return self.structure.f_basis

    @property
    def g_basis(self) -> Basis:
        """The output basis functions (``structure.g_basis``)."""
        return self.structure.g_basis

    def _fitted_model(self) -> ThetaHW:
        """:attr:`model`: a :class:`fohw.ThetaHW` holding theta itself (a map per lag).

        The class the method fitted, every parameter at its estimate (the offset, orders, past
        levels and the series output map's parameters included) and the orders' bounds those of
        the fit (``options["alpha_bounds"]``): ``result.model.simulate(u)`` is
        ``result.simulate(u)`` (from the model's own levels), and ``fohw.fit(result.model,
        data)`` starts at this estimate. ``result.model.shared()`` is the model with one map
        per branch of Eqs. (39)–(40) (a :class:`fohw.HammersteinWiener`, a smaller class that
        simulates otherwise unless theta is an exact Kronecker product).
        """
        s = self.structure
        model = ThetaHW(s, self.linear, self.nonlinear, operating_point=self.operating_point)
        bounds = self.options.get("alpha_bounds")
        if bounds is None or not s.orders.free:
            return model
        per = dict(bounds) if isinstance(bounds, Mapping) else dict.fromkeys(s.orders.free, bounds)
        params = model.parameters
        for name, pair in per.items():
            if name in params:
                params = params.replace(name, bounds=tuple(float(v) for v in pair))
        return model.with_parameters(params)

    @property
    def shared_model(self) -> HammersteinWiener | None:
        """``a, b, p, q`` recovered from ``theta`` by Eqs. (39)–(40): one map per branch.

        A :class:`fohw.HammersteinWiener`, the paper's smaller class; it reproduces the fit only
        when theta is an exact Kronecker product (``method="structured"``), so the fitted model
        is :attr:`model`. With a series output map it is the model of ``z``, before ``h``.
        ``None`` if the recovery is undefined (an ``a_i`` or ``b_i`` exactly zero, or several
        inputs; ``message`` says so).
        """
        return recover_model(self.structure, self.theta, self.orders, offset=self.offset,
                             past=self.past, operating_point=self.operating_point)[0]

    # ---- method-specific outputs (in `details`) ------------------------------------------------
    @property
    def theta_history(self) -> np.ndarray | None:
        """``theta(k)`` after the update at every sample of the last pass, shape (N, n).

        Recursive methods; ``None`` for the batch ones (``"varpro"``, …).
        """
        return self.details.get("theta_history")

    @property
    def alpha_sample_history(self) -> np.ndarray | None:
        """``alpha`` after every sample of the last pass, shape (N,), or ``None``.

        Constant within a pass in the iterative schedule; ``None`` for the batch methods.
        """
        return self.details.get("alpha_sample_history")

    @property
    def alpha_history(self) -> np.ndarray:
        """``alpha`` at the end of every outer iteration, shape (nit,).

        For ``"varpro"``: at every point of the bounded alpha search. A method that keeps no
        history gives ``[alpha]`` (empty when every order is fixed).
        """
        if "alpha_history" in self.details:
            return self.details["alpha_history"]
        return _readonly([] if self.alpha is None else [self.alpha])

    @property
    def J_history(self) -> np.ndarray:
        """``J`` at the end of every outer iteration, shape (nit,) (``[J]`` without a history)."""
        if "J_history" in self.details:
            return self.details["J_history"]
        return _readonly([self.J])

    @property
    def alpha_profile(self) -> np.ndarray | None:
        """``"varpro"``'s coarse scan: alpha in row 0, ``J(alpha)`` in row 1; else ``None``.

        With several free orders the scan moves them together, each at the same relative
        position in its bounds, and row 0 is the first order (zeros when only past levels
        are free).
        """
        return self.details.get("alpha_profile")

    # ---- views of the estimate ------------------------------------------------------------------
    @property
    def linear(self) -> np.ndarray:
        """The linear parameters: theta, then the offset if there is one."""
        return np.r_[self.theta, self.offset] if self.structure.offset else np.array(self.theta)

    @property
    def nonlinear(self) -> np.ndarray:
        """The nonlinear parameters: the free orders, ``u_past``, ``y_past`` if estimated, ``h_*``."""
        values = list(self.orders.values())
        if self.structure.past == "estimate":
            values += list(self.past)
        values += list(self.output_map_params.values())
        return np.array(values, dtype=np.float64)

    @property
    def estimate_names(self) -> tuple[str, ...]:
        """Names of the linear then the nonlinear parameters (the order of ``covariance``)."""
        return self.structure.linear_names + self.structure.nonlinear_names

    @property
    def dt(self) -> float:
        """Sampling time of the model."""
        return self.structure.dt

    @property
    def converged(self) -> bool:
        """``status == Status.CONVERGED``: the method's convergence test was met."""
        return self.status == Status.CONVERGED

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :attr:`theta`."""
        return self.layout.names

    @property
    def na(self) -> int:
        """Output lag order."""
        return self.layout.na

    @property
    def nb(self) -> int:
        """Input lag order."""
        return self.layout.nb

    @property
    def nk(self) -> int:
        """Input delay: the smallest input lag (1 for the paper's model; 0: direct feedthrough)."""
        return self.structure.nk

    # ---- serialisation ----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """A JSON-ready dict with one entry per field (:func:`fohw.save_result` writes it).

        Arrays are ``{"shape": [...], "data": [...]}``; floats are kept exact. Settings that
        have no JSON form (a ``start`` result, arrays) are left out of ``options``;
        ``details["start"]`` says which start was used.
        """
        def number(x):
            return None if x is None else float(x)

        settings = {str(k): _setting_to_json(v) for k, v in self.options.items()}
        extra = ({} if self.structure.output_map is None
                 else {"output_map_params": {k: float(v) for k, v in
                                             self.output_map_params.items()}})
        return {
            "method": self.method, "structure": self.structure.to_dict(),
            "theta": _array_to_dict(self.theta), "orders": dict(self.orders),
            "J": float(self.J), "status": int(self.status), "nit": int(self.nit),
            "nfev": int(self.nfev), "message": self.message, "n_samples": int(self.n_samples),
            "schedule": self.schedule, "offset": float(self.offset), "past": list(self.past),
            "operating_point": list(self.operating_point),
            "alpha_at_bound": bool(self.alpha_at_bound),
            "covariance": None if self.covariance is None else _array_to_dict(self.covariance),
            "noise_variance": number(self.noise_variance),
            "input_range": None if self.input_range is None else list(self.input_range),
            "options": {k: v for k, v in settings.items() if v is not ...},
            "details": {str(k): _detail_to_json(v) for k, v in self.details.items()},
            "data": _setting_to_json(dict(self.data)),   # what the record was (names, units)
        } | extra

    @classmethod
    def from_dict(cls, d, *, f_basis=None, g_basis=None,
                  output_map=None) -> IdentificationResult:
        """Inverse of :meth:`to_dict` (custom bases and maps passed again, checked by their names).

        Raises
        ------
        ParameterError, DimensionError
            A field is missing, unknown or inconsistent with another (the message names it).
        """
        names = {f.name for f in dataclasses.fields(cls) if f.init}
        if isinstance(d, Mapping) and "output_map_params" not in d:   # written only with a map
            names.discard("output_map_params")
        if isinstance(d, Mapping) and "data" not in d:         # files written before records
            names.discard("data")
        if not isinstance(d, Mapping) or set(d) != names:
            missing = sorted(names - set(d)) if isinstance(d, Mapping) else sorted(names)
            unknown = sorted(set(d) - names) if isinstance(d, Mapping) else []
            raise ParameterError(f"a result dict has one entry per field of IdentificationResult; "
                                 f"missing {missing}, unknown {unknown}.")
        values = dict(d)
        values["structure"] = Structure.from_dict(d["structure"], f_basis=f_basis,
                                                  g_basis=g_basis, output_map=output_map)
        if "output_map_params" in d and not isinstance(d["output_map_params"], Mapping):
            raise ParameterError(f"`output_map_params` must be a mapping of names to values; got "
                                 f"{d['output_map_params']!r}.")
        values["theta"] = _array_from_dict(d["theta"], "theta")
        if d["covariance"] is not None:
            values["covariance"] = _array_from_dict(d["covariance"], "covariance")
        values["options"] = {k: _setting_from_json(v) for k, v in d["options"].items()}
        values["details"] = {k: _detail_from_json(v, f"details[{k!r}]")
                             for k, v in d["details"].items()}
        return cls(**values)

    # ---- statistics ----------------------------------------------------------------------------
    def _require_covariance(self):
        if self.covariance is not None:
            return
        if self.status == Status.RANK_DEFICIENT:
            raise ValueError("this fit is rank deficient, so some parameters are not identifiable "
                             "and have no standard errors; see `message` for which.")
        if self.method in ("varpro", "structured", "output_error"):
            raise ValueError(f"this {self.method!r} fit has no covariance: its information "
                             "matrix at the estimate is singular; see `message`.")
        raise ValueError(f"method {self.method!r} gives no covariance: standard errors are only "
                         "defined at a least-squares optimum ('varpro', 'structured', "
                         "'output_error').")

    def standard_errors(self) -> dict:
        """Standard errors of the estimates and of the recovered ``a, b, p, q``.

        Returns
        -------
        dict of str to float
            Keyed by :attr:`estimate_names` (theta's names, then ``offset``, the free orders,
            ``u_past``, ``y_past`` where present; the paper's model: theta's names and
            ``"alpha"``) and the model parameter names (``a1``, ``b1``, ``p2``, ``q2``, …; the
            delta method through Eqs. 39–40).

        Raises
        ------
        ValueError
            The method provides no covariance.
        """
        self._require_covariance()
        se = np.sqrt(np.diag(self.covariance))
        out = dict(zip(self.estimate_names, se))
        out.update(zip(self.layout.model_parameter_names, np.sqrt(np.diag(self._model_covariance()))))
        return {k: float(v) for k, v in out.items()}

    def _model_covariance(self):
        jac = self.layout.recover_jacobian(self.theta)
        n = self.theta.shape[0]
        return jac @ self.covariance[:n, :n] @ jac.T

    def confidence_intervals(self, level=0.95) -> dict:
        """Wald confidence intervals ``estimate ± z * se`` (normal quantile ``z``).

        Parameters
        ----------
        level : float
            Coverage, in (0, 1). Default 0.95.

        Returns
        -------
        dict of str to (float, float)
            Same keys as :meth:`standard_errors`.
        """
        from scipy.stats import norm

        level = check_scalar(level, "level", lower=0.0, upper=1.0, lower_inclusive=False,
                             upper_inclusive=False)
        z = float(norm.ppf(0.5 + level / 2))
        se = self.standard_errors()
        est = self._estimates()
        return {k: (est[k] - z * se[k], est[k] + z * se[k]) for k in se}

    def _estimates(self) -> dict:
        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        est.update(zip(self.layout.model_parameter_names, self.layout.recover_vector(self.theta)))
        return {k: float(v) for k, v in est.items()}

    def relative_error(self, theta_true, *, history=False):
        """``delta = ||theta_hat - theta|| / ||theta||`` (Section 6.1).

        With ``history=True``, for every sample of :attr:`theta_history`.
        """
        theta_true = self.layout.check_theta(theta_true, "theta_true")
        if history and self.theta_history is None:
            raise ValueError(f"method {self.method!r} keeps no per-sample history.")
        est = self.theta_history if history else self.theta
        return np.linalg.norm(est - theta_true, axis=-1) / np.linalg.norm(theta_true)

    def linear_block(self):
        """The fitted model's linear block, linearised at the operating point (frequency view).

        Returns
        -------
        fohw.model.lagged.hw_frequency.LinearBlock
            Its ``frequency_response(omega)``, ``static_gain`` and ``stability()``; ``bode()``
            draws it. Raises ParameterError when :attr:`model` is undefined.
        """
        return linear_block(self)

    # ---- using the estimate ------------------------------------------------------------------------
    def predict(self, u, y):
        """One-step-ahead prediction ``yhat[k] = phi[k] @ [theta, c] + y0`` (Eq. 19).

        ``u`` and ``y`` in the data's units; the operating point is removed and added back.
        With a series output map ``h`` the prediction is ``h(phi[k] @ [theta, c] + y0)``, the
        regressors built from the measured ``y`` in place of the unmeasured ``z`` (exact only
        where ``h`` is the identity; the free run, :meth:`simulate`, is the model).
        """
        return self.model.predict(u, y)

    def simulate(self, u, *, initial=None, y=None, **kwargs):
        """Free-run simulation of the identified predictor, in the data's units.

        Uses ``theta`` itself (and the offset and orders), i.e. exactly the model that was
        fitted (:attr:`model`), from the initial state ``initial``; for the rank-one
        ``a, b, p, q`` of Eqs. (39)–(40) use ``result.shared_model``.

        Parameters
        ----------
        u : array_like, Record or list of Record
            Input; or a :class:`fohw.Record` (its input; its sampling time must be the
            fit's ``dt``; with ``initial="estimate"`` its output is used), or a list of
            Records (a list of outputs).
        initial : str, tuple or InitialState, optional
            What the signals did before ``u`` began (:mod:`fohw.model.lagged.initial` says what each
            choice assumes and costs): ``"rest"`` (the operating point; the default of a fit
            with ``past="rest"``); ``"fitted"`` (the levels estimated with a
            ``past="estimate"`` fit, which belong to the estimation record: right for that
            record, where it reproduces the fit); ``"estimate"`` or ``("estimate", n)`` (the
            levels, and ``n`` free past outputs, of *this* record fitted to its output ``y``);
            a measured history ``(u_hist, y_hist)`` just before ``u``; or an
            :class:`fohw.InitialState` (e.g. ``fohw.compare(...).initial``). A fit with
            ``past="estimate"`` has no default: without ``initial`` it raises a ParameterError
            that lists the choices.
        y : array_like, optional
            The measured output of the record, for ``initial="estimate"`` only.
        **kwargs
            ``noise``, ``noise_std``, ``random_state``, ``divergence_threshold``
            (:func:`fohw.simulate`).

        Raises
        ------
        SimulationDivergedError
            The identified model is unstable on this input.
        ParameterError
            No ``initial`` for a ``past="estimate"`` fit; a bad ``initial``; ``y`` without
            ``initial="estimate"`` or the reverse.

        Warns
        -----
        ExtrapolationWarning
            ``u`` leaves the estimation input's range (:attr:`input_range`) by more than 5 % of
            its span: the basis functions extrapolate there, and a polynomial does so fast.
        """
        records = record_list(u)
        if records is not None:
            if y is not None:
                raise ParameterError("`u` is a Record, which carries its output; do not also "
                                     "pass `y`.")
            estimates = initial == "estimate" if isinstance(initial, str) else (
                isinstance(initial, tuple) and bool(initial) and initial[0] == "estimate")
            for r in records:
                check_record_sampling(self, r)
            out = [self.simulate(r.u, initial=initial, y=r.y if estimates else None, **kwargs)
                   for r in records]
            return out if isinstance(u, (list, tuple)) else out[0]
        u = check_inputs(u, self.structure.n_inputs, names=self.structure.inputs)
        state = self.initial_state(u, y, initial)
        if self.input_range is not None:
            u_arr = u
            if u_arr.ndim == 2 and not input_in_range(u_arr, self.input_range):
                warnings.warn(ExtrapolationWarning(
                    f"an input leaves the range the model was estimated on (by more than "
                    f"{RANGE_TOLERANCE:.0%} of its span): it spans {u_arr.min(axis=0)} to "
                    f"{u_arr.max(axis=0)}, estimated on {self.input_range[0]} to "
                    f"{self.input_range[1]}; the basis functions extrapolate there, so check "
                    "the simulation before trusting it."), stacklevel=2)
            elif u_arr.ndim == 1 and not input_in_range(u_arr, self.input_range):
                lo, hi = self.input_range
                warnings.warn(ExtrapolationWarning(
                    f"the input spans [{u_arr.min():.4g}, {u_arr.max():.4g}], beyond the range "
                    f"[{lo:.4g}, {hi:.4g}] the model was estimated on (by more than "
                    f"{RANGE_TOLERANCE:.0%} of its span); the basis functions extrapolate "
                    "there, so check the simulation before trusting it."), stacklevel=2)
        return simulate_from(self, u, state, **kwargs)

    def initial_state(self, u, y=None, initial=None):
        """The state a free run on the record ``(u, y)`` starts from: :func:`fohw.initial_state`.

        ``initial`` as for :meth:`simulate`; ``y`` only for ``"estimate"``, whose fitted levels
        (and window) the returned :class:`fohw.InitialState` holds.
        """
        return initial_state(self, u, y, initial)

    def order_test(self, u=None, y=None, **kwargs):
        """The likelihood-ratio test of the free orders against orders 0 (and its verdict).

        Without the record: for an ``"output_error"`` fit by the default chain of starts,
        which fits the integer class it contains (``details["integer_sse"]``), the
        white-noise test without refitting; None otherwise (use :func:`fohw.lr_test` with
        both fits). An order not identified under the null (the mixed class) has no p-value
        here (NaN). With the estimation record (the integer class refitted, the test corrected
        for correlated residuals beside the white-noise one, the verdict against a held-back
        record): :func:`fohw.order_test` ``(result, u, y, validation=(u_val, y_val))``.
        """
        if u is None and y is None and not kwargs:
            return order_test(self)
        # the refit lives with the tests (fohw.analysis), above this layer
        raise ParameterError("result.order_test() takes no record; the test with the record "
                             "(the integer class refitted, the corrected statistic, the verdict) "
                             "is fohw.order_test(result, u, y, validation=(u_val, y_val)).")


def _rebuild(cls, values):
    return cls(**values)


def recover_model(structure, theta, orders, *, offset=0.0, past=(0.0, 0.0),
                  operating_point=(0.0, 0.0)):
    """The model of Eqs. (39)-(40), or None and a note saying why it is undefined."""
    if structure.n_inputs > 1:
        return None, (f" No shared-map model (result.shared_model, a HammersteinWiener): it has "
                      f"one input and this result has {structure.n_inputs} "
                      f"({', '.join(structure.inputs)}); the fitted model is result.model.")
    try:
        return HammersteinWiener.from_theta(
            theta, dict(orders), na=structure.na, nb=structure.nb, f_basis=structure.f_basis,
            g_basis=structure.g_basis, orders=structure.orders, dt=structure.dt,
            offset=offset, past=past, operating_point=operating_point, nk=structure.nk), ""
    except ParameterError as exc:
        return None, f" No shared-map model (result.shared_model): {exc}"
