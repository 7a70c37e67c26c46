"""Every verb takes a Record (issue 35): the same numbers as from arrays, names and units on show.

The matrix: for every model kind (``KINDS`` of the protocol tests, the lagged kind among them)
and for the lagged kind's own ``identify``, each verb is run on arrays ``(u, y)``, on a
:class:`fohw.Record` of them and on a Record built from a pandas DataFrame with
:meth:`fohw.Record.from_dataframe`; the three must give the same numbers to the bit (the same
samples reach the same computation: any difference is a conversion that changed them). Before
issue 35 every Record column of the matrix raised (``identify(rec)``: missing ``y``;
``compare(res, rec)``, ``res.simulate(rec)``: type errors).

Then the regression of ``select_structure`` (a Record sampled every 4 s refitted its winner at
``dt = 1``), the record's names and units in ``summary()`` and on the figures' axes, and the
joint Cramér–Rao bound of several records, whose information is the sum of the records'
(independent experiments: the log-likelihoods add).
"""

import importlib
import math
import warnings

import matplotlib
import numpy as np
import pytest

import fohw
from fohw.cli import main
from fohw.estimators.fit import free_jacobian

matplotlib.use("Agg")

# The protocol tests' kinds, from the module pytest already loaded (``--import-mode=importlib``
# names it ``tests.test_model_protocol``; a second copy would register its kind twice).
_protocol = importlib.import_module("tests.test_model_protocol")
KINDS, _case, _lagged, _with = _protocol.KINDS, _protocol._case, _protocol._lagged, _protocol._with

FORMS = ("arrays", "record", "dataframe")


def _forms(u, y, dt, form):
    """The data in ``form``: ``(u, y)``, a Record, or a Record from a DataFrame's columns."""
    m = 1 if np.ndim(u) == 1 else np.shape(u)[1]
    if form == "arrays":
        return u, y
    if form == "record":
        return (fohw.Record(u=u, y=y, dt=dt, input_name="u" if m == 1 else
                            tuple(f"u{j + 1}" for j in range(m))),)
    pd = pytest.importorskip("pandas")
    columns = {f"in{j}": np.reshape(u, (len(y), -1))[:, j] for j in range(m)}
    frame = pd.DataFrame({**columns, "out": y})
    return (fohw.Record.from_dataframe(frame, u=list(columns) if m > 1 else "in0", y="out",
                                       dt=dt),)


def _data(case, form):
    return _forms(case.u, case.y, case.true.dt, form)


def _record(case):
    return _data(case, "record")[0]


def _u_kw(args):
    """The data as the ``u=``, ``y=`` keywords of lr_test and profile_interval."""
    return {"u": args[0], "y": args[1]} if len(args) == 2 else {"u": args[0]}


def _wrong_order(case):
    truth = case.true.parameters[case.order].value
    lo, hi = case.start.parameters[case.order].bounds
    return lo + 0.75 * (hi - lo) if truth < (lo + hi) / 2 else lo + 0.25 * (hi - lo)


@pytest.fixture(scope="module", params=KINDS, ids=lambda f: f.__name__)
def case(request):
    c = _case(request.param, seed=1)
    c.fit = fohw.fit(c.start, c.u, c.y)
    c.restricted = fohw.fit(_with(c.start, c.order, value=_wrong_order(c), fixed=True), c.u, c.y)
    c.candidates = {"wrong": _with(c.start, c.order, value=_wrong_order(c), fixed=True),
                    "right": c.start}
    c.selection = fohw.select_structure(c.u, c.y, c.candidates)
    c.lr = fohw.lr_test(c.restricted, c.fit, u=c.u, y=c.y)
    c.interval = fohw.profile_interval(c.fit, c.order, u=c.u, y=c.y, n_grid=3, xtol=0.02)
    return c


# --- the matrix: every verb x {arrays, Record, DataFrame -> Record} --------------------------
@pytest.mark.parametrize("form", FORMS)
def test_fit_simulate_compare_crb(case, form):
    args = _data(case, form)
    res = fohw.fit(case.start, *args)
    assert res.sse == case.fit.sse and res.data_digest == case.fit.data_digest
    assert res.parameters.valuesdict() == case.fit.parameters.valuesdict()
    ref = case.true.simulate(case.u)
    np.testing.assert_array_equal(fohw.simulate(case.true, args[0]), ref)
    np.testing.assert_array_equal(case.fit.simulate(args[0]), case.fit.model.simulate(case.u))
    v = fohw.compare(case.fit, *args)
    assert v.fit == fohw.compare(case.fit, case.u, case.y).fit
    np.testing.assert_array_equal(v.simulated, case.fit.model.simulate(case.u))
    kw = {"noise": "output"} if _lagged(case.true) else {}
    bound = fohw.crb(case.true, args[0], case.noise_std ** 2, **kw)
    np.testing.assert_array_equal(bound.covariance,
                                  fohw.crb(case.true, case.u, case.noise_std ** 2, **kw).covariance)


