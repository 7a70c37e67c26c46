"""fohw.fit of a fractional transfer function: exact Jacobian, free/fixed/tied parameters,
Warburg orders, delays, bounds, bad input, honest statuses, and the Cramér–Rao bound over seeds.

The model comes before the estimator: its simulation is checked against a literal GL loop in
test_transfer_function.py, its Jacobian against central differences of that simulation here.
"""

import numpy as np
import pytest

import fohw
from fohw.estimators.fit import free_jacobian
from fohw.exceptions import DimensionError, ParameterError


def _model(num_orders, den_orders, dt, *, num=None, den=None, delay=0.0, free=None, ties=None,
           bounds=None):
    """A start model; ``free`` names the estimated parameters (the rest fixed), ``ties`` and
    ``bounds`` as ``{name: (source, factor)}`` and ``{name: (low, high)}``."""
    num = np.ones(len(num_orders)) if num is None else num
    den = np.ones(len(den_orders)) if den is None else den
    G = fohw.FractionalTF(num, num_orders, den, den_orders, dt=dt, delay=delay)
    p = G.parameters
    if free is not None:
        for name in p:
            p = p.replace(name, fixed=name not in free)
    for target, tie in (ties or {}).items():
        p = p.replace(target, fixed=False, tie=tie)
    for name, bound in (bounds or {}).items():
        p = p.replace(name, bounds=bound)
    return G.with_parameters(p)


def _fit(model, u, y, **options):
    return fohw.fit(model, u, y, **options)


def _value(fit, name):
    return fit.parameters[name].value


# ---------------------------------------------------------------- the model's Jacobian
SPECS = [
    dict(num=[1.0, 0.5], num_orders=[0.0, -0.5], den=[2.0, 1.0], den_orders=[0.6, 0.0],
         free=["b0", "b1", "beta1", "a0", "alpha0"]),
    dict(num=[1.0], num_orders=[0.0], den=[1.0, 0.7, 1.0], den_orders=[1.3, 0.5, 0.0],
         free=["b0", "a0", "a1", "alpha0", "alpha1"]),
    dict(num=[1.0], num_orders=[0.0], den=[1.0, 0.7, 1.0], den_orders=[1.0, 0.5, 0.0],
         free=["b0", "a1", "alpha1"], ties={"alpha0": ("alpha1", 2.0)}),
    dict(num=[1.0], num_orders=[0.0], den=[1.0, 1.0], den_orders=[1.0, 0.0], free=["alpha0"]),   # integer
]


def _terms(values, m, k):
    return ([values[f"b{j}"] for j in range(m)], [values[f"beta{j}"] for j in range(m)],
            [values[f"a{i}"] for i in range(k)], [values[f"alpha{i}"] for i in range(k)])


@pytest.mark.parametrize("spec", SPECS)
@pytest.mark.parametrize("h", [0.05, 1.0])
def test_jacobian_equals_central_differences(spec, h):
    """Every column (fixed parameters too, except denominator orders at 0, which cannot move
    below 0) against central differences of FractionalTF(...).simulate; the free Jacobian through
    the ties against differences in the free parameters."""
    spec = dict(spec)
    model = _model(spec.pop("num_orders"), spec.pop("den_orders"), h, **spec)
    m, k = model.config()["n_num"], model.config()["n_den"]
    u = np.random.default_rng(3).standard_normal(300)
    yhat, jac = model.jacobian(u)
    np.testing.assert_allclose(yhat, model.simulate(u), rtol=0, atol=1e-12 * np.max(np.abs(yhat)))
    values = model.parameters.valuesdict()
    eps = 1e-6
    for col, name in enumerate(model.parameters):
        if name.startswith("alpha") and values[name] == 0.0:
            continue
        plus, minus = dict(values), dict(values)
        plus[name] += eps
        minus[name] -= eps
        ref = (fohw.FractionalTF(*_terms(plus, m, k)).simulate(u, dt=h)
               - fohw.FractionalTF(*_terms(minus, m, k)).simulate(u, dt=h)) / (2 * eps)
        np.testing.assert_allclose(jac[:, col], ref, rtol=0, atol=1e-7 * np.max(np.abs(ref)),
                                   err_msg=name)
    params = model.parameters
    x = params.free_values()
    _, free_jac, how = free_jacobian(model, u)
    assert how == "exact"
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = eps
        ref = (model.with_parameters(params.with_free(x + e)).simulate(u)
               - model.with_parameters(params.with_free(x - e)).simulate(u)) / (2 * eps)
        np.testing.assert_allclose(free_jac[:, j], ref, rtol=0, atol=1e-7 * np.max(np.abs(ref)))


