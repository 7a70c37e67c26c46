"""The alternating driver: contracts, errors, convergence reporting and golden runs."""

import warnings

import numpy as np
import pytest

import fohw
from fohw.estimators.hybrid import HybridIdentifier, HybridOptions
from fohw.estimators.migd import MultiInnovationGradient
from fohw.estimators.rls import MultiInnovationRLS, RlsOptions
from fohw.model.lagged.regressors import RegressorBuilder

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


@pytest.fixture(scope="module")
def data2000():
    return fohw.datasets.paper_example(2000, random_state=0)


def paper_identify(u, y, **kw):
    """The paper's methods (default: the hybrid) on the paper's structure."""
    kw.setdefault("method", "hybrid")
    return fohw.identify(u, y, **{**STRUCT, **kw})


# Golden values: our own seeded runs (paper_example(2000, random_state=0)), recorded when the
# driver was written, to catch drift. They are not the paper's numbers.
GOLDEN_RECURSIVE_P5 = dict(
    theta=[0.00684582826264101, 0.00195175258853691, -0.03718258438912721, 0.00133468644585263,
           0.04016228276372388, 0.00429318065167809, -0.32574943934544703, -0.10302674537717035,
           -0.13769025457300957, -0.03840861873949784],
    alpha=0.4413516274473501, J=0.029220984981830553)
GOLDEN_ITERATIVE_RECORD = dict(
    theta=[-0.0714638841438226, 0.18455280057854057, 0.02635840962733589, 0.07227692660906304,
           -0.00713967992212338, 0.06778159285331206, -0.404627823408371, -0.27880023664046355,
           -0.21481352688505226, -0.1460610009297715],
    alpha=0.6044781813087945, J=0.011781340983699042, n_iter=38)


def test_golden_recursive_hybrid(data2000):
    res = paper_identify(data2000.u, data2000.y, innovation_length=5)
    np.testing.assert_allclose(res.theta, GOLDEN_RECURSIVE_P5["theta"], rtol=1e-9, atol=1e-12)
    assert res.alpha == pytest.approx(GOLDEN_RECURSIVE_P5["alpha"], rel=1e-10)
    assert res.J == pytest.approx(GOLDEN_RECURSIVE_P5["J"], rel=1e-10)
    assert (res.nit, res.converged, res.schedule) == (1, False, "recursive")
    assert res.status == fohw.Status.NOT_TESTED


def test_golden_iterative_record_window(data2000):
    # The golden state after exactly 38 outer iterations (a fixed count: whether the stopping
    # rule fires at 37, 38 or 39 may differ between BLAS builds; the state at 38 may not).
    kw = dict(method="hybrid", schedule="iterative", alpha_window="record", restart_r=True)
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 38"):
        fixed = fohw.identify(data2000.u, data2000.y, max_iter=38, tol=1e-12, **kw, **STRUCT)
    assert fixed.status == fohw.Status.MAX_ITER and fixed.nit == 38
    np.testing.assert_allclose(fixed.theta, GOLDEN_ITERATIVE_RECORD["theta"], rtol=1e-9,
                               atol=1e-12)
    assert fixed.alpha == pytest.approx(GOLDEN_ITERATIVE_RECORD["alpha"], rel=1e-10)
    assert fixed.J_history.shape == (38,) and fixed.alpha_history[-1] == fixed.alpha
    # With the default tol the stopping rule (Step 9) ends the run: its criterion is met.
    res = fohw.identify(data2000.u, data2000.y, max_iter=100, **kw, **STRUCT)
    assert res.converged and res.status == fohw.Status.CONVERGED and "converged" in res.message
    J = res.J_history
    assert abs(J[-1] - J[-2]) / J[-2] <= 1e-4 < abs(J[-2] - J[-3]) / J[-3]


def test_iterative_J_is_eq_41(data2000):
    import reference

    u, y = data2000.u[:300], data2000.y[:300]
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 3"):
        res = paper_identify(u, y, schedule="iterative", max_iter=3)
    yhat = reference.one_step_prediction(u, y, res.theta, res.alpha, **STRUCT)
    np.testing.assert_allclose(res.predict(u, y), yhat, rtol=0, atol=1e-12)
    assert res.J == pytest.approx(np.mean((y - yhat) ** 2), rel=1e-10)


