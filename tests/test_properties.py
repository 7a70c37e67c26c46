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
        Phi = fohw.model.lagged.regressors.information_matrix(u, y, alpha, na=na, nb=nb, f_basis=2, g_basis=2)
        assert np.max(np.abs(y - Phi @ m.theta - v)) <= 1e-10 * max(1.0, np.abs(y).max())


@settings(max_examples=60, deadline=None)
@given(na=st.integers(1, 4), nb=st.integers(1, 4), ng=st.integers(1, 4), nf=st.integers(1, 4))
def test_theta_names_and_blocks_agree(na, nb, ng, nf):
    layout = fohw.model.lagged.params.ThetaLayout(na=na, nb=nb, n_g=ng, n_f=nf)
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


# Issue 43: a user kind whose hooks misbehave at random. Each call of a hook takes the next
# step of a schedule drawn by hypothesis (then behaves): a wrong shape, NaN, None, an exception,
# a non-model. fohw.fit must end in a FitResult or a fohw error, never a raw Python or numpy
# exception, and never change the caller's arrays.
_STEPS = ["ok", "nan", "short", "two_columns", "value_error", "arithmetic", "none", "not_a_model",
          "jacobian_shape", "jacobian_nan", "jacobian_single"]


class _Wayward(fohw.Model, register=False):
    """y[k] = a y[k-1] + b u[k-1], each hook call following the next step of ``plan``."""

    def __init__(self, a=0.5, b=1.0, plan=None):
        self.a, self.b = a, b
        self.plan = {"steps": [], "calls": 0} if plan is None else plan

    def _step(self):
        k = self.plan["calls"]
        self.plan["calls"] += 1
        return self.plan["steps"][k] if k < len(self.plan["steps"]) else "ok"

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        step = self._step()
        if step == "not_a_model":
            return 42
        if step == "value_error":
            raise ValueError("a kind's own bug")
        v = self.parameters.with_values(values).valuesdict()
        return _Wayward(v["a"], v["b"], self.plan)

    def _run(self, u):
        y = np.zeros_like(u)
        for k in range(1, u.size):
            y[k] = self.a * y[k - 1] + self.b * u[k - 1]
        return y

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        step = self._step()
        y = self._run(u)
        return {"nan": lambda: np.full_like(y, np.nan), "short": lambda: y[:-1],
                "two_columns": lambda: np.column_stack([y, y]), "none": lambda: None,
                "not_a_model": lambda: "y",
                "value_error": lambda: np.zeros(3) + np.zeros(4),     # a raw numpy error
                "arithmetic": lambda: 1 / 0}.get(step, lambda: y)()

    def jacobian(self, u):
        u = self.check_input(u)
        step = self._step()
        y = self._run(u)
        ja = np.zeros_like(y)
        for k in range(1, u.size):
            ja[k] = y[k - 1] + self.a * ja[k - 1]
        jac = np.column_stack([ja, _Wayward(self.a, 1.0)._run(u)])
        return {"jacobian_shape": lambda: (y, jac[:, :1]), "jacobian_nan": lambda: (y, jac * np.nan),
                "jacobian_single": lambda: jac, "none": lambda: None, "short": lambda: (y[1:], jac),
                "value_error": lambda: {}["missing"]}.get(step, lambda: (y, jac))()

    def starts(self, u, y):
        step = self._step()
        return {"none": lambda: [None], "not_a_model": lambda: self,
                "value_error": lambda: [self, "x"]}.get(step, lambda: [self])()

    def linear_start(self, u, y):
        step = self._step()
        return {"not_a_model": lambda: {"a": 1.0}, "value_error": lambda: int("x")}.get(
            step, lambda: None)()


@settings(max_examples=25, deadline=None)
@given(steps=st.lists(st.sampled_from(_STEPS), max_size=12), skip=st.integers(0, 30),
       exact=st.booleans())
def test_a_kind_that_misbehaves_at_random_gets_a_fohw_error_or_a_fit(steps, skip, exact):
    import warnings

    u = np.random.default_rng(4).standard_normal(40)
    y = _Wayward(0.8, 2.0)._run(u)
    u_before, y_before = u.copy(), y.copy()
    kind = _Wayward(plan={"steps": ["ok"] * skip + steps, "calls": 0})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)      # a fit's own verdicts
        warnings.simplefilter("ignore", fohw.RankDeficiencyWarning)
        try:
            result = fohw.fit(kind, u, y, order_grid=1, n_starts=1, max_nfev=20,
                              exact_jacobian=exact)
        except fohw.FohwError:
            result = None
    if result is not None:
        assert isinstance(result, fohw.FitResult) and result.status is not None
        assert np.all(np.isfinite(result.parameters.free_values()))
    np.testing.assert_array_equal(u, u_before)
    np.testing.assert_array_equal(y, y_before)
