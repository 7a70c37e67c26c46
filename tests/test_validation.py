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
    v = res.validate(u, y, n_init=5)
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
    v = fohw.compare(res, data.u[800:], data.y[800:], history=(data.u[:800], data.y[:800]))
    np.testing.assert_array_equal(v.simulated, res.simulate(data.u[800:],
                                                            history=(data.u[:800], data.y[:800])))


def test_a_diverging_free_run_is_reported_not_raised(fitted):
    data, res = fitted
    with pytest.warns(fohw.ExtrapolationWarning):
        ysim_error = None
        try:
            res.simulate(8 * data.u[800:])
        except fohw.SimulationDivergedError as exc:
            ysim_error = exc
    assert ysim_error is not None          # the y^3 feedback escapes at 8x the input
    v = res.validate(8 * data.u[800:], 8 * data.y[800:])
    assert v.simulated is None and np.isnan(v.fit_simulation)
    assert "diverged at sample" in v.diverged and not v.in_range
    assert "diverged" in v.to_markdown()
    fig, axes = v.plot()
    assert len(axes) == 2


def test_bad_input_names_the_argument(fitted):
    data, res = fitted
    with pytest.raises(fohw.DimensionError, match="`u` and `y` must have the same length"):
        res.validate(data.u[:10], data.y[:11])
    with pytest.raises(fohw.ParameterError, match="`n_init`"):
        res.validate(data.u[:10], data.y[:10], n_init=20)


def test_cli_plot_shows_the_free_run(tmp_path):
    data = fohw.datasets.paper_example(400, random_state=0)
    path = tmp_path / "d.dat"
    np.savetxt(path, np.c_[data.u, data.y])
    png = tmp_path / "fit.png"
    assert main(["identify", str(path), "--na", "2", "--nb", "2", "--f-basis", "2",
                 "--g-basis", "3", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
