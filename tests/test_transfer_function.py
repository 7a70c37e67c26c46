"""fohw.FractionalTF: the GL simulation against literal loops and exact solutions, the sample
alignment, frequency responses, stability, arithmetic, figures and bad input (issue 25)."""

import numpy as np
import pytest
import scipy.signal
from tf_reference import SYSTEMS, literal_simulation, mittag_leffler

import fohw
from fohw.exceptions import DimensionError, ParameterError, SimulationDivergedError
from fohw.model.kernels import series_divide, series_reciprocal
from fohw.model.transfer_stability import commensurate_base, rhp_zero_count

RNG = np.random.default_rng(20250)


# ---------------------------------------------------------------- the kernel and the recursion
@pytest.mark.parametrize("n", [1, 2, 63, 64, 65, 300, 1000])
def test_series_division_equals_the_implicit_recursion_at_every_sample(n):
    c = np.r_[2.0, -0.9 * 0.5 ** np.arange(1, n)]           # a stable recursion
    f = RNG.standard_normal(n)
    y = np.zeros(n)
    for k in range(n):
        y[k] = (f[k] - np.dot(c[1:k + 1], y[:k][::-1])) / c[0]
    np.testing.assert_allclose(series_divide(f, c), y, rtol=0, atol=1e-13 * np.max(np.abs(y)))
    r = series_reciprocal(c, n)
    np.testing.assert_allclose(np.convolve(c, r)[:n], np.eye(1, n)[0], atol=1e-13)


@pytest.mark.parametrize("args", [
    ([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
    ([2.0, -1.0], [0.3, 0.0], [1.0, 0.4, 3.0], [1.7, 0.6, 0.0]),
    ([1.0, 0.5], [0.0, -0.5], [1.0, 1.0], [1.0, 0.0]),          # Warburg-type numerator
    ([1.0], [0.8], [1.0, 2.0], [1.2, 0.0]),
])
@pytest.mark.parametrize("h", [1.0, 0.05])
def test_simulate_equals_the_literal_gl_loop_at_every_sample(args, h):
    u = RNG.standard_normal(400)
    y = fohw.FractionalTF(*args).simulate(u, dt=h)
    ref = literal_simulation(*args, u, h)
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-11 * np.max(np.abs(ref)))


def test_delay_shifts_the_input_by_whole_samples():
    u = RNG.standard_normal(200)
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    Gd = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1, delay=0.3)
    np.testing.assert_allclose(Gd.simulate(u), np.r_[0, 0, 0, G.simulate(u)[:-3]], atol=1e-14)


# ---------------------------------------------------------------- sample alignment
@pytest.mark.parametrize("h", [0.1, 0.01])
def test_integer_order_matches_cont2discrete_backward_diff(h):
    """GL with alpha = 1 is backward Euler: the same samples as scipy's 'backward_diff'."""
    num, den = [1.0, 3.0], [1.0, 0.5, 2.0]                        # (s + 3) / (s^2 + 0.5 s + 2)
    G = fohw.FractionalTF(num, [1.0, 0.0], den, [2.0, 1.0, 0.0])
    u = RNG.standard_normal(500)
    bd, ad, _ = scipy.signal.cont2discrete((num, den), h, method="backward_diff")
    ref = scipy.signal.lfilter(bd.ravel(), ad, u)
    # rounding: the recursion sums terms up to ||c||_1 ~ 4/h^2 times the output (4e4 at h = 0.01)
    tol = 1e-16 * 4 / h ** 2 * np.max(np.abs(ref))
    np.testing.assert_allclose(G.simulate(u, dt=h), ref, rtol=0, atol=tol)
    # the other methods do not match: the alignment is a property, not an accident
    for method in ("zoh", "bilinear", "euler"):
        bm, am, _ = scipy.signal.cont2discrete((num, den), h, method=method)
        assert np.max(np.abs(scipy.signal.lfilter(bm.ravel(), am, u) - ref)) > 1e-4


