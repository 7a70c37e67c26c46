"""output_error's solver: its exact Jacobian, then the fits it reaches.

The model before the estimator: the Jacobian the solver is given (the exact sensitivity of the
free run, scaled as the solver sees it) must be the derivative of the residual it is given, on
the paper's model and on structures with several orders, an order at 0, an offset, dt, past
levels, a non-polynomial g and a left-out start-up; then fits with it must reach the optimum
that scipy's finite differences (the former path, kept in ``tests/reference_estimators.py``) reach.
"""

import contextlib

import numpy as np
import pytest
from reference_estimators import finite_difference_output_error

import fohw
from fohw.estimators import output_error as oe
from fohw.estimators._common import rms_scale
from fohw.exceptions import SimulationDivergedError
from fohw.model.lagged.regressors import RegressorBuilder

EPS = np.finfo(float).eps


def tanh(x):
    return np.tanh(x)


MODELS = {
    "paper": (lambda: fohw.datasets.paper_model(), 0),
    "mixed_offset_dt_tanh": (lambda: fohw.HammersteinWiener(
        [0.3, -0.2, 0.1, 0.05], [0.6, 0.2], [1, 0.4], [1, 0.5], {"alpha": 0.5},
        g_basis={"y": lambda x: x, "tanh": tanh}, orders="mixed", offset=0.1, dt=0.5), 30),
    "per_lag_order_at_0": (lambda: fohw.HammersteinWiener(
        [0.3], [1.0, 0.4], [1.0, 0.2], [1.0, -0.1],
        {"alpha_a1": 0.0, "alpha_b1": 0.6, "alpha_b2": 1.2}, orders="per_lag"), 0),
    "past_levels": (lambda: fohw.HammersteinWiener(
        [0.3, 0.2], [1.0, 0.5], [1.0], [1.0], 0.5, orders="mixed", past=(0.6, -0.4)), 10),
}


def _criterion(model, n=700, n_init=0, seed=3):
    s = model.structure
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    y = fohw.simulate(model, u) + 0.05 * rng.standard_normal(n)
    d = s.n_linear + s.n_nonlinear
    crit = oe.SimulationResidual(s, u, y, n_init, np.full(d, -np.inf), np.full(d, np.inf))
    return crit, u, y, rng


@pytest.mark.parametrize("case", sorted(MODELS))
def test_the_solver_jacobian_is_the_derivative_of_the_solver_residual(case):
    """Central differences with step h and 2h at a point off the truth (free orders kept in
    [0, 2], one of them at 0). The difference is bounded by the truncation error, estimated by
    Richardson as |D(h) - D(2h)| (= 3/4 of D(2h)'s, 3 times D(h)'s), plus rounding: a residual
    evaluated with absolute error at most N eps max|y| (a recursion summing N terms of size
    max|y|) gives D(h) an error of at most that over h."""
    make, n_init = MODELS[case]
    model = make()
    s = model.structure
    crit, u, y, rng = _criterion(model, n_init=n_init)
    x = np.r_[model.linear, model.nonlinear] + 0.02 * rng.standard_normal(
        s.n_linear + s.n_nonlinear)
    free = slice(s.n_linear, s.n_linear + len(s.orders.free))
    x[free] = np.clip(x[free], 0.0, 2.0)
    if case == "per_lag_order_at_0":
        assert x[free][0] == 0.0
    scale = oe._parameter_scale(x, s, u, y)
    residual, jacobian = crit.scaled(scale, rms_scale(y))
    z = x / scale
    J = jacobian(z)
    assert J.shape == (y.size - n_init, z.size)
    n_before = crit.n_simulations

    def central(step):
        cols = []
        for i in range(z.size):
            e = np.zeros_like(z)
            e[i] = step[i]
            cols.append((residual(z + e) - residual(z - e)) / (2 * step[i]))
        return np.column_stack(cols)

    h = 1e-5 * np.maximum(np.abs(z), 1e-2)
    d1, d2 = central(h), central(2 * h)
    assert crit.n_simulations == n_before + 4 * z.size      # one run per residual
    rounding = y.size * EPS * np.max(np.abs(y)) / rms_scale(y) / h
    tol = np.max(np.abs(d1 - d2), axis=0) + rounding
    size = np.max(np.abs(J), axis=0)
    assert np.all(tol < 1e-5 * size), tol / size             # the check has power
    assert np.all(np.max(np.abs(J - d1), axis=0) <= tol), np.max(np.abs(J - d1), axis=0) / tol


