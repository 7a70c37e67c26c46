"""The circuit's conventions (issue 37, item 1): the current's sign, the default tau scan, the
projection of infeasible starts, and one message per way a record cannot be fitted."""

import numpy as np
import pytest
import scipy.optimize
from circuit_records import ocv, record  # tests/circuit_records.py (conftest's path)

import fohw
from fohw.model.circuit import RC, ZARC, EquivalentCircuit

TRUE = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, a=0.01, ocv=ocv)


def noisy(model, u, seed, scale=1e-4):
    return model.simulate(u) + scale * np.random.default_rng(seed).standard_normal(u.shape[0])


def test_the_sign_argument_is_checked_and_kept_in_the_config():
    with pytest.raises(fohw.ParameterError, match="`current_sign` must be one of "
                                                  "'charge_positive', 'discharge_positive'.*got "
                                                  "'positive'"):
        EquivalentCircuit(["rc"], current_sign="positive")
    model = EquivalentCircuit(["rc"], current_sign="discharge_positive")
    assert model.config()["current_sign"] == "discharge_positive"
    assert fohw.Model.from_dict(model.to_dict()) == model
    assert model != EquivalentCircuit(["rc"])
    # A file written before the argument existed reads as the shipped record's convention.
    config = EquivalentCircuit(["rc"]).config()
    del config["current_sign"]
    assert EquivalentCircuit.from_config(config).current_sign == "charge_positive"


def test_discharge_positive_counts_the_negated_current():
    u = record(300, seed=1)
    pybamm_u = u * [-1.0, 1.0]
    pybamm = EquivalentCircuit(TRUE.elements, r0=TRUE.r0, a=TRUE.a, ocv=ocv,
                               current_sign="discharge_positive")
    np.testing.assert_array_equal(pybamm.simulate(pybamm_u), TRUE.simulate(u))
    v, jac = pybamm.jacobian(pybamm_u)
    v0, jac0 = TRUE.jacobian(u)
    np.testing.assert_array_equal(v, v0)
    np.testing.assert_array_equal(jac, jac0)
    # A discharge (u[:, 0] > 0 in this convention) lowers the voltage below the OCV.
    assert np.all(pybamm.simulate(np.column_stack([np.ones(5), np.full(5, 0.5)])) < ocv(0.5))


def test_a_pybamm_sign_record_is_refused_by_default_and_fitted_after_setting_the_convention():
    u = record(2000, seed=2)
    v = noisy(TRUE, u, 3)
    pybamm_u = u * [-1.0, 1.0]              # PyBaMM's "Current [A]": positive on discharge
    with pytest.raises(fohw.ParameterError) as err:
        fohw.fit(EquivalentCircuit(["zarc"], ocv=ocv, tau_bounds=(1.0, 1000.0)), pybamm_u, v)
    text = str(err.value)
    assert "voltage falls when the current rises" in text
    assert "current_sign='charge_positive'" in text and "current_sign='discharge_positive'" in text
    assert "PyBaMM" in text and "widen" not in text
    fit = fohw.fit(EquivalentCircuit(["zarc"], ocv=ocv, tau_bounds=(1.0, 1000.0),
                                     current_sign="discharge_positive"), pybamm_u, v)
    assert fit.converged
    se = fit.standard_errors()
    for name, true in (("R0", 0.015), ("R1", 0.012), ("tau1", 60.0), ("alpha1", 0.5)):
        assert abs(fit.parameters[name].value - true) < 4 * se[name], name
    # The same numbers as the charge-positive record fitted with the default convention.
    same = fohw.fit(EquivalentCircuit(["zarc"], ocv=ocv, tau_bounds=(1.0, 1000.0)), u, v)
    assert same.sse == fit.sse
    assert same.parameters.valuesdict() == fit.parameters.valuesdict()


def test_a_charge_positive_record_given_to_a_pybamm_sign_circuit_names_the_other_convention():
    u = record(2000, seed=4)
    v = noisy(TRUE, u, 5)
    with pytest.raises(fohw.ParameterError,
                       match="current_sign='discharge_positive'.*current_sign='charge_positive' "
                             r"\(the shipped LG M50LT record's\)"):
        fohw.fit(EquivalentCircuit(["zarc"], ocv=ocv, current_sign="discharge_positive"), u, v)


def test_the_sign_check_leaves_a_record_without_a_clear_sign_to_the_fit():
    # Noise only: the slope of the steps is not significant either way, so no refusal here;
    # the fit itself then says every resistance is 0 (check_fitted), naming the other sign.
    u = record(600, seed=6)
    v = 3.7 + 1e-3 * np.random.default_rng(7).standard_normal(u.shape[0])
    model = EquivalentCircuit(["rc"], tau_bounds=(1.0, 100.0))
    i, _ = model._signals(u)
    model.check_sign(i, v)                  # does not raise
    note = model.with_parameters({"R0": 0.0, "R1": 0.0}).check_fitted(u, v)
    assert "current_sign='discharge_positive'?" in note


def test_each_failure_has_its_own_message():
    u = record(300, seed=8)
    v = noisy(TRUE, u, 9)
    model = EquivalentCircuit(["zarc"], ocv=ocv, tau_bounds=(1.0, 1000.0))
    cases = {
        "no excitation": ((u * [0.0, 1.0]), v, fohw.ParameterError,
                          r"current `u\[:, 0\]` is zero at every sample: the record has no "
                          "excitation"),
        "constant current": (np.column_stack([np.full(300, -2.0), u[:, 1]]), v,
                             fohw.ParameterError, r"current `u\[:, 0\]` is constant \(-2.0 A at "
                                                  "all 300 samples\\)"),
        "constant voltage": (u, np.full(300, 3.7), fohw.ParameterError, "`y` is constant"),
        "too few samples": (u[:5], v[:5], fohw.DimensionError,
                            "`y` has 5 samples for 6 free parameters"),
        "sign": (u * [-1.0, 1.0], v, fohw.ParameterError, "voltage falls when the current rises"),
    }
    texts = {}
    for what, (uu, vv, error, match) in cases.items():
        with pytest.raises(error, match=match) as err:
            fohw.fit(model, uu, vv)
        texts[what] = str(err.value)
        assert "widen" not in texts[what] and "tau_bounds" not in texts[what], what
    assert len(set(texts.values())) == len(cases)


