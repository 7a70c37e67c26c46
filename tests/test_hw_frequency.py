"""The frequency view of a lagged HW model (issue 25, item 4): the linear block's response against
closed forms and against the FFT of a long simulated impulse response, its static gain, and the
stability verdict against long simulations."""

import warnings

import numpy as np
import pytest

import fohw
from fohw.exceptions import SimulationDivergedError
from fohw.model.lagged.hw_frequency import LinearBlock, linear_block

W = np.array([1e-3, 0.05, 0.3, 1.0, 2.0, 3.0])       # rad per sample when dt = 1


def _model(a, b, alpha, *, orders=None, dt=1.0, p=(1.0,), q=(1.0,)):
    return fohw.HammersteinWiener(a, b, list(p), list(q), alpha, orders=orders, dt=dt)


def test_integer_order_zero_is_the_classical_arx_response():
    """orders = 0: H(z) = (b1 z^-1 + b2 z^-2) / (1 - a1 z^-1 - a2 z^-2)."""
    m = _model([0.5, -0.2], [1.0, 0.3], None, orders=0)
    z = np.exp(1j * W)
    want = (1.0 / z + 0.3 / z ** 2) / (1 - 0.5 / z + 0.2 / z ** 2)
    got = linear_block(m).frequency_response(W)
    assert np.max(np.abs(got / want - 1)) < 1e-12


@pytest.mark.parametrize("alpha", [0.5, 1.0, 1.5])
@pytest.mark.parametrize("dt", [1.0, 0.1])
def test_commensurate_model_against_the_closed_form(alpha, dt):
    """H = sum b_i z^-i s_h^alpha / (1 - sum a_i z^-i s_h^alpha), s_h = (1 - z^-1)/h: written with
    numpy's complex power (principal branch; Re(1 - z^-1) >= 0 so it is the GL branch)."""
    m = _model([0.1, 0.2], [-0.4, -0.2], alpha, dt=dt)
    w = W / dt
    z = np.exp(1j * w * dt)
    s = ((1 - 1 / z) / dt) ** alpha
    want = (-0.4 / z - 0.2 / z ** 2) * s / (1 - (0.1 / z + 0.2 / z ** 2) * s)
    got = linear_block(m).frequency_response(w)
    assert np.max(np.abs(got / want - 1)) < 1e-12


def test_general_orders_per_term_against_the_closed_form():
    orders = fohw.Orders.from_lags(a=[(0, 0.7)], b=[(0, "nu"), 1.3])
    m = fohw.HammersteinWiener([0.3, -0.2], [1.0, 0.5, -0.4], [1.0], [1.0], {"nu": 0.4},
                               orders=orders, dt=0.5)
    w = W / 0.5
    z = np.exp(1j * w * 0.5)
    s = (1 - 1 / z) / 0.5
    want = (1.0 / z + 0.5 / z * s ** 0.4 - 0.4 / z ** 2 * s ** 1.3) / (1 - 0.3 / z + 0.2 / z * s ** 0.7)
    assert np.max(np.abs(linear_block(m).frequency_response(w) / want - 1)) < 1e-12


def test_polynomial_bases_linearise_to_their_first_function():
    """f = u + 0.5 u^2, g = y + 0.7 y^2 + 0.35 y^3: slopes at 0 are p1 = q1 = 1, so H is the same as
    with identity maps; a custom basis (sin, cubic) has slope 2 (central difference)."""
    m = fohw.datasets.paper_model()
    plain = _model(m.a, m.b, m.alpha)
    np.testing.assert_array_equal(linear_block(m).frequency_response(W),
                                  linear_block(plain).frequency_response(W))
    custom = fohw.HammersteinWiener([0.2], [1.0], [1.0, 1.0], [1.0], 0.5,
                                    f_basis=[np.sin, lambda x: x + x ** 3])
    blk = linear_block(custom)
    assert abs(blk.f_slope - 2.0) < 1e-9 and blk.g_slope == 1.0


