"""Property-based tests (hypothesis): the GL kernel, the theta container, the simulator and the
data loaders under arbitrary input."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fohw
from fohw.cli import read_table

FILE_SETTINGS = settings(max_examples=60, deadline=None,
                         suppress_health_check=[HealthCheck.function_scoped_fixture])


@settings(max_examples=40, deadline=None)
@given(alpha=st.floats(-0.9, 2.0), n=st.integers(1, 600), seed=st.integers(0, 2**32 - 1),
       shift=st.integers(0, 50))
def test_gl_is_shift_equivariant(alpha, n, seed, shift):
    # Delaying a zero-initial-condition signal delays its GL difference.
    x = np.random.default_rng(seed).standard_normal(n)
    delayed = np.r_[np.zeros(shift), x]
    d = fohw.gl_difference(delayed, alpha)
    # The FFT path (N > 160) is exact only to rounding: 1e-12 relative to max|x| (SPEC §2).
    tol = 1e-12 * np.abs(x).max() * (1 + np.abs(fohw.gl_weights(alpha, n + shift)).sum())
    np.testing.assert_allclose(d[shift:], fohw.gl_difference(x, alpha), rtol=0, atol=tol)
    assert np.all(np.abs(d[:shift]) <= tol)


@settings(max_examples=40, deadline=None)
@given(a=st.floats(0.05, 1.95), b=st.floats(0.05, 1.95), n=st.integers(2, 300),
       seed=st.integers(0, 2**32 - 1))
def test_gl_semigroup(a, b, n, seed):
    # Grünwald–Letnikov weights compose: Δ^a Δ^b = Δ^(a+b) (generating functions (1-z)^a (1-z)^b).
    x = np.random.default_rng(seed).standard_normal(n)
    lhs = fohw.gl_difference(fohw.gl_difference(x, b), a)
    rhs = fohw.gl_difference(x, a + b)
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-10 * max(1.0, np.abs(rhs).max()))


@settings(max_examples=30, deadline=None)
@given(na=st.integers(1, 3), nb=st.integers(1, 3), alpha=st.floats(0.05, 1.9),
       scale=st.floats(0.0, 0.25), n=st.integers(3, 400), seed=st.integers(0, 2**32 - 1))
def test_simulator_regression_identity(na, nb, alpha, scale, n, seed):
    rng = np.random.default_rng(seed)
    a = scale * rng.uniform(-1, 1, na) / na
    b = rng.uniform(-1, 1, nb)
    q = np.r_[1.0, 0.3 * rng.uniform(-1, 1)]
    p = np.r_[1.0, rng.uniform(-1, 1)]
    m = fohw.HammersteinWiener(a, b, p, q, alpha)
    u = rng.uniform(-1, 1, n)
    v = 0.1 * rng.standard_normal(n)
    try:
        y = fohw.simulate(m, u, noise=v)
    except fohw.SimulationDivergedError as err:     # allowed, and must say where
        assert 0 <= err.sample < n
        return
    assert np.all(np.isfinite(y))
    if n > max(na, nb):
        Phi = fohw.model.regressors.information_matrix(u, y, alpha, na=na, nb=nb, f_basis=2, g_basis=2)
        assert np.max(np.abs(y - Phi @ m.theta - v)) <= 1e-10 * max(1.0, np.abs(y).max())


@settings(max_examples=60, deadline=None)
@given(na=st.integers(1, 4), nb=st.integers(1, 4), ng=st.integers(1, 4), nf=st.integers(1, 4))
def test_theta_names_and_blocks_agree(na, nb, ng, nf):
    layout = fohw.model.params.ThetaLayout(na=na, nb=nb, n_g=ng, n_f=nf)
    theta = np.arange(layout.n_params, dtype=float) + 1
    qa, pb = layout.blocks(theta)
    names = layout.names
    assert len(set(names)) == layout.n_params
    for j in range(ng):
        for i in range(na):
            assert names[int(qa[j, i]) - 1] == (f"q{j + 1}" if j else "") + f"a{i + 1}"
    for j in range(nf):
        for i in range(nb):
            assert names[int(pb[j, i]) - 1] == (f"p{j + 1}" if j else "") + f"b{i + 1}"


lines = st.lists(st.one_of(
    st.text(alphabet="0123456789.-+eE \t,x%#n", max_size=30),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=4).map(
        lambda v: " ".join(repr(x) for x in v))), max_size=12)


@FILE_SETTINGS
@given(content=lines)
def test_loaders_never_crash_on_malformed_text(tmp_path, content):
    path = tmp_path / "fuzz.dat"
    path.write_text("\n".join(content))
    for load in (fohw.datasets.load_daisy, lambda p: read_table(p)[0]):
        try:
            data = load(path)
        except fohw.DataFileError as err:
            assert str(path) in str(err)
        else:
            assert data.ndim == 2 and data.shape[0] >= 1 and np.all(np.isfinite(data))


@FILE_SETTINGS
@given(blob=st.binary(max_size=200))
def test_loaders_never_crash_on_binary(tmp_path, blob):
    path = tmp_path / "blob.dat"
    path.write_bytes(blob)
    try:
        fohw.datasets.load_daisy(path)
    except fohw.DataFileError:
        pass
    try:
        read_table(path)
    except fohw.DataFileError:
        pass
