"""The circuit's impedance against its simulator, and fits to a spectrum (issue 37, item 4)."""

import math

import numpy as np
import pytest

import fohw
from fohw.estimators.impedance_fit import fit_impedance, fit_record_and_impedance, spectrum_residual
from fohw.model.circuit import RC, ZARC, EquivalentCircuit, Warburg

DT = 0.1
FREQS = (0.002, 0.01, 0.05, 0.2, 0.5)          # omega dt from 1.3e-3 to 0.31

CIRCUITS = {
    "RC": EquivalentCircuit([RC(0.01, 5.0)], r0=0.02, dt=DT),
    "ZARC": EquivalentCircuit([ZARC(0.012, 20.0, 0.5)], r0=0.015, dt=DT),
    "RC + ZARC": EquivalentCircuit([RC(0.004, 1.0), ZARC(0.01, 50.0, 0.7)], r0=0.02, dt=DT),
    "CPE (Warburg)": EquivalentCircuit([Warburg(0.003, 0.5)], r0=0.02, dt=DT),
}


def steady_state_gain(model, f, periods=12, kept=6):
    """The complex gain of the simulated voltage to a unit sine of frequency ``f``.

    The circuit is driven from rest by ``i = sin(omega k dt)``; over the last ``kept`` whole
    periods ``v`` is fitted by ``Re(G) sin + Im(G) cos`` plus a constant and a linear trend, which
    take up the start's transient (it decays as ``h(t) / omega``, ``h`` the impulse response:
    like ``t^(-alpha-1)`` for a ZARC, ``t^(alpha-1)`` for the fractional integrator).
    """
    n_period = 1.0 / (f * DT)
    n = int(round(periods * n_period))
    t = DT * np.arange(n)
    u = np.column_stack([np.sin(2 * np.pi * f * t), np.full(n, 0.5)])
    v = model.simulate(u)
    start = int(round((periods - kept) * n_period))
    tt = t[start:]
    cols = np.column_stack([np.sin(2 * np.pi * f * tt), np.cos(2 * np.pi * f * tt),
                            np.ones_like(tt), tt - tt.mean()])
    coef = np.linalg.lstsq(cols, v[start:], rcond=None)[0]
    return coef[0] + 1j * coef[1]


def discretisation_bound(model, f):
    """A bound on ``|Z_discrete - Z|`` [ohm] from the GL symbol's first-order error.

    The GL (backward-difference) symbol is ``g = (1 - e^{-s dt}) / dt = s e^{-s dt/2} sinc``, so
    ``g^alpha / s^alpha = e^{-j alpha omega dt / 2} sinc(omega dt / 2)^alpha``, whose distance from
    1 is at most ``alpha omega dt / 2 + (omega dt)^2 / 24`` to second order. An element
    ``R / (1 + op)`` (``|arg op| <= pi/2``, so ``|op / (1 + op)| <= 1``) and the fractional
    integrator pass that relative error on at most unchanged; ``R0`` is exact. So the bound is
    the sum over the elements of ``|Z_e|`` times their relative error; the factor 1.1 covers
    the terms of higher order (``omega dt <= 0.31`` here).
    """
    wdt = 2 * np.pi * f * DT
    return sum(1.1 * ((1.0 if e.kind == "rc" else e.alpha) * wdt / 2 + wdt ** 2 / 24)
               * abs(e.impedance([f])[0]) for e in model.elements)


@pytest.mark.parametrize("name", list(CIRCUITS))
def test_the_impedance_is_the_simulators_steady_state_gain(name):
    model = CIRCUITS[name]
    for f in FREQS:
        gain = steady_state_gain(model, f)
        z_cont = model.impedance([f])[0]
        z_disc = model.impedance([f], discrete=True)[0]
        # The simulator is the discretised model: its gain is Z_discrete up to the transient
        # left after the trend is removed (measured at most 3.6e-5 relative here: the Warburg
        # element's slowly decaying transient at 2 mHz).
        assert abs(gain - z_disc) / abs(z_disc) < 1e-4, (name, f)
        # Against the continuous circuit, the discretisation's error and no more.
        bound = discretisation_bound(model, f)
        assert abs(gain - z_cont) < bound + 1e-4 * abs(z_cont), (name, f)
    # The bound is not vacuous: at omega dt = 0.31 the discretisation's error is more than
    # half of it (a conjugated or mis-scaled impedance would fail above by far more).
    f = FREQS[-1]
    assert abs(steady_state_gain(model, f) - model.impedance([f])[0]) \
        > 0.5 * discretisation_bound(model, f)


def test_a_conjugated_impedance_would_fail_the_check():
    # The check above can fail: the complex conjugate of the right answer (a sign error in the
    # phase) is far outside the tolerance at every frequency but the lowest.
    model = CIRCUITS["ZARC"]
    f = 0.05
    gain = steady_state_gain(model, f)
    z = model.impedance([f])[0]
    assert abs(gain - np.conj(z)) > 10 * discretisation_bound(model, f)


FIT_CASES = [
    (EquivalentCircuit([RC(0.004, 2.0), ZARC(0.01, 80.0, 0.55)], r0=0.02, dt=0.01), ["rc", "zarc"],
     None),
    (EquivalentCircuit([ZARC(0.008, 0.5, 0.8), Warburg(0.002, 0.45)], r0=0.018, dt=0.01),
     ["zarc", "warburg"], None),
    (EquivalentCircuit([ZARC(0.01, 30.0, 0.6)], r0=0.02, b=0.05, dt=0.01), ["zarc"], 5.0),
]


