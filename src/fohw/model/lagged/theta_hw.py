"""The lagged Hammerstein–Wiener model in its identification form: theta itself (Eqs. 19–20).

The paper's model (Eq. 16) has one input map ``fbar = sum_j p_j f_j`` shared by every input
lag and one output map ``gbar = sum_j q_j g_j`` shared by every output lag, so its parameter
vector ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20) is a Kronecker product. The estimators that solve
for ``theta`` by least squares (``"varpro"``, ``"output_error"``, the paper's ``"hybrid"``,
``"rls"``) fit every entry of it freely: a **static map per lag** (``p2b1`` and ``p2b2`` need
not share the ratio ``p2``). That class contains the paper's and is what those methods fitted,
so it is what their result's :attr:`~fohw.IdentificationResult.model` is: a
:class:`ThetaHW`, whose free run is the fitted predictor itself (the same numbers as
``result.simulate``). :meth:`ThetaHW.shared` gives the nearest model with one map per branch
(the rank-one recovery of Eqs. 39–40, a :class:`fohw.HammersteinWiener`), which simulates
otherwise unless ``theta`` is an exact Kronecker product.

Its parameters are named as the result's (:attr:`fohw.Structure.linear_names` then
:attr:`fohw.Structure.nonlinear_names`: ``a1``, ``q2a1``, ``b1``, ``p2b1``, …, ``offset``,
the free orders, ``u_past``, ``y_past``, an output map's ``h_*``); every fohw verb works on it
as on any :class:`fohw.Model`, with the exact simulation sensitivity as its Jacobian
(:func:`fohw.model.lagged.sensitivity.simulation_jacobian`).
"""

from __future__ import annotations

import numpy as np

from ... import _linalg
from ..._validation import check_array, check_inputs, check_pair, check_scalar
from ...exceptions import DimensionError, ParameterError
from ..base import Model
from ..parameters import Parameter, Parameters
from .regressors import RegressorBuilder
from .sensitivity import simulation_jacobian
from .simulation import check_input_point, simulate_predictor
from .structure import Structure
from .system import HammersteinWiener

__all__ = ["ThetaHW"]


