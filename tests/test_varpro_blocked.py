"""varpro's blocked solves (TSQR, no N x n matrix) against the full-matrix reference.

Issue 15, item 5: the profile solve, the Golub–Pereyra Jacobian and the covariance are computed
from triangular factors accumulated over blocks of rows. Each is compared here with the
full-matrix computation it replaces (``FullMatrixProfile`` in ``tests/reference_estimators.py``,
what varpro did before), at the same
point, with tolerances from the conditioning of the problem; and whole fits are compared with a
tolerance from the solver's stopping rule.
"""

import numpy as np
import pytest
from reference_estimators import FullMatrixBuilder, FullMatrixProfile, full_matrix_varpro

import fohw
from fohw.estimators import profile
from fohw.estimators.profile import Profile
from fohw.estimators.varpro import VarproOptions, varpro_result

EPS = np.finfo(float).eps


def _paper():
    return fohw.datasets.paper_model()


def _mixed_offset():          # offset and an operating point
    return fohw.HammersteinWiener([0.3, 0.4], [1.0, 0.5, 0.3, -0.2], [1.0, 0.3], [1.0, -0.2],
                                  0.4, orders="mixed", offset=0.5, operating_point=(1.0, 2.0))


def _per_lag():               # three free orders: the vector search
    return fohw.HammersteinWiener([0.3], [1.0, 0.4], [1.0, 0.2], [1.0, -0.1],
                                  {"alpha_a1": 0.35, "alpha_b1": 0.6, "alpha_b2": 0.8},
                                  orders="per_lag")


def _past_levels():           # estimated past levels: transient columns
    return fohw.HammersteinWiener([0.3, 0.2], [1.0, 0.5], [1.0], [1.0], 0.5, orders="mixed",
                                  past=(0.6, -0.4))


SYSTEMS = {"paper": _paper, "mixed_offset": _mixed_offset, "per_lag": _per_lag,
           "past_levels": _past_levels}


def _builder(model, n=3000, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n) + model.operating_point[0]
    y = fohw.simulate(model, u, noise_std=0.05, random_state=seed + 1)
    u0, y0 = model.operating_point
    return fohw.model.lagged.regressors.RegressorBuilder(u - u0, y - y0, structure=model.structure)


def _gamma(n_rows, n_cols):
    """Householder QR's columnwise backward error bound, ``m n eps`` (Higham, Thm 19.4, c = 1)."""
    return n_rows * n_cols * EPS


# The records have 3000 rows, one block at the default BLOCK_ROWS; 1000 gives three blocks, 7
# (fewer rows than columns) 429 pieces, so the stacked triangles are reduced again on the way.
BLOCK_ROWS = [None, 1000, 7]


@pytest.fixture(params=BLOCK_ROWS, ids=lambda r: f"block_rows={r}")
def block_rows(request, monkeypatch):
    if request.param is not None:
        monkeypatch.setattr(profile, "BLOCK_ROWS", request.param)
    return request.param


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_profile_solve_equals_the_full_matrix_solve(name, block_rows):
    model = SYSTEMS[name]()
    b = _builder(model)
    for params in (model.nonlinear, 0.9 * np.asarray(model.nonlinear) + 0.05):
        x_new, rss_new, f_new = Profile(b)(params)
        x_ref, rss_ref, f_ref = FullMatrixProfile(b)(params)
        assert (f_new.rank, list(f_new.dependent)) == (f_ref.rank, list(f_ref.dependent))
        # Both are backward stable least-squares solves of A_s = Phi / scale; their solutions
        # differ by at most twice the perturbation bound (Higham, Thm 20.1):
        # |dx_s| <= g k (2 + (k + 1) |r| / (|A_s| |x_s|)) |x_s|, g = m n eps, k = cond(A_s).
        A = b.matrix(params) / f_ref.scale
        sv = np.linalg.svd(A, compute_uv=False)
        kappa, norm_a = sv[0] / sv[-1], sv[0]
        xs = x_ref * f_ref.scale
        r = np.sqrt(rss_ref)
        bound = 2 * _gamma(*A.shape) * kappa * (2 + (kappa + 1) * r / (norm_a * np.linalg.norm(xs)))
        assert np.linalg.norm((x_new - x_ref) * f_ref.scale) <= bound * np.linalg.norm(xs)
        # rss = |r|^2: |d rss| <= 2 |r| |dr|, |dr| <= g k |b| (the same theorem).
        assert abs(rss_new - rss_ref) <= 2 * 2 * r * _gamma(*A.shape) * kappa * np.linalg.norm(b.y)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_golub_pereyra_and_covariance_equal_the_full_matrix_ones(name, block_rows):
    model = SYSTEMS[name]()
    b = _builder(model)
    params = np.asarray(model.nonlinear, dtype=float)
    new, ref = Profile(b), FullMatrixProfile(FullMatrixBuilder(b))
    linear, rss, _ = ref(params)
    G = b.jacobian(linear, params)
    sv = np.linalg.svd(G / np.linalg.norm(G, axis=0), compute_uv=False)
    kappa_g = sv[0] / sv[-1]
    cov_new, s2_new = new.covariance(linear, params, rss)
    cov_ref, s2_ref = ref.covariance(linear, params, rss)
    assert s2_new == s2_ref
    # (G^T G)^-1 from two backward-stable QRs of G: relative error <= 2 g k^2 in the
    # equilibrated variables.
    d = np.sqrt(np.diag(cov_ref))
    bound = 2 * _gamma(*G.shape) * kappa_g**2
    assert np.max(np.abs((cov_new - cov_ref) / np.outer(d, d))) <= bound
    if params.size:
        A = b.matrix(params)
        sa = np.linalg.svd(A / np.linalg.norm(A, axis=0), compute_uv=False)
        kappa = sa[0] / sa[-1]
        gp_new, gp_ref = new.golub_pereyra(params), ref.golub_pereyra(params)
        # Two solves with R (k each) and products through Phi instead of an explicit Q: the
        # blocked Jacobian's error is within g k^2 of its size (Q^T v, R^-1, R^-T: k each,
        # the projection's own error eps k), the reference's within g.
        scale = np.max(np.abs(gp_ref), axis=0)
        assert np.all(np.max(np.abs(gp_new - gp_ref), axis=0) <= 2 * _gamma(*A.shape) * kappa**2
                      * scale)


