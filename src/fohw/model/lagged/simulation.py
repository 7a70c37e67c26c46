"""The simulator: the output of any fractional-order Hammerstein–Wiener model (Eqs. 14, 16).

:func:`fohw.simulate` (:mod:`fohw.model.simulate`) runs a :class:`fohw.HammersteinWiener`, an
identification result (its fitted predictor, any theta) or a :class:`fohw.Structure` with
parameter values through this one engine:

* :func:`forcing`: everything in ``y[k]`` that does not feed back (noise, offset, the input
  branch by FFT, the transients of past levels);
* :func:`recursion`: the output feedback, sample by sample in leaves (pure Python, or compiled by
  :mod:`fohw.model._compiled`) joined by FFT merges (:mod:`fohw.model.kernels`), ``O(N log^2 N)``;
* :func:`free_run`: the two in deviation coordinates, with a measured history and the divergence
  test (:data:`FAST_SIMULATION_THRESHOLD`, :data:`LEAF_SIZE`, :data:`LEAF_SIZE_COMPILED`).

Every order is checked against one rule, the closed interval
:data:`fohw.model.orders.ORDER_RANGE` ``= [0, 2]``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..._validation import (
    check_array,
    check_inputs,
    check_pair,
    check_random_state,
    check_same_length,
    check_scalar,
    unpack_pair,
)
from ...exceptions import (
    DimensionError,
    ParameterError,
    SimulationDivergedError,
)
from .. import _compiled
from ..gl import gl_weights, gl_weights_unchecked, past_transient
from ..kernels import HalfMerge, causal_convolve, divide_and_conquer

__all__ = ["simulate_predictor", "simulate_model", "equation_noise", "free_run",
           "forcing", "recursion", "accumulators", "output_terms", "Accumulators", "apply_output_map",
           "check_input_point", "FAST_SIMULATION_THRESHOLD", "LEAF_SIZE", "LEAF_SIZE_COMPILED"]

#: Below this record length the simulator runs the recursion directly (one dot product per
#: output signal and sample); above it, by divide and conquer (:func:`recursion`).
FAST_SIMULATION_THRESHOLD = 8192
#: Leaf sizes of the divide and conquer for the pure-Python and the compiled leaf, chosen by
#: ``benchmarks/bench_simulator.py --leaves`` (64 to 1024 measured at N = 10**5 and 10**6):
#: 256 is the fastest pure leaf; the compiled one is about 10 % faster at 512, but equal sizes
#: make the two leaves give identical numbers, so installing numba (or loading it part-way
#: through a process) changes no simulation.
LEAF_SIZE = 256
LEAF_SIZE_COMPILED = 256


def simulate_model(model, u, *, noise=None, noise_std=0.0, random_state=None,
                   divergence_threshold=None, history=None):
    """A model through its rank-one blocks: ``gbar`` is the one output signal fed back."""
    u = check_array(u, "u")
    v = equation_noise(u.shape[0], noise, noise_std, random_state)
    return free_run(model.structure, model.q[:, None], model.a[None, :],
                    np.outer(model.q, model.a), np.outer(model.p, model.b), model.orders, u, v,
                    offset=model.offset, past=model.past, operating_point=model.operating_point,
                    threshold=_check_threshold(divergence_threshold), history=history)


def simulate_predictor(structure, linear, nonlinear, u, *, operating_point=(0.0, 0.0), noise=None,
                       noise_std=0.0, random_state=None, divergence_threshold=None,
                       history=None):
    """Any theta of a structure (the predictor an estimator fitted, before Eqs. 39–40).

    :func:`simulate` of a Structure, for callers inside the package that checked the orders
    themselves (an estimator inside its bounds): they are used as given, any finite order (as
    :func:`fohw.gl_weights` allows), so that a finite difference may step across a bound.
    ``linear``, ``nonlinear``: :attr:`Structure.linear_names`, :attr:`Structure.nonlinear_names`.
    """
    layout = structure.layout
    linear = check_array(linear, "linear")
    nonlinear = np.atleast_1d(check_array(nonlinear, "params", ndim=None, min_length=0))
    for value, names, name in ((linear, structure.linear_names, "linear"),
                               (nonlinear, structure.nonlinear_names, "params")):
        if value.shape[0] != len(names):
            raise DimensionError(f"`{name}` must have {len(names)} entries {names}; got "
                                 f"{value.shape[0]}.")
    qa, pb = layout.blocks(linear[:layout.n_params])
    offset = float(linear[layout.n_params]) if structure.offset else 0.0
    values, past = structure.split_nonlinear(nonlinear)
    u = check_inputs(u, structure.n_inputs, names=structure.inputs)
    v = equation_noise(u.shape[0], noise, noise_std, random_state)
    Q, A = _output_representation(qa)
    hmap = structure.output_map
    if hmap is not None:
        eta = hmap.check_params(structure.output_map_params(nonlinear))
        if history is not None:            # the recursion's memory holds z, not y = h(z)
            u_hist, y_hist = _check_history(history)
            history = (u_hist, hmap.inverse(y_hist, eta))
    point = (check_pair(operating_point, "operating_point") if structure.n_inputs == 1 else
             check_input_point(operating_point, structure.n_inputs))
    z = free_run(structure, Q, A, qa, pb, values, u, v, offset=offset, past=past,
                 operating_point=point,
                 threshold=_check_threshold(divergence_threshold), history=history)
    return z if hmap is None else apply_output_map(hmap, eta, z)


def apply_output_map(output_map, params, z):
    """``y = h(z; params)`` of a series output map (data units), checked to be finite."""
    y = output_map.evaluate(z, params)
    if y.shape != z.shape or not np.all(np.isfinite(y)):
        k = int(np.flatnonzero(~np.isfinite(y))[0]) if y.shape == z.shape else 0
        raise ParameterError(f"the output map {output_map.describe()} returned "
                             f"{'shape ' + str(y.shape) if y.shape != z.shape else y[k]!r} for the "
                             f"model output z{'' if y.shape != z.shape else f'[{k}] = {z[k]!r}'}: "
                             "it must return a finite value per sample.")
    return y


def forcing(pb, in_terms, qa, out_terms, f_basis, g_basis, u, v, h, offset, past):
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


class Accumulators(NamedTuple):
    """The memories of the output feedback (:func:`accumulators`).

    ``count``: how many; ``terms``: ``(accumulator, lag - 1, coefficient)`` per output term
    and signal; ``memory``: ``(accumulator, signal, index into betas)`` of the accumulators
    with an order > 0; ``memoryless``: ``(accumulator, signal)`` of those of order 0;
    ``betas``: the GL weights of each distinct order > 0.
    """

    count: int
    terms: list
    memory: list
    memoryless: list
    betas: list


def accumulators(A, out_terms, h, n):
    """One accumulator of ``Delta^nu z_r`` per (signal ``r``, distinct order ``nu``) pair.

    ``A[r, t]`` is the coefficient of signal ``r`` in output term ``t`` of ``(lag, order)``
    ``out_terms[t]``; ``h`` the sampling time and ``n`` the record length.
    """
    R = A.shape[0]
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
    return Accumulators(len(acc), terms, memory, memoryless, betas)


def _leaf_kernel(g_basis, n, kernel):
    """The compiled leaf kernel for ``kernel`` ``"auto"``/``"compiled"``, or ``None`` (pure)."""
    if kernel not in ("auto", "compiled", "pure"):
        raise ParameterError(f"`kernel` must be 'auto', 'compiled' or 'pure'; got {kernel!r}.")
    if kernel == "pure":
        return None
    compiled = _compiled.leaf_for(g_basis, n if kernel == "auto" else _compiled.LOAD_AFTER)
    if compiled is None and kernel == "compiled":
        raise RuntimeError("the compiled leaf is not available (numba missing or disabled, "
                           "or a non-polynomial output basis).")
    return compiled


def recursion(Q, A, out_terms, g_basis, w, threshold, method="auto", h=1.0, y_fixed=None, *,
              kernel="auto", leaf_size=None):
    """``y[k] = w[k] + sum_r sum_t A[r, t] (Delta_h^{nu_t} z_r)[k - lag_t]`` (Eqs. 14, 16).

    ``z_r(y) = sum_j Q[j, r] g_j(y)``: for a model ``Q = q``, ``A = a`` (one signal, gbar);
    for a general theta either ``Q = I, A = qa`` or ``Q = qa, A = I``. ``out_terms[t]`` is the
    ``(lag, order)`` of column ``t`` of ``A``. Every (signal, distinct order) pair has an
    accumulator of ``Delta^nu z_r`` (:func:`accumulators`); order-0 accumulators have no memory
    (``z_r`` itself).

    O(N log^2 N) by divide and conquer over time (:mod:`fohw.model.kernels`): once the first
    half of ``[lo, hi)`` is finished, its contribution to the accumulators on the second half
    is added by FFT (one transform per signal and one inverse per accumulator, the weights'
    spectra computed once per level). Leaves run the recursion sample by sample, one dot
    product per accumulator and sample for the leaf's own past. ``method``: ``"direct"`` is one
    leaf of ``N`` samples (O(N^2)), ``"fast"`` the divide and conquer, ``"auto"`` the latter
    above :data:`FAST_SIMULATION_THRESHOLD` samples. The first ``len(y_fixed)`` outputs are not
    computed but taken from ``y_fixed`` (a measured history).

    ``kernel`` chooses the leaf: ``"auto"`` the compiled leaf (:mod:`fohw.model._compiled`,
    polynomial output bases, numba installed and loaded) or else the pure-Python one;
    ``"pure"``; ``"compiled"`` (an error if it is not available). ``leaf_size`` overrides the
    leaf size of the divide and conquer (:data:`LEAF_SIZE` for the pure leaf,
    :data:`LEAF_SIZE_COMPILED` for the compiled one).
    """
    n = w.shape[0]
    if method == "auto":
        method = "fast" if n > FAST_SIMULATION_THRESHOLD else "direct"
    compiled = _leaf_kernel(g_basis, n, kernel)
    if method == "direct":
        leaf_size = n
    elif leaf_size is None:
        leaf_size = LEAF_SIZE_COMPILED if compiled is not None else LEAF_SIZE
    leaf_size = max(1, min(leaf_size, n))

    acc = accumulators(A, out_terms, h, n)
    merge = HalfMerge(acc.betas, acc.memory)
    y = np.zeros(n)
    z = np.zeros((Q.shape[1], n))
    dz = np.zeros((acc.count, n))      # contributions gathered so far
    rev = np.array([acc.betas[k][:leaf_size][::-1] for _, _, k in acc.memory]).reshape(
        len(acc.memory), leaf_size)
    if compiled is not None:
        leaf = _compiled_leaf(compiled, Q, acc.terms, acc.memory, acc.memoryless, rev, w, y, z,
                              dz, threshold, y_fixed)
    else:
        leaf = _pure_leaf(output_terms(g_basis, Q), acc.terms, acc.memory, acc.memoryless, rev,
                          w, y, z, dz, threshold, y_fixed)
        _compiled.count_pure(n)
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            divide_and_conquer(n, leaf_size, leaf, lambda lo, mid, hi: merge(z, dz, lo, mid, hi))
    except SimulationDivergedError as err:
        if err.cause == "output_basis" and _basis_overflows(g_basis, err.value):
            raise SimulationDivergedError(err.sample, err.value, err.threshold, err.cause,
                                          overflow=True) from None
        raise
    return y


def _basis_overflows(g_basis, y):
    """Whether ``g`` is non-finite at the finite ``y`` by overflow (no function left its domain)."""
    if not np.isfinite(y):
        return False
    x = np.array([float(y)])
    for f in getattr(g_basis, "functions", ()):
        try:
            with np.errstate(over="ignore", invalid="raise", divide="raise"):
                value = np.asarray(f(x), dtype=np.float64)
        except FloatingPointError:
            return False                    # invalid or divide: sqrt, log of a bad value
        except (OverflowError, ArithmeticError):
            continue
        except Exception:                   # a user's function failing otherwise: not known
            return False
        if np.any(np.isnan(value)):
            return False
    return True


def _pure_leaf(zfun, terms, memory, memoryless, rev, w, y, z, dz, threshold, y_fixed):
    """The leaf of :func:`recursion` in Python: ``leaf(lo, hi)`` finishes samples lo..hi-1."""
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
    """The leaf of :func:`recursion` by the compiled ``kernel`` (:mod:`fohw.model._compiled`)."""
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


def output_terms(g_basis, Q):
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


def free_run(structure, Q, A, qa, pb, order_values, u, v, *, offset, past, operating_point,
             threshold, history, method="auto", kernel="auto", leaf_size=None):
    """Simulate any structure from its coefficient blocks (deviation coordinates inside).

    ``Q, A``: the fed-back signals and their coefficients (:func:`recursion`); ``qa``, ``pb``:
    the ``(n_g, n_out)`` and ``(n_f, n_in)`` coefficients of basis function and term
    (:func:`forcing`); ``order_values``: ``{free order: value}``, already checked; ``u``,
    ``v``: input (data units) and equation noise; ``threshold``: the divergence bound or
    ``None`` (the default of :func:`simulate`). ``method``, ``kernel``, ``leaf_size`` as for
    :func:`recursion`.
    """
    u0, y0 = operating_point
    out_nu, in_nu = structure.orders.values(order_values, check=False)
    out_terms = [(term.lag, nu) for term, nu in zip(structure.orders.output, out_nu)]
    in_terms = [(term.lag, nu) for term, nu in zip(structure.orders.input, in_nu)]
    n_hist, y_fixed = 0, None
    if history is not None:
        u_hist, y_hist = _check_history(history, structure.n_inputs)
        n_hist = u_hist.shape[0]
        u = np.r_[u_hist, u]
        v = np.r_[np.zeros(n_hist), v]
        y_fixed = y_hist - y0 if y0 != 0.0 else y_hist
    if np.any(np.asarray(u0) != 0.0):
        u = u - np.asarray(u0)
    w = forcing(pb, in_terms, qa, out_terms, structure.f_basis, structure.g_basis, u, v,
                structure.dt, offset, past)
    if threshold is None:
        threshold = _default_threshold(w, y_fixed)
    try:
        y = recursion(Q, A, out_terms, structure.g_basis, w, threshold, method,
                      structure.dt, y_fixed, kernel=kernel, leaf_size=leaf_size)
    except SimulationDivergedError as err:
        raise SimulationDivergedError(err.sample - n_hist, err.value + y0, err.threshold,
                                      err.cause, overflow=err.overflow) from None
    y = y[n_hist:]
    return y + y0 if y0 != 0.0 else y


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


def equation_noise(n, noise=None, noise_std=0.0, random_state=None):
    """The equation noise ``v`` of a simulation: ``noise`` itself, white Gaussian, or zeros.

    Parameters
    ----------
    n : int
        Number of samples.
    noise : array_like, shape (n,), optional
        Given noise (mutually exclusive with ``noise_std > 0``).
    noise_std : float, optional
        Standard deviation of white Gaussian noise drawn from ``random_state``. Default 0.
    random_state : None, int or numpy.random.Generator, optional
        Source of the drawn noise.

    Returns
    -------
    v : ndarray, shape (n,)
    """
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


def check_input_point(operating_point, n_inputs):
    """``(u0, y0)`` of a model with several inputs: ``u0`` one level per input (a tuple)."""
    u0, y0 = unpack_pair(operating_point, "operating_point", "(u0, y0)")
    if np.ndim(u0) == 0:
        u0 = [check_scalar(u0, "operating_point[0]")] * n_inputs
    u0 = check_array(u0, "operating_point[0]")
    if u0.shape[0] != n_inputs:
        raise DimensionError(f"`operating_point[0]` must give {n_inputs} input levels (one per "
                             f"input); got {u0.shape[0]}.")
    return tuple(float(x) for x in u0), check_scalar(y0, "operating_point[1]")


def _check_history(history, n_inputs=1):
    u_hist, y_hist = unpack_pair(history, "history", "(u_past, y_past) of measured records")
    u_hist = check_inputs(u_hist, n_inputs, "history u")
    y_hist = check_array(y_hist, "history y")
    check_same_length(u_hist, y_hist, "history u", "history y")
    return u_hist, y_hist


def _check_threshold(divergence_threshold):
    if divergence_threshold is None:
        return None
    return check_scalar(divergence_threshold, "divergence_threshold", lower=0.0,
                        lower_inclusive=False)
