"""fohw.FractionalHW (u -> f -> G(s) -> h -> y), a fohw.Model fitted by fohw.fit.

The simulator is checked at every sample against a literal per-sample implementation before any
estimator; the Jacobian against central differences; the fit against the Cramér–Rao bound.
"""

import json

import numpy as np
import pytest

import fohw
from fohw.exceptions import DimensionError, ParameterError
from fohw.model.output_map import DeadZone, PiecewiseLinear, PolynomialMap, Saturation
from fohw.model.parameters import ORDER_RANGE


def _gl(nu, n):
    """GL weights by their defining recursion w_0 = 1, w_j = w_{j-1} (1 - (nu + 1) / j)."""
    w = np.empty(n)
    w[0] = 1.0
    for j in range(1, n):
        w[j] = w[j - 1] * (1.0 - (nu + 1.0) / j)
    return w


def _literal(u, h, num, num_orders, den, den_orders, delay_samples, p, h_map):
    """The model written out sample by sample: w = sum p_j u^j; the implicit GL recursion of
    sum a_i D^alpha_i x = sum b_j D^beta_j w(t - delay); y = h(x)."""
    n = len(u)
    w = [sum(pj * uk ** (j + 1) for j, pj in enumerate(p)) for uk in u]
    wd = [0.0] * delay_samples + w[:n - delay_samples]
    c = sum(a * h ** (-al) * _gl(al, n) for a, al in zip(den, den_orders))
    d = sum(b * h ** (-be) * _gl(be, n) for b, be in zip(num, num_orders))
    x = np.zeros(n)
    y = np.zeros(n)
    for k in range(n):
        rhs = sum(d[j] * wd[k - j] for j in range(k + 1))
        rhs -= sum(c[j] * x[k - j] for j in range(1, k + 1))
        x[k] = rhs / c[0]
        y[k] = h_map(x[k])
    return y


MAPS = [
    ("identity", None, (), lambda x: x),
    ("polynomial", PolynomialMap(3), (0.4, -0.3), lambda x: x + 0.4 * x ** 2 - 0.3 * x ** 3),
    ("saturation", Saturation(), None, None),       # limits at the 20 % and 80 % quantiles of x
    ("deadzone", DeadZone(), None, None),           # ends at the 30 % and 70 % quantiles of x
]


@pytest.mark.parametrize("kind,hmap,params,h_map", MAPS)
@pytest.mark.parametrize("h", [0.05, 1.0])
def test_simulation_equals_the_literal_model_at_every_sample(kind, hmap, params, h_map, h):
    num, num_orders, den, den_orders = [1.0, 0.3], [0.0, 0.5], [2.0, 0.7, 1.0], [1.3, 0.6, 0.0]
    G = fohw.FractionalTF(num, num_orders, den, den_orders, delay=2 * h)
    u = np.random.default_rng(0).uniform(-1, 1, 400)
    if kind in ("saturation", "deadzone"):
        x = fohw.FractionalHW(G, p=[1.0, 0.5, -0.2]).simulate(u, dt=h)
        lo, hi = np.quantile(x, [0.2, 0.8] if kind == "saturation" else [0.3, 0.7])
        params = (lo, hi)
        h_map = ((lambda v: min(max(v, lo), hi)) if kind == "saturation"    # noqa: E731
                 else (lambda v: v - hi if v > hi else v - lo if v < lo else 0.0))
    model = fohw.FractionalHW(G, p=[1.0, 0.5, -0.2], output_map=hmap,
                              output_params=params if hmap is not None else None)
    y = model.simulate(u, dt=h)
    ref = _literal(u, h, num, num_orders, den, den_orders, 2, [1.0, 0.5, -0.2], h_map)
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(y - ref)) <= 1e-12 * scale
    if kind == "saturation":           # the limits are reached, so the test covers them
        assert np.sum(ref == lo) > 50 and np.sum(ref == hi) > 50
    if kind == "deadzone":             # samples inside the zone and on both sides
        assert np.sum(ref == 0.0) > 50 and np.sum(ref > 0) > 50 and np.sum(ref < 0) > 50


