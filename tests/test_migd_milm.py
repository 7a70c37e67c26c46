"""Unit level: the MIGD kernel, the MI-LM step and the sensitivities (Eqs. 29-48)."""

import numpy as np
import pytest

import fohw
from fohw.estimators.migd import migd_pass, migd_update
from fohw.estimators.milm import alpha_update, milm_step, output_sensitivity


def simple_record(seed, n=3000):
    """A well-conditioned linear fractional system (n = 2 parameters), noise-free."""
    m = fohw.HammersteinWiener([0.3], [1.0], [1.0], [1.0], 0.6)
    u = np.random.default_rng(seed).uniform(-1, 1, n)
    return m, u, fohw.simulate(m, u)


def test_migd_update_by_hand():
    theta = np.array([1.0, -1.0])
    window = np.array([[1.0, 2.0], [0.0, 1.0]])
    y = np.array([0.0, 1.0])
    # E = y - window @ theta = [0 - (-1), 1 - (-1)] = [1, 2]; ||window||_F^2 = 6; r = 1 + 6 = 7
    new, r, e = migd_update(theta, window, y, 1.0)
    np.testing.assert_array_equal(e, [1.0, 2.0])
    assert r == 7.0
    np.testing.assert_allclose(new, theta + np.array([1.0, 4.0]) / 7.0, rtol=1e-15)
    # Ding's MISG normalisation adds only ||phi(k)||^2 = 5; forgetting scales r(k-1).
    _, r2, _ = migd_update(theta, window, y, 1.0, normalisation="current", forgetting=0.5)
    assert r2 == 0.5 + 5.0


@pytest.mark.parametrize("normalisation, forgetting", [("window", 1.0), ("current", 1.0),
                                                       ("window", 0.9)])
def test_migd_pass_window_matches_definition(normalisation, forgetting):
    rng = np.random.default_rng(0)
    Phi, y = rng.standard_normal((20, 3)), rng.standard_normal(20)
    opts = dict(normalisation=normalisation, forgetting=forgetting)
    hist, r_hist, _ = migd_pass(Phi, y, innovation_length=4, theta0=np.zeros(3), **opts)
    theta, r = np.zeros(3), 1.0
    for k in range(20):
        rows = [k - i for i in range(4) if k - i >= 0]
        theta, r, _ = migd_update(theta, Phi[rows], y[rows], r, **opts)
        # Views and copies may take different BLAS paths: equal to rounding.
        np.testing.assert_allclose(hist[k], theta, rtol=1e-13, atol=1e-15)
        assert r_hist[k] == pytest.approx(r, rel=1e-14)


@pytest.mark.parametrize("seed", range(3))
def test_migd_noise_free_innovation_goes_to_zero(seed):
    m, u, y = simple_record(seed)
    kw = dict(na=1, nb=1, f_basis=1, g_basis=1, alpha=0.6, innovation_length=5)
    misg = fohw.estimators.migd.MultiInnovationGradient(normalisation="current", **kw).fit(u, y)
    first = np.sqrt(np.mean(misg.innovation_history_[:300] ** 2))
    last = np.sqrt(np.mean(misg.innovation_history_[-300:] ** 2))
    assert last < 1e-3 * first
    np.testing.assert_allclose(misg.theta_, m.theta, rtol=1e-3)
    # The paper's normalisation (Eq. 31) also reduces it, more slowly (1/r(k) step).
    paper = fohw.estimators.migd.MultiInnovationGradient(**kw).fit(u, y)
    first = np.sqrt(np.mean(paper.innovation_history_[:300] ** 2))
    last = np.sqrt(np.mean(paper.innovation_history_[-300:] ** 2))
    assert last < 0.5 * first


def test_migd_paper_example_noise_free_innovation_decreases():
    data = fohw.datasets.paper_example(4000, noise_variance=0.0, random_state=0)
    est = fohw.estimators.migd.MultiInnovationGradient(na=2, nb=2, f_basis=2, g_basis=3, alpha=0.6,
                                                       innovation_length=5).fit(data.u, data.y)
    inn = est.innovation_history_
    assert np.sqrt(np.mean(inn[-1000:] ** 2)) < np.sqrt(np.mean(inn[:1000] ** 2))


