"""``fohw.order_test`` of every kind: the fit with its free orders held at 0 against the fit.

Each case in ``CASES`` is a factory ``order -> (true model, start model, input, noise sd)``
whose free order (``Parameter(order=True)``) at 0 is a model of the same kind that is still
identified, so that orders 0 is a proper null (an order at 0 often is not: a transfer
function's ``a s^alpha + 1`` becomes the constant ``a + 1``, and ``a`` and the gain one
parameter; a ZARC's order lies in (0, 1], so orders 0 are outside its class and refused):

- a small kind defined here, ``tau D^(1 - alpha) y + y = gain u`` (alpha in [0, 0.7]: at 0 the
  first-order lag; the null on the order's lower bound, the chi-bar-squared mixture);
- ``fohw.FractionalTF`` ``b s^beta / (a s + 1)`` (beta in (-2, 2): at 0 the first-order lag,
  the null inside the bounds, chi2_1);
- ``fohw.FractionalHW`` ``u -> u + p2 u^2 -> b / (a s + s^alpha) -> x + c2 x^2`` with a
  polynomial output map (at alpha = 0 the first-order lag; normalised by the s^alpha term);
- ``fohw.HammersteinWiener`` fitted by ``fohw.fit`` (commensurate alpha: at 0 the integer
  model).

The checks: with a clearly fractional truth (0.5, small noise) the test rejects orders 0; the
statistic is ``N log(RSS_r / RSS_f)`` from the residuals of an independent fit at orders 0
and of the full fit, and the p-value its reference's tail (computed here from scipy); the fit at
orders 0 never ends above the full estimate with its orders put to 0; with the truth at orders 0
the p-value is not small over a few seeds; Records and arrays give the same test; the refusals
(no free order, an order bounded away from 0) name what is wrong. Small N, order_grid 3.
"""

import math

import numpy as np
import pytest
import scipy.stats

import fohw

#: The fit settings (quick; FitResult.options carries them to the refits).
SETTINGS = dict(order_grid=3, n_starts=1)


class FractionalInputLag(fohw.Model):
    """``tau D^(1 - alpha) y + y = gain u`` by Grünwald–Letnikov at step ``dt`` (implicit).

    ``(tau / dt^nu) sum_j w_j y[k-j] + y[k] = gain u[k]`` with ``nu = 1 - alpha`` and
    ``w = gl_weights(nu)``: at ``alpha = 0`` the backward-Euler first-order lag.
    """

    kind = "TestFractionalInputLag"

    def __init__(self, gain=1.0, tau=1.0, alpha=0.3, *, dt=0.1):
        self.gain, self.tau, self.alpha, self.step = float(gain), float(tau), float(alpha), float(dt)

    @property
    def dt(self):
        return self.step

    def config(self):
        return {"dt": self.step}

    @property
    def parameters(self):
        return fohw.Parameters([
            fohw.Parameter("gain", self.gain),
            fohw.Parameter("tau", self.tau, bounds=(1e-3, 1e3)),
            fohw.Parameter("alpha", self.alpha, bounds=(0.0, 0.7), order=True)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return FractionalInputLag(v["gain"], v["tau"], v["alpha"], dt=self.step)

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        nu = 1.0 - self.alpha
        w = fohw.gl_weights(nu, u.size)
        c = self.tau / self.step ** nu
        y = np.zeros(u.size)
        for k in range(u.size):
            memory = np.dot(w[1:k + 1], y[k - 1::-1]) if k else 0.0
            y[k] = (self.gain * u[k] - c * memory) / (1.0 + c)
        return y


def _with(model, name, **changes):
    return model.with_parameters(model.parameters.replace(name, **changes))


def small_kind(order):
    u = np.repeat(np.random.default_rng(11).standard_normal(30), 10)          # N = 300
    return FractionalInputLag(2.0, 0.5, order), FractionalInputLag(1.0, 1.0, 0.3), u, 0.02


def fractional_tf(order):
    def tf(beta):
        G = fohw.FractionalTF([1.0], [beta], [2.0, 1.0], [1.0, 0.0], dt=0.05)
        return _with(_with(G, "alpha0", fixed=True), "beta0", fixed=False)   # beta0 the only order
    return tf(order), tf(0.2), np.random.default_rng(21).standard_normal(300), 0.01


def fractional_hw(order):
    def hw(alpha, p2, c2):
        G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [1.0, alpha], dt=0.05)
        m = fohw.FractionalHW(G, p=[1.0, p2], f_basis=2, output_map=2, output_params=[c2], dt=0.05)
        return _with(m, "alpha0", fixed=True)                    # alpha1 (of s^alpha) the order
    return (hw(order, 0.3, -0.2), hw(0.3, 0.0, 0.0),
            np.random.default_rng(13).uniform(-2.0, 2.0, 300), 0.01)


def hammerstein_wiener(order):
    true = fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.3], [1.0], 0.4)
    true = true.with_parameters({"alpha": order})
    start = fohw.HammersteinWiener([0.1], [0.5, 0.1], [1.0, 0.0], [1.0], 0.6)
    return true, start, np.random.default_rng(22).uniform(-1.7, 1.7, 300), 0.02


