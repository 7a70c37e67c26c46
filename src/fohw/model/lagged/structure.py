"""The model class: everything about a fractional-order HW model except its parameter values.

A :class:`Structure` fixes the terms of the linear block and their orders (:class:`fohw.Orders`),
the basis functions, whether the equation has a constant (``offset``), what the signals did
before ``k = 0`` (``past``) and the sampling time ``dt``. Its parameters fall in two groups,
the split that separable least squares exploits:

* **linear**: ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20, named by
  :class:`fohw.model.lagged.params.ThetaLayout`), then the
  offset ``c`` if there is one;
* **nonlinear**: the free orders (in :attr:`Orders.free` order), then the levels ``u_past`` and
  ``y_past`` of the unseen past if ``past="estimate"``, then the parameters of a series output
  map ``h`` (``h_*``, :mod:`fohw.model.output_map`) if there is one.

The equation (Eq. 16 generalised; deviations from the operating point, see
:class:`fohw.HammersteinWiener`) is

.. math:: y[k] = \\sum_t a_t (\\Delta_h^{\\nu_t} \\bar g(y))[k - i_t]
          + \\sum_t b_t (\\Delta_h^{\\nu_t} \\bar f(u))[k - i_t] + c + v[k],

with ``Delta_h^nu = h**-nu Delta^nu`` (Eq. 4). ``past="rest"`` (default) is the usual assumption
for GL models of measured data: the signals were zero (at the operating point) before ``k = 0``.
``past="estimate"`` assumes the system rested at constant levels ``u(t) = u_past`` and
``y(t) = y_past`` for all ``t < 0`` and estimates them: a basis signal ``s`` with past level
``L`` then has ``(Delta^nu s)[t] = sum_{j<=t} beta_j (s[t-j] - L) + L * S_inf(nu)``, where
``S_inf(0) = 1`` and ``S_inf(nu) = 0`` for ``nu > 0`` (the GL sum of a constant over an infinite
past vanishes), i.e. the zero-past difference plus ``L (S_inf - S_t)`` with ``S_t`` the partial
sums of the weights.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..._validation import check_scalar
from ...exceptions import DimensionError, ParameterError
from ..basis import Basis, InputBases, as_basis, as_input_bases
from ..orders import Orders
from ..output_map import SeriesMap, as_output_map, output_map_from_dict
from .params import ThetaLayout

__all__ = ["Structure", "PAST_MODES"]

#: ``"rest"``: zero (the operating point) before ``k = 0``; ``"estimate"``: constant levels
#: ``u_past``, ``y_past`` before ``k = 0``, estimated.
PAST_MODES = ("rest", "estimate")
PAST_NAMES = ("u_past", "y_past")


@dataclass(frozen=True, eq=False)
class Structure:
    """The model class (orders, bases, offset, past, sampling time) without parameter values.

    Parameters
    ----------
    orders : Orders
    f_basis, g_basis : Basis
    offset : bool
        A constant ``c`` in the equation.
    past : {"rest", "estimate"}
        What the signals did before ``k = 0`` (see the module notes).
    dt : float
        Sampling time ``h > 0``; every term is divided by ``h**nu`` (Eq. 4).
    output_map : SeriesMap, str, int or None
        A series output block ``y = h(z)`` after the recursion (data units,
        :mod:`fohw.model.output_map`); None (default): the measured output is ``z`` itself.

    Examples
    --------
    >>> import fohw
    >>> s = fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, orders="mixed", offset=True)
    >>> s.linear_names, s.nonlinear_names
    (('a1_0', 'a1_alpha', 'b1_0', 'b1_alpha', 'offset'), ('alpha',))
    """

    orders: Orders
    f_basis: Basis
    g_basis: Basis
    offset: bool = False
    past: str = "rest"
    dt: float = 1.0
    output_map: SeriesMap | None = None

    def __post_init__(self):
        if not isinstance(self.orders, Orders):
            raise ParameterError(f"`orders` must be an Orders; got {type(self.orders).__name__}.")
        if self.orders.n_inputs > 1:
            object.__setattr__(self, "f_basis", as_input_bases(self.f_basis, self.orders.inputs))
            if self.past != "rest":
                raise ParameterError(f"`past` = {self.past!r} is for a single input; a model "
                                     f"with several inputs ({list(self.orders.inputs)}) starts "
                                     "from rest (past='rest').")
        else:
            object.__setattr__(self, "f_basis", as_basis(self.f_basis, "f_basis"))
        object.__setattr__(self, "g_basis", as_basis(self.g_basis, "g_basis"))
        if not isinstance(self.offset, bool):
            raise ParameterError(f"`offset` must be True or False; got {self.offset!r}.")
        if self.past not in PAST_MODES:
            raise ParameterError(f"`past` must be one of {PAST_MODES}; got {self.past!r}.")
        object.__setattr__(self, "dt", check_scalar(self.dt, "dt", lower=0.0,
                                                    lower_inclusive=False))
        object.__setattr__(self, "output_map", as_output_map(self.output_map))

    @classmethod
    def make(cls, *, na, nb, f_basis, g_basis, orders=None, offset=False, past="rest", dt=1.0,
             nk=1, inputs=None, output_map=None):
        """A structure from the spellings :func:`fohw.identify` accepts (``orders`` preset, …).

        ``nk`` is the input delay: the input terms sit at lags ``nk … nk + nb - 1``. Several
        inputs: ``inputs`` names them, and ``nb``, ``nk`` and ``f_basis`` are one per input
        (a list) or one for all.
        """
        return cls(Orders.resolve(orders, na=na, nb=nb, nk=nk, inputs=inputs), f_basis, g_basis,
                   offset, past, dt, output_map)

    @property
    def inner(self) -> Structure:
        """The structure without its series output map (itself when it has none): ``z``'s model."""
        if self.output_map is None:
            return self
        return Structure(self.orders, self.f_basis, self.g_basis, self.offset, self.past, self.dt)

    def with_output_map(self, output_map) -> Structure:
        """The same structure with another series output map (None: without one)."""
        return Structure(self.orders, self.f_basis, self.g_basis, self.offset, self.past, self.dt,
                         output_map)

    def output_map_params(self, params) -> np.ndarray:
        """The output map's parameters: the last entries of a nonlinear vector (empty if none)."""
        n = 0 if self.output_map is None else self.output_map.n_params
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        return params[params.shape[0] - n:].copy()

    @cached_property
    def layout(self) -> ThetaLayout:
        """The theta layout, with the term names of :attr:`orders`."""
        groups = None
        if self.orders.n_inputs > 1:
            groups = tuple((name, names, len(part)) for (name, names), part
                           in zip(self.orders.input_groups(), self.f_basis.parts))
        return ThetaLayout(na=len(self.orders.output), nb=len(self.orders.input),
                           n_g=len(self.g_basis), n_f=len(self.f_basis),
                           a_names=self.orders.a_names, b_names=self.orders.b_names,
                           b_groups=groups)

    @property
    def n_inputs(self) -> int:
        """Number of inputs (1: the paper's single-input model)."""
        return self.orders.n_inputs

    @property
    def inputs(self) -> tuple[str, ...]:
        """Names of the inputs when there are several (``()`` for one)."""
        return self.orders.inputs

    @property
    def na(self) -> int:
        """Largest output lag."""
        return self.orders.na

    @property
    def nb(self) -> int:
        """Number of input lags (``nk … nk + nb - 1``)."""
        return self.orders.nb

    @property
    def nk(self) -> int:
        """Input delay: the smallest input lag (1 in the paper; 0: direct feedthrough)."""
        return self.orders.nk

    @property
    def max_lag(self) -> int:
        """Largest lag of either branch: a record must be longer."""
        return self.orders.max_lag

    @property
    def is_paper_model(self) -> bool:
        """The paper's Eq. (16): commensurate orders (input lags from 1), no offset, rest, ``dt = 1``."""
        return (self.orders.is_commensurate and not self.offset and self.past == "rest"
                and self.dt == 1.0 and self.output_map is None)

    @property
    def linear_names(self) -> tuple[str, ...]:
        """Names of the linear parameters: theta's, then ``"offset"``."""
        return self.layout.names + (("offset",) if self.offset else ())

    @property
    def nonlinear_names(self) -> tuple[str, ...]:
        """Names of the nonlinear parameters: the free orders, ``u_past``, ``y_past``, ``h_*``."""
        return (self.orders.free + (PAST_NAMES if self.past == "estimate" else ())
                + (() if self.output_map is None else self.output_map.names))

    @property
    def n_linear(self) -> int:
        """Number of linear parameters."""
        return self.layout.n_params + int(self.offset)

    @property
    def n_nonlinear(self) -> int:
        """Number of nonlinear parameters."""
        return len(self.nonlinear_names)

    @property
    def structured_names(self) -> tuple[str, ...]:
        """Names of the structured parametrisation: ``a, b, p_2.., q_2..``, offset, nonlinear.

        The model's own parameters (:attr:`ThetaLayout.model_parameter_names`) in place of
        theta's ``n_g * na + n_f * nb`` entries; ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20).
        """
        return (self.layout.model_parameter_names + (("offset",) if self.offset else ())
                + self.nonlinear_names)

    def from_structured(self, x):
        """``(linear, nonlinear)`` from a vector in :attr:`structured_names` order."""
        x = np.asarray(x, dtype=np.float64)
        m = self.layout.n_model_params
        if x.ndim != 1 or x.shape[0] != len(self.structured_names):
            raise DimensionError(f"the structured parameters {self.structured_names} need "
                                 f"{len(self.structured_names)} values; got shape {x.shape}.")
        k = m + int(self.offset)
        theta = self.layout.theta_of_model_vector(x[:m])
        return np.r_[theta, x[m:k]], x[k:].copy()

    def structured_jacobian(self, x) -> np.ndarray:
        """``d (linear, nonlinear) / d x`` at ``x`` (:attr:`structured_names` order).

        Block diagonal: :meth:`ThetaLayout.theta_jacobian` for theta, the identity for the
        offset and the nonlinear parameters. A Jacobian ``G`` with respect to
        ``(linear, nonlinear)`` becomes ``G @ M`` with respect to the structured parameters,
        and a covariance ``C`` of the structured parameters becomes ``M C M^T`` (Eq. 20 and
        the delta method).

        Returns
        -------
        M : ndarray, shape (n_linear + n_nonlinear, len(structured_names))
        """
        x = np.asarray(x, dtype=np.float64)
        self.from_structured(x)                    # checks the length
        m, n = self.layout.n_model_params, self.layout.n_params
        rest = x.shape[0] - m
        M = np.zeros((n + rest, m + rest))
        M[:n, :m] = self.layout.theta_jacobian(x[:m])
        M[n:, m:] = np.eye(rest)
        return M

    def to_structured(self, linear, nonlinear) -> np.ndarray:
        """Structured parameters from any ``(linear, nonlinear)`` (rank-one recovery of theta).

        Exact when theta is of the form ``[q ⊗ a, p ⊗ b]``; otherwise the best rank-one fit of
        each block (:meth:`ThetaLayout.rank_one_recovery`).
        """
        linear = np.asarray(linear, dtype=np.float64)
        n = self.layout.n_params
        return np.r_[self.layout.rank_one_recovery(linear[:n]), linear[n:],
                     np.atleast_1d(np.asarray(nonlinear, dtype=np.float64))]

    def split_nonlinear(self, params):
        """``({free order: value}, (u_past, y_past))`` from a vector of nonlinear parameters."""
        n_free = len(self.orders.free)
        values = dict(zip(self.orders.free, (float(v) for v in params[:n_free])))
        past = (float(params[n_free]), float(params[n_free + 1])) if self.past == "estimate" \
            else (0.0, 0.0)
        return values, past

    def to_dict(self) -> dict:
        """A JSON-ready description (a custom basis by its names: code is never serialised).

        Examples
        --------
        >>> import fohw
        >>> s = fohw.Structure.make(na=1, nb=1, f_basis=2, g_basis=1, offset=True)
        >>> fohw.Structure.from_dict(s.to_dict()) == s
        True
        """
        d = {"orders": self.orders.to_dict(), "f_basis": self.f_basis.to_dict(),
             "g_basis": self.g_basis.to_dict(), "offset": self.offset, "past": self.past,
             "dt": self.dt}
        if self.output_map is not None:          # written only when there is one
            d["output_map"] = self.output_map.to_dict()
        return d

    @classmethod
    def from_dict(cls, d, *, f_basis=None, g_basis=None, output_map=None) -> Structure:
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            As written by :meth:`to_dict`.
        f_basis, g_basis : Basis, optional
            Needed for a custom basis, and checked against ``d`` (:meth:`Basis.from_dict`).
        output_map : SeriesMap, optional
            Needed for a custom output map, and checked against ``d``.

        Raises
        ------
        ParameterError
            A field is missing or invalid (the message names it).
        """
        keys = {"orders", "f_basis", "g_basis", "offset", "past", "dt"}
        if not isinstance(d, dict) or set(d) - {"output_map"} != keys:
            raise ParameterError(f"`structure` must have exactly the fields {sorted(keys)} (and "
                                 f"optionally 'output_map'); got "
                                 f"{sorted(d) if isinstance(d, dict) else d!r}.")
        orders = Orders.from_dict(d["orders"])
        if orders.n_inputs > 1:
            fb = InputBases.from_dict(d["f_basis"], orders.inputs, f_basis, name="f_basis")
        else:
            fb = Basis.from_dict(d["f_basis"], f_basis, name="f_basis")
        return cls(orders, fb,
                   Basis.from_dict(d["g_basis"], g_basis, name="g_basis"),
                   offset=d["offset"], past=d["past"], dt=d["dt"],
                   output_map=None if "output_map" not in d else output_map_from_dict(
                       d["output_map"], output_map))

    def __eq__(self, other):
        return (isinstance(other, Structure) and self.orders == other.orders
                and self.f_basis == other.f_basis and self.g_basis == other.g_basis
                and (self.offset, self.past, self.dt) == (other.offset, other.past, other.dt)
                and self.output_map == other.output_map)

    def __hash__(self):
        return hash((self.orders, self.f_basis, self.g_basis, self.offset, self.past, self.dt,
                     self.output_map))

    def describe(self) -> str:
        """One line: the terms and their orders, offset, past and dt."""
        parts = [repr(self.orders)]
        if self.nk != 1:
            parts.append(f"nk={self.nk}")
        if self.offset:
            parts.append("offset")
        if self.past != "rest":
            parts.append(f"past={self.past!r}")
        if self.dt != 1.0:
            parts.append(f"dt={self.dt:g}")
        if self.output_map is not None:
            parts.append(f"output_map={self.output_map.describe()}")
        return ", ".join(parts)
