"""Basis functions, the theta container and the model (SPEC §3-4, Eqs. 17-20, 39-40)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fohw
from fohw.datasets import paper_model


def test_paper_theta_layout_and_names():
    m = paper_model()
    np.testing.assert_allclose(m.theta, [0.1, 0.2, 0.07, 0.14, 0.035, 0.07, -0.4, -0.2, -0.2, -0.1],
                               rtol=1e-15)
    assert m.parameter_names == ("a1", "a2", "q2a1", "q2a2", "q3a1", "q3a2", "b1", "b2", "p2b1",
                                 "p2b2")
    assert m.layout.model_parameter_names == ("a1", "a2", "b1", "b2", "p2", "q2", "q3")


nonzero = st.floats(-5, 5).filter(lambda v: abs(v) > 1e-3)


@settings(max_examples=60, deadline=None)
@given(na=st.integers(1, 4), nb=st.integers(1, 4), ng=st.integers(1, 4), nf=st.integers(1, 4),
       data=st.data())
def test_from_theta_round_trips(na, nb, ng, nf, data):
    a = data.draw(st.lists(nonzero, min_size=na, max_size=na))
    b = data.draw(st.lists(nonzero, min_size=nb, max_size=nb))
    p = [1.0] + data.draw(st.lists(st.floats(-5, 5), min_size=nf - 1, max_size=nf - 1))
    q = [1.0] + data.draw(st.lists(st.floats(-5, 5), min_size=ng - 1, max_size=ng - 1))
    m = fohw.HammersteinWiener(a, b, p, q, 0.5)
    m2 = fohw.HammersteinWiener.from_theta(m.theta, 0.5, na=na, nb=nb, f_basis=nf, g_basis=ng)
    for name in "abpq":
        np.testing.assert_allclose(getattr(m2, name), getattr(m, name), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(m2.theta, m.theta, rtol=1e-12, atol=1e-12)


def test_recover_averages_ratios_as_eq_39():
    layout = fohw.model.lagged.params.ThetaLayout(na=2, nb=1, n_g=2, n_f=1)
    # q2*a disagrees between lags: Eq. (39) averages 0.3/0.1 = 3 and 0.2/0.2 = 1 to 2.
    a, b, p, q = layout.recover([0.1, 0.2, 0.3, 0.2, -0.5])
    np.testing.assert_allclose(q, [1.0, 2.0])
    np.testing.assert_allclose(a, [0.1, 0.2])
    with pytest.raises(fohw.ParameterError, match="Eq. \\(39\\)"):
        layout.recover([0.0, 0.2, 0.3, 0.2, -0.5])


def test_custom_basis_model():
    m = fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.2], [1.0, -0.1],
                               alpha=1.3, f_basis={"u": lambda x: x, "tanh": np.tanh},
                               g_basis=[np.sin, np.cos])
    assert m.f_basis.names == ("u", "tanh")
    assert m.g_basis.names == ("sin", "cos")
    assert "alpha=1.3" in repr(m)


def test_polynomial_basis_values():
    b = fohw.polynomial_basis(3)
    np.testing.assert_array_equal(b.evaluate([2.0, -1.0]), [[2, -1], [4, 1], [8, -1]])
    assert b.is_polynomial and fohw.model.basis.as_basis(3) == b
    assert not fohw.model.basis.as_basis([np.tanh]).is_polynomial


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(p=[0.9, 0.5]), fohw.ParameterError, r"`p\[0\]` must be exactly 1"),
        (dict(q=[2.0, 0.7, 0.35]), fohw.ParameterError, r"`q\[0\]` must be exactly 1"),
        (dict(alpha=2.7), fohw.ParameterError, r"`alpha` must be in \[0, 2\]; got 2.7"),
        (dict(alpha=-0.1), fohw.ParameterError, r"`alpha` must be in \[0, 2\]; got -0.1"),
        (dict(alpha=np.nan), fohw.ParameterError, r"`alpha` must be finite"),
        (dict(a=[]), fohw.DimensionError, r"`a` must have at least 1"),
        (dict(b=[[1.0]]), fohw.DimensionError, r"`b` must be 1-D"),
        (dict(a=[0.1, np.inf]), fohw.ParameterError, r"`a` must contain only finite"),
        (dict(f_basis=3), fohw.DimensionError, r"`p` must have one entry per f-basis function"),
        (dict(g_basis=["not callable"]), fohw.ParameterError, r"`g_basis` entry 0 must be callable"),
        (dict(g_basis=0), fohw.ParameterError, r"`g_basis` as a polynomial degree"),
    ],
)
def test_model_rejects_bad_input(kwargs, exc, match):
    base = dict(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1.0, 0.5], q=[1.0, 0.7, 0.35], alpha=0.6)
    base.update(kwargs)
    with pytest.raises(exc, match=match):
        fohw.HammersteinWiener(**base)


def test_basis_that_is_not_elementwise_is_rejected():
    bad = fohw.Basis((lambda x: x[:-1],), names=("short",))
    with pytest.raises(fohw.DimensionError, match="'short' returned shape"):
        bad.evaluate(np.ones(4))
    with pytest.raises(fohw.ParameterError, match="names must be distinct"):
        fohw.Basis((np.sin, np.cos), names=("s", "s"))


def test_theta_length_checked():
    layout = fohw.model.lagged.params.ThetaLayout(na=2, nb=2, n_g=3, n_f=2)
    with pytest.raises(fohw.DimensionError, match="`theta` must have 10 entries"):
        layout.recover(np.ones(9))
    with pytest.raises(fohw.ParameterError, match="`na` must be at least 1; got 0"):
        fohw.model.lagged.params.ThetaLayout(na=0, nb=2, n_g=1, n_f=1)
