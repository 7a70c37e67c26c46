"""The initial state of a record (issue 24, item 4): ``initial=`` on result.simulate and compare."""

import warnings

import numpy as np
import pytest

import fohw
from fohw.cli import main as cli


def _result(structure, linear, orders, n, **kw):
    """A result holding given parameters (the model known exactly: only the state is in doubt)."""
    return fohw.IdentificationResult(method="varpro", structure=structure, theta=linear,
                                     orders=orders, J=0.0, status=1, nit=0, nfev=0, message="",
                                     n_samples=n, **kw)


def _paper_result(n=1000):
    m = fohw.datasets.paper_model()
    return m, _result(m.structure, m.theta, dict(m.orders), n)


@pytest.fixture(scope="module")
def cut_record():
    """The paper's plant, simulated from rest over a long record, cut in the middle.

    The input varies, then holds 0.9 for 3000 samples before the cut, so the second piece (the
    "validation record") starts from a level that it does not show. The memory of the earlier
    variation still decays as t**-0.6 there (GL partial sums of order 0.6): constant levels
    are an approximation of this past, not the past itself.
    """
    m, res = _paper_result()
    rng = np.random.default_rng(1)
    k, n = 4000, 5000
    u = 0.6 + 0.4 * rng.uniform(-1, 1, n // 25).repeat(25)
    u[k - 3000:k] = 0.9
    y0 = fohw.simulate(m, u)
    sigma = 0.01 * np.ptp(y0[k:])
    y = y0 + sigma * np.random.default_rng(0).standard_normal(n)
    return res, u, y, k, sigma


def test_estimate_recovers_what_the_measured_history_gives(cut_record):
    """Must show: initial='estimate' does what the correct history does, within noise.

    The model is exact, so every free run's error is the output noise (sigma) plus the error
    of its initial state. The RMSE of 1000 samples of pure noise has a relative spread of
    1/sqrt(2 * 1000) = 2.2 %, so 1.1 sigma is 4.5 spreads above it: a run within 1.1 sigma
    has a state error below sqrt(1.1**2 - 1) = 0.46 sigma RMS, i.e. within the noise. From
    rest the state error is several sigma.
    """
    res, u, y, k, sigma = cut_record
    uv, yv = u[k:], y[k:]
    history = fohw.compare(res, uv, yv, initial=(u[:k], y[:k]))
    estimate = fohw.compare(res, uv, yv, initial="estimate")
    window = fohw.compare(res, uv, yv, initial=("estimate", 3))
    rest = fohw.compare(res, uv, yv, initial="rest")
    assert history.rmse < 1.1 * sigma
    assert estimate.rmse < 1.1 * sigma
    assert window.rmse <= estimate.rmse * (1 + 1e-9)       # nested: starts from the levels
    assert rest.rmse > 3 * sigma
    assert rest.fit < history.fit - 20 and estimate.fit > history.fit - 1.5
    assert estimate.initial.kind == "estimate" and estimate.initial.n_estimated == 2
    assert window.initial.n_estimated == 5 and window.initial.window.shape == (3,)
    assert history.initial.n_estimated == rest.initial.n_estimated == 0
    # the input level before the cut, 0.9, within the approximation of the past by levels
    assert estimate.initial.levels[0] == pytest.approx(0.9, abs=0.05)


CASES = {
    # input and output terms of the same lags and order: the levels are identified only
    # because the two lags mix them differently (det [[b1, a1], [b2, a2]] != 0)
    "linear commensurate": (dict(na=2, nb=2, f_basis=1, g_basis=1, orders="commensurate"),
                            [0.3, -0.2, 1.0, 0.5], {"alpha": 0.5}, (0.3, -0.8)),
    # the paper's model (f = u + 0.5 u^2 and g = y + 0.7 y^2 + 0.35 y^3, both monotone where
    # the levels lie), with levels
    "paper": (dict(na=2, nb=2, f_basis=2, g_basis=3),
              fohw.datasets.paper_model().theta, {"alpha": 0.6}, (0.4, -0.3)),
    "mixed orders, offset": (dict(na=1, nb=2, f_basis=1, g_basis=2, orders="mixed",
                                  offset=True),
                             None, {"alpha": 0.7}, (-0.5, 0.6)),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_estimate_is_exact_on_noise_free_data_from_levels(case):
    """Noise-free data of a structure with past levels: 'estimate' recovers the levels."""
    kw, theta, orders, levels = CASES[case]
    s = fohw.Structure.make(**kw)
    if theta is None:                     # a (1 x 2) mixed model: theta of its own layout
        theta = np.r_[0.4, -0.2, 0.1, 0.05, 0.9, 0.3, 0.5, -0.2, 0.2]
        theta = theta[:s.n_linear]
    linear = np.asarray(theta, dtype=float)
    u = np.random.default_rng(3).uniform(-1, 1, 400)
    y = fohw.simulate(fohw.Structure.make(past="estimate", **kw), u,
                      params=np.r_[linear, list(orders.values()), levels])
    res = _result(s, linear[:s.layout.n_params], orders, u.size,
                  offset=linear[s.layout.n_params] if s.offset else 0.0)
    state = res.initial_state(u, y, "estimate")
    np.testing.assert_allclose(state.past, levels, atol=1e-6)
    assert "identified" not in state.message                 # full rank: a unique state
    np.testing.assert_allclose(res.simulate(u, initial=state), y, atol=1e-8 * np.ptp(y))
    window = res.initial_state(u, y, ("estimate", 2))
    np.testing.assert_allclose(window.past[0], levels[0], atol=1e-5)
    np.testing.assert_allclose(res.simulate(u, initial=window), y, atol=1e-7 * np.ptp(y))


def test_an_unidentified_combination_of_levels_is_said():
    """One lag, one order: the levels enter through b1 fbar(u_past) + a1 gbar(y_past) only."""
    kw = dict(na=1, nb=1, f_basis=1, g_basis=1, orders="commensurate")
    u = np.random.default_rng(0).uniform(-1, 1, 200)
    y = fohw.simulate(fohw.Structure.make(past="estimate", **kw), u,
                      params=[-0.5, 1.0, 0.5, 0.3, -0.8])
    res = _result(fohw.Structure.make(**kw), [-0.5, 1.0], {"alpha": 0.5}, 200)
    state = res.initial_state(u, y, "estimate")
    assert "only 1 of the 2 values are identified" in state.message
    np.testing.assert_allclose(res.simulate(u, initial=state), y, atol=1e-8)   # same free run
    assert 1.0 * state.past[0] - 0.5 * state.past[1] == pytest.approx(0.3 + 0.4, abs=1e-7)


def test_rest_and_fitted_keep_todays_numbers():
    """'rest' (and 'fitted', and no initial) of a past='rest' fit: today's simulator, bit for
    bit; 'fitted' of a past='estimate' fit: the structure simulated with its levels."""
    d = fohw.datasets.paper_example(400, random_state=0)
    res = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3)
    today = fohw.simulate(res.structure, d.u, params=np.r_[res.linear, res.nonlinear])
    for initial in (None, "rest", "fitted"):
        np.testing.assert_array_equal(res.simulate(d.u, initial=initial), today)
    np.testing.assert_array_equal(fohw.compare(res, d.u, d.y).simulated, today)
    est = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3, past="estimate")
    today = fohw.simulate(est.structure, d.u, params=np.r_[est.linear, est.nonlinear])
    np.testing.assert_array_equal(est.simulate(d.u, initial="fitted"), today)
    rest = fohw.simulate(res.structure, d.u,
                         params=np.r_[est.linear, est.nonlinear[:-2]])    # levels (0, 0)
    np.testing.assert_array_equal(est.simulate(d.u, initial="rest"), rest)


