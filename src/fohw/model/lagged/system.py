"""The fractional-order Hammerstein–Wiener model (Section 2.3, Eqs. 10–18).

Also Eqs. 7, 14 (an order per term) and 56–57 (conventions: docs/conventions.md). The paper's model, Eq. (16):

.. math:: y[k] = \\sum_{i=1}^{n_a} a_i (\\Delta^{\\alpha} \\bar g(y))[k-i]
          + \\sum_{i=1}^{n_b} b_i (\\Delta^{\\alpha} \\bar f(u))[k-i] + v[k]

with ``fbar = sum_j p_j f_j``, ``gbar = sum_j q_j g_j``, ``p_1 = q_1 = 1`` and zero
initial conditions, so ``y[0] = v[0]``. The general model (:class:`fohw.Structure`) gives every
term its own lag and order (0 included), adds an offset, past levels and a sampling time, and
acts on deviations from an operating point. Its output is computed by
:mod:`fohw.model.lagged.simulation` (:func:`fohw.simulate`).
"""

from __future__ import annotations

import numpy as np

from ..._types import ArrayLike, PairLike
from ..._validation import check_alpha, check_array, check_pair, check_scalar
from ...exceptions import DimensionError, ParameterError
from ..base import Model
from ..basis import Basis, BasisLike, as_basis, polynomial_basis
from ..orders import ORDER_RANGE, Orders, OrdersLike
from ..parameters import Parameter, Parameters
from .simulation import simulate_model
from .structure import Structure

__all__ = ["HammersteinWiener", "ALPHA_BOUNDS"]

#: Closed interval of fractional orders a model may have (0: the integer-order model); the one
#: rule for every order (:data:`fohw.model.orders.ORDER_RANGE`).
ALPHA_BOUNDS = ORDER_RANGE