def test_parameters_follow_the_terms_as_given_and_the_default_preset():
    G = fohw.FractionalTF([0.5, 1.0], [-0.5, 0.0], [1.0, 2.0], [0.0, 0.6], dt=0.1)
    p = G.parameters
    assert p.names == ("b0", "b1", "beta0", "beta1", "a0", "a1", "alpha0", "alpha1")
    assert [p[n].value for n in p] == [0.5, 1.0, -0.5, 0.0, 1.0, 2.0, 0.0, 0.6]
    # every coefficient but the lowest-order denominator one (a0 here), every non-zero order
    assert p.free_names == ("b0", "b1", "beta0", "a1", "alpha1")
    assert p["beta0"].bounds == fohw.model.transfer.NUM_ORDER_RANGE == (-2.0, 2.0)
    assert p["alpha1"].bounds == fohw.model.orders.ORDER_RANGE == (0.0, 2.0)
    # an order given beyond the range widens its own bound to it
    assert fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [2.5, 0.0]).parameters["alpha0"].bounds == (0.0, 2.5)
    again = fohw.Model.from_dict(G.to_dict())
    assert again == G and again.parameters == p and str(again) == str(G)
    with pytest.raises(ParameterError, match="must be None or 'rest'"):
        G.simulate(np.ones(5), initial="estimate")
    np.testing.assert_array_equal(G.simulate(np.ones(5), initial="rest"), G.simulate(np.ones(5)))


def test_linear_start_solves_the_coefficients_or_gives_none():
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    u = np.random.default_rng(6).standard_normal(300)
    start = _model([0.0], [0.6, 0.0], 0.05, bounds={"a0": (0.0, 1.5)})
    solved = start.linear_start(u, G.simulate(u))        # a0 = 2 solved, clipped to its bound
    assert solved.parameters["a0"].value == 1.5 and solved.parameters["a0"].bounds == (0.0, 1.5)
    exact = _model([0.0], [0.6, 0.0], 0.05).linear_start(u, G.simulate(u))
    np.testing.assert_allclose([exact.parameters[n].value for n in ("b0", "a0")], [1.0, 2.0],
                               rtol=1e-9)
    assert _model([0.0], [0.6, 0.0], 0.05, free=["alpha0"]).linear_start(u, u) is None
    assert start.linear_start(u, np.full(300, 1e300)) is None         # its equations overflow


# ---------------------------------------------------------------- fits
def test_noiseless_two_term_non_commensurate_system_is_recovered():
    G = fohw.FractionalTF([1.5], [0.0], [0.8, 1.2, 1.0], [1.4, 0.45, 0.0])
    u = np.random.default_rng(0).standard_normal(1500)
    y = G.simulate(u, dt=0.05)
    fit = _fit(_model([0.0], [1.0, 0.6, 0.0], 0.05, bounds={"a0": (0, np.inf), "a1": (0, np.inf)}),
               u, y)
    # The two fractional terms may come back under either label (a0 s^alpha0 + a1 s^alpha1 is
    # symmetric in them): the model, its terms merged and sorted by order, is what is recovered.
    est = fit.model
    np.testing.assert_allclose(np.r_[est.num, est.den, est.den_orders],
                               [1.5, 0.8, 1.2, 1.0, 1.4, 0.45, 0.0], rtol=1e-6)
    assert fit.converged and fit.noise_variance < 1e-16


def test_commensurate_tie_and_fixed_orders():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 0.6, 1.0], [1.4, 0.7, 0.0])
    u = np.random.default_rng(1).standard_normal(1000)
    y = G.simulate(u, dt=0.05)
    fit = _fit(_model([0.0], [1.0, 0.5, 0.0], 0.05, free=["b0", "a0", "a1", "alpha1"],
                      ties={"alpha0": ("alpha1", 2.0)}), u, y)
    assert _value(fit, "alpha1") == pytest.approx(0.7, rel=1e-6)
    assert _value(fit, "alpha0") == 2 * _value(fit, "alpha1")
    se = fit.standard_errors()
    assert set(se) == {"b0", "a0", "a1", "alpha1", "alpha0"}
    assert se["alpha0"] == pytest.approx(2 * se["alpha1"], rel=1e-12)    # the tie's delta method
    assert fit.parameters["alpha0"].tie == ("alpha1", 2.0)
    # coefficients only ("n" mode of FOMCON's fid): orders stay where they were given
    fit = _fit(_model([0.0], [1.4, 0.7, 0.0], 0.05, free=["b0", "a0", "a1"]), u, y)
    assert _value(fit, "alpha0") == 1.4 and _value(fit, "a1") == pytest.approx(0.6, rel=1e-6)


