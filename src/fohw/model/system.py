"""The fractional-order Hammerstein–Wiener system and its simulator (Section 2.3, Eqs. 10–18).

Also Eqs. 56–57 and SPEC §3.

.. math:: y[k] = \\sum_{i=1}^{n_a} a_i (\\Delta^{\\alpha} \\bar g(y))[k-i]
          + \\sum_{i=1}^{n_b} b_i (\\Delta^{\\alpha} \\bar f(u))[k-i] + v[k]

with ``fbar = sum_j p_j f_j``, ``gbar = sum_j q_j g_j``, ``p_1 = q_1 = 1`` and zero
initial conditions, so ``y[0] = v[0]``.
"""

from __future__ import annotations

import numpy as np

from .._validation import check_alpha, check_array, check_random_state, check_scalar
from ..exceptions import DimensionError, ParameterError, SimulationDivergedError
from .basis import Basis, as_basis, polynomial_basis
from .gl import causal_convolve, gl_difference, gl_weights
from .params import ThetaLayout

__all__ = ["HammersteinWiener", "simulate", "simulate_theta", "ALPHA_BOUNDS"]

#: Closed interval of fractional orders a model may have (0: the integer-order model).
ALPHA_BOUNDS = (0.0, 2.0)


class HammersteinWiener:
    """A fractional-order Hammerstein–Wiener model (Eq. 16).

    Parameters
    ----------
    a : array_like, shape (na,)
        Coefficients of the output (``g``) branch, ``na >= 1``.
    b : array_like, shape (nb,)
        Coefficients of the input (``f``) branch, ``nb >= 1``.
    p : array_like, shape (n_f,)
        Weights of the input basis functions; ``p[0]`` must be exactly 1 (Eq. 17).
    q : array_like, shape (n_g,)
        Weights of the output basis functions; ``q[0]`` must be exactly 1 (Eq. 17).
    alpha : float
        Fractional order, in ``[0, 2]`` (0 gives the integer-order model).
    f_basis, g_basis : Basis, int, callables or None, optional
        Input and output basis functions; ``None`` means the polynomial basis of degree
        ``len(p)`` (``len(q)``): ``u, u**2, …``.

    Attributes
    ----------
    theta : ndarray
        ``[q ⊗ a, p ⊗ b]`` (Eq. 20).
    layout : ThetaLayout
        Maps theta to named blocks.

    Examples
    --------
    >>> import fohw
    >>> model = fohw.HammersteinWiener(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1, 0.5],
    ...                                q=[1, 0.7, 0.35], alpha=0.6)
    >>> model.parameter_names[:3], model.theta[:3].round(3)
    (('a1', 'a2', 'q2a1'), array([0.1 , 0.2 , 0.07]))
    """

    def __init__(self, a, b, p, q, alpha, f_basis=None, g_basis=None):
        a = check_array(a, "a")
        b = check_array(b, "b")
        p = check_array(p, "p")
        q = check_array(q, "q")
        if p[0] != 1.0:
            raise ParameterError(f"`p[0]` must be exactly 1 (normalisation of Eq. 17); got {p[0]!r}.")
        if q[0] != 1.0:
            raise ParameterError(f"`q[0]` must be exactly 1 (normalisation of Eq. 17); got {q[0]!r}.")
        self.alpha = check_alpha(alpha, lower=ALPHA_BOUNDS[0], upper=ALPHA_BOUNDS[1],
                                 inclusive=True)
        self.f_basis = polynomial_basis(p.shape[0]) if f_basis is None else as_basis(f_basis, "f_basis")
        self.g_basis = polynomial_basis(q.shape[0]) if g_basis is None else as_basis(g_basis, "g_basis")
        if len(self.f_basis) != p.shape[0]:
            raise DimensionError(f"`p` must have one entry per f-basis function ({len(self.f_basis)});"
                                 f" got {p.shape[0]}.")
        if len(self.g_basis) != q.shape[0]:
            raise DimensionError(f"`q` must have one entry per g-basis function ({len(self.g_basis)});"
                                 f" got {q.shape[0]}.")
        self.layout = ThetaLayout(na=a.shape[0], nb=b.shape[0], n_g=q.shape[0], n_f=p.shape[0])
        for name, v in (("a", a), ("b", b), ("p", p), ("q", q)):
            v.setflags(write=False)
            setattr(self, name, v)

    @property
    def na(self) -> int:
        """Number of output lags."""
        return self.layout.na

    @property
    def nb(self) -> int:
        """Number of input lags."""
        return self.layout.nb

    @property
    def theta(self) -> np.ndarray:
        """Parameter vector ``[q ⊗ a, p ⊗ b]`` (Eq. 20)."""
        return self.layout.to_theta(self.a, self.b, self.p, self.q)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :attr:`theta` (``a1``, ``q2a1``, ``b1``, ``p2b1``, …)."""
        return self.layout.names

    @classmethod
    def from_theta(cls, theta, alpha, *, na, nb, f_basis, g_basis):
        """Build a model from a parameter vector by Eqs. (39)–(40).

        Parameters
        ----------
        theta : array_like, shape (n,)
            ``[q ⊗ a, p ⊗ b]``.
        alpha : float
            Fractional order.
        na, nb : int
            Output and input lag orders.
        f_basis, g_basis : Basis, int or callables
            Input and output basis functions.

        Returns
        -------
        HammersteinWiener

        Notes
        -----
        ``a`` and ``b`` are the first ``na`` and the ``(na n_g + 1)``-th to ``(na n_g + nb)``-th
        entries; ``q_j``, ``p_j`` are averaged ratios (Eqs. 39–40). For a theta that is not an
        exact Kronecker product (any estimate), the model's :attr:`theta` differs from the
        input theta.

        Examples
        --------
        >>> import fohw
        >>> m = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
        >>> m2 = fohw.HammersteinWiener.from_theta(m.theta, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
        >>> m2.q.round(12)
        array([1.  , 0.7 , 0.35])
        """
        f_basis = as_basis(f_basis, "f_basis")
        g_basis = as_basis(g_basis, "g_basis")
        layout = ThetaLayout(na=na, nb=nb, n_g=len(g_basis), n_f=len(f_basis))
        a, b, p, q = layout.recover(theta)
        return cls(a, b, p, q, alpha, f_basis=f_basis, g_basis=g_basis)

    def __repr__(self):
        def fmt(v):
            return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
        return (f"HammersteinWiener(a={fmt(self.a)}, b={fmt(self.b)}, p={fmt(self.p)}, "
                f"q={fmt(self.q)}, alpha={self.alpha:.6g}, f_basis={self.f_basis!r}, "
                f"g_basis={self.g_basis!r})")

    def __eq__(self, other):
        return (isinstance(other, HammersteinWiener) and self.alpha == other.alpha
                and self.f_basis == other.f_basis and self.g_basis == other.g_basis
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
#: output signal and sample); above it, by divide and conquer (:func:`_simulate_recursion`).
FAST_SIMULATION_THRESHOLD = 8192
_LEAF = 128


def _prepare(Q, A, pb, alpha, f_basis, g_basis, u, v):
    n = u.shape[0]
    nb = pb.shape[1]
    df = gl_difference(f_basis.evaluate(u, "u"), alpha)          # (n_f, N)
    w = v.copy()
    for i in range(nb):
        w[i + 1:] += pb[:, i] @ df[:, : n - i - 1]
    # (r, i, coefficient) for every output term A[r, i] (Δ^α z_r)[k-1-i]
    terms = [(r, i, float(A[r, i])) for r in range(A.shape[0]) for i in range(A.shape[1])]
    return w, gl_weights(alpha, n), _output_terms(g_basis, Q), terms


def _simulate_recursion(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold, leaf_size):
    """The recursion of Eq. (16); O(N log^2 N) by divide and conquer over time.

    The output terms are written as ``sum_r sum_i A[r, i] (Δ^α z_r(y))[k-1-i]`` with
    ``z_r(y) = sum_j Q[j, r] g_j(y)``: for a model ``Q = q``, ``A = a`` (one signal, gbar);
    for a general theta either ``Q = I, A = qa`` or ``Q = qa, A = I``.

    ``solve(l, r)`` first finishes ``[l, mid)``, then adds the contribution of
    ``z[:, l:mid]`` to the differences at ``[mid, r)`` with one FFT convolution, then
    finishes ``[mid, r)``. On entry to ``solve(l, r)`` the differences at ``[l, r)`` already
    hold every contribution from samples before ``l``. Leaves of at most ``leaf_size`` samples
    run the recursion directly, one dot product per output signal and sample; with
    ``leaf_size >= N`` that is the whole (direct, O(N^2)) simulation.
    """
    import math

    n = u.shape[0]
    R = Q.shape[1]
    w, beta, zfun, terms = _prepare(Q, A, pb, alpha, f_basis, g_basis, u, v)
    w = w.tolist()
    leaf_size = min(leaf_size, n)
    beta_rev_leaf = beta[:leaf_size][::-1].copy()
    y = [0.0] * n
    z = np.zeros((R, n))
    dz = np.zeros((R, n))       # contributions gathered so far
    dz_item = dz.item
    isfinite = math.isfinite
    zrows = list(z)             # 1-D views, one per output signal
    dzrows = list(dz)
    dot = np.dot
    signals = range(R)

    def leaf(lo, hi):
        for k in range(lo, hi):
            yk = w[k]
            for r, i, c in terms:
                if i < k:
                    yk += c * dz_item(r, k - 1 - i)
            if not abs(yk) <= threshold:       # also catches nan
                raise SimulationDivergedError(k, yk, threshold)
            zk = zfun(yk)
            if not all(isfinite(x) for x in zk):
                raise SimulationDivergedError(k, yk, threshold)
            y[k] = yk
            b = beta_rev_leaf[leaf_size - (k - lo + 1):]
            for r in signals:
                zr = zrows[r]
                zr[k] = zk[r]
                dzrows[r][k] += dot(zr[lo:k + 1], b)

    def solve(lo, hi):
        if hi - lo <= leaf_size:
            leaf(lo, hi)
            return
        mid = (lo + hi) // 2
        solve(lo, mid)
        # dz[t] += sum_{m in [lo, mid)} beta[t - m] z[m] for t in [mid, hi); z[mid:hi] is
        # still zero, so this is the causal convolution of z[lo:hi].
        dz[:, mid:hi] += causal_convolve(z[:, lo:hi], beta[:hi - lo])[:, mid - lo:]
        solve(mid, hi)

    with np.errstate(over="ignore", invalid="ignore"):
        solve(0, n)
    return np.array(y)


def _simulate_blocks(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold, method="auto"):
    """Run the recursion directly (one leaf) or by divide and conquer (``auto``/``direct``/``fast``)."""
    if method == "auto":
        method = "fast" if u.shape[0] > FAST_SIMULATION_THRESHOLD else "direct"
    leaf_size = _LEAF if method == "fast" else u.shape[0]
    return _simulate_recursion(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold, leaf_size)


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


def simulate(model, u, *, noise=None, noise_std=0.0, random_state=None,
             divergence_threshold=1e8):
    """Simulate the output of a fractional-order Hammerstein–Wiener model.

    Parameters
    ----------
    model : HammersteinWiener
        The system.
    u : array_like, shape (N,)
        Input signal, finite.
    noise : array_like, shape (N,), optional
        The equation noise ``v[k]`` added at every sample. Mutually exclusive with
        ``noise_std > 0``.
    noise_std : float, optional
        Standard deviation of white Gaussian ``v[k]`` drawn from ``random_state``. Default 0.
    random_state : None, int or numpy.random.Generator, optional
        Source of the noise when ``noise_std > 0``.
    divergence_threshold : float, optional
        The output is declared divergent when ``|y[k]|`` exceeds this (default ``1e8``)
        or is not finite.

    Returns
    -------
    y : ndarray, shape (N,)
        The output. To keep the noise realisation, draw it yourself and pass ``noise``.

    Raises
    ------
    SimulationDivergedError
        The output escaped; ``err.sample`` is the first offending index.

    Notes
    -----
    The exact recursion of SPEC §3 (Eq. 16) with full memory: ``y[k]`` uses
    ``(Δ^α gbar(y))[k-i]`` for ``i = 1..na``, each the GL sum over all of
    ``gbar(y[0..k-i])``. The input branch is computed once by :func:`fohw.gl_difference`.
    Up to ``N = 8192`` the output memory is one dot product per sample (``O(N**2)``, about
    0.04 s at ``N = 10**4``); above, finished halves of the record enter later samples through
    FFT convolutions (``O(N log^2 N)``, about 3.5 s at ``N = 10**6``), equal to the direct
    recursion to rounding.

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
    threshold = check_scalar(divergence_threshold, "divergence_threshold", lower=0.0,
                             lower_inclusive=False)
    return _simulate_blocks(model.q[:, None], model.a[None, :], np.outer(model.p, model.b),
                            model.alpha, model.f_basis, model.g_basis, u, v, threshold)


def simulate_theta(theta, alpha, u, *, na, nb, f_basis, g_basis, noise=None, noise_std=0.0,
                   random_state=None, divergence_threshold=1e8):
    """Simulate the model ``y = Phi(alpha) theta + v`` for any theta (not only ``q ⊗ a, p ⊗ b``).

    The same recursion as :func:`simulate`, with each entry of theta its own coefficient: the
    free-run behaviour of exactly the predictor that an estimator fitted, before the rank-one
    projection of Eqs. (39)–(40).

    Parameters
    ----------
    theta : array_like, shape (n,)
        Parameters in the layout of :class:`fohw.ThetaLayout`.
    alpha : float
        Fractional order (finite).
    u : array_like, shape (N,)
        Input.
    na, nb, f_basis, g_basis
        Model structure.
    noise, noise_std, random_state, divergence_threshold
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
    f_basis = as_basis(f_basis, "f_basis")
    g_basis = as_basis(g_basis, "g_basis")
    layout = ThetaLayout(na=na, nb=nb, n_g=len(g_basis), n_f=len(f_basis))
    qa, pb = layout.blocks(theta)
    alpha = check_scalar(alpha, "alpha")
    u = check_array(u, "u")
    v = _noise(u.shape[0], noise, noise_std, random_state)
    threshold = check_scalar(divergence_threshold, "divergence_threshold", lower=0.0,
                             lower_inclusive=False)
    if qa.shape[0] <= qa.shape[1]:      # fewer g-signals than lags: z_j = g_j(y)
        Q, A = np.eye(qa.shape[0]), qa
    else:                               # fewer lags: z_i = sum_j qa[j, i] g_j(y)
        Q, A = qa, np.eye(qa.shape[1])
    return _simulate_blocks(Q, A, pb, alpha, f_basis, g_basis, u, v, threshold)