def test_states_are_the_three_blocks():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    model = fohw.FractionalHW(G, p=[1.0, 2.0], output_map=2, output_params=[0.5])
    u = np.linspace(0, 1, 50)
    w, x, y = model.simulate(u, states=True)
    np.testing.assert_array_equal(w, u + 2 * u ** 2)
    np.testing.assert_array_equal(x, G.simulate(w))
    # h(x) = x + 0.5 x^2, as PolynomialMap evaluates it (Horner): identical to the last bit
    np.testing.assert_array_equal(y, 0.0 + (1.0 + 0.5 * x) * x)


def test_parameters_names_defaults_and_round_trip():
    """Names as the old HWParametrisation gave them (G's stored order, p2…) plus the family's h_*;
    fixed by default: the lowest-order denominator coefficient and the zero orders."""
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.5, 0.0])
    model = fohw.FractionalHW(G, p=[1.0, 0.3], output_map="saturation", output_params=[-1, 1],
                              dt=0.1)
    params = model.parameters
    assert params.names == ("b0", "beta0", "a0", "a1", "alpha0", "alpha1", "p2", "h_lower",
                            "h_upper")
    assert params.free_names == ("b0", "a0", "alpha0", "p2", "h_lower", "h_upper")
    assert params["alpha0"].order and params["alpha0"].bounds == ORDER_RANGE
    new = model.with_parameters({"a0": 3.0, "alpha0": 0.7, "p2": -0.1, "h_upper": 2.0})
    assert new.G.den.tolist() == [3.0, 1.0] and new.G.den_orders.tolist() == [0.7, 0.0]
    assert new.p.tolist() == [1.0, -0.1] and new.output_params.tolist() == [-1.0, 2.0]
    assert model.p.tolist() == [1.0, 0.3]                      # the old model is unchanged
    back = fohw.Model.from_dict(json.loads(json.dumps(new.to_dict())))
    assert back == new and back.parameters == new.parameters
    u = np.random.default_rng(2).uniform(-1, 1, 200)
    np.testing.assert_array_equal(back.simulate(u), new.simulate(u))