def test_a_past_estimate_fit_asks_which_state():
    d = fohw.datasets.paper_example(300, random_state=0)
    est = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3, past="estimate")
    for call in (lambda: est.simulate(d.u), lambda: fohw.compare(est, d.u, d.y),
                 lambda: fohw.simulate(est, d.u), lambda: fohw.compare(est, d.u, d.y)):
        with pytest.raises(fohw.ParameterError, match="initial='fitted'.*initial='rest'"):
            call()
    np.testing.assert_array_equal(fohw.simulate(est, d.u, initial="fitted"),
                                  est.simulate(d.u, initial="fitted"))
    with pytest.raises(fohw.ParameterError, match="belong to an identification result"):
        fohw.simulate(est.model, d.u, initial="rest")
    # a measured history is an explicit choice, the same through fohw.simulate
    hist = est.simulate(d.u[200:], initial=(d.u[:200], d.y[:200]))
    np.testing.assert_array_equal(hist, fohw.simulate(est, d.u[200:],
                                                      initial=(d.u[:200], d.y[:200])))
    assert not np.array_equal(hist, est.simulate(d.u[200:], initial="fitted"))


def test_the_state_compare_used_reproduces_its_free_run(cut_record):
    res, u, y, k, _ = cut_record
    check = fohw.compare(res, u[k:], y[k:], initial=("estimate", 2))
    np.testing.assert_array_equal(res.simulate(u[k:], initial=check.initial), check.simulated)
    assert check.fit == check.fit_simulation and check.rmse == check.rmse_simulation
    assert "initial state fitted to this record's output (4 values)" in check.to_markdown()
    assert "initial state" not in fohw.compare(res, u[k:], y[k:]).to_markdown()


