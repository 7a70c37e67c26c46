"""The series output block y = h(z) (issue 24, item 2): the maps, the model, then the estimator.

The model is checked before the estimator: each map's derivatives against central differences,
the simulation against a literal per-sample implementation (the recursion written out, then h
in the data's units), the exact Jacobian through h against finite differences of the
simulation. Then output_error: the nesting rule (never above the model without h), recovery
within 1.2x the Cramér–Rao bound (computed from that exact Jacobian) over seeds, JSON, refusals.
"""

import warnings

import numpy as np
import pytest
from scipy import stats

import fohw
from fohw.model.lagged.sensitivity import simulation_jacobian
from fohw.model.output_map import (
    CustomMap,
    DeadZone,
    PiecewiseLinear,
    PolynomialMap,
    Saturation,
    as_output_map,
)

from .reference import gl_weights

RNG = np.random.default_rng(7)


def _soft():
    return CustomMap(lambda z, p: p[0] * np.tanh(z / p[0]),
                     lambda z, p: 1.0 / np.cosh(z / p[0]) ** 2,
                     lambda z, p: (np.tanh(z / p[0]) - z / p[0] / np.cosh(z / p[0]) ** 2)[:, None],
                     names=["scale"], start=[3.0], name="soft_saturation")


# maps and parameter values away from their kinks on Z below
MAPS = [
    (Saturation(), [-0.7, 0.8]),
    (Saturation(upper=0.8), [-0.7]),
    (DeadZone(), [-0.2, 0.3]),
    (DeadZone(lower=-0.2), [0.3]),
    (PiecewiseLinear([-1.0, 0.0, 1.0]), [-0.5, 0.1, 1.4]),
    (PiecewiseLinear([-1.0, 0.0, 1.0], free_breakpoints=True), [-0.5, 0.1, 1.4, -0.9, 0.05, 1.1]),
    (PolynomialMap(3), [0.2, -0.1]),
    (PolynomialMap(5, monotone=True), [0.3, -0.2]),
    (_soft(), [1.5]),
]
Z = np.array([-1.63, -0.95, -0.41, -0.07, 0.12, 0.55, 0.97, 1.7])


@pytest.mark.parametrize("hmap, params", MAPS, ids=[m.describe() for m, _ in MAPS])
def test_map_derivatives_equal_central_differences(hmap, params):
    params = np.array(params, dtype=float)
    step = 1e-6
    dz = (hmap.evaluate(Z + step, params) - hmap.evaluate(Z - step, params)) / (2 * step)
    np.testing.assert_allclose(hmap.derivative(Z, params), dz, rtol=1e-7, atol=1e-8)
    J = hmap.param_jacobian(Z, params)
    assert J.shape == (Z.shape[0], hmap.n_params) == (Z.shape[0], len(params))
    for i in range(len(params)):
        e = np.zeros_like(params)
        e[i] = step
        fd = (hmap.evaluate(Z, params + e) - hmap.evaluate(Z, params - e)) / (2 * step)
        np.testing.assert_allclose(J[:, i], fd, rtol=1e-7, atol=1e-8)


def test_closed_forms_of_the_maps():
    z = np.array([-3.0, -0.5, 0.0, 0.5, 3.0])
    np.testing.assert_array_equal(Saturation().evaluate(z, [-1.0, 2.0]), [-1, -0.5, 0, 0.5, 2])
    np.testing.assert_array_equal(DeadZone().evaluate(z, [-1.0, 0.5]), [-2, 0, 0, 0, 2.5])
    # monotone cubic: ∫ (1 + p t)^2 = z + p z^2 + p^2 z^3 / 3
    p = 0.4
    np.testing.assert_allclose(PolynomialMap(3, monotone=True).evaluate(z, [p]),
                               z + p * z**2 + p**2 * z**3 / 3, rtol=1e-14)
    assert np.all(PolynomialMap(5, monotone=True).derivative(np.linspace(-5, 5, 101),
                                                             [-3.0, 2.0]) >= 0)
    # piecewise linear extrapolates with the end slopes
    np.testing.assert_allclose(PiecewiseLinear([0.0, 1.0]).evaluate(z, [1.0, 3.0]), 1 + 2 * z)