def test_stopping_at_max_iter_warns_and_says_so(data2000):
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 3"):
        res = fohw.identify(data2000.u, data2000.y, method="hybrid", schedule="iterative",
                            max_iter=3, tol=1e-12, **STRUCT)
    assert not res.converged and res.nit == 3 and "max_iter = 3" in res.message
    assert res.status == fohw.Status.MAX_ITER and res.nfev == 3
    # One pass of Table 1 does not test convergence by design: no warning, status NOT_TESTED.
    res = fohw.identify(data2000.u[:300], data2000.y[:300], method="hybrid", **STRUCT)
    assert not res.converged and res.status == fohw.Status.NOT_TESTED
    assert "one pass only" in res.message


def test_single_innovation_gradient_is_hybrid_with_P1(data2000):
    a = paper_identify(data2000.u, data2000.y, method="single_innovation_gradient")
    b = paper_identify(data2000.u, data2000.y, method="hybrid", innovation_length=1)
    np.testing.assert_array_equal(a.theta, b.theta)
    assert a.alpha == b.alpha
    # P = 1 is what the baseline is; asking for another P is an error, not silently overridden.
    assert "innovation_length" not in a.options
    with pytest.raises(fohw.ParameterError, match="has no option `innovation_length`"):
        paper_identify(data2000.u, data2000.y, method="single_innovation_gradient",
                       innovation_length=5)


def test_single_innovation_lm_runs_and_differs(data2000):
    lm = paper_identify(data2000.u[:500], data2000.y[:500], method="single_innovation_lm")
    gd = paper_identify(data2000.u[:500], data2000.y[:500], method="single_innovation_gradient")
    assert lm.method == "single_innovation_lm" and lm.theta_history.shape == (500, 10)
    assert not np.allclose(lm.theta, gd.theta)


def test_iterative_single_innovation_lm_makes_lm_steps(data2000):
    """Under the iterative schedule the LM baseline makes Eq. (48) steps on theta, not MIGD.

    fohw 0.1 ran the gradient baseline here and labelled it LM (bit-identical results).
    """
    u, y = data2000.u[:600], data2000.y[:600]
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 2"):
        lm = paper_identify(u, y, method="single_innovation_lm", schedule="iterative",
                            max_iter=2)
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 2"):
        gd = paper_identify(u, y, method="single_innovation_gradient", schedule="iterative",
                            max_iter=2)
    assert not np.allclose(lm.theta, gd.theta)
    # Independent reference: the first iteration's alpha step is the hybrid's; then, at that
    # alpha, a theta pass of LM steps written out from Eq. (48) with P = 1.
    from fohw.estimators.milm import alpha_update

    b = RegressorBuilder(u, y, **STRUCT)
    theta = np.full(10, 1e-6)
    alpha = alpha_update(b, theta, 0.5, rows=np.array([0]))
    Phi = b.matrix(alpha)
    for k in range(600):
        jac = Phi[k:k + 1]
        step = (2 / 600) * np.linalg.solve((2 / 600) * jac.T @ jac + np.eye(10),
                                           jac.T @ (y[k:k + 1] - jac @ theta))
        theta = theta + step
    one = paper_identify(u, y, method="single_innovation_lm", schedule="iterative", max_iter=1)
    assert one.alpha == pytest.approx(alpha, rel=1e-12)
    np.testing.assert_allclose(one.theta, theta, rtol=1e-10, atol=1e-14)


def test_recursive_pass_of_hybrid_with_fixed_alpha_is_migd(data2000):
    # With a huge LM damping alpha cannot move, so Table 1's theta recursion must be the MIGD
    # pass at alpha0 (the windows being rebuilt per sample, exactly, from full memory).
    u, y = data2000.u[:600], data2000.y[:600]
    res = paper_identify(u, y, alpha0=0.6, lm_lambda=1e300, innovation_length=3)
    migd = MultiInnovationGradient(alpha=0.6, innovation_length=3, **STRUCT).fit(u, y)
    assert np.all(res.alpha_sample_history == 0.6)
    np.testing.assert_allclose(res.theta_history, migd.theta_history_, rtol=1e-10, atol=1e-13)


