"""The equivalent-circuit model: every element against a literal per-sample reference."""

import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.special

import fohw
from fohw.model.circuit import RC, ZARC, EquivalentCircuit, OCVTable, Warburg


def literal_zarc(i, R, tau, alpha, h):
    """(tau/h)^alpha sum_j beta_j x[k-j] + x[k] = R i[k], solved sample by sample."""
    n = len(i)
    beta = np.array([(-1) ** j * scipy.special.binom(alpha, j) for j in range(n)])
    r = (tau / h) ** alpha
    x = np.zeros(n)
    for k in range(n):
        memory = sum(beta[j] * x[k - j] for j in range(1, k + 1))
        x[k] = (R * i[k] - r * memory) / (1.0 + r)
    return x


def literal_backward_euler(i, R, tau, h):
    x, prev = np.zeros(len(i)), 0.0
    for k, ik in enumerate(i):
        prev = (tau / h * prev + R * ik) / (1.0 + tau / h)
        x[k] = prev
    return x


def literal_warburg(i, sigma, alpha, h):
    n = len(i)
    w = np.array([(-1) ** j * scipy.special.binom(-alpha, j) for j in range(n)])
    return np.array([sigma * h ** alpha * sum(w[j] * i[k - j] for j in range(k + 1))
                     for k in range(n)])


@pytest.fixture
def current():
    return np.random.default_rng(0).standard_normal(400)


@pytest.mark.parametrize("tau, alpha, h", [(50.0, 0.5, 1.5), (3.0, 0.3, 0.3), (700.0, 0.85, 1.5),
                                           (10.0, 1.0, 1.0)])
def test_zarc_matches_the_literal_recursion_at_every_sample(current, tau, alpha, h):
    x = ZARC(0.012, tau, alpha).response(current, h)
    np.testing.assert_allclose(x, literal_zarc(current, 0.012, tau, alpha, h), rtol=1e-10,
                               atol=1e-14)


@pytest.mark.parametrize("tau, h", [(50.0, 1.5), (0.2, 1.0)])
def test_rc_is_backward_euler_and_the_zarc_at_order_one(current, tau, h):
    x = RC(0.01, tau).response(current, h)
    np.testing.assert_allclose(x, literal_backward_euler(current, 0.01, tau, h), rtol=1e-12, atol=1e-16)
    np.testing.assert_allclose(ZARC(0.01, tau, 1.0).response(current, h), x, rtol=1e-10, atol=1e-15)


@pytest.mark.parametrize("alpha, h", [(0.5, 1.5), (0.2, 0.3)])
def test_warburg_matches_the_literal_fractional_sum(current, alpha, h):
    x = Warburg(0.003, alpha).response(current, h)
    np.testing.assert_allclose(x, literal_warburg(current, 0.003, alpha, h), rtol=1e-10, atol=1e-15)


def test_warburg_step_grows_like_t_to_the_alpha():
    # GL sum of a unit step: h^a sum_{j<=k} (-1)^j binom(-a, j) = h^a binom(k + a, k), which is
    # ~ (kh)^a / Gamma(1 + a) for large k (the Riemann-Liouville integral of a step).
    x = Warburg(1.0, 0.5).response(np.ones(20_000), 0.5)
    k = 19_999
    assert x[-1] == pytest.approx(0.5 ** 0.5 * scipy.special.binom(k + 0.5, k), rel=1e-10)
    assert x[-1] == pytest.approx((k * 0.5) ** 0.5 / scipy.special.gamma(1.5), rel=1e-4)


CIRCUITS = [
    EquivalentCircuit([RC(0.006, 20.0), RC(0.004, 300.0)], r0=0.015, a=0.01, b=-0.02, dt=1.5),
    EquivalentCircuit([ZARC(0.01, 80.0, 0.55)], r0=0.014, a=0.01, b=0.03, c3=-2e-4, dt=1.5),
    EquivalentCircuit([RC(0.003, 5.0), ZARC(0.01, 300.0, 0.45), Warburg(0.002, 0.6)], r0=0.015,
                      dt=1.5),
]