class ThetaHW(Model):
    """A lagged HW model given by its parameter vector theta: a static map per lag (Eqs. 19–20).

    The model that :func:`fohw.identify` fits (``result.model``): ``y[k] = phi[k] @ theta + c``
    in free run, with ``phi`` the information matrix (Eq. 19) built from the simulated output,
    every entry of ``theta`` its own parameter. The paper's model (one map per branch) is the
    special case ``theta = [q ⊗ a, p ⊗ b]``; :meth:`shared` returns it.

    Parameters
    ----------
    structure : Structure
        The model class: orders (which lags, which order per term), bases, offset, past levels,
        ``dt``, series output map, inputs.
    linear : array_like, optional
        The linear parameters, :attr:`fohw.Structure.linear_names` order (theta, then the
        offset). Default zeros.
    nonlinear : array_like, optional
        The nonlinear parameters, :attr:`fohw.Structure.nonlinear_names` order (the free
        orders, ``u_past``, ``y_past``, the output map's). Default: every free order 0.5, the
        past levels 0, the output map's parameters 0.
    operating_point : (float, float), optional
        ``(u0, y0)`` (``((u0_1, …), y0)`` with several inputs): the model acts on deviations from
        it. Default zeros.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> m = fohw.datasets.paper_model()
    >>> t = fohw.ThetaHW(m.structure, m.linear, m.nonlinear)
    >>> u = np.random.default_rng(0).uniform(-1, 1, 200)
    >>> bool(np.allclose(t.simulate(u), m.simulate(u), rtol=1e-12, atol=1e-12))
    True
    >>> t.parameters.names[:4]
    ('a1', 'a2', 'q2a1', 'q2a2')
    """

    def __init__(self, structure: Structure, linear=None, nonlinear=None, *,
                 operating_point=None):
        if not isinstance(structure, Structure):
            raise ParameterError(f"`structure` must be a fohw.Structure; got "
                                 f"{type(structure).__name__}.")
        self.structure = structure
        n_lin, n_nl = structure.n_linear, structure.n_nonlinear
        if linear is None:
            linear = np.zeros(n_lin)
        if nonlinear is None:
            nonlinear = np.zeros(n_nl)
            nonlinear[:len(structure.orders.free)] = 0.5
        linear = np.atleast_1d(check_array(linear, "linear", min_length=0))
        nonlinear = np.atleast_1d(check_array(nonlinear, "nonlinear", min_length=0))
        for value, names, what in ((linear, structure.linear_names, "linear"),
                                   (nonlinear, structure.nonlinear_names, "nonlinear")):
            if value.shape != (len(names),):
                raise DimensionError(f"`{what}` must have {len(names)} entries {names}; got "
                                     f"shape {value.shape}.")
        structure.orders.free_mapping(dict(zip(structure.orders.free, nonlinear)), "nonlinear")
        if operating_point is None:
            operating_point = ((0.0,) * structure.n_inputs, 0.0) if structure.n_inputs > 1 \
                else (0.0, 0.0)
        self.operating_point = (check_pair(operating_point, "operating_point")
                                if structure.n_inputs == 1 else
                                check_input_point(operating_point, structure.n_inputs))
        linear.setflags(write=False)
        nonlinear.setflags(write=False)
        self.linear, self.nonlinear = linear, nonlinear

    # --- the facts a result also has ---------------------------------------------------------
    @property
    def theta(self) -> np.ndarray:
        """The parameter vector theta (Eq. 20): :attr:`linear` without the offset."""
        return self.linear[:self.structure.layout.n_params]

    @property
    def offset(self) -> float:
        """The constant ``c`` of the equation (0 when the structure fits none)."""
        return float(self.linear[-1]) if self.structure.offset else 0.0

    @property
    def orders(self) -> dict:
        """``{free order: value}``."""
        return self.structure.split_nonlinear(self.nonlinear)[0]

    @property
    def alpha(self) -> float | None:
        """The first free order (the paper's alpha), or ``None`` when every order is fixed."""
        return next(iter(self.orders.values()), None)

    @property
    def past(self) -> tuple:
        """The levels ``(u_past, y_past)`` the model rested at before ``k = 0``."""
        return self.structure.split_nonlinear(self.nonlinear)[1]

    @property
    def output_map_params(self) -> dict:
        """The series output map's parameters ``{name: value}`` (empty without one)."""
        hmap = self.structure.output_map
        if hmap is None:
            return {}
        return dict(zip(hmap.names, self.structure.output_map_params(self.nonlinear).tolist()))

    @property
    def layout(self):
        """Names and blocks of theta (``structure.layout``)."""
        return self.structure.layout

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :attr:`theta` (``a1``, ``q2a1``, ``b1``, ``p2b1``, …)."""
        return self.layout.names

    @property
    def na(self) -> int:
        """Largest output lag."""
        return self.structure.na

    @property
    def nb(self) -> int:
        """Number of input lags."""
        return self.structure.nb

    @property
    def nk(self) -> int:
        """Input delay: the smallest input lag."""
        return self.structure.nk

    @property
    def dt(self) -> float:
        """Sampling time."""
        return self.structure.dt

    @property
    def n_inputs(self) -> int:
        """Number of input columns."""
        return self.structure.n_inputs

    def shared(self) -> HammersteinWiener:
        """The model with one map per branch nearest to this one (Eqs. 39–40).

        ``a, b, p, q`` recovered from theta by the rank-one recovery of the paper
        (:meth:`fohw.HammersteinWiener.from_theta`): exact when theta is ``[q ⊗ a, p ⊗ b]``,
        otherwise a different (smaller) model that simulates otherwise.

        Raises
        ------
        ParameterError
            The recovery is undefined (an ``a_i`` or ``b_i`` exactly zero), the model has
            several inputs or a series output map (which a HammersteinWiener does not carry).
        """
        s = self.structure
        if s.n_inputs > 1 or s.output_map is not None:
            raise ParameterError("ThetaHW.shared: a fohw.HammersteinWiener has one input and no "
                                 "series output map; this model has "
                                 + ("several inputs" if s.n_inputs > 1 else "an output map") + ".")
        return HammersteinWiener.from_theta(
            self.theta, self.orders, na=s.na, nb=s.nb, f_basis=s.f_basis, g_basis=s.g_basis,
            orders=s.orders, dt=s.dt, offset=self.offset, past=self.past,
            operating_point=self.operating_point, nk=s.nk)

    def predict(self, u, y) -> np.ndarray:
        """One-step-ahead prediction ``yhat[k] = phi[k] @ [theta, c] + y0`` (Eq. 19), data units.

        The regressors are built from the measured ``y``; with a series output map ``h`` the
        prediction is ``h(phi[k] @ [theta, c] + y0)`` (exact only where ``h`` is the identity;
        the free run, :meth:`simulate`, is the model).
        """
        y = check_array(y, "y")
        y0 = float(self.operating_point[1])
        builder = RegressorBuilder(self._deviation(u), y - y0 if y0 else y,
                                   structure=self.structure.inner)
        nonlinear = self.nonlinear[:self.structure.inner.n_nonlinear]
        yhat = builder.matrix(nonlinear) @ self.linear
        yhat = yhat + y0 if y0 else yhat
        hmap = self.structure.output_map
        if hmap is not None:
            yhat = hmap.evaluate(yhat, self.structure.output_map_params(self.nonlinear))
        return yhat

    def static_gain(self, u_level) -> float:
        """The steady output for a constant input ``u_level`` (data units), or ``nan``.

        As :meth:`fohw.HammersteinWiener.static_gain`, each term with its own map: only order-0
        terms carry a static gain (a fractional difference of a constant vanishes), and the
        steady ``ybar`` solves ``ybar = c + sum_{nu_t = 0} qa_t ybar + sum_{nu_t = 0}
        sum_j pb_jt f_j(ubar)`` for the linear output basis (``g = y``; refused otherwise).
        ``nan`` when ``1 - sum qa_t`` (order 0) is 0. Single input, no output map.

        Examples
        --------
        >>> import fohw
        >>> s = fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, orders="mixed")
        >>> m = fohw.ThetaHW(s, [0.3, 0.1, 1.0, 0.5], [0.4])     # y = 0.3 y[k-1] + 1.0 u[k-1] + …
        >>> round(m.static_gain(2.0), 12)                           # 2 / (1 - 0.3)
        2.857142857143
        """
        s = self.structure
        if not s.g_basis.is_polynomial or len(s.g_basis) != 1:
            raise ParameterError("static_gain is explicit for the linear output basis "
                                 "(g_basis=1) only.")
        if s.n_inputs > 1 or s.output_map is not None:
            raise ParameterError("ThetaHW.static_gain is written for one input and no series "
                                 "output map.")
        out_nu, in_nu = s.orders.values(self.orders)
        qa, pb = s.layout.blocks(self.theta)
        u0, y0 = self.operating_point
        fvals = s.f_basis.evaluate(np.array([check_scalar(u_level, "u_level") - u0]))[:, 0]
        a0 = sum(qa[0, t] for t, nu in enumerate(out_nu) if nu == 0.0)
        b0 = sum(float(pb[:, t] @ fvals) for t, nu in enumerate(in_nu) if nu == 0.0)
        denom = 1.0 - a0
        if denom == 0.0:
            return float("nan")
        return float(y0 + (self.offset + b0) / denom)

    # --- the Model protocol ------------------------------------------------------------------
    @property
    def parameters(self) -> Parameters:
        """Theta's entries, the offset, the free orders (``order=True``), past levels, ``h_*``."""
        s = self.structure
        orders = set(s.orders.free)
        return Parameters([Parameter(n, float(v)) for n, v in zip(s.linear_names, self.linear)]
                          + [Parameter(n, float(v), order=n in orders)
                             for n, v in zip(s.nonlinear_names, self.nonlinear)])

    def with_parameters(self, values) -> ThetaHW:
        """A copy with new values of :attr:`parameters` (a mapping by name, or Parameters)."""
        v = self.parameters.with_values(values).valuesdict()
        s = self.structure
        return ThetaHW(s, [v[n] for n in s.linear_names], [v[n] for n in s.nonlinear_names],
                       operating_point=self.operating_point)

    def _deviation(self, u):
        u = check_inputs(u, self.structure.n_inputs, names=self.structure.inputs)
        u0 = np.asarray(self.operating_point[0], dtype=float)
        return u - u0 if np.any(u0) else u

    def simulate(self, u, *, initial=None, noise=None, noise_std=0.0, random_state=None,
                 divergence_threshold=None) -> np.ndarray:
        """The free run for ``u`` (data units), from the model's own past levels.

        ``initial`` is ``None`` or a measured history ``(u_past, y_past)`` just before ``u``; the
        other keywords as for :func:`fohw.simulate`.
        """
        if isinstance(initial, str) or (initial is not None and (
                not isinstance(initial, (tuple, list)) or len(initial) != 2)):
            raise ParameterError("ThetaHW.simulate: `initial` is a measured history (u_past, "
                                 "y_past); the other initial states are an identification "
                                 f"result's (result.simulate(u, initial=...)); got {initial!r}.")
        return simulate_predictor(self.structure, self.linear, self.nonlinear, u,
                                  operating_point=self.operating_point, noise=noise,
                                  noise_std=noise_std, random_state=random_state,
                                  divergence_threshold=divergence_threshold, history=initial)

    def jacobian(self, u):
        """``(yhat, J)``: the free run and its exact sensitivity to every parameter (in order)."""
        y0 = float(self.operating_point[1])
        y, jac = simulation_jacobian(self.structure, self.linear, self.nonlinear,
                                     self._deviation(u), y0=y0)
        return (y + y0 if y0 else y), jac

    def linear_start(self, u, y, *, sample_weight=None):
        """The model with theta (and the offset) solved by least squares at its own orders.

        The equation-error fit of Eq. (19) at the current nonlinear parameters (the step of
        ``"varpro"`` for fixed orders), weighted by ``sample_weight``. ``None`` with a series
        output map (``y`` is then not the recursion's signal).
        """
        s = self.structure
        if s.output_map is not None:
            return None
        y0 = float(self.operating_point[1])
        yd = check_array(y, "y") - y0
        builder = RegressorBuilder(self._deviation(u), yd, structure=s)
        phi = builder.matrix(self.nonlinear)
        if sample_weight is not None:
            w = np.sqrt(check_array(sample_weight, "sample_weight"))
            phi, yd = phi * w[:, None], yd * w
        linear, _, _ = _linalg.lstsq(phi, yd)
        if not np.all(np.isfinite(linear)):
            return None
        return self.with_parameters(dict(zip(s.linear_names, linear.tolist())))

    # the lagged kind's refusal of non-uniform instants and its curve's name: one text, the
    # HammersteinWiener's (its message names the class it is called on)
    simulate_at = HammersteinWiener.simulate_at

    def frequency_response(self, omega):
        """The linear block's ``H(e^{j omega dt})`` (:mod:`fohw.model.lagged.hw_frequency`).

        Each term linearised with its own map's slope at the operating point (for polynomial
        bases theta's first block, as :meth:`fohw.HammersteinWiener.frequency_response` of the
        rank-one model); ``omega`` in radians per unit of :attr:`dt`. Single input.
        """
        from .hw_frequency import LinearBlock

        return LinearBlock.from_model(self).frequency_response(omega)

    response_label = HammersteinWiener.response_label

    def config(self) -> dict:
        """``{"structure", "operating_point", "dt"}``: the settings that are not parameters.

        ``dt`` is also the structure's; it is given on its own, as every kind with a sampling
        time gives it, so that the verbs check it against a record's.
        """
        op = self.operating_point
        point = [list(op[0]), op[1]] if self.structure.n_inputs > 1 else list(op)
        structure = {k: v for k, v in self.structure.to_dict().items() if k != "dt"}
        return {"structure": structure, "operating_point": point, "dt": self.dt}

    @classmethod
    def from_config(cls, config) -> ThetaHW:
        """Inverse of :meth:`config` (parameters at their defaults)."""
        if not isinstance(config, dict) or set(config) != {"structure", "operating_point", "dt"}:
            raise ParameterError("a ThetaHW's config has exactly 'structure', "
                                 f"'operating_point' and 'dt'; got {config!r}.")
        structure = config["structure"]
        if not isinstance(structure, dict):
            raise ParameterError(f"a ThetaHW's 'structure' must be a mapping; got {structure!r}.")
        return cls(Structure.from_dict({**structure, "dt": config["dt"]}),
                   operating_point=config["operating_point"])

    def __repr__(self):
        values = ", ".join(f"{n}={v:.6g}" for n, v in self.parameters.valuesdict().items())
        return f"ThetaHW({values}, dt={self.dt!r})"

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return (self.structure == other.structure and self.operating_point ==
                other.operating_point and np.array_equal(self.linear, other.linear)
                and np.array_equal(self.nonlinear, other.nonlinear))

    __hash__ = None
