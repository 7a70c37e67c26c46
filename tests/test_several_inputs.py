"""Several inputs (MISO, issue 24): ``u`` of shape (N, m), each input its own basis, lags, delay
and orders, ``theta = [q ⊗ a, p_1 ⊗ b_1, …, p_m ⊗ b_m]``.

The model first: a literal per-sample implementation of the two-input equation (written here,
GL weights from SciPy's binomial) against :func:`fohw.simulate` at every sample, and the
regression identity. Then the estimators (noise-free recovery, efficiency against the
Cramér–Rao bound of the output-noise model, slow), select_structure, compare, JSON, the CLI,
a pandas DataFrame, and bad input. The single-input model is untouched (its own tests).
"""

import json

import numpy as np
import pytest
from scipy.special import binom

import fohw


def gl_weights(nu, n):
    j = np.arange(n)
    return (-1.0) ** j * binom(nu, j)


def literal(structure, params, u, v=None, operating_point=None):
    """``y[k] = sum_t sum_j qa (Delta^nu g_j(y))[k - i_t] + sum_inputs sum_t sum_j p_ij b_it
    (Delta^nu f_ij(u_i))[k - i_t] + c + v[k]``, term by term, every GL sum from scratch."""
    names = structure.linear_names + structure.nonlinear_names
    values = dict(zip(names, np.asarray(params, dtype=float)))
    n, m = u.shape
    v = np.zeros(n) if v is None else v
    u0, y0 = operating_point if operating_point is not None else ((0.0,) * m, 0.0)
    h = structure.dt
    free = {name: values[name] for name in structure.orders.free}

    def order(term):
        return free[term.order] if term.free else term.order

    def diff(signal, nu, k):
        if k < 0:
            return 0.0
        w = gl_weights(nu, k + 1)
        return sum(w[j] * signal[k - j] for j in range(k + 1)) / h**nu

    parts = structure.f_basis.parts
    F = [[[float(fn(np.array([x]))[0]) for x in u[:, i] - u0[i]] for fn in part.functions]
         for i, part in enumerate(parts)]
    gfun = structure.g_basis.functions
    G = [[0.0] * n for _ in gfun]
    y = np.zeros(n)
    for k in range(n):
        yk = v[k] + (values["offset"] if structure.offset else 0.0)
        for t, name in zip(structure.orders.input, structure.orders.b_names):
            prefix, _, base = name.partition(".")
            for j in range(len(parts[t.input])):
                coef = values[f"{prefix}." + (f"p{j + 1}" if j else "") + base]
                yk += coef * diff(F[t.input][j], order(t), k - t.lag)
        for t, name in zip(structure.orders.output, structure.orders.a_names):
            for j in range(len(gfun)):
                coef = values[(f"q{j + 1}" if j else "") + name]
                yk += coef * diff(G[j], order(t), k - t.lag)
        y[k] = yk
        for j, g in enumerate(gfun):
            G[j][k] = float(g(np.array([yk]))[0])
    return y + y0


#: Two inputs with different orders, lags, delays and bases; a feedthrough on the first.
ORDERS = fohw.Orders([(1, "alpha"), (2, "alpha")],
                     [(0, "alpha", 0), (1, "alpha", 0), (1, "beta", 1), (2, "beta", 1),
                      (3, "beta", 1)], inputs=("heat", "flow"))
SPEC = dict(na=2, nb=[2, 3], nk=[0, 1], f_basis=[2, 1], g_basis=1)


def plant_structure():
    return fohw.Structure.make(**SPEC, orders=ORDERS, inputs=("heat", "flow"))


# a1 a2 | heat.b0 heat.b1 heat.p2b0 heat.p2b1 | flow.b1 flow.b2 flow.b3 | alpha beta
TRUE = np.r_[0.5, 0.2, 0.6, 0.3, 0.18, 0.09, -0.5, 0.3, 0.2, 0.45, 0.8]


