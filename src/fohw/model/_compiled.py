"""The simulator's and its sensitivity's leaves compiled with numba (extra ``fohw[fast]``; Eqs. 14, 16).

:func:`fohw.model.lagged.simulation.recursion` runs each leaf of its divide and conquer sample by sample:
``y[k]`` from the forcing and the accumulated GL memory, the output signals ``z_r(y[k])``, then
the leaf's own past added to the accumulators by one dot product each. :func:`_leaf` is that
loop for a polynomial output basis, doing the same floating-point operations in the same order
as the pure-Python leaf (the dot products through BLAS ``ddot``, as ``numpy.dot``), compiled by
numba. :func:`_feedback_leaf` is the leaf of the sensitivity's linear recursion
(:func:`fohw.model.lagged.sensitivity._solve_feedback`), likewise the operations of its pure leaf in
their order (the leaf's own past by one BLAS ``dgemv`` per term and sample, as NumPy's
``rev @ Z``). Without numba, with ``FOHW_NO_NUMBA=1`` in the environment, with :data:`ENABLED`
set to False, or (simulator) for any other output basis, the pure-Python leaves run instead,
which give the same numbers (``tests/test_compiled.py`` compares them at every sample).

Importing numba and loading the compiled leaves from numba's cache costs 0.5–1.7 s once per
process in the measurements of docs/performance.md (compiling them the first time, before the
cache exists, 3–4 s), so they
are loaded lazily: by a simulation of at least :data:`LOAD_AFTER` samples (a sensitivity solve
counts :data:`FEEDBACK_WEIGHT` samples per sample), or once the pure leaves of the process have
run that many samples. From then on every simulation long enough for the divide and conquer,
and every sensitivity solve, uses them. :func:`load` loads them at once.
"""

from __future__ import annotations

import importlib.util
import os
import time
import warnings

import numpy as np

__all__ = ["ENABLED", "LOAD_AFTER", "FEEDBACK_WEIGHT", "available", "load", "leaf_for",
           "feedback_leaf_for", "count_pure"]

#: Use the compiled leaf when numba is importable; ``FOHW_NO_NUMBA=1`` in the environment turns
#: it off at import, and tests and benchmarks flip it to compare both paths in one process.
ENABLED = os.environ.get("FOHW_NO_NUMBA", "") in ("", "0")

#: Samples of pure-leaf simulation (one simulation, or all of the process so far) after which
#: the compiled leaf is loaded: about 1 s of pure leaf at 4 µs per sample, comparable to the
#: one-time cost of importing numba and loading the cached leaf.
LOAD_AFTER = 2**18

#: Samples of the simulator's pure leaf that one sample of a pure sensitivity solve counts for
#: (towards :data:`LOAD_AFTER`): the solve's time per sample with the 11 columns of the paper's
#: example, about 6 times the pure simulator's (``benchmarks/bench_output_error.py
#: --sensitivity``: the whole sensitivity, simulation included, is 7-8 simulations at 1e4-1e5).
FEEDBACK_WEIGHT = 6

# Status codes returned by the leaf (the caller raises SimulationDivergedError).
OK, GROWTH, OUTPUT_BASIS = 0, 1, 2

_state = {"kernel": None, "feedback": None, "failed": False, "error": None, "pure_samples": 0,
          "load_seconds": None}


def _has_numba():
    return importlib.util.find_spec("numba") is not None


def available():
    """True when the compiled leaf can be used (enabled, numba installed and importable)."""
    return ENABLED and not _state["failed"] and (_state["kernel"] is not None or _has_numba())