def test_step_and_impulse_alignment_conventions():
    h = 0.25
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])
    t = np.arange(5) * h
    # u = [0, 1, 1, ...] read by backward Euler: y[k] = 1 - (1 + h)^-k
    np.testing.assert_allclose(G.step(t, dt=h), 1 - (1 + h) ** -np.arange(5.0), atol=1e-15)
    np.testing.assert_allclose(G.impulse(t, dt=h), np.r_[0.0, (1 + h) ** -np.arange(1.0, 5.0)], atol=1e-15)
    # the integrator's step is exact at every sample (the rectangle rule on (t_{k-1}, t_k])
    integ = fohw.FractionalTF([1.0], [0.0], [1.0], [1.0])
    np.testing.assert_allclose(integ.step(t, dt=h), t, atol=1e-15)
    # step(t) reads the response on the grid, in the order asked for
    tt = np.array([1.0, 0.0, 0.5])
    np.testing.assert_allclose(G.step(tt, dt=h), G.step(t, dt=h)[[4, 0, 2]], atol=1e-15)
    # dt from the model, or from an equally spaced t starting at 0
    np.testing.assert_allclose(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], dt=h).step(t),
                               G.step(t), atol=1e-15)


def test_mittag_leffler_reference_against_closed_forms():
    from scipy.special import erfcx
    t = np.linspace(0.01, 5, 50)
    np.testing.assert_allclose(mittag_leffler(0.5, -np.sqrt(t)), erfcx(np.sqrt(t)), rtol=1e-12)
    np.testing.assert_allclose(mittag_leffler(1.0, -t), np.exp(-t), rtol=1e-11)
    np.testing.assert_allclose(mittag_leffler(2.0, -t ** 2), np.cos(t), atol=1e-12)


H_LIST = [0.1 / 2 ** i for i in range(6)]


def _errors(name, kind):
    args, step, impulse = SYSTEMS[name]
    G = fohw.FractionalTF(*args)
    out = []
    for h in H_LIST:
        t = np.arange(int(round(3.0 / h)) + 1) * h
        k1 = int(round(1.0 / h))
        if kind == "step":
            y = G.step(t, dt=h)
            out.append((np.max(np.abs(y[1:] - step(t[1:]))), abs(y[k1] - step(1.0))))
        else:
            y = G.impulse(t, dt=h)
            out.append((np.max(np.abs(y[k1:] - impulse(t[k1:]))), abs(y[k1] - impulse(1.0))))
    return np.array(out)


@pytest.mark.parametrize("name", list(SYSTEMS))
@pytest.mark.parametrize("kind", ["step", "impulse"])
def test_first_order_convergence_to_the_exact_response(name, kind):
    """At a fixed time the GL error is O(h) for every system; over all samples of the step it is
    O(h^min(alpha, 1)) (the solution's t^alpha start); the impulse is compared from t = 1 on."""
    err = _errors(name, kind)
    order_at_1 = np.log2(err[-2, 1] / err[-1, 1])
    assert 0.95 < order_at_1 < 1.05, (order_at_1, err)
    order_max = np.log2(err[-2, 0] / err[-1, 0])
    alpha = {"1/(s^0.5+1)": 0.5, "1/(s^0.7+1)": 0.7, "s^-0.5": 0.5}.get(name, 1.0)
    expected = alpha if kind == "step" else 1.0
    assert abs(order_max - expected) < 0.08, (order_max, err)
    assert err[-1, 0] < 0.01                                    # h = 0.003125


# ---------------------------------------------------------------- frequency response
def test_frequency_response_equals_closed_forms():
    w = np.logspace(-3, 3, 301)
    s = 1j * w
    cases = [
        (([1.0], [0.0], [1.0, 1.0], [1.0, 0.0]), 1 / (s + 1)),
        (([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), 1 / (np.sqrt(s) + 1)),
        (([2.0, 1.0], [1.0, 0.0], [1.0, 0.2, 1.0], [2.0, 1.0, 0.0]), (2 * s + 1) / (s ** 2 + 0.2 * s + 1)),
        (([1.0], [0.0], [1.0, 1.0], [1.5, 0.0]), 1 / (s * np.sqrt(s) + 1)),
        (([1.0, 1.0], [0.0, -0.5], [1.0], [0.0]), 1 + 1 / np.sqrt(s)),
        (([3.0], [0.0], [1.0, 2.0, 1.0], [2.3, 0.9, 0.0]),
         3 / (np.exp(2.3 * np.log(s)) + 2 * np.exp(0.9 * np.log(s)) + 1)),
    ]
    for args, exact in cases:
        g = fohw.FractionalTF(*args).frequency_response(w)
        np.testing.assert_allclose(g, exact, rtol=1e-12, atol=0)
    Gd = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], delay=0.3)
    np.testing.assert_allclose(Gd.frequency_response(w), np.exp(-0.3 * s) / (s + 1), rtol=1e-12)
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    np.testing.assert_allclose(G.frequency_response(-w), np.conj(G.frequency_response(w)), rtol=1e-15)


