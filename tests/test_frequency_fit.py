"""``fohw.fit_frequency_response``: any kind with a frequency response fitted to a measured one.

The model before the estimator: each kind's response at its true parameters is checked against
its literal formula written out here (so the criterion is zero at the truth for the right
reason); then the fit recovers the truth from a perturbed start on exact data (to 1e-6: on
exact data the search stops at ``tol = 1e-10`` and the estimate is the truth to rounding, the
parameters of these problems being well conditioned), lies within a few standard errors of it
on noisy data over several seeds, honours fixed flags, bounds and ties, and agrees with
``fit_impedance`` on a circuit. Every shipped kind of ``tests/test_model_protocol.py`` is
fitted, so none is left out; a kind without the hook is refused naming it.
"""

import importlib
import warnings

import numpy as np
import pytest

import fohw
from fohw.estimators.frequency_fit import FrequencyProblem, idle_parameters
from fohw.estimators.impedance_fit import fit_impedance

# The protocol tests' kinds, from the module pytest loads (``--import-mode=importlib`` names it
# ``tests.test_model_protocol``; a second copy would register its kind twice).
KINDS = importlib.import_module("tests.test_model_protocol").KINDS

W = np.logspace(-2, 2, 40)


def tf_one():
    """1 / (s^0.8 + 1)."""
    return fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0])


def tf_two():
    """1.5 / (0.5 s^1.6 + 2 s^0.7 + 1): two fractional terms in the denominator."""
    return fohw.FractionalTF([1.5], [0.0], [0.5, 2.0, 1.0], [1.6, 0.7, 0.0])


def test_the_responses_are_their_formulas():
    s = 1j * W
    # principal branch: (j w)^a = w^a e^{j a pi / 2}
    np.testing.assert_allclose(tf_one().frequency_response(W), 1 / (W ** 0.8 * np.exp(0.4j * np.pi) + 1),
                               rtol=1e-13)
    np.testing.assert_allclose(tf_two().frequency_response(W),
                               1.5 / (0.5 * s ** 1.6 + 2 * s ** 0.7 + 1), rtol=1e-13)
    cell = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015)
    np.testing.assert_allclose(cell.frequency_response(W), 0.015 + 0.012 / (1 + (50.0 * s) ** 0.55),
                               rtol=1e-13)
    # the criterion is zero at the truth, and only there (a 1 % change of one value moves it)
    true = tf_one()
    problem = FrequencyProblem(true, true.parameters, lambda m: m.frequency_response(W),
                               true.frequency_response(W), np.ones(W.size))
    x = true.parameters.free_values()
    assert np.max(np.abs(problem.residual(x))) == 0.0
    assert np.max(np.abs(problem.residual(x * [1.01, 1.0, 1.0]))) > 1e-3


def _truth_of(res, true):
    """The truth's name for each estimate's name.

    A FractionalTF's denominator terms have no order among themselves: ``a0 s^alpha0 + a1
    s^alpha1`` with the two terms swapped is the same function, which the fit may end at
    (both labellings start from the order grid at the same criterion). The estimate's terms
    are matched to the truth's by their orders (both sorted).
    """
    names = {n: n for n in res.parameters}
    if isinstance(true, fohw.FractionalTF) and "alpha1" in res.free_names:
        if (res.parameters["alpha0"].value < res.parameters["alpha1"].value) != \
                (true.parameters["alpha0"].value < true.parameters["alpha1"].value):
            names.update(a0="a1", a1="a0", alpha0="alpha1", alpha1="alpha0")
    return names


def _errors(res, true):
    tv = true.parameters.valuesdict()
    truth = _truth_of(res, true)
    return {n: abs(res.parameters[n].value - tv[truth[n]]) / max(abs(tv[truth[n]]), 1.0)
            for n in res.free_names}


@pytest.mark.parametrize("true, start", [
    (tf_one(), fohw.FractionalTF([0.5], [0.0], [2.0, 1.0], [0.5, 0.0])),
    (tf_two(), fohw.FractionalTF([1.0], [0.0], [1.0, 1.0, 1.0], [1.3, 0.4, 0.0])),
], ids=["1/(s^0.8+1)", "two terms"])
def test_a_transfer_function_is_recovered_from_its_exact_response(true, start):
    res = fohw.fit_frequency_response(start, W, true.frequency_response(W))
    assert isinstance(res, fohw.FitResult) and res.converged, res.message
    assert res.n_samples == 2 * W.size and res.options["data"] == "frequency response"
    assert res.free_names == start.parameters.free_names          # nothing held: all enter
    errors = _errors(res, true)
    assert max(errors.values()) < 1e-6, errors
    assert res.standard_errors() is not None


