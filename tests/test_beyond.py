"""Beyond the paper: separable least squares, uncertainty, the CRB, Monte Carlo, MI-RLS."""

import sys

import numpy as np
import pytest

import fohw
from fohw.estimators.varpro import profile_theta

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def cube(x):
    return x**3


# The two further systems of docs/accuracy.md: another alpha, other lags and bases.
SYSTEM_B = dict(model=lambda: fohw.HammersteinWiener(
    [0.4], [0.5, -0.3, 0.2], [1, -0.2], [1, 0.3], 0.3,
    f_basis={"u": lambda x: x, "u^3": cube}, g_basis=2), bounds=(0.0, 1.0))
SYSTEM_C = dict(model=lambda: fohw.HammersteinWiener(
    [0.2, -0.1], [0.8], [1, 0.5], [1], 1.4, f_basis={"u": lambda x: x, "tanh": np.tanh},
    g_basis=1), bounds=(0.0, 2.0))


def record(model, n, seed, noise_std=0.1):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
    v = noise_std * rng.standard_normal(n)
    return u, fohw.simulate(model, u, noise=v)


def fit_varpro(model, u, y, bounds=(0.0, 1.0)):
    return fohw.identify(u, y, na=model.na, nb=model.nb, f_basis=model.f_basis,
                         g_basis=model.g_basis, method="varpro", alpha_bounds=bounds)


@pytest.mark.parametrize("system", ["paper", "B", "C"])
def test_varpro_is_exact_on_noise_free_data(system):
    if system == "paper":
        model, bounds = fohw.datasets.paper_model(), (0.0, 1.0)
    else:
        spec = SYSTEM_B if system == "B" else SYSTEM_C
        model, bounds = spec["model"](), spec["bounds"]
    u, y = record(model, 2000, 0, noise_std=0.0)
    res = fit_varpro(model, u, y, bounds)
    assert res.converged
    assert res.alpha == pytest.approx(model.alpha, abs=1e-7)
    np.testing.assert_allclose(res.theta, model.theta, rtol=0, atol=1e-7)


def test_varpro_finds_the_global_minimum_of_the_profile():
    d = fohw.datasets.paper_example(2000, random_state=5)
    res = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, **STRUCT)
    fine = [profile_theta(b.matrix(a), d.y)[1] / 2000 for a in np.linspace(0.01, 0.99, 197)]
    assert res.J <= min(fine) + 1e-12
    assert res.alpha_profile.shape == (2, 41)


def rms_ratio_tolerance(bound, n_seeds):
    """3 standard deviations of RMS(delta)/CRB over n_seeds for an efficient estimator.

    If the error e ~ N(0, C), then Var(|e|^2) = 2 tr(C^2); the mean of n_seeds draws of |e|^2
    has relative sd sqrt(2 tr(C^2) / n) / tr(C), and its square root half of that.
    """
    C = bound.covariance[:-1, :-1]
    return 3 * 0.5 * np.sqrt(2 * np.trace(C @ C) / n_seeds) / np.trace(C)


@pytest.mark.parametrize("system", ["paper", "B", "C"])
def test_varpro_reaches_the_cramer_rao_bound(system):
    n, n_seeds = 3000, 20
    if system == "paper":
        model, bounds = fohw.datasets.paper_model(), (0.0, 1.0)
    else:
        spec = SYSTEM_B if system == "B" else SYSTEM_C
        model, bounds = spec["model"](), spec["bounds"]
    deltas, alpha_err = [], []
    for seed in range(n_seeds):
        u, y = record(model, n, 1000 + seed)
        res = fit_varpro(model, u, y, bounds)
        deltas.append(np.linalg.norm(res.theta - model.theta) / np.linalg.norm(model.theta))
        alpha_err.append(res.alpha - model.alpha)
    u, _ = record(model, n, 999)
    bound = fohw.crb(model, u, 0.01, n_realizations=8, random_state=0)
    ratio = np.sqrt(np.mean(np.square(deltas))) / bound.rms_relative_error
    assert abs(ratio - 1) < rms_ratio_tolerance(bound, n_seeds)
    # alpha: the sd of a sample sd over 20 draws is about 1/sqrt(2*20) = 16 %; 3 sd = 48 %.
    assert abs(np.sqrt(np.mean(np.square(alpha_err))) / bound.alpha_std - 1) < 0.48


