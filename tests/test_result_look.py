"""Issue 42, item 4: every kind's result reads alike in a notebook (status, the data line with
units, estimates with standard errors and 95 % intervals), and a comparison of a kind without a
one-step predictor shows no NaN row."""

import re

import numpy as np
import pytest

import fohw

RNG = np.random.default_rng(3)


def _text(html):
    return re.sub(r"\s+", " ", re.sub("<[^>]+>", " ", html))


def _tf():
    g = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)
    u = RNG.standard_normal(300)
    y = g.simulate(u) + 0.01 * RNG.standard_normal(300)
    rec = fohw.Record(u=u, y=y, dt=0.1, time_unit="s", input_unit="V", output_unit="m")
    return fohw.fit(g, rec, order_grid=2, n_starts=1), rec


def _circuit():
    ocv = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
    truth = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.6)], r0=0.015, dt=1.0, ocv=ocv)
    i = np.repeat(RNG.uniform(-3.0, 1.0, 20), 20)
    u = np.column_stack([i, 0.8 + np.cumsum(i) / 18000])
    v = truth.simulate(u) + 1e-4 * RNG.standard_normal(i.size)
    rec = fohw.Record(u=u, y=v, dt=1.0, time_unit="s", input_name=("i", "soc"),
                      input_unit=("A", "1"), output_name="v", output_unit="V")
    start = fohw.EquivalentCircuit(("zarc",), dt=1.0, ocv=ocv, tau_bounds=(1.0, 500.0))
    return fohw.fit(start, rec, order_grid=2, n_starts=1), rec


def _lagged():
    d = fohw.datasets.paper_example(300, random_state=0)
    rec = fohw.Record(u=d.u, y=d.y, dt=1.0, time_unit="s", input_unit="V", output_unit="m")
    return fohw.identify(rec, na=1, nb=1, f_basis=1, g_basis=1), rec


@pytest.mark.parametrize("make, output_error", [(_tf, True), (_circuit, True), (_lagged, False)],
                         ids=["FractionalTF", "circuit", "lagged"])
def test_every_kind_shows_the_same_fields(make, output_error):
    res, rec = make()
    text = _text(res._repr_html_())
    assert "status = CONVERGED" in text
    units = f"output {rec.output_name} [{rec.output_unit}], dt = {rec.dt:g} s"
    assert "data: 1 record(s); input " in text and units in text
    assert "std err 95% CI low 95% CI high" in text
    for name in (res.free_names if hasattr(res, "free_names") else res.parameter_names):
        assert f" {name} " in text
    check = fohw.compare(res, rec)
    view = _text(check._repr_html_()) + check.to_markdown() + repr(check)
    assert "nan" not in view.lower() and "bound method" not in view
    if output_error:                    # a kind without a one-step predictor: no such row at all
        assert "one-step prediction |" not in check.to_markdown()
        assert "Free-run residual whiteness" in view