def test_a_model_keeps_its_own_levels_unless_asked():
    m = fohw.HammersteinWiener([0.3, 0.2], [1.0, 0.5], [1.0], [1.0], 0.5, orders="mixed",
                               past=(0.6, -0.4))
    u = np.random.default_rng(0).uniform(-1, 1, 300)
    y = fohw.simulate(m, u)
    np.testing.assert_array_equal(fohw.compare(m, u, y).simulated, y)
    np.testing.assert_array_equal(fohw.compare(m, u, y, initial="fitted").simulated, y)
    at_rest = fohw.HammersteinWiener([0.3, 0.2], [1.0, 0.5], [1.0], [1.0], 0.5, orders="mixed")
    np.testing.assert_array_equal(fohw.compare(m, u, y, initial="rest").simulated,
                                  fohw.simulate(at_rest, u))
    found = fohw.compare(at_rest, u, y, initial="estimate")
    np.testing.assert_allclose(found.initial.past, (0.6, -0.4), atol=1e-6)


def test_selection_scores_a_separate_record_from_rest_and_held_back_data_as_fitted():
    """The held-back part continues the estimation part (sample 0 is the fit's own start, so
    its levels apply); a separate record starts at rest for every candidate."""
    d = fohw.datasets.paper_example(700, random_state=2)
    kw = dict(na=2, nb=2, f_basis=2, g_basis=3, past="estimate")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.ExtrapolationWarning)
        sel = fohw.select_structure(d.u[:500], d.y[:500], [kw], validation=(d.u[500:],
                                                                             d.y[500:]))
        res = sel.results[0]
        assert sel.rows[0]["fit"] == fohw.compare(res, d.u[500:], d.y[500:],
                                                  initial="rest").fit
        held = fohw.select_structure(d.u, d.y, [kw], validation=200, refit=False)
        res = held.results[0]
        ysim = res.simulate(d.u, initial="fitted")
    assert held.rows[0]["fit"] == fohw.analysis.metrics.fit_percent(d.y[500:], ysim[500:])


def simulated(text):
    """The output column of ``fohw simulate`` (CSV: comments, a header, the time if any, y)."""
    import io

    from fohw.io.text import read_table

    return read_table(io.StringIO(text)).data[:, -1]


def test_cli_simulate_takes_the_initial_state(tmp_path, capsys):
    d = fohw.datasets.paper_example(200, random_state=0)
    est = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3, past="estimate")
    fohw.save_result(est, tmp_path / "r.json")
    np.savetxt(tmp_path / "u.txt", d.u)
    for initial in ("fitted", "rest"):
        assert cli(["simulate", "--model", str(tmp_path / "r.json"), "--input",
                    str(tmp_path / "u.txt"), "--initial", initial, "-q"]) == 0
        y = simulated(capsys.readouterr().out)
        np.testing.assert_array_equal(y, est.simulate(d.u, initial=initial))
    fohw.save_model(est.model, tmp_path / "m.json")
    assert cli(["simulate", "--model", str(tmp_path / "m.json"), "--input",
                str(tmp_path / "u.txt"), "--initial", "rest", "-q"]) == 0
    y = simulated(capsys.readouterr().out)
    assert est.model.past != (0.0, 0.0)         # the levels exist, so "rest" is a choice
    np.testing.assert_allclose(y, fohw.compare(est.model, d.u, d.y, initial="rest").simulated)


def test_initial_states_of_a_fit_with_a_series_output_map():
    # The levels and the map's parameters both sit in `nonlinear` (levels, then h_*): the
    # initial-state code once dropped h's and every simulate of a past="estimate" fit with a
    # map, and every initial="estimate" of a fit with a map, raised a DimensionError.
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, 400)
    s = fohw.Structure.make(na=1, nb=2, f_basis=1, g_basis=1, orders="commensurate",
                            past="estimate", nk=0, output_map="saturation")
    params = [0.4, 1.0, 0.5, 0.5, 0.2, -0.3, -0.6, 0.8]     # a, b0, b1, alpha, levels, h
    y = fohw.simulate(s, u, params=params)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = fohw.identify(u, y, na=1, nb=2, nk=0, f_basis=1, g_basis=1, past="estimate",
                          method="output_error", output_map="saturation")
    fitted = r.simulate(u, initial="fitted")
    np.testing.assert_allclose(fitted, fohw.simulate(r.structure, u,
                                                     params=np.r_[r.linear, r.nonlinear]),
                               atol=1e-12)
    # Noise-free data from a model in the class: the fit and the state estimate recover it to
    # the solvers' tolerances (1e-8 relative, as the exactness tests above; measured ~1e-16).
    assert np.sqrt(np.mean((fitted - y) ** 2)) < 1e-8 * np.std(y)
    st = r.initial_state(u, fitted, "estimate")              # noise-free: its own levels back
    np.testing.assert_allclose(st.past, r.nonlinear[1:3], atol=1e-6)
    assert fohw.compare(r, u, y, initial="estimate").rmse < 1e-8 * np.std(y)
    with pytest.raises(fohw.ParameterError, match="result.simulate"):
        fohw.simulate(r, u, initial="estimate")