def record(n=1500, seed=0, noise_std=0.0):
    s = plant_structure()
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, (n, 2))
    y = fohw.simulate(s, u, params=TRUE)
    return s, u, y + noise_std * rng.standard_normal(n)


def test_names_and_layout():
    s = plant_structure()
    assert s.linear_names == ("a1", "a2", "heat.b0", "heat.b1", "heat.p2b0", "heat.p2b1",
                              "flow.b1", "flow.b2", "flow.b3")
    assert s.nonlinear_names == ("alpha", "beta")
    assert s.structured_names == ("a1", "a2", "heat.b0", "heat.b1", "flow.b1", "flow.b2",
                                  "flow.b3", "heat.p2", "alpha", "beta")
    assert (s.nb, s.nk, s.n_inputs, s.inputs) == ((2, 3), (0, 1), 2, ("heat", "flow"))
    assert not s.is_paper_model


@pytest.mark.parametrize("case", ["plant", "per_lag_offset_dt_point", "mixed_three_inputs"])
def test_simulate_equals_the_literal_two_input_equation_at_every_sample(case):
    rng = np.random.default_rng(3)
    point = None
    if case == "plant":
        s, params = plant_structure(), TRUE
    elif case == "per_lag_offset_dt_point":
        s = fohw.Structure.make(na=1, nb=[1, 2], nk=[2, 0], f_basis=[1, 2], g_basis=2,
                                orders="per_lag", offset=True, dt=0.5, inputs=("u1", "u2"))
        lin = rng.uniform(-0.3, 0.3, s.n_linear)
        params = np.r_[lin, rng.uniform(0.1, 1.2, s.n_nonlinear)]
        point = ((0.4, -0.2), 1.5)
    else:
        s = fohw.Structure.make(na=1, nb=1, nk=[0, 1, 3], f_basis=1, g_basis=1, orders="mixed",
                                inputs=("a", "b", "c"))
        lin = rng.uniform(-0.3, 0.3, s.n_linear)
        params = np.r_[lin, 0.6]
    m = s.n_inputs
    u = rng.uniform(-1, 1, (80, m)) + (0.0 if point is None else np.asarray(point[0]))
    v = 0.05 * rng.standard_normal(80)
    kw = {} if point is None else {"operating_point": point}
    got = fohw.simulate(s, u, params=params, noise=v, **kw)
    np.testing.assert_allclose(got, literal(s, params, u, v, point), rtol=0, atol=1e-12)


def test_the_information_matrix_reproduces_the_record():
    s, u, _ = record(400)
    v = 0.05 * np.random.default_rng(8).standard_normal(400)
    y = fohw.simulate(s, u, params=TRUE, noise=v)
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, structure=s)
    np.testing.assert_allclose(y - b.matrix(TRUE[-2:]) @ TRUE[:-2], v, rtol=0, atol=1e-12)


def test_each_input_acts_only_through_its_own_terms():
    # An impulse on input 2 reaches y one sample later (nk = 1), on input 1 at once (nk = 0).
    s = fohw.Structure.make(na=1, nb=1, nk=[0, 1], f_basis=1, g_basis=1, orders=0,
                            inputs=("u1", "u2"))
    for col, first in ((0, 5), (1, 6)):
        u = np.zeros((20, 2))
        u[5, col] = 1.0
        y = fohw.simulate(s, u, params=[0.5, 2.0, 3.0])
        assert np.all(y[:first] == 0.0) and y[first] == (2.0, 3.0)[col]


def test_a_model_with_one_zero_input_is_the_single_input_model():
    # Nesting identity: the flow coefficients at 0 give the single-input model of heat.
    s, u, _ = record(300)
    params = TRUE.copy()
    params[6:9] = 0.0
    single = fohw.Structure.make(na=2, nb=2, nk=0, f_basis=2, g_basis=1)
    want = fohw.simulate(single, u[:, 0], params=np.r_[params[:6], params[9]])
    np.testing.assert_allclose(fohw.simulate(s, u, params=params), want, rtol=0, atol=1e-13)


