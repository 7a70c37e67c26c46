"""Which equivalent circuit fits a cell's record: simulation-error least squares with a scan of the orders.

``fit_circuit(i, v, soc, h, elements=("zarc",))`` fits the circuit of
:mod:`fohw.model.circuit` by minimising the free-run simulation error ``sum (v_model - v)^2``
over its parameters, within physical bounds (resistances ``>= 0``, time constants in
``tau_bounds``, orders in ``alpha_bounds``), with the exact Jacobian (series derivatives):

1. **Scan.** For every combination of the elements' time constants and orders on a grid
   (``n_tau`` log-spaced time constants, ``n_alpha`` orders), the parameters that enter
   linearly (``a, b, R0, c3`` and the resistances) are solved by linear least squares (from one
   Gram matrix of all the grid's unit responses); combinations with a negative resistance are
   dropped. Without it, local searches of RC + ZARC mixtures were seen to end at ``alpha -> 1``
   (in a prototype fit of this record) or ``alpha -> 0``.
2. **Local search** from the ``n_starts`` best distinct grid points: ``scipy.optimize.least_squares``
   (trust-region reflective, bounds, the exact Jacobian; time constants searched in ``log tau``).
3. **Standard errors** from ``sigma^2 (J^T J)^-1``, ``sigma^2 = RSS / (n - d)``: they assume white
   residuals, which a drive cycle's are not (see :class:`CircuitFit`).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from .._validation import check_array, check_int, check_same_length, check_scalar
from ..exceptions import ParameterError
from ..model.circuit import ELEMENT_KINDS, RC, ZARC, EquivalentCircuit, Warburg

__all__ = ["CircuitFit", "fit_circuit", "circuit_template"]


@dataclass(frozen=True, repr=False)
class CircuitFit:
    """An equivalent circuit fitted by simulation error.

    Attributes
    ----------
    circuit : EquivalentCircuit
        The fitted circuit (with the ``ocv`` map it was fitted with).
    names : tuple of str
        The free parameters (``circuit.names`` without the ``fixed`` ones).
    stderr : dict
        Standard error of each free parameter, ``sigma^2 (J^T J)^-1`` with
        ``sigma^2 = RSS / (n - d)``; ``nan`` for a parameter at a bound. They assume white
        residuals: on a drive cycle the residuals are strongly correlated, so they are lower
        bounds of the real uncertainty.
    at_bound : tuple of str
        Free parameters that ended on a bound.
    fixed : dict
        Parameters held at given values.
    rss : float
        Residual sum of squares ``sum w (v_model - v)^2`` [V^2] (``w`` the sample weights, 1 by
        default).
    n : int
        Samples in the criterion (with a positive weight).
    h : float
        Sampling time [s].
    tau_bounds, alpha_bounds : tuple of float
    fit_time : float
        Wall-clock seconds (scan and local searches).
    nfev : int
        Simulations of the local searches (each with its Jacobian).
    converged : bool
        The best local search stopped on a tolerance, not on ``max_nfev``.
    message : str
    scan : list of (float, tuple)
        The best grid points: ``(rss, ((tau, alpha), ...))`` per element.
    residuals : ndarray
        ``v_model - v`` at every sample (unweighted).
    sample_weight : ndarray or None
        The weights the fit was given.
    """

    circuit: EquivalentCircuit
    names: tuple
    stderr: dict
    at_bound: tuple
    fixed: dict
    rss: float
    n: int
    h: float
    tau_bounds: tuple
    alpha_bounds: tuple
    fit_time: float
    nfev: int
    converged: bool
    message: str
    scan: list = field(default_factory=list)
    residuals: np.ndarray = field(default=None)
    sample_weight: np.ndarray | None = field(default=None)

    @property
    def n_params(self) -> int:
        """Free parameters ``d``."""
        return len(self.names)

    @property
    def rmse(self) -> float:
        """Root-mean-square simulation error [V]."""
        return math.sqrt(self.rss / self.n)

    @property
    def params(self) -> dict:
        """All parameters by name (free and fixed)."""
        return {n: float(x) for n, x in zip(self.circuit.names, self.circuit.values)}

    def predict(self, i, soc, h=None):
        """Simulated voltage of the fitted circuit for another record (``h`` defaults to the fit's)."""
        return self.circuit.simulate(i, soc, self.h if h is None else h)

    def summary(self) -> str:
        """A text table of the parameters with their standard errors."""
        lines = [f"{'+'.join(self.circuit.kinds) or 'R0 only'}"
                 f"{' + c3 i^3' if self.circuit.c3 is not None else ''}: RMSE "
                 f"{1e3 * self.rmse:.3f} mV, n = {self.n}, d = {self.n_params}, "
                 f"{self.fit_time:.2f} s"]
        for name, value in self.params.items():
            if name in self.fixed:
                lines.append(f"  {name:>8} = {value:.6g} (fixed)")
            else:
                se = self.stderr[name]
                flag = " (at bound)" if name in self.at_bound else ""
                lines.append(f"  {name:>8} = {value:.6g} +- {se:.3g}{flag}")
        return "\n".join(lines)

    def __repr__(self):
        return (f"CircuitFit({'+'.join(self.circuit.kinds) or 'R0 only'}, rmse={1e3 * self.rmse:.4g} mV, "
                f"d={self.n_params}, converged={self.converged})")


def circuit_template(elements, *, current_map=False, ocv=None):
    """A circuit with the given element kinds and placeholder values (a structure to fit).

    Parameters
    ----------
    elements : sequence of {"rc", "zarc", "warburg"}
    current_map : bool, optional
        Include the static current map ``c3 i^3``.
    ocv : callable or None, optional
        The known open-circuit voltage map.

    Returns
    -------
    EquivalentCircuit

    Examples
    --------
    >>> from fohw.estimators.circuit_fit import circuit_template
    >>> circuit_template(["rc", "zarc"], current_map=True).names
    ('a', 'b', 'R0', 'c3', 'R1', 'tau1', 'R2', 'tau2', 'alpha2')
    """
    if isinstance(elements, str):
        elements = (elements,)
    made = []
    for k, kind in enumerate(elements):
        if kind not in ELEMENT_KINDS:
            raise ParameterError(f"`elements[{k}]` must be one of {', '.join(ELEMENT_KINDS)}; "
                                 f"got {kind!r}.")
        made.append({"rc": RC(0.0, 1.0), "zarc": ZARC(0.0, 1.0, 0.5),
                     "warburg": Warburg(0.0, 0.5)}[kind])
    return EquivalentCircuit(made, r0=0.0, c3=0.0 if current_map else None, ocv=ocv)


def _grid(kind, tau_grid, alpha_grid, warburg_grid):
    if kind == "rc":
        return [(t, 1.0) for t in tau_grid]
    if kind == "zarc":
        return [(t, a) for t in tau_grid for a in alpha_grid]
    return [(None, a) for a in warburg_grid]


def _element(kind, R, tau, alpha):
    if kind == "rc":
        return RC(R, tau)
    if kind == "zarc":
        return ZARC(R, tau, alpha)
    return Warburg(R, alpha)


def _scan(template, i, soc, y, h, fixed, tau_grid, alpha_grid, warburg_grid, keep, sw):
    """Best grid points by linear least squares of the linear parameters."""
    kinds = template.kinds
    base = [np.ones_like(i), soc, i] + ([i ** 3] if template.c3 is not None else [])
    base_names = ["a", "b", "R0"] + (["c3"] if template.c3 is not None else [])
    grids = []
    for k, kind in enumerate(kinds, start=1):
        g = _grid(kind, tau_grid, alpha_grid, warburg_grid)
        if f"tau{k}" in fixed:
            g = [(fixed[f"tau{k}"], a) for a in sorted({a for _, a in g})]
        if f"alpha{k}" in fixed:
            g = [(t, fixed[f"alpha{k}"]) for t in sorted({t for t, _ in g}, key=lambda t: t or 0)]
        grids.append(g)
    responses = {}
    for kind, g in zip(kinds, grids):
        for tau, alpha in g:
            if (kind, tau, alpha) not in responses:
                e = _element(kind, 1.0, tau if tau is not None else 1.0, alpha)
                responses[(kind, tau, alpha)] = e.unit_response(i, h)
    keys = list(responses)
    cols = np.column_stack(base + [responses[k] for k in keys]) * sw[:, None]
    y = y * sw
    scale = np.sqrt(np.sum(cols ** 2, axis=0))
    scale[scale == 0] = 1.0
    cols = cols / scale
    gram = cols.T @ cols
    rhs = cols.T @ y
    yy = float(y @ y)
    nb = len(base)
    index = {k: nb + j for j, k in enumerate(keys)}
    found = []
    for combo in itertools.product(*grids):
        # Same-kind elements are interchangeable: keep their time constants increasing.
        if any(kinds[p] == kinds[q] and kinds[p] != "warburg" and combo[p][0] >= combo[q][0]
               for p in range(len(kinds)) for q in range(p + 1, len(kinds))):
            continue
        if any(kinds[p] == kinds[q] == "warburg" and combo[p][1] >= combo[q][1]
               for p in range(len(kinds)) for q in range(p + 1, len(kinds))):
            continue
        idx = list(range(nb)) + [index[(kinds[e], t, a)] for e, (t, a) in enumerate(combo)]
        names = base_names + [f"R{e + 1}" if kinds[e] != "warburg" else f"sigma{e + 1}"
                              for e in range(len(kinds))]
        free = [j for j, n in zip(idx, names) if n not in fixed]
        fix = [(j, fixed[n]) for j, n in zip(idx, names) if n in fixed]
        r = rhs[free] - sum((gram[free, j] * v * scale[j] for j, v in fix), np.zeros(len(free)))
        sub = gram[np.ix_(free, free)]
        try:
            c = np.linalg.solve(sub, r)
        except np.linalg.LinAlgError:
            continue
        coef = dict(zip([n for n in names if n not in fixed], c / scale[free]))
        if coef.get("R0", 0.0) < 0 or any(coef[n] < 0 for n in coef if n[0] in "Rs" and n != "R0"):
            continue
        full = np.zeros(len(idx))
        for p, (j, n) in enumerate(zip(idx, names)):
            full[p] = fixed[n] * scale[j] if n in fixed else coef[n] * scale[j]
        gsub = gram[np.ix_(idx, idx)]
        rss = yy - 2 * float(full @ rhs[idx]) + float(full @ gsub @ full)
        found.append((rss, tuple(combo), {**{n: fixed[n] for n in names if n in fixed}, **coef}))
    found.sort(key=lambda t: t[0])
    return found[:keep]


def _start_circuit(template, combo, coef):
    kinds = template.kinds
    elements = []
    for e, (kind, (tau, alpha)) in enumerate(zip(kinds, combo), start=1):
        r = coef[f"sigma{e}" if kind == "warburg" else f"R{e}"]
        elements.append(_element(kind, max(r, 0.0), tau if tau is not None else 1.0, alpha))
    return EquivalentCircuit(elements, r0=max(coef["R0"], 0.0), a=coef["a"], b=coef["b"],
                             c3=coef.get("c3") if template.c3 is not None else None,
                             ocv=template.ocv)


def _bounds(template, tau_bounds, alpha_bounds, warburg_alpha_bounds):
    """Lower and upper bounds of each parameter of the template, natural units."""
    lo, hi = [], []
    kinds = template.kinds
    for name in template.names:
        stem = name.rstrip("0123456789")
        k = int(name[len(stem):]) if name[len(stem):] else 0
        if name in ("a", "b", "c3"):
            lo.append(-np.inf)
            hi.append(np.inf)
        elif stem in ("R", "sigma") or name == "R0":
            lo.append(0.0)
            hi.append(np.inf)
        elif stem == "tau":
            lo.append(tau_bounds[0])
            hi.append(tau_bounds[1])
        elif stem == "alpha":
            b = warburg_alpha_bounds if kinds[k - 1] == "warburg" else alpha_bounds
            lo.append(b[0])
            hi.append(b[1])
    return np.array(lo), np.array(hi)


def fit_circuit(i, v, soc, h, elements=("zarc",), *, current_map=False, ocv=None, fixed=None,
                tau_bounds=None, alpha_bounds=(0.05, 1.0), warburg_alpha_bounds=(0.05, 0.95),
                n_tau=8, n_alpha=5, n_starts=3, max_nfev=200, start=None, sample_weight=None):
    """Fit an equivalent circuit to a record by free-run simulation error.

    Parameters
    ----------
    i, v, soc : array_like, shape (N,)
        Current [A], terminal voltage [V] and state of charge (coulomb count from the known
        initial state of charge).
    h : float
        Sampling time [s].
    elements : sequence of {"rc", "zarc", "warburg"}, optional
        The dynamic elements (default one ZARC); ``()`` is the R0-only circuit.
    current_map : bool, optional
        Add the static current map ``c3 i^3`` (default False).
    ocv : callable or None, optional
        The known open-circuit voltage ``OCV(soc)`` (e.g. ``BatteryCell.ocv``).
    fixed : dict, optional
        Parameters held at given values, by name (``{"alpha1": 1.0}``: the integer limit).
    tau_bounds : (float, float), optional
        Bounds of every time constant [s]; default ``(h, N h / 10)``.
    alpha_bounds : (float, float), optional
        Bounds of ZARC orders (default ``(0.05, 1.0)``).
    warburg_alpha_bounds : (float, float), optional
        Bounds of Warburg orders (default ``(0.05, 0.95)``).
    n_tau, n_alpha : int, optional
        Scan grid: log-spaced time constants in ``tau_bounds`` and orders (ZARC: up to 1;
        Warburg: inside its bounds). Default 8 and 5.
    n_starts : int, optional
        Local searches from the best distinct grid points (default 3).
    max_nfev : int, optional
        Evaluations per local search (default 200).
    start : EquivalentCircuit, optional
        Start the local search here instead of scanning (warm starts, profiles).
    sample_weight : array_like, shape (N,), optional
        Non-negative weights of the squared errors (default 1). Zeros hold samples back from
        the criterion while the simulation still runs through them (the circuit's state needs
        the whole current history): a held-back block inside the record.

    Returns
    -------
    CircuitFit

    Raises
    ------
    ParameterError
        Bad settings (names echo what arrived).

    Notes
    -----
    The elements start at rest at ``k = 0`` (zero current before the record); the known initial
    state of charge enters through ``soc``. The criterion is the free-run RSS; the Jacobian is
    exact (:meth:`fohw.model.circuit.EquivalentCircuit.jacobian`), time constants are searched
    in ``log tau``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.circuit import EquivalentCircuit, ZARC
    >>> from fohw.estimators.circuit_fit import fit_circuit
    >>> rng = np.random.default_rng(0)
    >>> i = np.repeat(rng.uniform(-3, 1, 60), 25)
    >>> soc = 0.8 + np.concatenate([[0], np.cumsum(i[:-1])]) / (3600 * 5)
    >>> true = EquivalentCircuit([ZARC(0.01, 40.0, 0.6)], r0=0.015, a=3.6, b=0.5)
    >>> fit = fit_circuit(i, true.simulate(i, soc, 1.0), soc, 1.0, tau_bounds=(1.0, 500.0))
    >>> [round(fit.params[n], 4) for n in ("R0", "R1", "tau1", "alpha1")]
    [0.015, 0.01, 40.0, 0.6]
    """
    t0 = time.perf_counter()
    i = check_array(i, "i")
    v = check_array(v, "v")
    soc = check_array(soc, "soc")
    check_same_length(i, v, "i", "v")
    check_same_length(i, soc, "i", "soc")
    h = check_scalar(h, "h", lower=0.0, lower_inclusive=False)
    n = i.shape[0]
    if tau_bounds is None:
        tau_bounds = (h, n * h / 10.0)
    tau_bounds = _pair(tau_bounds, "tau_bounds", lower=0.0)
    alpha_bounds = _pair(alpha_bounds, "alpha_bounds", lower=0.0, upper=1.0)
    warburg_alpha_bounds = _pair(warburg_alpha_bounds, "warburg_alpha_bounds", lower=0.0,
                                 upper=1.0)
    if warburg_alpha_bounds[1] >= 1.0:
        raise ParameterError("`warburg_alpha_bounds` must stay below 1 (order 1 is a capacitor, "
                             f"the b soc term); got {warburg_alpha_bounds!r}.")
    n_tau = check_int(n_tau, "n_tau", minimum=1)
    n_alpha = check_int(n_alpha, "n_alpha", minimum=1)
    n_starts = check_int(n_starts, "n_starts", minimum=1)
    max_nfev = check_int(max_nfev, "max_nfev", minimum=1)
    template = circuit_template(elements, current_map=current_map, ocv=ocv)
    fixed = dict(fixed or {})
    for name, value in fixed.items():
        if name not in template.names:
            raise ParameterError(f"`fixed` names {name!r}, which is not a parameter of this "
                                 f"circuit ({', '.join(template.names)}).")
        fixed[name] = check_scalar(value, f"fixed[{name!r}]")
    lo, hi = _bounds(template, tau_bounds, alpha_bounds, warburg_alpha_bounds)
    for name, value in fixed.items():
        j = template.names.index(name)
        if not lo[j] <= value <= hi[j]:
            raise ParameterError(f"`fixed[{name!r}]` = {value!r} is outside its bounds "
                                 f"[{lo[j]:g}, {hi[j]:g}].")
    if sample_weight is None:
        sw = np.ones(n)
    else:
        weight = check_array(sample_weight, "sample_weight")
        check_same_length(i, weight, "i", "sample_weight")
        if np.any(weight < 0) or not np.any(weight > 0):
            raise ParameterError("`sample_weight` must be non-negative with at least one positive "
                                 f"entry; got values from {weight.min()!r} to {weight.max()!r}.")
        sw = np.sqrt(weight)
    ocv_v = np.zeros(n) if ocv is None else np.asarray(ocv(soc), dtype=np.float64)
    y = v - ocv_v

    scan = []
    if start is None:
        tau_grid = np.geomspace(tau_bounds[0], tau_bounds[1], n_tau) if n_tau > 1 else \
            np.array([math.sqrt(tau_bounds[0] * tau_bounds[1])])
        alpha_grid = np.linspace(max(alpha_bounds[0], 0.2), alpha_bounds[1], n_alpha) \
            if n_alpha > 1 else np.array([alpha_bounds[1]])
        wb = warburg_alpha_bounds
        warburg_grid = np.linspace(max(wb[0], 0.2), wb[1], n_alpha) if n_alpha > 1 else \
            np.array([0.5 * (wb[0] + wb[1])])
        found = _scan(template, i, soc, y, h, fixed, tau_grid, alpha_grid, warburg_grid,
                      keep=n_starts, sw=sw)
        if not found:
            raise ParameterError("no grid point gave non-negative resistances; widen `tau_bounds`.")
        scan = [(rss, combo) for rss, combo, _ in found]
        starts = [_start_circuit(template, combo, coef) for _, combo, coef in found]
    else:
        if not isinstance(start, EquivalentCircuit) or start.kinds != template.kinds or \
                (start.c3 is None) != (template.c3 is None):
            raise ParameterError(f"`start` must be an EquivalentCircuit of the same structure "
                                 f"({'+'.join(template.kinds)}); got {start!r}.")
        starts = [EquivalentCircuit(start.elements, start.r0, start.a, start.b, start.c3, ocv=ocv)]

    names = template.names
    free = [j for j, nm in enumerate(names) if nm not in fixed]
    logs = np.array([names[j].startswith("tau") for j in free])

    def to_natural(p):
        full = np.empty(len(names))
        for j, nm in enumerate(names):
            if nm in fixed:
                full[j] = fixed[nm]
        q = p.copy()
        q[logs] = np.exp(p[logs])
        full[free] = q
        return full

    def fun_and_jac(p):
        circuit = template.with_values(to_natural(p))
        vm, jac = circuit.jacobian(i, soc, h)
        jac = jac[:, free] * sw[:, None]
        jac[:, logs] *= np.exp(p[logs])
        return (vm - v) * sw, jac

    cache = {}

    def fun(p):
        r, jac = fun_and_jac(p)
        cache["p"], cache["jac"] = p.copy(), jac
        return r

    def jac(p):
        if "p" in cache and np.array_equal(cache["p"], p):
            return cache["jac"]
        return fun_and_jac(p)[1]

    plo, phi = lo[free].copy(), hi[free].copy()
    plo[logs], phi[logs] = np.log(plo[logs]), np.log(phi[logs])
    best, nfev = None, 0
    for s in starts:
        x0 = s.values[free]
        p0 = np.clip(x0, lo[free], hi[free])
        p0[logs] = np.log(p0[logs])
        # Start strictly inside (TRF needs it): nudge by a small fraction of the range.
        width = np.where(np.isfinite(phi - plo), phi - plo, 1.0)
        p0 = np.minimum(np.maximum(p0, plo + 1e-6 * width), phi - 1e-6 * width)
        res = scipy.optimize.least_squares(fun, p0, jac=jac, bounds=(plo, phi), method="trf",
                                           x_scale="jac", max_nfev=max_nfev, xtol=1e-10,
                                           ftol=1e-12, gtol=1e-10)
        nfev += res.nfev
        if best is None or res.cost < best.cost:
            best = res
    values = to_natural(best.x)
    circuit = template.with_values(values)
    vm, full_jac = circuit.jacobian(i, soc, h)
    resid = vm - v
    rss = float(np.sum((resid * sw) ** 2))
    n_used = int(np.count_nonzero(sw))
    fnames = tuple(names[j] for j in free)
    at_bound = tuple(nm for nm, x, a, b in zip(fnames, values[free], lo[free], hi[free])
                     if (np.isfinite(a) and x <= a * (1 + 1e-6) + 1e-12) or
                     (np.isfinite(b) and x >= b * (1 - 1e-6)))
    stderr = _stderr(full_jac[:, free] * sw[:, None], rss, n_used, fnames, at_bound)
    return CircuitFit(circuit=circuit, names=fnames, stderr=stderr, at_bound=at_bound,
                      fixed=fixed, rss=rss, n=n_used, h=h, tau_bounds=tau_bounds,
                      alpha_bounds=alpha_bounds, fit_time=time.perf_counter() - t0, nfev=nfev,
                      converged=bool(best.status > 0), message=str(best.message), scan=scan,
                      residuals=resid, sample_weight=None if sample_weight is None else weight)


def _pair(value, name, *, lower=None, upper=None):
    try:
        a, b = (float(x) for x in value)
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be a pair (low, high); got {value!r}.") from None
    if not (np.isfinite(a) and np.isfinite(b) and a < b) or (lower is not None and a <= lower) or \
            (upper is not None and b > upper):
        rng = f" inside ({lower:g}, {upper:g}]" if upper is not None else f" above {lower:g}"
        raise ParameterError(f"`{name}` must be finite, increasing and{rng}; got {value!r}.")
    return (a, b)


def _stderr(jac, rss, n, names, at_bound):
    d = len(names)
    out = dict.fromkeys(names, float("nan"))
    keep = [k for k, nm in enumerate(names) if nm not in at_bound]
    if not keep or n <= d:
        return out
    sigma2 = rss / (n - d)
    jk = jac[:, keep]
    scale = np.sqrt(np.sum(jk ** 2, axis=0))
    scale[scale == 0] = 1.0
    try:
        cov = np.linalg.pinv((jk / scale).T @ (jk / scale)) / np.outer(scale, scale)
    except np.linalg.LinAlgError:
        return out
    for k, j in enumerate(keep):
        out[names[j]] = float(math.sqrt(max(sigma2 * cov[k, k], 0.0)))
    return out