def test_files_refuse_code_and_bad_configs():
    """A custom basis is code: its model is written (names only) but not rebuilt from a file."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    custom = fohw.FractionalHW(G, p=[1.0, 0.5], f_basis=[np.tanh, np.sin], dt=0.1)
    d = json.loads(json.dumps(custom.to_dict()))
    assert d["config"]["f_basis"] == {"kind": "custom", "names": ["tanh", "sin"]}
    with pytest.raises(ParameterError, match="`f_basis`.*custom code"):
        fohw.Model.from_dict(d)
    d = fohw.FractionalHW(G, dt=0.1).to_dict()
    d["config"]["n_den"] = 0
    with pytest.raises(ParameterError, match="`n_den` must be at least 1"):
        fohw.Model.from_dict(d)


def _fd(model, u, eps=1e-6):
    """Central differences of every parameter off its bounds (a zero denominator order sits on
    its bound 0: FractionalTF takes no negative one)."""
    params = model.parameters
    cols = []
    for name in params:
        v = params[name].value
        if not params[name].bounds[0] < v - eps < v + eps < params[name].bounds[1]:
            cols.append(np.full(u.size, np.nan))
            continue
        up = model.with_parameters({name: v + eps}).simulate(u)
        down = model.with_parameters({name: v - eps}).simulate(u)
        cols.append((up - down) / (2 * eps))
    return np.column_stack(cols)


@pytest.mark.parametrize("hmap,params", [(None, None), (PolynomialMap(3), (0.4, -0.3)),
                                         (Saturation(), (-0.3, 0.45))])
def test_jacobian_equals_central_differences(hmap, params):
    h = 0.05
    G = fohw.FractionalTF([1.0, 0.3], [0.0, 0.5], [2.0, 1.0], [0.7, 0.0], delay=h)
    model = fohw.FractionalHW(G, p=[1.0, 0.5], output_map=hmap, output_params=params, dt=h)
    u = np.random.default_rng(1).uniform(-1, 1, 300)
    yhat, jac = model.jacobian(u)
    np.testing.assert_array_equal(yhat, model.simulate(u))
    assert jac.shape == (300, len(model.parameters))           # every parameter, fixed ones too
    ref = _fd(model, u)
    skipped = [n for j, n in enumerate(model.parameters) if np.isnan(ref[0, j])]
    assert skipped == ["alpha1"]                               # G's constant term, fixed
    keep = ~np.isnan(ref[0])
    jac, ref = jac[:, keep], ref[:, keep]
    # central differences: truncation O(eps^2 y''') and rounding O(1e-16 |y| / eps) ~ 1e-9 of scale;
    # the saturation's kinks: a sample within eps of a limit would differ (none is, checked below)
    if hmap is not None and hmap.kind == "saturation":
        x = model.simulate(u, states=True)[1]
        assert np.min(np.abs(x[:, None] - np.array(params))) > 1e-5
    assert np.max(np.abs(jac - ref)) <= 1e-7 * max(1.0, np.max(np.abs(ref)))


TRUE_MAPS = {"polynomial": (PolynomialMap(2), [-0.2]),
             "saturation": (Saturation(), [0.1, 0.45]), "identity": (None, None)}
TRUE = {"b0": 1.0, "a0": 2.0, "alpha0": 0.6, "p2": 0.3, "h_c2": -0.2, "h_lower": 0.1,
        "h_upper": 0.45}
H, N, SIGMA = 0.05, 1000, 0.01


def _truth(kind):
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    hmap, params = TRUE_MAPS[kind]
    return fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=hmap, output_params=params,
                             dt=H)


def _start(kind, y):
    """The start the old fit_fractional_hw made of `den_orders=[0.5, 0.0]` and its map spec."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    hmap = TRUE_MAPS[kind][0]
    params = [float(np.min(y)), float(np.max(y))] if kind == "saturation" else None
    return fohw.FractionalHW(G, p=[1.0, 0.0], f_basis=2, output_map=hmap, output_params=params,
                             dt=H)


def _data(kind, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2, 2, N)
    return u, _truth(kind).simulate(u) + SIGMA * rng.standard_normal(N)


def _crb_sd(model, u, sigma):
    """Standard deviations of fohw.crb at the truth (sigma^2 (S^T S)^-1, S the free run's
    sensitivity, the exact Jacobian tested above against central differences), free order."""
    bound = fohw.crb(model, u, sigma ** 2)
    assert tuple(bound.parameter_names) == model.parameters.free_names
    return np.sqrt(np.diag(bound.covariance))


@pytest.mark.parametrize("kind", ["identity", "polynomial", "saturation"])
def test_fit_recovers_a_simulated_system_within_the_crb(kind):
    u, y = _data(kind, 11)
    fit = fohw.fit(_start(kind, y), u, y)
    assert fit.status == fohw.Status.CONVERGED, fit.message
    names = fit.free_names
    assert set(names) == set(TRUE) & set(fit.parameters)
    assert names == _truth(kind).parameters.free_names    # the bound's order (zip below)
    sd = _crb_sd(_truth(kind), u, SIGMA)
    assert np.all(np.isfinite(sd))                      # every parameter is informed
    z = np.array([(fit.parameters[n].value - TRUE[n]) / s for n, s in zip(names, sd)])
    # asymptotically z ~ N(0, 1): |z| < 4.5 fails with probability < 7e-6 per parameter
    assert np.all(np.abs(z) < 4.5), dict(zip(names, z))
    se = fit.standard_errors()                          # s^2 (J^T J)^{-1} at the estimate ~ the CRB
    assert all(0.8 < se[n] / s < 1.25 for n, s in zip(names, sd))