@pytest.mark.parametrize("hmap", [Saturation(), DeadZone(), PolynomialMap(3),
                                  PiecewiseLinear([-2.0, 0.0, 2.0])],
                         ids=lambda m: m.describe())
def test_the_start_is_the_identity_over_the_data(hmap):
    y = RNG.uniform(-1.0, 1.5, 200)
    eta = hmap.start(y, y)
    np.testing.assert_allclose(hmap.evaluate(y, eta), y, rtol=0, atol=1e-15)


def _literal(a, b, alpha, u, u0, y0, h, eta):
    """z[k] = a (Δ^α z)[k-1] + b (Δ^α (u - u0))[k-1], written out; then y = h(z + y0)."""
    n = len(u)
    beta = gl_weights(alpha, n)
    ud = np.asarray(u) - u0
    z = np.zeros(n)
    for k in range(1, n):
        dz = sum(beta[j] * z[k - 1 - j] for j in range(k))
        du = sum(beta[j] * ud[k - 1 - j] for j in range(k))
        z[k] = a * dz + b * du
    return np.array([float(h.evaluate(np.array([zk + y0]), eta)[0]) for zk in z])


@pytest.mark.parametrize("hmap, eta", [(Saturation(), [4.4, 5.6]), (DeadZone(), [4.9, 5.3]),
                                       (PolynomialMap(3), [0.01, -0.002])],
                         ids=["saturation", "deadzone", "polynomial"])
def test_simulate_equals_a_literal_implementation_at_every_sample(hmap, eta):
    s = fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, output_map=hmap)
    u = 2.0 + RNG.uniform(-1, 1, 300)
    a, b, alpha, u0, y0 = 0.5, 1.2, 0.4, 2.0, 5.0       # data around 5 V: h acts in volts
    y = fohw.simulate(s, u, params=np.r_[a, b, alpha, eta], operating_point=(u0, y0))
    ref = _literal(a, b, alpha, u, u0, y0, hmap, np.array(eta))
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-12)
    z = fohw.simulate(s.inner, u, params=[a, b, alpha], operating_point=(u0, y0))
    assert np.any(hmap.evaluate(z, eta) != z)          # the map did act


def test_without_a_map_nothing_changes():
    s = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3)
    assert s.output_map is None and s.inner is s and "output_map" not in s.to_dict()
    m = fohw.datasets.paper_model()
    u = RNG.uniform(-1, 1, 500)
    with_none = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3, output_map=None)
    assert with_none == s and hash(with_none) == hash(s)
    np.testing.assert_array_equal(fohw.simulate(with_none, u, params=np.r_[m.theta, 0.6]),
                                  fohw.simulate(s, u, params=np.r_[m.theta, 0.6]))


@pytest.mark.parametrize("hmap, eta", [(Saturation(), [-0.6, 0.7]), (PolynomialMap(3), [0.3, -0.2]),
                                       (PiecewiseLinear([-1.0, 0.0, 1.0], True),
                                        [-0.8, 0.1, 1.2, -0.9, 0.05, 1.1]), (_soft(), [1.2])],
                         ids=["saturation", "polynomial", "pwl", "custom"])
