"""The structured parametrisation (a, b, p, q, orders), the output-noise bound and the structured
estimator: the model (mapping, Jacobians, bounds) before the estimator."""

import numpy as np
import pytest
import reference

import fohw
from fohw.model.lagged.sensitivity import simulation_jacobian

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def tanh(x):
    return np.tanh(x)


def central_difference(fun, x, rel=1e-6):
    """Columns ``(fun(x + h e_i) - fun(x - h e_i)) / 2h``, ``h = rel * max(|x_i|, 0.01)``."""
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        step = rel * max(abs(x[i]), 1e-2)
        e = np.zeros_like(x)
        e[i] = step
        cols.append((fun(x + e) - fun(x - e)) / (2 * step))
    return np.column_stack(cols)


# ---- the mapping theta(a, b, p, q) ------------------------------------------------------------

def test_theta_jacobian_matches_finite_differences_and_inverts_the_recovery():
    layout = fohw.model.lagged.params.ThetaLayout(na=3, nb=2, n_g=3, n_f=2)
    eta = np.random.default_rng(0).normal(size=layout.n_model_params)
    jac = layout.theta_jacobian(eta)
    fd = central_difference(layout.theta_of_model_vector, eta)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-9)    # theta is bilinear: fd exact
    theta = layout.theta_of_model_vector(eta)
    np.testing.assert_allclose(layout.recover_vector(theta), eta, rtol=1e-13)
    np.testing.assert_allclose(layout.rank_one_recovery(theta), eta, rtol=1e-12)
    np.testing.assert_allclose(layout.recover_jacobian(theta) @ jac, np.eye(eta.size),
                               atol=1e-12)


def test_rank_one_recovery_is_the_best_rank_one_fit_of_each_block():
    """On a perturbed theta, the recovered blocks are the leading SVD term of each block."""
    layout = fohw.model.lagged.params.ThetaLayout(na=2, nb=2, n_g=3, n_f=2)
    rng = np.random.default_rng(1)
    theta = fohw.datasets.paper_model().theta + 0.01 * rng.standard_normal(10)
    rebuilt = layout.blocks(layout.theta_of_model_vector(layout.rank_one_recovery(theta)))
    for block, fit in zip(layout.blocks(theta), rebuilt):
        u, s, vt = np.linalg.svd(block)
        np.testing.assert_allclose(fit, s[0] * np.outer(u[:, 0], vt[0]), atol=1e-14)


def test_rank_one_recovery_names_a_block_it_cannot_normalise():
    layout = fohw.model.lagged.params.ThetaLayout(na=1, nb=1, n_g=2, n_f=1)
    with pytest.raises(fohw.ParameterError, match="output"):
        layout.rank_one_recovery([0.0, 0.5, 1.0])


def test_structure_mapping_with_offset_and_several_orders():
    s = fohw.Structure.make(na=2, nb=1, f_basis=2, g_basis=2, orders="mixed", offset=True)
    assert s.structured_names[-2:] == ("offset", "alpha")
    x = np.random.default_rng(2).normal(size=len(s.structured_names))
    fd = central_difference(lambda z: np.r_[s.from_structured(z)], x)
    np.testing.assert_allclose(s.structured_jacobian(x), fd, atol=1e-9)
    np.testing.assert_allclose(s.to_structured(*s.from_structured(x)), x, rtol=1e-12)


# ---- the sensitivity of the free run ----------------------------------------------------------

@pytest.mark.parametrize("case", ["paper", "general"])
def test_simulation_jacobian_matches_finite_differences(case):
    rng = np.random.default_rng(3)
    if case == "paper":
        model = fohw.datasets.paper_model()
        n = 700                         # above the 128-sample leaves: the FFT merges run
    else:                               # several orders, order 0, offset, dt, a non-polynomial g
        model = fohw.HammersteinWiener(
            [0.3, -0.2, 0.1, 0.05], [0.6, 0.2], [1, 0.4], [1, 0.5], {"alpha": 0.5},
            g_basis={"y": lambda x: x, "tanh": tanh}, orders="mixed", offset=0.1, dt=0.5)
        n = 300
    u = rng.uniform(-1, 1, n)
    s = model.structure
    y, S = simulation_jacobian(s, model.linear, model.nonlinear, u)
    np.testing.assert_allclose(y, fohw.simulate(model, u), rtol=0, atol=1e-12)
    fd = central_difference(lambda x: fohw.simulate(s, u, params=x),
                            np.r_[model.linear, model.nonlinear])
    np.testing.assert_allclose(S, fd, rtol=0, atol=1e-7 * np.abs(S).max())


