"""Input delay ``nk`` (issue 24): direct feedthrough (nk = 0) and dead time (nk > 1).

The model first: a literal per-sample implementation of the equation with the input terms at
lags ``nk … nk + nb - 1`` (written here, GL weights from SciPy's binomial) against
:func:`fohw.simulate` at every sample, then the regression identity ``y = Phi theta + v``.
Then the estimators: noise-free recovery by every general method, efficiency of output_error
against the Cramér–Rao bound (slow), the docs lesson (nk = 1 on a feedthrough plant is clearly
worse), JSON and the CLI. nk = 1 is today's model: names and numbers unchanged.
"""

import json

import numpy as np
import pytest
from scipy.special import binom

import fohw


def gl_weights(nu, n):
    j = np.arange(n)
    return (-1.0) ** j * binom(nu, j)


def literal(structure, params, u, v=None, operating_point=(0.0, 0.0)):
    """``y[k] = sum_t sum_j qa[j,t] h^-nu (Delta^nu g_j(y))[k - i_t]
    + sum_t sum_j pb[j,t] h^-nu (Delta^nu f_j(u))[k - i_t] + c + v[k]``, term by term.

    Loops over samples, terms and basis functions; every GL sum recomputed from scratch with
    zero signals before k = 0 (``past="rest"``). Input lags may be 0 (the present input).
    """
    names = structure.linear_names + structure.nonlinear_names
    values = dict(zip(names, np.asarray(params, dtype=float)))
    n = len(u)
    v = np.zeros(n) if v is None else v
    u0, y0 = operating_point
    h = structure.dt
    free = {name: values[name] for name in structure.orders.free}

    def order(term):
        return free[term.order] if term.free else term.order

    def coef(prefix_index, term_name, letter):
        return values[(f"{letter}{prefix_index}" if prefix_index > 1 else "") + term_name]

    f = [lambda x, fn=fn: float(fn(np.array([x]))[0]) for fn in structure.f_basis.functions]
    g = [lambda x, fn=fn: float(fn(np.array([x]))[0]) for fn in structure.g_basis.functions]
    ud = np.asarray(u, dtype=float) - u0
    F = [[fj(x) for x in ud] for fj in f]
    G = [[0.0] * n for _ in g]
    y = np.zeros(n)

    def diff(signal, nu, m):
        if m < 0:
            return 0.0
        w = gl_weights(nu, m + 1)
        return sum(w[j] * signal[m - j] for j in range(m + 1)) / h**nu

    for k in range(n):
        yk = v[k] + (values["offset"] if structure.offset else 0.0)
        for t, name in zip(structure.orders.input, structure.orders.b_names):
            for j in range(len(f)):
                yk += coef(j + 1, name, "p") * diff(F[j], order(t), k - t.lag)
        for t, name in zip(structure.orders.output, structure.orders.a_names):
            for j in range(len(g)):
                yk += coef(j + 1, name, "q") * diff(G[j], order(t), k - t.lag)
        y[k] = yk
        for j, gj in enumerate(g):
            G[j][k] = gj(yk)
    return y + y0


CASES = {
    "nk0_commensurate": dict(na=2, nb=2, nk=0, f_basis=2, g_basis=2, orders="commensurate",
                             nonlinear=[0.45]),
    "nk0_mixed_offset_dt": dict(na=1, nb=2, nk=0, f_basis=1, g_basis=1, orders="mixed",
                                offset=True, dt=0.5, nonlinear=[0.6]),
    "nk1_per_lag": dict(na=1, nb=2, nk=1, f_basis=2, g_basis=1, orders="per_lag",
                        nonlinear=[0.3, 0.7, 1.2]),
    "nk3_commensurate": dict(na=2, nb=2, nk=3, f_basis=1, g_basis=2, orders="commensurate",
                             nonlinear=[0.8]),
    "nk0_integer": dict(na=1, nb=3, nk=0, f_basis=2, g_basis=1, orders=0, nonlinear=[]),
}


def structure_and_params(case, seed=0):
    spec = dict(CASES[case])
    nonlinear = spec.pop("nonlinear")
    s = fohw.Structure.make(**spec)
    rng = np.random.default_rng(seed)
    lin = rng.uniform(-0.3, 0.3, s.n_linear)
    lin[: s.layout.n_output_params] *= 0.5             # a stable feedback
    return s, np.r_[lin, nonlinear]