def test_exact_jacobian_through_h_equals_finite_differences(hmap, eta):
    s = fohw.Structure.make(na=2, nb=1, f_basis=2, g_basis=1, orders="commensurate",
                            output_map=hmap)
    u = RNG.uniform(-1, 1, 400)
    linear = np.array([0.3, 0.2, 1.0, 0.3])
    params = np.r_[0.5, eta]
    y0 = 0.2
    y, G = simulation_jacobian(s, linear, params, u, y0=y0)
    np.testing.assert_allclose(y, fohw.simulate(s, u, params=np.r_[linear, params],
                                                operating_point=(0.0, y0)) - y0, atol=1e-13)
    x = np.r_[linear, params]
    n = len(linear)
    for i in range(len(x)):
        step = 1e-6 * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += step
        xm[i] -= step
        fd = (fohw.simulate(s, u, params=xp, operating_point=(0.0, y0))
              - fohw.simulate(s, u, params=xm, operating_point=(0.0, y0))) / (2 * step)
        if isinstance(hmap, Saturation):
            # the clip's kinks: a sample whose z is within the step of a limit differs
            z = fohw.simulate(s.inner, u, params=x[:n + 1]) + y0
            near = np.min(np.abs(z[:, None] - np.array(eta)[None, :]), axis=1) < 1e-4
            fd, col = fd[~near], G[~near, i]
        else:
            col = G[:, i]
        np.testing.assert_allclose(col, fd, rtol=1e-5, atol=1e-7 * np.max(np.abs(fd)) + 1e-12)


def _tanks_like(kind, n=600, seed=0, sigma=0.02):
    s = fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, output_map=kind)
    truth = np.r_[0.5, 1.0, 0.4, -0.8, 0.9] if kind == "saturation" else \
        np.r_[0.5, 1.0, 0.4, -0.3, 0.25]
    u = np.random.default_rng(123).uniform(-1, 1, n)
    y_true = fohw.simulate(s, u, params=truth)
    y = y_true + sigma * np.random.default_rng(seed).standard_normal(n)
    return s, truth, u, y_true, y


@pytest.mark.parametrize("kind", ["saturation", "deadzone", 3, "piecewise_linear"])
def test_the_series_fit_never_ends_above_the_model_it_nests(kind):
    _, _, u, _, y = _tanks_like("saturation", seed=3)
    plain = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error")
    res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map=kind)
    assert res.details["identity_sse"] == plain.details["simulation_sse"]
    # never above; for the identity starts to rounding of h(z + y0) - y0 (1e-12 relative)
    assert res.details["simulation_sse"] <= plain.details["simulation_sse"] * (1 + 1e-12)
    # and the reported criterion is the simulation's
    r = y - res.simulate(u)
    assert np.isclose(r @ r, res.details["simulation_sse"], rtol=1e-9)


def test_fit_reports_the_map_parameters_and_operating_point_units():
    s, truth, u, _, y = _tanks_like("saturation", seed=1)
    y_volts = y + 5.0
    res = fohw.identify(u, y_volts, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map="saturation", operating_point=(0.0, 5.0))
    assert list(res.output_map_params) == ["h_lower", "h_upper"]
    assert res.estimate_names[-2:] == ("h_lower", "h_upper")
    assert "h_lower" in res.summary() and "saturation" in res.summary()
    lo, hi = res.output_map_params.values()
    se = res.standard_errors()              # in volts: the truth is 5 - 0.8, 5 + 0.9
    assert abs(lo - 4.2) < 4 * se["h_lower"] and abs(hi - 5.9) < 4 * se["h_upper"], se
    assert res.simulate(u).max() <= hi + 1e-12


def _crb_statistics(kind, seeds):
    s, truth, u, y_true, _ = _tanks_like(kind, n=2000)
    sigma = 0.05
    ys, G = simulation_jacobian(s, truth[:2], truth[2:], u)
    np.testing.assert_allclose(ys, y_true, atol=1e-13)
    F = G.T @ G / sigma**2
    errors = []
    for seed in range(seeds):
        y = y_true + sigma * np.random.default_rng(seed).standard_normal(u.shape[0])
        res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                            output_map=kind)
        assert res.converged
        errors.append(np.r_[res.linear, res.nonlinear] - truth)
    E = np.array(errors)
    d = E.shape[1]
    pooled = np.sqrt(np.mean(np.einsum("ij,jk,ik->i", E, F, E)) / d)
    per = np.sqrt(np.mean(E**2, axis=0) / np.diag(np.linalg.inv(F)))
    return pooled, per, d


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["saturation", "deadzone"])
def test_recovered_within_the_cramer_rao_bound_over_seeds(kind):
    """Output noise on a saturation / dead zone with free limits after a fractional block.

    An efficient estimator has (x - x*)^T F (x - x*) ~ chi2_d per seed. The issue's 1.2 x CRB
    (in standard deviation) is checked on the pooled ratio sqrt(mean / d) over M seeds, whose
    sampling spread is small (the 99 % point of sqrt(chi2_{dM} / (dM)) is below 1.2 for these
    d and M, asserted); each parameter's RMS error over its bound stays below the 99 % point of
    sqrt(chi2_M / M), Bonferroni over the d parameters (efficiency, the seeds' spread only).
    """
    seeds = 50
    pooled, per, d = _crb_statistics(kind, seeds)
    assert np.sqrt(stats.chi2.ppf(0.99, d * seeds) / (d * seeds)) < 1.2
    assert pooled <= 1.2, pooled
    assert np.all(per <= np.sqrt(stats.chi2.ppf(1 - 0.01 / d, seeds) / seeds)), per


