"""Simulation on non-uniform sampling instants (fohw.model.irregular, issue 35 item 2).

References are closed forms written without fohw (tests/irregular_reference.py): superposed
step and ramp responses of the RC element and of one fractional element
``1 / ((tau s)^alpha + 1)`` (``1 - E_alpha(-(t / tau)^alpha)``: erfcx at alpha = 1/2, the
Mittag-Leffler series of tests/tf_reference.py at alpha = 0.7).

The convergence checks assert the observed order of the fine-grid scheme between refine 16 and
128 (a factor 8 in the step). ``benchmarks/irregular_convergence.py`` measured that order over
10 sets of instants and inputs: 0.82-1.08 for every case (mean 0.95-1.03), so ``|order - 1| <
0.2`` holds each; an ``O(h^alpha)`` scheme (order 0.5, e.g. reading the output after the next
held value has acted) fails it.
"""

import importlib
import math

import numpy as np
import pytest
import scipy.signal
from irregular_reference import (
    foh_response,
    half_ramp,
    half_step,
    instants,
    rc_ramp,
    rc_step,
    zoh_response,
)
from tf_reference import mittag_leffler

import fohw
from fohw.model.irregular import (
    MAX_FINE_SAMPLES,
    fine_grid,
    jacobian_at,
    rc_response_at,
    resample,
    simulate_at,
)

# The protocol tests' kinds, from the module pytest already loads (``--import-mode=importlib``
# names it ``tests.test_model_protocol``; a second copy would register its kind twice).
KINDS = importlib.import_module("tests.test_model_protocol").KINDS

TAU = 0.5


def _record(seed=0, n=60):
    t = instants(n, seed)
    return t, np.random.default_rng(100 + seed).standard_normal(t.size)


def _order(model, u, t, hold, exact, coarse=16, fine=128):
    errs = [np.max(np.abs(simulate_at(model, u, t, intersample=hold, refine=r) - exact))
            for r in (coarse, fine)]
    return math.log(errs[0] / errs[1]) / math.log(fine / coarse), errs[1]


# --- the RC element: exact on any steps ----------------------------------------------------------
@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize("tau", [1e-3, 0.07, 5.0, 1e4])      # steps >> tau ... steps << tau
def test_rc_element_exact_to_rounding_on_irregular_steps(hold, tau):
    t = instants(200, 3, low=0.01, high=0.5) + 7.0
    i = np.random.default_rng(4).uniform(-3.0, 3.0, t.size)
    R = 0.02
    ref, size = ((zoh_response(t, i, rc_step(R, tau), magnitude=m) for m in (False, True))
                 if hold == "zoh" else
                 (foh_response(t, i, rc_step(R, tau), rc_ramp(R, tau), magnitude=m)
                  for m in (False, True)))
    x = rc_response_at(R, tau, i, t, hold)
    # The superposition's own rounding is eps times the sum of its terms' sizes (the ramps of
    # the first-order hold cancel: up to 1e3 times the result); the recursion's is smaller.
    err = np.abs(x - ref)
    assert np.all(err <= 4 * np.finfo(float).eps * size + 1e-16), np.max(err / size)


def test_rc_element_on_uniform_instants_against_lsim():
    # scipy.signal.lsim holds U[k] on [T[k], T[k+1]); fohw's u_k stands for (t_{k-1}, t_k]
    # (u_0 for the first step before t_0): the same input is U = u on T = t - dt.
    dt, R, tau = 0.3, 0.5, 0.8
    t = 2.0 + dt * np.arange(40)
    i = np.random.default_rng(5).standard_normal(40)
    T = np.concatenate([[t[0] - dt], t])
    _, x, _ = scipy.signal.lsim(([R], [tau, 1.0]), np.concatenate([i, [0.0]]), T - T[0],
                                interp=False)
    np.testing.assert_allclose(rc_response_at(R, tau, i, t), x[1:], rtol=0, atol=1e-14)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_circuit_of_rc_branches_exact_on_irregular_steps(hold):
    # R0, the OCV map, a + b soc and two RC branches: every term exact at any steps.
    t = instants(150, 6, low=0.2, high=3.0)
    rng = np.random.default_rng(7)
    i = np.repeat(rng.uniform(-4.0, 2.0, 30), 5)
    soc = 0.6 + 0.1 * np.sin(t / 50.0)
    ocv = fohw.OCVTable([0.0, 0.5, 1.0], [3.2, 3.6, 4.1])
    cell = fohw.EquivalentCircuit([fohw.RC(0.01, 2.0), fohw.RC(0.02, 40.0)], r0=0.015, a=0.01,
                                  b=-0.02, ocv=ocv, dt=1.0)
    branch = ((lambda R, tau: zoh_response(t, i, rc_step(R, tau))) if hold == "zoh" else
              (lambda R, tau: foh_response(t, i, rc_step(R, tau), rc_ramp(R, tau))))
    ocv_ref = np.interp(soc, [0.0, 0.5, 1.0], [3.2, 3.6, 4.1])
    ref = ocv_ref + 0.01 - 0.02 * soc + 0.015 * i + branch(0.01, 2.0) + branch(0.02, 40.0)
    v = simulate_at(cell, np.column_stack([i, soc]), t, intersample=hold)
    size = 4.2 + 0.015 * np.abs(i) + sum(
        zoh_response(t, i, rc_step(R, tau), magnitude=True) if hold == "zoh" else
        foh_response(t, i, rc_step(R, tau), rc_ramp(R, tau), magnitude=True)
        for R, tau in ((0.01, 2.0), (0.02, 40.0)))
    err = np.abs(v - ref)
    assert np.all(err <= 8 * np.finfo(float).eps * size), np.max(err / size)


