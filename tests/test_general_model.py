"""The paper's general model (Eqs. 7, 14) before any estimator touches it (issue 10).

An order per term (0 included), tied and fixed orders, offset, past levels, sampling time and
operating point: the simulator against the literal reference of tests/reference.py at every
sample, the regression identity ``y = Phi(params) [theta, c] + v``, exact derivatives against
finite differences, the static gain computed by hand, and bad input.
"""

import numpy as np
import pytest
import reference
from models import MODELS

import fohw


def lin():
    return fohw.polynomial_basis(1)




@pytest.mark.parametrize("name", sorted(MODELS))
def test_simulator_equals_literal_reference_at_every_sample(name):
    model = MODELS[name]()
    rng = np.random.default_rng(7)
    u = rng.uniform(-1, 1, 90) + model.operating_point[0]
    v = 0.05 * rng.standard_normal(90)
    got = fohw.simulate(model, u, noise=v)
    np.testing.assert_allclose(got, reference.simulate_general(model, u, v), rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["mixed", "past", "offset_dt_point"])
def test_simulation_continues_from_a_measured_history(name):
    model = MODELS[name]()
    rng = np.random.default_rng(3)
    u_hist = rng.uniform(-1, 1, 40) + model.operating_point[0]
    y_hist = rng.uniform(-1, 1, 40) + model.operating_point[1]
    u = rng.uniform(-1, 1, 50) + model.operating_point[0]
    got = fohw.simulate(model, u, initial=(u_hist, y_hist))
    want = reference.simulate_general(model, u, np.zeros(50), history=(u_hist, y_hist))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(set(MODELS) - {"paper"}))
def test_fast_simulator_equals_direct_for_general_models(name, monkeypatch):
    from fohw.model.lagged import simulation

    model = MODELS[name]()
    u = np.random.default_rng(1).uniform(-1, 1, 700) + model.operating_point[0]
    direct = fohw.simulate(model, u)
    monkeypatch.setattr(simulation, "FAST_SIMULATION_THRESHOLD", 100)   # divide and conquer
    fast = fohw.simulate(model, u)
    np.testing.assert_allclose(fast, direct, rtol=0, atol=1e-11)


def _linear_params(model):
    lin_params = model.theta
    if model.structure.offset:
        lin_params = np.r_[lin_params, model.offset]
    return lin_params


def _nonlinear_params(model):
    values = list(model.orders.values())
    if model.structure.past == "estimate":
        values += list(model.past)
    return np.array(values)


@pytest.mark.parametrize("name", sorted(set(MODELS) - {"offset_dt_point"}))
def test_regression_identity_holds_for_every_structure(name):
    """y - Phi(params) @ [theta, c] is the noise at every sample (deviation coordinates)."""
    model = MODELS[name]()
    rng = np.random.default_rng(11)
    u = rng.uniform(-1, 1, 600)
    v = 0.05 * rng.standard_normal(600)
    y = fohw.simulate(model, u, noise=v)
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, structure=model.structure)
    Phi = b.matrix(_nonlinear_params(model))
    np.testing.assert_allclose(y - Phi @ _linear_params(model), v, rtol=0, atol=1e-12)


def test_regression_identity_with_offset_dt_and_operating_point():
    model = MODELS["offset_dt_point"]()
    rng = np.random.default_rng(12)
    u = 2.0 + rng.uniform(-1, 1, 600)
    v = 0.05 * rng.standard_normal(600)
    y = fohw.simulate(model, u, noise=v)
    b = fohw.model.lagged.regressors.RegressorBuilder(u - 2.0, y - 5.0, structure=model.structure)
    Phi = b.matrix(_nonlinear_params(model))
    np.testing.assert_allclose(y - 5.0 - Phi @ _linear_params(model), v, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["per_lag", "custom", "past", "offset_dt_point"])
def test_matrix_derivatives_match_central_differences(name):
    model = MODELS[name]()
    rng = np.random.default_rng(2)
    u = rng.uniform(-1, 1, 400)
    y = fohw.simulate(model, u + model.operating_point[0], noise_std=0.05, random_state=0) \
        - model.operating_point[1]
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, structure=model.structure)
    params = _nonlinear_params(model)
    for m, exact in enumerate(b.matrix_derivatives(params)):
        step = 1e-6 * max(1.0, abs(params[m]))
        hi, lo = params.copy(), params.copy()
        hi[m] += step
        lo[m] -= step
        fd = (b.matrix(hi) - b.matrix(lo)) / (2 * step)
        np.testing.assert_allclose(exact, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(exact).max()),
                                   err_msg=b.structure.nonlinear_names[m])


def test_commensurate_step_response_decays_like_k_to_minus_alpha():
    """SPEC §8: y[k] = 0.5 (Delta^a y)[k-1] + (Delta^a u)[k-1] under a unit step.

    The integer model (alpha = 0) settles at 1 / (1 - 0.5) = 2; for alpha > 0 there is no
    static gain: at k = 5000 the response is 1.96 (alpha = 0.001), 0.50 (0.1), 0.003 (0.6), and
    it decays like k**-alpha (log-log slope -alpha).
    """
    step = np.ones(5001)
    finals = {}
    for alpha in (0.0, 0.001, 0.1, 0.6):
        y = fohw.simulate(fohw.HammersteinWiener([0.5], [1.0], [1.0], [1.0], alpha), step)
        finals[alpha] = y[5000]
        if alpha >= 0.1:
            slope = np.log(y[5000] / y[2500]) / np.log(2.0)
            assert slope == pytest.approx(-alpha, abs=0.02 + 0.1 * alpha)
    assert finals[0.0] == pytest.approx(2.0, abs=1e-12)
    assert finals[0.001] == pytest.approx(1.96, abs=0.005)
    assert finals[0.1] == pytest.approx(0.50, abs=0.005)
    assert finals[0.6] == pytest.approx(0.003, abs=0.0005)