@pytest.mark.slow
def test_standard_errors_match_the_spread_of_the_estimates():
    """Intervals neither too wide nor too narrow, with tolerances derived from the seeds.

    z = (estimate - truth) / se is standard normal when the standard errors are right, so
    E[z**2] = 1 for each parameter. With R records, the mean of z**2 over records has standard
    deviation sqrt(2 / R) for one parameter; averaging over the 11 correlated parameters cannot
    make it larger, so |mean z**2 - 1| < 3 sqrt(2 / R) holds with 3-sigma confidence. Intervals
    twice too wide give mean z**2 = 0.25, twice too narrow 4: both fail (for R = 60 the band is
    +-0.55). The 95 % coverage is checked too, against the worst-case binomial spread (all
    intervals of a record failing together): +-3 sqrt(0.95 * 0.05 / R).
    """
    n_records = 60
    z2, hits = [], []
    for seed in range(n_records):
        d = fohw.datasets.paper_example(2000, random_state=2000 + seed)
        res = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
        se, ci = res.standard_errors(), res.confidence_intervals(0.95)
        truth = dict(zip(d.model.parameter_names, d.model.theta), alpha=0.6)
        est = dict(zip(res.parameter_names, res.theta), alpha=res.alpha)
        z2.append([((est[k] - v) / se[k]) ** 2 for k, v in truth.items()])
        hits.append([ci[k][0] <= v <= ci[k][1] for k, v in truth.items()])
    assert abs(np.mean(z2) - 1) < 3 * np.sqrt(2 / n_records)
    assert abs(np.mean(hits) - 0.95) < 3 * np.sqrt(0.95 * 0.05 / n_records)


def test_standard_errors_and_summary():
    d = fohw.datasets.paper_example(2000, random_state=0)
    res = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    se = res.standard_errors()
    assert set(se) >= {"alpha", "q2a1", "a1", "p2", "q3"}
    assert all(v > 0 for v in se.values())
    lo, hi = res.confidence_intervals(0.95)["alpha"]
    assert lo < res.alpha < hi and hi - lo == pytest.approx(2 * 1.959964 * se["alpha"], rel=1e-5)
    text = res.summary()
    assert "std err" in text and "95% CI" in text and "noise variance" in text
    assert res.noise_variance == pytest.approx(0.01, rel=0.15)
    assert res.theta_history is None
    with pytest.raises(ValueError, match="no per-sample history"):
        res.relative_error(d.model.theta, history=True)
    with pytest.raises(fohw.ParameterError, match="`level`"):
        res.confidence_intervals(1.5)
    hybrid = fohw.identify(d.u[:300], d.y[:300], method="hybrid", **STRUCT)
    with pytest.raises(ValueError, match="only defined at a least-squares optimum"):
        hybrid.standard_errors()


def test_recover_jacobian_matches_finite_differences():
    layout = fohw.model.lagged.params.ThetaLayout(na=2, nb=3, n_g=3, n_f=2)
    theta = np.random.default_rng(0).uniform(0.2, 1.0, layout.n_params)
    jac = layout.recover_jacobian(theta)
    eps = 1e-7
    fd = np.array([(layout.recover_vector(theta + eps * e) - layout.recover_vector(theta - eps * e))
                   / (2 * eps) for e in np.eye(layout.n_params)]).T
    np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-8)


def test_crb_agrees_with_the_estimated_covariance():
    d = fohw.datasets.paper_example(10_000, random_state=0)
    bound = fohw.crb(d.model, d.u, 0.01, n_realizations=4, random_state=1)
    res = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    # Same Fisher information, evaluated at the truth vs at the estimate with s^2: close.
    assert res.standard_errors()["alpha"] == pytest.approx(bound.alpha_std, rel=0.1)
    assert bound.rms_relative_error == pytest.approx(0.025, abs=0.002)   # SPEC §6
    assert bound.alpha_std == pytest.approx(0.004, abs=0.0005)
    assert "rms_relative_error" in repr(bound)
    with pytest.raises(fohw.ParameterError, match="`noise_variance`"):
        fohw.crb(d.model, d.u, 0.0)