@pytest.mark.slow
def test_fit_spread_over_seeds_matches_the_crb():
    """Polynomial h, 10 seeds: sum z^2 over seeds ~ chi^2_10 per parameter; its 99.9 % quantile
    29.59 bounds the RMS of z by sqrt(29.59 / 10) = 1.72 (and its 0.1 % quantile 1.479 from below
    by 0.385)."""
    kind = "polynomial"
    zs = []
    for seed in range(10):
        u, y = _data(kind, 100 + seed)
        fit = fohw.fit(_start(kind, y), u, y, order_grid=3)
        names = fit.free_names
        sd = _crb_sd(_truth(kind), u, SIGMA)
        zs.append([(fit.parameters[n].value - TRUE[n]) / s for n, s in zip(names, sd)])
    rms = np.sqrt(np.mean(np.square(zs), axis=0))
    assert np.all(rms < 1.72) and np.all(rms > 0.385), dict(zip(names, rms))


def _held(model, free):
    params = model.parameters
    for name in params:
        if params[name].tie is None:
            params = params.replace(name, fixed=name not in free)
    return model.with_parameters(params)


def test_fixed_and_tied_parameters_and_a_start():
    u, y = _data("polynomial", 5)
    start = _truth("polynomial")
    fit = fohw.fit(_held(start, ["b0", "a0", "h_c2"]), u, y)
    assert fit.free_names == ("b0", "a0", "h_c2")
    assert fit.model.G.den_orders[0] == 0.6 and fit.model.p[1] == 0.3      # held at the start
    fit2 = fohw.fit(_held(start, ["p2", "h_c2"]), u, y)
    assert fit2.model.G.num[0] == 1.0 and fit2.free_names == ("p2", "h_c2")
    # a tie: b0 = 0.5 a0 (true values 1 and 2 satisfy it), so b0 follows a0 in the fit
    tied = start.parameters.replace("b0", tie=("a0", 0.5))
    fit3 = fohw.fit(start.with_parameters(tied), u, y)
    assert "b0" not in fit3.free_names
    assert fit3.parameters["b0"].value == 0.5 * fit3.parameters["a0"].value