@pytest.mark.parametrize("seed", range(5))
def test_longer_innovation_converges_faster_on_a_well_conditioned_system(seed):
    m, u, y = simple_record(seed)
    delta = {}
    for P in (1, 5):
        est = fohw.estimators.migd.MultiInnovationGradient(na=1, nb=1, f_basis=1, g_basis=1, alpha=0.6,
                                                           innovation_length=P).fit(u, y)
        delta[P] = np.linalg.norm(est.theta_ - m.theta) / np.linalg.norm(m.theta)
    assert delta[5] < delta[1]


def test_milm_step_by_hand_and_vector_form():
    # (2/N) = 0.5: increment = 0.5 * (xi @ e) / (0.5 * xi @ xi + lambda)
    xi, e = np.array([2.0, 1.0]), np.array([1.0, -1.0])
    assert milm_step(xi, e, n_samples=4, lm_lambda=2.0) == pytest.approx(0.5 * 1 / (0.5 * 5 + 2))
    # The vector form with one column equals the scalar form.
    vec = milm_step(xi[:, None], e, n_samples=4, lm_lambda=2.0)
    assert vec.shape == (1,) and vec[0] == pytest.approx(0.5 * 1 / (0.5 * 5 + 2), rel=1e-15)


@pytest.mark.parametrize("start", [0.45, 0.5, 0.7, 0.75])
def test_alpha_step_with_true_theta_moves_toward_truth(start):
    data = fohw.datasets.paper_example(3000, noise_variance=0.0, random_state=1)
    b = fohw.model.lagged.regressors.RegressorBuilder(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    new = alpha_update(b, data.model.theta, start)
    assert abs(new - 0.6) < abs(start - 0.6)
    assert np.sign(new - start) == np.sign(0.6 - start)


@pytest.mark.parametrize("start", [0.5, 0.7])
def test_innovation_window_alpha_step_points_toward_truth(start):
    # Eq. (48) as printed: the window of the last P = 5 samples, at many sample indices.
    data = fohw.datasets.paper_example(3000, noise_variance=0.0, random_state=2)
    b = fohw.model.lagged.regressors.RegressorBuilder(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    signs = [np.sign(alpha_update(b, data.model.theta, start, rows=np.arange(k, k - 5, -1)) - start)
             for k in range(50, 3000, 150)]
    assert all(s == np.sign(0.6 - start) for s in signs)


def test_exact_and_finite_difference_sensitivities_agree():
    data = fohw.datasets.paper_example(2000, random_state=3)
    b = fohw.model.lagged.regressors.RegressorBuilder(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    theta = data.model.theta
    exact = output_sensitivity(b, 0.6, theta, sensitivity="exact")
    err = {d: np.max(np.abs(output_sensitivity(b, 0.6, theta, delta_alpha=d) - exact))
           for d in (1e-3, 1e-4, 1e-5)}
    # A forward difference is first order: its error shrinks tenfold with the step.
    assert 8 < err[1e-3] / err[1e-4] < 12
    assert 8 < err[1e-4] / err[1e-5] < 12
    assert err[1e-5] < 1e-4 * np.max(np.abs(exact))


def test_windowed_regressors_equal_the_full_matrix():
    data = fohw.datasets.paper_example(700, random_state=4)
    b = fohw.model.lagged.regressors.RegressorBuilder(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    for alpha in (0.35, 0.6, 0.95):
        Phi = b.matrix(alpha)
        w = fohw.gl_weights(alpha, 700)
        for k in (0, 1, 2, 5, 333, 699):
            (rows,) = b.window(k, 5, [w])
            idx = np.arange(k, max(k - 5, -1), -1)
            np.testing.assert_allclose(rows, Phi[idx], rtol=0, atol=1e-13)


def test_migd_estimator_contract():
    est = fohw.estimators.migd.MultiInnovationGradient(na=2, nb=2, f_basis=2, g_basis=3, alpha=0.6)
    with pytest.raises(fohw.NotFittedError, match="not fitted"):
        est.predict(np.zeros(10), np.zeros(10))
    assert est.get_params()["innovation_length"] == 5
    assert est.set_params(innovation_length=3) is est and est.innovation_length == 3
    with pytest.raises(ValueError, match="invalid parameter 'P'"):
        est.set_params(P=3)
    d = fohw.datasets.paper_example(300, random_state=0)
    assert est.fit(d.u, d.y) is est
    assert est.theta_history_.shape == (300, 10) and est.n_iter_ == 300
    assert est.predict(d.u, d.y).shape == (300,)
