"""A Hammerstein–Wiener model around a fractional transfer function: ``u -> f -> G(s) -> h -> y``.

The model as the fractional-order literature writes it (e.g. FOMCON-style ``fotf`` blocks between
static maps):

.. math:: w[k] = \\bar f(u[k]) = \\sum_j p_j f_j(u[k]), \\quad x = G(s)\\,w, \\quad y[k] = h(x[k]),

- ``f``: a :class:`fohw.Basis` with coefficients ``p``, **normalised by** ``p_1 = 1`` (the gain
  lives in ``G``, whose lowest-order denominator coefficient is the fit's normaliser, as in
  :attr:`fohw.FractionalTF.parameters`);
- ``G``: a :class:`fohw.FractionalTF`, simulated by its GL discretisation with the current
  sample on both sides (implicit; sample alignment of :mod:`fohw.model.fotf`);
- ``h``: a static output map in **series** (:class:`OutputMap`): the identity, a polynomial
  ``h(x) = x + r_2 x^2 + ... + r_d x^d`` (``r_1 = 1``: its scale is ``G``'s), or a saturation
  ``h(x) = min(max(x, lower), upper)``.

This is *not* the paper's lagged model (Eq. 16), whose output map acts inside the recursion on
lags ``>= 1``; ``docs/transfer_functions.md`` says where the two classes coincide and where they
differ.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import DimensionError, ParameterError
from .basis import Basis, as_basis
from .fotf import FractionalTF

__all__ = ["OutputMap", "FractionalHW", "OUTPUT_MAP_KINDS"]

OUTPUT_MAP_KINDS = ("identity", "polynomial", "saturation")


class OutputMap:
    """A static output map ``h`` in series after the linear block.

    Parameters
    ----------
    kind : {"identity", "polynomial", "saturation"}
    params : array_like, optional
        ``"polynomial"``: ``[r_2, …, r_d]`` (``r_1 = 1`` is implied); ``"saturation"``:
        ``[lower, upper]`` with ``lower < upper``; ``"identity"``: none.

    Attributes
    ----------
    names : tuple of str
        ``("r2", …)`` or ``("lower", "upper")``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.fotf_hw import OutputMap
    >>> h = OutputMap("polynomial", [0.5])          # x + 0.5 x^2
    >>> h(np.array([2.0])), h.derivative(np.array([2.0]))
    (array([4.]), array([3.]))
    >>> OutputMap("saturation", [-1.0, 1.0])(np.array([-3.0, 0.2, 3.0]))
    array([-1. ,  0.2,  1. ])
    """

    def __init__(self, kind="identity", params=()):
        if kind not in OUTPUT_MAP_KINDS:
            raise ParameterError(f"`output_map` kind must be one of {OUTPUT_MAP_KINDS}; got {kind!r}.")
        try:
            params = np.atleast_1d(np.asarray(params, dtype=np.float64)).ravel()
        except (TypeError, ValueError):
            raise ParameterError(f"`output_map` parameters must be real numbers; got {params!r}.") from None
        if not np.all(np.isfinite(params)):
            raise ParameterError(f"`output_map` parameters must be finite; got {params.tolist()}.")
        if kind == "identity" and params.size:
            raise DimensionError(f"the identity output map has no parameters; got {params.tolist()}.")
        if kind == "polynomial" and params.size == 0:
            raise DimensionError("a polynomial output map needs [r_2, ..., r_d] (r_1 = 1 is implied); "
                                 "got none (use 'identity' for h(x) = x).")
        if kind == "saturation":
            if params.size != 2:
                raise DimensionError(f"a saturation needs [lower, upper]; got {params.tolist()}.")
            if not params[0] < params[1]:
                raise ParameterError(f"a saturation needs lower < upper; got {params.tolist()}.")
        self.kind = kind
        self.params = params
        self.params.setflags(write=False)
        if kind == "polynomial":
            self.names = tuple(f"r{k}" for k in range(2, params.size + 2))
        elif kind == "saturation":
            self.names = ("lower", "upper")
        else:
            self.names = ()

    @classmethod
    def make(cls, spec):
        """An :class:`OutputMap` from a name, a degree or a ``(kind, params)`` pair.

        An int ``d >= 2`` means a polynomial of degree ``d`` with zero higher coefficients.
        """
        if isinstance(spec, OutputMap):
            return spec
        if spec is None or spec == "identity":
            return cls("identity")
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            if spec < 1:
                raise ParameterError(f"`output_map` as a polynomial degree must be >= 1; got {spec}.")
            return cls("identity") if spec == 1 else cls("polynomial", np.zeros(int(spec) - 1))
        if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[0], str):
            return cls(spec[0], spec[1])
        raise ParameterError(f"`output_map` must be 'identity', a degree, ('polynomial', [r2, ...]) or "
                             f"('saturation', [lower, upper]); got {spec!r}.")

    def with_params(self, params):
        """The same kind of map with other parameters."""
        return OutputMap(self.kind, params)

    def __call__(self, x):
        """``h(x)``."""
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "identity":
            return x.copy()
        if self.kind == "saturation":
            return np.clip(x, self.params[0], self.params[1])
        out = x.copy()
        xk = x.copy()
        for r in self.params:
            xk = xk * x
            out += r * xk
        return out

    def derivative(self, x):
        """``h'(x)`` (the saturation: 1 strictly inside the limits, 0 outside)."""
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "identity":
            return np.ones_like(x)
        if self.kind == "saturation":
            return ((x > self.params[0]) & (x < self.params[1])).astype(np.float64)
        out = np.ones_like(x)
        xk = np.ones_like(x)
        for k, r in enumerate(self.params, start=2):
            xk = xk * x
            out += k * r * xk
        return out

    def parameter_jacobian(self, x):
        """``d h(x) / d params``, shape ``(len(x), len(params))``."""
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "identity":
            return np.zeros((x.size, 0))
        if self.kind == "saturation":
            return np.column_stack([(x < self.params[0]).astype(float), (x > self.params[1]).astype(float)])
        return np.column_stack([x ** k for k in range(2, self.params.size + 2)])

    def __repr__(self):
        return f"OutputMap({self.kind!r}, {self.params.tolist()!r})" if self.params.size \
            else f"OutputMap({self.kind!r})"

    def __str__(self):
        if self.kind == "identity":
            return "h(x) = x"
        if self.kind == "saturation":
            return f"h(x) = min(max(x, {self.params[0]:g}), {self.params[1]:g})"
        terms = " + ".join(f"{r:g} x^{k}" for k, r in enumerate(self.params, start=2))
        return ("h(x) = x + " + terms).replace("+ -", "- ")