@pytest.mark.parametrize("case", sorted(CASES))
def test_simulate_equals_the_literal_equation_with_delay_at_every_sample(case):
    s, params = structure_and_params(case)
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, 80) + 0.3
    v = 0.05 * rng.standard_normal(80)
    got = fohw.simulate(s, u, params=params, noise=v, operating_point=(0.3, -1.0))
    want = literal(s, params, u, v, operating_point=(0.3, -1.0))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


@pytest.mark.parametrize("nk", [0, 2])
def test_past_levels_and_history_with_a_delay_follow_the_reference(nk):
    import reference

    model = fohw.HammersteinWiener([0.3, 0.2], [1.0, 0.5], [1.0, 0.3], [1.0, -0.2], 0.4, nk=nk,
                                   offset=0.2, past=(0.3, -0.1), operating_point=(0.5, 1.0))
    rng = np.random.default_rng(5)
    u = rng.uniform(-1, 1, 70) + 0.5
    v = 0.05 * rng.standard_normal(70)
    np.testing.assert_allclose(fohw.simulate(model, u, noise=v),
                               reference.simulate_general(model, u, v), rtol=0, atol=1e-12)
    hist = (rng.uniform(-1, 1, 30) + 0.5, rng.uniform(-1, 1, 30) + 1.0)
    np.testing.assert_allclose(fohw.simulate(model, u, initial=hist),
                               reference.simulate_general(model, u, np.zeros(70), history=hist),
                               rtol=0, atol=1e-12)
    # and the information matrix with estimated past levels reproduces the record
    y = fohw.simulate(model, u, noise=v)
    b = fohw.model.lagged.regressors.RegressorBuilder(u - 0.5, y - 1.0, structure=model.structure)
    np.testing.assert_allclose(y - 1.0 - b.matrix(model.nonlinear) @ model.linear, v,
                               rtol=0, atol=1e-12)


def test_feedthrough_reaches_the_output_at_the_same_sample_and_delay_shifts_it():
    # An impulse at k = 5 appears at y[5] with nk = 0, at y[8] with nk = 3, not before.
    u = np.zeros(30)
    u[5] = 1.0
    for nk in (0, 1, 3):
        s = fohw.Structure.make(na=1, nb=1, nk=nk, f_basis=1, g_basis=1, orders=0)
        y = fohw.simulate(s, u, params=[0.5, 2.0])
        assert np.all(y[: 5 + nk] == 0.0)
        assert y[5 + nk] == 2.0
        assert y[6 + nk] == 1.0


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_information_matrix_reproduces_the_record(case):
    s, params = structure_and_params(case)
    rng = np.random.default_rng(2)
    u = rng.uniform(-1, 1, 300)
    v = 0.05 * rng.standard_normal(300)
    y = fohw.simulate(s, u, params=params, noise=v)
    b = fohw.model.lagged.regressors.RegressorBuilder(u, y, structure=s)
    k = s.n_linear
    Phi = b.matrix(params[k:]) if s.n_nonlinear else b.matrix(np.zeros(0))
    np.testing.assert_allclose(y - Phi @ params[:k], v, rtol=0, atol=1e-12)


def test_nk_one_is_todays_model_names_and_numbers():
    base = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3)
    same = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3, nk=1)
    assert base == same and base.is_paper_model and same.nk == 1
    assert base.linear_names == ('a1', 'a2', 'q2a1', 'q2a2', 'q3a1', 'q3a2', 'b1', 'b2', 'p2b1',
                                 'p2b2')
    data = fohw.datasets.paper_example(600, random_state=0)
    a = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    b = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3, nk=1)
    assert np.array_equal(a.theta, b.theta) and a.alpha == b.alpha


def test_names_follow_the_lags():
    s = fohw.Structure.make(na=1, nb=2, nk=3, f_basis=2, g_basis=1)
    assert s.layout.names == ("a1", "b3", "b4", "p2b3", "p2b4")
    assert (s.nk, s.nb, s.max_lag) == (3, 2, 4)
    d = fohw.Structure.make(na=1, nb=1, nk=0, f_basis=1, g_basis=1, orders="per_lag")
    assert d.linear_names == ("a1", "b0") and d.nonlinear_names == ("alpha_a1", "alpha_b0")
    assert "nk=0" in d.describe()
    assert not d.is_paper_model


def test_per_lag_orders_dict_starts_at_nk():
    o = fohw.Orders.resolve({"a": [0.5], "b": [(0, "nu"), "nu"]}, na=1, nb=2, nk=0)
    assert [(t.lag, t.order) for t in o.input] == [(0, 0.0), (0, "nu"), (1, "nu")]
    assert o.b_names == ("b0_0", "b0_nu", "b1")