# --- the GL-based kinds: first order against the closed form -------------------------------------
def test_fractional_tf_first_order_zoh_and_foh():
    t, u = _record()
    G = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0], dt=0.1)
    S, Q = (lambda x: half_step(x, TAU)), (lambda x: half_ramp(x, TAU))
    order, err = _order(G, u, t, "zoh", zoh_response(t, u, S))
    assert abs(order - 1.0) < 0.2 and err < 2e-3, (order, err)      # measured 0.824, 1.5e-3
    order, err = _order(G, u, t, "foh", foh_response(t, u, S, Q))
    assert abs(order - 1.0) < 0.2 and err < 5e-3, (order, err)      # measured 1.078, 3.6e-3


def test_fractional_tf_first_order_at_alpha_07():
    t, u = _record(seed=1)
    G = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.7, 1.0], [0.7, 0.0], dt=0.1)

    def S(x):
        x = np.asarray(x, float)
        return np.where(x > 0, 1.0 - mittag_leffler(0.7, -(np.maximum(x, 0.0) / TAU) ** 0.7), 0.0)
    order, err = _order(G, u, t, "zoh", zoh_response(t, u, S))
    assert abs(order - 1.0) < 0.2 and err < 2e-3, (order, err)


def test_fractional_hw_first_order():
    t, u = _record(seed=2)
    G = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0])
    hw = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=2, output_params=[-0.2],
                           dt=0.1)
    x = zoh_response(t, u + 0.3 * u ** 2, lambda s: half_step(s, TAU))
    order, err = _order(hw, u, t, "zoh", x - 0.2 * x ** 2)
    assert abs(order - 1.0) < 0.2 and err < 3e-3, (order, err)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_circuit_zarc_first_order(hold):
    t, u = _record(seed=3)
    i, soc = 2.0 * u, np.full(t.size, 0.5)
    cell = fohw.EquivalentCircuit([fohw.ZARC(0.01, TAU, 0.5), fohw.RC(0.005, 0.3)], r0=0.015,
                                  a=3.7, dt=0.1, tau_bounds=(0.01, 100.0))
    S, Q = (lambda x: half_step(x, TAU)), (lambda x: half_ramp(x, TAU))
    resp = ((lambda s, q: zoh_response(t, i, s)) if hold == "zoh" else
            (lambda s, q: foh_response(t, i, s, q)))
    exact = 3.7 + 0.015 * i + 0.01 * resp(S, Q) + resp(rc_step(0.005, 0.3), rc_ramp(0.005, 0.3))
    order, err = _order(cell, np.column_stack([i, soc]), t, hold, exact)
    assert abs(order - 1.0) < 0.2 and err < 1e-4, (order, err)


def test_input_delay_on_irregular_instants():
    # exp(-0.25 s) / ((0.5 s)^0.5 + 1): the step divides the delay; the closed form is shifted.
    # A delayed switch arrives at t_m + 0.25, between instants: an instant just after one sees
    # the start of a step response, O(h^alpha) (seed 4 has one 1e-5 s after an arrival: its
    # error stays 5e-3 down to refine 512). First order holds 0.02 s away from arrivals.
    t, u = _record(seed=4)
    G = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0], dt=0.05, delay=0.25)
    exact = zoh_response(t, u, lambda x: half_step(x - 0.25, TAU))
    starts = np.concatenate([[2 * t[0] - t[1]], t[:-1]]) + 0.25
    lag = t[:, None] - starts[None, :]
    far = np.where(lag > 0, lag, np.inf).min(axis=1) > 0.02
    assert 40 < far.sum() < t.size
    errs = [np.max(np.abs(simulate_at(G, u, t, refine=r) - exact)[far]) for r in (16, 128)]
    order = math.log(errs[0] / errs[1]) / math.log(8)
    assert abs(order - 1.0) < 0.2 and errs[1] < 3e-3, (order, errs)     # measured 0.987, 1.9e-3


