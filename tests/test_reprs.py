"""Text and notebook (HTML) views of results, validations, selections, tests and models.

The text repr is one short line (never an array dump or ``<... object at 0x...>``); the HTML view
is a table, and for an identification result it holds everything :meth:`summary` prints.
"""

import html
import re

import numpy as np
import pytest

import fohw
from fohw.model.circuit import ZARC, EquivalentCircuit

KW = dict(na=2, nb=2, f_basis=2, g_basis=3)


@pytest.fixture(scope="module")
def fitted():
    data = fohw.datasets.paper_example(400, random_state=0)
    return data, fohw.identify(data.u, data.y, **KW)


def _short(text, limit=300):
    assert "\n" not in text and " object at 0x" not in text and len(text) <= limit, text
    return text


def _html_table(text):
    assert text.startswith("<div") and "<table>" in text and "</table>" in text
    return text


def test_result_html_holds_what_summary_prints(fitted):
    _, res = fitted
    page = html.unescape(re.sub(r"<[^>]+>", " ", res._repr_html_()))
    words = set(page.split())
    summary = res.summary()
    assert "std err" in summary and "95% CI low" in summary
    missing = [w for w in summary.split() if w not in words]
    assert missing == []
    se = res.standard_errors()
    assert f"{se['alpha']:.3g}" in words            # the standard errors are in the table


def test_validation_repr_and_table(fitted):
    data, res = fitted
    v = fohw.compare(res, data.u, data.y)
    text = _short(repr(v))
    assert f"fit {v.fit_simulation:.1f} %" in text and "N=400" in text
    page = _html_table(v._repr_html_())
    assert f"{v.fit_simulation:.1f}" in page and f"{v.rmse_prediction:.4g}" in page
    assert "whiteness" in page


def test_selection_repr_and_table(fitted):
    data, _ = fitted
    sel = fohw.select_structure(data.u, data.y, {"na": [1, 2]}, nb=2, f_basis=2, g_basis=3)
    text = _short(repr(sel))
    assert "2 candidates" in text and repr(sel.best_row["candidate"]) in text
    page = _html_table(sel._repr_html_())
    assert page.count("<tr>") == 1 + len(sel.rows)          # header and one row per candidate
    for row in sel.rows:
        assert f">{row['candidate']}<" in page


def test_tests_intervals_and_bounds(fitted):
    data, res = fitted
    integer = fohw.identify(data.u, data.y, orders=0, **KW)
    t = fohw.lr_test(integer, res)
    assert _short(repr(t)).startswith("LRTest(statistic=")
    assert f"{t.pvalue:.4g}" in _html_table(t._repr_html_())
    pi = fohw.profile_interval(res, "alpha", u=data.u, y=data.y, n_grid=5)
    text = _short(repr(pi))
    assert f"[{pi.low:.4g}, {pi.high:.4g}]" in text and "grid" not in text
    _html_table(pi._repr_html_())
    bound = fohw.crb(fohw.datasets.paper_model(), data.u, 0.01)
    _short(repr(bound))
    page = _html_table(bound._repr_html_())
    assert all(f">{n}<" in page for n in bound.estimate_names)


def test_linear_block_and_models(fitted):
    _, res = fitted
    blk = res.linear_block()
    assert _short(repr(blk)).startswith("LinearBlock(")
    assert "static gain" in _html_table(blk._repr_html_())
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    models = [fohw.datasets.paper_model(), G, fohw.FractionalHW(G, p=[1.0, 0.3]),
              EquivalentCircuit([ZARC(0.01, 50.0, 0.5)], r0=0.015, a=3.7)]
    for m in models:
        _short(repr(m), limit=400)
        _html_table(m._repr_html_())
    assert np.isclose(float(re.search(r">R0<.*?>([-\d.e]+)<", models[3]._repr_html_()).group(1)), 0.015)


def test_fit_result_html_shows_units_intervals_and_the_records():
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    rng = np.random.default_rng(2)
    u = np.repeat(rng.standard_normal(40), 10)
    rec = fohw.Record(u, G.simulate(u) + 0.01 * rng.standard_normal(u.size), dt=0.05,
                      name="step test", input_name="current", input_unit="A",
                      output_name="voltage", output_unit="V", time_unit="s")
    fit = fohw.fit(G.with_parameters({"a0": 1.5, "alpha0": 0.5}), rec)
    page = _html_table(fit._repr_html_())
    text = html.unescape(re.sub(r"<[^>]+>", " ", page))
    words = set(text.split())
    assert [w for w in fit.summary().split() if w not in words] == []    # all the summary says
    assert "current [A]" in text and "voltage [V]" in text                # the units
    assert "records: step test (N = 400, dt = 0.05 s)" in text            # the data line
    assert "95% CI low" in page and "95% CI high" in page
    for name, (low, high) in fit.confidence_intervals().items():         # the Wald intervals
        se = fit.standard_errors()[name]
        value = fit.parameters[name].value
        assert np.isclose(high - value, 1.959963984540054 * se) and np.isclose(value - low, high - value)
        assert f">{low:.6g}<" in page and f">{high:.6g}<" in page
    assert ">fixed<" in page                                              # a1, the normaliser


def test_a_new_kind_reads_as_a_table_of_its_parameters():
    class Scaled(fohw.Model, register=False):
        def __init__(self, k=1.5, c=0.25):
            self.k, self.c = k, c

        @property
        def parameters(self):
            return fohw.Parameters([fohw.Parameter("k", self.k, bounds=(0.0, 10.0)),
                                    fohw.Parameter("c", self.c, fixed=True)])

        def with_parameters(self, values):
            v = self.parameters.with_values(values).valuesdict()
            return Scaled(v["k"], v["c"])

        def simulate(self, u, *, initial=None):
            return self.k * self.check_input(u) + self.c

    m = Scaled()
    page = _html_table(m._repr_html_())
    assert re.search(r">k<.*?>1\.5<.*?>\[0, 10\]<.*?>free<", page)
    assert re.search(r">c<.*?>0\.25<.*?>\[-inf, inf\]<.*?>fixed<", page)
    assert "dt = 1" in page
    lines = m.summary().splitlines()
    assert lines[0] == "Scaled" and lines[-2].split() == ["k", "1.5", "[0,", "10]", "free"]
    assert lines[-1].split() == ["c", "0.25", "[-inf,", "inf]", "fixed"]