def test_discrete_frequency_response_matches_freqz_at_alpha_1_and_tends_to_the_exact_one():
    h = 0.05
    num, den = [1.0, 3.0], [1.0, 0.5, 2.0]
    G = fohw.FractionalTF(num, [1.0, 0.0], den, [2.0, 1.0, 0.0], dt=h)
    w = np.linspace(0.01, 0.99 * np.pi / h, 200)
    bd, ad, _ = scipy.signal.cont2discrete((num, den), h, method="backward_diff")
    _, ref = scipy.signal.freqz(bd.ravel(), ad, worN=w * h)
    np.testing.assert_allclose(G.discrete_frequency_response(w), ref, rtol=1e-11)
    F = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    w = np.array([0.1, 1.0, 3.0])
    errs = [np.max(np.abs(F.discrete_frequency_response(w, dt=h) / F.frequency_response(w) - 1))
            for h in (1e-2, 1e-3)]
    assert 8 < errs[0] / errs[1] < 12                              # O(h)


def test_simulated_sinusoid_follows_the_discrete_frequency_response():
    """The GL recursion's steady state is the discrete response (the transient decays like t^-1.5)."""
    h, w0 = 0.01, 2.0
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=h)
    t = np.arange(200_000) * h
    y = G.simulate(np.sin(w0 * t))
    g = G.discrete_frequency_response([w0])[0]
    tail = slice(-2000, None)
    ref = np.abs(g) * np.sin(w0 * t[tail] + np.angle(g))
    assert np.max(np.abs(y[tail] - ref)) < 1e-4


def test_dcgain():
    assert fohw.FractionalTF([2.0], [0.0], [1.0, 4.0], [0.7, 0.0]).dcgain == 0.5
    assert fohw.FractionalTF([1.0], [0.5], [1.0, 1.0], [0.7, 0.0]).dcgain == 0.0
    assert fohw.FractionalTF([1.0, 1.0], [0.0, -0.5], [1.0], [0.0]).dcgain == np.inf
    assert fohw.FractionalTF([-1.0], [0.0], [1.0], [0.5]).dcgain == -np.inf
    G = fohw.FractionalTF([3.0], [0.0], [1.0, 2.0], [0.5, 0.0])
    assert G.dcgain == pytest.approx(G.step([0.0, 4000.0], dt=0.5)[-1], rel=0.02)


# ---------------------------------------------------------------- poles and stability
STABLE = [
    ([1.0, 1.0], [0.5, 0.0]),
    ([1.0, 0.5, 1.0], [1.6, 0.8, 0.0]),            # lambda = s^0.8: complex pair, |arg| > 0.4 pi
    ([1.0, 2.0, 1.0], [1.5, 1.0, 0.0]),
    ([1.0, 0.2, 1.0], [2.0, 1.0, 0.0]),
    ([1.0, -0.1, 1.0], [1.8, 0.9, 0.0]),           # negative damping, still stable for q = 0.9
]
UNSTABLE = [
    ([1.0, -1.0], [0.5, 0.0]),
    ([1.0, -0.5, 1.0], [2.0, 1.0, 0.0]),
    ([1.0, -0.5, 1.0], [1.8, 0.9, 0.0]),           # q = 0.9: the pair at |arg lambda| < 0.45 pi
    ([1.0, 0.1, 1.0], [2.4, 1.2, 0.0]),            # order above 2 between 1.2 pi/2 ... unstable
]