class HammersteinWiener(Model):
    """A fractional-order Hammerstein–Wiener model (Eq. 16; Eq. 14 with an order per term).

    The lagged model kind of :class:`fohw.Model`: its :attr:`parameters` are ``a``, ``b``,
    ``p[1:]``, ``q[1:]`` (``p[0] = q[0] = 1``, Eq. 17), the free orders and the offset (when it
    has one); :func:`fohw.fit` fits them by simulation error like any kind, and
    :func:`fohw.identify` is its own front door with the paper's and further methods.

    Parameters
    ----------
    a : array_like, shape (n_a,)
        Coefficients of the output (``g``) branch, one per output term (``na`` lags for the
        paper's commensurate model).
    b : array_like, shape (n_b,)
        Coefficients of the input (``f``) branch, one per input term.
    p : array_like, shape (n_f,)
        Weights of the input basis functions; ``p[0]`` must be exactly 1 (Eq. 17).
    q : array_like, shape (n_g,)
        Weights of the output basis functions; ``q[0]`` must be exactly 1 (Eq. 17).
    alpha : float, sequence or dict, optional
        The fractional order in ``[0, 2]`` (the paper's model), or the values of the free orders
        of ``orders`` (a dict by name, or a sequence in :attr:`Orders.free` order). Not needed
        when every order is fixed.
    f_basis, g_basis : Basis, int, callables or None, optional
        Input and output basis functions; ``None`` means the polynomial basis of degree
        ``len(p)`` (``len(q)``): ``u, u**2, …``.
    orders : str, number, dict or Orders, optional
        Which term has which order (:class:`fohw.Orders`): ``"commensurate"`` (default, the
        paper's Eq. 16), ``"per_lag"``, ``"mixed"`` (then ``a`` and ``b`` hold two coefficients per
        lag: order 0, then alpha), a number, or an :class:`Orders`.
    dt : float, optional
        Sampling time ``h > 0`` (Eq. 4: each term is divided by ``h**nu``). Default 1.
    offset : float, optional
        Constant ``c`` in the equation. Default 0.
    past : (float, float), optional
        Levels ``(u_past, y_past)`` at which the system rested before ``k = 0``, relative to the
        operating point. Default ``(0, 0)``: at rest at the operating point.
    operating_point : (float, float), optional
        ``(u0, y0)``: the model acts on ``u - u0`` and produces ``y - y0``; :func:`fohw.simulate`
        subtracts ``u0`` and adds ``y0``. Default ``(0, 0)``.
    nk : int, optional
        Input delay in samples, ``>= 0``: ``b`` acts at lags ``nk … nk + nb - 1`` (``nk = 0``:
        direct feedthrough, ``b[0]`` multiplies ``fbar(u)(k)``). Default 1 (the paper's lags
        ``1 … nb``), or the lags of an :class:`Orders` given as ``orders``.

    Attributes
    ----------
    theta : ndarray
        ``[q ⊗ a, p ⊗ b]`` (Eq. 20).
    alpha : float or None
        The first free order (the paper's alpha); ``None`` when every order is fixed.
    orders : dict
        ``{free order name: value}``.
    structure : Structure
        The model class (orders, bases, offset, past, dt).
    layout : ThetaLayout
        Maps theta to named blocks.

    Examples
    --------
    >>> import fohw
    >>> model = fohw.HammersteinWiener(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1, 0.5],
    ...                                q=[1, 0.7, 0.35], alpha=0.6)
    >>> model.parameter_names[:3], model.theta[:3].round(3)
    (('a1', 'a2', 'q2a1'), array([0.1 , 0.2 , 0.07]))
    >>> mixed = fohw.HammersteinWiener([0.5, 0.2], [1.0, 0.3], [1], [1], alpha=0.4,
    ...                                orders="mixed")
    >>> mixed.parameter_names, mixed.orders
    (('a1_0', 'a1_alpha', 'b1_0', 'b1_alpha'), {'alpha': 0.4})
    """

    def __init__(self, a: ArrayLike, b: ArrayLike, p: ArrayLike, q: ArrayLike,
                 alpha: float | ArrayLike | None = None, f_basis: BasisLike | None = None,
                 g_basis: BasisLike | None = None, *, orders: OrdersLike | None = None,
                 dt: float = 1.0, offset: float = 0.0, past: PairLike = (0.0, 0.0),
                 operating_point: PairLike = (0.0, 0.0), nk: int | None = None):
        a = check_array(a, "a")
        b = check_array(b, "b")
        p = check_array(p, "p")
        q = check_array(q, "q")
        if p[0] != 1.0:
            raise ParameterError(f"`p[0]` must be exactly 1 (normalisation of Eq. 17); got {p[0]!r}.")
        if q[0] != 1.0:
            raise ParameterError(f"`q[0]` must be exactly 1 (normalisation of Eq. 17); got {q[0]!r}.")
        f_basis = polynomial_basis(p.shape[0]) if f_basis is None else as_basis(f_basis, "f_basis")
        g_basis = polynomial_basis(q.shape[0]) if g_basis is None else as_basis(g_basis, "g_basis")
        if len(f_basis) != p.shape[0]:
            raise DimensionError(f"`p` must have one entry per f-basis function ({len(f_basis)});"
                                 f" got {p.shape[0]}.")
        if len(g_basis) != q.shape[0]:
            raise DimensionError(f"`q` must have one entry per g-basis function ({len(g_basis)});"
                                 f" got {q.shape[0]}.")
        terms = Orders.infer(orders, a.shape[0], b.shape[0], nk)
        if len(terms.free) == 1 and np.ndim(alpha) == 0 and not isinstance(alpha, dict) \
                and alpha is not None:
            alpha = {terms.free[0]: check_alpha(alpha, lower=ALPHA_BOUNDS[0],
                                                upper=ALPHA_BOUNDS[1], inclusive=True)}
        self.orders = terms.free_mapping(alpha)
        self.offset = check_scalar(offset, "offset")
        self.past = check_pair(past, "past")
        self.operating_point = check_pair(operating_point, "operating_point")
        self.structure = Structure(terms, f_basis, g_basis, offset=self.offset != 0.0,
                                   past="estimate" if self.past != (0.0, 0.0) else "rest", dt=dt)
        self.f_basis, self.g_basis = f_basis, g_basis
        self.layout = self.structure.layout
        for name, v in (("a", a), ("b", b), ("p", p), ("q", q)):
            v.setflags(write=False)
            setattr(self, name, v)

    @property
    def alpha(self):
        """The first free order (the paper's alpha), or ``None`` when every order is fixed."""
        return next(iter(self.orders.values()), None)

    @property
    def dt(self) -> float:
        """Sampling time."""
        return self.structure.dt

    @property
    def na(self) -> int:
        """Number of output terms (lags, for the paper's model)."""
        return self.layout.na

    @property
    def nb(self) -> int:
        """Number of input terms (lags, for the paper's model)."""
        return self.layout.nb

    @property
    def nk(self) -> int:
        """Input delay: the smallest input lag (1 for the paper's model; 0: direct feedthrough)."""
        return self.structure.nk

    @property
    def theta(self) -> np.ndarray:
        """Parameter vector ``[q ⊗ a, p ⊗ b]`` (Eq. 20)."""
        return self.layout.to_theta(self.a, self.b, self.p, self.q)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :attr:`theta` (``a1``, ``q2a1``, ``b1``, ``p2b1``, …)."""
        return self.layout.names

    @property
    def linear(self) -> np.ndarray:
        """The linear parameters of :attr:`structure`: :attr:`theta`, then the offset if any."""
        extra = [self.offset] if self.structure.offset else []
        return np.concatenate([self.theta, extra])

    @property
    def nonlinear(self) -> np.ndarray:
        """The nonlinear parameters of :attr:`structure`: free orders, then the past levels."""
        past = list(self.past) if self.structure.past == "estimate" else []
        return np.array([self.orders[n] for n in self.structure.orders.free] + past, dtype=float)

    def static_gain(self, u_level):
        """The steady output for a constant input ``u_level`` (model units), or ``nan``.

        A fractional term (order > 0) of a constant vanishes in steady state (``Delta^nu`` of
        a constant decays like ``k**-nu``), so only order-0 terms carry a static gain: the
        steady ``y`` solves ``ybar = c + sum_{nu_t = 0} (a_t gbar(ybar)) + sum_{nu_t = 0} b_t
        fbar(ubar)`` in deviation coordinates. Returned for the linear output basis (``g =
        y``), where it is explicit; ``nan`` when ``1 - sum a_t`` (order 0) is 0.
        """
        if not self.g_basis.is_polynomial or len(self.g_basis) != 1:
            raise ParameterError("static_gain is explicit for the linear output basis "
                                 "(g_basis=1) only.")
        out_nu, in_nu = self.structure.orders.values(self.orders)
        u0, y0 = self.operating_point
        ubar = check_scalar(u_level, "u_level") - u0
        fbar = float(self.p @ self.f_basis.evaluate(np.array([ubar]))[:, 0])
        a0 = sum(a for a, nu in zip(self.a, out_nu) if nu == 0.0)
        b0 = sum(b for b, nu in zip(self.b, in_nu) if nu == 0.0)
        denom = 1.0 - a0
        if denom == 0.0:
            return float("nan")
        return y0 + (self.offset + b0 * fbar) / denom

    @classmethod
    def from_theta(cls, theta: ArrayLike, alpha: float | ArrayLike | None, *, na: int, nb: int,
                   f_basis: BasisLike, g_basis: BasisLike, orders: OrdersLike | None = None,
                   dt: float = 1.0, offset: float = 0.0, past: PairLike = (0.0, 0.0),
                   operating_point: PairLike = (0.0, 0.0), nk: int = 1) -> HammersteinWiener:
        """Build a model from a parameter vector by Eqs. (39)–(40).

        Parameters
        ----------
        theta : array_like, shape (n,)
            ``[q ⊗ a, p ⊗ b]``.
        alpha : float, sequence or dict
            Fractional order(s), as for the constructor.
        na, nb : int
            Output and input lag orders.
        f_basis, g_basis : Basis, int or callables
            Input and output basis functions.
        orders, dt, offset, past, operating_point
            As for the constructor (``orders`` with the lags ``na``, ``nb``).
        nk : int, optional
            Input delay (default 1): input lags ``nk … nk + nb - 1``.

        Returns
        -------
        HammersteinWiener

        Notes
        -----
        ``a`` and ``b`` are the first block of each branch; ``q_j``, ``p_j`` are averaged
        ratios (Eqs. 39–40). For a theta that is not an exact Kronecker product (any estimate),
        the model's :attr:`theta` differs from the input theta.

        Examples
        --------
        >>> import fohw
        >>> m = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
        >>> m2 = fohw.HammersteinWiener.from_theta(m.theta, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
        >>> m2.q.round(12)
        array([1.  , 0.7 , 0.35])
        """
        structure = Structure.make(na=na, nb=nb, f_basis=f_basis, g_basis=g_basis,
                                   orders=orders, dt=dt, nk=nk)
        a, b, p, q = structure.layout.recover(theta)
        return cls(a, b, p, q, alpha, f_basis=structure.f_basis, g_basis=structure.g_basis,
                   orders=structure.orders, dt=dt, offset=offset, past=past,
                   operating_point=operating_point)

    def __repr__(self):
        def fmt(v):
            return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
        if self.structure.orders.is_commensurate:
            orders = f"alpha={self.alpha:.6g}"
        else:
            values = ", ".join(f"{k}={v:.6g}" for k, v in self.orders.items())
            orders = f"orders={self.structure.orders!r}" + (f", {values}" if values else "")
        extra = "".join(f", {name}={value!r}" for name, value, default in (
            ("dt", self.dt, 1.0), ("offset", self.offset, 0.0), ("past", self.past, (0.0, 0.0)),
            ("operating_point", self.operating_point, (0.0, 0.0))) if value != default)
        return (f"HammersteinWiener(a={fmt(self.a)}, b={fmt(self.b)}, p={fmt(self.p)}, "
                f"q={fmt(self.q)}, {orders}, f_basis={self.f_basis!r}, "
                f"g_basis={self.g_basis!r}{extra})")

    def __eq__(self, other):
        return (isinstance(other, HammersteinWiener) and self.orders == other.orders
                and self.structure == other.structure
                and (self.offset, self.past, self.operating_point)
                == (other.offset, other.past, other.operating_point)
                and all(np.array_equal(getattr(self, n), getattr(other, n)) for n in "abpq"))

    __hash__ = None

    def description(self) -> list:
        """The bases and the orders, then the sampling time (:meth:`fohw.Model.description`)."""
        return [f"f_basis = {self.f_basis!r}, g_basis = {self.g_basis!r}",
                f"orders: {self.structure.orders!r}", *super().description()]

    # --- the Model protocol ---------------------------------------------------------------
    def _names(self):
        a_names = tuple(self.layout.a_names)
        b_names = tuple(self.layout.b_names)
        p_names = tuple(f"p{j}" for j in range(2, self.p.size + 1))
        q_names = tuple(f"q{j}" for j in range(2, self.q.size + 1))
        return a_names, b_names, p_names, q_names

    @property
    def parameters(self) -> Parameters:
        """``a``, ``b``, ``p[1:]``, ``q[1:]``, the free orders and the offset, as :class:`fohw.Parameters`.

        Examples
        --------
        >>> import fohw
        >>> m = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
        >>> m.parameters.names
        ('a1', 'a2', 'b1', 'b2', 'p2', 'q2', 'q3', 'alpha')
        """
        a_names, b_names, p_names, q_names = self._names()
        pars = [Parameter(n, v) for n, v in zip(a_names, self.a.tolist())]
        pars += [Parameter(n, v) for n, v in zip(b_names, self.b.tolist())]
        pars += [Parameter(n, v) for n, v in zip(p_names, self.p[1:].tolist())]
        pars += [Parameter(n, v) for n, v in zip(q_names, self.q[1:].tolist())]
        pars += [Parameter(n, v, order=True) for n, v in self.orders.items()]
        if self.structure.offset:
            pars.append(Parameter("offset", self.offset))
        return Parameters(pars)

    def with_parameters(self, values) -> HammersteinWiener:
        """A copy with new values of :attr:`parameters` (a mapping by name, or Parameters)."""
        v = self.parameters.with_values(values).valuesdict()
        a_names, b_names, p_names, q_names = self._names()
        return HammersteinWiener(
            [v[n] for n in a_names], [v[n] for n in b_names], [1.0] + [v[n] for n in p_names],
            [1.0] + [v[n] for n in q_names], {n: v[n] for n in self.orders} or None,
            f_basis=self.f_basis, g_basis=self.g_basis, orders=self.structure.orders,
            dt=self.dt, offset=v.get("offset", self.offset), past=self.past,
            operating_point=self.operating_point)

    def simulate(self, u, *, initial=None, noise=None, noise_std=0.0, random_state=None,
                 divergence_threshold=None):
        """The model's output for ``u``: :func:`fohw.simulate` (the same keywords).

        ``initial`` is ``None`` (at rest before ``u``, after the model's past levels) or a
        measured history ``(u_past, y_past)`` just before ``u``, from which the free run
        continues.
        """
        if isinstance(initial, str) or (initial is not None and (
                not isinstance(initial, (tuple, list)) or len(initial) != 2)):
            raise ParameterError("HammersteinWiener.simulate: `initial` is a measured history "
                                 "(u_past, y_past); the other initial states need an "
                                 f"identification result's estimate; got {initial!r}.")
        return simulate_model(self, u, noise=noise, noise_std=noise_std,
                              random_state=random_state,
                              divergence_threshold=divergence_threshold, history=initial)

    def jacobian(self, u):
        """``(yhat, J)``: the free run and its exact sensitivity to every parameter (in order).

        The sensitivity of the free run to ``(theta, offset, orders)``
        (:func:`fohw.model.lagged.sensitivity.simulation_jacobian`, exact) chain-ruled through
        ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20, :meth:`fohw.Structure.structured_jacobian`) to
        :attr:`parameters`: ``a``, ``b``, ``p[1:]``, ``q[1:]``, the free orders, the offset.
        """
        from .sensitivity import simulation_jacobian

        s = self.structure
        u = check_array(u, "u")
        u0, y0 = self.operating_point
        y, jac = simulation_jacobian(s, self.linear, self.nonlinear, u - u0 if u0 else u)
        a_names, b_names, p_names, q_names = self._names()
        eta = np.r_[self.a, self.b, self.p[1:], self.q[1:]]
        x = np.r_[eta, [self.offset] if s.offset else [], self.nonlinear]
        by_name = dict(zip(s.structured_names, (jac @ s.structured_jacobian(x)).T))
        names = self.parameters.names
        if set(names) - set(by_name):           # the layout names the model's blocks otherwise
            raise ParameterError(f"HammersteinWiener.jacobian: no column for "
                                 f"{sorted(set(names) - set(by_name))}.")
        return (y + y0 if y0 else y), np.column_stack([by_name[n] for n in names])

    def simulate_at(self, u, t, *, intersample="zoh", refine=None, step=None):
        """Refused: the lagged model is discrete in samples (its lags are samples, not seconds)."""
        # fohw.ThetaHW shares this method (one text for the lagged kind): the message names the
        # class it is called on
        raise ParameterError(
            f"a {type(self).__name__} (the lagged kind) is discrete in samples: it has no meaning "
            "between its samples, so it cannot be simulated at non-uniform instants `t`. "
            "resample the record to a uniform grid (fohw.model.irregular.resample), or use a "
            "continuous-time kind (fohw.FractionalTF, fohw.FractionalHW, fohw.EquivalentCircuit).")

    def config(self) -> dict:
        """The model in its own file format (:meth:`to_dict`): what :meth:`fohw.Model.to_dict` stores."""
        return self.to_dict()

    @classmethod
    def from_config(cls, config) -> HammersteinWiener:
        """Inverse of :meth:`config`."""
        return cls.from_dict(config)

    #: The fields of :meth:`to_dict`, each fact once.
    DICT_FIELDS = ("a", "b", "p", "q", "orders", "terms", "f_basis", "g_basis", "dt", "offset",
                   "past", "operating_point")

    def to_dict(self) -> dict:
        """A JSON-ready dict of the model, each fact once (:func:`fohw.save_model` writes it).

        ``orders`` holds the values of the free orders, ``terms`` which term has which order
        (:meth:`Orders.to_dict`); a custom basis is stored by its names only.

        Examples
        --------
        >>> import fohw
        >>> m = fohw.datasets.paper_model()
        >>> fohw.HammersteinWiener.from_dict(m.to_dict()) == m
        True
        """
        return {"a": self.a.tolist(), "b": self.b.tolist(), "p": self.p.tolist(),
                "q": self.q.tolist(), "orders": dict(self.orders),
                "terms": self.structure.orders.to_dict(), "f_basis": self.f_basis.to_dict(),
                "g_basis": self.g_basis.to_dict(), "dt": self.dt, "offset": self.offset,
                "past": list(self.past), "operating_point": list(self.operating_point)}

    @classmethod
    def from_dict(cls, d, *, f_basis=None, g_basis=None) -> HammersteinWiener:
        """Inverse of :meth:`to_dict` (custom bases passed again, checked by their names).

        Raises
        ------
        ParameterError, DimensionError
            A field is missing, unknown or invalid (the message names it).
        """
        if not isinstance(d, dict) or set(d) != set(cls.DICT_FIELDS):
            got = sorted(d) if isinstance(d, dict) else d
            raise ParameterError(f"a model dict has exactly the fields {sorted(cls.DICT_FIELDS)}; "
                                 f"got {got!r}.")
        return cls(d["a"], d["b"], d["p"], d["q"], d["orders"],
                   f_basis=Basis.from_dict(d["f_basis"], f_basis, name="f_basis"),
                   g_basis=Basis.from_dict(d["g_basis"], g_basis, name="g_basis"),
                   orders=Orders.from_dict(d["terms"]), dt=d["dt"], offset=d["offset"],
                   past=d["past"], operating_point=d["operating_point"])

    # --- the frequency view (fohw.Model's hooks) ----------------------------------------------
    def frequency_response(self, omega):
        """The linear block's ``H(e^{j omega dt}) = f' B / (1 - g' A)`` (:mod:`~.hw_frequency`).

        The :meth:`fohw.Model.frequency_response` hook: the static maps replaced by their
        slopes at the operating point (the linearisation of
        :class:`fohw.model.lagged.hw_frequency.LinearBlock`), ``omega`` in radians per unit of
        :attr:`dt` (``0 < |omega| dt < 2 pi``). :meth:`bode` and :meth:`nyquist` draw it.

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> m = fohw.HammersteinWiener([0.5], [1.0], [1.0], [1.0], orders=0)   # y = 0.5 y[k-1] + u[k-1]
        >>> z = np.exp(0.3j)
        >>> bool(np.isclose(m.frequency_response([0.3])[0], (1 / z) / (1 - 0.5 / z), rtol=1e-14))
        True
        """
        from .hw_frequency import LinearBlock

        return LinearBlock.from_model(self).frequency_response(omega)

    def response_label(self):
        """The curve's name in :meth:`bode` and :meth:`nyquist`: the linear block ``H``."""
        return "linear block H(exp(jωh))"