def test_orders_object_must_agree_with_nk():
    o = fohw.Orders.preset("commensurate", na=1, nb=1, nk=0)
    with pytest.raises(fohw.ParameterError, match="input lags 0..0.*nk = 1"):
        fohw.Orders.resolve(o, na=1, nb=1)
    assert fohw.Orders.resolve(o, na=1, nb=1, nk=0) == o
    with pytest.raises(fohw.ParameterError, match="branch 'a' must be an integer >= 1"):
        fohw.Orders([(0, 0.0)], [(0, 0.0)])


def test_the_model_class_takes_nk():
    m = fohw.HammersteinWiener([0.5], [1.0, 0.4], [1.0], [1.0], 0.5, nk=0)
    assert m.parameter_names == ("a1", "b0", "b1") and m.nk == 0
    assert fohw.HammersteinWiener.from_dict(m.to_dict()) == m
    back = fohw.HammersteinWiener.from_theta(m.theta, 0.5, na=1, nb=2, f_basis=1, g_basis=1,
                                             nk=0)
    assert back == m
    # its simulation is the structure's with the same numbers
    u = np.random.default_rng(0).uniform(-1, 1, 60)
    np.testing.assert_allclose(fohw.simulate(m, u),
                               fohw.simulate(m.structure, u, params=[0.5, 1.0, 0.4, 0.5]),
                               rtol=0, atol=1e-14)


def test_frequency_response_of_feedthrough_is_the_d_term():
    # H(z) = b0 + b1 z^-1 (orders 0, no feedback term worth speaking of: a1 = 0 at order 0).
    m = fohw.HammersteinWiener([0.0], [0.7, 0.2], [1.0], [1.0], orders=0, nk=0)
    lb = fohw.model.lagged.hw_frequency.LinearBlock.from_model(m)
    w = np.array([0.0, 0.5, np.pi])
    np.testing.assert_allclose(lb.frequency_response(w), 0.7 + 0.2 * np.exp(-1j * w), atol=1e-14)


# ---- estimators ---------------------------------------------------------------------------------

def plant(nk, n=1500, seed=0, noise_std=0.0):
    model = fohw.HammersteinWiener([0.4, 0.2], [0.9, 0.5], [1.0, 0.3], [1.0], 0.55, nk=nk)
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = fohw.simulate(model, u, noise_std=noise_std, random_state=seed + 1)
    return model, u, y


@pytest.mark.parametrize("method", ["varpro", "structured", "output_error"])
@pytest.mark.parametrize("nk", [0, 3])
def test_noise_free_delay_is_recovered_exactly(nk, method):
    model, u, y = plant(nk)
    r = fohw.identify(u, y, na=2, nb=2, nk=nk, f_basis=2, g_basis=1, method=method)
    assert r.status == fohw.Status.CONVERGED
    assert r.nk == nk
    np.testing.assert_allclose(r.theta, model.theta, atol=1e-6)
    assert r.alpha == pytest.approx(0.55, abs=1e-6)
    np.testing.assert_allclose(r.simulate(u), y, atol=1e-6)


@pytest.mark.parametrize("method", ["hybrid", "rls", "single_innovation_lm"])
def test_the_paper_methods_refuse_a_delay(method):
    model, u, y = plant(0, n=300)
    with pytest.raises(fohw.ParameterError, match="nk=0"):
        fohw.identify(u, y, na=2, nb=2, nk=0, f_basis=2, g_basis=1, method=method)


def test_fitting_without_feedthrough_on_a_feedthrough_plant_is_clearly_worse():
    # The docs lesson (docs/real_data.md): the b0 term is the fit.
    model, u, y = plant(0, n=2000, noise_std=0.02)
    _, u_val, y_val = plant(0, n=1000, seed=9, noise_std=0.0)
    rmse = {}
    for nk in (0, 1):
        r = fohw.identify(u, y, na=2, nb=2, nk=nk, f_basis=2, g_basis=1, method="output_error")
        rmse[nk] = fohw.compare(r, u_val, y_val).rmse
    # The right class's error on noise-free validation data is its parameter error's, about
    # noise * sqrt(d / N) = 0.02 * sqrt(8 / 2000) = 0.0013, far below the estimation noise
    # 0.02; without b0 (0.9 times an input of RMS 0.58) the model cannot reach the noise.
    assert rmse[0] < 0.02 / 4, rmse
    assert rmse[1] > 0.02 * 4, rmse