def test_alpha_held_at_bound_is_reported(data2000):
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 5"):
        res = paper_identify(data2000.u, data2000.y, schedule="iterative",
                             alpha_window="record", restart_r=True, lm_lambda=1e-8,
                             alpha_bounds=(0.3, 0.5), alpha0=0.4, max_iter=5)
    assert res.alpha_at_bound and "bound" in res.message
    assert 0.3 < res.alpha < 0.5


def test_result_object(data2000):
    res = paper_identify(data2000.u[:400], data2000.y[:400])
    assert res.parameter_names[2] == "q2a1"
    text = res.summary()
    for word in ("alpha", "q3a2", "p2b2", "J (Eq. 41)", "status = NOT_TESTED (2)"):
        assert word in text
    assert res.nit == 1 and not res.converged
    assert "IdentificationResult(method='hybrid'" in repr(res)
    with pytest.raises(AttributeError):
        res.alpha = 0.1
    with pytest.raises(ValueError):
        res.theta[0] = 1.0
    assert res.relative_error(fohw.datasets.paper_model().theta, history=True).shape == (400,)
    assert res.model is not None and res.model.alpha == res.alpha


def test_result_plot_returns_figure(data2000):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    res = paper_identify(data2000.u[:300], data2000.y[:300])
    before = plt.get_fignums()
    fig = res.plot(theta_true=fohw.datasets.paper_model().theta)
    assert len(fig.axes) == 3
    assert plt.get_fignums() == before          # never registered with pyplot


def test_hybrid_identifier_estimator(data2000):
    est = HybridIdentifier(innovation_length=3, schedule="iterative", max_iter=40, **STRUCT)
    assert est.get_params()["innovation_length"] == 3
    with pytest.raises(fohw.NotFittedError):
        est.predict(data2000.u, data2000.y)
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 40"):
        assert est.fit(data2000.u, data2000.y) is est
    assert est.theta_.shape == (10,) and est.result_.options["innovation_length"] == 3
    assert est.alpha_ == est.result_.alpha and est.result_.method == "hybrid"
    # The same run as fohw.identify with those options.
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 40"):
        direct = paper_identify(data2000.u, data2000.y, innovation_length=3,
                                schedule="iterative", max_iter=40)
    np.testing.assert_array_equal(est.theta_, direct.theta)
    # predict uses what was fitted: changing a setting afterwards changes nothing.
    before = est.predict(data2000.u, data2000.y)
    est.set_params(innovation_length=1, alpha0=0.9)
    np.testing.assert_array_equal(est.predict(data2000.u, data2000.y), before)
    with pytest.raises(TypeError, match="unexpected keyword argument 'P'; its parameters are na"):
        HybridIdentifier(P=3, **STRUCT)
    with pytest.raises(TypeError, match="unexpected keyword argument 'method'"):
        HybridIdentifier(method="varpro", **STRUCT)
    with pytest.raises(TypeError, match="missing required keyword argument"):
        HybridIdentifier(na=2, nb=2)
    with pytest.raises(TypeError):              # keyword-only
        HybridIdentifier(2, 2, 2, 3)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(innovation_length=0), fohw.ParameterError, r"`innovation_length` must be at least 1"),
        (dict(innovation_length=51), fohw.ParameterError, r"`innovation_length` must be at most 50; got 51"),
        (dict(tol=0.0), fohw.ParameterError, r"`tol` must be in \(0, inf\]; got 0.0"),
        (dict(tol=-1e-3), fohw.ParameterError, r"`tol`"),
        (dict(alpha0=1.2), fohw.ParameterError, r"`alpha0` must be in \(0, 1\); got 1.2"),
        (dict(alpha0=0.0), fohw.ParameterError, r"`alpha0` must be in \(0, 1\)"),
        (dict(max_iter=0), fohw.ParameterError, r"`max_iter` must be at least 1"),
        (dict(method="newton"), fohw.ParameterError, r"`method` must be one of"),
        (dict(schedule="batch"), fohw.ParameterError, r"`schedule` must be one of"),
        (dict(alpha_bounds=(0.5, 0.2)), fohw.ParameterError, r"`alpha_bounds`"),
        (dict(alpha_bounds=(0.0, 2.5)), fohw.ParameterError, r"`alpha_bounds`"),
        (dict(alpha_window="record"), fohw.ParameterError, r"iterative schedule only"),
        (dict(lm_lambda=0.0), fohw.ParameterError, r"`lm_lambda`"),
        (dict(delta_alpha=0.0), fohw.ParameterError, r"`delta_alpha`"),
        (dict(sensitivity="analytic"), fohw.ParameterError, r"`sensitivity` must be one of"),
        (dict(p0=0.0), fohw.ParameterError, r"`p0`"),
        (dict(forgetting=1.5), fohw.ParameterError, r"`forgetting` must be in \(0, 1\]"),
        (dict(normalisation="frobenius"), fohw.ParameterError, r"`normalisation` must be one of"),
        (dict(random_state=0), fohw.ParameterError, r"method 'hybrid' has no option `random_state`"),
        (dict(na=50), fohw.DimensionError, r"longer than the lags: got 50 samples for na=50"),
        (dict(y=np.ones(49)), fohw.DimensionError, r"`u` and `y` must have the same length; got 50 and 49"),
        (dict(u=np.r_[np.ones(49), np.nan]), fohw.ParameterError, r"`u` must contain only finite values"),
    ],
)
def test_identify_rejects_bad_input(kwargs, exc, match):
    args = dict(u=np.random.default_rng(0).uniform(-1, 1, 50), y=np.zeros(50), method="hybrid",
                **STRUCT)
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        fohw.identify(args.pop("u"), args.pop("y"), **args)