def test_mixed_step_response_settles_at_the_hand_computed_gain():
    """Mixed model: order-0 terms carry the static gain, fractional terms vanish at rest.

    y = 0.5 y(k-1) + 0.2 (Delta^0.5 y)(k-1) + 1.0 u(k-1) + 0.4 (Delta^0.5 u)(k-1) + 0.3:
    at rest ybar = 0.5 ybar + 1.0 ubar + 0.3, so a unit step settles at (1.0 + 0.3) / 0.5 = 2.6.
    The fractional terms approach 0 like k**-0.5, so y(k) - 2.6 ~ C k**-0.5.
    """
    model = fohw.HammersteinWiener([0.5, 0.2], [1.0, 0.4], [1.0], [1.0], 0.5, orders="mixed",
                                   offset=0.3)
    assert model.static_gain(1.0) == pytest.approx(2.6, rel=1e-15)
    y = fohw.simulate(model, np.ones(40001))
    err = y - 2.6
    # err * sqrt(k) tends to a constant: the same at k = 10^4 and 4 * 10^4 within 1 %.
    assert err[40000] * np.sqrt(40000) == pytest.approx(err[10000] * np.sqrt(10000), rel=0.01)
    assert abs(err[40000]) < 0.01
    # With operating point (u0, y0), the gain acts on deviations.
    shifted = fohw.HammersteinWiener([0.5, 0.2], [1.0, 0.4], [1.0], [1.0], 0.5, orders="mixed",
                                     offset=0.3, operating_point=(4.0, 10.0))
    assert shifted.static_gain(5.0) == pytest.approx(12.6, rel=1e-15)


def test_orders_spellings():
    o = fohw.Orders.resolve("mixed", na=2, nb=1)
    assert o.free == ("alpha",) and o.a_names == ("a1_0", "a1_alpha", "a2_0", "a2_alpha")
    assert fohw.Orders.resolve({"a": [(0, "alpha"), (0, "alpha")], "b": [(0, "alpha")]},
                               na=2, nb=1) == o
    per_lag = fohw.Orders.resolve("per_lag", na=2, nb=1)
    assert per_lag.free == ("alpha_a1", "alpha_a2", "alpha_b1")
    assert fohw.Orders.resolve("commensurate", na=2, nb=2).is_commensurate
    assert not fohw.Orders.resolve(0, na=2, nb=2).free
    tied = fohw.Orders.from_lags(a=["nu", "nu"], b=[(0, "mu")])
    assert tied.free == ("nu", "mu") and tied.values({"nu": 0.3, "mu": 0.9}) == (
        (0.3, 0.3), (0.0, 0.9))
    assert fohw.Orders.from_dict(tied.to_dict()) == tied


@pytest.mark.parametrize("call, match", [
    (lambda: fohw.Orders.resolve("fractional", na=1, nb=1), r"`orders` must be one of"),
    (lambda: fohw.Orders.resolve(2.5, na=1, nb=1), r"must be in \[0, 2\]; got 2.5"),
    (lambda: fohw.Orders.from_lags(a=[-0.1], b=[0]),
     r"`orders`: the order of term 0 of branch 'a' must be in \[0, 2\]; got -0.1"),
    (lambda: fohw.Orders.from_lags(a=[(0, 0)], b=[0]), r"has the term \(lag 1, order 0"),
    (lambda: fohw.Orders([(0, 0.5)], [(1, 0.5)]),
     r"the lag of term 0 of branch 'a' must be an integer >= 1; got 0"),
    (lambda: fohw.Orders.resolve({"a": [0.5]}, na=1, nb=1), r"needs exactly the keys 'a' and 'b'"),
    (lambda: fohw.Orders.resolve({"a": [0.5, 0.5], "b": [0.5]}, na=1, nb=1),
     r"uses lags up to 2 \(output\)"),
    (lambda: fohw.HammersteinWiener([0.1, 0.2], [1.0], [1], [1], {"alpha": 0.5, "beta": 0.2},
                                    orders=fohw.Orders.from_lags(a=["alpha", "alpha"], b=["alpha"])),
     r"unknown \['beta'\]"),
    (lambda: fohw.HammersteinWiener([0.1], [1.0], [1], [1], 0.5, orders="per_lag"),
     r"one number, but there are 2 free orders"),
    (lambda: fohw.HammersteinWiener([0.1], [1.0], [1], [1], 0.5, orders="mixed"),
     r"`a` and `b` need even lengths"),
    (lambda: fohw.HammersteinWiener([0.1], [1.0], [1], [1], 0.5, dt=0.0), r"`dt` must be in \(0"),
    (lambda: fohw.HammersteinWiener([0.1], [1.0], [1], [1], 0.5, past=(1.0,)),
     r"`past` must be a pair"),
])
def test_bad_structure_input(call, match):
    with pytest.raises(fohw.ParameterError, match=match):
        call()