def test_the_jacobian_is_zero_where_the_residual_is_the_penalty():
    """Where the free run escapes, the residual is a constant and its derivative zero, both when
    the sensitivity's own simulation stops (an unstable model) and when it does not (a stable,
    linear-output model whose output exceeds ten times the measured one)."""
    for model, block, factor, stops in (
            (fohw.datasets.paper_model(), "output", 4.0, True),
            (fohw.HammersteinWiener([0.5, -0.2], [1.0], [1.0, 0.3], [1.0], 0.6), "input", 100.0,
             False)):
        crit, u, y, _ = _criterion(model)
        x = np.r_[model.linear, model.nonlinear]
        k, n = model.layout.n_output_params, model.layout.n_params
        point = x.copy()
        point[slice(0, k) if block == "output" else slice(k, n)] *= factor
        assert np.any(crit.jacobian(x))
        try:
            y_sim, _ = fohw.model.lagged.sensitivity.simulation_jacobian(model.structure, point[:n],
                                                                  point[n:], u)
            assert not stops and np.max(np.abs(y_sim)) > crit.guard
        except SimulationDivergedError:
            assert stops
        assert np.array_equal(crit.residual(point), crit.penalty)
        J = crit.jacobian(point)
        assert J.shape == (y.size, x.size) and not np.any(J)


def _fit_both(u, y, jacobians=("2-point", "exact"), n_init=0, **kw):
    start = fohw.identify(u, y, method="varpro", **kw)
    s = start.structure
    u0, y0 = start.operating_point
    builder = RegressorBuilder(u - u0, y - y0, structure=s)
    bounds = kw.get("alpha_bounds", (0.0, 1.0))
    lower = np.full(len(s.orders.free), bounds[0])
    upper = np.full(len(s.orders.free), bounds[1])
    fits = []
    for j in jacobians:
        with finite_difference_output_error() if j == "2-point" else contextlib.nullcontext():
            fits.append(oe.fit_output_error(builder, start.linear, start.nonlinear, lower=lower,
                                            upper=upper, n_init=n_init, max_nfev=100))
    return s, fits


def _same_optimum(s, a, b, m):
    """scipy stops when a step lowers the cost by less than ftol (1e-8) of it, so each end
    point's cost is within about ftol of the minimum: the SSEs agree to 2 ftol, and the
    parameters (those not on a bound) differ by at most 2 sqrt(ftol (m - d)) in the metric of
    the covariance s^2 (S^T S)^-1 (a cost excess dF = dx^T S^T S dx / 2 <= ftol F, with
    s^2 = 2 F / (m - d))."""
    ftol = 1e-8
    assert a.status == b.status == fohw.Status.CONVERGED
    assert abs(a.sse - b.sse) <= 2 * ftol * a.sse, (a.sse, b.sse)
    assert np.array_equal(a.at_lower, b.at_lower) and np.array_equal(a.at_upper, b.at_upper)
    n_lin = s.n_linear
    keep = np.ones(n_lin + s.n_nonlinear, dtype=bool)
    keep[n_lin:n_lin + len(s.orders.free)] = ~(a.at_lower | a.at_upper)
    bound = slice(n_lin, n_lin + len(s.orders.free))
    assert np.array_equal(np.r_[a.linear, a.params][bound][~keep[bound]],
                          np.r_[b.linear, b.params][bound][~keep[bound]])
    d = (np.r_[a.linear, a.params] - np.r_[b.linear, b.params])[keep]
    cov = a.covariance[np.ix_(keep, keep)]
    distance = float(np.sqrt(d @ np.linalg.solve(cov, d)))
    assert distance <= 2 * np.sqrt(ftol * (m - keep.size)), distance


FITS = {
    "paper": lambda: _paper(dict(alpha_bounds=(0.0, 1.0))),
    "paper_alpha_at_bound": lambda: _paper(dict(alpha_bounds=(0.0, 0.3))),
    "mixed_offset_operating_point_n_init": lambda: _mixed(),
    "per_lag": lambda: _per_lag(),
}