def test_the_estimate_is_within_its_standard_errors_on_noisy_data():
    # 1 % complex relative noise: the relative residual's RMS is the noise's, and each estimate
    # lies within 4 standard errors of the truth on every seed (|z| > 4 has probability 6e-5).
    true, sigma = tf_two(), 0.01
    start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0, 1.0], [1.3, 0.4, 0.0])
    h0 = true.frequency_response(W)
    zs, d2 = [], 0.0
    for seed in range(5):
        rng = np.random.default_rng(seed)
        h = h0 * (1 + sigma * (rng.standard_normal(W.size) + 1j * rng.standard_normal(W.size)))
        res = fohw.fit_frequency_response(start, W, h)
        assert res.converged, res.message
        assert res.rmse == pytest.approx(sigma, rel=0.3)
        se, truth = res.standard_errors(), _truth_of(res, true)
        e = np.array([res.parameters[n].value - true.parameters[truth[n]].value
                      for n in res.free_names])
        zs += list(e / [se[n] for n in res.free_names])
        d2 += float(e @ np.linalg.solve(res.covariance, e))
    zs = np.array(zs)
    assert np.all(np.abs(zs) < 4), zs
    # the covariance is neither far too small nor far too large: the squared Mahalanobis
    # distances of the 5 seeds sum to a chi-squared of 25 degrees of freedom, inside its
    # central 99.9 % [7.99, 54.9] (measured: 14.3; a covariance 4 times too small or too large
    # would put it outside)
    assert 7.99 < d2 < 54.9, d2


def test_a_circuit_fit_agrees_with_fit_impedance():
    true = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015)
    f = np.logspace(-4, 1, 30)
    z = true.impedance(f)
    model = fohw.EquivalentCircuit(["zarc"])
    generic = fohw.fit_frequency_response(model, 2 * np.pi * f, z)
    circuit = fit_impedance(model, f, z)
    assert generic.converged and circuit.converged
    assert max(_errors(generic, true).values()) < 1e-6
    for name in generic.free_names:
        assert generic.parameters[name].value == pytest.approx(circuit.parameters[name].value,
                                                               rel=1e-8, abs=1e-12)
    # both hold a and b (they do not enter the impedance) and say so
    assert generic.free_names == circuit.free_names == ("R0", "R1", "tau1", "alpha1")
    assert "a and b do not enter the frequency response: held" in generic.message


def test_the_lagged_kinds_fit_their_linear_block():
    # H(e^{jw}) = f'(0) B / (1 - g'(0) A): the curvature of the input map does not enter
    for true, start, held in [
        (fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.3], [1.0], 0.4),
         fohw.HammersteinWiener([0.1], [0.5, 0.1], [1.0, 0.0], [1.0], 0.6), "p2 does not"),
        (fohw.ThetaHW(fohw.Structure.make(na=1, nb=2, f_basis=2, g_basis=1), [0.3, 1.0, 0.5, 0.3, -0.1],
                      [0.4]),
         fohw.ThetaHW(fohw.Structure.make(na=1, nb=2, f_basis=2, g_basis=1), [0.1, 0.5, 0.1, 0.0, 0.0],
                      [0.6]), "p2b1 and p2b2 do not")]:
        w = true.default_frequencies(40)
        res = fohw.fit_frequency_response(start, w, true.frequency_response(w))
        assert res.converged and held in res.message, res.message
        assert max(_errors(res, true).values()) < 1e-6
        # they are fixed at the start's values in the result, not moved
        for n in res.parameters:
            if n not in res.free_names:
                assert res.parameters[n].value == start.parameters[n].value


@pytest.mark.parametrize("factory", KINDS, ids=lambda f: f.__name__)
def test_every_kind_with_a_frequency_response_is_fitted_to_it(factory):
    true, start, _, _, _ = factory()
    if type(true).frequency_response is fohw.Model.frequency_response:
        with pytest.raises(fohw.ParameterError, match=r"has no frequency response: its kind does "
                                                      r"not define the fohw.Model hook `frequency_response"):
            fohw.fit_frequency_response(start, W, np.ones(W.size))
        return
    # the tables' impedance is that of one operating point: at a breakpoint only its values enter
    where = dict(soc=0.3, temperature=5.0) if isinstance(true, fohw.CircuitTables) else {}
    w = true.default_frequencies(40)
    h = true.frequency_response(w, **where)
    res = fohw.fit_frequency_response(start, w, h, **where)
    assert res.converged, res.message
    assert res.sse < 1e-20
    assert max(_errors(res, true).values()) < 1e-6, _errors(res, true)
    np.testing.assert_allclose(res.model.frequency_response(w, **where), h, rtol=1e-8)
    # what is held is what the response does not read (at either probe point)
    assert set(res.parameters.free_names) | set(idle_parameters(start, lambda m: m.frequency_response(
        w, **where))) == set(start.parameters.free_names)