@pytest.mark.parametrize("method", ["varpro", "structured", "output_error"])
def test_noise_free_two_input_plant_is_recovered_exactly(method):
    s, u, y = record()
    r = fohw.identify(u, y, **SPEC, orders=ORDERS, method=method,
                      alpha_bounds={"alpha": (0.0, 1.0), "beta": (0.0, 1.5)})
    assert r.status == fohw.Status.CONVERGED
    assert r.parameter_names == s.linear_names
    np.testing.assert_allclose(np.r_[r.linear, r.nonlinear], TRUE, atol=1e-6)
    np.testing.assert_allclose(r.simulate(u), y, atol=1e-6)
    assert r.shared_model is None and "one input" in r.message
    np.testing.assert_array_equal(r.model.simulate(u), r.simulate(u))   # the fitted model


def test_method_auto_chain_and_compare_work_on_two_inputs():
    s, u, y = record(1200, noise_std=0.02)
    r = fohw.identify(u, y, **SPEC, orders=ORDERS, operating_point="mean", offset=True)
    assert len(r.operating_point[0]) == 2 and len(r.input_range[0]) == 2
    v = fohw.compare(r, u, y)
    assert v.fit_simulation > 90.0
    assert any("cross-correlation" in n for n in v.notes)
    with pytest.warns(fohw.ExtrapolationWarning, match="an input leaves the range"):
        r.simulate(u * np.array([1.0, 3.0]))


def test_select_structure_chooses_the_delays_of_each_input():
    s, u, y = record(1200, noise_std=0.02)
    sel = fohw.select_structure(u, y, {"nk": [[0, 1], [1, 1], [0, 2]]}, na=2, nb=[2, 3],
                                f_basis=[2, 1], g_basis=1)
    assert sel.best.nk == (0, 1)


def test_result_json_round_trip(tmp_path):
    s, u, y = record(600, noise_std=0.01)
    r = fohw.identify(u, y, **SPEC, orders=ORDERS, operating_point="initial", offset=True,
                      method="output_error")
    fohw.save_result(r, tmp_path / "r.json")
    back = fohw.load_result(tmp_path / "r.json")
    assert back.structure == r.structure and back.operating_point == r.operating_point
    assert back.input_range == r.input_range
    np.testing.assert_array_equal(back.theta, r.theta)
    np.testing.assert_array_equal(back.simulate(u), r.simulate(u))
    text = json.loads((tmp_path / "r.json").read_text())
    assert text["structure"]["orders"]["inputs"] == ["heat", "flow"]
    assert text["structure"]["f_basis"]["kind"] == "inputs"


def test_the_initial_state_of_a_two_input_fit():
    # "rest" and "fitted" work on (N, 2) inputs; an estimated or measured initial state would
    # need one past level per input, which fohw does not model yet: a clear error, not a crash.
    s, u, y = record(600, noise_std=0.01)
    r = fohw.identify(u, y, **SPEC, orders=ORDERS, method="varpro")
    np.testing.assert_array_equal(r.simulate(u, initial="rest"), r.simulate(u))
    assert fohw.compare(r, u, y, initial="rest").fit > 90
    with pytest.raises(fohw.ParameterError, match="single-input"):
        fohw.compare(r, u, y, initial="estimate")
    with pytest.raises(fohw.ParameterError, match="single-input"):
        r.simulate(u[100:], initial=(u[:100], y[:100]))


def test_names_from_inputs_and_from_a_dataframe_give_the_same_numbers():
    s, u, y = record(500, noise_std=0.01)
    plain = fohw.identify(u, y, na=2, nb=[2, 3], nk=[0, 1], f_basis=[2, 1], g_basis=1)
    assert plain.parameter_names[2] == "u1.b0"
    named = fohw.identify(u, y, na=2, nb=[2, 3], nk=[0, 1], f_basis=[2, 1], g_basis=1,
                          inputs=("heat", "flow"))
    assert named.parameter_names[2] == "heat.b0"
    np.testing.assert_array_equal(plain.theta, named.theta)
    pd = pytest.importorskip("pandas")
    frame = fohw.identify(pd.DataFrame(u, columns=["heat", "flow"]), y, na=2, nb=[2, 3],
                          nk=[0, 1], f_basis=[2, 1], g_basis=1)
    assert frame.parameter_names == named.parameter_names
    np.testing.assert_array_equal(frame.theta, named.theta)