def test_a_limit_never_reached_is_rank_deficient_and_named():
    """The lower limit -5 lies below every x: its Jacobian column is zero at every sample, so
    the data say nothing about it: the CRB and the fit name it (the old ones gave a nan
    standard error)."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    model = fohw.FractionalHW(G, output_map=Saturation(), output_params=[-5.0, 0.2], dt=0.1)
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 300)
    _, jac = model.jacobian(u)
    names = list(model.parameters)
    assert not np.any(jac[:, names.index("h_lower")]) and np.any(jac[:, names.index("h_upper")])
    with pytest.raises(ParameterError, match="h_lower are not identifiable"):
        fohw.crb(model, u, 0.01 ** 2)
    y = model.simulate(u) + 0.01 * rng.standard_normal(300)
    with pytest.warns(fohw.RankDeficiencyWarning, match="h_lower"):
        fit = fohw.fit(model, u, y)
    assert fit.status == fohw.Status.RANK_DEFICIENT and "h_lower" in fit.message
    assert fit.covariance is None


@pytest.mark.parametrize("call,exc,match", [
    (lambda G: fohw.FractionalHW(G, p=[2.0, 1.0]), ParameterError, r"`p\[0\]` must be exactly 1"),
    (lambda G: fohw.FractionalHW(G, p=[1.0, 1.0], f_basis=3), DimensionError, "one entry per f-basis"),
    (lambda G: fohw.FractionalHW("G"), ParameterError, "`G` must be a FractionalTF"),
    (lambda G: fohw.FractionalHW(G, output_map=Saturation(1.0, 0.0)), ParameterError,
     "lower < upper"),
    (lambda G: fohw.FractionalHW(G, output_map="cubic"), ParameterError, "`output_map`"),
    (lambda G: fohw.FractionalHW(G, output_map=("saturation", [-1, 1])), ParameterError,
     "`output_map` must be None"),
    (lambda G: fohw.FractionalHW(G, output_map=0), ParameterError, "`output_map` as a polynomial"),
    (lambda G: fohw.FractionalHW(G, output_map=PiecewiseLinear(4)), ParameterError,
     "`output_map`.*breakpoints"),
    (lambda G: fohw.FractionalHW(G, output_map="saturation"), ParameterError, "`output_params`"),
    (lambda G: fohw.FractionalHW(G, output_map=3, output_params=[1.0]), DimensionError,
     "`output_params`"),
    (lambda G: fohw.FractionalHW(G, output_map=2, output_params=[np.nan]), ParameterError, "finite"),
    (lambda G: fohw.FractionalHW(G, output_params=[1.0]), DimensionError, "no `output_map`"),
    (lambda G: fohw.FractionalHW(G, dt=0.0), ParameterError, "`dt`"),
    (lambda G: fohw.FractionalHW(G, dt=0.1).simulate(np.ones(3), initial="fitted"), ParameterError,
     "`initial`"),
])
def test_bad_model_input(call, exc, match):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    with pytest.raises(exc, match=match):
        call(G)


def test_bad_fit_input():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    model = fohw.FractionalHW(G, dt=0.1)
    u = np.random.default_rng(0).standard_normal(50)
    with pytest.raises(DimensionError, match="same length"):
        fohw.fit(model, u, np.zeros(49))
    with pytest.raises(ParameterError, match="`u` is zero"):
        fohw.fit(model, np.zeros(50), u)
    with pytest.raises(ParameterError, match="`y` is constant"):
        fohw.fit(model, u, np.ones(50))
    with pytest.raises(ParameterError, match="`dt` is needed"):
        fohw.fit(fohw.FractionalHW(G), u, u)
    sat = fohw.FractionalHW(G, output_map=Saturation(upper=-10.0), dt=0.1,
                            output_params=[-20.0])
    with pytest.raises(ParameterError, match="`output_map`.*entirely at one limit"):
        fohw.fit(sat, u, u)


def test_a_cubic_output_map_on_a_linear_record_is_a_fit_not_a_linalg_error():
    """Issue 34, case 13: `output_map=3` on the TF fixture ended in a raw LinAlgError. The truth
    has h_c2 = h_c3 = 0, so the fit must converge with every estimate near the truth."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0])
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    y = G.simulate(u, dt=0.1) + 1e-3 * rng.standard_normal(400)
    start = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
                              output_map=3, dt=0.1)
    fit = fohw.fit(start, u, y)
    assert fit.status == fohw.Status.CONVERGED, fit.message
    se = fit.standard_errors()
    for name, true in (("b0", 1.0), ("a0", 1.0), ("alpha0", 0.8), ("h_c2", 0.0), ("h_c3", 0.0)):
        assert abs(fit.parameters[name].value - true) < 4.5 * se[name], name


# ---- relation to the paper's lagged class (docs/transfer_functions.md) ----------------------------

def test_coincides_with_the_lagged_class_for_a_first_order_integer_block():
    """G = 1/(s + 1) with a delay of one sample, f = g = identity: backward Euler gives
    x[k] = x[k-1] / (1 + h) + h w[k-1] / (1 + h), the lagged model with order-0 terms
    a1 = 1 / (1 + h), b1 = h / (1 + h)."""
    h = 0.1
    ftf = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], delay=h), dt=h)
    lagged = fohw.HammersteinWiener([1 / (1 + h)], [h / (1 + h)], [1.0], [1.0], orders=0, dt=h)
    u = np.random.default_rng(4).standard_normal(2000)
    y1, y2 = ftf.simulate(u, dt=h), fohw.simulate(lagged, u)
    assert np.max(np.abs(y1 - y2)) <= 1e-13 * np.max(np.abs(y2))


