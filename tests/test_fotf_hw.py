"""fohw.FractionalHW (u -> f -> G(s) -> h -> y) and fohw.fit_fractional_hw (issue 25, item 3).

The simulator is checked at every sample against a literal per-sample implementation before any
estimator; the Jacobian against central differences; the fit against the Cramér–Rao bound.
"""

import numpy as np
import pytest

import fohw
from fohw.estimators.fotf_hw_fit import HWParametrisation, _simulate_and_jacobian
from fohw.exceptions import DimensionError, ParameterError
from fohw.model.fotf_hw import OutputMap


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
    ("identity", (), lambda x: x),
    ("polynomial", (0.4, -0.3), lambda x: x + 0.4 * x ** 2 - 0.3 * x ** 3),
    ("saturation", None, None),           # limits at the 20 % and 80 % quantiles of x
]


@pytest.mark.parametrize("kind,params,h_map", MAPS)
@pytest.mark.parametrize("h", [0.05, 1.0])
def test_simulation_equals_the_literal_model_at_every_sample(kind, params, h_map, h):
    num, num_orders, den, den_orders = [1.0, 0.3], [0.0, 0.5], [2.0, 0.7, 1.0], [1.3, 0.6, 0.0]
    G = fohw.FractionalTF(num, num_orders, den, den_orders, delay=2 * h)
    u = np.random.default_rng(0).uniform(-1, 1, 400)
    if kind == "saturation":
        x = fohw.FractionalHW(G, p=[1.0, 0.5, -0.2]).simulate(u, dt=h)
        lo, hi = np.quantile(x, [0.2, 0.8])
        params = (lo, hi)
        h_map = (lambda v: min(max(v, lo), hi))   # noqa: E731
    model = fohw.FractionalHW(G, p=[1.0, 0.5, -0.2], output_map=(kind, params) if params else kind)
    y = model.simulate(u, dt=h)
    ref = _literal(u, h, num, num_orders, den, den_orders, 2, [1.0, 0.5, -0.2], h_map)
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(y - ref)) <= 1e-12 * scale
    if kind == "saturation":           # the limits are reached, so the test covers them
        assert np.sum(ref == lo) > 50 and np.sum(ref == hi) > 50


def test_states_are_the_three_blocks():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    model = fohw.FractionalHW(G, p=[1.0, 2.0], output_map=("polynomial", [0.5]))
    u = np.linspace(0, 1, 50)
    w, x, y = model.simulate(u, states=True)
    np.testing.assert_array_equal(w, u + 2 * u ** 2)
    np.testing.assert_array_equal(x, G.simulate(w))
    np.testing.assert_array_equal(y, x + 0.5 * x ** 2)


def _fd(par, q, u, h, eps=1e-6):
    cols = []
    for j in range(q.size):
        e = np.zeros(q.size)
        e[j] = eps
        cols.append((par.model(q + e, h).simulate(u, h) - par.model(q - e, h).simulate(u, h)) / (2 * eps))
    return np.column_stack(cols)


@pytest.mark.parametrize("kind,params", [("identity", ()), ("polynomial", (0.4, -0.3)),
                                         ("saturation", (-0.3, 0.45))])
def test_jacobian_equals_central_differences(kind, params):
    h = 0.05
    G = fohw.FractionalTF([1.0, 0.3], [0.0, 0.5], [2.0, 1.0], [0.7, 0.0], delay=h)
    model = fohw.FractionalHW(G, p=[1.0, 0.5], output_map=(kind, params) if params else kind)
    par = HWParametrisation.of_model(model)
    u = np.random.default_rng(1).uniform(-1, 1, 300)
    q = par.q0
    _, jac = _simulate_and_jacobian(par, q, u, h, 1)
    ref = _fd(par, q, u, h)
    # central differences: truncation O(eps^2 y''') and rounding O(1e-16 |y| / eps) ~ 1e-9 of scale;
    # the saturation's kinks: a sample within eps of a limit would differ (none is, checked below)
    if kind == "saturation":
        x = par.model(q, h).simulate(u, h, states=True)[1]
        assert np.min(np.abs(x[:, None] - np.array(params))) > 1e-5
    assert np.max(np.abs(jac - ref)) <= 1e-7 * max(1.0, np.max(np.abs(ref)))


def _truth(kind):
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    out = {"polynomial": ("polynomial", [-0.2]), "saturation": ("saturation", [0.1, 0.45]),
           "identity": "identity"}[kind]
    return fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=out)


SPEC = {"polynomial": 2, "saturation": "saturation", "identity": "identity"}
H, N, SIGMA = 0.05, 1000, 0.01


def _data(kind, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2, 2, N)
    return u, _truth(kind).simulate(u, dt=H) + SIGMA * rng.standard_normal(N)