def _long_step_grows(args, n=40_000, h=0.05):
    G = fohw.FractionalTF([1.0], [0.0], *args, dt=h)
    try:
        y = G.step(np.arange(n) * h)
    except SimulationDivergedError:
        return True
    tail = np.abs(y[-n // 4:] - G.dcgain)
    mid = np.abs(y[n // 2:n // 2 + n // 4] - G.dcgain)
    return bool(np.max(tail) > 10 * max(np.max(mid), 1e-3) or np.max(np.abs(y)) > 1e6)


@pytest.mark.parametrize("den", STABLE)
def test_stable_systems_by_matignon_argument_principle_and_simulation(den):
    G = fohw.FractionalTF([1.0], [0.0], *den)
    assert G.is_stable("matignon") and G.is_stable("argument")
    assert not _long_step_grows(den)


@pytest.mark.parametrize("den", UNSTABLE)
def test_unstable_systems_by_matignon_argument_principle_and_simulation(den):
    G = fohw.FractionalTF([1.0], [0.0], *den)
    assert not G.is_stable("matignon") and not G.is_stable("argument")
    assert _long_step_grows(den)


def test_matignon_and_argument_principle_agree_on_random_commensurate_denominators():
    rng = np.random.default_rng(7)
    agree = 0
    for _ in range(60):
        q = rng.choice([0.3, 0.5, 0.7, 0.9])
        degree = rng.integers(1, 4)
        coefs = np.r_[1.0, rng.uniform(-1.5, 3.0, degree)]
        orders = q * np.arange(degree, -1, -1.0)
        G = fohw.FractionalTF([1.0], [0.0], coefs, orders)
        agree += G.is_stable("matignon") == G.is_stable("argument")
    assert agree == 60


def test_non_commensurate_stability_and_poles():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0, 1.0], [np.sqrt(2), 1 / np.pi, 0.0])
    assert G.commensurate_order() is None
    assert G.is_stable()
    with pytest.raises(ParameterError, match="not commensurate"):
        G.poles()
    assert not fohw.FractionalTF([1.0], [0.0], [1.0, -2.0, 0.5], [np.sqrt(2), 1 / np.pi, 0.0]).is_stable()
    assert not fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.3]).is_stable()   # pole at s = 0


def test_poles_of_integer_and_fractional_denominators():
    np.testing.assert_allclose(fohw.FractionalTF([1.0], [0.0], [1.0, 3.0, 2.0], [2.0, 1.0, 0.0]).poles(),
                               [-2.0, -1.0], atol=1e-12)
    # s^1.5 + 1 = 0: lambda = s^0.5 solves lambda^3 = -1, lambda = e^{+-j pi/3} -> s = e^{+-2j pi/3}
    p = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.5, 0.0]).poles()
    np.testing.assert_allclose(np.sort(np.angle(p)), [-2 * np.pi / 3, 2 * np.pi / 3], atol=1e-12)
    np.testing.assert_allclose(np.abs(p), 1.0, atol=1e-12)
    assert fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]).poles().size == 0
    assert commensurate_base([1.2, 0.8, 0.0]) == pytest.approx(0.4)
    assert commensurate_base([3.0, 1.5]) == pytest.approx(0.75)
    assert rhp_zero_count([1.0, -1.0], [1.0, 0.0]) == 1


# ---------------------------------------------------------------- arithmetic
def test_series_parallel_feedback_against_frequency_responses():
    G1 = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    G2 = fohw.FractionalTF([2.0, 1.0], [0.3, 0.0], [1.0, 3.0], [1.2, 0.0])
    w = np.logspace(-2, 2, 50)
    g1, g2 = G1.frequency_response(w), G2.frequency_response(w)
    np.testing.assert_allclose((G1 * G2).frequency_response(w), g1 * g2, rtol=1e-12)
    np.testing.assert_allclose((G1 + G2).frequency_response(w), g1 + g2, rtol=1e-12)
    np.testing.assert_allclose((G1 - G2).frequency_response(w), g1 - g2, rtol=1e-11)
    np.testing.assert_allclose((2.0 * G1 + 1.0).frequency_response(w), 2 * g1 + 1, rtol=1e-12)
    np.testing.assert_allclose(G1.feedback(G2).frequency_response(w), g1 / (1 + g1 * g2), rtol=1e-12)
    np.testing.assert_allclose(G1.feedback(G2, sign=1).frequency_response(w), g1 / (1 - g1 * g2), rtol=1e-12)
    # the time domain agrees: series = simulating one after the other
    u = RNG.standard_normal(300)
    np.testing.assert_allclose((G1 * G2).simulate(u, dt=0.1), G2.simulate(G1.simulate(u, dt=0.1), dt=0.1),
                               atol=1e-10)
    warburg = fohw.FractionalTF([1.0, 0.5], [0.0, -0.5], [1.0], [0.0])
    closed = warburg.feedback()
    assert closed.den_orders.min() >= 0
    np.testing.assert_allclose(closed.frequency_response(w), warburg.frequency_response(w)
                               / (1 + warburg.frequency_response(w)), rtol=1e-12)


def test_arithmetic_that_leaves_the_class_is_refused():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], delay=0.2)
    H = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    with pytest.raises(ParameterError, match="delays differ"):
        G + H
    with pytest.raises(ParameterError, match="delay inside the loop"):
        G.feedback()
    assert (G * G).delay == pytest.approx(0.4)
    with pytest.raises(ParameterError, match="sampling times differ"):
        fohw.FractionalTF([1.0], [0.0], [1.0], [0.0], dt=0.1) * fohw.FractionalTF([1.0], [0.0], [1.0], [0.0],
                                                                                dt=0.2)