def test_summary_and_frequency_view():
    u, y = _data("polynomial", 3)
    fit = fohw.fit(_start("polynomial", y), u, y)
    text = fit.summary()
    assert "alpha0" in text and "h_c2" in text
    back = fohw.FitResult.from_dict(json.loads(json.dumps(fit.to_dict())))
    assert back.model == fit.model and back.sse == fit.sse
    np.testing.assert_array_equal(back.simulate(u), fit.simulate(u))
    w = np.array([0.1, 1.0, 10.0])
    np.testing.assert_array_equal(fit.model.frequency_response(w), fit.model.G.frequency_response(w))
    assert fit.model.linearised_gain() == 1.0


@pytest.mark.parametrize("alpha", [0.5, 1.3])
def test_every_lagged_linear_block_is_a_gl_discretised_tf_at_the_same_dt(alpha):
    """q^-1 = 1 - h nabla_h exactly (nabla_h = (1 - q^-1)/h), so the lagged term q^-1 nabla^alpha is
    nabla^alpha - h nabla^(alpha+1): y = a q^-1 nabla^alpha y + b q^-1 nabla^alpha fbar(u) is the
    FTF (b s^alpha - b h s^(alpha+1)) / (1 - a s^alpha + a h s^(alpha+1)) simulated at that h, with
    the same Hammerstein map f and g = h = identity."""
    h, b = 0.1, 0.8
    a = -0.2 * h ** alpha      # |a h^-alpha x (1 - x)^alpha| <= 0.2 * 2^alpha < 1 on |x| <= 1: stable
    lagged = fohw.HammersteinWiener([a], [b], [1.0, 0.5], [1.0], alpha, dt=h)
    G = fohw.FractionalTF([b, -b * h], [alpha, alpha + 1], [1.0, -a, a * h], [0.0, alpha, alpha + 1])
    ftf = fohw.FractionalHW(G, p=[1.0, 0.5])
    u = np.random.default_rng(6).uniform(-1, 1, 3000)
    y1, y2 = ftf.simulate(u, dt=h), fohw.simulate(lagged, u)
    assert np.max(np.abs(y1 - y2)) <= 1e-12 * np.max(np.abs(y2))


def test_linear_start_solves_a_noise_free_record_at_the_true_orders():
    """Identity map, noise-free record, orders at the truth: the equation error is exact there
    (sum a_i W_alpha_i y = sum b_j W_beta_j fbar(u) holds sample by sample), and x is linear in
    b ⊗ p, so the start is the truth itself (to rounding), from coefficients far from it."""
    G = fohw.FractionalTF([1.5, 0.4], [0.0, 0.7], [2.0, 1.0], [0.6, 0.0])
    truth = fohw.FractionalHW(G, p=[1.0, 0.3, -0.1], dt=0.05)
    u = np.random.default_rng(8).uniform(-1.5, 1.5, 800)
    y = truth.simulate(u)
    wrong = truth.with_parameters({"b0": 0.2, "b1": -1.0, "a0": 0.5, "p2": 0.0, "p3": 0.0})
    start = wrong.linear_start(u, y)
    got, want = start.parameters.valuesdict(), truth.parameters.valuesdict()
    assert max(abs(got[n] - want[n]) for n in want) < 1e-8, got


def test_coefficient_sensitivities_alone_are_the_full_ones_columns():
    from fohw.model.wiener import tf_sensitivities
    G = fohw.FractionalTF([1.0, 0.3], [0.5, 0.0], [2.0, 0.7, 1.0], [1.3, 0.6, 0.0])
    w = np.random.default_rng(3).uniform(-1, 1, 300)
    x = G.simulate(w, dt=0.05)
    terms = (G.num, G.num_orders, G.den, G.den_orders)
    full = tf_sensitivities(*terms, w, x, 0.05)
    coef = tf_sensitivities(*terms, w, x, 0.05, orders=False)
    assert full.shape == (300, 10) and coef.shape == (300, 5)
    np.testing.assert_array_equal(coef, full[:, [0, 1, 4, 5, 6]])       # b0, b1, a0, a1, a2