def test_warburg_numerator_order_of_negative_sign():
    """Z(s) = R + sigma s^-nu (a resistance and a Warburg element): current in, voltage out."""
    Z = fohw.FractionalTF([0.2, 0.05], [0.0, -0.5], [1.0], [0.0])
    rng = np.random.default_rng(2)
    u = rng.standard_normal(2000)
    y = Z.simulate(u, dt=1.0) + 1e-3 * rng.standard_normal(2000)
    fit = _fit(_model([0.0, -0.3], [0.0], 1.0, num=[0.1, 0.1], free=["b0", "b1", "beta1"],
                      bounds={"b0": (0, np.inf), "b1": (0, np.inf), "beta1": (-1, 0)}), u, y)
    se = fit.standard_errors()
    for name, true in (("b0", 0.2), ("b1", 0.05), ("beta1", -0.5)):
        assert abs(_value(fit, name) - true) < 4 * se[name]


def test_the_lowest_sse_among_candidate_delays_is_the_true_delay():
    """Candidate delays are candidate models (the delay is the model's setting, not a parameter):
    fitted each, the one of lowest simulation error is the truth's."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], delay=0.3)
    rng = np.random.default_rng(4)
    u = rng.standard_normal(800)
    y = G.simulate(u, dt=0.1) + 0.01 * rng.standard_normal(800)
    fits = [_fit(_model([0.0], [0.5, 0.0], 0.1, delay=d), u, y, order_grid=3, n_starts=1)
            for d in (0.0, 0.1, 0.2, 0.3, 0.4)]
    best = min(fits, key=lambda f: f.sse)
    assert best.model.delay == pytest.approx(0.3)
    assert abs(_value(best, "alpha0") - 0.8) < 4 * best.standard_errors()["alpha0"]


def test_bounds_hold_the_estimate():
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    u = np.random.default_rng(5).standard_normal(500)
    y = G.simulate(u, dt=0.05)
    fit = _fit(_model([0.0], [0.3, 0.0], 0.05, bounds={"alpha0": (0.1, 0.5)}), u, y)
    assert 0.1 <= _value(fit, "alpha0") <= 0.5
    assert _value(fit, "alpha0") == pytest.approx(0.5, abs=1e-6)


def test_bad_input_names_the_argument():
    u = np.ones(50)
    G = _model([0.0], [0.5, 0.0], 0.1)
    with pytest.raises(DimensionError, match="`u` and `y`"):
        fohw.fit(G, u, np.ones(49))
    with pytest.raises(ParameterError, match="`y` must contain only finite"):
        fohw.fit(G, u, np.r_[np.ones(49), np.nan])
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) \['a7'\]"):
        G.with_parameters({"a7": 1.0})
    with pytest.raises(ParameterError, match="outside its bounds"):
        _model([0.0], [0.5, 0.0], 0.1, bounds={"alpha0": (0.6, 0.9)})
    with pytest.raises(ParameterError, match="`delay` must be a multiple"):
        _model([0.0], [0.5, 0.0], 0.1, delay=0.25)
    with pytest.raises(ParameterError, match="`dt`"):
        _model([0.0], [0.5, 0.0], 0.0)
    with pytest.raises(ParameterError, match="no sampling time"):
        fohw.fit(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), u, np.arange(50.0))
    with pytest.raises(DimensionError, match="`den`"):
        fohw.FractionalTF([1.0], [0.0], [1.0], [0.5, 0.0], dt=0.1)
    with pytest.raises(ParameterError, match="not itself tied"):
        _model([0.0], [1.0, 0.5, 0.0], 0.1, ties={"alpha1": ("a0", 1.0), "alpha0": ("alpha1", 2.0)})


# ---------------------------------------------------------------- honest statuses
@pytest.fixture(scope="module")
def record():
    """1 / (2 s^0.6 + 1), white input, 1 % output noise, N = 400."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    y = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0]).simulate(u, dt=0.05)
    return u, y + 0.01 * rng.standard_normal(u.size)


def test_a_zero_input_or_a_constant_output_is_refused(record):
    u, y = record
    G = _model([0.0], [0.5, 0.0], 0.05)
    with pytest.raises(ParameterError, match="`u` is zero at every sample"):
        fohw.fit(G, np.zeros_like(u), y)
    with pytest.raises(ParameterError, match="`y` is constant"):
        fohw.fit(G, u, np.full_like(y, 0.3))


def test_a_scale_left_free_is_rank_deficient_and_named(record):
    """Every coefficient free: numerator and denominator scale together without changing G."""
    u, y = record
    G = _model([0.0], [0.5, 0.0], 0.05, free=["b0", "a0", "a1", "alpha0"])
    with pytest.warns(fohw.RankDeficiencyWarning, match="not identifiable"):
        fit = fohw.fit(G, u, y)
    assert fit.status == fohw.Status.RANK_DEFICIENT and fit.covariance is None
    assert "rank 3 of 4" in fit.message
    named = fit.message.split("the columns of ")[1].split(" are linear")[0].split(", ")
    assert len(named) == 1 and named[0] in {"b0", "a0", "a1"}