def test_fixed_bounds_and_ties_are_honoured():
    true = fohw.FractionalTF([2.0], [0.0], [2.0, 1.0], [0.8, 0.0])            # b0 = a0 = 2
    h = true.frequency_response(W)
    start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    # a tie: b0 = 1.0 * a0 (unit static gain), one free value fewer
    tied = start.with_parameters(start.parameters.replace("b0", tie=("a0", 1.0)))
    res = fohw.fit_frequency_response(tied, W, h)
    assert res.free_names == ("a0", "alpha0") and res.converged
    assert res.parameters["b0"].value == res.parameters["a0"].value
    assert res.parameters["a0"].value == pytest.approx(2.0, rel=1e-6)
    # fixed: alpha0 held at 0.8 exactly
    fixed = start.with_parameters(start.parameters.replace("alpha0", value=0.8, fixed=True))
    res = fohw.fit_frequency_response(fixed, W, h)
    assert res.parameters["alpha0"].value == 0.8 and "alpha0" not in res.free_names
    assert res.parameters["b0"].value == pytest.approx(2.0, rel=1e-6)
    # a bound that excludes the truth: the estimate ends on it, and the message says so
    bounded = start.with_parameters(start.parameters.replace("alpha0", bounds=(0.3, 0.7)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        res = fohw.fit_frequency_response(bounded, W, h)
    assert res.parameters["alpha0"].value == 0.7


def test_weights():
    true, start = tf_one(), fohw.FractionalTF([0.5], [0.0], [2.0, 1.0], [0.5, 0.0])
    h = true.frequency_response(W)
    unit = fohw.fit_frequency_response(start, W, h, weight="unit")
    assert unit.converged and max(_errors(unit, true).values()) < 1e-6
    # the residual is the weighted complex error, stacked: recomputed here from its definition
    rng = np.random.default_rng(3)
    noisy = h * (1 + 0.01 * rng.standard_normal(W.size))
    w = 1 + rng.uniform(size=W.size)
    res = fohw.fit_frequency_response(start, W, noisy, weight=w)
    d = (res.model.frequency_response(W) - noisy) * w
    np.testing.assert_allclose(res.residuals, np.r_[d.real, d.imag], rtol=1e-12, atol=1e-15)
    assert res.sse == pytest.approx(float(res.residuals @ res.residuals), rel=1e-12)


def test_a_frequency_fit_is_a_fit_result_that_files_hold(tmp_path):
    true = fohw.CircuitTables(["zarc"], soc_points=[0.3, 0.7], temperature_points=[5.0],
                              values={"R0": [[0.02], [0.015]], "R1": [[0.012], [0.01]],
                                      "tau1": [[40.0], [30.0]], "alpha1": 0.6},
                              tau_bounds=(1.0, 500.0))
    start = fohw.CircuitTables(["zarc"], soc_points=[0.3, 0.7], temperature_points=[5.0],
                               tau_bounds=(1.0, 500.0))
    w = np.logspace(-4, 0, 30)
    res = fohw.fit_frequency_response(start, w, true.frequency_response(w, soc=0.7), soc=0.7)
    assert res.options["soc"] == 0.7 and res.converged
    fohw.save_result(res, tmp_path / "fit.json")
    back = fohw.load_result(tmp_path / "fit.json")
    assert back.parameters == res.parameters and back.options == res.options


def test_refusals_name_what_is_wrong():
    G = tf_one()
    h = G.frequency_response(W)
    with pytest.raises(fohw.ParameterError, match="`omega` must be positive angular frequencies"):
        fohw.fit_frequency_response(G, np.r_[0.0, W[1:]], h)
    with pytest.raises(fohw.ParameterError, match="`response` must have one value per frequency"):
        fohw.fit_frequency_response(G, W, h[:-1])
    with pytest.raises(fohw.ParameterError, match="need more equations than parameters"):
        fohw.fit_frequency_response(G, W[:1], h[:1])
    with pytest.raises(fohw.ParameterError, match="`weight` must be one of 'relative', 'unit'"):
        fohw.fit_frequency_response(G, W, h, weight="modulus")
    with pytest.raises(fohw.ParameterError, match="`n_start` is neither an argument of "
                                                  "fit_frequency_response nor a keyword of "
                                                  r"FractionalTF.frequency_response \(it takes none\)"):
        fohw.fit_frequency_response(G, W, h, n_start=2)
    with pytest.raises(fohw.ParameterError, match="`model` must be a fohw.Model"):
        fohw.fit_frequency_response("G", W, h)
    # a sampled response (the lagged kind's) above pi / dt: refused; a continuous one is not
    lagged = fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.3], [1.0], 0.4)
    w = np.linspace(0.1, 5.0, 30)
    with pytest.raises(fohw.ParameterError, match=r"11 of its 30 frequencies above the Nyquist "
                                                  r"frequency pi / dt = 3.14159"):
        fohw.fit_frequency_response(lagged, w, lagged.frequency_response(w))
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.5)       # pi / dt = 6.3
    assert fohw.fit_frequency_response(G, W, h).converged
    # an impedance with the other sign (-Z) is refused; conj(Z) (the "-Im Z" convention) warned
    cell = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015)
    z = cell.frequency_response(W)
    with pytest.raises(fohw.ParameterError, match="negative real part at 40 of its 40 frequencies"):
        fohw.fit_frequency_response(cell, W, -z)
    with pytest.warns(fohw.DataWarning, match="looks like the \"-Im Z\" convention"), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.RankDeficiencyWarning)
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        fohw.fit_frequency_response(cell, W, np.conj(z))
