"""Fitting equivalent circuits with fohw.fit: recovery, the scan, the nested integer limit, the checks."""

import math

import numpy as np
import pytest
import scipy.optimize
import scipy.stats
from circuit_records import ocv, record  # tests/circuit_records.py (conftest's path)

import fohw
from fohw.model.circuit import RC, ZARC, EquivalentCircuit

TRUE = EquivalentCircuit([RC(0.004, 6.0), ZARC(0.012, 150.0, 0.55)], r0=0.015, a=0.01, b=-0.02,
                         c3=-1e-4, ocv=ocv)


def circuit(elements, *, current_map=False, **held):
    """The structure to fit (tau in [1, 1000] s), with ``held`` parameters fixed at their values."""
    model = EquivalentCircuit(elements, c3=0.0 if current_map else None, ocv=ocv,
                              tau_bounds=(1.0, 1000.0))
    params = model.parameters
    for name, value in held.items():
        params = params.replace(name, value=value, fixed=True)
    return model.with_parameters(params)


def at_bounds(fit):
    """Free parameters on, or within 1e-6 (relative) of, a bound."""
    return [n for n in fit.free_names
            if np.any(np.isclose(fit.parameters[n].value, fit.parameters[n].bounds, rtol=1e-6,
                                 atol=0.0))]


def test_noise_free_record_is_recovered_exactly():
    u = record()
    v = TRUE.simulate(u)
    fit = fohw.fit(circuit(("rc", "zarc"), current_map=True), u, v)
    truth = TRUE.parameters.valuesdict()
    np.testing.assert_allclose([fit.parameters[n].value for n in truth], list(truth.values()),
                               rtol=1e-6, atol=1e-9)
    assert fit.converged and fit.rmse < 1e-9 and at_bounds(fit) == []
    assert fit.free_names == TRUE.parameters.names     # a, b, R0, c3, R1, tau1, R2, tau2, alpha2


def test_noisy_record_within_standard_errors_and_gradient_zero():
    u = record(4000, seed=1)
    noise = 1e-3 * np.random.default_rng(2).standard_normal(u.shape[0])
    v = TRUE.simulate(u) + noise
    fit = fohw.fit(circuit(("rc", "zarc"), current_map=True), u, v)
    se = fit.standard_errors()
    truth = TRUE.parameters.valuesdict()
    z = {n: (fit.parameters[n].value - x) / se[n] for n, x in truth.items()}
    # 9 z-scores, each ~N(0, 1) for an efficient fit: 99.9 % familywise (Bonferroni) bound.
    hi = scipy.stats.norm.isf(0.0005 / len(z))
    assert max(abs(x) for x in z.values()) < hi, {n: round(x, 2) for n, x in z.items()}
    # The residual RMS of N samples of 1e-3 noise (less d fitted): relative spread
    # 1 / sqrt(2 N); 3.3 of those is 99.9 %.
    assert fit.rmse == pytest.approx(1e-3, rel=3.3 / np.sqrt(2 * u.shape[0]))
    # First-order optimality with the exact Jacobian: J^T r = 0 relative to |J| |r|.
    _, jac = fit.model.jacobian(u)
    g = jac.T @ fit.residuals
    assert np.all(np.abs(g) <= 1e-5 * np.linalg.norm(jac, axis=0) * np.linalg.norm(fit.residuals))
    # The same minimum as a finite-difference least_squares from the fit.
    names = list(truth)

    def resid(p):
        return TRUE.with_parameters(dict(zip(names, p))).simulate(u) - v
    x0 = [fit.parameters[n].value for n in names]
    fd = scipy.optimize.least_squares(resid, x0, x_scale="jac", method="lm")
    assert 2 * fd.cost >= fit.sse * (1 - 1e-9)