def test_an_order_without_its_coefficient_is_rank_deficient_and_named(record):
    """beta1 multiplies b1 = 0 (fixed): the output does not depend on it at all."""
    u, y = record
    G = _model([0.0, 0.5], [0.5, 0.0], 0.05, num=[1.0, 0.0], free=["b0", "beta1", "a0", "alpha0"])
    with pytest.warns(fohw.RankDeficiencyWarning, match="the columns of beta1 are"):
        fit = fohw.fit(G, u, y)
    assert fit.status == fohw.Status.RANK_DEFICIENT


class _UphillTF(fohw.FractionalTF, register=False):
    """A transfer function whose Jacobian has the wrong sign: every Gauss-Newton step climbs."""

    def jacobian(self, u):
        yhat, jac = super().jacobian(u)
        return yhat, -jac

    def with_parameters(self, values):
        G = super().with_parameters(values)
        return _UphillTF(*_terms(G.parameters.valuesdict(), 1, 2), dt=G.dt, delay=G.delay)


def test_a_fit_stuck_at_its_start_is_failed(record):
    """No step lowers the simulation error (the search ends where it started): FAILED and a
    ConvergenceWarning, never CONVERGED (fit_fractional_tf counted scipy's xtol stop as converged)."""
    u, y = record
    G = _UphillTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05)
    with pytest.warns(fohw.ConvergenceWarning, match="stuck at its start"):
        fit = fohw.fit(G, u, y, order_grid=1, n_starts=1)
    assert fit.status == fohw.Status.FAILED
    assert fit.sse == pytest.approx(fit.starts[0][1], rel=1e-9)


# ---------------------------------------------------------------- accuracy
@pytest.mark.slow
def test_free_order_and_coefficients_reach_the_crb_over_seeds():
    """1/(a s^alpha + 1) with b, a, alpha free: the mean squared error over seeds within 1.2x the
    CRB. The ratio of an empirical to a true variance has sampling sd ~ sqrt(2 / (n - 1)) (0.14
    for 100 seeds), so the test allows 1.2 + 2 sd above and 1 - 3 sd below. The CRB is
    sigma^2 (J^T J)^-1 with J the exact free Jacobian at the truth."""
    h, n, sigma, n_seeds = 0.05, 1000, 0.05, 100
    truth = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=h)
    u = np.random.default_rng(100).standard_normal(n)
    y0 = truth.simulate(u)
    _, jac, _ = free_jacobian(truth, u)
    crb = sigma ** 2 * np.linalg.inv(jac.T @ jac)
    names = truth.parameters.free_names
    assert names == ("b0", "a0", "alpha0")
    true = np.array([1.0, 2.0, 0.6])
    errors, se2 = [], []
    for seed in range(n_seeds):
        y = y0 + sigma * np.random.default_rng(seed).standard_normal(n)
        fit = fohw.fit(_model([0.0], [0.5, 0.0], h), u, y, order_grid=3, n_starts=1)
        errors.append([_value(fit, k) for k in names] - true)
        se2.append([fit.standard_errors()[k] ** 2 for k in names])
    errors = np.array(errors)
    ratio = np.mean(errors ** 2, axis=0) / np.diag(crb)
    sd = np.sqrt(2 / (n_seeds - 1))
    print("MSE / CRB:", ratio, "mean reported variance / CRB:", np.mean(se2, axis=0) / np.diag(crb))
    assert np.all(ratio < 1.2 + 2 * sd), ratio
    assert np.all(ratio > 1 - 3 * sd), ratio
    # the reported standard errors estimate the CRB (on average over seeds; each is evaluated at
    # its own estimate, where J differs from J at the truth)
    np.testing.assert_allclose(np.mean(se2, axis=0) / np.diag(crb), 1.0, atol=3 * sd)


def test_a_fit_round_trips_through_its_dict(record):
    """The fitted model (its terms, dt, delay and the fit's bounds) comes back exactly."""
    u, y = record
    G = _model([0.0], [0.5, 0.0], 0.05, delay=0.1, bounds={"a0": (0.0, 10.0)})
    fit = fohw.fit(G, u, y)
    again = fohw.FitResult.from_dict(fit.to_dict())
    assert again.model == fit.model and again.parameters["a0"].bounds == (0.0, 10.0)
    assert again.model.delay == 0.1 and again.model.dt == 0.05
    np.testing.assert_array_equal(again.simulate(u), fit.simulate(u))


def test_an_order_tied_to_a_coefficient_is_refused():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05)
    with pytest.raises(fohw.ParameterError, match="a tie joins two orders or two coefficients"):
        G.with_parameters(G.parameters.replace("alpha0", tie=("a0", 1.0)))
    tied = G.parameters.replace("b0", tie=("a0", 2.0))           # two coefficients: fine
    assert G.with_parameters(tied).parameters["b0"].value == 2.0
