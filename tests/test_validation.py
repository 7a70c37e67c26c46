"""fohw.compare / result.validate: free run and one-step prediction on a record."""

import numpy as np
import pytest

import fohw
from fohw.analysis.metrics import fit_percent, rmse, whiteness_test
from fohw.cli import main

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


@pytest.fixture(scope="module")
def fitted():
    data = fohw.datasets.paper_example(1200, random_state=0)
    res = fohw.identify(data.u[:800], data.y[:800], **STRUCT)
    return data, res


def test_numbers_are_the_simulation_and_prediction_they_name(fitted):
    data, res = fitted
    u, y = data.u[800:], data.y[800:]
    v = fohw.compare(res, u, y, n_init=5)
    ysim, yhat = res.simulate(u), res.predict(u, y)
    np.testing.assert_array_equal(v.simulated, ysim)
    np.testing.assert_array_equal(v.predicted, yhat)
    assert v.fit_simulation == fit_percent(y, ysim, n_init=5)
    assert v.rmse_simulation == rmse(y, ysim, n_init=5)
    assert v.fit_prediction == fit_percent(y, yhat, n_init=5)
    assert v.whiteness.p_value == whiteness_test(y - yhat, n_init=5).p_value
    assert v.diverged == "" and v.in_range
    # the noise is white with variance 0.01 and the model is right: the one-step RMSE is
    # close to the noise level 0.1 (400 samples: +-10 % is over 2 standard errors)
    assert 0.09 < v.rmse_prediction < 0.11
    assert "free-run simulation" in v.to_markdown()


def test_history_continues_the_free_run(fitted):
    data, res = fitted
    v = fohw.compare(res, data.u[800:], data.y[800:], initial=(data.u[:800], data.y[:800]))
    np.testing.assert_array_equal(v.simulated, res.simulate(data.u[800:],
                                                            initial=(data.u[:800], data.y[:800])))


def test_a_diverging_free_run_is_reported_not_raised(fitted):
    data, res = fitted
    with pytest.warns(fohw.ExtrapolationWarning):
        ysim_error = None
        try:
            res.simulate(8 * data.u[800:])
        except fohw.SimulationDivergedError as exc:
            ysim_error = exc
    assert ysim_error is not None          # the y^3 feedback escapes at 8x the input
    v = fohw.compare(res, 8 * data.u[800:], 8 * data.y[800:])
    assert v.simulated is None and np.isnan(v.fit_simulation)
    assert "diverged at sample" in v.diverged and not v.in_range
    assert "diverged" in v.to_markdown()
    fig = v.plot()
    assert len(fig.axes) == 2


def test_bad_input_names_the_argument(fitted):
    data, res = fitted
    with pytest.raises(fohw.DimensionError, match="`u` and `y` must have the same length"):
        fohw.compare(res, data.u[:10], data.y[:11])
    with pytest.raises(fohw.ParameterError, match="`n_init`"):
        fohw.compare(res, data.u[:10], data.y[:10], n_init=20)