class FractionalHW:
    """``u -> fbar -> G(s) -> h -> y``: a Hammerstein–Wiener model around a fractional transfer function.

    Parameters
    ----------
    G : FractionalTF
        The linear block (its ``dt`` is the default sampling time, its ``delay`` the input delay).
    p : array_like, optional
        Coefficients of the input basis, ``p[0] == 1`` (normalisation). Default ``[1]``.
    f_basis : Basis, int or callables, optional
        Input basis (default the polynomial basis of degree ``len(p)``: ``u, u^2, …``).
    output_map : OutputMap, str, int or tuple, optional
        ``h`` (see :meth:`OutputMap.make`); default the identity.

    Notes
    -----
    :meth:`simulate` computes ``w = fbar(u)`` at every sample, ``x = G.simulate(w)`` (the implicit
    GL recursion ``sum_j c_j x[k-j] = sum_j d_j w[k-j-n_delay]``, solved in ``O(N log^2 N)``) and
    ``y = h(x)``; the tests compare every sample with the literal per-sample loop.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])           # 1 / (s + 1)
    >>> m = fohw.FractionalHW(G, p=[1.0, 0.5], output_map=("saturation", [-1.0, 1.0]))
    >>> print(m)
    u -> 1·x + 0.5·x^2 -> 1 / (s + 1) -> h(x) = min(max(x, -1), 1)
    >>> m.simulate([1.0, 1.0, 1.0], dt=1.0)          # w = 1.5; x = 0.75, 1.125, 1.3125
    array([0.75, 1.  , 1.  ])
    """

    def __init__(self, G, *, p=(1.0,), f_basis=None, output_map=None):
        if not isinstance(G, FractionalTF):
            raise ParameterError(f"`G` must be a FractionalTF; got {type(G).__name__}.")
        try:
            p = np.atleast_1d(np.asarray(p, dtype=np.float64)).ravel()
        except (TypeError, ValueError):
            raise ParameterError(f"`p` must be a sequence of real numbers; got {p!r}.") from None
        if p.size == 0 or not np.all(np.isfinite(p)):
            raise ParameterError(f"`p` must be a non-empty sequence of finite numbers; got {p.tolist()}.")
        if p[0] != 1.0:
            raise ParameterError(f"`p[0]` must be exactly 1 (the gain is G's); got {p[0]!r}.")
        basis = as_basis(p.size if f_basis is None else f_basis, "f_basis")
        if len(basis) != p.size:
            raise DimensionError(f"`p` must have one entry per f-basis function ({len(basis)}); "
                                 f"got {p.size}.")
        self.G = G
        self.p = p
        self.p.setflags(write=False)
        self.f_basis: Basis = basis
        self.output_map = OutputMap.make(output_map)

    @property
    def dt(self):
        """The linear block's default sampling time."""
        return self.G.dt

    def __str__(self):
        f = " + ".join(f"{c:g}·{n}" for c, n in zip(self.p, self.f_basis.names)).replace("+ -", "- ")
        return f"u -> {f} -> {self.G} -> {self.output_map}"

    def __repr__(self):
        return (f"FractionalHW({self.G!r}, p={self.p.tolist()!r}, f_basis={self.f_basis!r}, "
                f"output_map={self.output_map!r})")

    def _repr_html_(self):
        from .._repr import html_table

        rows = [(f"p{j}", n, v) for j, (n, v) in enumerate(zip(self.f_basis.names, self.p), 1)]
        return html_table("FractionalHW", ["parameter", "basis", "value"], rows,
                          lines=[str(self), f"G(s) = {self.G}", str(self.output_map)])

    def input_signal(self, u):
        """``w = fbar(u) = sum_j p_j f_j(u)``."""
        return self.p @ self.f_basis.evaluate(np.asarray(u, dtype=np.float64), "u")

    def simulate(self, u, dt=None, *, states=False, divergence_threshold=None):
        """Output for the input ``u`` (zero initial conditions of ``G``).

        Parameters
        ----------
        u : array_like, shape (N,)
            Input samples (alignment of :class:`fohw.FractionalTF`).
        dt : float, optional
            Sampling time (default ``G.dt``).
        states : bool, optional
            Also return ``w = fbar(u)`` and ``x = G w``.
        divergence_threshold : float, optional
            The bound on ``|x|`` of :meth:`fohw.FractionalTF.simulate` (default: ``1e8`` times
            the output scale of a bounded response; ``np.inf``: no bound).

        Returns
        -------
        y : ndarray, shape (N,)
            Or ``(w, x, y)`` with ``states=True``.
        """
        w = self.input_signal(u)
        x = self.G.simulate(w, dt, divergence_threshold=divergence_threshold)
        y = self.output_map(x)
        return (w, x, y) if states else y

    def frequency_response(self, omega):
        """The linear block's exact ``G(j omega)`` (the maps are static: see :meth:`linearised_gain`)."""
        return self.G.frequency_response(omega)

    def linearised_gain(self):
        """``f'(0) h'(0)``: the slope of the static maps at 0, multiplying ``G`` for small signals."""
        if self.f_basis.is_polynomial:
            fs = float(self.p[0])
        else:
            step = 1e-6
            v = self.input_signal(np.array([-step, step]))
            fs = float((v[1] - v[0]) / (2 * step))
        return fs * float(self.output_map.derivative(np.array([0.0]))[0])