@pytest.mark.parametrize("circuit", CIRCUITS, ids=lambda c: "+".join(c.kinds))
def test_circuit_is_the_sum_of_its_literal_terms(current, circuit):
    soc = np.linspace(0.8, 0.6, current.size)
    h = 1.5
    expected = circuit.a + circuit.b * soc + circuit.r0 * current
    if circuit.c3 is not None:
        expected += circuit.c3 * current ** 3
    for e in circuit.elements:
        if e.kind == "warburg":
            expected += literal_warburg(current, e.sigma, e.alpha, h)
        else:
            expected += literal_zarc(current, e.R, e.tau, e.alpha, h)
    u = np.column_stack([current, soc])
    np.testing.assert_allclose(circuit.simulate(u), expected, rtol=1e-12, atol=1e-13)
    # The OCV map enters additively.
    with_ocv = dataclasses.replace(circuit, ocv=lambda s: 3.0 + s)
    np.testing.assert_allclose(with_ocv.simulate(u) - 3.0 - soc, expected, rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("circuit", CIRCUITS, ids=lambda c: "+".join(c.kinds))
def test_jacobian_matches_central_differences(current, circuit):
    u = np.column_stack([current, np.linspace(0.8, 0.6, current.size)])
    v, jac = circuit.jacobian(u)
    np.testing.assert_allclose(v, circuit.simulate(u), rtol=0, atol=1e-15)
    theta = circuit.parameters.valuesdict()
    assert jac.shape == (u.shape[0], len(theta))
    for j, (name, value) in enumerate(theta.items()):
        step = 1e-6 * max(abs(value), 1e-3)
        fd = (circuit.with_parameters({name: value + step}).simulate(u)
              - circuit.with_parameters({name: value - step}).simulate(u)) / (2 * step)
        # Central difference: truncation O(step^2) and rounding 1e-16 |v| / step.
        scale = np.max(np.abs(fd)) + 1e-12
        np.testing.assert_allclose(jac[:, j], fd, rtol=0, atol=1e-6 * scale, err_msg=name)


def test_impedance_is_the_closed_form():
    f = np.logspace(-4, 1, 30)
    s = 2j * np.pi * f
    circuit = CIRCUITS[2]
    rc, zarc, war = circuit.elements
    closed = (circuit.r0 + rc.R / (1 + s * rc.tau) + zarc.R / (1 + (s * zarc.tau) ** zarc.alpha)
              + war.sigma * s ** -war.alpha)
    np.testing.assert_allclose(circuit.impedance(f), closed, rtol=1e-12)
    # The GL-discretised model: s -> (1 - exp(-s h)) / h, below the Nyquist frequency 1/(2h).
    h = 1.5
    f = np.logspace(-4, np.log10(0.33), 30)
    s = 2j * np.pi * f
    q = (1 - np.exp(-s * h)) / h
    discrete = (circuit.r0 + rc.R / (1 + q * rc.tau) + zarc.R / (1 + zarc.tau ** zarc.alpha * q ** zarc.alpha)
                + war.sigma * q ** -war.alpha)
    np.testing.assert_allclose(circuit.impedance(f, discrete=True), discrete, rtol=1e-12)


@pytest.mark.parametrize("element", [RC(0.01, 30.0), ZARC(0.01, 30.0, 0.7)], ids=["rc", "zarc"])
def test_discrete_impedance_is_the_impulse_responses_transform(element):
    # sum_k x[k] e^{-j omega h k} for a unit impulse: the simulator and the frequency response
    # agree (the tail beyond 2^17 samples decays like k^(-1-alpha): bounded by 1e-4 here).
    h, n = 1.0, 2 ** 17
    impulse = np.zeros(n)
    impulse[0] = 1.0
    g = element.response(impulse, h)
    f = np.array([1e-3, 1e-2, 0.1, 0.4])
    transform = np.array([np.sum(g * np.exp(-2j * np.pi * fk * h * np.arange(n))) for fk in f])
    np.testing.assert_allclose(transform, element.impedance(f, dt=h), rtol=2e-3)


@pytest.mark.parametrize("make, match", [
    (lambda: ZARC(0.01, 10.0, 1.2), "`alpha` must be in \\(0, 1\\]"),
    (lambda: ZARC(0.01, 0.0, 0.5), "`tau` must be in \\(0, inf\\]"),
    (lambda: RC(-0.01, 1.0), "`R` must be in \\[0, inf\\]"),
    (lambda: Warburg(0.01, 1.0), "`alpha` must be in \\(0, 1\\)"),
    (lambda: EquivalentCircuit(["cpe"], r0=0.01), "`elements\\[0\\]` must be an RC"),
    (lambda: EquivalentCircuit(RC(0.01, 5.0)), "`elements` must be a sequence"),
    (lambda: EquivalentCircuit([], r0=0.01).with_parameters({"R1": 1.0}), "unknown parameter"),
    (lambda: EquivalentCircuit([], r0=0.01).simulate(np.ones((3, 3))), "must have 2 columns"),
    (lambda: EquivalentCircuit([], r0=0.01, dt=0.0), "`dt` must be"),
    (lambda: EquivalentCircuit([], tau_bounds=(10.0, 1.0)), "`tau_bounds` must be increasing"),
    (lambda: EquivalentCircuit([], ocv=[3.0, 4.0]), "`ocv` must be an OCVTable"),
    (lambda: EquivalentCircuit([], r0=0.01).simulate(np.ones((3, 2)), initial=[0.0]), "at rest"),
    (lambda: EquivalentCircuit([ZARC(0.01, 0.5, 0.5)]).parameters, "tau1.*outside its bounds"),
    (lambda: OCVTable([0.0, 0.5, 0.5], [3.0, 3.5, 3.6]), "must increase strictly"),
    (lambda: OCVTable([0.0, 1.0], [3.0, 4.0])([1.2]), "covers soc in \\[0, 1\\]"),
])
def test_bad_parameters_are_named(make, match):
    with pytest.raises(fohw.FohwError, match=match):
        make()


def test_impedance_with_the_ocv_capacitor():
    f = np.array([1e-3, 1e-2])
    circuit = EquivalentCircuit([ZARC(0.01, 100.0, 0.5)], r0=0.015, b=0.05, dt=1e-3)
    extra = circuit.impedance(f, capacity=5.0, ocv_slope=0.55) - circuit.impedance(f)
    # (dOCV/dsoc + b) / (3600 Q j omega): a capacitor of 3600 Q / 0.6 farad.
    np.testing.assert_allclose(extra, 0.6 / (3600 * 5.0 * 2j * np.pi * f), rtol=1e-14)
    # Discrete: the left sum of the coulomb count, h z^-1 / (1 - z^-1) = 1/(j omega) - h/2 + O(h^2).
    h = 1e-3
    d = (circuit.impedance(f, discrete=True, capacity=5.0, ocv_slope=0.55)
         - circuit.impedance(f, discrete=True))
    np.testing.assert_allclose(d, extra - 0.6 / (3600 * 5.0) * h / 2, rtol=1e-9)


def test_circuit_is_a_model_with_named_bounded_parameters():
    circuit = EquivalentCircuit([RC(0.003, 5.0), ZARC(0.01, 300.0, 0.45), Warburg(0.002, 0.6)],
                                r0=0.015, c3=1e-4, dt=1.5)
    assert isinstance(circuit, fohw.Model) and circuit.n_inputs == 2
    p = circuit.parameters
    assert p.names == ("a", "b", "R0", "c3", "R1", "tau1", "R2", "tau2", "alpha2", "sigma3", "alpha3")
    assert [n for n in p if p[n].order] == ["alpha2", "alpha3"]
    # One declaration of each order range: the element's.
    assert p["alpha2"].bounds == ZARC.order_bounds == (0.05, 1.0)
    assert p["alpha3"].bounds == Warburg.order_bounds == (0.05, 0.95)
    assert p["tau1"].bounds == (1.5, math.inf) and p["R0"].bounds == (0.0, math.inf)
    assert p["a"].bounds == (-math.inf, math.inf)
    narrowed = dataclasses.replace(circuit, tau_bounds=(2.0, 500.0)).parameters
    assert narrowed["tau1"].bounds == narrowed["tau2"].bounds == (2.0, 500.0)
    # Kinds by name: a structure with placeholder values inside the bounds.
    template = EquivalentCircuit(("rc", "zarc", "warburg"), tau_bounds=(1.0, 100.0))
    assert template.kinds == ("rc", "zarc", "warburg") and template.parameters["tau1"].value == 10.0


def test_model_file_round_trip_needs_a_tabulated_ocv():
    table = OCVTable(np.linspace(0, 1, 11), 3.0 + np.linspace(0, 1, 11) ** 2)
    circuit = EquivalentCircuit([RC(0.003, 5.0), ZARC(0.01, 300.0, 0.45)], r0=0.015, a=0.01,
                                c3=-1e-4, ocv=table, dt=1.5, tau_bounds=(1.5, 1e4), n_tau=6)
    held = circuit.with_parameters(circuit.parameters.replace("alpha2", value=1.0, fixed=True))
    for model in (circuit, held):
        d = json.loads(json.dumps(model.to_dict()))
        back = fohw.Model.from_dict(d)
        assert back == model and back.parameters == model.parameters
        u = np.column_stack([np.sin(np.arange(50.0)), np.linspace(0.8, 0.7, 50)])
        assert np.array_equal(back.simulate(u), model.simulate(u))
    assert fohw.Model.from_dict(held.to_dict()).parameters["alpha2"].fixed
    with pytest.raises(fohw.ParameterError, match="cannot be written to a file.*OCVTable"):
        dataclasses.replace(circuit, ocv=lambda s: 3.0 + s).to_dict()


def test_the_battery_cells_ocv_table_is_its_ocv():
    cell = fohw.datasets.battery_cell()
    table = cell.ocv_table()
    soc = np.random.default_rng(0).uniform(0.0, 1.0, 20_000)
    # Both are piecewise linear with the same knots: equal up to rounding of volts (2e-16 * 4 V).
    np.testing.assert_allclose(table(soc), cell.ocv(soc), rtol=0, atol=1e-14)
    assert table.soc[0] == 0.0 and table.soc[-1] == 1.0