def test_equation_error_methods_refuse_a_series_map():
    _, _, u, _, y = _tanks_like("saturation")
    for method in ("varpro", "structured", "hybrid"):
        with pytest.raises(fohw.ParameterError, match="cannot fit a series `output_map`"):
            fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method=method,
                          output_map="saturation")


@pytest.mark.parametrize("kind", ["saturation", "deadzone", 3, "piecewise_linear",
                                  PolynomialMap(3, monotone=True), Saturation(upper=0.9)])
def test_json_round_trip(kind, tmp_path):
    _, _, u, _, y = _tanks_like("saturation", seed=2)
    res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map=kind)
    fohw.save_result(res, tmp_path / "r.json")
    back = fohw.load_result(tmp_path / "r.json")
    assert back.structure == res.structure
    assert dict(back.output_map_params) == dict(res.output_map_params)
    np.testing.assert_array_equal(back.simulate(u), res.simulate(u))
    assert fohw.Structure.from_dict(res.structure.to_dict()) == res.structure


def test_a_custom_map_is_stored_by_name_and_needed_again(tmp_path):
    soft = _soft()
    _, _, u, _, y = _tanks_like("saturation", seed=2)
    res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map=soft)
    assert res.structure.to_dict()["output_map"] == {"kind": "custom", "name": "soft_saturation",
                                                     "names": ["h_scale"]}
    fohw.save_result(res, tmp_path / "r.json")
    with pytest.raises(fohw.DataFileError, match="pass the same map again"):
        fohw.load_result(tmp_path / "r.json")
    back = fohw.load_result(tmp_path / "r.json", output_map=soft)
    np.testing.assert_array_equal(back.simulate(u), res.simulate(u))


def test_history_goes_through_the_inverse_of_the_map():
    s, truth, u, _, _ = _tanks_like("saturation")
    k = 300
    u = np.r_[0.2 * u[:k], u[k:]]           # a quiet history: z stays inside the limits there
    z = fohw.simulate(s.inner, u, params=truth[:3])
    assert np.all((z[:k] > -0.8) & (z[:k] < 0.9)) and np.any(z[k:] > 0.9)
    y = fohw.simulate(s, u, params=truth)
    cont = fohw.simulate(s, u[k:], params=truth, initial=(u[:k], y[:k]))
    np.testing.assert_allclose(cont, y[k:], atol=1e-12)
    with pytest.raises(fohw.ParameterError, match="has no inverse"):
        fohw.simulate(fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, output_map=3),
                      u[k:], params=[0.5, 1.0, 0.4, 0.0, 0.0], initial=(u[:k], y[:k]))