# ---- the bounds against literal implementations -----------------------------------------------

def _small_model():
    return fohw.HammersteinWiener([0.3, 0.15], [-0.5, 0.2], [1, 0.4], [1, 0.5], 0.6)


def _structured_vector(model):
    return np.r_[model.a, model.b, model.p[1:], model.q[1:], model.alpha]


def _model_of(x):
    return fohw.HammersteinWiener(x[:2], x[2:4], [1, x[4]], [1, x[5]], x[6])


def test_structured_equation_noise_bound_matches_a_literal_computation():
    """Eq. (19) written out (tests/reference.py) on the same noise realisations, differentiated
    numerically with respect to (a, b, p2, q2, alpha)."""
    model = _small_model()
    n, sigma2 = 60, 0.01
    u = np.random.default_rng(4).uniform(-1, 1, n)
    rng = np.random.default_rng(5)
    info = np.zeros((7, 7))
    for _ in range(2):
        v = np.sqrt(sigma2) * rng.standard_normal(n)
        y = reference.simulate_general(model, u, v)

        def predictor(x, y=y):
            m = _model_of(x)
            return reference.one_step_prediction(u, y, m.theta, x[6], na=2, nb=2, f_basis=2,
                                                 g_basis=2)
        G = central_difference(predictor, _structured_vector(model))
        info += G.T @ G
    literal = np.linalg.inv(info / (2 * sigma2))
    bound = fohw.crb(model, u, sigma2, parametrisation="structured", n_realizations=2,
                     random_state=5)
    assert bound.estimate_names == ("a1", "a2", "b1", "b2", "p2", "q2", "alpha")
    np.testing.assert_allclose(bound.covariance, literal, rtol=1e-5)
    assert bound.parametrisation == "structured" and bound.noise == "equation"
    assert "structured" in bound.description and "equation" in bound.description


def test_output_noise_bound_matches_a_literal_computation():
    """Literal simulation (tests/reference.py) differentiated numerically, in both
    parametrisations: (S^T S / sigma^2)^{-1}."""
    model = _small_model()
    n, sigma2 = 60, 0.04
    u = np.random.default_rng(6).uniform(-1, 1, n)

    def run(x):
        return reference.simulate_general(_model_of(x), u, np.zeros(n))
    S = central_difference(run, _structured_vector(model))
    bound = fohw.crb(model, u, sigma2, parametrisation="structured", noise="output")
    np.testing.assert_allclose(bound.covariance, np.linalg.inv(S.T @ S / sigma2), rtol=1e-5)

    # theta parametrisation: the free run of an unstructured theta is Eq. (19) written out
    # (tests/reference.py) applied to its own past outputs, one sample at a time.
    def free_run(x):
        y = np.zeros(n)
        for k in range(n):
            y[k] = reference.one_step_prediction(u[:k + 1], y[:k + 1], x[:8], x[8], na=2, nb=2,
                                                 f_basis=2, g_basis=2)[k]
        return y
    x0 = np.r_[model.theta, model.alpha]
    St = central_difference(free_run, x0)
    theta_bound = fohw.crb(model, u, sigma2, noise="output")
    np.testing.assert_allclose(theta_bound.covariance, np.linalg.inv(St.T @ St / sigma2),
                               rtol=1e-5)
    assert theta_bound.parametrisation == "theta" and theta_bound.noise == "output"


@pytest.mark.parametrize("noise", ["equation", "output"])
def test_structured_bound_is_never_above_the_unstructured_one(noise):
    """A bound under constraints is below the free one (Loewner order), for theta and alpha."""
    data = fohw.datasets.paper_example(3000, random_state=0)
    kw = dict(random_state=1) if noise == "equation" else {}
    free = fohw.crb(data.model, data.u, 0.01, noise=noise, **kw)
    tight = fohw.crb(data.model, data.u, 0.01, parametrisation="structured", noise=noise, **kw)
    n = data.model.theta.size
    diff = free.covariance[:n, :n] - tight.theta_covariance
    assert np.linalg.eigvalsh(diff).min() > -1e-12 * np.abs(diff).max()
    assert tight.rms_relative_error < free.rms_relative_error
    assert tight.alpha_std <= free.alpha_std