def test_monte_carlo_rows_and_parallel_equals_serial(monkeypatch):
    methods = {"varpro": {"method": "varpro"},
               "hybrid P=1": {"method": "hybrid", "innovation_length": 1}}
    kw = dict(seeds=range(3), settings=[{"n_samples": 400}, {"n_samples": 800}], progress=False)
    serial = fohw.monte_carlo(methods, n_jobs=1, **kw)
    assert len(serial) == 2 * 3 * 2
    assert {r["n_samples"] for r in serial} == {400, 800}
    parallel = fohw.monte_carlo(methods, n_jobs=2, **kw)
    key = lambda r: (r["n_samples"], r["seed"], r["method"])  # noqa: E731
    for a, b in zip(sorted(serial, key=key), sorted(parallel, key=key)):
        assert (a["delta"], a["alpha"]) == (b["delta"], b["alpha"])
    monkeypatch.setitem(sys.modules, "joblib", None)
    with pytest.warns(RuntimeWarning, match="joblib is not installed"):
        fallback = fohw.monte_carlo(methods, n_jobs=2, **kw)
    assert [r["delta"] for r in fallback] == [r["delta"] for r in serial]
    summary = fohw.analysis.montecarlo.summarise(serial, by=("method", "n_samples"))
    assert summary[("varpro", 800)]["n"] == 3


def test_monte_carlo_records_diverged_data():
    def make(seed):
        return fohw.datasets.paper_example(3000, input_kind="gaussian", random_state=seed)
    rows = fohw.monte_carlo({"varpro": {"method": "varpro"}}, seeds=range(6), make_data=make,
                            progress=False)
    assert any(r["error"] for r in rows)
    assert all("diverged" in r["error"] for r in rows if r["error"])


@pytest.mark.parametrize("P", [1, 3])
@pytest.mark.parametrize("chunks", [[1000], [1, 499, 500], [250, 250, 250, 250], [7] * 142 + [6]])
def test_partial_fit_equals_fit(P, chunks):
    d = fohw.datasets.paper_example(1000, random_state=3)
    whole = fohw.estimators.rls.MultiInnovationRLS(innovation_length=P, **STRUCT).fit(d.u, d.y)
    stream = fohw.estimators.rls.MultiInnovationRLS(innovation_length=P, **STRUCT)
    i = 0
    for c in chunks:
        stream.partial_fit(d.u[i:i + c], d.y[i:i + c])
        i += c
    assert stream.n_samples_seen_ == 1000
    np.testing.assert_array_equal(stream.theta_history_, whole.theta_history_)
    np.testing.assert_array_equal(stream.alpha_history_, whole.alpha_history_)
    # fit() starts afresh.
    again = stream.fit(d.u, d.y)
    np.testing.assert_array_equal(again.theta_, whole.theta_)


def test_rls_with_fixed_alpha_is_least_squares():
    d = fohw.datasets.paper_example(3000, random_state=4)
    rls = fohw.estimators.rls.MultiInnovationRLS(estimate_alpha=False, alpha0=0.6, initial_covariance=1e8,
                                                 **STRUCT)
    rls.fit(d.u, d.y)
    Phi = fohw.model.lagged.regressors.information_matrix(d.u, d.y, 0.6, **STRUCT)
    theta_ls, _ = profile_theta(Phi, d.y)
    # RLS from S(0) = c I is ridge regression with penalty 1/c = 1e-8: equal to ~1e-6.
    np.testing.assert_allclose(rls.theta_, theta_ls, rtol=0, atol=1e-6)


def test_rls_tracks_alpha_on_the_paper_example():
    bound_alpha_std = 0.004   # CRB at N = 10 000 (SPEC §6; test_crb_agrees_with...)
    for seed in range(2):
        d = fohw.datasets.paper_example(10_000, random_state=seed)
        rls = fohw.estimators.rls.MultiInnovationRLS(**STRUCT).fit(d.u, d.y)
        assert abs(rls.alpha_ - 0.6) < 5 * bound_alpha_std
        assert np.linalg.norm(rls.theta_ - d.model.theta) / np.linalg.norm(d.model.theta) < 0.1


def test_rls_bad_input():
    with pytest.raises(fohw.ParameterError, match="`forgetting`"):
        fohw.estimators.rls.MultiInnovationRLS(forgetting=0.0, **STRUCT).fit(np.zeros(10), np.zeros(10))
    with pytest.raises(fohw.ParameterError, match="`alpha0`"):
        fohw.estimators.rls.MultiInnovationRLS(alpha0=1.5, **STRUCT).fit(np.zeros(10), np.zeros(10))
    with pytest.raises(fohw.DimensionError, match="same length"):
        fohw.estimators.rls.MultiInnovationRLS(**STRUCT).partial_fit(np.zeros(10), np.zeros(9))
    with pytest.raises(fohw.NotFittedError):
        fohw.estimators.rls.MultiInnovationRLS(**STRUCT).predict(np.zeros(10), np.zeros(10))