def test_paper_claim_larger_P_measured_on_the_paper_example():
    """docs/reproduction.md: on the paper's example, as printed, P barely matters.

    The paper claims that a larger innovation length converges faster; the docs report that,
    implemented as printed, the median delta of P = 5 and P = 1 differ by under 1 %. This
    checks that documented claim on three short records (within 5 %), so a change that makes
    P matter shows up here and in the docs together.
    """
    d1, d5 = [], []
    for seed in range(3):
        data = fohw.datasets.paper_example(3000, random_state=seed)
        d1.append(paper_identify(data.u, data.y, innovation_length=1).relative_error(
            data.model.theta))
        d5.append(paper_identify(data.u, data.y, innovation_length=5).relative_error(
            data.model.theta))
    assert abs(np.median(d1) - np.median(d5)) < 0.05 * np.median(d1)
    assert 0.3 < np.median(d5) < 0.8


def test_notebook_reprs(data2000):
    res = paper_identify(data2000.u[:300], data2000.y[:300], method="varpro")
    html = res._repr_html_()
    assert "<table>" in html and "q3a2" in html and "varpro" in html
    model_html = fohw.datasets.paper_model()._repr_html_()
    # the kind's one vocabulary (its parameters' names), as every kind's table
    assert "<table>" in model_html and ">a2<" in model_html and ">0.2<" in model_html
    assert ">alpha<" in model_html and ">q3<" in model_html and "g_basis" in model_html


def test_every_option_is_declared_once_and_checked_by_one_check():
    from fohw.estimators.identify import OPTIONS
    from fohw.estimators.migd import MigdOptions

    for cls in (*OPTIONS.values(), MigdOptions):
        # A constraint for every field, and one check signature for every class.
        assert set(cls.constraints) == set(cls.names()), cls
        checked = cls().check(n_samples=100, bounds=(0.0, 1.0))
        assert type(checked) is cls and checked.check(n_samples=100, bounds=(0.0, 1.0)) == checked
    # The estimator classes take their settings, defaults included, from the dataclasses.
    for est, cls in ((HybridIdentifier, HybridOptions),
                     (MultiInnovationRLS, RlsOptions),
                     (MultiInnovationGradient, MigdOptions)):
        params = est(**STRUCT, **({"alpha": 0.6} if cls is MigdOptions else {})).get_params()
        assert {k: v for k, v in params.items() if k in cls.names()} == cls.defaults()


def test_rls_class_and_method_share_the_alpha0_default(data2000):
    # alpha0 defaults to the middle of alpha_bounds for both (the class once started at 0.5,
    # outside these bounds).
    u, y = data2000.u[:300], data2000.y[:300]
    est = MultiInnovationRLS(alpha_bounds=(1.0, 2.0), estimate_alpha=False, **STRUCT)
    assert est.fit(u, y).alpha_ == 1.5
    # alpha held at 1.5 (the truth is 0.6): the recursive estimate is unstable in free run on
    # its own input, so it is FAILED, not NOT_TESTED (issue 36)
    with pytest.warns(fohw.ConvergenceWarning, match="free run on its own estimation input"):
        res = fohw.identify(u, y, method="rls", alpha_bounds=(1.0, 2.0), estimate_alpha=False,
                            **STRUCT)
    assert res.alpha == 1.5 and res.options["alpha0"] == 1.5
    assert res.status == fohw.Status.IMPLAUSIBLE
    np.testing.assert_array_equal(res.theta, est.theta_)