def test_crb_names_what_it_does_not_take():
    data = fohw.datasets.paper_example(300, random_state=0)
    with pytest.raises(fohw.ParameterError, match="parametrisation.*'thetas'"):
        fohw.crb(data.model, data.u, 0.01, parametrisation="thetas")
    with pytest.raises(fohw.ParameterError, match="noise.*'measurement'"):
        fohw.crb(data.model, data.u, 0.01, noise="measurement")
    with pytest.raises(fohw.ParameterError, match="n_realizations.*got 4"):
        fohw.crb(data.model, data.u, 0.01, noise="output", n_realizations=4)


# ---- the structured estimator -----------------------------------------------------------------

def test_structured_fit_is_exact_on_noise_free_data():
    model = fohw.datasets.paper_model()
    u = np.random.default_rng(7).uniform(-np.sqrt(3), np.sqrt(3), 1500)
    y = fohw.simulate(model, u)
    r = fohw.identify(u, y, method="structured", **STRUCT)
    assert r.method == "structured" and r.converged
    assert r.relative_error(model.theta) < 1e-8
    assert abs(r.alpha - 0.6) < 1e-8
    np.testing.assert_allclose(r.shared_model.q, model.q, atol=1e-8)


def test_structured_fit_of_a_general_structure_is_exact_on_noise_free_data():
    model = fohw.HammersteinWiener([0.3, 0.2, -0.1, 0.05], [0.5, 0.25], [1, 0.3], [1, -0.4],
                                   {"alpha": 0.45}, orders="mixed", offset=0.2)
    u = np.random.default_rng(8).uniform(-1, 1, 1500)
    y = fohw.simulate(model, u)
    r = fohw.identify(u, y, method="structured", na=2, nb=1, f_basis=2, g_basis=2,
                      orders="mixed", offset=True)
    assert r.converged
    np.testing.assert_allclose(r.linear, model.linear, atol=1e-8)
    assert abs(r.orders["alpha"] - 0.45) < 1e-8


def test_structured_standard_errors_are_those_of_the_structured_jacobian():
    """s^2 ((G M)^T G M)^{-1} with G M by finite differences of the predictor written
    independently of the estimator (information_matrix of theta(a, b, p, q))."""
    data = fohw.datasets.paper_example(1500, random_state=9)
    r = fohw.identify(data.u, data.y, method="structured", **STRUCT)
    m = r.shared_model
    x = np.r_[m.a, m.b, m.p[1:], m.q[1:], r.alpha]
    layout = m.layout

    def predictor(z):
        theta = layout.to_theta(z[:2], z[2:4], np.r_[1, z[4]], np.r_[1, z[5:7]])
        return fohw.model.lagged.regressors.information_matrix(data.u, data.y, z[7], **STRUCT) @ theta
    G = central_difference(predictor, x)
    rss = float(np.sum((data.y - predictor(x)) ** 2))
    cov = rss / (data.u.size - x.size) * np.linalg.inv(G.T @ G)
    se = r.standard_errors()
    names = ("a1", "a2", "b1", "b2", "p2", "q2", "q3", "alpha")
    np.testing.assert_allclose([se[n] for n in names], np.sqrt(np.diag(cov)), rtol=1e-5)


def test_structured_result_round_trips_through_json(tmp_path):
    data = fohw.datasets.paper_example(800, random_state=10)
    r = fohw.identify(data.u, data.y, method="structured", **STRUCT)
    fohw.save_result(r, tmp_path / "r.json")
    back = fohw.load_result(tmp_path / "r.json")
    assert back.method == "structured"
    assert back.standard_errors() == pytest.approx(r.standard_errors(), rel=1e-12)


def _ratio_sd(cov, n_seeds):
    """Sampling sd of RMS error / bound over n seeds for an efficient estimator:
    0.5 sqrt(2 / (n nu)), nu = (tr C)^2 / tr(C^2) the effective number of directions."""
    nu = np.trace(cov) ** 2 / np.trace(cov @ cov)
    return 0.5 * np.sqrt(2.0 / (n_seeds * nu))