#: name -> (factory, the free order, its lower bound is 0 (the chi-bar-squared mixture), the
#: fit's settings). The transfer function's numerator order has a local minimum near -0.1 on
#: its record (bounds (-2, 2)), which one start of a 3-point scan finds: three starts.
CASES = {"small kind": (small_kind, "alpha", True, SETTINGS),
         "FractionalTF": (fractional_tf, "beta0", False, dict(SETTINGS, n_starts=3)),
         "FractionalHW with an output map": (fractional_hw, "alpha1", True, SETTINGS),
         "HammersteinWiener by fohw.fit": (hammerstein_wiener, "alpha", True, SETTINGS)}


def _record(factory, order, seed):
    true, start, u, sd = factory(order)
    y = true.simulate(u) + sd * np.random.default_rng(seed).standard_normal(np.shape(u)[0])
    return true, start, u, y


def _sse(model, u, y):
    r = y - np.asarray(model.simulate(u), dtype=float)
    return float(r @ r)


@pytest.fixture(scope="module", params=list(CASES))
def fractional(request):
    """A fit of each kind to a record made with its order at 0.5."""
    factory, order, on_bound, settings = CASES[request.param]
    true, start, u, y = _record(factory, 0.5, seed=1)
    return dict(name=request.param, order=order, on_bound=on_bound, u=u, y=y, settings=settings,
                fit=fohw.fit(start, u, y, **settings))


def test_a_fractional_order_is_told_from_orders_0(fractional):
    fit, u, y, order = fractional["fit"], fractional["u"], fractional["y"], fractional["order"]
    assert fit.status == fohw.Status.CONVERGED, fit.message
    t = fohw.order_test(fit, u, y)
    assert t.hypothesis == f"{order} = 0" and t.df == 1
    assert t.pvalue < 0.01 and t.pvalue_corrected < 0.01
    # The fit at orders 0, made here independently: the same model, the order fixed at 0,
    # the same settings and data.
    model0 = _with(fit.model, order, value=0.0, fixed=True)
    restricted = fohw.fit(model0, u, y, start=model0, **fractional["settings"])
    r_r = y - restricted.simulate(u)
    assert t.rss_restricted == pytest.approx(float(r_r @ r_r), rel=1e-12)
    # Nested: it never ends above the full estimate with its order put to 0.
    assert t.rss_restricted <= _sse(model0, u, y)
    # The full fit is already at its optimum here (its refit from the restricted estimate
    # gained nothing), so the statistic is of the two fits' own residuals.
    assert "refitted" not in t.note
    r_f = y - fit.simulate(u)
    assert t.rss_full == pytest.approx(float(r_f @ r_f), rel=1e-12)
    n = y.size
    assert t.n == n
    assert t.statistic == pytest.approx(n * math.log((r_r @ r_r) / (r_f @ r_f)), rel=1e-12)
    tail = scipy.stats.chi2.sf(t.statistic, 1)
    if fractional["on_bound"]:           # 0 on the order's lower bound: 0.5 chi2_0 + 0.5 chi2_1
        assert t.boundary == (order,) and t.pvalue == pytest.approx(0.5 * tail, rel=1e-9)
    else:                                # 0 inside its bounds: chi2_1
        assert t.boundary == () and t.pvalue == pytest.approx(tail, rel=1e-9)