def test_cli_plot_shows_the_free_run(tmp_path):
    data = fohw.datasets.paper_example(400, random_state=0)
    path = tmp_path / "d.dat"
    np.savetxt(path, np.c_[data.u, data.y])
    png = tmp_path / "fit.png"
    assert main(["identify", str(path), "--na", "2", "--nb", "2", "--f-basis", "2",
                 "--g-basis", "3", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000


# issue 28 (28b) -------------------------------------------------------------------------------
def test_compare_takes_a_model_not_only_a_result():
    # The paper's record is y = Phi(alpha) theta + v (equation noise): the true model's one-step
    # prediction error is the noise itself, and its free run is fohw.simulate's.
    data = fohw.datasets.paper_example(600, random_state=2)
    v = fohw.compare(data.model, data.u, data.y)
    np.testing.assert_array_equal(v.simulated, fohw.simulate(data.model, data.u))
    np.testing.assert_allclose(data.y - v.predicted, data.noise, atol=1e-12)
    assert v.status == "ok" and v.in_range and np.isfinite(v.fit_simulation)
    with pytest.raises(fohw.ParameterError, match="`model` must be an identification result"):
        fohw.compare(data.model.structure, data.u, data.y)


def test_constant_input_still_gives_the_fit(fitted):
    # The cross-correlation with a constant input is undefined: skipped with a note, and the
    # fit % of both predictions is still there (they are the ones of a direct computation).
    data, res = fitted
    u = np.full(400, 0.3)
    v = fohw.compare(res, u, data.y[800:])
    assert v.fit_simulation == fit_percent(data.y[800:], res.simulate(u))
    assert v.fit_prediction == fit_percent(data.y[800:], res.predict(u, data.y[800:]))
    assert v.cross_correlation is None and v.whiteness is not None
    assert any("`u` is constant" in n for n in v.notes)
    assert "Note: input cross-correlation test skipped" in v.to_markdown()


def test_one_sample_names_the_record_length(fitted):
    _, res = fitted
    with pytest.raises(fohw.DimensionError, match="the record has 1 sample"):
        fohw.compare(res, [0.1], [0.2])


def test_a_free_run_outside_the_envelope_is_implausible_not_scored():
    # A stable linear model (y[k] = 0.5 y[k-1] + u[k-1]) simulated from a unit input reaches
    # about 2; a "measured" output spanning [0, 0.01] puts the envelope (factor 10) at
    # [-0.1, 0.11]: the first sample above 0.11 is flagged with its index and value.
    model = fohw.HammersteinWiener([-0.5], [1.0], [1.0], [1.0], orders=0)
    u = np.ones(50)
    ysim = fohw.simulate(model, u)
    y = np.linspace(0.0, 0.01, 50)
    k = int(np.argmax(ysim > 0.11))
    assert k > 0
    v = fohw.compare(model, u, y)
    assert v.status == "implausible" and v.simulated is None
    assert np.isnan(v.fit_simulation) and np.isnan(v.rmse_simulation)
    assert f"sample k = {k}: y[k] = {ysim[k]:.6g}" in v.diverged
    assert "implausible" in v.to_markdown()
    # a wider envelope (or none) scores it
    assert fohw.compare(model, u, y, envelope=None).status == "ok"
    assert fohw.compare(model, u, y, envelope=1e3).status == "ok"
    with pytest.raises(fohw.ParameterError, match="`envelope`"):
        fohw.compare(model, u, y, envelope=-1.0)


def test_a_hammerstein_wiener_is_predicted_by_the_one_copy_of_eq19(monkeypatch):
    # compare of a fohw.HammersteinWiener takes its one-step prediction from ThetaHW.predict
    # (the copy an identification result uses too), not from a copy of its own; the numbers are
    # Eq. (19) by hand: y = 0.5 y[k-1] + u[k-1] about the operating point (u0, y0) = (0.3, 2).
    model = fohw.HammersteinWiener([0.5], [1.0], [1.0], [1.0], orders=0, operating_point=(0.3, 2.0))
    rng = np.random.default_rng(1)
    u = 0.3 + rng.uniform(-1, 1, 200)
    y = model.simulate(u) + 0.01 * rng.standard_normal(200)
    calls = []
    original = fohw.ThetaHW.predict

    def spy(self, u, y):
        calls.append(type(self).__name__)
        return original(self, u, y)

    monkeypatch.setattr(fohw.ThetaHW, "predict", spy)
    v = fohw.compare(model, u, y)
    assert calls == ["ThetaHW"]
    by_hand = 2.0 + 0.5 * (np.r_[np.nan, y[:-1]] - 2.0) + (np.r_[np.nan, u[:-1]] - 0.3)
    by_hand[0] = 2.0                  # zero initial conditions: phi[0] = 0, yhat[0] = y0
    np.testing.assert_allclose(v.predicted, by_hand, rtol=1e-14, atol=1e-14)
    assert v.rmse_prediction == pytest.approx(rmse(y, by_hand), rel=1e-13)
