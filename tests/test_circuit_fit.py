"""Fitting equivalent circuits with fohw.fit: recovery, the scan, the nested integer limit, the checks."""

import math

import numpy as np
import pytest
import scipy.optimize
import scipy.stats

import fohw
from fohw.analysis.circuit_checks import (
    circuit_lr_test,
    circuit_order_interval,
    effective_samples,
    impedance_error,
)
from fohw.model.circuit import RC, ZARC, EquivalentCircuit


def record(n=3000, seed=0, hold=20):
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-3, 1.2, n // hold + 1), hold)[:n]
    soc = 0.8 + np.concatenate([[0.0], np.cumsum(i[:-1])]) / (3600 * 5.0)
    return np.column_stack([i, soc])


def ocv(soc):
    return 3.3 + 0.9 * soc - 0.3 * (soc - 0.5) ** 2


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
    return [n for n in fit.free_names if fit.parameters[n].value in fit.parameters[n].bounds]


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
    test = circuit_lr_test(rc, full)
    assert test.statistic == pytest.approx(u.shape[0] * math.log(rc.sse / full.sse))
    assert test.df == 1 and "0.5*chi2_0" in test.distribution
    # The mixture's p-value is half the chi2_1 tail.
    assert test.pvalue == pytest.approx(0.5 * scipy.stats.chi2.sf(test.statistic, 1))
    assert test.pvalue == pytest.approx(circuit_lr_test(at_one, full).pvalue, rel=1e-9)


def test_profile_interval_covers_the_true_order_and_matches_the_statistic():
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, ocv=ocv)
    u = record(3000, seed=5)
    v = true.simulate(u) + 1e-3 * np.random.default_rng(6).standard_normal(u.shape[0])
    fit = fohw.fit(circuit(("zarc",)), u, v)
    pi = circuit_order_interval(fit, u, v, "alpha1", n_grid=5)
    assert pi.low < 0.5 < pi.high and pi.one_sided == ""
    # At each end the refit's statistic is the chi2_1 quantile, 3.84.
    for end in (pi.low, pi.high):
        r = fohw.fit(circuit(("zarc",), alpha1=end), u, v, start=fit.model)
        assert u.shape[0] * math.log(r.sse / fit.sse) == pytest.approx(3.841, abs=0.05)
    # The width agrees with the standard error (a quadratic profile): 1.96 se each side.
    assert (pi.high - pi.low) / 2 == pytest.approx(1.96 * fit.standard_errors()["alpha1"], rel=0.15)


def test_profile_interval_scans_the_fits_own_order_bounds():
    # Declared once: a Warburg order bounded to [0.3, 0.7] is profiled over [0.3, 0.7] (the
    # former fitter scanned 0.05 to 0.95 and refitted under its default bounds).
    u = record(1500, seed=8)
    true = EquivalentCircuit([fohw.Warburg(0.002, 0.5)], r0=0.015, ocv=ocv)
    v = true.simulate(u) + 1e-3 * np.random.default_rng(9).standard_normal(u.shape[0])
    model = EquivalentCircuit(["warburg"], ocv=ocv)
    model = model.with_parameters(model.parameters.replace("alpha1", bounds=(0.3, 0.7)))
    fit = fohw.fit(model, u, v)
    pi = circuit_order_interval(fit, u, v, "alpha1", n_grid=3)
    assert pi.grid.min() >= 0.3 and pi.grid.max() <= 0.7 and 0.3 in pi.grid and 0.7 in pi.grid


def test_effective_samples_of_white_and_of_an_ar1():
    rng = np.random.default_rng(0)
    e = rng.standard_normal(50_000)
    assert effective_samples(e) == pytest.approx(50_000, rel=0.05)
    x = np.zeros_like(e)
    for k in range(1, e.size):
        x[k] = 0.8 * x[k - 1] + e[k]
    # AR(1): n (1 - rho) / (1 + rho) = n / 9.
    assert effective_samples(x) == pytest.approx(50_000 / 9, rel=0.15)


def test_impedance_error_against_its_own_spectrum_is_zero():
    f = np.logspace(-3, 0, 12)
    z = TRUE.impedance(f)
    kept, model, rel = impedance_error(TRUE, f, z, band=(1e-3, 0.5))
    assert kept.max() <= 0.5 and np.all(rel < 1e-15)
    assert np.array_equal(model, z[: kept.size])


@pytest.mark.parametrize("make, error, match", [
    (lambda: EquivalentCircuit(("rc", "cpe")), fohw.ParameterError,
     "`elements\\[1\\]` must be an RC, ZARC or Warburg element or one of"),
    (lambda: EquivalentCircuit(("zarc",), tau_bounds=(10.0, 1.0)), fohw.ParameterError,
     "`tau_bounds` must be increasing"),
    (lambda: circuit(("zarc",), alpha9=1.0), KeyError, "no parameter 'alpha9'"),
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


def test_a_constant_current_leaves_r0_and_the_offset_unidentified():
    u = record(300, seed=15)
    u[:, 0] = -1.0
    v = TRUE.simulate(u) + 1e-4 * np.random.default_rng(16).standard_normal(u.shape[0])
    with pytest.warns(fohw.RankDeficiencyWarning):
        fit = fohw.fit(circuit(()), u, v)
    assert fit.status == fohw.Status.RANK_DEFICIENT
    assert "a" in fit.message.split("columns of")[1] or "R0" in fit.message


def test_a_current_of_the_other_sign_is_named():
    # A discharge record whose current is given with the other sign: the voltage rises with a
    # "discharge"; the best non-negative resistances are all 0, and the fit says why.
    u = record(2000, seed=17)
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015)
    v = true.simulate(u) + 1e-4 * np.random.default_rng(18).standard_normal(u.shape[0])
    flipped = u * [-1.0, 1.0]
    with pytest.warns((fohw.ConvergenceWarning, fohw.RankDeficiencyWarning)):
        fit = fohw.fit(EquivalentCircuit(["zarc"], tau_bounds=(1.0, 1000.0)), flipped, v)
    assert fit.status in (fohw.Status.FAILED, fohw.Status.RANK_DEFICIENT)
    assert "Every resistance of the fitted circuit is 0" in fit.message
    assert "sign convention" in fit.message