def test_as_output_map_spellings():
    assert as_output_map(None) is None
    assert as_output_map("saturation") == Saturation()
    assert as_output_map("deadzone") == DeadZone()
    assert as_output_map(2) == PolynomialMap(2)
    for bad in ("saturate", 0, True, 1.5):
        with pytest.raises(fohw.ParameterError, match="output_map"):
            as_output_map(bad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "output_map=deadzone" in fohw.Structure.make(
            na=1, nb=1, f_basis=1, g_basis=1, output_map="deadzone").describe()


def test_cli_identify_and_select_with_an_output_map(tmp_path, capsys):
    from fohw.cli import main as cli

    _, _, u, _, y = _tanks_like("saturation", n=400, seed=4)
    data = tmp_path / "d.txt"
    np.savetxt(data, np.column_stack([u, y]))
    assert cli(["identify", str(data), "--na", "1", "--nb", "1", "--method", "output_error",
                "--output-map", "saturation", "--save", str(tmp_path / "r.json"), "-q"]) == 0
    out = capsys.readouterr().out
    assert "h_lower" in out and "h_upper" in out
    back = fohw.load_result(tmp_path / "r.json")
    assert back.structure.output_map == Saturation()
    assert cli(["select", str(data), "--na", "1", "--method", "output_error",
                "--output-map", "none,saturation", "-q"]) == 0
    out = capsys.readouterr().out
    assert "output_map=None" in out and "output_map=saturation" in out


def test_select_structure_over_output_maps():
    _, _, u, _, y = _tanks_like("saturation", n=800, seed=5)
    sel = fohw.select_structure(u, y, {"output_map": [None, "saturation", "deadzone"]}, na=1,
                                f_basis=1, g_basis=1, method="output_error")
    assert [r["status"] for r in sel.rows] == ["ok"] * 3
    assert sel.best.structure.output_map == Saturation()      # the truth is a saturation


def test_compare_and_predict_apply_the_map():
    _, truth, u, y_true, y = _tanks_like("saturation", seed=6)
    res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map="saturation")
    v = fohw.compare(res, u, y)
    np.testing.assert_array_equal(v.simulated, res.simulate(u))
    # the noise is 0.02: the free run of a good fit leaves about that (RMS of 600 noise
    # samples spreads by 1/sqrt(2 * 600) = 3 %; 4 of those)
    assert v.rmse_simulation < 0.02 * (1 + 4 / np.sqrt(2 * 600))
    lo, hi = res.output_map_params.values()
    yhat = res.predict(u, y)
    assert lo - 1e-12 <= yhat.min() and yhat.max() <= hi + 1e-12


def test_a_given_start_of_the_series_structure_is_searched_from():
    _, _, u, _, y = _tanks_like("saturation", seed=7)
    first = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                          output_map="saturation")
    again = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                          output_map="saturation", start=first)
    assert again.details["start"] == "the given start" and "identity_sse" not in again.details
    assert again.details["simulation_sse"] <= first.details["simulation_sse"]


def test_a_file_with_map_parameters_but_no_map_is_refused(tmp_path):
    import json

    _, _, u, _, y = _tanks_like("saturation", seed=2)
    res = fohw.identify(u, y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                        output_map="saturation")
    fohw.save_result(res, tmp_path / "r.json")
    d = json.loads((tmp_path / "r.json").read_text())
    del d["structure"]["output_map"]
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(fohw.DataFileError, match="output_map_params"):
        fohw.load_result(tmp_path / "bad.json")


def test_a_dead_zone_outside_the_data_is_reported_not_identified():
    # A review's reproducer: the dead zone starts at width 0 at 0 in data units, far below an
    # output near 5, and stays outside the data: h_lower has no effect on the output. The fit
    # said CONVERGED with no covariance and no reason; now RANK_DEFICIENT, naming it.
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 300)
    y = fohw.simulate(fohw.Structure.make(na=1, nb=2, nk=0, f_basis=1, g_basis=1, orders=0),
                      u, params=[0.5, 1.0, 0.4])
    y = y + 0.01 * rng.standard_normal(300)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = fohw.identify(u + 2, y + 5, na=1, nb=2, nk=0, f_basis=1, g_basis=1, orders=0,
                          operating_point="mean", method="output_error", output_map="deadzone")
    assert r.covariance is None and r.status == fohw.Status.RANK_DEFICIENT
    assert "Not identified at the estimate" in r.message and "h_lower" in r.message
    with pytest.raises(ValueError, match="rank deficient"):
        r.standard_errors()