def test_response_equals_the_fft_of_a_long_simulated_impulse_response():
    """alpha = 0.5, na = nb = 1: simulate the impulse u = [1, 0, ...] (f = g = identity) over
    N = 2^17 samples; its DTFT sum_k y[k] e^{-j w k} is H(e^{jw}) up to the truncated tail. The
    tail decays monotonically (checked), so by Abel summation it is at most
    2 |y[N-1]| / |1 - e^{-jw}|: the tolerance."""
    m = _model([-0.3], [1.0], 0.5)
    n = 2 ** 17
    u = np.zeros(n)
    u[0] = 1.0
    y = fohw.simulate(m, u)
    tail = np.abs(y[n // 2:])
    assert np.all(np.diff(tail) <= 0)
    w = np.array([0.05, 0.3, 1.0, 2.5])
    k = np.arange(n)
    dtft = np.array([np.sum(y * np.exp(-1j * wi * k)) for wi in w])
    h = linear_block(m).frequency_response(w)
    bound = 2 * abs(y[-1]) / np.abs(1 - np.exp(-1j * w)) + 1e-12 * np.sum(np.abs(y))
    assert np.all(np.abs(dtft - h) <= bound), (np.abs(dtft - h), bound)
    # the same numbers by one FFT at its own bins
    fft = np.fft.rfft(y)
    bins = np.array([100, 3000, 20000])
    wb = 2 * np.pi * bins / n
    hb = linear_block(m).frequency_response(wb)
    tol = 2 * abs(y[-1]) / np.abs(1 - np.exp(-1j * wb)) + 1e-12 * np.sum(np.abs(y))
    assert np.all(np.abs(fft[bins] - hb) <= tol)


def test_static_gain():
    # commensurate alpha > 0: every term vanishes at z = 1 (SPEC Sec. 8)
    assert linear_block(_model([0.1, 0.2], [-0.4, -0.2], 0.6)).static_gain == 0.0
    # alpha = 0: the ARX gain sum b / (1 - sum a)
    assert linear_block(_model([0.5, -0.2], [1.0, 0.3], 0.0)).static_gain == pytest.approx(1.3 / 0.7,
                                                                                         rel=1e-15)
    # mixed: only the order-0 coefficients count
    m = fohw.HammersteinWiener([0.4, 0.3], [0.6, -0.5], [1.0], [1.0], 0.5, orders="mixed")
    blk = linear_block(m)
    assert blk.static_gain == pytest.approx(0.6 / (1 - 0.4), rel=1e-15)
    # ... and it is the limit of H at low frequency (|H(w) - H(0)| ~ w^0.5)
    assert abs(blk.frequency_response([1e-12])[0] - blk.static_gain) < 1e-4
    # and the end of a long step response
    y = fohw.simulate(m, np.ones(200_000))
    assert abs(y[-1] - blk.static_gain) < 0.02
    # an integrator: 1 - sum a0 = 0
    assert LinearBlock([1.0], [1.0], [(1, 0.0)], [(1, 0.0)], dt=1.0).static_gain == np.inf


CASES = [   # (a, b, alpha, orders): stable or not, decided independently below by simulation
    ([-0.5], [1.0], 0.5, None),
    ([-1.0], [1.0], 0.5, None),       # 1 + x (1 - x)^0.5 has a real zero in (-1, 0): unstable
    ([0.3, 0.2], [1.0, 0.5], 1.5, None),
    ([0.6, 0.3], [1.0, 0.5], 1.5, None),
    ([1.2], [1.0], 0.3, None),
    ([-0.9], [1.0], 0.3, None),
    ([0.5, -0.2], [1.0], 0.0, 0),
    ([1.5, -0.4], [1.0], 0.0, 0),
    ([0.4, 0.3], [0.6, -0.5], 0.5, "mixed"),
    ([0.9, 0.3], [0.6, -0.5], 0.5, "mixed"),
    ([1.1, 0.3], [0.6, -0.5], 0.5, "mixed"),    # 1 - A(1) = -0.1 < 0 = a real zero in (0, 1)
    ([0.9, 0.3], [1.0, 0.5], 1.5, None),        # two poles outside
]


def _simulated_verdict(model, n=50_000):
    """Stable iff the impulse response has decayed: sum |y| over the last half is below 1e-3 of the
    first half's, and nothing diverged."""
    u = np.zeros(n)
    u[0] = 1.0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            y = fohw.simulate(model, u, divergence_threshold=1e12)
    except SimulationDivergedError:
        return False
    first, last = np.sum(np.abs(y[:n // 2])), np.sum(np.abs(y[n // 2:]))
    return bool(last < 1e-3 * first) if np.max(np.abs(y[n // 2:])) < 1e6 else False


@pytest.mark.parametrize("a,b,alpha,orders", CASES)
def test_stability_verdict_agrees_with_long_simulations(a, b, alpha, orders):
    nb = len(b) // 2 if orders == "mixed" else len(b)
    model = fohw.HammersteinWiener(a, b[:2 * nb] if orders == "mixed" else b, [1.0], [1.0],
                                   None if orders == 0 else alpha, orders=orders)
    verdict = linear_block(model).stability()
    assert verdict.stable == _simulated_verdict(model), str(verdict)


def test_the_cases_cover_both_verdicts():
    got = {linear_block(fohw.HammersteinWiener(a, b, [1.0], [1.0], None if o == 0 else al,
                                               orders=o)).stability().stable
           for a, b, al, o in CASES}
    assert got == {True, False}


@pytest.mark.parametrize("seed", range(20))
def test_integer_orders_count_the_poles_outside_the_unit_circle(seed):
    """orders 0/1/2 per term: D(x) = 1 - A(x) is a polynomial; its roots inside |x| < 1 are the
    poles z = 1/x outside the unit circle. The winding number counts them."""
    rng = np.random.default_rng(seed)
    terms = [(int(rng.integers(1, 4)), float(rng.integers(0, 3))) for _ in range(3)]
    terms = list(dict.fromkeys(terms))
    a = rng.normal(0, 0.8, len(terms))
    blk = LinearBlock(a, [1.0], terms, [(1, 0.0)], dt=float(rng.choice([0.5, 1.0, 2.0])))
    poly = np.zeros(8)                            # coefficients of x^0..x^7
    poly[0] = 1.0
    h = blk.dt
    for c, (lag, nu) in zip(a, terms):
        # x^lag (1 - x)^nu h^-nu
        term = np.polynomial.polynomial.polypow([1.0, -1.0], int(nu)) * h ** -nu
        poly[lag:lag + term.size] -= c * term
    roots = np.polynomial.polynomial.polyroots(np.trim_zeros(poly, "b"))
    if np.min(np.abs(np.abs(roots) - 1)) < 1e-6:
        pytest.skip("a root on the circle")
    verdict = blk.stability()
    assert verdict.zeros_inside == int(np.sum(np.abs(roots) < 1))
    assert verdict.stable == (verdict.zeros_inside == 0)


def test_result_frequency_view_summary_and_bode(tmp_path):
    import matplotlib.pyplot as plt

    data = fohw.datasets.paper_example(300, random_state=0)
    res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    blk = res.linear_block()
    np.testing.assert_array_equal(blk.a, res.shared_model.a)   # polynomial bases: the same
    text = res.summary()
    assert "static gain H(1) = 0 (no order-0 term" in text
    assert "stability: stable (argument principle" in text
    assert text.startswith(res.summary(linear_block=False))
    before = plt.get_fignums()
    fig = res.bode()
    axes = fig.axes
    assert plt.get_fignums() == before                  # never registered with pyplot, never shown
    assert len(axes) == 2 and axes[0].get_ylabel() == "magnitude [dB]"
    fig.savefig(tmp_path / "bode.png")
    assert (tmp_path / "bode.png").stat().st_size > 0
    w = blk.default_frequencies()
    line = axes[0].get_lines()[0]
    np.testing.assert_allclose(line.get_ydata(), 20 * np.log10(np.abs(blk.frequency_response(w))))
    axes = res.bode(others={"true model": fohw.datasets.paper_model()}).axes
    labels = [ln.get_label() for ln in axes[0].get_lines()]
    assert labels == ["estimate", "true model"]


def test_stability_shows_in_summary_for_an_unstable_estimate():
    m = fohw.HammersteinWiener([-1.0], [1.0], [1.0], [1.0], 0.5)
    assert not linear_block(m).stability().stable
    assert "unstable (1 pole(s) with |z| > 1)" in str(linear_block(m).stability())