def test_the_method_names_the_verb(fractional):
    # FitResult sits below the fitting code (CONTRIBUTING.md's layers), so fit.order_test
    # cannot refit: it raises, naming the call that does; so does the verb without the data.
    fit = fractional["fit"]
    for call in (lambda: fit.order_test(fractional["u"], fractional["y"]), fit.order_test,
                 lambda: fohw.order_test(fit)):
        with pytest.raises(fohw.ParameterError, match=r"fohw.order_test\(fit, u, y\)"):
            call()


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_with_the_truth_at_orders_0_the_pvalue_is_not_small(name):
    # Under the null the p-value is about uniform (with the mixture, 1 half the time): on
    # three seeded records each is above 0.001 (all three pass by chance with probability
    # 0.997 if the test has its size).
    factory, _, _, settings = CASES[name]
    for seed in (1, 2, 3):
        _, start, u, y = _record(factory, 0.0, seed)
        fit = fohw.fit(start, u, y, **settings)
        t = fohw.order_test(fit, u, y)
        assert t.pvalue > 1e-3, (seed, t)


def test_records_and_arrays_give_the_same_test():
    true, start, u, y = _record(small_kind, 0.5, seed=1)
    by_arrays = fohw.order_test(fohw.fit(start, u, y, **SETTINGS), u, y)
    record = fohw.Record(u, y, dt=0.1)
    by_record = fohw.order_test(fohw.fit(start, record, **SETTINGS), record)
    for what in ("statistic", "pvalue", "rss_restricted", "rss_full", "statistic_corrected"):
        assert getattr(by_record, what) == pytest.approx(getattr(by_arrays, what), rel=1e-12)
    # Two records fitted as one data set: the test refits at orders 0 on both.
    halves = [fohw.Record(u[:150], y[:150], dt=0.1), fohw.Record(u[150:], y[150:], dt=0.1)]
    fit = fohw.fit(start, halves, **SETTINGS)
    t = fohw.order_test(fit, halves)
    model0 = _with(fit.model, "alpha", value=0.0, fixed=True)
    restricted = fohw.fit(model0, halves, start=model0, **SETTINGS)
    assert t.rss_restricted == pytest.approx(restricted.sse, rel=1e-12) and t.pvalue < 0.01
    with pytest.raises(fohw.ParameterError, match="not the data `full` was fitted to"):
        fohw.order_test(fit, halves[:1] + halves[:1])


def test_the_verdict_with_held_back_data():
    true, start, u, y = _record(small_kind, 0.5, seed=1)
    u_val = np.repeat(np.random.default_rng(5).standard_normal(20), 10)
    y_val = true.simulate(u_val) + 0.02 * np.random.default_rng(6).standard_normal(200)
    fit = fohw.fit(start, u, y, **SETTINGS)
    t = fohw.order_test(fit, u, y, validation=(u_val, y_val))
    assert t.verdict == "significant and validates"
    r, f = t.validation
    assert f >= r + t.margin
    again = fohw.order_test(fit, u, y, validation=fohw.Record(u_val, y_val, dt=0.1))
    assert again.validation == t.validation and again.verdict == t.verdict


def test_the_settings_of_the_fit_reach_the_fit_at_orders_0():
    # A held-back block (sample_weight 0) stays out of the restricted criterion too.
    true, start, u, y = _record(small_kind, 0.5, seed=1)
    weight = np.ones(u.size)
    weight[100:150] = 0.0
    fit = fohw.fit(start, u, y, sample_weight=weight, **SETTINGS)
    t = fohw.order_test(fit, u, y)
    model0 = _with(fit.model, "alpha", value=0.0, fixed=True)
    restricted = fohw.fit(model0, u, y, start=model0, sample_weight=weight, **SETTINGS)
    r = (y - restricted.simulate(u)) * np.sqrt(weight)
    assert t.rss_restricted == pytest.approx(float(r @ r), rel=1e-12)
    assert t.n == 250
    # Two records with a weight each: the fit keeps one array over both, which the refits
    # split back per record.
    halves = [fohw.Record(u[:150], y[:150], dt=0.1), fohw.Record(u[150:], y[150:], dt=0.1)]
    weights = [weight[:150], weight[150:]]
    fit = fohw.fit(start, halves, sample_weight=weights, **SETTINGS)
    t = fohw.order_test(fit, halves)
    restricted = fohw.fit(model0, halves, start=model0, sample_weight=weights, **SETTINGS)
    assert t.rss_restricted == pytest.approx(restricted.sse, rel=1e-12) and t.n == 250
    # An order estimated per record is refused (its values are not one parameter).
    with pytest.raises(fohw.ParameterError, match=r"estimates the order\(s\) \['alpha'\] once per"):
        fohw.order_test(fohw.fit(start, halves, per_record=["alpha"], **SETTINGS), halves)


