"""The fractional-order Hammerstein–Wiener system and its simulator (Section 2.3, Eqs. 10–18).

Also Eqs. 7, 14 (an order per term) and 56–57 (conventions: docs/conventions.md). The paper's model, Eq. (16):

.. math:: y[k] = \\sum_{i=1}^{n_a} a_i (\\Delta^{\\alpha} \\bar g(y))[k-i]
          + \\sum_{i=1}^{n_b} b_i (\\Delta^{\\alpha} \\bar f(u))[k-i] + v[k]

with ``fbar = sum_j p_j f_j``, ``gbar = sum_j q_j g_j``, ``p_1 = q_1 = 1`` and zero
initial conditions, so ``y[0] = v[0]``. The general model (:class:`fohw.Structure`) gives every
term its own lag and order (0 included), adds an offset, past levels and a sampling time, and
acts on deviations from an operating point.
"""

from __future__ import annotations

import numpy as np

from .._validation import (
    check_alpha,
    check_array,
    check_int,
    check_random_state,
    check_same_length,
    check_scalar,
)
from ..exceptions import DimensionError, ParameterError, SimulationDivergedError
from . import _compiled
from ._online import HalfMerge, divide_and_conquer
from .basis import Basis, as_basis, polynomial_basis
from .gl import causal_convolve, gl_weights, gl_weights_unchecked, past_transient
from .orders import Orders
from .structure import Structure

__all__ = ["HammersteinWiener", "simulate", "simulate_theta", "ALPHA_BOUNDS"]

#: Closed interval of fractional orders a model may have (0: the integer-order model).
ALPHA_BOUNDS = (0.0, 2.0)