@pytest.mark.parametrize("form", FORMS)
def test_lr_test_profile_interval_select(case, form):
    args = _data(case, form)
    t, ref = fohw.lr_test(case.restricted, case.fit, **_u_kw(args)), case.lr
    assert (t.statistic, t.pvalue, t.rss_full) == (ref.statistic, ref.pvalue, ref.rss_full)
    pi = fohw.profile_interval(case.fit, case.order, n_grid=3, xtol=0.02, **_u_kw(args))
    assert (pi.lower, pi.upper) == (case.interval.lower, case.interval.upper)
    sel = fohw.select_structure(*args, case.candidates)
    assert [r["fit"] for r in sel.rows] == [r["fit"] for r in case.selection.rows]
    assert sel.best.sse == case.selection.best.sse


@pytest.fixture(scope="module")
def paper():
    """The lagged kind's own estimator: identify on the paper's example (N = 400)."""
    data = fohw.datasets.paper_example(400, random_state=0)
    kw = dict(na=2, nb=2, f_basis=2, g_basis=3)
    return data, kw, fohw.identify(data.u, data.y, **kw), fohw.identify(data.u, data.y,
                                                                        orders=0, **kw)


@pytest.mark.parametrize("form", FORMS)
def test_identify_and_its_verbs(paper, form):
    data, kw, frac, integer = paper
    args = _forms(data.u, data.y, 1.0, form)
    res = fohw.identify(*args, **kw)
    np.testing.assert_array_equal(res.theta, frac.theta)
    assert res.orders == frac.orders and res.J == frac.J
    np.testing.assert_array_equal(res.simulate(args[0]), frac.simulate(data.u))
    np.testing.assert_array_equal(fohw.simulate(res, args[0]), frac.simulate(data.u))
    v = fohw.compare(res, *args)
    ref = fohw.compare(frac, data.u, data.y)
    assert (v.fit_simulation, v.fit_prediction) == (ref.fit_simulation, ref.fit_prediction)
    uy = _u_kw(args)
    t = fohw.lr_test(integer, frac, reference="bootstrap", n_bootstrap=3, random_state=0, **uy)
    t_ref = fohw.lr_test(integer, frac, u=data.u, y=data.y, reference="bootstrap",
                         n_bootstrap=3, random_state=0)
    assert (t.statistic, t.pvalue) == (t_ref.statistic, t_ref.pvalue)
    pi = fohw.profile_interval(frac, "alpha", n_grid=3, xtol=0.02, **uy)
    assert tuple(pi) == tuple(fohw.profile_interval(frac, "alpha", u=data.u, y=data.y,
                                                    n_grid=3, xtol=0.02))
    sel = fohw.select_structure(*args, {"na": [1, 2]}, f_basis=2, g_basis=3)
    ref_sel = fohw.select_structure(data.u, data.y, {"na": [1, 2]}, f_basis=2, g_basis=3)
    assert [r["fit"] for r in sel.rows] == [r["fit"] for r in ref_sel.rows]
    np.testing.assert_array_equal(sel.best.theta, ref_sel.best.theta)


def test_a_dataframe_is_refused_by_every_verb_naming_from_dataframe(paper):
    pd = pytest.importorskip("pandas")
    data, kw, frac, integer = paper
    frame = pd.DataFrame({"u": data.u, "y": data.y})
    model = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    calls = [lambda: fohw.identify(frame, **kw), lambda: fohw.compare(frac, frame),
             lambda: fohw.fit(model, frame), lambda: fohw.crb(model, frame, 0.01),
             lambda: fohw.select_structure(frame, {"na": [1]}, f_basis=2, g_basis=3),
             lambda: fohw.lr_test(integer, frac, u=frame),
             lambda: fohw.profile_interval(frac, "alpha", u=frame)]
    for call in calls:
        with pytest.raises(fohw.ParameterError, match="Record.from_dataframe"):
            call()