def test_a_fit_without_a_free_order_is_refused_naming_its_parameters():
    true, start, u, y = _record(small_kind, 0.5, seed=1)
    fit = fohw.fit(_with(start, "alpha", value=0.5, fixed=True), u, y, **SETTINGS)
    with pytest.raises(fohw.ParameterError, match=r"no free order .*gain \(free\), tau \(free\), "
                                                  r"alpha \(order, fixed\)"):
        fohw.order_test(fit, u, y)


def _circuit_fit(model, u):
    """A FitResult of a circuit at its own values (the refusal reads only its parameters)."""
    return fohw.FitResult(model=model, parameters=model.parameters, covariance=None,
                          status=fohw.Status.CONVERGED, sse=1.0, n_samples=np.shape(u)[0])


@pytest.mark.parametrize("kind", ["EquivalentCircuit", "CircuitTables"])
def test_a_zarc_order_is_bounded_away_from_0_so_the_null_is_refused(kind):
    # A ZARC's order lies in (0, 1] (1 is the RC element), its bounds (0.05, 1): orders 0 are
    # not in the circuit's class (at 0 the element is the resistor R / 2, beside R0).
    ocv = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
    i = np.repeat(np.random.default_rng(23).uniform(-3.0, 1.2, 10), 20)
    if kind == "EquivalentCircuit":
        model = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015, ocv=ocv)
        u = np.column_stack([i, 0.8 + np.cumsum(i) / 18000])
    else:
        model = fohw.CircuitTables(["zarc"], soc_points=[0.3, 0.8], temperature_points=[5.0, 35.0],
                                   ocv=ocv)
        u = np.column_stack([i, 0.8 + np.cumsum(i) / 18000, np.full(i.size, 25.0)])
    y = model.simulate(u)
    with pytest.raises(fohw.ParameterError, match=r"order alpha1 is bounded to \(0.05, 1\), so "
                                                  "orders 0 are outside its bounds"):
        fohw.order_test(_circuit_fit(model, u), u, y)


def test_a_lagged_fit_with_a_series_output_map_is_tested():
    # Issue 41: the lagged kind's J of a fit with a series map is of the inner one-step
    # prediction, so the record check refused the very record it was fitted to; the refit at
    # orders 0 dropped the map. Now the record is checked by the free-run criterion, and the
    # restricted fit is the same class with every order 0: an independent identify() at
    # orders=0 with the fit's (resolved) map gives the same restricted criterion.
    data = fohw.datasets.paper_example(300, random_state=0)
    u, y = data.u, np.minimum(data.y, np.quantile(data.y, 0.9))           # a clipped output
    kw = dict(na=1, nb=1, f_basis=1, g_basis=1, method="output_error")
    full = fohw.identify(u, y, orders="commensurate", output_map="saturation", **kw)
    t = fohw.order_test(full, u, y)
    integer = fohw.identify(u, y, orders=0, output_map=full.structure.output_map, **kw)
    assert t.rss_restricted == pytest.approx(integer.details["simulation_sse"], rel=1e-9)
    n = y.size - int(full.options.get("n_init", 0))
    assert t.statistic == pytest.approx(max(n * math.log(t.rss_restricted / t.rss_full), 0.0),
                                        rel=1e-12)
    with pytest.raises(fohw.ParameterError, match="free-run error sum of squares"):
        fohw.order_test(full, u, y + 0.01)