@pytest.mark.parametrize("kind", ["identity", "polynomial", "saturation"])
def test_fit_recovers_a_simulated_system_within_the_crb(kind):
    u, y = _data(kind, 11)
    fit = fohw.fit_fractional_hw(u, y, dt=H, num_orders=[0.0], den_orders=[0.5, 0.0], f_basis=2,
                                 output_map=SPEC[kind])
    names, cov = fohw.fractional_hw_crb(u, _truth(kind), dt=H, noise_std=SIGMA)
    assert list(fit.free_names) == names
    true = {"b0": 1.0, "a0": 2.0, "alpha0": 0.6, "p2": 0.3, "r2": -0.2, "lower": 0.1, "upper": 0.45}
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.isfinite(sd))                      # every parameter is informed
    z = np.array([(fit.estimates[n] - true[n]) / s for n, s in zip(names, sd)])
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
    true = {"b0": 1.0, "a0": 2.0, "alpha0": 0.6, "p2": 0.3, "r2": -0.2}
    zs = []
    for seed in range(10):
        u, y = _data(kind, 100 + seed)
        fit = fohw.fit_fractional_hw(u, y, dt=H, num_orders=[0.0], den_orders=[0.5, 0.0], f_basis=2,
                                     output_map=2, order_grid=3)
        names, cov = fohw.fractional_hw_crb(u, _truth(kind), dt=H, noise_std=SIGMA)
        zs.append([(fit.estimates[n] - true[n]) / np.sqrt(cov[i, i]) for i, n in enumerate(names)])
    rms = np.sqrt(np.mean(np.square(zs), axis=0))
    assert np.all(rms < 1.72) and np.all(rms > 0.385), dict(zip(names, rms))


def test_fixed_and_tied_parameters_and_a_start():
    u, y = _data("polynomial", 5)
    start = _truth("polynomial")
    fit = fohw.fit_fractional_hw(u, y, dt=H, num_orders=[0.0], den_orders=[0.5, 0.0], f_basis=2,
                                 output_map=2, free=["b0", "a0", "r2"], start=start)
    assert fit.free_names == ("b0", "a0", "r2")
    assert fit.model.G.den_orders[0] == 0.6 and fit.model.p[1] == 0.3      # held at the start
    fit2 = fohw.fit_fractional_hw(u, y, dt=H, num_orders=[0.0], den_orders=[0.5, 0.0], f_basis=2,
                                  output_map=2, free=["p2", "r2"], start=start)
    assert fit2.model.G.num[0] == 1.0 and fit2.free_names == ("p2", "r2")


def test_a_limit_never_reached_has_no_standard_error():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    model = fohw.FractionalHW(G, output_map=("saturation", [-5.0, 0.2]))
    u = np.random.default_rng(0).uniform(-1, 1, 300)
    names, cov = fohw.fractional_hw_crb(u, model, dt=0.1, noise_std=0.1)
    sd = dict(zip(names, np.sqrt(np.diag(cov))))
    assert np.isnan(sd["lower"]) and np.isfinite(sd["upper"]) and np.isfinite(sd["a0"])


@pytest.mark.parametrize("call,exc,match", [
    (lambda G: fohw.FractionalHW(G, p=[2.0, 1.0]), ParameterError, r"`p\[0\]` must be exactly 1"),
    (lambda G: fohw.FractionalHW(G, p=[1.0, 1.0], f_basis=3), DimensionError, "one entry per f-basis"),
    (lambda G: fohw.FractionalHW("G"), ParameterError, "`G` must be a FractionalTF"),
    (lambda G: fohw.FractionalHW(G, output_map=("saturation", [1.0, 0.0])), ParameterError, "lower < upper"),
    (lambda G: fohw.FractionalHW(G, output_map="cubic"), ParameterError, "`output_map`"),
    (lambda G: OutputMap("identity", [1.0]), DimensionError, "no parameters"),
    (lambda G: OutputMap("polynomial", [np.nan]), ParameterError, "finite"),
])
def test_bad_model_input(call, exc, match):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    with pytest.raises(exc, match=match):
        call(G)


def test_bad_fit_input():
    u = np.zeros(50)
    kw = dict(dt=0.1, num_orders=[0.0], den_orders=[0.5, 0.0])
    with pytest.raises(DimensionError, match="same length"):
        fohw.fit_fractional_hw(u, np.zeros(49), **kw)
    with pytest.raises(ParameterError, match="`free`: unknown"):
        fohw.fit_fractional_hw(u, np.ones(50), free=["zeta"], **kw)
    with pytest.raises(ParameterError, match="range of `y`"):
        fohw.fit_fractional_hw(u, np.ones(50), output_map="saturation", **kw)
    with pytest.raises(ParameterError, match="`dt`"):
        fohw.fit_fractional_hw(u, u, dt=0.0, num_orders=[0.0], den_orders=[0.5, 0.0])


# ---- relation to the paper's lagged class (docs/transfer_functions.md) ----------------------------

def test_coincides_with_the_lagged_class_for_a_first_order_integer_block():
    """G = 1/(s + 1) with a delay of one sample, f = g = identity: backward Euler gives
    x[k] = x[k-1] / (1 + h) + h w[k-1] / (1 + h), the lagged model with order-0 terms
    a1 = 1 / (1 + h), b1 = h / (1 + h)."""
    h = 0.1
    ftf = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], delay=h))
    lagged = fohw.HammersteinWiener([1 / (1 + h)], [h / (1 + h)], [1.0], [1.0], orders=0, dt=h)
    u = np.random.default_rng(4).standard_normal(2000)
    y1, y2 = ftf.simulate(u, dt=h), fohw.simulate(lagged, u)
    assert np.max(np.abs(y1 - y2)) <= 1e-13 * np.max(np.abs(y2))


def test_summary_and_frequency_view():
    u, y = _data("polynomial", 3)
    fit = fohw.fit_fractional_hw(u, y, dt=H, num_orders=[0.0], den_orders=[0.5, 0.0], f_basis=2,
                                 output_map=2)
    text = fit.summary()
    assert "alpha0" in text and "r2" in text
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
