"""Fitting equivalent circuits: recovery, the scan, the nested integer limit, the checks."""

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
from fohw.estimators.circuit_fit import circuit_template, fit_circuit
from fohw.model.circuit import RC, ZARC, EquivalentCircuit


def record(n=3000, seed=0, hold=20):
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-3, 1.2, n // hold + 1), hold)[:n]
    soc = 0.8 + np.concatenate([[0.0], np.cumsum(i[:-1])]) / (3600 * 5.0)
    return i, soc


def ocv(soc):
    return 3.3 + 0.9 * soc - 0.3 * (soc - 0.5) ** 2


TRUE = EquivalentCircuit([RC(0.004, 6.0), ZARC(0.012, 150.0, 0.55)], r0=0.015, a=0.01, b=-0.02,
                         c3=-1e-4, ocv=ocv)


def test_noise_free_record_is_recovered_exactly():
    i, soc = record()
    v = TRUE.simulate(i, soc, 1.0)
    fit = fit_circuit(i, v, soc, 1.0, ("rc", "zarc"), current_map=True, ocv=ocv,
                      tau_bounds=(1.0, 1000.0))
    np.testing.assert_allclose(fit.circuit.values, TRUE.values, rtol=1e-6, atol=1e-9)
    assert fit.converged and fit.rmse < 1e-9 and fit.at_bound == ()
    assert fit.n_params == 9 and fit.names == TRUE.names     # a, b, R0, c3, R1, tau1, R2, tau2, alpha2


def test_noisy_record_within_standard_errors_and_gradient_zero():
    i, soc = record(4000, seed=1)
    noise = 1e-3 * np.random.default_rng(2).standard_normal(i.size)
    v = TRUE.simulate(i, soc, 1.0) + noise
    fit = fit_circuit(i, v, soc, 1.0, ("rc", "zarc"), current_map=True, ocv=ocv,
                      tau_bounds=(1.0, 1000.0))
    z = [(fit.params[nm] - x) / fit.stderr[nm] for nm, x in zip(TRUE.names, TRUE.values)]
    # 9 z-scores, each ~N(0, 1) for an efficient fit: 99.9 % familywise (Bonferroni) bound.
    hi = scipy.stats.norm.isf(0.0005 / len(z))
    assert np.max(np.abs(z)) < hi, dict(zip(TRUE.names, np.round(z, 2)))
    # The residual RMS of N samples of 1e-3 noise (less d fitted): relative spread
    # 1 / sqrt(2 N); 3.3 of those is 99.9 %.
    assert fit.rmse == pytest.approx(1e-3, rel=3.3 / np.sqrt(2 * i.size))
    # First-order optimality with the exact Jacobian: J^T r = 0 relative to |J| |r|.
    _, jac = fit.circuit.jacobian(i, soc, 1.0)
    g = jac.T @ fit.residuals
    assert np.all(np.abs(g) <= 1e-5 * np.linalg.norm(jac, axis=0) * np.linalg.norm(fit.residuals))
    # The same minimum as a finite-difference least_squares from the fit.
    def resid(p):
        return TRUE.with_values(p).simulate(i, soc, 1.0) - v
    fd = scipy.optimize.least_squares(resid, fit.circuit.values, x_scale="jac", method="lm")
    assert 2 * fd.cost >= fit.rss * (1 - 1e-9)


def test_zarc_at_order_one_is_the_rc_fit():
    i, soc = record(2000, seed=3)
    v = TRUE.simulate(i, soc, 1.0) + 1e-3 * np.random.default_rng(4).standard_normal(i.size)
    rc = fit_circuit(i, v, soc, 1.0, ("rc",), ocv=ocv, tau_bounds=(1.0, 1000.0))
    at_one = fit_circuit(i, v, soc, 1.0, ("zarc",), ocv=ocv, tau_bounds=(1.0, 1000.0),
                         fixed={"alpha1": 1.0})
    assert at_one.rss == pytest.approx(rc.rss, rel=1e-8)
    full = fit_circuit(i, v, soc, 1.0, ("zarc",), ocv=ocv, tau_bounds=(1.0, 1000.0))
    test = circuit_lr_test(rc, full)
    assert test.statistic == pytest.approx(i.size * math.log(rc.rss / full.rss))
    assert test.df == 1 and "0.5*chi2_0" in test.distribution
    # The mixture's p-value is half the chi2_1 tail.
    assert test.pvalue == pytest.approx(0.5 * scipy.stats.chi2.sf(test.statistic, 1))
    assert test.pvalue == pytest.approx(circuit_lr_test(at_one, full).pvalue, rel=1e-9)


