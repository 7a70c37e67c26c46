"""Sensitivity of the free-run simulation to the parameters — beyond the paper.

The noise-free output ``y = ysim(x)`` of a model (Eq. 16; Eq. 14 for a general
:class:`fohw.Structure`) with parameters ``x = (linear, nonlinear)`` satisfies
``y = Phi(y; x_nl) @ linear`` exactly, where ``Phi`` is the information matrix built from the
simulated output itself. Differentiating this identity with respect to ``x`` gives the
sensitivity ``S = d ysim / d x`` as the solution of a linear recursion,

.. math:: S[k] = E[k] + \\sum_t h^{-\\nu_t} \\sum_{m \\le k - i_t}
          \\beta_{\\nu_t}[k - i_t - m] \\, c_t[m] \\, S[m],
          \\qquad c_t[m] = \\sum_j (q_j a_t)\\, g_j'(y[m]),

where ``E = [Phi, dPhi/dx_nl @ linear]`` is the one-step-predictor Jacobian
(:meth:`fohw.model.lagged.regressors.RegressorBuilder.jacobian`) evaluated on the simulated output,
and the sum runs
over the output terms ``t`` (lag ``i_t >= 1``, order ``nu_t``, coefficient ``q_j a_t`` of basis
function ``g_j``). Because every lag is at least 1, ``S[k]`` depends on ``S[0..k-1]`` only, and
the recursion is solved exactly by the divide-and-conquer scheme of the simulator
(:func:`fohw.simulate`): finished halves enter later samples through FFT convolutions,
``O(N log^2 N)``. The leaves are compiled with numba when it is installed (as the
simulator's, :mod:`fohw.model._compiled`), with the same numbers.

``S`` is the Jacobian of the simulation-error residual (:mod:`fohw.estimators.output_error`),
and ``S^T S / sigma^2`` is the Fisher information when white Gaussian noise of variance
``sigma^2`` is added to the measured output (:func:`fohw.crb` with ``noise="output"``).
"""

from __future__ import annotations

import numpy as np

from ..._validation import check_array, check_inputs
from ...exceptions import DimensionError
from .. import _compiled
from ..gl import gl_weights
from ..kernels import HalfMerge, divide_and_conquer
from .regressors import RegressorBuilder
from .simulation import simulate_predictor
from .structure import Structure

__all__ = ["simulation_jacobian", "basis_derivative"]

#: Leaf sizes of the divide and conquer for the pure-Python and the compiled leaf
#: (``benchmarks/bench_output_error.py --leaves``: 128 is the fastest pure leaf at 10**5 and
#: within the spread of the fastest compiled one, 128-256, at 10**4-10**6). Equal sizes make
#: the two leaves give identical numbers, so numba changes no sensitivity.
LEAF_SIZE = 128
LEAF_SIZE_COMPILED = 128


def basis_derivative(basis, x):
    """Derivatives ``g_j'(x)`` of every basis function, shape ``(len(basis), len(x))``.

    Exact for :func:`fohw.polynomial_basis` (``d/dx x**n = n x**(n-1)``); other functions by a
    central difference with step ``1e-6 * max(|x|, rms(x))`` (relative error about ``1e-10``
    for smooth functions).
    """
    x = np.asarray(x, dtype=np.float64)
    if basis.is_polynomial:
        return np.array([n * x ** (n - 1) for n in range(1, len(basis) + 1)])
    scale = float(np.sqrt(np.mean(x * x))) if x.size else 1.0
    step = 1e-6 * np.maximum(np.abs(x), max(scale, 1e-300))
    return (basis.evaluate(x + step) - basis.evaluate(x - step)) / (2.0 * step)


def simulation_jacobian(structure, linear, params, u, *, y0=0.0):
    """Free-run output of a structure and its exact derivative with respect to the parameters.

    Parameters
    ----------
    structure : Structure
        The model class.
    linear : array_like
        The linear parameters (theta, then the offset; :attr:`Structure.linear_names`), any
        theta (not only ``[q ⊗ a, p ⊗ b]``).
    params : array_like
        The nonlinear parameters (:attr:`Structure.nonlinear_names`).
    u : array_like, shape (N,)
        The input, as a deviation from the operating point.
    y0 : float, optional
        The output's operating point, for a structure with a series output map ``h`` (which
        acts in the data's units): the output is then ``h(z + y0) - y0`` with ``z`` the free
        run of :attr:`Structure.inner`, and the Jacobian ``[h'(z + y0) S_z, dh/d(h_*)]`` (the
        chain rule through ``h``, exact). Default 0.

    Returns
    -------
    y : ndarray, shape (N,)
        The noise-free simulated output (deviation from the operating point).
    S : ndarray, shape (N, n_linear + n_nonlinear)
        ``d y / d (linear, params)``, columns in :attr:`Structure.linear_names` then
        :attr:`Structure.nonlinear_names` order.

    Raises
    ------
    SimulationDivergedError
        The model's free run escapes.

    Notes
    -----
    The recursion in the module notes (the derivative of Eq. 16 through the output feedback).
    It equals central finite differences of :func:`fohw.simulate` to their
    truncation error (``tests/test_structured.py``).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> from fohw.model.lagged.sensitivity import simulation_jacobian
    >>> m = fohw.datasets.paper_model()
    >>> u = np.random.default_rng(0).uniform(-1, 1, 300)
    >>> y, S = simulation_jacobian(m.structure, m.linear, m.nonlinear, u)
    >>> S.shape, bool(np.allclose(y, fohw.simulate(m, u)))
    ((300, 11), True)
    """
    hmap = getattr(structure, "output_map", None)
    if hmap is not None:
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        eta = structure.output_map_params(params)
        z, S = simulation_jacobian(structure.inner, linear, params[:params.shape[0] - eta.shape[0]],
                                   u)
        zd = z + y0
        y = hmap.evaluate(zd, eta)
        G = np.hstack([hmap.derivative(zd, eta)[:, None] * S,
                       hmap.param_jacobian(zd, eta).reshape(z.shape[0], eta.shape[0])])
        return (y - y0 if y0 != 0.0 else y), G
    y, E, lags, betas, coefs = _feedback_problem(structure, linear, params, u)
    return y, _solve_feedback(E, lags, betas, coefs)