# --- every kind: the uniform limit, the refusal -----------------------------------------------------
@pytest.mark.parametrize("factory", KINDS, ids=lambda f: f.__name__)
def test_every_kind_on_uniform_instants_is_its_own_simulate(factory):
    true, _, u, _, _ = factory()
    t = 3.0 + true.dt * np.arange(np.shape(u)[0])
    if isinstance(true, (fohw.HammersteinWiener, fohw.ThetaHW)):     # the lagged kind
        with pytest.raises(fohw.ParameterError, match=r"discrete in samples.*resample.*FractionalTF"):
            simulate_at(true, u, t)
        return
    # refine 1 on uniform instants: the kind's own simulation, bit for bit
    np.testing.assert_array_equal(simulate_at(true, u, t, refine=1), true.simulate(u))
    # refined, the same continuous-time input: within the coarse simulation's own GL error
    fine = simulate_at(true, u, t, refine=8)
    finer = simulate_at(true, u, t, refine=16)
    coarse_err = np.max(np.abs(true.simulate(u) - finer))
    assert np.max(np.abs(fine - finer)) < coarse_err


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_jacobian_at_against_finite_differences(hold):
    t, u = _record(seed=5, n=30)
    G = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0], dt=0.1)
    hw = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=2, output_params=[-0.2])
    for model in (G, hw):
        yhat, J = jacobian_at(model, u, t, intersample=hold)
        np.testing.assert_array_equal(yhat, simulate_at(model, u, t, intersample=hold))
        for c, (name, par) in enumerate(model.parameters.items()):
            if par.fixed:                               # beta0 = alpha1 = 0 sit on their bounds
                continue
            d = 1e-6 * max(1.0, abs(par.value))
            up = simulate_at(model.with_parameters({name: par.value + d}), u, t, intersample=hold)
            down = simulate_at(model.with_parameters({name: par.value - d}), u, t,
                               intersample=hold)
            np.testing.assert_allclose(J[:, c], (up - down) / (2 * d), atol=1e-7, err_msg=name)
    cell = fohw.EquivalentCircuit([fohw.RC(0.01, 2.0)], dt=1.0)
    assert jacobian_at(cell, np.column_stack([u, np.full(u.size, 0.5)]), t) is None


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_held_input_of_several_columns_is_each_column_held(hold):
    t, u = _record(seed=7, n=40)
    u2 = np.column_stack([u, np.cos(t)])
    grid = fine_grid(t, refine=3)
    both = grid.hold(u2, t, hold)
    np.testing.assert_array_equal(both[:, 0], grid.hold(u, t, hold))
    np.testing.assert_array_equal(both[:, 1], grid.hold(np.cos(t), t, hold))
    # the mean over each fine interval keeps the integral of the held input exactly
    if hold == "zoh":
        t_ext = np.concatenate([[2 * t[0] - t[1]], t])
        total = u[0] * (t[1] - t[0]) + np.sum(u[1:] * np.diff(t))
        assert grid.t0 - grid.step <= t_ext[0] < grid.t0     # the first fine interval holds it
        k_end = grid.position(t[-1])[0]                  # the last point, in (t[-2], t[-1]]
        tau_end = grid.times[k_end]
        assert t[-2] < tau_end <= t[-1]
        np.testing.assert_allclose(np.sum(both[:k_end + 1, 0]) * grid.step,
                                   total - u[-1] * (t[-1] - tau_end), rtol=1e-12)


def test_a_kind_without_a_step_is_refused_naming_resample():
    class Gain(fohw.Model, register=False):
        @property
        def parameters(self):
            return fohw.Parameters([fohw.Parameter("k", 2.0)])

        def with_parameters(self, values):
            return self

        def simulate(self, u, *, initial=None):
            return 2.0 * self.check_input(u)

    with pytest.raises(fohw.ParameterError, match=r"no sampling time.*resample"):
        simulate_at(Gain(), np.ones(3), [0.0, 1.0, 2.5])


@pytest.mark.parametrize("t, kwargs, match", [
    ([0.0, 1.0, 1.0], {}, r"`t` must be strictly increasing; got t\[1\] = 1.0"),
    ([0.0, 1.0, np.nan], {}, "`t` must contain only finite"),
    ([0.0, 1.0], {}, "`t` must have one instant per sample: 3; got 2"),
    ([0.0, 1.0, 2.0], {"intersample": "linear"}, "`intersample` must be one of"),
    ([0.0, 1.0, 2.0], {"refine": 2, "step": 0.1}, "give `refine` or `step`, not both"),
    ([0.0, 1.0, 2.0], {"refine": 0}, "`refine` must be at least 1"),
    ([0.0, 1.0, 2.0], {"step": 5.0}, "`step` must be at most the span"),
    ([0.0, 1.0, 2.0], {"step": 1e-7}, f"more than {MAX_FINE_SAMPLES}"),
])
def test_bad_instants_and_options_are_refused(t, kwargs, match):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    with pytest.raises((fohw.ParameterError, fohw.DimensionError), match=match):
        simulate_at(G, np.ones(3), t, **kwargs)