def test_select_structure_chooses_the_delay():
    model, u, y = plant(0, n=1200, noise_std=0.02)
    sel = fohw.select_structure(u, y, {"nk": [0, 1, 2]}, na=2, nb=2, f_basis=2, g_basis=1)
    assert sel.best.nk == 0


def test_result_json_round_trip_keeps_the_delay(tmp_path):
    model, u, y = plant(3, n=400)
    r = fohw.identify(u, y, na=2, nb=2, nk=3, f_basis=2, g_basis=1)
    fohw.save_result(r, tmp_path / "r.json")
    back = fohw.load_result(tmp_path / "r.json")
    assert back.nk == 3 and back.parameter_names == r.parameter_names
    np.testing.assert_array_equal(back.simulate(u), r.simulate(u))
    text = json.loads((tmp_path / "r.json").read_text())
    assert [3, "alpha"] in text["structure"]["orders"]["b"]


def test_summary_shows_the_delay():
    model, u, y = plant(0, n=400)
    text = fohw.identify(u, y, na=2, nb=2, nk=0, f_basis=2, g_basis=1).summary()
    assert "nk = 0" in text and "b0" in text
    paper = fohw.identify(u, y, na=2, nb=2, f_basis=2, g_basis=1).summary()
    assert "nk" not in paper


def test_crb_of_a_feedthrough_model_names_b0():
    model, u, _ = plant(0, n=500)
    bound = fohw.crb(model, u, 0.01, noise="output")
    assert bound.estimate_names[:4] == ("a1", "a2", "b0", "b1")
    assert np.all(np.isfinite(bound.theta_std))


def _efficiency(nk, noise_std, n, seeds):
    """Sum over seeds of each parameter's squared error over its output-noise CRB variance."""
    model = fohw.HammersteinWiener([0.4, 0.2], [0.9, 0.5], [1.0, 0.3], [1.0], 0.55, nk=nk)
    u = np.random.default_rng(21).uniform(-1.0, 1.0, n)
    y0 = fohw.simulate(model, u)
    bound = fohw.crb(model, u, noise_std**2, noise="output")
    true = np.r_[model.linear, model.nonlinear]
    z2 = np.zeros(true.shape[0])
    for seed in range(seeds):
        y = y0 + noise_std * np.random.default_rng(300 + seed).standard_normal(n)
        r = fohw.identify(u, y, na=2, nb=2, nk=nk, f_basis=2, g_basis=1, method="output_error")
        z2 += (np.r_[r.linear, r.nonlinear] - true) ** 2
    return dict(zip(bound.estimate_names, z2 / seeds / np.diag(bound.covariance)))


@pytest.mark.slow
@pytest.mark.parametrize("nk", [0, 3])
def test_output_error_with_a_delay_reaches_the_bound(nk):
    """Mean squared error over the output-noise CRB variance, per parameter, over 24 seeds.

    An efficient estimator gives chi2(24)/24 per parameter: its 99.9 % upper quantile is 2.1,
    so the issue's 1.2 x CRB (in standard deviation: 1.44 in variance) is checked on the
    average over the parameters (chi2(24 d)/(24 d), upper 99.9 % 1.37 for d = 7 parameters),
    and each parameter below its own 99.9 % quantile.
    """
    from scipy import stats

    seeds = 24
    ratio = _efficiency(nk, 0.05, 1500, seeds)
    d = len(ratio)
    assert np.mean(list(ratio.values())) < 1.44, ratio
    hi = stats.chi2.ppf(1 - 0.001 / d, seeds) / seeds
    assert max(ratio.values()) < hi, ratio


def test_cli_identify_and_select_take_nk(tmp_path, capsys):
    from fohw.cli import main

    model, u, y = plant(0, n=600, noise_std=0.01)
    path = tmp_path / "d.csv"
    np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="u,y", comments="")
    assert main(["identify", str(path), "--na", "2", "--nb", "2", "--nk", "0", "--f-basis", "2",
                 "--json", "-q"]) == 0
    out = json.loads(capsys.readouterr().out)
    want = fohw.identify(u, y, na=2, nb=2, nk=0, f_basis=2, g_basis=1)
    assert list(out["theta"]) == list(want.parameter_names)
    np.testing.assert_allclose(list(out["theta"].values()), want.theta, rtol=1e-12)
    assert main(["select", str(path), "--na", "2", "--nk", "0,1", "--f-basis", "2", "-q",
                 "--save", str(tmp_path / "best.json")]) == 0
    assert fohw.load_result(tmp_path / "best.json").nk == 0
