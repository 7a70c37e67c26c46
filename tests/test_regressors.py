"""The information matrix, column by column (SPEC §4)."""

import numpy as np
import pytest

import fohw


def test_columns_are_lagged_gl_differences():
    rng = np.random.default_rng(0)
    u, y = rng.uniform(-1, 1, (2, 400))
    alpha = 0.7
    Phi = fohw.model.lagged.regressors.information_matrix(u, y, alpha, na=2, nb=3, f_basis=2, g_basis=3)
    assert Phi.shape == (400, 2 * 3 + 3 * 2)
    col = 0
    for sig, lags in [(y, 2), (y**2, 2), (y**3, 2), (u, 3), (u**2, 3)]:
        d = fohw.gl_difference(sig, alpha)
        for i in range(1, lags + 1):
            expected = np.concatenate([np.zeros(i), d[:-i]])
            np.testing.assert_allclose(Phi[:, col], expected, rtol=0, atol=1e-13)
            col += 1
    assert np.all(Phi[0] == 0)


def test_builder_derivative_matches_finite_difference():
    rng = np.random.default_rng(1)
    u, y = rng.uniform(-1, 1, (2, 1000))
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=2, nb=2, f_basis=2, g_basis=3)
    eps = 1e-6
    fd = (b.matrix(0.6 + eps) - b.matrix(0.6 - eps)) / (2 * eps)
    np.testing.assert_allclose(b.matrix_derivative(0.6), fd, rtol=0, atol=1e-7)


def test_builder_short_record_uses_direct_path_consistently():
    rng = np.random.default_rng(2)
    u, y = rng.uniform(-1, 1, (2, 50))
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=1, nb=1, f_basis=1, g_basis=1)
    np.testing.assert_allclose(b.matrix(0.3)[1:, 0], fohw.gl_difference(y, 0.3)[:-1], atol=1e-15)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(u=np.ones(9)), fohw.DimensionError, r"`u` and `y` must have the same length; got 9 and 10"),
        (dict(na=0), fohw.ParameterError, r"`na` must be at least 1; got 0"),
        (dict(nb=1.5), fohw.ParameterError, r"`nb` must be an integer"),
        (dict(na=10), fohw.DimensionError, "longer than the lags"),
        (dict(y=np.r_[np.ones(9), np.inf]), fohw.ParameterError, r"`y` must contain only finite.*index 9"),
        (dict(f_basis=[len, 3]), fohw.ParameterError, r"`f_basis` entry 1 must be callable"),
        (dict(g_basis="cubic"), fohw.ParameterError, r"`g_basis` must be a Basis"),
        (dict(alpha=np.nan), fohw.ParameterError, r"`alpha` must be finite"),
    ],
)
def test_information_matrix_rejects_bad_input(kwargs, exc, match):
    args = dict(u=np.ones(10), y=np.ones(10), alpha=0.5, na=2, nb=2, f_basis=2, g_basis=3)
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        fohw.model.lagged.regressors.information_matrix(args.pop("u"), args.pop("y"),
                                                        args.pop("alpha"), **args)


def test_basis_returning_nonfinite_is_named():
    with pytest.raises(fohw.ParameterError,
                       match=r"'log' returned nan at index 0 of `u` \(where `u` = -1.0\): "
                             "it returned a non-finite"):
        fohw.model.lagged.regressors.information_matrix(np.r_[-1.0, np.ones(9)], np.ones(10), 0.5, na=1, nb=1,
                                                 f_basis=[np.log], g_basis=1)


@pytest.mark.parametrize("bad", [-1.0, -1e-12, 2.0 + 1e-9, 3.5])
def test_orders_outside_the_model_range_are_refused(bad):
    """Issue 28 #14: information_matrix accepted alpha = -1, which every model refuses."""
    rng = np.random.default_rng(0)
    u, y = rng.uniform(-1, 1, 60), rng.uniform(-1, 1, 60)
    with pytest.raises(fohw.ParameterError, match=r"`alpha` must be in \[0, 2\]"):
        fohw.model.lagged.regressors.information_matrix(u, y, bad, na=2, nb=2, f_basis=1, g_basis=1)
    builder = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=2, nb=1, f_basis=1, g_basis=1,
                                                            orders="per_lag")
    with pytest.raises(fohw.ParameterError, match=r"the order 'alpha_a2' must be in \[0, 2\]"):
        builder.matrix([0.5, bad, 0.5])
    with pytest.raises(fohw.ParameterError, match=r"the order 'alpha_b1' must be in \[0, 2\]"):
        builder.matrix_derivatives([0.5, 0.5, bad])
    # The ends of the range are orders like any other.
    for edge in (0.0, 2.0):
        matrix = fohw.model.lagged.regressors.information_matrix(u, y, edge, na=2, nb=2,
                                                                 f_basis=1, g_basis=1)
        assert np.all(np.isfinite(matrix))