def test_terms_are_merged_sorted_and_printed():
    G = fohw.FractionalTF([1.0, 2.0], [0.0, 0.0], [1.0, 2.0, 1.0, 0.0], [0.0, 0.5, 0.5, 0.2])
    assert G.num.tolist() == [3.0] and G.den_orders.tolist() == [0.5, 0.0]
    assert str(G) == "3 / (3 s^0.5 + 1)"
    assert repr(G).startswith("FractionalTF([3.0], [0.0], [3.0, 1.0], [0.5, 0.0]")


# ---------------------------------------------------------------- figures
def test_bode_and_nyquist_figures(tmp_path):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    fig = G.bode(np.logspace(-2, 6, 200),
                 others={"1/(s+1)": fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])})
    axes = fig.axes
    assert len(axes) == 2 and len(axes[0].lines) == 2
    slope = np.diff(axes[0].lines[0].get_ydata()[-2:]) / np.diff(np.log10(axes[0].lines[0].get_xdata()[-2:]))
    assert slope[0] == pytest.approx(-10.0, rel=0.01)                  # -20 alpha dB/decade
    fig.savefig(tmp_path / "bode.png")
    fig = G.nyquist()
    fig.savefig(tmp_path / "nyquist.png")
    assert (tmp_path / "bode.png").stat().st_size > 0 and (tmp_path / "nyquist.png").stat().st_size > 0


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, error, match", [
    (dict(num=[1.0], num_orders=[np.nan], den=[1.0], den_orders=[0.0]), ParameterError, "num_orders"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0], den_orders=[np.inf]), ParameterError, "den_orders"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0, 1.0], den_orders=[-0.5, 0.0]), ParameterError,
     "den_orders"),
    (dict(num=[1.0], num_orders=[0.0], den=[0.0, 1.0], den_orders=[0.5, 0.0]), ParameterError,
     "leading"),
    (dict(num=[1.0, 2.0], num_orders=[0.0], den=[1.0], den_orders=[0.0]), DimensionError,
     "`num` and `num_orders`"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0, 2.0], den_orders=[0.0]), DimensionError,
     "`den` and `den_orders`"),
    (dict(num=[], num_orders=[], den=[1.0], den_orders=[0.0]), DimensionError, "`num`"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0], den_orders=[0.0], dt=-1.0), ParameterError, "`dt`"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0], den_orders=[0.0], delay=-1.0), ParameterError, "`delay`"),
    (dict(num=[1.0], num_orders=[0.0], den=[1.0], den_orders=[0.0], dt=0.1, delay=0.25), ParameterError,
     "multiple of the sampling time"),
    (dict(num=["a"], num_orders=[0.0], den=[1.0], den_orders=[0.0]), ParameterError, "`num`"),
])
def test_bad_construction_names_the_argument(kwargs, error, match):
    num, num_orders = kwargs.pop("num"), kwargs.pop("num_orders")
    den, den_orders = kwargs.pop("den"), kwargs.pop("den_orders")
    with pytest.raises(error, match=match):
        fohw.FractionalTF(num, num_orders, den, den_orders, **kwargs)


def test_bad_simulation_input_names_the_argument():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], delay=0.25)
    with pytest.raises(ParameterError, match="`dt` is needed"):
        G.simulate([1.0, 2.0])
    with pytest.raises(ParameterError, match="multiple of the sampling time"):
        G.simulate([1.0, 2.0], dt=0.1)
    with pytest.raises(ParameterError, match="`u` must contain only finite"):
        G.simulate([1.0, np.nan], dt=0.05)
    with pytest.raises(DimensionError, match="`u`"):
        G.simulate(np.ones((2, 3)), dt=0.05)
    with pytest.raises(ParameterError, match="`t` must lie on the sampling grid"):
        G.step([0.0, 0.33], dt=0.05)
    with pytest.raises(ParameterError, match="`t` must start at 0"):
        G.step([0.1, 0.2])
    with pytest.raises(ParameterError, match="singular"):
        fohw.FractionalTF([1.0], [0.0], [1.0, -1.0], [1.0, 0.0]).simulate([1.0, 1.0], dt=1.0)
    with pytest.raises(SimulationDivergedError):
        fohw.FractionalTF([1.0], [0.0], [1.0, -5.0], [1.0, 0.0]).simulate(np.ones(100_000), dt=0.1)
    with pytest.raises(ParameterError, match="`method`"):
        G.is_stable("nyquist")