def test_resample_holds_the_input_and_interpolates_the_output():
    t = np.array([0.0, 0.9, 2.1, 3.0])
    u = np.array([1.0, 2.0, 3.0, 4.0])
    y = np.array([0.0, 0.9, 2.1, 3.0])                # y = t: interpolation is exact
    t_new, u_new, y_new = resample(t, u, y, dt=1.0)
    np.testing.assert_array_equal(t_new, [0.0, 1.0, 2.0, 3.0])
    # zoh: u_k on (t_{k-1}, t_k]: 1.0 lies in (0.9, 2.1] -> 3, 2.0 too, 3.0 is t_3 -> 4
    np.testing.assert_array_equal(u_new, [1.0, 3.0, 3.0, 4.0])
    np.testing.assert_allclose(y_new, t_new, rtol=0, atol=1e-15)
    _, u_foh = resample(t, u, dt=1.0, intersample="foh")
    np.testing.assert_allclose(u_foh, [1.0, 2.0 + 0.1 / 1.2, 2.0 + 1.1 / 1.2, 4.0])


# --- a fit on irregularly sampled data ------------------------------------------------------------
def _recovers(fit, true, n_se=3.0):
    assert fit.status == fohw.Status.CONVERGED, fit.message
    se = fit.standard_errors()
    z = {n: (fit.parameters[n].value - true.parameters[n].value) / se[n] for n in fit.free_names}
    assert all(abs(v) < n_se for v in z.values()), z
    return z


def test_fit_on_irregular_instants_recovers_a_fractional_tf():
    # 400 instants, steps uniform in [0.05, 0.15]; the record's instants reach fohw.fit, which
    # simulates on them (simulate_at) with the fine grid's exact Jacobian (jacobian_at).
    t = instants(400, 0)
    u = np.repeat(np.random.default_rng(0).standard_normal(80), 5)
    true = fohw.FractionalTF([2.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0], dt=0.1)
    y = simulate_at(true, u, t) + 0.01 * np.random.default_rng(50).standard_normal(t.size)
    record = fohw.Record(u=u, y=y, t=t)
    assert not record.uniform
    fit = fohw.fit(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.7, 0.0], dt=0.1), record)
    assert fit.jacobian == "exact"
    _recovers(fit, true)
    # the same samples read as uniform (the instants dropped) fit a different model
    wrong = fohw.fit(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.7, 0.0], dt=0.1), u, y)
    assert wrong.sse > 4 * fit.sse


def test_fit_on_irregular_instants_recovers_a_circuit():
    # A cell logged at irregular instants (steps 0.5-1.5 s), current held between them (foh):
    # R0 and an RC branch exact, a ZARC on the fine grid; finite differences of simulate_at.
    t = instants(600, 1, low=0.5, high=1.5)
    i = np.repeat(np.random.default_rng(2).uniform(-3.0, 1.5, 40), 15)
    soc = 0.7 + np.concatenate([[0.0], np.cumsum(i[1:] * np.diff(t))]) / (3600 * 2.5)
    u = np.column_stack([i, soc])
    ocv = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
    true = fohw.EquivalentCircuit([fohw.RC(0.006, 8.0), fohw.ZARC(0.012, 60.0, 0.55)],
                                  r0=0.015, ocv=ocv, tau_bounds=(1.0, 600.0))
    y = simulate_at(true, u, t, intersample="foh")
    y = y + 1e-4 * np.random.default_rng(3).standard_normal(t.size)
    record = fohw.Record(u=u, y=y, t=t, intersample="foh")
    start = fohw.EquivalentCircuit(["rc", "zarc"], ocv=ocv, tau_bounds=(1.0, 600.0))
    fit = fohw.fit(start, record)
    assert fit.jacobian == "finite differences"
    _recovers(fit, true)


def test_circuit_warburg_first_order():
    # sigma s^-alpha: the step response sigma x^alpha / Gamma(1 + alpha), superposed.
    t, u = _record(seed=6)
    cell = fohw.EquivalentCircuit([fohw.Warburg(0.01, 0.5)], dt=0.1)
    exact = zoh_response(t, u, lambda x: np.where(np.asarray(x) > 0, 0.01 * np.maximum(x, 0.0)
                                                  ** 0.5 / math.gamma(1.5), 0.0))
    order, err = _order(cell, np.column_stack([u, np.full(t.size, 0.5)]), t, "zoh", exact)
    assert abs(order - 1.0) < 0.2 and err < 1e-4, (order, err)