class HammersteinWiener:
    """A fractional-order Hammerstein–Wiener model (Eq. 16; Eq. 14 with an order per term).

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

    def __init__(self, a, b, p, q, alpha=None, f_basis=None, g_basis=None, *, orders=None,
                 dt=1.0, offset=0.0, past=(0.0, 0.0), operating_point=(0.0, 0.0)):
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
        terms = Orders.infer(orders, a.shape[0], b.shape[0])
        if len(terms.free) == 1 and np.ndim(alpha) == 0 and not isinstance(alpha, dict) \
                and alpha is not None:
            alpha = {terms.free[0]: check_alpha(alpha, lower=ALPHA_BOUNDS[0],
                                                upper=ALPHA_BOUNDS[1], inclusive=True)}
        self.orders = terms.free_mapping(alpha)
        self.offset = check_scalar(offset, "offset")
        self.past = _pair(past, "past")
        self.operating_point = _pair(operating_point, "operating_point")
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
    def from_theta(cls, theta, alpha, *, na, nb, f_basis, g_basis, orders=None, dt=1.0,
                   offset=0.0, past=(0.0, 0.0), operating_point=(0.0, 0.0)):
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
                                   orders=orders, dt=dt)
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

    def _repr_html_(self):
        import html

        return f"<pre>{html.escape(repr(self))}</pre>"

    def to_json(self, path):
        """Write the model to a versioned JSON file (:func:`fohw.save_model`)."""
        from ..io.jsonio import save_model

        save_model(self, path)


def _output_terms(g_basis: Basis, Q: np.ndarray):
    """Return ``y -> [z_1, …, z_R]`` with ``z_r = sum_j Q[j, r] g_j(y)``, for one float.

    The rank-one polynomial case (a model's ``gbar``) is a Horner scheme.
    """
    n_g, R = Q.shape
    cols = [[float(Q[j, r]) for j in range(n_g)] for r in range(R)]
    if g_basis.is_polynomial and R == 1:
        rev = cols[0][::-1]

        def horner(y):
            acc = 0.0
            for c in rev:
                acc = acc * y + c
            return [acc * y]
        return horner
    if g_basis.is_polynomial:
        def powers(y):
            g, p = [], y
            for _ in range(n_g):
                g.append(p)
                p *= y
            return [sum(c * gj for c, gj in zip(col, g)) for col in cols]
        return powers
    funcs = g_basis.functions

    def general(y):
        arr = np.array([y])
        g = [float(np.asarray(f(arr), dtype=np.float64)[0]) for f in funcs]
        return [sum(c * gj for c, gj in zip(col, g)) for col in cols]
    return general


#: Below this record length the simulator runs the recursion directly (one dot product per
#: output signal and sample); above it, by divide and conquer (:func:`_recursion`).
FAST_SIMULATION_THRESHOLD = 8192
#: Leaf sizes of the divide and conquer for the pure-Python and the compiled leaf, chosen by
#: ``benchmarks/bench_simulator.py --leaves`` (64 to 1024 measured at N = 10**5 and 10**6):
#: 256 is the fastest pure leaf; the compiled one is about 10 % faster at 512, but equal sizes
#: make the two leaves give identical numbers, so installing numba (or loading it part-way
#: through a process) changes no simulation.
_LEAF = 256
_LEAF_COMPILED = 256


def _forcing(pb, in_terms, qa, out_terms, f_basis, g_basis, u, v, h, offset, past):
    """Everything in y[k] that does not feed back: noise, offset, input branch, past levels.

    ``in_terms`` and ``out_terms`` are sequences of ``(lag, order)``; ``pb`` is ``(n_f, n_in)``
    and ``qa`` is ``(n_g, n_out)``, the coefficient of basis function ``j`` in term ``t``.
    """
    n = u.shape[0]
    w = v.copy()
    if offset != 0.0:
        w += offset
    F = f_basis.evaluate(u, "u")
    diffs = {}
    for t, (lag, nu) in enumerate(in_terms):
        if nu not in diffs:
            d = F if nu == 0.0 else causal_convolve(F, gl_weights_unchecked(nu, n))
            diffs[nu] = d if h == 1.0 or nu == 0.0 else d * h**-nu
        if lag < n:
            w[lag:] += pb[:, t] @ diffs[nu][:, : n - lag]
    u_past, y_past = past
    if u_past != 0.0 or y_past != 0.0:
        lf = f_basis.evaluate(np.array([u_past]), "u_past")[:, 0]
        lg = g_basis.evaluate(np.array([y_past]), "y_past")[:, 0]
        for coef, levels, terms in ((pb, lf, in_terms), (qa, lg, out_terms)):
            for t, (lag, nu) in enumerate(terms):
                w += (coef[:, t] @ levels) * past_transient(nu, lag, n, h)
    return w


def _recursion(Q, A, out_terms, g_basis, w, threshold, method="auto", h=1.0, y_fixed=None, *,
               kernel="auto", leaf_size=None):
    """``y[k] = w[k] + sum_r sum_t A[r, t] (Delta_h^{nu_t} z_r)[k - lag_t]`` (Eqs. 14, 16).

    ``z_r(y) = sum_j Q[j, r] g_j(y)``: for a model ``Q = q``, ``A = a`` (one signal, gbar);
    for a general theta either ``Q = I, A = qa`` or ``Q = qa, A = I``. ``out_terms[t]`` is the
    ``(lag, order)`` of column ``t`` of ``A``. Every (signal, distinct order) pair has an
    accumulator of ``Delta^nu z_r``; order-0 accumulators have no memory (``z_r`` itself).

    O(N log^2 N) by divide and conquer over time (:mod:`fohw.model._online`): once the first
    half of ``[lo, hi)`` is finished, its contribution to the accumulators on the second half
    is added by FFT (one transform per signal and one inverse per accumulator, the weights'
    spectra computed once per level). Leaves run the recursion sample by sample, one dot
    product per accumulator and sample for the leaf's own past. ``method``: ``"direct"`` is one
    leaf of ``N`` samples (O(N^2)), ``"fast"`` the divide and conquer, ``"auto"`` the latter
    above :data:`FAST_SIMULATION_THRESHOLD` samples. The first ``len(y_fixed)`` outputs are not
    computed but taken from ``y_fixed`` (a measured history).

    ``kernel`` chooses the leaf: ``"auto"`` the compiled leaf (:mod:`fohw.model._compiled`,
    polynomial output bases, numba installed and loaded) or else the pure-Python one;
    ``"pure"``; ``"compiled"`` (an error if it is not available);
    ``"merges"`` a leaf that does nothing, so only the FFT merges run, on the same segments
    (the floor of the divide and conquer, for benchmarks; the output is then meaningless).
    ``leaf_size`` overrides the leaf size of the divide and conquer (:data:`_LEAF` for the pure
    leaf, :data:`_LEAF_COMPILED` for the compiled one).
    """
    n = w.shape[0]
    if method == "auto":
        method = "fast" if n > FAST_SIMULATION_THRESHOLD else "direct"
    compiled = None
    if kernel in ("auto", "compiled"):
        compiled = _compiled.leaf_for(g_basis, n if kernel == "auto" else _compiled.LOAD_AFTER)
        if compiled is None and kernel == "compiled":
            raise RuntimeError("the compiled leaf is not available (numba missing or disabled, "
                               "or a non-polynomial output basis).")
    if method == "direct":
        leaf_size = n
    elif leaf_size is None:
        leaf_size = _LEAF_COMPILED if compiled is not None else _LEAF
    leaf_size = max(1, min(leaf_size, n))

    R = Q.shape[1]
    nus = []
    for _, nu in out_terms:
        if nu not in nus:
            nus.append(nu)
    acc = [(r, nu) for r in range(R) for nu in nus]          # accumulator index -> (signal, nu)
    index = {key: a for a, key in enumerate(acc)}
    terms = [(index[r, nu], lag - 1, float(A[r, t]) * (1.0 if h == 1.0 else h**-nu))
             for r in range(R) for t, (lag, nu) in enumerate(out_terms)]
    mem_nus = [nu for nu in nus if nu != 0.0]
    betas = [gl_weights(nu, n) for nu in mem_nus]
    memory = [(a, r, mem_nus.index(nu)) for a, (r, nu) in enumerate(acc) if nu != 0.0]
    memoryless = [(a, r) for a, (r, nu) in enumerate(acc) if nu == 0.0]
    merge = HalfMerge(betas, memory)
    y = np.zeros(n)
    z = np.zeros((R, n))
    dz = np.zeros((len(acc), n))      # contributions gathered so far
    rev = np.array([betas[k][:leaf_size][::-1] for _, _, k in memory]).reshape(
        len(memory), leaf_size)
    if kernel == "merges":
        def leaf(lo, hi):
            pass
    elif compiled is not None:
        leaf = _compiled_leaf(compiled, Q, terms, memory, memoryless, rev, w, y, z, dz,
                              threshold, y_fixed)
    else:
        leaf = _pure_leaf(_output_terms(g_basis, Q), terms, memory, memoryless, rev, w, y, z,
                          dz, threshold, y_fixed)
        _compiled.count_pure(n)
    with np.errstate(over="ignore", invalid="ignore"):
        divide_and_conquer(n, leaf_size, leaf, lambda lo, mid, hi: merge(z, dz, lo, mid, hi))
    return y


def _pure_leaf(zfun, terms, memory, memoryless, rev, w, y, z, dz, threshold, y_fixed):
    """The leaf of :func:`_recursion` in Python: ``leaf(lo, hi)`` finishes samples lo..hi-1."""
    import math

    R = z.shape[0]
    L = rev.shape[1]
    w = w.tolist()
    n_fixed = 0 if y_fixed is None else y_fixed.shape[0]
    fixed = [] if y_fixed is None else y_fixed.tolist()
    dz_item = dz.item
    isfinite = math.isfinite
    zrows = list(z)                   # 1-D views, one per output signal
    dzrows = list(dz)
    dot = np.dot
    signals = range(R)
    leaf_memory = [(dzrows[a], r, rev[j]) for j, (a, r, _) in enumerate(memory)]
    leaf_memoryless = [(dzrows[a], r) for a, r in memoryless]

    def leaf(lo, hi):
        for k in range(lo, hi):
            if k < n_fixed:
                yk = fixed[k]
            else:
                yk = w[k]
                for a, i, c in terms:
                    if i < k:
                        yk += c * dz_item(a, k - 1 - i)
                if not abs(yk) <= threshold:       # also catches nan
                    raise SimulationDivergedError(k, yk, threshold)
            zk = zfun(yk)
            for x in zk:
                if not isfinite(x):
                    raise SimulationDivergedError(k, yk, threshold, "output_basis")
            y[k] = yk
            for r in signals:
                zrows[r][k] = zk[r]
            for row, r, b_rev in leaf_memory:
                row[k] += dot(zrows[r][lo:k + 1], b_rev[L - (k - lo + 1):])
            for row, r in leaf_memoryless:
                row[k] = zk[r]
    return leaf


def _compiled_leaf(kernel, Q, terms, memory, memoryless, rev, w, y, z, dz, threshold, y_fixed):
    """The leaf of :func:`_recursion` by the compiled ``kernel`` (:mod:`fohw.model._compiled`)."""
    intp = np.intp
    args = (w, y, z, dz,
            np.array([a for a, _, _ in terms], dtype=intp),
            np.array([i for _, i, _ in terms], dtype=intp),
            np.array([c for _, _, c in terms], dtype=np.float64),
            np.array([a for a, _, _ in memory], dtype=intp),
            np.array([r for _, r, _ in memory], dtype=intp),
            np.ascontiguousarray(rev),
            np.array([a for a, _ in memoryless], dtype=intp),
            np.array([r for _, r in memoryless], dtype=intp),
            np.array(Q, dtype=np.float64, order="C"), Q.shape[1] == 1,    # writable copies:
            np.zeros(0) if y_fixed is None else np.array(y_fixed, dtype=np.float64),  # one type
            float(threshold), np.zeros(Q.shape[0]))

    def leaf(lo, hi):
        status, k, yk = kernel(lo, hi, *args)
        if status == _compiled.GROWTH:
            raise SimulationDivergedError(k, yk, threshold)
        if status == _compiled.OUTPUT_BASIS:
            raise SimulationDivergedError(k, yk, threshold, "output_basis")
    return leaf


def _simulate_blocks(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold, method="auto"):
    """The paper's commensurate model in block form (``auto``/``direct``/``fast``)."""
    out_terms = [(i, alpha) for i in range(1, A.shape[1] + 1)]
    in_terms = [(i, alpha) for i in range(1, pb.shape[1] + 1)]
    w = _forcing(pb, in_terms, None, out_terms, f_basis, g_basis, u, v, 1.0, 0.0, (0.0, 0.0))
    return _recursion(Q, A, out_terms, g_basis, w, threshold, method)


def _output_representation(qa):
    """``(Q, A)`` with the fewer output signals: ``z_j = g_j(y)`` or one signal per term."""
    if qa.shape[0] <= qa.shape[1]:      # fewer g-signals than terms: z_j = g_j(y)
        return np.eye(qa.shape[0]), qa
    return qa, np.eye(qa.shape[1])     # fewer terms: z_t = sum_j qa[j, t] g_j(y)


def _default_threshold(w, y_fixed):
    """1e8 times the largest magnitude that drives the recursion.

    The drive is the input branch, noise, offset, past levels and history: an output beyond
    1e8 times it has been amplified by the feedback and is escaping, in any units.
    """
    drive = float(np.max(np.abs(w))) if w.size else 0.0
    if y_fixed is not None and y_fixed.size:
        drive = max(drive, float(np.max(np.abs(y_fixed))))
    return 1e8 * max(drive, np.finfo(float).tiny)


def _noise(n, noise, noise_std, random_state):
    noise_std = check_scalar(noise_std, "noise_std", lower=0.0)
    if noise is not None:
        if noise_std > 0:
            raise ParameterError("pass either `noise` or `noise_std` > 0, not both.")
        v = check_array(noise, "noise")
        if v.shape[0] != n:
            raise DimensionError(f"`noise` and `u` must have the same length; got {v.shape[0]} "
                                 f"and {n}.")
        return v
    if noise_std > 0:
        return noise_std * check_random_state(random_state).standard_normal(n)
    return np.zeros(n)


def _run(structure, Q, A, qa, pb, order_values, u, v, *, offset, past, operating_point,
         threshold, history, method="auto", kernel="auto", leaf_size=None):
    """Simulate any structure from its coefficient blocks (deviation coordinates inside)."""
    u0, y0 = operating_point
    out_nu, in_nu = structure.orders.values(order_values, check=False)
    out_terms = [(term.lag, nu) for term, nu in zip(structure.orders.output, out_nu)]
    in_terms = [(term.lag, nu) for term, nu in zip(structure.orders.input, in_nu)]
    n_hist, y_fixed = 0, None
    if history is not None:
        u_hist, y_hist = _check_history(history)
        n_hist = u_hist.shape[0]
        u = np.r_[u_hist, u]
        v = np.r_[np.zeros(n_hist), v]
        y_fixed = y_hist - y0 if y0 != 0.0 else y_hist
    if u0 != 0.0:
        u = u - u0
    w = _forcing(pb, in_terms, qa, out_terms, structure.f_basis, structure.g_basis, u, v,
                 structure.dt, offset, past)
    if threshold is None:
        threshold = _default_threshold(w, y_fixed)
    try:
        y = _recursion(Q, A, out_terms, structure.g_basis, w, threshold, method,
                       structure.dt, y_fixed, kernel=kernel, leaf_size=leaf_size)
    except SimulationDivergedError as err:
        raise SimulationDivergedError(err.sample - n_hist, err.value + y0, err.threshold,
                                      err.cause) \
            from None
    y = y[n_hist:]
    return y + y0 if y0 != 0.0 else y


def _check_history(history):
    try:
        u_hist, y_hist = history
    except (TypeError, ValueError):
        raise ParameterError("`history` must be a pair (u_past, y_past) of measured records; "
                             f"got {type(history).__name__}.") from None
    u_hist = check_array(u_hist, "history u")
    y_hist = check_array(y_hist, "history y")
    check_same_length(u_hist, y_hist, "history u", "history y")
    return u_hist, y_hist


def _threshold(divergence_threshold):
    if divergence_threshold is None:
        return None
    return check_scalar(divergence_threshold, "divergence_threshold", lower=0.0,
                        lower_inclusive=False)


def simulate(model, u, *, noise=None, noise_std=0.0, random_state=None,
             divergence_threshold=None, history=None):
    """Simulate the output of a fractional-order Hammerstein–Wiener model.

    Parameters
    ----------
    model : HammersteinWiener
        The system.
    u : array_like, shape (N,)
        Input signal, finite, in the model's units (its operating point is subtracted inside
        and the output's added back).
    noise : array_like, shape (N,), optional
        The equation noise ``v[k]`` added at every sample. Mutually exclusive with
        ``noise_std > 0``.
    noise_std : float, optional
        Standard deviation of white Gaussian ``v[k]`` drawn from ``random_state``. Default 0.
    random_state : None, int or numpy.random.Generator, optional
        Source of the noise when ``noise_std > 0``.
    divergence_threshold : float, optional
        The output is declared divergent when ``|y[k]|`` (deviation from the operating point)
        exceeds this or is not finite. Default: ``1e8`` times the largest magnitude that drives
        the recursion (input branch, noise, offset, past levels, history), so the test means the
        same in every unit.
    history : (u_past, y_past), optional
        Measured input and output just before ``u`` (same units): the simulation continues
        from them, its GL memory holding that history, in free run from the first sample of
        ``u``. The model's past levels (if any) apply before the history.

    Returns
    -------
    y : ndarray, shape (N,)
        The output. To keep the noise realisation, draw it yourself and pass ``noise``.

    Raises
    ------
    SimulationDivergedError
        The output escaped; ``err.sample`` is the first offending index of ``u``.

    Notes
    -----
    The exact recursion of Eq. (16) (Eq. 14 for a general :class:`fohw.Orders`) with
    full memory: ``y[k]`` uses ``(Delta^nu gbar(y))[k-i]`` for every output term, each the GL
    sum over all of ``gbar(y[0..k-i])``. The input branch is computed once by FFT. Up to
    ``N = 8192`` the output memory is one dot product per sample (``O(N**2)``); above,
    finished halves of the record enter later samples through FFT convolutions
    (``O(N log^2 N)``), equal to the direct recursion to rounding: 0.38 s at ``N = 10**5`` and
    3.9 s at ``10**6`` with the per-sample loop in Python, 0.078 s and 0.88 s when the optional
    ``fast`` extra (numba) compiles it for a polynomial output basis (identical numbers; loaded
    once per process, for simulations of at least ``2**18`` samples or once that many have
    run; docs/performance.md, measured on an idle 2-core machine).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> model = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
    >>> u = np.array([1.0, 0.0, 0.0, 0.0])
    >>> fohw.simulate(model, u).round(4)
    array([ 0.    , -0.6   ,  0.0176,  0.1945])
    """
    if not isinstance(model, HammersteinWiener):
        raise ParameterError(f"`model` must be a HammersteinWiener; got {type(model).__name__}.")
    u = check_array(u, "u")
    v = _noise(u.shape[0], noise, noise_std, random_state)
    return _run(model.structure, model.q[:, None], model.a[None, :], np.outer(model.q, model.a),
                np.outer(model.p, model.b), model.orders, u, v, offset=model.offset,
                past=model.past, operating_point=model.operating_point,
                threshold=_threshold(divergence_threshold), history=history)


def simulate_theta(theta, alpha, u, *, na, nb, f_basis, g_basis, orders=None, dt=1.0,
                   offset=0.0, past=(0.0, 0.0), operating_point=(0.0, 0.0), noise=None,
                   noise_std=0.0, random_state=None, divergence_threshold=None, history=None):
    """Simulate ``y = Phi(alpha) theta + v`` for any theta (not only ``q ⊗ a, p ⊗ b``).

    The same recursion as :func:`simulate`, with each entry of theta its own coefficient: the
    free-run behaviour of exactly the predictor that an estimator fitted, before the rank-one
    projection of Eqs. (39)–(40).

    Parameters
    ----------
    theta : array_like, shape (n,)
        Parameters in the layout of :class:`fohw.ThetaLayout`.
    alpha : float, sequence or dict
        The fractional order, or the free orders of ``orders``.
    u : array_like, shape (N,)
        Input.
    na, nb, f_basis, g_basis, orders, dt
        Model structure (as in :func:`fohw.identify`).
    offset, past, operating_point
        The constant, the past levels ``(u_past, y_past)`` and ``(u0, y0)``.
    noise, noise_std, random_state, divergence_threshold, history
        As in :func:`simulate`.

    Returns
    -------
    y : ndarray, shape (N,)

    Examples
    --------
    >>> import numpy as np, fohw
    >>> m = fohw.datasets.paper_model()
    >>> u = np.random.default_rng(0).uniform(-1, 1, 300)
    >>> y1 = fohw.simulate(m, u)
    >>> y2 = fohw.simulate_theta(m.theta, 0.6, u, na=2, nb=2, f_basis=2, g_basis=3)
    >>> bool(np.max(np.abs(y1 - y2)) < 1e-13)
    True
    """
    na = check_int(na, "na", minimum=1)
    nb = check_int(nb, "nb", minimum=1)
    structure = Structure.make(na=na, nb=nb, f_basis=f_basis, g_basis=g_basis, orders=orders,
                               dt=dt)
    qa, pb = structure.layout.blocks(theta)
    if not structure.orders.free:
        values = {}
    elif np.ndim(alpha) == 0 and not isinstance(alpha, dict) and len(structure.orders.free) == 1:
        # Any finite order here (a negative one is a fractional sum), as gl_difference allows.
        values = {structure.orders.free[0]: check_scalar(alpha, "alpha")}
    else:
        values = structure.orders.free_mapping(alpha)
    u = check_array(u, "u")
    v = _noise(u.shape[0], noise, noise_std, random_state)
    Q, A = _output_representation(qa)
    return _run(structure, Q, A, qa, pb, values, u, v, offset=check_scalar(offset, "offset"),
                past=_pair(past, "past"), operating_point=_pair(operating_point,
                                                                "operating_point"),
                threshold=_threshold(divergence_threshold), history=history)


def _pair(value, name):
    try:
        a, b = value
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be a pair of numbers; got {value!r}.") from None
    return check_scalar(a, f"{name}[0]"), check_scalar(b, f"{name}[1]")


def simulate_parameters(structure, linear, params, u, *, operating_point=(0.0, 0.0), noise=None,
                        divergence_threshold=None, history=None):
    """Free run of the predictor an estimator fitted: any structure, unstructured theta.

    Parameters
    ----------
    structure : Structure
    linear : ndarray
        ``[theta, offset]`` (:attr:`Structure.linear_names`).
    params : ndarray
        The nonlinear parameters (:attr:`Structure.nonlinear_names`).
    u : ndarray
        Input in the data's units.
    operating_point, noise, divergence_threshold, history
        As in :func:`simulate`.

    Returns
    -------
    y : ndarray
    """
    if not isinstance(structure, Structure):
        raise ParameterError(f"`structure` must be a fohw.Structure; got "
                             f"{type(structure).__name__}.")
    linear = check_array(linear, "linear")
    params = np.atleast_1d(check_array(params, "params", ndim=None, min_length=0))
    for value, names, name in ((linear, structure.linear_names, "linear"),
                               (params, structure.nonlinear_names, "params")):
        if value.shape[0] != len(names):
            raise DimensionError(f"`{name}` must have {len(names)} entries {names}; got "
                                 f"{value.shape[0]}.")
    layout = structure.layout
    qa, pb = layout.blocks(linear[:layout.n_params])
    offset = float(linear[layout.n_params]) if structure.offset else 0.0
    values, past = structure.split_nonlinear(params)
    u = check_array(u, "u")
    v = np.zeros(u.shape[0]) if noise is None else check_array(noise, "noise")
    check_same_length(u, v, "u", "noise")
    Q, A = _output_representation(qa)
    return _run(structure, Q, A, qa, pb, values, u, v, offset=offset, past=past,
                operating_point=operating_point, threshold=_threshold(divergence_threshold),
                history=history)