def test_zarc_at_order_one_is_the_rc_fit():
    u = record(2000, seed=3)
    v = TRUE.simulate(u) + 1e-3 * np.random.default_rng(4).standard_normal(u.shape[0])
    rc = fohw.fit(circuit(("rc",)), u, v)
    at_one = fohw.fit(circuit(("zarc",), alpha1=1.0), u, v)
    assert at_one.sse == pytest.approx(rc.sse, rel=1e-8)
    full = fohw.fit(circuit(("zarc",)), u, v)
    # The generic test, though the OCV is a Python function (no config(): issue 32).
    test = fohw.lr_test(at_one, full)
    assert test.statistic == pytest.approx(u.shape[0] * math.log(at_one.sse / full.sse))
    assert test.df == 1 and test.boundary == ("alpha1",) and "0.5*chi2_0" in test.distribution
    # The mixture's p-value is half the chi2_1 tail.
    assert test.pvalue == pytest.approx(0.5 * scipy.stats.chi2.sf(test.statistic, 1))
    assert test.hypothesis == "alpha1 = 1" and test.criterion == "free-run RSS"
    # With the record, `full` is refitted from the restricted estimate too: never above it.
    again = fohw.lr_test(at_one, full, u=u, y=v)
    assert again.rss_full <= full.sse and again.statistic >= test.statistic
    # The RC circuit is the same model, but not the ZARC's with a parameter fixed: the
    # generic test needs the pair written as one model (alpha1 held at 1).
    with pytest.raises(fohw.ParameterError, match="have different parameters"):
        fohw.lr_test(rc, full)


def test_lr_test_with_an_effective_sample_size():
    u = record(2000, seed=3)
    v = TRUE.simulate(u) + 1e-3 * np.random.default_rng(4).standard_normal(u.shape[0])
    at_one = fohw.fit(circuit(("zarc",), alpha1=1.0), u, v)
    full = fohw.fit(circuit(("zarc",)), u, v)
    test = fohw.lr_test(at_one, full, n_effective=250.5)
    assert test.statistic == pytest.approx(250.5 * math.log(at_one.sse / full.sse), rel=1e-12)
    assert test.pvalue == pytest.approx(0.5 * scipy.stats.chi2.sf(test.statistic, 1), rel=1e-12)
    assert test.n == 250 and "n_effective = 250.5 of 2000 samples" in test.criterion
    assert "n_effective = 250.5" in str(test)
    with pytest.raises(fohw.ParameterError, match="`n_effective` must be at most the 2000"):
        fohw.lr_test(at_one, full, n_effective=2001)
    with pytest.raises(fohw.ParameterError, match="`n_effective` must be"):
        fohw.lr_test(at_one, full, n_effective=0.5)


def test_lr_test_refuses_circuit_fits_to_two_records_or_step_sizes():
    # issue 34 case 22: the former circuit_lr_test gave LR 34 260 (two records) and 2 168 (two
    # step sizes), p = 0, without a check.
    u = record(1500, seed=20)
    v = TRUE.simulate(u) + 1e-3 * np.random.default_rng(21).standard_normal(u.shape[0])
    full = fohw.fit(circuit(("zarc",)), u, v)
    other = record(1500, seed=22)
    w = TRUE.simulate(other) + 1e-3 * np.random.default_rng(23).standard_normal(u.shape[0])
    restricted = fohw.fit(circuit(("zarc",), alpha1=1.0), other, w)
    with pytest.raises(fohw.ParameterError, match="not fitted to the same record"):
        fohw.lr_test(restricted, full)
    coarse = EquivalentCircuit(["zarc"], ocv=ocv, dt=2.0, tau_bounds=(2.0, 1000.0))
    coarse = coarse.with_parameters(coarse.parameters.replace("alpha1", value=1.0, fixed=True))
    restricted = fohw.fit(coarse, u, v)
    with pytest.raises(fohw.ParameterError, match="different step sizes"):
        fohw.lr_test(restricted, full)
    # Half the record passed for the refit: refused, not refitted on it.
    at_one = fohw.fit(circuit(("zarc",), alpha1=1.0), u, v)
    with pytest.raises(fohw.ParameterError, match="fitted to 1500"):
        fohw.lr_test(at_one, full, u=u[:750], y=v[:750])