@pytest.mark.parametrize("true, elements, capacity", FIT_CASES)
def test_the_impedance_fit_recovers_a_circuit_from_its_exact_spectrum(true, elements, capacity):
    f = fohw.datasets.battery_cell().impedance_f          # the shipped spectra's 65 frequencies
    kw = {} if capacity is None else dict(capacity=capacity, ocv_slope=0.8)
    z = true.impedance(f, **kw)
    res = fit_impedance(EquivalentCircuit(elements, dt=0.01), f, z, **kw)
    assert isinstance(res, fohw.FitResult) and res.converged
    got = res.parameters.valuesdict()
    for name, value in true.parameters.valuesdict().items():
        if name in ("a", "c3") or (name == "b" and capacity is None):
            assert got[name] == 0.0 and res.parameters[name].fixed, name   # held, said so
            continue
        assert got[name] == pytest.approx(value, rel=1e-6), name
    assert "not enter the impedance: held" in res.message
    assert res.sse < 1e-20 and res.n_samples == 2 * f.size


def test_an_impedance_fit_is_a_fit_result_that_files_hold(tmp_path):
    true = FIT_CASES[0][0]
    f = np.logspace(-3, 1, 30)
    res = fit_impedance(EquivalentCircuit(["rc", "zarc"], dt=0.01), f, true.impedance(f))
    assert res.message.endswith("a and b do not enter the impedance: held at the model's values.")
    assert set(res.starts[0][0]) == {"alpha2"}
    fohw.save_result(res, tmp_path / "fit.json")
    back = fohw.load_result(tmp_path / "fit.json")
    assert back.parameters == res.parameters and back.options["data"] == "impedance"
    np.testing.assert_array_equal(back.covariance, res.covariance)


def test_the_impedance_fit_with_noise_is_within_its_standard_errors():
    rng = np.random.default_rng(1)
    f = np.logspace(-3, 2, 40)
    true = EquivalentCircuit([RC(0.004, 2.0), ZARC(0.01, 80.0, 0.55)], r0=0.02)
    z0 = true.impedance(f)
    z = z0 * (1 + 0.002 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)))
    res = fit_impedance(EquivalentCircuit(["rc", "zarc"]), f, z)
    se = res.standard_errors()
    for name in res.free_names:
        assert abs(res.parameters[name].value - true.parameters[name].value) < 4 * se[name], name
    # The residual is the relative one: its RMS is the noise's, 0.002.
    assert res.rmse == pytest.approx(0.002, rel=0.3)
    np.testing.assert_allclose(res.residuals, spectrum_residual(res.model, f, z, 1 / np.abs(z)))


def test_the_impedance_fit_refuses_bad_spectra():
    model = EquivalentCircuit(["zarc"])
    with pytest.raises(fohw.ParameterError, match="`f` must be positive"):
        fit_impedance(model, [0.0, 1.0, 2.0], [1, 1, 1])
    with pytest.raises(fohw.ParameterError, match="one value per frequency"):
        fit_impedance(model, [1.0, 2.0], [1.0])
    with pytest.raises(fohw.ParameterError, match="need more equations than parameters"):
        fit_impedance(model, [1.0, 2.0], [0.02, 0.02 - 0.001j])
    with pytest.raises(fohw.ParameterError, match="`weight` must be one of"):
        fit_impedance(model, [1.0, 2.0, 3.0], [0.02] * 3, weight="modulus")
    with pytest.raises(fohw.ParameterError, match="must be an EquivalentCircuit"):
        fit_impedance("zarc", [1.0], [1.0])


def record(n=3000, seed=0, hold=20):
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-3, 1.2, n // hold + 1), hold)[:n]
    soc = 0.8 + np.concatenate([[0.0], np.cumsum(i[:-1])]) / (3600 * 5.0)
    return np.column_stack([i, soc])


@pytest.mark.slow
def test_the_joint_fit_weights_each_part_by_its_noise():
    true = EquivalentCircuit([RC(0.004, 3.0), ZARC(0.01, 120.0, 0.55)], r0=0.015, a=3.7, b=0.2)
    u = record(1500, seed=2)
    y = true.simulate(u) + 2e-4 * np.random.default_rng(3).standard_normal(1500)
    f = np.logspace(-3.5, 1, 30)
    rng = np.random.default_rng(4)
    z = true.impedance(f) * (1 + 0.003 * (rng.standard_normal(30) + 1j * rng.standard_normal(30)))
    model = EquivalentCircuit(["rc", "zarc"], tau_bounds=(1.0, 2000.0), n_tau=5, n_alpha=3)
    res = fit_record_and_impedance(model, u, y, f, z)
    assert res.converged and res.n_samples == 1500 + 60
    s_time, s_spec = res.options["noise"]
    # The default noise levels are the separate fits' RMS residuals (near the true 2e-4, 0.003).
    alone = fohw.fit(model, u, y, order_grid=1)
    assert s_time == pytest.approx(math.sqrt(alone.sse / (alone.n_samples - alone.n_free)))
    assert s_time == pytest.approx(2e-4, rel=0.1) and s_spec == pytest.approx(0.003, rel=0.3)
    # The criterion is the stacked scaled residual, recomputed here from its definition.
    e = y - res.simulate(u)
    d = (res.model.impedance(f) - z) / np.abs(z)
    expected = e @ e / s_time ** 2 + (d.real @ d.real + d.imag @ d.imag) / s_spec ** 2
    assert res.sse == pytest.approx(expected, rel=1e-9)
    se = res.standard_errors()
    for name in res.free_names:
        assert abs(res.parameters[name].value - true.parameters[name].value) < 4 * se[name], name
    # The spectrum pins the slow ZARC better than the record alone: a smaller standard error.
    assert se["tau2"] < alone.standard_errors()["tau2"]
    with pytest.raises(fohw.ParameterError, match="`noise` must hold two positive"):
        fit_record_and_impedance(model, u, y, f, z, noise=(0.0, 0.01))
