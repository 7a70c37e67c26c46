"""The frequency view of every model kind: one hook, one Bode and one Nyquist implementation.

``fohw.Model.frequency_response(omega)`` is optional (``None``: the kind has none). Each shipped
kind's response is checked against an independent computation (its literal formula written out
here, or the DTFT of its simulated impulse response); ``bode``/``nyquist`` of a model, of a fit
and of ``fohw.bode``/``fohw.nyquist`` return a Figure drawing that response; a kind without one
is refused, naming the kind.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.figure  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import fohw  # noqa: E402
from fohw.model.circuit import RC, ZARC, EquivalentCircuit, Warburg  # noqa: E402

W = np.logspace(-2, 1, 31)


class Gain(fohw.Model):
    """``y = k u``: a kind with the three required members only (no frequency response)."""

    kind = "TestFrequencyGain"

    def __init__(self, k=1.0):
        self.k = float(k)

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("k", self.k, bounds=(-10.0, 10.0))])

    def with_parameters(self, values):
        return Gain(self.parameters.with_values(values)["k"].value)

    def simulate(self, u, *, initial=None):
        return self.k * self.check_input(u)


class DiscreteLag(fohw.Model):
    """``y[k] = a y[k-1] + b u[k-1]`` (dt = 1) with its frequency response ``b z^-1 / (1 - a z^-1)``."""

    kind = "TestFrequencyLag"

    def __init__(self, a=0.5, b=1.0):
        self.a, self.b = float(a), float(b)

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return DiscreteLag(v["a"], v["b"])

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        y = np.zeros_like(u)
        for k in range(1, u.size):
            y[k] = self.a * y[k - 1] + self.b * u[k - 1]
        return y

    def frequency_response(self, omega):
        zinv = np.exp(-1j * np.asarray(omega, dtype=float))
        return self.b * zinv / (1.0 - self.a * zinv)


def _dtft(h, omega, dt=1.0):
    """``sum_k h[k] exp(-j omega k dt)``: the DTFT of a (long, decayed) impulse response."""
    k = np.arange(h.size)
    return np.exp(-1j * np.outer(omega * dt, k)) @ h


def _magnitude_line(fig):
    return fig.axes[0].get_lines()[0].get_ydata()


# ---------------------------------------------------------------- each kind against a reference
def test_test_kind_response_is_the_dtft_of_its_impulse_response():
    lag = DiscreteLag(0.7, 2.0)
    u = np.zeros(400)
    u[0] = 1.0
    h = lag.simulate(u)                        # 0.7^400 ~ 1e-62: the tail is below double precision
    # rounding: 400 eps sum|h| = 6e-13 absolute, 5e-13 of the smallest |H| = 2 / 1.7
    np.testing.assert_allclose(lag.frequency_response(W), _dtft(h, W), rtol=1e-12)


def test_fractional_tf_against_its_literal_formula():
    G = fohw.FractionalTF([2.0, 1.0], [0.3, 0.0], [1.0, 3.0, 2.0], [1.4, 0.5, 0.0], delay=0.2)
    s = 1j * W                                  # principal branch of numpy's complex power
    literal = (2 * s ** 0.3 + 1) / (s ** 1.4 + 3 * s ** 0.5 + 2) * np.exp(-0.2 * s)
    g = G.frequency_response(W)
    assert g.dtype == complex and g.shape == W.shape
    np.testing.assert_allclose(g, literal, rtol=1e-12)


def test_fractional_hw_is_its_linear_block():
    G = fohw.FractionalTF([1.5], [0.0], [1.0, 1.0], [0.7, 0.0], dt=0.05)
    hw = fohw.FractionalHW(G, p=[1.0, 0.4], output_map="saturation", output_params=[-1.0, 1.0])
    s = 1j * W
    np.testing.assert_allclose(hw.frequency_response(W), 1.5 / (s ** 0.7 + 1), rtol=1e-12)


def test_lagged_hw_against_the_literal_dtft_of_its_lag_and_gl_terms():
    m = fohw.datasets.paper_model()            # commensurate: lags 1..na, 1..nb, one order
    h, alpha = m.dt, m.alpha
    w = np.linspace(0.01, 3.0, 40) / h
    zinv = np.exp(-1j * w * h)
    op = ((1 - zinv) / h) ** alpha             # Re(1 - z^-1) > 0: the principal branch is the series'
    A = sum(a * zinv ** (i + 1) for i, a in enumerate(m.a)) * op
    B = sum(b * zinv ** (i + 1) for i, b in enumerate(m.b)) * op
    # polynomial bases: the slopes at 0 are p1 = q1 = 1
    np.testing.assert_allclose(m.frequency_response(w), B / (1 - A), rtol=1e-12)


def test_lagged_hw_response_is_the_dtft_of_its_simulated_impulse_response():
    # integer order (alpha = 1) and linear maps: the impulse response decays geometrically
    m = fohw.HammersteinWiener([0.3, -0.1], [1.0, 0.5], [1.0], [1.0], alpha=1.0, dt=0.5)
    assert fohw.model.lagged.hw_frequency.linear_block(m).stability().stable
    u = np.zeros(3000)
    u[0] = 1.0
    y = m.simulate(u)
    assert np.max(np.abs(y[-100:])) < 1e-14 * np.max(np.abs(y))   # decayed: truncation negligible
    w = np.linspace(0.05, 6.0, 25)
    # rounding of the DTFT's 3000-term sum: at most 3000 eps sum|y| = 9e-12 absolute, 1.2e-10
    # of the smallest |H| here (0.075)
    np.testing.assert_allclose(m.frequency_response(w), _dtft(y, w, m.dt), rtol=2e-10)


def test_equivalent_circuit_against_its_literal_impedance():
    cell = EquivalentCircuit([ZARC(0.01, 50.0, 0.6), RC(0.004, 2.0), Warburg(0.002, 0.5)],
                             r0=0.015, a=3.7, c3=0.01)
    w = W
    literal = (0.015 + 0.01 / (1 + (1j * w * 50.0) ** 0.6) + 0.004 / (1 + 1j * w * 2.0)
               + 0.002 * (1j * w) ** -0.5)
    np.testing.assert_allclose(cell.frequency_response(w), literal, rtol=1e-12)
    # the same spectrum as impedance(f) at f = omega / (2 pi)
    np.testing.assert_allclose(cell.frequency_response(w), cell.impedance(w / (2 * np.pi)), rtol=1e-15)
    with pytest.raises(fohw.ParameterError, match="`omega` = 2 pi f: `f` = 0.0 .*Warburg"):
        cell.frequency_response([0.0, 1.0])
    with pytest.raises(fohw.ParameterError, match="`omega` must contain only finite values"):
        cell.frequency_response([np.nan])


def test_circuit_tables_at_an_operating_point_against_the_literal_interpolation():
    cell = fohw.CircuitTables(["zarc", "rc"], soc_points=[0.2, 0.8], temperature_points=[0.0, 40.0],
                              values={"R0": [[0.03, 0.01], [0.02, 0.006]], "R1": [[0.01, 0.004],
                                      [0.008, 0.002]], "tau1": 30.0, "alpha1": 0.7,
                                      "R2": 0.005, "tau2": [[2.0, 1.0], [4.0, 3.0]]})
    soc, temp = 0.35, 10.0
    ws, wt = (0.35 - 0.2) / 0.6, 10.0 / 40.0            # bilinear weights, written out

    def bilinear(t):
        return ((1 - ws) * (1 - wt) * t[0][0] + (1 - ws) * wt * t[0][1]
                + ws * (1 - wt) * t[1][0] + ws * wt * t[1][1])
    r0 = bilinear([[0.03, 0.01], [0.02, 0.006]])
    r1 = bilinear([[0.01, 0.004], [0.008, 0.002]])
    tau2 = bilinear([[2.0, 1.0], [4.0, 3.0]])
    s = 1j * W
    literal = r0 + r1 / (1 + (s * 30.0) ** 0.7) + 0.005 / (1 + s * tau2)
    np.testing.assert_allclose(cell.frequency_response(W, soc=soc, temperature=temp), literal,
                               rtol=1e-12)
    for missing, given in (("soc", {"temperature": temp}), ("temperature", {"soc": soc})):
        with pytest.raises(fohw.ParameterError, match=f"vary with `{missing}`.*give {missing}="):
            cell.frequency_response(W, **given)
    with pytest.raises(fohw.ParameterError, match="soc"):
        cell.frequency_response(W, soc=1.5, temperature=temp)
    # one breakpoint along an axis: that point is the default
    flat = fohw.CircuitTables(["rc"], soc_points=[0.5], temperature_points=[25.0],
                              values={"R0": 0.02, "R1": 0.01, "tau1": 5.0})
    np.testing.assert_allclose(flat.frequency_response(W), 0.02 + 0.01 / (1 + 5.0 * s), rtol=1e-12)


# ---------------------------------------------------------------- bode and nyquist for every kind
def _kinds():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    tables = fohw.CircuitTables(["zarc"], soc_points=[0.5], temperature_points=[25.0],
                                values={"R0": 0.02, "R1": 0.01, "tau1": 5.0, "alpha1": 0.6})
    return [G, fohw.FractionalHW(G, p=[1.0, 0.3]), fohw.datasets.paper_model(),
            EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015), tables, DiscreteLag(0.6, 1.0)]


@pytest.mark.parametrize("model", _kinds(), ids=lambda m: type(m).__name__)
def test_bode_and_nyquist_draw_the_hook_for_every_kind(model):
    for fig in (model.bode(), fohw.bode(model)):
        assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 2
        w = fig.axes[0].get_lines()[0].get_xdata()
        np.testing.assert_allclose(w, model.default_frequencies())
        np.testing.assert_allclose(_magnitude_line(fig),
                                   20 * np.log10(np.abs(model.frequency_response(w))), rtol=1e-12)
        assert fig.axes[0].get_lines()[0].get_label() == model.response_label()
    for fig in (model.nyquist(), fohw.nyquist(model)):
        assert isinstance(fig, matplotlib.figure.Figure)
        line = fig.axes[0].get_lines()[0]
        g = model.frequency_response(model.default_frequencies())
        sign = -1.0 if model.response_kind == "impedance" else 1.0     # -Im Z upwards
        np.testing.assert_allclose(line.get_ydata(), sign * g.imag, rtol=1e-12)


def test_circuit_nyquist_is_the_impedance_plane_and_transfer_functions_mark_minus_one():
    cell = EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015)
    ax = cell.nyquist().axes[0]
    assert ax.get_ylabel() == "-imaginary part"
    assert all(ln.get_marker() != "+" for ln in ax.get_lines())      # no critical point -1
    assert min(ln.get_xdata().min() for ln in ax.get_lines()) >= 0.015 - 1e-12
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    assert any(ln.get_marker() == "+" for ln in G.nyquist().axes[0].get_lines())


def test_operating_point_keywords_reach_the_response():
    cell = fohw.CircuitTables(["rc"], soc_points=[0.2, 0.8], temperature_points=[25.0],
                              values={"R0": [[0.03], [0.01]], "R1": 0.01, "tau1": 5.0})
    with pytest.raises(fohw.ParameterError, match="vary with `soc`"):
        cell.bode()
    w = np.logspace(-2, 1, 20)
    fig = cell.bode(w, soc=0.8)
    np.testing.assert_allclose(_magnitude_line(fig),
                               20 * np.log10(np.abs(0.01 + 0.01 / (1 + 5j * w))), rtol=1e-12)
    assert isinstance(cell.nyquist(w, soc=0.2), matplotlib.figure.Figure)


def test_a_kind_without_a_response_is_refused_naming_it():
    gain = Gain(2.0)
    assert gain.frequency_response(W) is None
    for call in (gain.bode, gain.nyquist, lambda: fohw.bode(gain), lambda: fohw.nyquist(gain)):
        with pytest.raises(fohw.ParameterError, match="a Gain has no frequency response"):
            call()
    u = np.random.default_rng(0).standard_normal(50)
    fit = fohw.fit(Gain(1.0), u, 3.0 * u)
    with pytest.raises(fohw.ParameterError, match="a Gain has no frequency response"):
        fit.bode()
    with pytest.raises(fohw.ParameterError, match="`others\\['g'\\]`: a Gain has no frequency"):
        DiscreteLag().bode(others={"g": gain})
    with pytest.raises(fohw.ParameterError, match="`system` must be a fohw.Model.*got str"):
        fohw.bode("G")


# ---------------------------------------------------------------- fits
def test_fit_bode_and_nyquist_use_the_model_and_the_records_time_unit():
    truth = DiscreteLag(0.6, 1.5)
    u = np.random.default_rng(3).standard_normal(300)
    y = truth.simulate(u) + 0.01 * np.random.default_rng(4).standard_normal(300)
    rec = fohw.Record(u, y, dt=1.0, name="bench", time_unit="s", output_unit="V", input_unit="A")
    fit = fohw.fit(DiscreteLag(0.3, 1.0), rec)
    fig = fit.bode(others={"truth": truth})
    assert isinstance(fig, matplotlib.figure.Figure)
    assert fig.axes[-1].get_xlabel() == "angular frequency ω [rad/s]"
    labels = [ln.get_label() for ln in fig.axes[0].get_lines()]
    assert labels == ["estimate", "truth"]
    w = fig.axes[0].get_lines()[0].get_xdata()
    np.testing.assert_allclose(_magnitude_line(fig), 20 * np.log10(np.abs(fit.model.frequency_response(w))))
    assert fohw.bode(fit, hz=True).axes[-1].get_xlabel() == "frequency f [Hz]"
    assert isinstance(fit.nyquist(), matplotlib.figure.Figure)
    assert isinstance(fohw.nyquist(fit), matplotlib.figure.Figure)
    plain = fohw.fit(DiscreteLag(0.3, 1.0), u, y)            # arrays: the time unit is unknown
    assert plain.bode().axes[-1].get_xlabel() == "angular frequency ω [rad / time unit]"


def test_identification_result_bode_and_nyquist_route_through_the_same_drawing():
    data = fohw.datasets.paper_example(300, random_state=0)
    res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    w = res.model.default_frequencies()
    for fig in (res.bode(), fohw.bode(res)):
        np.testing.assert_allclose(_magnitude_line(fig),
                                   20 * np.log10(np.abs(res.linear_block().frequency_response(w))))
    assert res.bode().axes[-1].get_xlabel() == "angular frequency ω [rad / sample]"
    line = res.nyquist().axes[0].get_lines()[0]
    np.testing.assert_allclose(line.get_xdata(), res.linear_block().frequency_response(w).real)