def test_the_default_scan_reaches_the_relaxation_of_a_pulse():
    # A 20 s discharge pulse and 20 s of relaxation at 0.1 s: the old default scan stopped at
    # N dt / 10 = 4 s, below the 15 s time constant of the relaxation; the default now covers
    # the record's duration (40 s), so a grid point lies near it and the fit finds it.
    dt = 0.1
    t = dt * np.arange(400)
    i = np.where(t < 20.0, -5.0, 0.0)
    soc = 0.5 + np.concatenate([[0.0], np.cumsum(i[:-1])]) * dt / (3600 * 5.0)
    u = np.column_stack([i, soc])
    true = EquivalentCircuit([RC(0.004, 0.8), RC(0.01, 15.0)], r0=0.02, a=3.7, dt=dt)
    v = noisy(true, u, 10)
    model = EquivalentCircuit(["rc", "rc"], dt=dt)
    assert model.parameters["tau2"].bounds == (dt, np.inf)
    taus = sorted({s.parameters["tau2"].value for s in model.starts(u, v)})
    assert taus[-1] > 15.0 / 2
    assert taus[-1] == pytest.approx(400 * dt, rel=1e-12)   # the documented top: N dt
    fit = fohw.fit(model, u, v)
    assert fit.converged
    se = fit.standard_errors()
    assert abs(fit.parameters["tau2"].value - 15.0) < 4 * se["tau2"]
    assert fit.rmse < 1.5e-4


def test_infeasible_grid_points_are_projected_onto_non_negative_resistances():
    # A record no grid point fits with non-negative resistances: the voltage undershoots after
    # each step (an RC element of negative resistance, which a cell has not). The start is the
    # bounded least-squares solution at its grid point (R1 = 0, a, b, R0 re-solved), computed
    # here independently with scipy's NNLS-type solver on the raw columns, not R1 clipped to 0
    # with the others left where the unconstrained solve put them.
    u = record(1500, seed=11)
    i, soc = u[:, 0], u[:, 1]
    overshoot = RC(1.0, 40.0).response(i, 1.0)
    v = 3.6 + 0.1 * soc + 0.02 * i - 0.01 * overshoot
    model = EquivalentCircuit(["rc"], tau_bounds=(2.0, 500.0), n_tau=4)
    starts = model.starts(u, v)
    assert starts
    for s in starts:
        p = s.parameters.valuesdict()
        assert p["R0"] >= 0 and p["R1"] >= 0
        cols = np.column_stack([np.ones_like(i), soc, i, RC(1.0, p["tau1"]).response(i, 1.0)])
        ref = scipy.optimize.lsq_linear(cols, v, bounds=([-np.inf, -np.inf, 0, 0], np.inf),
                                        tol=1e-12)
        np.testing.assert_allclose([p["a"], p["b"], p["R0"], p["R1"]], ref.x, rtol=1e-6,
                                   atol=1e-9)
    with pytest.warns(fohw.RankDeficiencyWarning, match="tau1"):   # R1 = 0: tau1 has no effect
        fit = fohw.fit(model, u, v)
    assert fit.parameters["R1"].value == 0.0


@pytest.mark.slow
def test_a_pulse_simulated_by_pybamm_is_fitted_in_its_own_sign_convention():
    # PyBaMM's SPMe with the Chen2020 parameters (an LG M50 cell): a 30 s, 5 A discharge pulse
    # between rests, PyBaMM's "Current [A]" positive on discharge.
    pybamm = pytest.importorskip("pybamm")
    dt = 0.5
    t = np.arange(0.0, 120.0 + dt / 2, dt)
    pulse = np.where((t >= 10.0) & (t < 40.0), 5.0, 0.0)
    values = pybamm.ParameterValues("Chen2020")
    values["Current function [A]"] = pybamm.Interpolant(t, pulse, pybamm.t, interpolator="linear")
    solution = pybamm.Simulation(pybamm.lithium_ion.SPMe(), parameter_values=values).solve(
        t_eval=t, t_interp=t, initial_soc=0.5)
    i = solution["Current [A]"].entries
    v = solution["Voltage [V]"].entries
    soc = 0.5 - np.concatenate([[0.0], np.cumsum(i[:-1])]) * dt / (3600 * 5.0)
    u = np.column_stack([i, soc])
    with pytest.raises(fohw.ParameterError, match="current_sign='discharge_positive' \\(PyBaMM"):
        fohw.fit(EquivalentCircuit(["rc", "rc"], dt=dt), u, v)
    fit = fohw.fit(EquivalentCircuit(["rc", "rc"], dt=dt, current_sign="discharge_positive"), u, v)
    assert fit.converged and fit.rmse < 1e-3
    # R0 is about the voltage's jump at the pulse's ends divided by the current's (the first
    # sample after each edge also holds the elements' first step, hence 25 %).
    edges = [int(np.argmax(i > 4.99)), int(np.argmax((t > 40.0) & (i < 0.01)))]
    jump = np.mean([abs(v[k] - v[k - 2]) for k in edges]) / 5.0
    assert fit.parameters["R0"].value == pytest.approx(jump, rel=0.25)