def test_lr_test_compares_the_ocv_maps():
    # A circuit's OCV is a setting, not a parameter: two fits with different OCV functions are
    # not one model with a parameter fixed, though their parameters have the same names.
    u = record(1500, seed=24)
    v = TRUE.simulate(u) + 1e-3 * np.random.default_rng(25).standard_normal(u.shape[0])
    full = fohw.fit(circuit(("zarc",)), u, v)
    shifted = EquivalentCircuit(["zarc"], ocv=lambda s: ocv(s) + 0.01, tau_bounds=(1.0, 1000.0))
    shifted = shifted.with_parameters(shifted.parameters.replace("alpha1", value=1.0, fixed=True))
    restricted = fohw.fit(shifted, u, v)
    with pytest.raises(fohw.ParameterError, match="same settings.*Python-function OCV"):
        fohw.lr_test(restricted, full)
    # Two tables: compared through config(), the message names the setting that differs.
    grid = np.linspace(0.0, 1.0, 101)
    tables = [fohw.OCVTable(grid, ocv(grid) + shift) for shift in (0.0, 0.01)]
    pair = []
    for table, held in zip(tables, (False, True)):
        model = EquivalentCircuit(["zarc"], ocv=table, tau_bounds=(1.0, 1000.0))
        if held:
            model = model.with_parameters(model.parameters.replace("alpha1", value=1.0, fixed=True))
        pair.append(fohw.fit(model, u, v))
    with pytest.raises(fohw.ParameterError, match="same settings.*config\\(\\) differ in 'ocv'"):
        fohw.lr_test(pair[1], pair[0])
    # The same bound method of one object is the same map (a new object at each access).
    cell = fohw.datasets.battery_cell()
    a = EquivalentCircuit(["zarc"], ocv=cell.ocv)
    assert a.ocv is not cell.ocv and a == EquivalentCircuit(["zarc"], ocv=cell.ocv)
    assert a != EquivalentCircuit(["zarc"], ocv=fohw.datasets.battery_cell().ocv)


def test_profile_interval_covers_the_true_order_and_matches_the_statistic():
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, ocv=ocv)
    u = record(3000, seed=5)
    v = true.simulate(u) + 1e-3 * np.random.default_rng(6).standard_normal(u.shape[0])
    fit = fohw.fit(circuit(("zarc",)), u, v)
    pi = fohw.profile_interval(fit, "alpha1", u=u, y=v, n_grid=5)
    assert pi.low < 0.5 < pi.high and pi.one_sided == ""
    # At each end the refit's statistic is the chi2_1 quantile, 3.84 (xtol 1e-4 in the order,
    # times a slope of the statistic below 200 per unit there).
    for end in (pi.low, pi.high):
        r = fohw.fit(circuit(("zarc",), alpha1=end), u, v, start=fit.model)
        assert u.shape[0] * math.log(r.sse / fit.sse) == pytest.approx(3.841, abs=0.05)
    # The width agrees with the standard error (a quadratic profile): 1.96 se each side.
    assert (pi.high - pi.low) / 2 == pytest.approx(1.96 * fit.standard_errors()["alpha1"], rel=0.15)
    # With an effective sample size the statistic scales by n_eff / n: at each end of that
    # interval the nominal statistic is 3.84 * n / n_eff.
    wide = fohw.profile_interval(fit, "alpha1", u=u, y=v, n_grid=5, n_effective=750.0)
    assert wide.low < pi.low and pi.high < wide.high
    for end in (wide.low, wide.high):
        r = fohw.fit(circuit(("zarc",), alpha1=end), u, v, start=fit.model)
        assert 750.0 * math.log(r.sse / fit.sse) == pytest.approx(3.841, abs=0.05)
    # issue 34 case 23: an interval on half the record it was not fitted to is refused.
    with pytest.raises(fohw.ParameterError, match="fitted to 3000"):
        fohw.profile_interval(fit, "alpha1", u=u[:1500], y=v[:1500])


def test_profile_interval_scans_the_fits_own_order_bounds():
    # Declared once: a Warburg order bounded to [0.3, 0.7] is profiled over [0.3, 0.7] (the
    # former fitter scanned 0.05 to 0.95 and refitted under its default bounds).
    u = record(1500, seed=8)
    true = EquivalentCircuit([fohw.Warburg(0.002, 0.5)], r0=0.015, ocv=ocv)
    v = true.simulate(u) + 1e-3 * np.random.default_rng(9).standard_normal(u.shape[0])
    model = EquivalentCircuit(["warburg"], ocv=ocv)
    model = model.with_parameters(model.parameters.replace("alpha1", bounds=(0.3, 0.7)))
    fit = fohw.fit(model, u, v)
    pi = fohw.profile_interval(fit, "alpha1", u=u, y=v, n_grid=3)
    assert pi.grid.min() >= 0.3 and pi.grid.max() <= 0.7 and 0.3 in pi.grid and 0.7 in pi.grid