def _paper(kw):
    d = fohw.datasets.paper_example(800, random_state=0)
    m = d.model
    return d.u, d.y, dict(na=2, nb=2, f_basis=m.f_basis, g_basis=m.g_basis, **kw), 0


def _mixed():
    model = fohw.HammersteinWiener([0.3, 0.4], [1.0, 0.5, 0.3, -0.2], [1.0, 0.3], [1.0, -0.2],
                                   0.4, orders="mixed", offset=0.5)
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 800)
    y = fohw.simulate(model, u, noise_std=0.05, random_state=1)
    return (u + 2.0, 3.0 + y, dict(na=2, nb=2, f_basis=2, g_basis=2, orders="mixed", offset=True,
                                   operating_point=(2.0, 3.0), alpha_bounds=(0.0, 1.5)), 20)


def _per_lag():
    model = fohw.HammersteinWiener([0.3], [1.0, 0.4], [1.0, 0.2], [1.0, -0.1],
                                   {"alpha_a1": 0.35, "alpha_b1": 0.6, "alpha_b2": 0.8},
                                   orders="per_lag")
    u = np.random.default_rng(1).uniform(-1, 1, 800)
    y = fohw.simulate(model, u, noise_std=0.02, random_state=2)
    return u, y, dict(na=1, nb=2, f_basis=2, g_basis=2, orders="per_lag",
                      alpha_bounds=(0.0, 1.5)), 0


@pytest.mark.parametrize("case", sorted(FITS))
def test_exact_and_finite_difference_jacobians_reach_the_same_optimum(case):
    u, y, kw, n_init = FITS[case]()
    s, (fd, exact) = _fit_both(u, y, n_init=n_init, **kw)
    _same_optimum(s, fd, exact, y.size - n_init)
    if case == "paper_alpha_at_bound":
        assert exact.at_upper[0] and exact.params[0] == 0.3
    # The point of the exact Jacobian: one run (and a sensitivity) per Jacobian, not d + 1.
    assert exact.nfev < fd.nfev / 2, (exact.nfev, fd.nfev)


def test_where_the_sensitivity_stops_the_jacobian_falls_back_to_forward_differences(
        monkeypatch):
    """The sensitivity's simulation stopping where the residual's does not (a gain beyond 1e7,
    not met in practice) is forced here: the Jacobian is then the forward difference of the
    residual, and the fit still reaches the optimum."""
    u, y, kw, _ = _paper(dict(alpha_bounds=(0.0, 1.0)))
    s, (exact,) = _fit_both(u, y, jacobians=("exact",), **kw)

    def stops(*args, **kwargs):
        raise SimulationDivergedError(5, 1e30, 1.0)

    monkeypatch.setattr(oe, "simulation_jacobian", stops)
    upper = np.r_[np.full(10, np.inf), 1.0]
    crit = oe.SimulationResidual(s, u, y, 0, np.r_[np.full(10, -np.inf), 0.0], upper)
    x = np.r_[exact.linear, exact.params]
    r = crit.residual(x)
    J = crit.jacobian(x)
    step = np.sqrt(EPS) * np.maximum(np.abs(x), 1.0)
    for i in range(x.size):
        xi = x.copy()
        xi[i] = x[i] + step[i] if x[i] + step[i] <= upper[i] else x[i] - step[i]   # inwards
        np.testing.assert_array_equal(J[:, i], (crit.residual(xi) - r) / (xi[i] - x[i]))
    _, (fallback,) = _fit_both(u, y, jacobians=("exact",), **kw)
    _same_optimum(s, exact, fallback, y.size)


def test_a_start_that_escapes_after_shrinking_is_a_failed_fit():
    """Shrinking the start's output parameters cannot tame an input branch 1e6 times too large:
    scipy then met a zero Jacobian at the penalty and stopped, and the fit said CONVERGED."""
    model = fohw.datasets.paper_model()
    crit, u, y, _ = _criterion(model)
    s = model.structure
    builder = RegressorBuilder(u, y, structure=s)
    k, n = model.layout.n_output_params, model.layout.n_params
    start = model.linear.copy()
    start[k:n] *= 1e6
    fit = oe.fit_output_error(builder, start, model.nonlinear, lower=np.array([0.0]),
                              upper=np.array([1.0]))
    assert fit.status == fohw.Status.FAILED
    assert "free run of the estimate escapes" in fit.message