def test_a_record_at_another_step_than_the_model_is_refused():
    model = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    u = np.random.default_rng(0).standard_normal(200)
    rec = fohw.Record(u=u, y=model.simulate(u), dt=0.1, time_unit="s")
    for call in (lambda: fohw.simulate(model, rec), lambda: fohw.compare(model, rec),
                 lambda: fohw.crb(model, rec, 0.01)):
        with pytest.raises(fohw.ParameterError, match=r"sampled every 0\.1 s but .*0\.05"):
            call()
    # instants that are not uniform: a kind discrete in samples says so (the lagged kind),
    # and so does a result of its own estimator
    odd = fohw.Record(u=u[:5], y=u[:5], t=[0.0, 0.05, 0.1, 0.2, 0.25])
    lagged = fohw.datasets.paper_model()
    res = fohw.identify(u, model.simulate(u), na=1, nb=1, f_basis=1, g_basis=1)
    for call in (lambda: fohw.simulate(lagged, odd), lambda: fohw.compare(lagged, odd),
                 lambda: res.simulate(odd), lambda: fohw.identify(odd, na=1, nb=1, f_basis=1,
                                                                  g_basis=1)):
        with pytest.raises(fohw.ParameterError, match="non-uniform time stamps.*resample"):
            call()


def test_several_records_in_simulate_and_compare(case):
    rec = _record(case)
    parts = [rec[:rec.n_samples // 2], rec[rec.n_samples // 2:]]
    runs = fohw.simulate(case.fit, parts)
    assert [r.size for r in runs] == [p.n_samples for p in parts]
    np.testing.assert_array_equal(runs[1], case.fit.model.simulate(parts[1].u))
    pooled = fohw.compare(case.fit, parts)
    for v, p in zip(pooled.records, parts):
        assert v.fit == fohw.compare(case.fit, p).fit
    # pooled: the fit % of the stacked samples, by its definition
    y = np.concatenate([p.y for p in parts])
    ysim = np.concatenate([case.fit.model.simulate(p.u) for p in parts])
    expected = 100 * (1 - np.linalg.norm(y - ysim) / np.linalg.norm(y - y.mean()))
    assert pooled.fit == pytest.approx(expected, rel=1e-12)
    assert "| pooled |" in pooled.to_markdown()


# --- several experiments: the joint Cramér–Rao bound ---------------------------------------------
def test_joint_crb_is_the_inverse_of_the_summed_information(case):
    # Independent records: the log-likelihoods add, so the Fisher informations add. Each
    # bound's inverse is its record's information times the noise variance; the joint one
    # must be their sum, to rounding (the stacked QR against three separate inversions).
    rec = _record(case)
    cut = [0, rec.n_samples // 3, 2 * rec.n_samples // 3, rec.n_samples]
    parts = [rec[a:b] for a, b in zip(cut, cut[1:])]
    kw = {"noise": "output"} if _lagged(case.true) else {}
    sigma2 = case.noise_std ** 2
    joint = fohw.crb(case.true, parts, sigma2, **kw)
    if _lagged(case.true):
        info = sum(np.linalg.inv(fohw.crb(case.true, p, sigma2, **kw).covariance) for p in parts)
    else:
        # S^T S / sigma^2 of each part from its free-run sensitivities (a part alone may not
        # identify every parameter: a table's breakpoint it never visits)
        info = sum(j.T @ j for j in (free_jacobian(case.true, p.u)[1] for p in parts)) / sigma2
    np.testing.assert_allclose(np.linalg.inv(joint.covariance), info,
                               rtol=1e-7, atol=1e-9 * np.abs(info).max())
    # the joint bound is below each record's own (more data, never less information)
    for p in parts:
        try:
            alone = fohw.crb(case.true, p, sigma2, **kw)
        except fohw.ParameterError as exc:      # a part that identifies less: no bound alone
            assert "singular" in str(exc)
            continue
        assert np.all(np.diag(joint.covariance) <= np.diag(alone.covariance) * (1 + 1e-12))


# --- the dt regression ----------------------------------------------------------------------------
def test_select_on_a_record_refits_at_its_sampling_time():
    # Issue 35: select_structure(record, ...) on a record sampled every 4 s refitted its winner
    # at dt = 1 (fohw select on the same file used 4 s).
    tanks = fohw.datasets.cascaded_tanks().estimation
    assert tanks.dt == 4.0
    sel = fohw.select_structure(tanks, {"na": [1, 2]}, f_basis=1, g_basis=1,
                                operating_point="initial")
    assert sel.best.structure.dt == 4.0
    assert sel.best.structure.dt == fohw.identify(tanks, na=sel.best_row["na"], nb=sel.best_row[
        "na"], f_basis=1, g_basis=1, operating_point="initial").structure.dt
    with pytest.raises(fohw.ParameterError, match=r"sampled every 4\.0 s but `dt` = 1\.0"):
        fohw.select_structure(tanks, {"na": [1]}, f_basis=1, g_basis=1, dt=1.0)
    model = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=1.0)
    with pytest.raises(fohw.ParameterError, match=r"sampled every 4\.0 s"):
        fohw.select_structure(tanks, [model])


def test_select_on_several_records_holds_back_the_end_or_whole_records():
    rng = np.random.default_rng(5)
    true = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05)
    recs = []
    for _ in range(3):
        u = np.repeat(rng.standard_normal(30), 5)
        recs.append(fohw.Record(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal(u.size),
                                dt=0.05))
    wrong = _with(start, "alpha0", value=1.5, fixed=True)
    sel = fohw.select_structure(recs, {"wrong": wrong, "right": start})
    assert sel.best_row["candidate"] == "right" and sel.best.n_samples == 450
    assert "end of each of 3 records" in sel.validation
    whole = fohw.select_structure(recs, {"wrong": wrong, "right": start}, hold_out="records",
                                  validation=1)
    assert whole.best_row["candidate"] == "right" and "last 1 of 3 records" in whole.validation
    # the held-back record's free run from rest is what is scored
    est = fohw.fit(start, recs[:2])
    assert whole.rows[1]["rmse"] == pytest.approx(
        math.sqrt(np.mean((recs[2].y - est.model.simulate(recs[2].u)) ** 2)), rel=1e-9)
    with pytest.raises(fohw.ParameterError, match="model candidates"):
        fohw.select_structure(recs, {"na": [1]}, f_basis=1, g_basis=1)


# --- names and units on show -----------------------------------------------------------------
def _named_record():
    tanks = fohw.datasets.cascaded_tanks().estimation
    return fohw.Record(u=tanks.u, y=tanks.y, dt=4.0, time_unit="s", input_name="pump voltage",
                       input_unit="V", output_name="lower tank level", output_unit="V")


def test_names_and_units_reach_the_summary_the_file_and_the_figures(tmp_path):
    rec = _named_record()
    res = fohw.identify(rec, na=2, nb=2, f_basis=1, g_basis=1, operating_point="initial")
    assert res.structure.dt == 4.0
    text = res.summary()
    assert "input pump voltage [V]; output lower tank level [V], dt = 4 s" in text
    fohw.save_result(res, tmp_path / "r.json")
    assert fohw.load_result(tmp_path / "r.json").data["output_unit"] == "V"
    fig = fohw.compare(res, rec).plot()
    assert fig.axes[-1].get_xlabel() == "time [s]"
    assert fig.axes[0].get_ylabel() == "lower tank level [V]"
    assert fig.axes[0].get_lines()[0].get_xdata()[-1] == 4.0 * (rec.n_samples - 1)
    assert res.bode().axes[-1].get_xlabel() == "angular frequency ω [rad/s]"
    assert res.bode(hz=True).axes[-1].get_xlabel() == "frequency f [Hz]"
    plain = fohw.identify(rec.u, rec.y, na=2, nb=2, f_basis=1, g_basis=1,
                          operating_point="initial")
    assert plain.bode().axes[-1].get_xlabel() == "angular frequency ω [rad / sample]"
    assert fohw.compare(plain, rec.u, rec.y).plot().axes[-1].get_xlabel() == "sample k"
    # a model of another kind: the FitResult's summary and its comparison's figure
    model = fohw.FractionalTF([1.0], [0.0], [20.0, 1.0], [0.8, 0.0], dt=4.0)
    small = rec[:200]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fitted = fohw.fit(model, small, order_grid=1, n_starts=1, max_nfev=20)
    assert "output lower tank level [V], dt = 4 s" in fitted.summary()
    assert fohw.compare(fitted, small).plot().axes[-1].get_xlabel() == "time [s]"


def test_the_command_line_plots_against_the_files_time(tmp_path, monkeypatch, capsys):
    import fohw.cli as cli

    figures = []
    monkeypatch.setattr(cli, "save_figure", lambda fig, path, **kw: figures.append(fig))
    args = ["identify", "@cascaded_tanks", "--columns", "uEst,yEst", "--na", "1", "--nb", "1",
            "--f-basis", "1", "--g-basis", "1", "--operating-point", "initial", "--plot",
            str(tmp_path / "f.png"), "-q"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "input uEst; output yEst, dt = 4" in out and "dt=4" in out
    ax = figures[0].axes[-1]
    assert ax.get_xlabel() == "time"            # the file gives the step (Ts), not its unit
    assert ax.get_lines()[0].get_xdata()[-1] == 4.0 * 1023
    assert figures[0].axes[0].get_ylabel() == "yEst"


class ZohLag(fohw.Model):
    """``tau x' + x = gain u`` with the input held between instants: exact at any step."""

    kind = "TestRecordVerbsZohLag"

    def __init__(self, gain=1.0, tau=1.0):
        self.gain, self.tau = float(gain), float(tau)

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("gain", self.gain),
                                fohw.Parameter("tau", self.tau, bounds=(1e-3, 1e3))])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return ZohLag(v["gain"], v["tau"])

    def simulate(self, u, *, initial=None):
        return self.simulate_at(u, np.arange(np.shape(u)[0], dtype=float))

    def simulate_at(self, u, t, *, intersample="zoh", refine=None, step=None):
        u = self.check_input(u)
        x = np.zeros(u.size)
        for k in range(1, u.size):
            a = math.exp(-(t[k] - t[k - 1]) / self.tau)
            x[k] = a * x[k - 1] + (1 - a) * self.gain * u[k - 1]
        return x