def test_an_option_of_another_method_says_which_methods_have_it(data2000):
    with pytest.raises(fohw.ParameterError, match="`max_iter` is an option of 'hybrid'"):
        fohw.identify(data2000.u, data2000.y, method="output_error", max_iter=3, **STRUCT)
    with pytest.raises(fohw.ParameterError, match="`max_nfev` is an option of 'output_error', "
                                                  "'structured', 'varpro'"):
        fohw.identify(data2000.u, data2000.y, method="hybrid", max_nfev=3, **STRUCT)


def test_which_structures_a_method_supports_is_declared_with_it():
    from fohw.estimators import hybrid, rls, varpro

    paper = fohw.datasets.paper_model().structure
    mixed = fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, orders="mixed")
    for method in (*hybrid.METHODS, rls.METHOD):
        assert method.supports(paper) is None
        assert "implements the paper's commensurate model" in method.supports(mixed)
    assert varpro.METHOD.supports(mixed) is None


def test_an_order_ending_at_0_with_past_levels_simulates_as_fitted():
    """Issue 24's bug (issue 28): CONVERGED at alpha_b1 = 0 with a criterion RMSE of 0.238 V,
    while result.simulate gave 0.919 V. The solver stopped just above 0 (the limit nu -> 0+,
    where a term forgets the past level) and the estimate was put on 0 (a term of order 0
    keeps it: another model). The order now stays where the fit was evaluated. The levels
    are those of the estimation record, so the free run on it says initial="fitted"."""
    e = fohw.datasets.cascaded_tanks().estimation
    kw = dict(na=2, nb=2, f_basis=2, g_basis=3, orders="per_lag", offset=True,
              operating_point="mean", dt=4, past="estimate")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.DataWarning)
        # The call started output_error from the varpro estimate; since issue 26 the
        # default is a chain of starts, so the reproducer names that start to take its path.
        # Issue 36: the varpro start and the fit both explode from rest (the operating point,
        # the tanks at their mean levels) through the y^3 feedback; their fitted levels hide
        # it on this record, so they are IMPLAUSIBLE, not CONVERGED, saying so.
        with pytest.warns(fohw.ConvergenceWarning, match="from rest"):
            start = fohw.identify(e.u, e.y, method="varpro", **kw)
        with pytest.warns(fohw.ConvergenceWarning, match="from rest"):
            res = fohw.identify(e.u, e.y, method="output_error", start=start, **kw)
    assert res.status == fohw.Status.IMPLAUSIBLE
    assert 0.0 <= res.orders["alpha_b1"] < 1e-8 and res.alpha_at_bound
    assert "alpha_b1 ended at" in res.message and "order 0 is another model" in res.message
    sse = float(np.sum((e.y - res.simulate(e.u, initial="fitted")) ** 2))
    assert sse == pytest.approx(res.details["simulation_sse"], rel=1e-12)
    assert np.sqrt(sse / e.y.size) < 0.24                    # 0.919 V before
    check = fohw.compare(res, e.u, e.y, initial="fitted")
    assert check.rmse == pytest.approx(np.sqrt(sse / e.y.size), rel=1e-12)
    with pytest.raises(fohw.ParameterError, match="initial='fitted'"):
        res.simulate(e.u)                   # its levels are not applied to a record unasked


def test_the_default_chain_does_at_least_as_well_as_the_varpro_start():
    e = fohw.datasets.cascaded_tanks().estimation
    kw = dict(na=2, nb=2, f_basis=2, g_basis=3, orders="per_lag", offset=True,
              operating_point="mean", dt=4, past="estimate")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.DataWarning)
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        start = fohw.identify(e.u, e.y, method="varpro", **kw)
        from_varpro = fohw.identify(e.u, e.y, method="output_error", start=start, **kw)
        default = fohw.identify(e.u, e.y, method="output_error", **kw)
    assert (default.details["simulation_sse"]
            <= from_varpro.details["simulation_sse"] * (1 + 1e-6))