def test_verbs_refit_with_the_fits_own_sample_weights():
    # A fit with a block held back (weight 0): the profile's refits and lr_test's refit use the
    # same weights, so the criterion is the fit's. Before, the record check (unweighted) refused
    # the fit's own record.
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, ocv=ocv)
    u = record(2000, seed=26)
    v = true.simulate(u) + 1e-3 * np.random.default_rng(27).standard_normal(u.shape[0])
    v[800:1100] += 0.05                             # a block the criterion must not see
    w = np.ones(u.shape[0])
    w[800:1100] = 0.0
    fit = fohw.fit(circuit(("zarc",)), u, v, sample_weight=w)
    assert fit.n_samples == 1700
    pi = fohw.profile_interval(fit, "alpha1", u=u, y=v, n_grid=3)
    assert pi.low < 0.5 < pi.high
    # Each grid point's statistic is that of a weighted refit with alpha1 held there.
    for value, stat in zip(pi.grid, pi.statistic):
        r = fohw.fit(circuit(("zarc",), alpha1=float(value)), u, v, sample_weight=w,
                     start=fit.model.with_parameters({"alpha1": float(value)}))
        assert stat == pytest.approx(max(1700 * math.log(r.sse / fit.sse), 0.0), rel=1e-6, abs=1e-6)
    at_one = fohw.fit(circuit(("zarc",), alpha1=1.0), u, v, sample_weight=w)
    test = fohw.lr_test(at_one, fit, u=u, y=v)
    assert test.statistic == pytest.approx(1700 * math.log(at_one.sse / test.rss_full))
    # The same record with other weights is another criterion: refused.
    with pytest.raises(fohw.ParameterError, match="not fitted to the same record"):
        fohw.lr_test(fohw.fit(circuit(("zarc",), alpha1=1.0), u, v), fit)


@pytest.mark.parametrize("make, error, match", [
    (lambda: EquivalentCircuit(("rc", "cpe")), fohw.ParameterError,
     "`elements\\[1\\]` must be an RC, ZARC or Warburg element or one of"),
    (lambda: EquivalentCircuit(("zarc",), tau_bounds=(10.0, 1.0)), fohw.ParameterError,
     "`tau_bounds` must be increasing"),
    (lambda: circuit(("zarc",), alpha9=1.0), fohw.ParameterError, "no parameter 'alpha9'"),
    (lambda: circuit(("zarc",), alpha1=1.5), fohw.ParameterError, "outside its bounds"),
    (lambda: fohw.fit(circuit(("zarc",)), record(200), 3.7 + 0.01 * record(200)[:, 0],
                      start=circuit(("rc",))), fohw.ParameterError,
     "`start` must hold models of the same kind and parameters"),
])
def test_bad_settings_are_named(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_zero_weights_hold_a_block_back():
    u = record(3000, seed=7)
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, a=0.01, b=-0.02, ocv=ocv)
    v = true.simulate(u)
    held = slice(1200, 1800)
    spoiled = v.copy()
    spoiled[held] += 0.05                       # a block the criterion must not see
    w = np.ones(u.shape[0])
    w[held] = 0.0
    fit = fohw.fit(circuit(("zarc",)), u, spoiled, sample_weight=w)
    truth = true.parameters.valuesdict()
    np.testing.assert_allclose([fit.parameters[n].value for n in truth], list(truth.values()),
                               rtol=1e-6, atol=1e-9)
    assert fit.n_samples == 2400 and fit.sse < 1e-18
    np.testing.assert_allclose(fit.residuals[held], 0.05, atol=1e-9)     # y - yhat
    with pytest.raises(fohw.ParameterError, match="`sample_weight` must be non-negative"):
        fohw.fit(circuit(("zarc",)), u, v, sample_weight=-w)


# --- honesty: what the record cannot tell is named, what carries nothing is refused -----------

def test_two_identical_rc_elements_are_rank_deficient_and_named():
    u = record(2000, seed=10)
    v = TRUE.simulate(u) + 1e-3 * np.random.default_rng(11).standard_normal(u.shape[0])
    # Both elements held at one time constant: only R1 + R2 is identified.
    model = circuit(("rc", "rc"), tau1=20.0, tau2=20.0)
    with pytest.warns(fohw.RankDeficiencyWarning, match="R[12]"):
        fit = fohw.fit(model, u, v)
    assert fit.status == fohw.Status.RANK_DEFICIENT and fit.covariance is None
    assert "not identifiable" in fit.message and ("R1" in fit.message or "R2" in fit.message)