def _feedback_problem(structure, linear, params, u):
    """The simulated output and the arguments of :func:`_solve_feedback` for them."""
    if not isinstance(structure, Structure):
        raise DimensionError(f"`structure` must be a fohw.Structure; got "
                             f"{type(structure).__name__}.")
    linear = check_array(linear, "linear")
    params = np.atleast_1d(np.asarray(params, dtype=np.float64))
    u = check_inputs(u, structure.n_inputs, names=structure.inputs)
    y = simulate_predictor(structure, linear, params, u)
    builder = RegressorBuilder(u, y, structure=structure)
    E = builder.jacobian(linear, params)
    layout = structure.layout
    qa, _ = layout.blocks(linear[:layout.n_params])
    out_nu, _, _ = builder.term_orders(params)
    dg = basis_derivative(structure.g_basis, y)             # (n_g, N)
    h = structure.dt
    lags, betas, coefs = [], [], []
    n = y.shape[0]
    weights = {}                          # one array per distinct order (shared spectra)
    for t, (term, nu) in enumerate(zip(structure.orders.output, out_nu)):
        lags.append(term.lag)
        if nu not in weights:
            weights[nu] = gl_weights(nu, n)
        betas.append(weights[nu])
        coefs.append((qa[:, t] @ dg) * (1.0 if h == 1.0 else h**-nu))
    return y, E, lags, betas, coefs


def _solve_feedback(E, lags, betas, coefs, *, kernel="auto", leaf_size=None):
    """``S[k] = E[k] + sum_t (beta_t * (c_t S))[k - lag_t]`` for all ``k`` (lags >= 1).

    Divide and conquer over time with the simulator's skeleton (:mod:`fohw.model.kernels`):
    ``D[t]`` gathers ``beta_t * z_t`` with ``z_t = c_t S``; a leaf finishes its samples one by
    one (a matrix-vector product per term and sample for the leaf's own past), and once the
    first half of ``[lo, hi)`` is finished its ``z`` enters ``D`` on the second half by FFT
    (:class:`~fohw.model.kernels.HalfMerge`: the spectra of the weights once per FFT size, and
    terms given the same weights array share them).

    ``kernel`` chooses the leaf: ``"auto"`` the compiled one (:mod:`fohw.model._compiled`, when
    numba is installed and loaded) or else the pure-Python one; ``"pure"``; ``"compiled"`` (an
    error if it is not available). Both do the same operations in the same order, so at equal
    leaf sizes they give identical numbers. ``leaf_size`` overrides the leaf size
    (:data:`LEAF_SIZE` for the pure leaf, :data:`LEAF_SIZE_COMPILED` for the compiled one).
    """
    n, d = E.shape
    T = len(lags)
    compiled = None
    if kernel in ("auto", "compiled"):
        compiled = _compiled.feedback_leaf_for(n if kernel == "auto" else _compiled.LOAD_AFTER)
        if compiled is None and kernel == "compiled":
            raise RuntimeError("the compiled leaf is not available (numba missing or disabled).")
    if leaf_size is None:
        leaf_size = LEAF_SIZE_COMPILED if compiled is not None else LEAF_SIZE
    S = E.copy()
    Z = np.zeros((T, n, d))
    D = np.zeros((T, n, d))
    leaf = max(1, min(leaf_size, n))
    rev = [b[:leaf][::-1].copy() for b in betas]
    distinct = {}
    for b in betas:
        distinct.setdefault(id(b), (len(distinct), b))
    merge = HalfMerge([b for _, b in distinct.values()],
                      [(t, t, distinct[id(b)][0]) for t, b in enumerate(betas)])

    if compiled is not None:
        args = (S, Z, D, np.array(lags, dtype=np.intp),
                np.array(coefs, dtype=np.float64).reshape(T, n),
                np.array(rev, dtype=np.float64).reshape(T, leaf), np.zeros(d))

        def run_leaf(lo, hi):
            compiled(lo, hi, *args)
    else:
        _compiled.count_pure(n * _compiled.FEEDBACK_WEIGHT)

        def run_leaf(lo, hi):
            for k in range(lo, hi):
                s = S[k]
                for t in range(T):
                    j = k - lags[t]
                    if j >= 0:
                        s += D[t, j]
                for t in range(T):
                    Z[t, k] = coefs[t][k] * s
                    D[t, k] += rev[t][leaf - (k - lo + 1):] @ Z[t, lo:k + 1]

    divide_and_conquer(n, leaf, run_leaf, lambda lo, mid, hi: merge(Z, D, lo, mid, hi))
    return S