def test_a_kind_that_simulates_on_instants_runs_a_non_uniform_record():
    # A step held from t = 0: x(t) = gain (1 - exp(-t / tau)) at every instant, whatever the
    # steps (the exact zero-order-hold solution), through fohw.simulate and compare.
    t = np.cumsum(np.r_[0.0, np.random.default_rng(3).uniform(0.05, 0.4, 59)])
    model = ZohLag(2.0, 1.5)
    rec = fohw.Record(u=np.ones(t.size), y=2.0 * (1 - np.exp(-t / 1.5)), t=t, time_unit="s")
    assert not rec.uniform
    np.testing.assert_allclose(fohw.simulate(model, rec), rec.y, rtol=1e-12, atol=1e-15)
    v = fohw.compare(model, rec)
    assert v.rmse < 1e-12 and v.fit > 99.999
    assert "ZohLag is an output-error model" in " ".join(v.notes)
    fig = v.plot()
    assert fig.axes[-1].get_xlabel() == "time [s]"
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_xdata(), t)


def test_the_command_line_simulates_only_at_the_files_step(tmp_path, capsys):
    # The file says Ts = 4 (the cascaded tanks); the paper's model runs at dt = 1.
    fohw.save_model(fohw.datasets.paper_model(), tmp_path / "m.json")
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input", "@cascaded_tanks",
                 "--column", "uEst", "--output", str(tmp_path / "y.txt")]) == 2
    assert "sampled every 4 (its Ts) but" in capsys.readouterr().err
    assert not (tmp_path / "y.txt").exists()


def test_profile_interval_and_lr_test_check_a_record_on_instants_by_the_fits_digest():
    # The fit's fingerprint holds the instants and how the model ran between them (hold,
    # refine): the same record passes, the same samples with another hold are another record.
    rng = np.random.default_rng(4)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.05, 0.4, 79)])
    u = np.repeat(rng.standard_normal(16), 5)
    y = ZohLag(2.0, 1.5).simulate_at(u, t) + 0.01 * rng.standard_normal(t.size)
    rec = fohw.Record(u=u, y=y, t=t, intersample="foh")
    res = fohw.fit(ZohLag(1.0, 1.0), rec)
    pi = fohw.profile_interval(res, "tau", u=rec, n_grid=5)
    assert pi.lower < 1.5 < pi.upper
    held = fohw.Record(u=u, y=y, t=t, intersample="zoh")
    with pytest.raises(fohw.ParameterError, match="not the data `result` was fitted to"):
        fohw.profile_interval(res, "tau", u=held)
    fixed = fohw.fit(_with(ZohLag(1.0, 1.0), "tau", value=1.0, fixed=True), rec)
    assert fohw.lr_test(fixed, res, u=rec).pvalue < 1e-6