def test_one_value_applies_to_every_input():
    s, u, y = record(500)
    a = fohw.identify(u, y, na=2, nb=2, nk=1, f_basis=2, g_basis=1)
    b = fohw.identify(u, y, na=2, nb=[2, 2], nk=[1, 1], f_basis=[2, 2], g_basis=1)
    assert a.structure == b.structure
    np.testing.assert_array_equal(a.theta, b.theta)


def test_cli_identify_with_several_input_columns(tmp_path, capsys):
    from fohw.cli import main

    s, u, y = record(600, noise_std=0.01)
    path = tmp_path / "d.csv"
    np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="heat,flow,y", comments="")
    assert main(["identify", str(path), "--columns", "heat,flow,y", "--na", "2", "--nb", "2,3",
                 "--nk", "0,1", "--f-basis", "2,1", "--json", "-q"]) == 0
    out = json.loads(capsys.readouterr().out)
    want = fohw.identify(u, y, na=2, nb=[2, 3], nk=[0, 1], f_basis=[2, 1], g_basis=1,
                         inputs=("heat", "flow"))
    assert list(out["theta"]) == list(want.parameter_names)
    np.testing.assert_allclose(list(out["theta"].values()), want.theta, rtol=1e-12)


def _output_noise_bound(structure, params, u, sigma):
    """``sigma^2 (S^T S)^-1``: the CRB of white output noise, S the free-run sensitivity."""
    from fohw.model.lagged.sensitivity import simulation_jacobian

    n = structure.n_linear
    _, S = simulation_jacobian(structure, params[:n], params[n:], u)
    return sigma**2 * np.linalg.inv(S.T @ S)


@pytest.mark.slow
def test_output_error_on_two_inputs_reaches_the_bound():
    """Mean squared error over the output-noise CRB variance, per parameter, over 24 seeds.

    Efficient: chi2(24)/24 per parameter; the issue's 1.2 x CRB (1.44 in variance) on the
    average over the 11 parameters (chi2(264)/264: upper 99.9 % 1.29), each parameter below
    its own Bonferroni 99.9 % quantile.
    """
    from scipy import stats

    s = plant_structure()
    n, sigma, seeds = 1500, 0.05, 24
    u = np.random.default_rng(41).uniform(-1.0, 1.0, (n, 2))
    y0 = fohw.simulate(s, u, params=TRUE)
    bound = np.diag(_output_noise_bound(s, TRUE, u, sigma))
    z2 = np.zeros(TRUE.shape[0])
    for seed in range(seeds):
        y = y0 + sigma * np.random.default_rng(500 + seed).standard_normal(n)
        r = fohw.identify(u, y, **SPEC, orders=ORDERS, method="output_error",
                          alpha_bounds={"alpha": (0.0, 1.0), "beta": (0.0, 1.5)})
        z2 += (np.r_[r.linear, r.nonlinear] - TRUE) ** 2
    ratio = dict(zip(s.linear_names + s.nonlinear_names, z2 / seeds / bound))
    assert np.mean(list(ratio.values())) < 1.44, ratio
    hi = stats.chi2.ppf(1 - 0.001 / len(ratio), seeds) / seeds
    assert max(ratio.values()) < hi, ratio


def test_profile_interval_of_a_two_input_fit():
    s, u, y = record(800, noise_std=0.02)
    r = fohw.identify(u, y, **SPEC, orders=ORDERS)
    iv = fohw.profile_interval(r, "beta", u=u, y=y)
    assert iv.low < 0.8 < iv.high
    with pytest.raises(fohw.ParameterError, match="or several inputs"):
        r.linear_block()