def test_profile_interval_covers_the_true_order_and_matches_the_statistic():
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, ocv=ocv)
    i, soc = record(3000, seed=5)
    v = true.simulate(i, soc, 1.0) + 1e-3 * np.random.default_rng(6).standard_normal(i.size)
    fit = fit_circuit(i, v, soc, 1.0, ("zarc",), ocv=ocv, tau_bounds=(1.0, 1000.0))
    pi = circuit_order_interval(fit, i, v, soc, "alpha1", n_grid=5)
    assert pi.low < 0.5 < pi.high and pi.one_sided == ""
    # At each end the refit's statistic is the chi2_1 quantile, 3.84.
    for end in (pi.low, pi.high):
        r = fit_circuit(i, v, soc, 1.0, ("zarc",), ocv=ocv, tau_bounds=(1.0, 1000.0),
                        fixed={"alpha1": end}, start=fit.circuit)
        assert i.size * math.log(r.rss / fit.rss) == pytest.approx(3.841, abs=0.05)
    # The width agrees with the standard error (a quadratic profile): 1.96 se each side.
    assert (pi.high - pi.low) / 2 == pytest.approx(1.96 * fit.stderr["alpha1"], rel=0.15)


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


@pytest.mark.parametrize("kwargs, match", [
    (dict(elements=("rc", "cpe")), "`elements\\[1\\]` must be one of"),
    (dict(tau_bounds=(10.0, 1.0)), "`tau_bounds` must be finite, increasing"),
    (dict(alpha_bounds=(0.2, 1.5)), "`alpha_bounds`"),
    (dict(fixed={"alpha9": 1.0}), "`fixed` names 'alpha9'"),
    (dict(fixed={"alpha1": 1.5}), "outside its bounds"),
    (dict(warburg_alpha_bounds=(0.1, 1.0)), "must stay below 1"),
    (dict(start=circuit_template(("rc",))), "`start` must be an EquivalentCircuit of the same"),
])
def test_fit_bad_settings_are_named(kwargs, match):
    i, soc = record(200)
    kwargs = {"elements": ("zarc",), **kwargs}
    with pytest.raises(fohw.ParameterError, match=match):
        fit_circuit(i, 3.7 + 0.01 * i, soc, 1.0, **kwargs)


def test_zero_weights_hold_a_block_back():
    i, soc = record(3000, seed=7)
    true = EquivalentCircuit([ZARC(0.012, 60.0, 0.5)], r0=0.015, a=0.01, b=-0.02, ocv=ocv)
    v = true.simulate(i, soc, 1.0)
    held = slice(1200, 1800)
    spoiled = v.copy()
    spoiled[held] += 0.05                       # a block the criterion must not see
    w = np.ones(i.size)
    w[held] = 0.0
    fit = fit_circuit(i, spoiled, soc, 1.0, ("zarc",), ocv=ocv, tau_bounds=(1.0, 1000.0),
                      sample_weight=w)
    np.testing.assert_allclose(fit.circuit.values, true.values, rtol=1e-6, atol=1e-9)
    assert fit.n == 2400 and fit.rss < 1e-18
    np.testing.assert_allclose(fit.residuals[held], -0.05, atol=1e-9)
    with pytest.raises(fohw.ParameterError, match="`sample_weight` must be non-negative"):
        fit_circuit(i, v, soc, 1.0, ("zarc",), sample_weight=-w)