@pytest.mark.slow
def test_structured_reaches_the_structured_bound_on_the_paper_example():
    """Issue 13's must-show, 50 seeds at N = 10^4: RMS delta and RMS alpha error within three
    sampling sd of the structured bound (examples/accuracy_noise_models.py prints 100 seeds)."""
    n, n_seeds = 10_000, 50
    deltas, alpha_err = [], []
    for seed in range(n_seeds):
        d = fohw.datasets.paper_example(n, random_state=2000 + seed)
        r = fohw.identify(d.u, d.y, method="structured", **STRUCT)
        deltas.append(r.relative_error(d.model.theta))
        alpha_err.append(r.alpha - 0.6)
    ref = fohw.datasets.paper_example(n, random_state=10**6)
    bound = fohw.crb(ref.model, ref.u, 0.01, parametrisation="structured", n_realizations=8,
                     random_state=0)
    ratio_d = np.sqrt(np.mean(np.square(deltas))) / bound.rms_relative_error
    ratio_a = np.sqrt(np.mean(np.square(alpha_err))) / bound.alpha_std
    sd_d = _ratio_sd(bound.theta_covariance, n_seeds)
    sd_a = _ratio_sd(np.eye(1), n_seeds)
    assert abs(ratio_d - 1) < 3 * sd_d, (ratio_d, sd_d)
    assert abs(ratio_a - 1) < 3 * sd_a, (ratio_a, sd_a)


@pytest.mark.slow
def test_structured_intervals_cover_at_their_nominal_level():
    """Coverage of each 95 % interval over 200 seeds (N = 1000) within three binomial standard
    errors of 0.95; the pooled coverage too, with the se of 200 seeds (the parameters of one
    seed are correlated, so 200 * 8 independent trials would understate it)."""
    n_seeds = 200
    truth = dict(a1=0.1, a2=0.2, b1=-0.4, b2=-0.2, p2=0.5, q2=0.7, q3=0.35, alpha=0.6)
    hits = dict.fromkeys(truth, 0)
    for seed in range(n_seeds):
        d = fohw.datasets.paper_example(1000, random_state=3000 + seed)
        ci = fohw.identify(d.u, d.y, method="structured", **STRUCT).confidence_intervals()
        for k, v in truth.items():
            hits[k] += ci[k][0] <= v <= ci[k][1]
    se = np.sqrt(0.95 * 0.05 / n_seeds)
    for k, h in hits.items():
        assert abs(h / n_seeds - 0.95) < 3 * se, (k, h / n_seeds)
    pooled = sum(hits.values()) / (n_seeds * len(hits))
    assert abs(pooled - 0.95) < 3 * se, pooled


def test_output_error_standard_errors_are_those_of_the_free_run_sensitivity():
    """s^2 (S^T S)^{-1}, S by central differences of the simulation at the estimate."""
    model = fohw.datasets.paper_model()
    rng = np.random.default_rng(11)
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), 400)
    y = fohw.simulate(model, u) + 0.1 * rng.standard_normal(400)
    r = fohw.identify(u, y, method="output_error", **STRUCT)
    s = r.structure
    S = central_difference(lambda x: fohw.simulate(s, u, params=x), np.r_[r.linear, r.nonlinear])
    resid = y - fohw.simulate(s, u, params=np.r_[r.linear, r.nonlinear])
    cov = resid @ resid / (400 - 11) * np.linalg.inv(S.T @ S)
    np.testing.assert_allclose(np.sqrt(np.diag(r.covariance)), np.sqrt(np.diag(cov)), rtol=1e-5)


def test_crb_names_the_parameters_of_a_singular_information():
    # b = 0: the input nonlinearity's p2 has no effect on the output, in either noise model.
    model = fohw.HammersteinWiener([0.3, 0.2], [0.0, 0.0], [1.0, 0.5], [1.0], 0.5)
    u = np.random.default_rng(0).uniform(-1, 1, 300)
    with pytest.raises(fohw.ParameterError, match="singular: the parameters p2 are not"):
        fohw.crb(model, u, 0.01, parametrisation="structured", random_state=0)
    with pytest.raises(fohw.ParameterError, match="Fisher information is singular"):
        fohw.crb(model, u, 0.01, parametrisation="structured", noise="output")