def load():
    """Import numba and compile (or load from cache) both leaves; return the simulator's, or ``None``.

    ``None`` when numba is not installed, or is installed but does not import (for instance a
    NumPy newer than the numba release supports, or a module of the script's directory
    shadowing one numba imports, such as a ``coverage.py``) or cannot compile the leaves: then
    a ``RuntimeWarning`` says why, once, and the pure leaf is used. Where numba has nowhere to
    write its cache (a read-only install and no writable home), the leaves are compiled without
    it, in every process. The seconds spent are kept in
    ``_state["load_seconds"]``.
    """
    if _state["kernel"] is not None or _state["failed"]:
        return _state["kernel"]
    if not _has_numba():
        _state["failed"] = True
        return None
    t0 = time.perf_counter()
    try:
        import numba
    except Exception as err:   # an optional accelerator: any import failure means the pure leaf
        return _fail(err, "is installed but does not import")
    try:
        try:
            kernel, feedback = _compile(numba, cache=True)
        except RuntimeError as err:          # e.g. "cannot cache function": nowhere to write
            if "cache" not in str(err):
                raise
            kernel, feedback = _compile(numba, cache=False)
    except Exception as err:   # a compile or typing error (another numba release, ...)
        return _fail(err, "could not compile the leaves")
    _state["feedback"] = feedback
    _state["kernel"] = kernel
    _state["load_seconds"] = time.perf_counter() - t0
    return kernel


def _compile(numba, *, cache):
    """Both leaves compiled (from numba's cache when ``cache`` and it exists), called once."""
    kernel = numba.njit(cache=cache, nogil=True)(_leaf)
    n_g = 2
    kernel(0, 1, np.zeros(1), np.zeros(1), np.zeros((1, 1)), np.zeros((1, 1)),
           np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0), np.zeros(1, np.intp),
           np.zeros(1, np.intp), np.ones((1, 1)), np.zeros(0, np.intp), np.zeros(0, np.intp),
           np.ones((n_g, 1)), True, np.zeros(0), 1.0, np.zeros(n_g))   # compile now
    feedback = numba.njit(cache=cache, nogil=True)(_feedback_leaf)
    feedback(0, 1, np.zeros((1, 2)), np.zeros((1, 1, 2)), np.zeros((1, 1, 2)),
             np.ones(1, np.intp), np.zeros((1, 1)), np.ones((1, 1)), np.zeros(2))
    return kernel, feedback


def _fail(err, what):
    """Give up on the compiled leaves for this process: one RuntimeWarning, then the pure ones."""
    _state["failed"] = True
    _state["error"] = err
    warnings.warn(f"numba {what} ({type(err).__name__}: {err}); the simulator and its "
                  "sensitivity use their pure-Python leaves (same numbers, slower).",
                  RuntimeWarning, stacklevel=3)
    return None


def count_pure(n):
    """Record ``n`` samples run through the pure leaf (towards :data:`LOAD_AFTER`)."""
    _state["pure_samples"] += n


def _loaded_after(n):
    """The compiled leaves once loaded, or when ``n`` or the pure samples so far reach LOAD_AFTER."""
    return _state["kernel"] is not None or max(n, _state["pure_samples"]) >= LOAD_AFTER


def feedback_leaf_for(n):
    """The compiled sensitivity leaf for a solve of ``n`` samples, or ``None`` (the pure leaf).

    The rules of :func:`leaf_for`, a sample of the solve counting :data:`FEEDBACK_WEIGHT`.
    """
    if not available() or not _loaded_after(n * FEEDBACK_WEIGHT):
        return None
    return _state["feedback"] if load() is not None else None


def leaf_for(g_basis, n):
    """The compiled leaf for a simulation of ``n`` samples with output basis ``g_basis``.

    ``None`` (use the pure leaf) when the basis is not polynomial, the compiled leaf is not
    available, or it is not loaded yet and neither ``n`` nor the pure-leaf samples run so far
    reach :data:`LOAD_AFTER`.
    """
    if not g_basis.is_polynomial or not available():
        return None
    if not _loaded_after(n):
        return None
    return load()


