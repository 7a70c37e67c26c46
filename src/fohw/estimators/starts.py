"""Where a simulation-error fit starts: nested models, a scan of the orders, several starts.

A free-run (simulation-error) criterion has local minima; which one a local search ends in
depends on where it starts. The default chain of ``method="output_error"`` (the standard
initialisation of block-oriented identification, as MATLAB's ``nlhw`` and PNLSS start from a
linear approximation) gathers candidate starts, ranks them by their free-run criterion and runs
the local search from ``n_starts`` of them: the best, the equation-error estimate whatever its
rank (a start's criterion does not tell its basin), then the next best:

* **the nested integer model**: the same structure with every free order fixed at 0 (the class
  contains it: commensurate, mixed and per-lag orders at 0, the mixed class's fractional
  coefficients at 0) is fitted first by simulation error and put into the richer class
  (continuation in the orders from 0 upward); where the class at orders 1 is an integer model of
  full rank (commensurate, per-lag), that one too when the scan's best point is there
  (continuation from 1 downward; otherwise the scan's end point at 1 starts from the
  equation-error fit of that model); a class with
  several free orders also starts from its fit with the orders tied (per-lag ⊃ commensurate);
* **the equation-error estimate** (``"varpro"``: the linear-in-theta model first);
* **a coarse scan of the orders**: at each point of a grid the equation-error theta of those
  orders (one linear least-squares solve) and the free run it gives; for several free orders
  the diagonal (all orders equal), then each order in turn around the best diagonal point.

Since the local search never ends above its start and the nested model's optimum is one of the
candidates, the fit of a class never ends with a worse criterion than the class it contains
(:func:`nested_structure`, :func:`embed`). The result reports every local search's criterion
and how many agreed with the best (:func:`agreement`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._parallel import TaskError, run_tasks
from ..model.lagged.structure import Structure
from ..model.orders import Orders
from .profile import Profile

__all__ = ["Start", "nested_structure", "tied_structure", "embed", "scan_starts", "choose_starts",
           "agreement", "AGREEMENT_RTOL", "SCAN_POINTS"]

#: Points of the coarse scan of each free order (the bounds' ends included).
SCAN_POINTS = 11
#: Two local searches agree when their criteria differ by less than this fraction of the best
#: (the solver stops at a relative change of the cost of 1e-8; 1e-3 leaves room for two
#: searches that approach the same minimum from different sides).
AGREEMENT_RTOL = 1e-3


@dataclass
class Start:
    """One candidate start: its name, the parameters and the free-run SSE there."""

    name: str
    linear: np.ndarray
    params: np.ndarray
    sse: float

    def orders(self, n_free):
        """The free orders of the start."""
        return self.params[:n_free]


def nested_structure(structure, value=0.0):
    """The structure with every free order fixed at ``value`` (None if it has no free order).

    Terms that become equal (the mixed class's ``(i, 0)`` and ``(i, alpha)`` at ``alpha = 0``)
    appear once. None also when the result would be rank deficient by construction: a class
    with fixed terms beside free ones at ``value != 0`` (the mixed class at 1, whose columns
    ``x(k-i)`` and ``Delta x(k-i)`` span fewer lags than they count).
    """
    orders = structure.orders
    if not orders.free:
        return None
    if value != 0.0 and any(not t.free for t in orders.output + orders.input):
        return None

    def terms(branch):
        out = []
        for t in branch:
            term = (t.lag, value if t.free else t.order, t.input)
            if term not in out:
                out.append(term)
        return out

    return Structure(Orders([t[:2] for t in terms(orders.output)], terms(orders.input),
                            inputs=orders.inputs or None), structure.f_basis,
                     structure.g_basis, structure.offset, structure.past, structure.dt)


def tied_structure(structure):
    """The structure with every free order tied to one (per-lag -> commensurate), or None.

    None when the structure has fewer than two free orders or tying them would make two terms
    equal.
    """
    orders = structure.orders
    if len(orders.free) < 2:
        return None
    name = "alpha"

    def terms(branch):
        return [(t.lag, name if t.free else t.order, t.input) for t in branch]

    a, b = terms(orders.output), terms(orders.input)
    if len(set(a)) < len(a) or len(set(b)) < len(b):
        return None
    return Structure(Orders([t[:2] for t in a], b, inputs=orders.inputs or None),
                     structure.f_basis, structure.g_basis, structure.offset, structure.past,
                     structure.dt)


def _term_values(structure, free_values):
    """Order value of every term of each branch, the free ones from ``free_values``."""
    def value(t):
        return float(free_values[t.order]) if t.free else float(t.order)
    return ([value(t) for t in structure.orders.output],
            [value(t) for t in structure.orders.input])


def _term_map(full_terms, full_values, nested_values):
    """Index of the nested term each full term takes its coefficients from (or None).

    Fixed terms are matched first, so the mixed class's order-0 terms take the integer
    model's coefficients and its fractional terms start at 0.
    """
    used, out = set(), [None] * len(full_terms)
    for pass_free in (False, True):
        for i, t in enumerate(full_terms):
            if t.free != pass_free:
                continue
            for j, (lag, v) in enumerate(nested_values):
                if j not in used and lag == t.lag and v == full_values[i]:
                    used.add(j)
                    out[i] = j
                    break
    return out


def embed(nested, linear, params, structure, free_values):
    """Parameters of ``structure`` that give exactly the model ``(linear, params)`` of ``nested``.

    Parameters
    ----------
    nested : Structure
        The contained class (its free orders, if any, at the values in ``params``).
    linear, params : ndarray
        Its linear and nonlinear parameters.
    structure : Structure
        The containing class.
    free_values : dict
        The value of each free order of ``structure`` at which it contains ``nested``.

    Returns
    -------
    (linear, params) : ndarray
        Of ``structure``: each term the nested model has keeps its coefficients, every other
        term gets 0; the offset and the past levels are copied.
    """
    n_values, past = nested.split_nonlinear(np.atleast_1d(params))
    nl_out, nl_in = _term_values(nested, n_values)
    f_out, f_in = _term_values(structure, free_values)
    lay, nlay = structure.layout, nested.layout
    out = np.zeros(structure.n_linear)
    branches = [
        (structure.orders.output, f_out, [(t.lag, v) for t, v in zip(nested.orders.output, nl_out)],
         len(structure.g_basis), lay.na, nlay.na, 0, 0)]
    if structure.n_inputs == 1:
        branches.append(
            (structure.orders.input, f_in, [(t.lag, v) for t, v in zip(nested.orders.input, nl_in)],
             len(structure.f_basis), lay.nb, nlay.nb, lay.n_output_params, nlay.n_output_params))
    else:                                # each input's block in turn
        for i, (group, ngroup) in enumerate(zip(lay.groups, nlay.groups)):
            full = [(t, v) for t, v in zip(structure.orders.input, f_in) if t.input == i]
            nest = [(t.lag, v) for t, v in zip(nested.orders.input, nl_in) if t.input == i]
            branches.append(([t for t, _ in full], [v for _, v in full], nest, group[2],
                             len(group[1]), len(ngroup[1]), group[3], ngroup[3]))
    for terms, values, nested_terms, n_basis, n_full, n_nest, at, n_at in branches:
        mapping = _term_map(terms, values, nested_terms)
        for j in range(n_basis):
            for i, src in enumerate(mapping):
                if src is not None:
                    out[at + j * n_full + i] = linear[n_at + j * n_nest + src]
    if structure.offset:
        out[lay.n_params] = linear[nlay.n_params]
    new_params = [float(free_values[name]) for name in structure.orders.free]
    if structure.past == "estimate":
        new_params += list(past)
    return out, np.array(new_params, dtype=float)


def _grid(lo, hi, n):
    return np.linspace(lo, hi, n)


def scan_starts(builder, base_params, lower, upper, criterion, *, n_points=SCAN_POINTS):
    """Starts from a coarse scan of the free orders: ``[Start]``, one per point scanned.

    At each point the equation-error theta of those orders (:class:`Profile`, one linear
    least-squares solve) and its free-run SSE (``criterion(linear, params)``). One free order:
    its grid. Several: the diagonal (every order at the same grid value, clipped into its
    bounds), then each order along its grid with the others at the best point so far. Past
    levels (``past="estimate"``) stay at ``base_params``'.
    """
    n_free = len(builder.structure.orders.free)
    profile = Profile(builder)
    base = np.array(base_params, dtype=float)
    out = []

    def visit(orders, name):
        params = base.copy()
        params[:n_free] = orders
        try:
            linear = profile(params)[0]
        except (ValueError, np.linalg.LinAlgError):
            return None
        start = Start(name, np.asarray(linear, dtype=float), params, criterion(linear, params))
        out.append(start)
        return start

    t = np.linspace(0.0, 1.0, n_points)
    for s in t:
        visit(lower + s * (upper - lower), "scan")
    if n_free > 1 and out:
        best = min(out, key=lambda st: st.sse)
        for j in range(n_free):
            point = best.params[:n_free].copy()
            for v in _grid(lower[j], upper[j], n_points):
                point[j] = v
                visit(point.copy(), "scan")
            best = min(out, key=lambda st: st.sse)
    return out


def choose_starts(candidates, n_starts, n_free, *, min_distance=0.05, second=None):
    """The ``n_starts`` best candidates by free-run SSE, their orders at least ``min_distance`` apart.

    The best candidate is always first, so the fit never ends above any candidate's criterion
    (the local search only descends). With ``n_starts >= 2``, the candidate named ``second``
    (the equation-error estimate in the default chain) comes next whatever its criterion: a
    start's free-run SSE does not tell which basin it lies in, and the standard chain of
    block-oriented identification always searches from the linear-in-theta fit (on the
    cascaded tanks, per-lag orders with estimated past levels, it ends at SSE 57.83 where the
    two better-ranked starts end at 63.23 and above). Starts whose free run diverged (SSE inf)
    are left out unless nothing else is left.
    """
    finite = sorted((c for c in candidates if np.isfinite(c.sse)), key=lambda c: c.sse)
    pool = finite or list(candidates)
    if second is not None and n_starts >= 2 and len(pool) > 1:
        named = [c for c in pool[1:] if c.name == second]
        if named:
            pool = [pool[0], named[0]] + [c for c in pool[1:] if c is not named[0]]
    chosen = []
    for c in pool:
        if len(chosen) == n_starts:
            break
        if any(np.max(np.abs(c.orders(n_free) - o.orders(n_free)), initial=0.0) < min_distance
               and c.name == o.name for o in chosen):
            continue
        chosen.append(c)
    for c in pool:                     # fewer distinct ones than asked: fill with the rest
        if len(chosen) == n_starts:
            break
        if all(c is not o for o in chosen):
            chosen.append(c)
    return chosen


def agreement(sses):
    """How many criteria lie within :data:`AGREEMENT_RTOL` of the smallest."""
    sses = np.asarray(sses, dtype=float)
    best = np.min(sses)
    return int(np.sum(sses <= best + AGREEMENT_RTOL * abs(best)))


@dataclass
class ChainResult:
    """What :func:`multi_start` found: the best local search, its start, and every start's record."""

    fit: object
    start: Start
    searches: list
    n_candidates: int


def multi_start(builder, bounds, *, nested_fit, equation_error, criterion, search, search_args=(),
                n_starts=1, executor=None):
    """The default chain: candidates, the best ``n_starts`` searched, the best result kept.

    Parameters
    ----------
    builder : RegressorBuilder
        The record and the class (with free orders).
    bounds : (ndarray, ndarray)
        Bounds of the free orders.
    nested_fit : callable
        ``nested_fit(structure) -> (linear, params, sse)`` or None: the simulation-error fit of
        a contained class (:func:`nested_structure`, :func:`tied_structure`).
    equation_error : callable
        ``() -> (linear, params)``: the equation-error (varpro) estimate of the class.
    criterion : callable
        ``criterion(linear, params) -> SSE`` of the free run (inf if it escapes).
    search : callable
        A module-level ``search(builder, linear0, params0, lower, upper, *search_args)`` that
        returns an object with ``sse`` (run on ``executor`` if one is given).
    n_starts : int
        Local searches.
    executor : concurrent.futures.Executor, optional
        Where to run them.

    Returns
    -------
    ChainResult
    """
    s = builder.structure
    lower, upper = bounds
    n_free = len(s.orders.free)
    candidates = []
    lin_ee, par_ee = equation_error()
    candidates.append(Start("equation error", np.asarray(lin_ee, dtype=float),
                            np.asarray(par_ee, dtype=float), criterion(lin_ee, par_ee)))
    scans = scan_starts(builder, par_ee, lower, upper, criterion)
    best_scan = min(scans, key=lambda c: c.sse) if scans else None
    # Orders 1 only where the scan points there (its best point on the upper bound 1): the
    # scan's end point already starts from its equation-error fit, and a simulation-error fit
    # of the orders-1 model costs as much as a search.
    at_one = best_scan is not None and np.all(best_scan.params[:n_free] == 1.0)
    for value, name in ((0.0, "nested integer model (orders 0)"),
                        (1.0, "nested integer model (orders 1)")):
        sub = nested_structure(s, value)
        if sub is None or np.any(lower > value) or np.any(upper < value) or (
                value == 1.0 and not at_one):
            continue
        got = nested_fit(sub)
        if got is None:
            continue
        lin_n, par_n, _ = got
        at = {o: value for o in s.orders.free}
        if any(not t.free for t in s.orders.output + s.orders.input) and best_scan is not None:
            # Fixed terms beside free ones (the mixed class): the free terms start at 0, so
            # any order gives the nested model; the scan's best order avoids the duplicate
            # columns at the order's own value.
            at = dict(zip(s.orders.free, best_scan.params[:n_free]))
        linear, params = embed(sub, lin_n, par_n, s, at)
        if s.past == "estimate":
            params[n_free:] = par_n[-2:]
        candidates.append(Start(name, linear, params, criterion(linear, params)))
    tied = tied_structure(s)
    if tied is not None and np.ptp(lower) == 0 and np.ptp(upper) == 0:
        got = nested_fit(tied)
        if got is not None:
            lin_t, par_t, _ = got
            at = {o: float(par_t[0]) for o in s.orders.free}
            linear, params = embed(tied, lin_t, par_t, s, at)
            candidates.append(Start("nested model with the orders tied", linear, params,
                                    criterion(linear, params)))
    candidates += scans
    chosen = choose_starts(candidates, n_starts, n_free, second="equation error")
    tasks = [(builder, c.linear, c.params, lower, upper, *search_args) for c in chosen]
    fits = run_tasks(search, tasks, executor=executor, label="starts")
    searches = []
    for c, f in zip(chosen, fits):
        if isinstance(f, TaskError):
            searches.append((c, None))
        else:
            searches.append((c, f))
    done = [(c, f) for c, f in searches if f is not None]
    if not done:
        raise RuntimeError("every local search failed to run: "
                           + "; ".join(f.message for f in fits if isinstance(f, TaskError)))
    best_start, best_fit = min(done, key=lambda cf: cf[1].sse)
    return ChainResult(best_fit, best_start, searches, len(candidates))