def test_a_time_constant_far_beyond_the_record_is_rank_deficient_and_named():
    # tau = 1e16 s on a 500 s record: tau/dt / (1 + tau/dt) rounds to 1, so the element is
    # R dt / tau times the running sum of the current, which is a + b soc + R0 i (the coulomb
    # count): the columns of R1 (and tau1) are combinations of a, b and R0's.
    u = record(500, seed=12)
    model = EquivalentCircuit([RC(0.01, 1e16)], r0=0.015, ocv=ocv, tau_bounds=(1.0, 1e20))
    v = model.simulate(u) + 1e-4 * np.random.default_rng(13).standard_normal(u.shape[0])
    held = model.with_parameters(model.parameters.replace("tau1", fixed=True))
    with pytest.warns(fohw.RankDeficiencyWarning, match="not identifiable"):
        fit = fohw.fit(held, u, v)
    assert fit.status == fohw.Status.RANK_DEFICIENT and fit.covariance is None
    named = fit.message.split("the columns of ")[1].split(" are ")[0].split(", ")
    assert set(named) <= {"a", "b", "R0", "R1"} and named


def test_zero_current_and_constant_voltage_are_refused():
    u = record(300, seed=14)
    v = TRUE.simulate(u)
    zero = u.copy()
    zero[:, 0] = 0.0
    with pytest.raises(fohw.ParameterError, match="current `u\\[:, 0\\]` is zero at every sample"):
        fohw.fit(circuit(("zarc",)), zero, v)
    with pytest.raises(fohw.ParameterError, match="`y` is constant"):
        fohw.fit(circuit(("zarc",)), u, np.full(u.shape[0], 3.7))


def test_a_constant_current_is_refused_unless_the_offset_or_r0_is_held():
    # R0 i is then a constant, the offset a: issue 34 #15 (it was a rank-deficiency warning with
    # the lagged kind's advice, "remove a basis function or a lag"). With a held it is a fit.
    u = record(300, seed=15)
    u[:, 0] = -1.0
    v = TRUE.simulate(u) + 1e-4 * np.random.default_rng(16).standard_normal(u.shape[0])
    with pytest.raises(fohw.ParameterError, match="current `u\\[:, 0\\]` is constant \\(-1.0 A at "
                                                  "all 300 samples\\): R0 i is then a constant"):
        fohw.fit(circuit(()), u, v)
    fit = fohw.fit(circuit((), current_map=True, a=TRUE.a, c3=TRUE.c3), u, v)
    assert fit.converged and fit.parameters["a"].value == TRUE.a


def test_a_current_of_the_other_sign_is_named():
    # A record whose current is given with the other sign: the voltage falls with a "charge".
    # Issue 37: the fit ran and ended with every resistance at 0; the record is now refused
    # before the scan, naming the other convention (tests/test_circuit_conventions.py).
    u = record(2000, seed=17)
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015)
    v = true.simulate(u) + 1e-4 * np.random.default_rng(18).standard_normal(u.shape[0])
    flipped = u * [-1.0, 1.0]
    with pytest.raises(fohw.ParameterError, match="current_sign='discharge_positive'"):
        fohw.fit(EquivalentCircuit(["zarc"], tau_bounds=(1.0, 1000.0)), flipped, v)


@pytest.mark.parametrize("kind, bounds, match", [
    ("zarc", (0.2, 1.5), r"leave the order domain \(0, 1\] of a ZARC"),
    ("warburg", (0.1, 1.0), r"leave the order domain \(0, 1\), below 1 of a Warburg"),
    ("zarc", (0.0, 0.9), r"leave the order domain"),
])
def test_an_order_bound_beyond_the_elements_domain_is_refused(kind, bounds, match):
    model = EquivalentCircuit((kind,), ocv=ocv, tau_bounds=(1.0, 1000.0))
    with pytest.raises(fohw.ParameterError, match=match):
        model.with_parameters(model.parameters.replace("alpha1", bounds=bounds))
    inside = model.with_parameters(model.parameters.replace("alpha1", bounds=(0.3, 0.7)))
    assert inside.parameters["alpha1"].bounds == (0.3, 0.7)