def _leaf(lo, hi, w, y, z, dz, term_acc, term_lag, term_coef, mem_acc, mem_sig, rev,
          ml_acc, ml_sig, Q, horner, fixed, threshold, g):
    """Samples ``lo .. hi-1`` of the recursion in place; returns ``(status, k, y[k])``.

    ``term_*``: accumulator, ``lag - 1`` and coefficient of every output term (in the pure
    leaf's order); ``mem_*``: accumulator and signal of every accumulator with memory, ``rev``
    its first ``L`` weights reversed (one row each); ``ml_*``: the order-0 accumulators;
    ``Q``: ``(n_g, R)`` coefficients of the polynomial output basis ``g_j(y) = y**j``;
    ``horner``: ``R == 1`` (Horner's scheme, as the pure leaf); ``fixed``: a measured history
    of outputs; ``g``: scratch of length ``n_g``. Status :data:`OK`, :data:`GROWTH` (``|y[k]|``
    beyond ``threshold`` or nan) or :data:`OUTPUT_BASIS` (a non-finite ``z_r(y[k])``).
    """
    n_fixed = fixed.shape[0]
    n_terms = term_acc.shape[0]
    n_g, n_sig = Q.shape
    L = rev.shape[1]
    for k in range(lo, hi):
        if k < n_fixed:
            yk = fixed[k]
        else:
            yk = w[k]
            for t in range(n_terms):
                i = term_lag[t]
                if i < k:
                    yk += term_coef[t] * dz[term_acc[t], k - 1 - i]
            if not abs(yk) <= threshold:                   # also catches nan
                return GROWTH, k, yk
        finite = True
        if horner:
            acc = 0.0
            for j in range(n_g - 1, -1, -1):
                acc = acc * yk + Q[j, 0]
            zk = acc * yk
            z[0, k] = zk
            finite = np.isfinite(zk)
        else:
            p = yk
            for j in range(n_g):
                g[j] = p
                p *= yk
            for r in range(n_sig):
                s = 0.0
                for j in range(n_g):
                    s += Q[j, r] * g[j]
                z[r, k] = s
                if not np.isfinite(s):
                    finite = False
        if not finite:
            return OUTPUT_BASIS, k, yk
        y[k] = yk
        m = k - lo + 1
        for a in range(mem_acc.shape[0]):
            dz[mem_acc[a], k] += np.dot(z[mem_sig[a], lo:k + 1], rev[a, L - m:])
        for a in range(ml_acc.shape[0]):
            dz[ml_acc[a], k] = z[ml_sig[a], k]
    return OK, hi, 0.0


def _feedback_leaf(lo, hi, S, Z, D, lags, coefs, rev, x):
    """Samples ``lo .. hi-1`` of the sensitivity recursion in place (``_solve_feedback``'s leaf).

    ``S[k] += D[t, k - lags[t]]`` over the terms ``t`` (those with ``k >= lags[t]``), then per
    term ``Z[t, k] = coefs[t, k] * S[k]`` and ``D[t, k] += rev[t, L - m:] @ Z[t, lo:k + 1]``
    (``m = k - lo + 1``, ``rev`` the first ``L`` weights of each term reversed), as the pure
    leaf does: a BLAS ``dgemv`` for ``d >= 2`` columns and a ``ddot`` for one, which is what
    NumPy's ``@`` calls for these shapes. ``x``: scratch of length ``d``.
    """
    n_terms = lags.shape[0]
    d = S.shape[1]
    L = rev.shape[1]
    for k in range(lo, hi):
        for t in range(n_terms):
            j = k - lags[t]
            if j >= 0:
                for c in range(d):
                    S[k, c] += D[t, j, c]
        m = k - lo + 1
        for t in range(n_terms):
            ck = coefs[t, k]
            for c in range(d):
                Z[t, k, c] = ck * S[k, c]
            if d == 1:
                D[t, k, 0] += np.dot(rev[t, L - m:], Z[t, lo:k + 1].reshape(m))
            else:
                np.dot(rev[t, L - m:], Z[t, lo:k + 1], x)
                for c in range(d):
                    D[t, k, c] += x[c]