def test_rank_deficient_profile_names_the_same_columns(block_rows):
    rng = np.random.default_rng(3)
    u = rng.uniform(-1, 1, 2000)
    y = fohw.simulate(_paper(), u, noise_std=0.05, random_state=4)
    dup = fohw.Basis((lambda v: v, lambda v: 1.0 * v), names=("x", "x_again"))
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=2, nb=2, f_basis=dup, g_basis=3)
    x_new, rss_new, f_new = Profile(b)(0.6)
    x_ref, rss_ref, f_ref = FullMatrixProfile(b)(0.6)
    assert f_new.rank == f_ref.rank == 8
    # Of two identical columns the later is named (ties go to the first column) by both paths;
    # LAPACK's pivoting alone broke the tie by rounding (the full-matrix path named b2 and p2b1
    # here before _linalg.factor applied the rule too).
    assert list(f_new.dependent) == list(f_ref.dependent) == [8, 9]       # p2b1, p2b2
    assert np.all(x_new[[8, 9]] == 0) and np.all(x_ref[[8, 9]] == 0)
    # The basic solution is the least-squares solution without those columns.
    A = b.matrix(0.6)[:, :8]
    x_sub, rss_sub, f_sub = fohw._linalg.lstsq(A, b.y)
    sv = np.linalg.svd(A / f_sub.scale, compute_uv=False)
    kappa = sv[0] / sv[-1]
    xs = x_sub * f_sub.scale
    bound = 2 * _gamma(*A.shape) * kappa * (2 + (kappa + 1) * np.sqrt(rss_sub)
                                            / (sv[0] * np.linalg.norm(xs)))
    assert np.linalg.norm((x_new[:8] - x_sub) * f_sub.scale) <= bound * np.linalg.norm(xs)
    allowed = 2 * 2 * np.sqrt(rss_sub) * _gamma(*A.shape) * kappa * np.linalg.norm(b.y)
    assert abs(rss_new - rss_sub) <= allowed and abs(rss_ref - rss_sub) <= allowed


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_fit_equals_the_full_matrix_fit(name, block_rows):
    model = SYSTEMS[name]()
    b = _builder(model)
    k = len(model.structure.orders.free)
    bounds = (np.zeros(k), np.full(k, 1.5))
    opts = VarproOptions().check(n_samples=b.n_samples, bounds=bounds)
    new = varpro_result(b, opts, bounds, operating_point=model.operating_point)
    with full_matrix_varpro():
        ref = varpro_result(b, opts, bounds, operating_point=model.operating_point)
    assert new.status == ref.status == fohw.Status.CONVERGED
    # The two fits see the same residuals and Jacobians to rounding, but each stops where the
    # solver's tolerance `tol` is met, not at the minimiser: a step that lowers the cost by
    # less than tol * cost ends it, which leaves the estimate within
    # sqrt(2 tol (N - d)) standard errors of the minimiser (the cost's curvature is
    # G^T G = s^2 Cov^-1 with s^2 = rss / (N - d)). Two such estimates: twice that.
    x_new, x_ref = np.r_[new.linear, new.nonlinear], np.r_[ref.linear, ref.nonlinear]
    se = np.sqrt(np.diag(ref.covariance))
    allowed = 2 * np.sqrt(2 * opts.tol * (b.n_samples - x_ref.size))
    assert np.max(np.abs(x_new - x_ref) / se) <= allowed
    # The covariance s^2 (G^T G)^-1 moves with the estimate: to first order by the displacement
    # in standard errors (<= allowed) where G varies on the scale of one standard error or
    # slower (measured: at most 1.1e-5 relative, against allowed = 1.5e-3).
    np.testing.assert_allclose(new.covariance, ref.covariance, rtol=allowed)
    # Each cost is within tol * cost of the minimum (the quadratic model above: F - F* <=
    # s^2 |delta|^2 / 2 with |delta| <= sqrt(2 tol (N - d)) gives tol * rss), so the two J
    # differ by at most 2 tol relative (measured: 3.5e-16).
    assert new.J == pytest.approx(ref.J, rel=2 * opts.tol)
