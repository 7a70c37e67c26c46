"""The catalogue of bad inputs: each gets a clear error naming the argument, never a crash,
a hang or NaNs. docs/bad_input.md is generated from this table:

    python tests/test_bad_input.py > docs/bad_input.md

and a test checks that the page is current.
"""

import functools
import io
import os
import sys
from contextlib import redirect_stderr
from pathlib import Path

import numpy as np
import pytest

import fohw
from fohw.analysis.metrics import effective_samples
from fohw.cli import main as cli
from fohw.estimators.impedance_fit import fit_impedance, fit_record_and_impedance
from fohw.exceptions import ModelHookError
from fohw.model.circuit import impedance_error

ROOT = Path(__file__).resolve().parents[1]
S = dict(na=2, nb=2, f_basis=2, g_basis=3)
U = np.random.default_rng(0).uniform(-1, 1, 50)
Y = np.zeros(50)
M = fohw.datasets.paper_model
_U2 = np.column_stack([U, U[::-1]])
_PAPER16 = fohw.datasets.paper_example(16, random_state=0)
_TF = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
_PAPER100 = fohw.datasets.paper_example(100, random_state=0)
_U2_100 = np.column_stack([_PAPER100.u, np.random.default_rng(5).uniform(-1, 1, 100)])
_G34 = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0])
_CIRC34 = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015)


class _NoResponse(fohw.Model, register=False):
    """A kind with the three required members only: no frequency response."""

    parameters = fohw.Parameters([fohw.Parameter("k", 1.0)])

    def with_parameters(self, values):
        return self

    def simulate(self, u, *, initial=None):
        return self.check_input(u)


class _Lag43(fohw.Model, register=False):
    """Issue 43's Lag (the fohw.Model docstring's example): y[k] = a y[k-1] + b u[k-1]."""

    def __init__(self, a=0.5, b=1.0):
        self.a, self.b = a, b

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return type(self)(v["a"], v["b"])

    def run(self, u):
        y = np.zeros_like(u)
        for k in range(1, u.size):
            y[k] = self.a * y[k - 1] + self.b * u[k - 1]
        return y

    def simulate(self, u, *, initial=None):
        return self.run(self.check_input(u))


_U43 = np.random.default_rng(43).standard_normal(200)
_Y43 = _Lag43(0.8, 2.0).simulate(_U43)


def _misbehaving(**hooks):
    """A _Lag43 whose hooks (``simulate=``, ``jacobian=``, ...) are replaced by functions."""
    return type("Kind43", (_Lag43,), dict(hooks), register=False)()


def _mut_simulate(self, u, *, initial=None):
    a = np.asarray(u)
    a *= 1.01                   # issue 43's N1: writes into its input
    return self.run(np.array(a))


def _unchanged(call):
    """``call(u)`` on a copy of _U43, checking that the copy is unchanged afterwards."""
    u = _U43.copy()
    try:
        return call(u)
    finally:
        assert np.array_equal(u, _U43), "the caller's array was changed"


def _wrong_sign_jacobian(self, u):
    y = self.run(self.check_input(u))
    ja = np.r_[0.0, y[:-1]]              # d y[k] / d a, to first order (the probe is coarse)
    for k in range(1, u.size):
        ja[k] = y[k - 1] + self.a * ja[k - 1]
    jb = _Lag43(self.a, 1.0).run(u)
    return y, -np.column_stack([ja, jb])


def _warned(call, category=fohw.ConvergenceWarning):
    """``call()`` with ``category`` raised as an error (the catalogue's rows raise)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", category)
        return call()


_G43 = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)
_R43 = [fohw.Record(u=x, y=_G43.simulate(x), dt=0.1)
        for x in np.random.default_rng(0).standard_normal((2, 300))]
_FIT43 = dict(order_grid=2, n_starts=1, max_nfev=30)


def _profile_per_record():
    half = [fohw.Record(u=_R43[0].u[:150], y=_R43[0].y[:150], dt=0.1),
            fohw.Record(u=_R43[0].u[150:], y=_R43[0].y[150:], dt=0.1)]
    joint = fohw.fit(_G43, half, per_record=["b0"], **_FIT43)
    return fohw.profile_interval(joint, "b0", u=half)


def _order_test_on_its_own_record():
    d = _PAPER100
    full = fohw.identify(d.u, d.y, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                         orders="commensurate")
    return fohw.order_test(full, d.u, d.y, validation=(d.u, d.y))


def _bad_file(tmp, text, name="bad.dat"):
    p = tmp / name
    p.write_text(text)
    return str(p)


def _model_file(tmp, **change):
    """A saved paper model with some fields changed (``f_basis=...``, ``version=...``)."""
    import json

    path = tmp / "m.json"
    fohw.save_model(M(), path)
    d = json.loads(path.read_text())
    d.update(change)
    path.write_text(json.dumps(d))
    return str(path)


def _result():
    return fohw.identify(U, U**3, na=1, nb=1, f_basis=1, g_basis=1)


def _result_file(tmp, **change):
    """A saved result with fields changed; ``theta_0``/``covariance_0`` change one entry."""
    import json

    path = tmp / "r.json"
    fohw.save_result(_result(), path)
    d = json.loads(path.read_text())
    for key, value in change.items():
        if key.endswith("_0"):
            d[key[:-2]]["data"][0] = value
        else:
            d[key] = value
    path.write_text(json.dumps(d))       # json writes NaN as NaN, as a hand edit might
    return str(path)


def _link(tmp, target, name="l.json"):
    (tmp / name).symlink_to(target)
    return str(tmp / name)


def _shipped_as(tmp, how):
    """battery_cell() with its shipped file replaced by a folder, a link or a long file."""
    from unittest import mock

    (tmp / "data").mkdir()
    path = tmp / "data" / fohw.datasets.BATTERY_FILENAME
    if how == "folder":
        path.mkdir()
    elif how == "long":
        with open(path, "wb") as fh:
            fh.truncate(64 * 2**20 + 1)                 # sparse: no disk used
    else:
        path.symlink_to(how)
    with mock.patch("importlib.resources.files", lambda package: tmp):
        return fohw.datasets.battery_cell()


def _two_inputs():
    """A fit of the paper's output to its input beside a second one (inputs named 'a', 'b')."""
    return fohw.identify(_U2_100, _PAPER100.y, na=2, nb=2, f_basis=1, g_basis=3, inputs=("a", "b"))


def _two_input_file(tmp, **change):
    """The saved _two_inputs() with fields replaced (``theta=x`` scales theta by x)."""
    import json

    path = tmp / "two.json"
    fohw.save_result(_two_inputs(), path)
    d = json.loads(path.read_text())
    for key, value in change.items():
        if key == "theta":
            d["theta"]["data"] = [v * value for v in d["theta"]["data"]]
        else:
            d[key] = value
    path.write_text(json.dumps(d))
    return str(path)


def _past_result():
    """A fit with past='estimate' (its levels belong to its estimation record)."""
    return fohw.identify(U, U**3, na=1, nb=1, f_basis=1, g_basis=1, past="estimate")


def _nan_result():
    import dataclasses

    return dataclasses.replace(_result(), J=float("nan"))


_G43 = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)        # 1/(s^0.8 + 1)
_UD43 = np.random.default_rng(43).standard_normal(300)
_YD43 = _G43.simulate(_UD43)


@functools.cache
def _fit43(joint=False):
    """Issue 43's fits: of one record, or of its halves with ``b0`` per record (as JSON)."""
    import json

    halves = [fohw.Record(u=_UD43[:150], y=_YD43[:150], dt=0.1),
              fohw.Record(u=_UD43[150:], y=_YD43[150:], dt=0.1)]
    fit = (fohw.fit(_G43, halves, per_record=["b0"], order_grid=2, n_starts=1) if joint else
           fohw.fit(_G43, fohw.Record(u=_UD43, y=_YD43, dt=0.1), order_grid=2, n_starts=1))
    return fit, json.dumps(fit.to_dict())


def _fit43_dict(joint=False, **change):
    """A fresh copy of an issue-43 fit's ``to_dict()`` with fields changed."""
    import json

    d = json.loads(_fit43(joint)[1])
    d.update(change)
    return d


def _fit43_file(tmp, joint=False, drop=(), **change):
    """An issue-43 fit saved, then its fields changed (``drop``: fields deleted)."""
    import json

    path = tmp / "fit43.json"
    fohw.save_result(_fit43(joint)[0], path)
    d = json.loads(path.read_text())
    d.update(change)
    for key in drop:
        del d[key]
    path.write_text(json.dumps(d))
    return path


def _tables43(**kw):
    """Issue 43's CircuitTables: one RC, breakpoints SOC 0.2, 0.8 and 10, 30 degC."""
    kw = {"soc_points": [0.2, 0.8], "temperature_points": [10.0, 30.0], **kw}
    return fohw.CircuitTables(["rc"], ocv=lambda s: 3.3 + 0.9 * np.asarray(s), **kw)


def _cu43(soc=None, temperature=20.0):
    """Issue 43's CU3: 20-s current steps from U(-3, 1) A, soc from 0.6, 400 samples."""
    i = np.repeat(np.random.default_rng(3).uniform(-3.0, 1.0, 20), 20)
    s = 0.6 + np.cumsum(i) / 18000 if soc is None else np.full(400, soc)
    return np.column_stack([i, s, np.full(400, temperature)])


def _frame43(columns=("i", "v"), index=None):
    import pandas as pd

    data = np.column_stack([_UD43, _YD43, _YD43])[:, :len(columns)]
    return pd.DataFrame(data, columns=list(columns), index=index)


def _nat_index43():
    import pandas as pd

    stamps = pd.date_range("2024-01-01", periods=300, freq="100ms").to_series().reset_index(drop=True)
    stamps[3] = pd.NaT
    return pd.DatetimeIndex(stamps)


# (where, what is wrong, call, exception, text the message must contain)
API = [
    ("fit", "a FractionalTF, u and y differ in length",
     lambda t: fohw.fit(_TF, np.ones(50), np.ones(49)),
     fohw.DimensionError, "`u` and `y` must have the same length"),
    ("fit", "a FractionalTF without a sampling time",
     lambda t: fohw.fit(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), U, U),
     fohw.ParameterError, "this FractionalTF has no sampling time"),
    ("fit", "a FractionalTF on a zero input",
     lambda t: fohw.fit(_TF, np.zeros(50), U), fohw.ParameterError, "`u` is zero at every sample"),
    ("fit", "a FractionalTF on a constant output",
     lambda t: fohw.fit(_TF, U, np.ones(50)), fohw.ParameterError, "`y` is constant"),
    ("FractionalTF.simulate", "an initial state other than rest",
     lambda t: _TF.simulate(U, initial="estimate"), fohw.ParameterError,
     "`initial` must be None or 'rest'; got 'estimate'"),
    ("FractionalTF", "a zero leading denominator coefficient",
     lambda t: fohw.FractionalTF([1.0], [0.0], [0.0, 1.0], [0.5, 0.0]), fohw.ParameterError, "`den`"),
    ("gl_difference", "alpha is NaN", lambda t: fohw.gl_difference(np.ones(5), np.nan),
     fohw.ParameterError, "`alpha` must be finite"),
    ("gl_difference", "x holds NaN", lambda t: fohw.gl_difference([1.0, np.nan], 0.5),
     fohw.ParameterError, "`x` must contain only finite values"),
    ("gl_difference", "axis out of range", lambda t: fohw.gl_difference(np.ones((2, 3)), 0.5, axis=3),
     fohw.DimensionError, "`axis` 3 is out of range"),
    ("gl_difference", "memory = 0", lambda t: fohw.gl_difference(np.ones(5), 0.5, memory=0),
     fohw.ParameterError, "`memory` must be at least 1"),
    ("gl_difference", "h <= 0", lambda t: fohw.gl_difference(np.ones(5), 0.5, h=-1.0),
     fohw.ParameterError, "`h` must be in (0, inf]"),
    ("gl_weights", "n is a float", lambda t: fohw.gl_weights(0.5, 3.0),
     fohw.ParameterError, "`n` must be an integer"),
    ("gl_weights_derivative", "n = 0", lambda t: fohw.model.gl.gl_weights_derivative(0.5, 0),
     fohw.ParameterError, "`n` must be at least 1; got 0"),
    ("polynomial_basis", "degree 0", lambda t: fohw.polynomial_basis(0),
     fohw.ParameterError, "`degree` must be at least 1; got 0"),
    ("as_basis", "a string", lambda t: fohw.model.basis.as_basis("x", "f_basis"),
     fohw.ParameterError, "`f_basis` must be a Basis, an int degree, or callables; got 'x'"),
    ("save_model", "not a model", lambda t: fohw.save_model("m", t / "m.json"),
     fohw.ParameterError,
     "`model` must be a fohw.Model (a HammersteinWiener or any other kind); got str"),
    ("load_model", "not a model file", lambda t: fohw.load_model(_bad_file(t, "{}", "m.json")),
     fohw.DataFileError, "is not a fohw-model file"),
    ("monte_carlo", "an option the method does not have",
     lambda t: fohw.monte_carlo({"v": {"method": "varpro", "innovation_length": 2}},
                                seeds=range(1), settings=[{"n_samples": 200}]),
     fohw.ParameterError, "method 'varpro' has no option `innovation_length`"),
    ("compare", "a validation record whose u and y differ in length",
     lambda t: fohw.compare(fohw.identify(U, U**3, na=1, nb=1, f_basis=1, g_basis=1), U,
                            np.zeros(40)),
     fohw.DimensionError, "`u` and `y` must have the same length; got 50 and 40"),
    ("identify_many", "a record that is neither a Record nor a pair",
     lambda t: fohw.identify_many([U], na=1, nb=1, f_basis=1, g_basis=1),
     fohw.ParameterError,
     "`records[0]` must be a Record, a pair (u, y) or a file path; got ndarray"),
    ("stream_fits", "a start model that is not a fohw.Model",
     lambda t: list(fohw.stream_fits([(U, Y)], "FractionalTF")),
     fohw.ParameterError, "`model` must be a fohw.Model (a start model of any kind); got str"),
    ("stream_fits", "records per task that are not a positive integer",
     lambda t: fohw.stream_fits([(U, Y)], _TF, chunksize=0),
     fohw.ParameterError, "`chunksize` must be a positive integer; got 0"),
    ("stream_fits", "an executor that is not one",
     lambda t: list(fohw.stream_fits([(U, Y)], _TF, executor=4)),
     fohw.ParameterError, "`executor` must be a concurrent.futures.Executor"),
    ("read_record", "three signal columns and no say which is u and y",
     lambda t: fohw.read_record(_bad_file(t, "0 1 2\n1 2 3\n", "r.dat")),
     fohw.ParameterError, "say which is the input and which the output with u=... and y=..."),
    ("select_structure", "a grid entry that is not a list",
     lambda t: fohw.select_structure(U, Y, {"na": 2}, nb=2, f_basis=2, g_basis=3),
     fohw.ParameterError, "maps each keyword to a list of values; `candidates['na']` is 2"),
    ("select_structure", "a held-back part that leaves no estimation data",
     lambda t: fohw.select_structure(U, Y, [dict(na=2)], validation=1.0, nb=2, f_basis=2,
                                     g_basis=3),
     fohw.ParameterError, "`validation` as a fraction must be in (0, 1); got 1.0"),
    ("HammersteinWiener", "alpha outside [0, 2]",
     lambda t: fohw.HammersteinWiener([0.1], [1.0], [1.0], [1.0], 2.7),
     fohw.ParameterError, "`alpha` must be in [0, 2]; got 2.7"),
    ("HammersteinWiener", "p[0] != 1", lambda t: fohw.HammersteinWiener([0.1], [1.0], [2.0], [1.0], 0.5),
     fohw.ParameterError, "`p[0]` must be exactly 1"),
    ("HammersteinWiener", "q longer than g_basis",
     lambda t: fohw.HammersteinWiener([0.1], [1.0], [1.0], [1.0, 0.5], 0.5, g_basis=1),
     fohw.DimensionError, "`q` must have one entry per g-basis function"),
    ("HammersteinWiener", "a basis entry not callable",
     lambda t: fohw.HammersteinWiener([0.1], [1.0], [1.0, 0.2], [1.0], 0.5, f_basis=[np.sin, "cos"]),
     fohw.ParameterError, "`f_basis` entry 1 must be callable"),
    ("HammersteinWiener.from_theta", "theta of the wrong length",
     lambda t: fohw.HammersteinWiener.from_theta(np.ones(9), 0.5, **S),
     fohw.DimensionError, "`theta` must have 10 entries"),
    ("ThetaHW", "a structure that is not a Structure", lambda t: fohw.ThetaHW("na=1"),
     fohw.ParameterError, "`structure` must be a fohw.Structure; got str"),
    ("ThetaHW", "linear parameters of the wrong length",
     lambda t: fohw.ThetaHW(fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1), [1.0]),
     fohw.DimensionError, "`linear` must have 2 entries ('a1', 'b1'); got shape (1,)"),
    ("ThetaHW", "an order outside [0, 2]",
     lambda t: fohw.ThetaHW(fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1), [0.1, 1.0],
                            [2.5]),
     fohw.ParameterError, "`nonlinear['alpha']` must be in [0, 2]; got 2.5"),
    ("simulate", "u holds inf", lambda t: fohw.simulate(M(), [0.0, np.inf]),
     fohw.ParameterError, "`u` must contain only finite values"),
    ("simulate", "noise of another length", lambda t: fohw.simulate(M(), U, noise=np.zeros(3)),
     fohw.DimensionError, "`noise` and `u` must have the same length; got 3 and 50"),
    ("simulate", "unstable model or input", lambda t: fohw.simulate(M(), 4.0 * np.ones(100)),
     fohw.SimulationDivergedError, "diverged at sample k ="),
    ("simulate", "a Structure without parameter values",
     lambda t: fohw.simulate(fohw.Structure.make(**S), U),
     fohw.ParameterError, "simulating a Structure needs its parameter values `params`"),
    ("simulate", "parameters of the wrong length",
     lambda t: fohw.simulate(
         fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, orders="mixed"), U,
         params=np.ones(3)),
     fohw.DimensionError,
     "`params` must have 5 entries ('a1_0', 'a1_alpha', 'b1_0', 'b1_alpha', 'alpha'); got 3"),
    ("simulate", "an order outside [0, 2]",
     lambda t: fohw.simulate(fohw.Structure.make(**S), U, params=np.r_[M().theta, 2.5]),
     fohw.ParameterError, "`params['alpha']` must be in [0, 2]; got 2.5"),
    ("simulate", "`params` with a model (it carries its own)",
     lambda t: fohw.simulate(M(), U, params=[0.6]),
     fohw.ParameterError, "`params` is for a Structure; a HammersteinWiener carries its own"),
    ("information_matrix", "u and y of different lengths",
     lambda t: fohw.model.lagged.regressors.information_matrix(U, Y[:49], 0.5, **S),
     fohw.DimensionError, "`u` and `y` must have the same length; got 50 and 49"),
    ("information_matrix", "record shorter than the lags",
     lambda t: fohw.model.lagged.regressors.information_matrix(U[:2], Y[:2], 0.5, **S),
     fohw.DimensionError, "the record must be longer than the lags"),
    ("information_matrix", "na < 1",
     lambda t: fohw.model.lagged.regressors.information_matrix(U, Y, 0.5, **{**S, "na": 0}),
     fohw.ParameterError, "`na` must be at least 1; got 0"),
    ("identify", "innovation_length longer than the record",
     lambda t: fohw.identify(U, Y, method="hybrid", innovation_length=51, **S),
     fohw.ParameterError, "`innovation_length` must be at most 50; got 51"),
    ("identify", "tol <= 0", lambda t: fohw.identify(U, Y, method="hybrid", tol=0.0, **S),
     fohw.ParameterError, "`tol` must be in (0, inf]; got 0.0"),
    ("identify", "alpha0 outside alpha_bounds",
     lambda t: fohw.identify(U, Y, method="hybrid", alpha0=1.5, **S),
     fohw.ParameterError, "`alpha0` must be in (0, 1); got 1.5"),
    ("identify", "an option the method does not have",
     lambda t: fohw.identify(U, Y, method="varpro", innovation_length=3, **S),
     fohw.ParameterError, "method 'varpro' has no option `innovation_length`"),
    ("identify", "an option of another method",
     lambda t: fohw.identify(U, Y, method="output_error", max_iter=3, **S),
     fohw.ParameterError, "`max_iter` is an option of 'hybrid'"),
    ("identify", "an option given twice",
     lambda t: fohw.identify(U, Y, method="hybrid", tol=1e-3, options={"tol": 1e-2}, **S),
     fohw.ParameterError, "given both as keywords and in `options`"),
    ("HybridIdentifier", "another method asked of it",
     lambda t: fohw.estimators.hybrid.HybridIdentifier(method="varpro", **S),
     TypeError, "unexpected keyword argument 'method'"),
    ("MultiInnovationRLS", "a parameter it does not have",
     lambda t: fohw.estimators.rls.MultiInnovationRLS(p0=1e3, **S),
     TypeError, "unexpected keyword argument 'p0'"),
    ("identify", "unknown method", lambda t: fohw.identify(U, Y, method="newton", **S),
     fohw.ParameterError, "`method` must be one of"),
    ("identify", "alpha_bounds reversed", lambda t: fohw.identify(U, Y, alpha_bounds=(0.9, 0.1), **S),
     fohw.ParameterError, "`alpha_bounds` must satisfy"),
    ("IdentificationResult.standard_errors", "asked of a recursive method",
     lambda t: _hybrid().standard_errors(), ValueError, "only defined at a least-squares optimum"),
    ("MultiInnovationRLS.predict", "used before fit",
     lambda t: fohw.estimators.rls.MultiInnovationRLS(**S).predict(U, Y), fohw.NotFittedError,
     "not fitted yet"),
    ("crb", "noise_variance = 0", lambda t: fohw.crb(M(), U, 0.0),
     fohw.ParameterError, "`noise_variance` must be in (0, inf]"),
    ("crb", "an unknown parametrisation",
     lambda t: fohw.crb(M(), U, 0.01, parametrisation="struct"),
     fohw.ParameterError, "`parametrisation` must be one of ('theta', 'structured'); got 'struct'"),
    ("crb", "noise realisations for the deterministic output-noise bound",
     lambda t: fohw.crb(M(), U, 0.01, noise="output", n_realizations=3),
     fohw.ParameterError, "`n_realizations` is not used with noise='output'"),
    ("identify", "method='structured' with fewer samples than parameters",
     lambda t: fohw.identify(U[:8], U[:8] ** 3, method="structured", **S),
     fohw.DimensionError, "least squares needs more samples than parameters"),
    ("datasets.paper_example", "unknown input_kind",
     lambda t: fohw.datasets.paper_example(100, input_kind="binary"),
     fohw.ParameterError, "`input_kind` must be 'uniform' or 'gaussian'"),
    ("datasets.load_daisy", "a non-numeric entry",
     lambda t: fohw.datasets.load_daisy(_bad_file(t, "1 2\n3 x\n")),
     fohw.DataFileError, "line 2: 'x' is not a number"),
    ("datasets.load_daisy", "a ragged line", lambda t: fohw.datasets.load_daisy(_bad_file(t, "1 2\n3\n")),
     fohw.DataFileError, "line 2 has 1 column(s); expected 2"),
    ("datasets.robot_arm", "file missing", lambda t: fohw.datasets.robot_arm(t),
     FileNotFoundError, "robot-arm data not found"),
    ("datasets.robot_arm", "file corrupted",
     lambda t: fohw.datasets.robot_arm(_bad_file(t, "1 2\n", "daisy_robot_arm.dat")),
     fohw.DataFileError, "does not match the published"),
    ("Record", "u and y of different lengths",
     lambda t: fohw.Record(u=np.ones(3), y=np.ones(4)),
     fohw.DimensionError, "`u` and `y` must have the same length"),
    ("Record.split", "a split point that leaves one side empty",
     lambda t: fohw.datasets.cascaded_tanks().estimation.split(1024),
     fohw.ParameterError, "`at` must leave samples on both sides"),
    ("load_result", "not a result file", lambda t: fohw.load_result(_bad_file(t, "{}", "r.json")),
     fohw.DataFileError, "is not a fohw-result file"),
    # issue 14, cases 4-30 (the numbers are the issue's): each was a traceback, a hang, a silent
    # NaN or a misleading message before
    ("identify", "data of size 1e160 (hybrid)",
     lambda t: fohw.identify(1e160 * U, 1e160 * U**3, method="hybrid", **S),
     fohw.ParameterError, "it returned a non-finite value. If the data are merely large, rescale"),
    ("identify", "data of size 1e160 (varpro)",
     lambda t: fohw.identify(1e160 * U, 1e160 * U**3, method="varpro", **S),
     fohw.ParameterError, "it returned a non-finite value. If the data are merely large, rescale"),
    ("identify", "data of size 1e160 (rls)",
     lambda t: fohw.identify(1e160 * U, 1e160 * U**3, method="rls", **S),
     fohw.ParameterError, "it returned a non-finite value. If the data are merely large, rescale"),
    ("identify", "fewer samples than parameters (varpro, output_error)",
     lambda t: fohw.identify(U[:8], U[:8] ** 3, **S),
     fohw.DimensionError, "least squares needs more samples than parameters: the record has 8 "
     "samples for 11 parameters"),
    ("identify", "as many samples as parameters (was ZeroDivisionError)",
     lambda t: fohw.identify(U[:11], U[:11] ** 3, method="output_error", **S),
     fohw.DimensionError, "the record has 11 samples for 11 parameters"),
    ("identify", "output_error from a given start on as many samples as parameters",
     lambda t: fohw.identify(U[:11], U[:11] ** 3, method="output_error",
                             start=fohw.identify(U, U**3, **S), **S),
     fohw.DimensionError, "the record has 11 samples for 11 parameters"),
    ("identify", "output_error whose n_init leaves fewer samples than parameters",
     lambda t: fohw.identify(U, U**3, method="output_error", n_init=42, **S),
     fohw.DimensionError, "the record has 8 samples after n_init = 42 for 11 parameters"),
    ("identify", "N = 3 with varpro (named an option the user never set)",
     lambda t: fohw.identify(U[:3], U[:3] ** 3, **S),
     fohw.DimensionError, "least squares needs more samples than parameters"),
    ("identify", "n_grid = 10**7 (a hang)",
     lambda t: fohw.identify(U, U**3, n_grid=10**7, **S),
     fohw.ParameterError, "`n_grid` must be at most 100000; got 10000000"),
    ("polynomial_basis", "degree 10**8 (a hang)", lambda t: fohw.polynomial_basis(10**8),
     fohw.ParameterError, "`degree` must be at most 100; got 100000000"),
    ("load_model", "'degree': 1e8 in the file (a hang)",
     lambda t: fohw.load_model(_model_file(t, f_basis={"kind": "polynomial", "degree": 1e8})),
     fohw.DataFileError, "'degree' must be an integer from 1 to 100; got 100000000.0"),
    ("load_model", "'degree': \"two\"",
     lambda t: fohw.load_model(_model_file(t, f_basis={"kind": "polynomial", "degree": "two"})),
     fohw.DataFileError, "'degree' must be an integer from 1 to 100; got 'two'"),
    ("load_model", "'f_basis': \"poly2\"",
     lambda t: fohw.load_model(_model_file(t, f_basis="poly2")),
     fohw.DataFileError, "field 'f_basis' must be an object such as"),
    ("load_model", "'degree': 2.7 (was read as 2)",
     lambda t: fohw.load_model(_model_file(t, f_basis={"kind": "polynomial", "degree": 2.7})),
     fohw.DataFileError, "'degree' must be an integer from 1 to 100; got 2.7"),
    ("load_model", "an unknown basis kind",
     lambda t: fohw.load_model(_model_file(t, f_basis={"kind": "spline"})),
     fohw.DataFileError, "has kind 'spline'; fohw writes 'polynomial' (a degree) or 'custom'"),
    ("load_model", "a custom basis not passed again",
     lambda t: fohw.load_model(_model_file(t, f_basis={"kind": "custom", "names": ["tanh"]})),
     fohw.ParameterError, "fohw.load_model(path, f_basis=...)"),
    ("load_model", "'version': \"1\" (a string)",
     lambda t: fohw.load_model(_model_file(t, version="1")),
     fohw.DataFileError, "field 'version' is the string '1'; this fohw reads fohw-model files of "
     "version 3, written as a JSON integer"),
    ("load_model", "#15/#17 a directory", lambda t: fohw.load_model(t),
     fohw.DataFileError, "is a directory, not a fohw JSON file"),
    ("load_result", "a NaN J", lambda t: fohw.load_result(_result_file(t, J=float("nan"))),
     fohw.DataFileError, "field 'J' must be a finite number >= 0; got nan"),
    ("load_result", "a NaN order",
     lambda t: fohw.load_result(_result_file(t, orders={"alpha": float("nan")})),
     fohw.DataFileError, "field 'orders' must be an object of finite numbers"),
    ("load_result", "an order outside [0, 2]",
     lambda t: fohw.load_result(_result_file(t, orders={"alpha": 2.5})),
     fohw.DataFileError, "field 'orders': order 'alpha' is 2.5, outside [0, 2]"),
    ("load_result", "a top-level alpha (not part of the format)",
     lambda t: fohw.load_result(_result_file(t, alpha=0.1)),
     fohw.DataFileError, "field 'alpha' is not part of a fohw-result file of version 3"),
    ("load_result", "input_range reversed",
     lambda t: fohw.load_result(_result_file(t, input_range=[1.0, -1.0])),
     fohw.DataFileError, "field 'input_range' is reversed ([1.0, -1.0])"),
    ("load_result", "an unknown method",
     lambda t: fohw.load_result(_result_file(t, method="magic")),
     fohw.DataFileError, "field 'method' must be one of fohw's methods"),
    ("load_result", "'status': \"yes\"",
     lambda t: fohw.load_result(_result_file(t, status="yes")),
     fohw.DataFileError, "field 'status' must be one of [-3, -2, -1, 0, 1, 2]"),
    ("load_result", "a NaN in theta",
     lambda t: fohw.load_result(_result_file(t, theta_0=float("nan"))),
     fohw.DataFileError, "field 'theta' holds a non-finite value (nan at entry 0)"),
    ("load_result", "a negative variance in the covariance",
     lambda t: fohw.load_result(_result_file(t, covariance_0=-1.0)),
     fohw.DataFileError, "field 'covariance' has a negative variance"),
    ("save_result", "a result holding NaN (the old file is kept)",
     lambda t: fohw.save_result(_nan_result(), t / "r.json"),
     fohw.ParameterError, "field 'J' is nan, and JSON holds finite numbers only; nothing was "
     "written"),
    ("save_result", "a directory as the file", lambda t: fohw.save_result(_result(), t),
     fohw.DataFileError, "is a directory; give a file name"),
    ("read_record", "';' columns with decimal commas, no decimal=','",
     lambda t: fohw.read_record(_bad_file(t, "u;y\n0,5;1,25\n-0,25;0,5\n", "r.csv")),
     fohw.DataFileError, "line 2: '0,5' is not a number (column 0). It looks like a decimal "
     "comma: pass decimal=','"),
    ("read_record", "decimal=',' on a comma-separated file (rows 1,2 would read as 1.2)",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n1,2\n3,4\n", "r.csv"), decimal=","),
     fohw.DataFileError, "line 1: the header 'u,y' is separated by commas, but decimal=',' "
     "makes commas decimal marks"),
    ("read_record", "two header lines",
     lambda t: fohw.read_record(_bad_file(t, "u,y\nV,m\n1,2\n3,4\n", "r.csv")),
     fohw.DataFileError, "line 2 looks like a second header line"),
    ("read_record", "an NA value",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n1,2\n3,NA\n4,5\n", "r.csv")),
     fohw.DataFileError, "line 3: column 'y' has 'NA', a missing value; fohw does not fill gaps"),
    ("metrics.fit_percent", "n_init leaves no samples",
     lambda t: fohw.analysis.metrics.fit_percent(Y, Y, n_init=49),
     fohw.DimensionError, "`n_init` must leave at least 2 samples"),
    # issue 26 (26lr)
    ("order_test", "a validation record without the estimation record",
     lambda t: fohw.order_test(_lr_fit("commensurate"), validation=(U, U ** 3)),
     fohw.ParameterError, "`validation` needs the estimation record too"),
    ("lr_test", "`restricted` not a result", lambda t: fohw.lr_test("x", _lr_fit("commensurate")),
     fohw.ParameterError, "`restricted` must be an IdentificationResult"),
    ("lr_test", "`full` from a recursive method",
     lambda t: fohw.lr_test(_lr_fit(0), _hybrid()),
     fohw.ParameterError, "`full` was fitted by method 'hybrid', which is not a least-squares"),
    ("lr_test", "not nested: other lags",
     lambda t: fohw.lr_test(_lr_fit(0, na=2), _lr_fit("commensurate")),
     fohw.ParameterError, "is not `full`"),
    ("lr_test", "the pair swapped", lambda t: fohw.lr_test(_lr_fit("commensurate"), _lr_fit(0)),
     fohw.ParameterError, "`restricted` must be the integer class"),
    ("lr_test", "other methods",
     lambda t: fohw.lr_test(_lr_fit(0, method="structured"), _lr_fit("commensurate")),
     fohw.ParameterError, "`restricted` and `full` must be fitted by the same method"),
    ("lr_test", "other records",
     lambda t: fohw.lr_test(_lr_fit(0, n=40), _lr_fit("commensurate")),
     fohw.ParameterError, "were not fitted to the same record: n_samples 40 and 50"),
    ("lr_test", "full's orders bounded away from 0",
     lambda t: fohw.lr_test(_lr_fit(0), _lr_fit("commensurate", alpha_bounds=(0.2, 1))),
     fohw.ParameterError, "is bounded below by 0.2, so orders 0 are not in its class"),
    ("lr_test", "unknown `reference`",
     lambda t: fohw.lr_test(_lr_fit(0), _lr_fit("commensurate"), reference="chi2"),
     fohw.ParameterError, "`reference` must be one of"),
    ("lr_test", "the mixture for the mixed class (alpha unidentified)",
     lambda t: fohw.lr_test(_lr_fit(0), _lr_fit("mixed"), reference="mixture"),
     fohw.ParameterError, "are not identified under the null"),
    ("lr_test", "bootstrap without the record",
     lambda t: fohw.lr_test(_lr_fit(0), _lr_fit("commensurate"), reference="bootstrap"),
     fohw.ParameterError, "pass `u` and `y`"),
    ("lr_test", "`u`, `y` of another record",
     lambda t: fohw.lr_test(_lr_fit(0), _lr_fit("commensurate"), u=U, y=U**2),
     fohw.ParameterError, "`u` and `y` are not the record `restricted` was fitted to"),
    ("profile_interval", "unknown order name",
     lambda t: fohw.profile_interval(_lr_fit("commensurate"), "beta", u=U, y=U**3),
     fohw.ParameterError, "`name` must be one of the free orders ['alpha']; got 'beta'"),
    ("profile_interval", "`level` 1.5",
     lambda t: fohw.profile_interval(_lr_fit("commensurate"), "alpha", 1.5, u=U, y=U**3),
     fohw.ParameterError, "`level`"),
    ("profile_interval", "without the record",
     lambda t: fohw.profile_interval(_lr_fit("commensurate"), "alpha"),
     fohw.ParameterError, "pass `u` and `y` (fohw's results keep no data)"),
    ("profile_interval", "a fit with every order fixed",
     lambda t: fohw.profile_interval(_lr_fit(0), "alpha", u=U, y=U**3),
     fohw.ParameterError, "`name` must be one of the free orders []"),
    # issue 28 (28a)
    ("read_record", "a last line without its line end (a file cut mid-number)",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n1,2\n3,0.12", "r.csv")),
     fohw.DataFileError, "the last line has no line end, so it may have been cut"),
    ("read_record", "neither a path nor a file object",
     lambda t: fohw.read_record(3), fohw.ParameterError,
     "`path` must be a file path (str, bytes or os.PathLike) or a file object with read()"),
    ("read_record", "`dt` naming a signal column",
     lambda t: fohw.read_record(_bad_file(t, "u,y,Ts\n1,2,4\n3,4,\n", "r.csv"), dt="u"),
     fohw.ParameterError, "`dt` = 'u' names a signal column"),
    ("read_record", "a header naming a column twice (u,u,y)",
     lambda t: fohw.read_record(_bad_file(t, "u,u,y\n1,2,3\n4,5,6\n", "r.csv")),
     fohw.DataFileError, "the header on line 1 names 'u' twice (columns 0 and 1)"),
    ("read_record", "an extra field on line 11",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n" + "1,2\n" * 9 + "1,2,3\n", "r.csv")),
     fohw.DataFileError, "line 11 has 3 field(s) but the header on line 1 has 2: an extra field"),
    ("read_record", "a thousands separator (0.5,1,234.5) on line 6",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n" + "1,2\n" * 4 + "0.5,1,234.5\n", "r.csv")),
     fohw.DataFileError, "line 6 has 3 field(s)"),
    ("read_record", "a short row on line 4",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n1,2\n3,4\n5\n6,7\n", "r.csv")),
     fohw.DataFileError, "line 4 has 1 field(s) but the header on line 1 has 2: a missing field"),
    ("read_record", "a header-less comma file with decimal=','",
     lambda t: fohw.read_record(_bad_file(t, "0.5,1.25\n0.25,0.5\n", "r.csv"), decimal=","),
     fohw.DataFileError, "line 1: '0.5,1.25' holds numbers separated by commas"),
    ("read_record", "a 'u,y' header above ';' data",
     lambda t: fohw.read_record(_bad_file(t, "u,y\n1;2\n3;4\n", "r.csv")),
     fohw.DataFileError, "line 2 is separated by ';' but the header on line 1 by ','"),
    # issue 28 (tf2)
    ("FractionalHW", "p[0] is not 1 (the gain is G's)",
     lambda t: fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0], [0.0]), p=[2.0]),
     fohw.ParameterError, "`p[0]` must be exactly 1"),
    ("FractionalHW", "an output map as a (kind, values) tuple",
     lambda t: fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0], [0.0]),
                                 output_map=("saturation", [1.0, 0.0])),
     fohw.ParameterError, "`output_map` must be None, one of"),
    ("FractionalHW", "a saturation without its limits",
     lambda t: fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0], [0.0]),
                                 output_map="saturation"),
     fohw.ParameterError, "`output_params`: the saturation(lower=free, upper=free) has no default"),
    ("fit", "a FractionalHW without a sampling time",
     lambda t: fohw.fit(fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])),
                        np.arange(50.0), np.arange(50.0)),
     fohw.ParameterError, "`dt` is needed"),
    ("register_model", "a class that is not a fohw.Model",
     lambda t: fohw.register_model(int),
     fohw.ParameterError, "register_model takes a subclass of fohw.Model; got <class 'int'>"),
    ("fit", "a FractionalHW on a constant output",
     lambda t: fohw.fit(fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]),
                                          dt=0.1), np.arange(50.0), np.ones(50)),
     fohw.ParameterError, "`y` is constant"),
    # issue 28 (28b)
    ("select_structure", "an empty grid {}",
     lambda t: fohw.select_structure(U, U**3, {}, na=1, f_basis=1, g_basis=1),
     fohw.ParameterError, "`candidates` is an empty grid {}"),
    ("select_structure", "a misspelt keyword",
     lambda t: fohw.select_structure(U, U**3, {"naa": [1, 2]}, f_basis=1, g_basis=1),
     fohw.ParameterError, "`candidates[0]` gives 'naa': not a keyword of fohw.identify; did "
     "you mean 'na'?"),
    ("select_structure", "an unknown method",
     lambda t: fohw.select_structure(U, U**3, {"na": [1]}, f_basis=1, g_basis=1,
                                     method="nope"),
     fohw.ParameterError, "`method` must be one of"),
    ("select_structure", "a required keyword missing from every candidate",
     lambda t: fohw.select_structure(U, U**3, {"na": [1, 2]}, f_basis=1),
     fohw.ParameterError, "`g_basis` is required by fohw.identify and missing from every "
     "candidate"),
    ("select_structure", "validation=1 (an int: one sample held back)",
     lambda t: fohw.select_structure(U, U**3, {"na": [1]}, f_basis=1, g_basis=1,
                                     validation=1),
     fohw.ParameterError, "`validation` = 1 (an int: a number of samples) holds back 1 of 50"),
    ("select_structure", "a constant held-back output, ranked by fit %",
     lambda t: fohw.select_structure(U, np.r_[U[:40], np.zeros(10)], {"na": [1]}, f_basis=1,
                                     g_basis=1, validation=10),
     fohw.ParameterError, "is constant (0.0): no candidate can be ranked by its fit %"),
    ("compare", "not a result or a model",
     lambda t: fohw.compare("model.json", U, U),
     fohw.ParameterError, "`model` must be an identification result (fohw.identify), a "
     "fohw.HammersteinWiener or a fohw.ThetaHW; got str"),
    ("compare", "a record of one sample",
     lambda t: fohw.compare(fohw.identify(U, U**3, na=1, nb=1, f_basis=1, g_basis=1), U[:1],
                            U[:1]),
     fohw.DimensionError, "the record has 1 sample (`u` and `y`); compare needs at least 2"),
    # issue 28 (28c)
    ("identify", "u * 1e-150 with f_basis=3 (was AttributeError)",
     lambda t: fohw.identify(_PAPER16.u * 1e-150, _PAPER16.y * 1e20, na=1, nb=2, f_basis=3,
                             g_basis=1, past="estimate"),
     fohw.ParameterError, "basis function 'x^3' of `u` underflows"),
    ("identify", "u * 1e100, y * 1e-100 (was scipy's 'array must not contain infs')",
     lambda t: fohw.identify(_PAPER16.u * 1e100, _PAPER16.y * 1e-100, na=1, nb=2, f_basis=3,
                             g_basis=1),
     fohw.ParameterError, "the parameter 'p3b1' would be about 1e-401"),
    ("gl_difference", "h**-alpha overflows (was OverflowError)",
     lambda t: fohw.gl_difference(np.ones(10), 2.0, h=1e-300),
     fohw.ParameterError, "`h` = 1e-300 with the order 2.0 gives the scale h**-order = 10**600"),
    ("gl_weights", "n = 10**12 (was MemoryError)",
     lambda t: fohw.gl_weights(0.5, 10**12),
     fohw.ParameterError, "`n` = 1000000000000 needs 8 TB of memory"),
    ("identify", "a masked array with masked samples (they were fitted)",
     lambda t: fohw.identify(np.ma.masked_array(U, mask=U > 0.9), U**3, **S),
     fohw.ParameterError, "`u` is a masked array with"),
    ("identify", "datetime64 samples (read as seconds since 1970)",
     lambda t: fohw.identify(np.arange(50).astype("datetime64[s]"), U, **S),
     fohw.ParameterError, "`u` must be an array of real numbers; got datetime64[s] values"),
    ("information_matrix", "alpha = -1 (was accepted)",
     lambda t: fohw.model.lagged.regressors.information_matrix(U, U, -1.0, **S),
     fohw.ParameterError, "`alpha` must be in [0, 2]; got -1.0"),
    ("load_result", "an extra order key (was refused at simulate time)",
     lambda t: fohw.load_result(_result_file(t, orders={"alpha": 0.5, "beta": 0.5})),
     fohw.DataFileError, "field 'orders' gives the orders ['alpha', 'beta'], but field "
     "'structure' has the free orders ['alpha']"),
    ("load_result", "an order outside the run's alpha_bounds",
     lambda t: fohw.load_result(_result_file(t, orders={"alpha": 1.5})),
     fohw.DataFileError, "outside field 'options.alpha_bounds' = [0.0, 1.0]"),
    ("load_result", "a schedule the method does not have",
     lambda t: fohw.load_result(_result_file(t, schedule="recursive")),
     fohw.DataFileError, "field 'schedule' is 'recursive', but method 'varpro' has no schedule"),
    # issue 24 (initial)
    ("IdentificationResult.simulate", "a past='estimate' fit without `initial`",
     lambda t: _past_result().simulate(U), fohw.ParameterError,
     "its levels (u_past, y_past) = (0.508501, 0.737396) are those before the *estimation* "
     "record"),
    ("compare", "a past='estimate' fit without `initial`",
     lambda t: fohw.compare(_past_result(), U, U**3), fohw.ParameterError,
     "Say which initial state to start from: initial='fitted'"),
    ("IdentificationResult.simulate", "initial='estimate' without `y`",
     lambda t: _result().simulate(U, initial="estimate"), fohw.ParameterError,
     "initial='estimate' fits the record's initial state to its output: pass the measured "
     "output as `y`"),
    ("IdentificationResult.simulate", "`y` with initial='rest' (it would be ignored)",
     lambda t: _result().simulate(U, initial="rest", y=U**3), fohw.ParameterError,
     "`y` is used only by initial='estimate'"),
    ("initial_state", "initial=('estimate', 2) on a record of 4 samples (4 unknowns)",
     lambda t: fohw.initial_state(_result(), U[:4], Y[:4], ("estimate", 2)),
     fohw.DimensionError, "fits 4 unknowns (u_past, y_past and 2 past outputs) to the record's "
     "output, which has 4 sample(s): it needs more samples than unknowns"),
    ("compare", "initial='estimate' on a record of 2 samples",
     lambda t: fohw.compare(_result(), U[:2], Y[:2], initial="estimate"),
     fohw.DimensionError, "fits 2 unknowns (u_past, y_past) to the record's output, which has "
     "2 sample(s)"),
    ("compare", "an unknown initial state 'zero'",
     lambda t: fohw.compare(_result(), U, Y, initial="zero"), fohw.ParameterError,
     "`initial` must be one of ('rest', 'fitted', 'estimate'), ('estimate', n), (u_hist, "
     "y_hist) or an InitialState; got 'zero'"),
    ("IdentificationResult.simulate", "initial=('estimate', -1)",
     lambda t: _result().simulate(U, initial=("estimate", -1), y=Y), fohw.ParameterError,
     "must be ('estimate', n), n >= 0 free past output samples; got ('estimate', -1)"),
    ("IdentificationResult.simulate", "a history whose u and y differ in length",
     lambda t: _result().simulate(U, initial=(U[:5], U[:4])), fohw.DimensionError,
     "`initial history u` and `initial history y` must have the same length; got 5 and 4"),
    ("IdentificationResult.simulate", "a history of shape (5, 2)",
     lambda t: _result().simulate(U, initial=(np.ones((5, 2)), np.ones(5))),
     fohw.DimensionError, "`initial history u` must be 1-D; got an array of shape (5x2)"),
    ("IdentificationResult.simulate", "initial=3 (neither a choice nor a history)",
     lambda t: _result().simulate(U, initial=3), fohw.ParameterError,
     "`initial` must be one of ('rest', 'fitted', 'estimate'), ('estimate', n), a measured "
     "history (u_hist, y_hist) or an InitialState; got 3"),
    ("compare", "`history=` (the measured history is `initial=(u_past, y_past)`)",
     lambda t: fohw.compare(_result(), U, Y, history=(U, Y)),
     TypeError, "unexpected keyword argument 'history'"),
    ("simulate", "a named initial state with a HammersteinWiener (it carries its own levels)",
     lambda t: fohw.simulate(M(), U, initial="rest"), fohw.ParameterError,
     "belong to an identification result"),
    # issue 24 (outmap)
    ("identify", "output_map: saturation limits out of order",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                             output_map=fohw.model.output_map.Saturation(lower=2.0, upper=1.0)),
     fohw.ParameterError, "the saturation limits must satisfy lower < upper; got lower = 2.0"),
    ("identify", "output_map: a dead zone wider than the data",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                             output_map=fohw.model.output_map.DeadZone(lower=-5.0, upper=5.0)),
     fohw.ParameterError, "is wider than the data"),
    ("identify", "output_map: an unknown name",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                             output_map="saturate"),
     fohw.ParameterError, "`output_map` must be None, one of ('saturation', 'deadzone', "
     "'piecewise_linear'), an int (a polynomial degree) or a SeriesMap; got 'saturate'"),
    ("identify", "output_map: polynomial degree 0",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                             output_map=0),
     fohw.ParameterError, "`output_map` as a polynomial degree must be at least 1; got 0"),
    ("identify", "output_map with an equation-error method",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, output_map="saturation"),
     fohw.ParameterError, "method 'varpro' cannot fit a series `output_map`"),
    ("identify", "output_map: fixed saturation limits that leave the data at one limit",
     lambda t: fohw.identify(U, U, na=1, nb=1, f_basis=1, g_basis=1, method="output_error",
                             output_map=fohw.model.output_map.Saturation(lower=3.0)),
     fohw.ParameterError, "entirely at one limit"),
    ("simulate", "output_map without an inverse and a measured history",
     lambda t: fohw.simulate(fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1, output_map=3),
                             U, params=[0.5, 1.0, 0.4, 0.0, 0.0], initial=(U, U)),
     fohw.ParameterError, "has no inverse"),
    ("PolynomialMap", "monotone with an even degree",
     lambda t: fohw.model.output_map.PolynomialMap(4, monotone=True), fohw.ParameterError,
     "a monotone polynomial output map has an odd degree"),
    # issue 24 (nk)
    ("identify", "nk = -1",
     lambda t: fohw.identify(U, U, nk=-1, **S), fohw.ParameterError,
     "`nk` (the input delay in samples) must be an integer >= 0 (0: direct feedthrough); got -1"),
    ("identify", "nk = 1.5",
     lambda t: fohw.identify(U, U, nk=1.5, **S), fohw.ParameterError,
     "`nk` (the input delay in samples) must be an integer >= 0 (0: direct feedthrough); got 1.5"),
    ("identify", "nk = True (a bool is not a delay)",
     lambda t: fohw.identify(U, U, nk=True, **S), fohw.ParameterError,
     "must be an integer >= 0 (0: direct feedthrough); got True"),
    ("identify", "nk = '0' (a string)",
     lambda t: fohw.identify(U, U, nk="0", **S), fohw.ParameterError,
     "must be an integer >= 0 (0: direct feedthrough); got '0'"),
    ("identify", "nk = 49 on a record of 50 samples with nb = 2",
     lambda t: fohw.identify(U, U, nk=49, **S), fohw.DimensionError,
     "na=2, nb=2, nk=49 (need at least 51)"),
    ("identify", "orders with input lags from 0, but nk left at 1",
     lambda t: fohw.identify(U, U, orders=fohw.Orders.preset("commensurate", na=2, nb=2, nk=0),
                             **S), fohw.ParameterError,
     "input lags 0..1, but na = 2, nb = 2 and nk = 1"),
    ("identify", "method='hybrid' with nk = 0 (the paper's model has nk = 1)",
     lambda t: fohw.identify(U, U, nk=0, method="hybrid", **S), fohw.ParameterError,
     "method 'hybrid' implements the paper's commensurate model"),
    ("Orders", "an output term at lag 0",
     lambda t: fohw.Orders([(0, "alpha")], [(0, "alpha")]), fohw.ParameterError,
     "the lag of term 0 of branch 'a' must be an integer >= 1; got 0"),
    ("HammersteinWiener", "nk = -2",
     lambda t: fohw.HammersteinWiener([0.1], [1.0], [1.0], [1.0], 0.5, nk=-2),
     fohw.ParameterError, "`nk` (the input delay in samples) must be an integer >= 0"),
    # issue 24 (miso)
    ("identify", "u with 2 columns, nb with 3 entries",
     lambda t: fohw.identify(_U2, U, na=2, nb=[2, 2, 2], f_basis=1, g_basis=1),
     fohw.DimensionError, "`nb` gives 3 value(s), one per input, but there are 2 input(s) "
     "(columns of `u`)"),
    ("identify", "u with 2 columns, nk with 3 entries",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, nk=[0, 1, 1], f_basis=1, g_basis=1),
     fohw.DimensionError, "`nk` gives 3 value(s), one per input, but there are 2 input(s)"),
    ("identify", "u with 2 columns, f_basis with 3 entries",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=[2, 1, 1], g_basis=1),
     fohw.DimensionError, "`f_basis` gives 3 bases (one per input), but there are 2 inputs"),
    ("identify", "1-D u, nb with 2 entries",
     lambda t: fohw.identify(U, U, na=2, nb=[2, 2], f_basis=1, g_basis=1),
     fohw.DimensionError, "`nb` gives 2 value(s), one per input, but there is 1 input(s)"),
    ("identify", "1-D u, f_basis with 2 degrees",
     lambda t: fohw.identify(U, U, na=2, nb=2, f_basis=[2, 1], g_basis=1),
     fohw.DimensionError, "`f_basis` gives 2 bases (one per input), but `u` has 1 column"),
    ("identify", "method='rls' with 2 inputs",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=1, g_basis=1, method="rls"),
     fohw.ParameterError, "implements the paper's single-input model; `u` has 2 columns"),
    ("identify", "past='estimate' with 2 inputs",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=1, g_basis=1, past="estimate"),
     fohw.ParameterError, "`past` = 'estimate' is for a single input"),
    ("identify", "inputs naming 1 of 2 columns",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=1, g_basis=1, inputs=("a",)),
     fohw.DimensionError, "`inputs` must name the 2 columns of `u`; got ('a',)"),
    ("identify", "an input name with a dot",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=1, g_basis=1, inputs=("a.b", "c")),
     fohw.ParameterError, "each input's name is a non-empty string without '.'; got 'a.b'"),
    ("identify", "operating_point with 3 input levels for 2 inputs",
     lambda t: fohw.identify(_U2, U, na=2, nb=2, f_basis=1, g_basis=1,
                             operating_point=((1.0, 2.0, 3.0), 0.0)),
     fohw.DimensionError, "`operating_point[0]` must give 2 input levels (one per input); got 3"),
    ("simulate", "a 2-input structure, 1-D u",
     lambda t: fohw.simulate(fohw.Structure.make(na=1, nb=1, f_basis=1, g_basis=1,
                                                 inputs=("a", "b")), U,
                             params=[0.1, 1.0, 1.0, 0.5]),
     fohw.DimensionError, "`u` must be 2-D"),
    # issue 27 (battery)
    ("ZARC", "an order above 1 (the element would be a resonance, not a ZARC)",
     lambda t: fohw.ZARC(0.01, 10.0, 1.2), fohw.ParameterError, "`alpha` must be in (0, 1]"),
    ("Warburg", "order 1 (a capacitor: the b soc term already)",
     lambda t: fohw.Warburg(0.01, 1.0), fohw.ParameterError, "`alpha` must be in (0, 1)"),
    ("EquivalentCircuit", "an unknown element kind",
     lambda t: fohw.EquivalentCircuit(["cpe"], r0=0.01), fohw.ParameterError,
     "`elements[0]` must be an RC, ZARC or Warburg element or one of rc, zarc, warburg; got 'cpe'"),
    ("EquivalentCircuit", "tau bounds reversed",
     lambda t: fohw.EquivalentCircuit(["rc"], tau_bounds=(100.0, 1.0)), fohw.ParameterError,
     "`tau_bounds` must be increasing with 0 < low"),
    ("EquivalentCircuit.simulate", "current and state of charge not as two columns",
     lambda t: fohw.EquivalentCircuit(["rc"]).simulate(U), fohw.DimensionError, "`u` must be 2-D"),
    ("EquivalentCircuit.to_dict", "an OCV given as a Python function",
     lambda t: fohw.EquivalentCircuit(["rc"], ocv=np.sqrt).to_dict(), fohw.ParameterError,
     "cannot be written to a file; build the circuit with a tabulated OCV"),
    ("OCVTable", "states of charge not increasing",
     lambda t: fohw.OCVTable([0.0, 0.5, 0.4], [3.0, 3.5, 3.6]), fohw.ParameterError,
     "`soc` of an OCVTable must increase strictly; got 0.5 then 0.4"),
    ("fit", "a circuit's record with zero current",
     lambda t: fohw.fit(fohw.EquivalentCircuit(["rc"]), np.column_stack([0 * U, 0.5 + 0 * U]), U),
     fohw.ParameterError, "the current `u[:, 0]` is zero at every sample"),
    ("fit", "sample weights all zero",
     lambda t: fohw.fit(fohw.EquivalentCircuit(["rc"]), np.column_stack([U, 0.5 + 0 * U]), U,
                        sample_weight=0 * U),
     fohw.ParameterError, "`sample_weight` must be non-negative with at least one positive entry"),
    ("lr_test", "circuit fits to two records",
     lambda t: fohw.lr_test(_circuit_fit(_SOC[::-1].copy(), b=0.0), _circuit_fit()),
     fohw.ParameterError, "`restricted` and `full` were not fitted to the same record"),
    ("lr_test", "circuit fits at two step sizes",
     lambda t: fohw.lr_test(_circuit_fit(dt=2.0, b=0.0), _circuit_fit()), fohw.ParameterError,
     "`restricted` and `full` were fitted at different step sizes (dt 2.0 and 1.0)"),
    ("lr_test", "an effective sample size above the samples",
     lambda t: fohw.lr_test(_circuit_fit(b=0.0), _circuit_fit(), n_effective=60),
     fohw.ParameterError, "`n_effective` must be at most the 50 samples of the criterion"),
    ("profile_interval", "a circuit fit and half its record",
     lambda t: fohw.profile_interval(_circuit_fit(), "R0", u=_circuit_u()[:25], y=U[:25]),
     fohw.ParameterError, "`u` and `y` have 25 samples, but `result` was fitted to 50"),
    ("profile_interval", "an order the circuit does not have",
     lambda t: fohw.profile_interval(_circuit_fit(), "alpha1", u=_circuit_u(), y=U),
     fohw.ParameterError, "`name` must be one of the free parameters ['a', 'b', 'R0'] of the "
     "EquivalentCircuit fit; got 'alpha1'"),
    ("circuit.impedance_error", "a NaN in the measured spectrum",
     lambda t: impedance_error(fohw.EquivalentCircuit([]), [1.0, 2.0], [1.0, np.nan]),
     fohw.ParameterError, "`z` must be finite and non-zero at every frequency"),
    ("circuit.impedance_error", "a fit of another kind (a fit of a circuit is scored)",
     lambda t: impedance_error(_result(), [1.0, 2.0], [1.0, 1.0]), fohw.ParameterError,
     "`circuit` must be an EquivalentCircuit or a fohw.fit result of one; got "
     "IdentificationResult"),
    ("register_model", "a class that is not a fohw.Model",
     lambda t: fohw.register_model(dict), fohw.ParameterError,
     "register_model takes a subclass of fohw.Model; got <class 'dict'>"),
    ("metrics.effective_samples", "constant residuals",
     lambda t: effective_samples(np.zeros(50)), fohw.ParameterError,
     "`residuals` are constant (0.0 at all 50 samples)"),
    ("BatteryCell.ocv", "a state of charge above 1",
     lambda t: fohw.datasets.battery_cell().ocv(1.2), fohw.ParameterError,
     "`soc` must be in [0, 1]"),
    # issue 34 (io): transfer functions #1-6, circuits #21 and the rest of their class
    ("FractionalTF", "a denominator order of 1e6 (was OverflowError in simulate)",
     lambda t: fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1e6, 0.0]), fohw.ParameterError,
     "`den_orders` must lie in [0, 20]; got 1000000.0 at index 0"),
    ("FractionalTF", "a numerator order of -25",
     lambda t: fohw.FractionalTF([1.0], [-25.0], [1.0, 1.0], [0.5, 0.0]), fohw.ParameterError,
     "`num_orders` must lie in [-20, 20]; got -25.0 at index 0"),
    ("FractionalTF.frequency_response", "a string (the error did not name omega)",
     lambda t: _G34.frequency_response(["a"]), fohw.ParameterError,
     "`omega` must be an array of real numbers; got an array of strings"),
    ("FractionalTF.frequency_response", "omega = 0 at a pole at s = 0 (was inf+nanj)",
     lambda t: fohw.FractionalTF([1.0], [0.0], [1.0], [0.5]).frequency_response([0.0, 1.0]),
     fohw.ParameterError, "`omega` = 0.0 (index 0): G has a pole at s = 0 (dcgain = inf, G ~ s^-0.5"),
    ("FractionalTF.frequency_response", "a NaN frequency (was returned as NaN)",
     lambda t: _G34.frequency_response([np.nan, 1.0]), fohw.ParameterError,
     "`omega` must contain only finite values"),
    ("FractionalTF.discrete_frequency_response", "an infinite frequency",
     lambda t: _G34.discrete_frequency_response([np.inf], dt=0.1), fohw.ParameterError,
     "`omega` must contain only finite values"),
    ("FractionalTF.oustaloup", "a band of 600 decades (its response was nan+nanj)",
     lambda t: _G34.oustaloup(band=(1e-300, 1e300)), fohw.ParameterError,
     "`band` = (1e-300, 1e+300) spans 600 decades: with order N = 5 the approximation cannot be "
     "represented in double precision"),
    ("FractionalTF.oustaloup", "a band of 60 decades (finite coefficients, response not)",
     lambda t: _G34.oustaloup(band=(1e-30, 1e30)), fohw.ParameterError,
     "(its response in the band is not finite)"),
    ("FractionalTF.oustaloup", "order = 10**6 (np.poly of 2e6 roots, a hang)",
     lambda t: _G34.oustaloup(order=10**6), fohw.ParameterError,
     "`order` must be an integer from 1 to 100; got 1000000"),
    ("OustaloupApproximation.frequency_response", "a NaN frequency",
     lambda t: _G34.oustaloup().frequency_response([np.nan]), fohw.ParameterError,
     "`omega` must contain only finite values"),
    ("OustaloupApproximation.errors", "points_per_decade = 10**9 (a hang)",
     lambda t: _G34.oustaloup().errors(points_per_decade=10**9), fohw.ParameterError,
     "`points_per_decade` must be at most 10000"),
    ("FractionalTF.simulate", "an unstable improper model with a delay (was 1e51, "
     "unchecked)",
     lambda t: fohw.FractionalTF([1.0, 2.0], [1.7, 0.3], [1.0, -3.0], [0.4, 0.0], delay=0.3)
     .simulate(np.random.default_rng(1).standard_normal(200), dt=0.1),
     fohw.SimulationDivergedError, "diverged at sample k = 39"),
    ("FractionalTF.is_stable", "fuzz: a coefficient of 1e-143 (was a RuntimeWarning "
     "or OverflowError)",
     lambda t: fohw.FractionalTF([1.0], [0.0], [1.0, 1.26e-143], [0.4140625, 0.0]).is_stable(),
     fohw.ParameterError, "the argument principle needs the frequencies 10**-360.3"),
    ("FractionalTF.default_frequencies", "n = 10**9 (a grid without a cap)",
     lambda t: _G34.default_frequencies(10**9), fohw.ParameterError, "`n` must be at most 1000000"),
    ("model.frequency_response.gl_operator_response", "a NaN frequency (the kernel)",
     lambda t: fohw.model.frequency_response.gl_operator_response([1.0], [0.5], [np.nan], 0.1),
     fohw.ParameterError, "`omega` must contain only finite values"),
    ("FractionalHW.frequency_response", "a NaN frequency",
     lambda t: fohw.FractionalHW(_G34).frequency_response([1.0, np.nan]), fohw.ParameterError,
     "`omega` must contain only finite values; got np.float64(nan) at index 1"),
    ("LinearBlock.frequency_response", "omega = 0 of an integrator (was inf+nanj)",
     lambda t: fohw.model.lagged.hw_frequency.LinearBlock([1.0], [1.0], [(1, 0.0)], [(1, 0.0)], dt=1.0)
     .frequency_response([0.0, 1.0]), fohw.ParameterError,
     "`omega` = 0.0: the block's response is infinite there"),
    ("EquivalentCircuit.impedance", "a NaN frequency (was NaN with a RuntimeWarning)",
     lambda t: _CIRC34.impedance(np.array([np.nan, 1.0])), fohw.ParameterError,
     "`f` must contain only finite values"),
    ("EquivalentCircuit.impedance", "f = 0 with capacity= (was inf with a RuntimeWarning)",
     lambda t: _CIRC34.impedance([0.0, 1.0], capacity=5.0), fohw.ParameterError,
     "`f` = 0.0 (index 0): the impedance of the open-circuit voltage (capacity=) is infinite"),
    ("EquivalentCircuit.frequency_response", "omega = 0 with capacity= (infinite there)",
     lambda t: _CIRC34.frequency_response([0.0, 1.0], capacity=5.0), fohw.ParameterError,
     "`omega` = 2 pi f: `f` = 0.0 (index 0): the impedance of the open-circuit voltage"),
    ("CircuitTables.frequency_response", "tables over two SOC points, no `soc`",
     lambda t: fohw.CircuitTables(["rc"], soc_points=[0.2, 0.8], temperature_points=[25.0])
     .frequency_response([1.0]), fohw.ParameterError,
     "the tables of this CircuitTables vary with `soc` (breakpoints [0.2, 0.8])"),
    ("bode", "a string for the system",
     lambda t: fohw.bode("G"), fohw.ParameterError,
     "`system` must be a fohw.Model, a fit result or an object with a frequency_response(omega); "
     "got str"),
    ("nyquist", "a kind without a frequency response (a Model's default hook)",
     lambda t: fohw.nyquist(_NoResponse()), fohw.ParameterError,
     "a _NoResponse has no frequency response"),
    ("identify", "a fixed dead zone entirely above the data (was fitted, converged)",
     lambda t: fohw.identify(_PAPER100.u, _PAPER100.y, **S, method="output_error",
                             output_map=fohw.model.output_map.DeadZone(100.0, 200.0)),
     fohw.ParameterError, "`output_map` deadzone(lower=100, upper=200) lies entirely above the "
     "measured output"),
    ("identify", "a dead zone with one fixed end below the data",
     lambda t: fohw.identify(_PAPER100.u, _PAPER100.y, **S, method="output_error",
                             output_map=fohw.model.output_map.DeadZone(None, -50.0)),
     fohw.ParameterError, "lies entirely below the measured output"),
    ("identify", "fixed piecewise-linear breakpoints all above the data",
     lambda t: fohw.identify(_PAPER100.u, _PAPER100.y, **S, method="output_error",
                             output_map=fohw.model.output_map.PiecewiseLinear([10.0, 20.0, 30.0])),
     fohw.ParameterError, "has every breakpoint above the measured output"),
    ("datasets.battery_cell", "the shipped file replaced by a folder (was "
     "IsADirectoryError)", lambda t: _shipped_as(t, "folder"), fohw.DataFileError,
     "is a directory, not a data file. The installed fohw is damaged; reinstall it."),
    ("datasets.battery_cell", "the shipped file a link to /dev/zero (the checksum "
     "read forever)", lambda t: _shipped_as(t, "/dev/zero"), fohw.DataFileError,
     "(a symbolic link to '/dev/zero') is a character device, not a regular file"),
    ("datasets.battery_cell", "the shipped file longer than 64 MiB (read whole)",
     lambda t: _shipped_as(t, "long"), fohw.DataFileError,
     "longer than 67108864 bytes (read so far), so not the published file"),
    ("datasets.load_daisy", "a link to /dev/zero (was 'not found')",
     lambda t: fohw.datasets.load_daisy(_link(t, "/dev/zero")), fohw.DataFileError,
     "is a character device, not a regular file"),
    ("read_record", "a FIFO (the read never ended)",
     lambda t: fohw.read_record(os.mkfifo(t / "f.dat") or t / "f.dat"), fohw.DataFileError,
     "is a FIFO, not a regular file; fohw reads a data file only from a regular file"),
    ("load_result", "a link to /dev/zero (the read never ended)",
     lambda t: fohw.load_result(_link(t, "/dev/zero")), fohw.DataFileError,
     "is a character device, not a regular file; fohw reads a fohw JSON file only"),
    ("identify", "u of shape (50, 0) (was IndexError)",
     lambda t: fohw.identify(np.empty((50, 0)), U, **S), fohw.DimensionError,
     "`u` has no columns (shape (50x0)): give one column per input"),
    ("compare", "u of shape (100, 0) for a 2-input fit",
     lambda t: fohw.compare(_two_inputs(), np.empty((100, 0)), _PAPER100.y), fohw.DimensionError,
     "`u` has no columns (shape (100x0))"),
    ("IdentificationResult.simulate", "a DataFrame whose columns are not the fit's "
     "inputs (matched by position)",
     lambda t: _two_inputs().simulate(pytest.importorskip("pandas").DataFrame(
         _U2_100, columns=["x", "a"])), fohw.DimensionError,
     "`u` is a DataFrame with the columns ['x', 'a'], but the model's inputs are ['a', 'b']"),
    ("IdentificationResult.simulate", "initial={'u': ..., 'y': ...} (its keys were read "
     "as data)",
     lambda t: _result().simulate(U, initial={"u": U[:10], "y": U[:10]}), fohw.ParameterError,
     "`initial` must be the pair (u_hist, y_hist); got a dict with the keys ['u', 'y']"),
    ("simulate", "initial={'u': ..., 'y': ...} for a model",
     lambda t: fohw.simulate(M(), U, initial={"u": U[:10], "y": U[:10]}), fohw.ParameterError,
     "`initial` must be the pair (u_past, y_past) of measured records; got a dict"),
    ("identify", "operating_point={'u': 0, 'y': 0}",
     lambda t: fohw.identify(U, U**3, na=1, nb=1, f_basis=1, g_basis=1,
                             operating_point={"u": 0.0, "y": 0.0}), fohw.ParameterError,
     "`operating_point` must be the pair (u0, y0); got a dict with the keys ['u', 'y']"),
    ("HammersteinWiener", "past={0.1: 'a', 0.2: 'b'} (its keys were read as levels)",
     lambda t: fohw.HammersteinWiener([0.1], [1.0], [1.0], [1.0], 0.5, past={0.1: "a", 0.2: "b"}),
     fohw.ParameterError, "`past` must be the pair of numbers (a, b); got a dict"),
    ("FractionalTF.oustaloup", "band={1e-2: ..., 1e2: ...} (its keys were read as the band)",
     lambda t: _G34.oustaloup(band={1e-2: "low", 1e2: "high"}), fohw.ParameterError,
     "`band` must be the pair (omega_b, omega_h); got a dict"),
    ("lr_test", "an output map on one side only (LR with df 3, p from 1 order)",
     lambda t: fohw.lr_test(_lr_fit(0, method="output_error"),
                            _lr_fit("commensurate", method="output_error", output_map="saturation")),
     fohw.ParameterError, "`restricted` (output map none) and `full` (output map saturation(lower=free, "
     "upper=free)) differ beyond their orders"),
    ("load_result", "3 input levels in a 2-input result (the error named input_range)",
     lambda t: fohw.load_result(_two_input_file(t, operating_point=[[0.0, 0.0, 0.0], 0.0])),
     fohw.DataFileError, "field 'operating_point' gives 3 input levels but field 'input_range' "
     "gives 2 inputs"),
    ("IdentificationResult.simulate", "a result file with theta x 1e300 (was 'sqrt or "
     "log of a negative value')",
     lambda t: fohw.load_result(_two_input_file(t, theta=1e300)).simulate(_U2_100),
     fohw.SimulationDivergedError, "the output basis g overflowed at sample k = 1"),
    ("monte_carlo", "n_jobs=1000 (more workers than processors)",
     lambda t: fohw.monte_carlo({"v": {"method": "varpro"}}, seeds=range(1), n_jobs=1000),
     fohw.ParameterError, "`n_jobs` must be from 1 to"),
    ("end_with_parent", "poll = 0 seconds",
     lambda t: fohw.analysis.batch.end_with_parent(poll=0), fohw.ParameterError,
     "`poll` must be a number of seconds in (0, 60]; got 0"),
    ("Warburg.impedance", "f = 0 (was inf+nanj)",
     lambda t: fohw.Warburg(0.01, 0.5).impedance([0.0]), fohw.ParameterError,
     "the impedance of a Warburg element is infinite there"),
    # issue 34 (fits): transfer functions and FractionalHW #7-#13, circuits #15-#20
    ("fit", "a FractionalHW on a zero input (#8)",
     lambda t: fohw.fit(fohw.FractionalHW(_G34, dt=0.1), np.zeros(50), U), fohw.ParameterError,
     "`u` is zero at every sample"),
    ("fit", "data scaled by 1e-200 (#9: was garbage marked converged)",
     lambda t: fohw.fit(_TF, U * 1e-200, U**3 * 1e-200), fohw.ParameterError,
     "`u` has magnitudes near 9.95e-201, outside [1e-150, 1e+150]"),
    ("fit", "data scaled by 1e200 (#10: was 'give starts or bounds')",
     lambda t: fohw.fit(_TF, U * 1e200, U**3 * 1e200), fohw.ParameterError,
     "rescale `u` (e.g. to an RMS near 1)"),
    ("fit", "order_grid = 0 (#11)", lambda t: fohw.fit(_TF, U, U**3, order_grid=0),
     fohw.ParameterError, "`order_grid` must be at least 1; got 0"),
    ("fit", "n_starts = -1 (#11)", lambda t: fohw.fit(_TF, U, U**3, n_starts=-1),
     fohw.ParameterError, "`n_starts` must be at least 1; got -1"),
    ("fit", "order_grid = 10**6 (#11: ran past 120 s)",
     lambda t: fohw.fit(_TF, U, U**3, order_grid=10**6), fohw.ParameterError,
     "`order_grid` = 1000000 scans 1000001 points for 1 free orders, more than 20000"),
    ("fit", "tol = 0 (#12: was scipy's raw message)", lambda t: fohw.fit(_TF, U, U**3, tol=0),
     fohw.ParameterError, "`tol` must be in [2.22045e-16, 1); got 0"),
    ("fit", "a circuit with 3 samples (#15)",
     lambda t: fohw.fit(_circ34(), *_cell34(n=3)), fohw.DimensionError,
     "`y` has 3 samples for 6 free parameters (a, b, R0, R1, tau1, alpha1)"),
    ("fit", "a circuit with 5 samples for 6 parameters (#15)",
     lambda t: fohw.fit(_circ34(), *_cell34(n=5)), fohw.DimensionError,
     "`y` has 5 samples for 6 free parameters"),
    ("fit", "a circuit on a constant current (#15: was a rank-deficiency warning)",
     lambda t: fohw.fit(_circ34(), *_cell34(current=np.ones(600))), fohw.ParameterError,
     "the current `u[:, 0]` is constant (1.0 A at all 600 samples): R0 i is then a constant, "
     "which the offset `a` already is"),
    ("fit", "a circuit on a constant voltage (#15)",
     lambda t: fohw.fit(_circ34(), _cell34()[0], np.full(600, 3.7)), fohw.ParameterError,
     "`y` is constant"),
    ("fit", "an OCV that returns NaN (#16: the error named the parameter a)",
     lambda t: fohw.fit(_circ34(ocv=lambda s: np.full_like(s, np.nan)), *_cell34()),
     fohw.ParameterError, "returned np.float64(nan) at sample 0"),
    ("fit", "an OCV that returns 3 values for 600 samples (#17: raw broadcast error)",
     lambda t: fohw.fit(_circ34(ocv=lambda s: np.ones(3)), *_cell34()), fohw.ParameterError,
     "must return one voltage per sample of the state of charge: shape (600,) for 600 samples; "
     "got shape (3,)"),
    ("fit", "a state of charge of 1.5 (#18: accepted without a word)",
     lambda t: fohw.fit(_circ34(), *_cell34(soc_shift=0.7)), fohw.ParameterError,
     "the state of charge `u[:, 1]` must be in [0, 1] (a fraction of the capacity); got 1.4"),
    ("EquivalentCircuit.simulate", "a negative state of charge (#18)",
     lambda t: _CIRC34.simulate(np.column_stack([U, U])), fohw.ParameterError,
     "the state of charge `u[:, 1]` must be in [0, 1]"),
    ("EquivalentCircuit", "c3 = 'yes' (#19)", lambda t: fohw.EquivalentCircuit(["rc"], c3="yes"),
     fohw.ParameterError, "`c3` must be a real number; got 'yes'"),
    ("EquivalentCircuit.from_config", "current_map = 'yes' (#19: was taken as True)",
     lambda t: fohw.EquivalentCircuit.from_config({"elements": ["rc"], "current_map": "yes"}),
     fohw.ParameterError, "`current_map` of a circuit's config must be true or false (with or "
     "without the c3 i^3 term); got 'yes'"),
    ("fit", "five ZARCs at the default grid (#20: the start scan ran past 120 s)",
     lambda t: fohw.fit(_circ34(("zarc",) * 5), *_cell34(), n_starts=1, max_nfev=20),
     fohw.ParameterError, "would solve more than MAX_GRID_STARTS = 50000 combinations of grid "
     "points (`n_tau` = 8 time constants and `n_alpha` = 5 orders per element)"),
    ("fit", "n_tau = 10**6 (#20: no cap)",
     lambda t: fohw.fit(_circ34(n_tau=10**6), *_cell34()), fohw.ParameterError,
     "(`n_tau` = 1000000 time constants"),
    ("EquivalentCircuit", "current_sign = 'positive' (issue 37)",
     lambda t: fohw.EquivalentCircuit(["rc"], current_sign="positive"), fohw.ParameterError,
     "`current_sign` must be one of 'charge_positive', 'discharge_positive'"),
    ("fit", "a circuit's current in the other sign convention (issue 37)",
     lambda t: fohw.fit(_circ34(), *(lambda u, v: (u * [-1.0, 1.0], v))(*_cell34())),
     fohw.ParameterError, "The current `u[:, 0]` is given in the other convention: build the "
     "circuit with current_sign='discharge_positive'"),
    ("fit_impedance", "a frequency of 0 Hz",
     lambda t: fit_impedance(fohw.EquivalentCircuit(["zarc"]), [0.0, 1.0, 2.0], [0.02] * 3),
     fohw.ParameterError, "`f` must be positive frequencies [Hz]; got 0.0 at index 0"),
    ("fit_record_and_impedance", "a noise level of 0",
     lambda t: fit_record_and_impedance(fohw.EquivalentCircuit(["rc"]),
                                        np.column_stack([U, 0.5 + 0 * U]), U, [1.0, 2.0],
                                        [0.02, 0.02], noise=(0.0, 0.01)),
     fohw.ParameterError, "`noise` must hold two positive, finite noise levels; got (0.0, 0.01)"),
    ("fit_impedance", "f above the Nyquist frequency with discrete=True (issue 43, N22: was fitted)",
     lambda t: fit_impedance(_S43, _F43, _C43.impedance(_F43), discrete=True), fohw.ParameterError,
     "`f` has 26 of its 40 frequencies above the Nyquist frequency 1 / (2 dt) = 0.5 Hz of the "
     "circuit"),
    ("fit_impedance", "conj(Z), the \"-Im Z\" plotting convention (issue 43, N23: was fitted)",
     lambda t: fit_impedance(_S43, _F43, np.conj(_C43.impedance(_F43))), fohw.ParameterError,
     "`z` has a positive imaginary part at 40 of its 40 frequencies, where a capacitive impedance "
     "(RC, ZARC and Warburg elements) has Im Z <= 0: this looks like the \"-Im Z\" convention"),
    ("fit_impedance", "-Z (issue 43, N51: a rank-deficient fit)",
     lambda t: fit_impedance(_S43, _F43, -_C43.impedance(_F43)), fohw.ParameterError,
     "`z` has a negative real part at 40 of its 40 frequencies: a passive impedance has Re Z >= 0, "
     "so this looks like -Z"),
    ("fit_record_and_impedance", "a spectrum 10 times the record's impedance (issue 43, N24: was "
     "fitted without a word)", lambda t: _disagreeing_data(t), fohw.DataWarning,
     "The record and the spectrum disagree: at the joint estimate the record's RMS error is"),
    ("fit_frequency_response", "a kind without a frequency response",
     lambda t: fohw.fit_frequency_response(_NoResponse(), [1.0, 2.0], [1.0, 1.0]),
     fohw.ParameterError, "a _NoResponse has no frequency response: its kind does not define the "
     "fohw.Model hook `frequency_response(omega)`"),
    ("fit_frequency_response", "a keyword the kind's response does not take",
     lambda t: fohw.fit_frequency_response(_S43, 2 * np.pi * _F43, _C43.impedance(_F43), soc=0.5),
     fohw.ParameterError, "`soc` is neither an argument of fit_frequency_response nor a keyword of "
     "EquivalentCircuit.frequency_response (it takes 'discrete', 'capacity', 'ocv_slope')"),
    ("fit_frequency_response", "the lagged kind above the Nyquist frequency",
     lambda t: fohw.fit_frequency_response(M(), np.linspace(0.1, 5.0, 30),
                                           M().frequency_response(np.linspace(0.1, 5.0, 30))),
     fohw.ParameterError, "`omega` has 11 of its 30 frequencies above the Nyquist frequency "
     "pi / dt = 3.14159 of this HammersteinWiener"),
    # issue 43: the Model protocol's hooks checked once in the engine, the caller's data never
    # handed writable to a kind, several records checked as one is
    ("fit", "a kind that writes into its input (issue 43 N1: the caller's u scaled in place)",
     lambda t: _unchanged(lambda u: fohw.fit(_misbehaving(simulate=_mut_simulate), u, _Y43)),
     ModelHookError, "simulate must not write into its input; copy it first"),
    ("simulate", "a kind that writes into its input (issue 43 N2: the caller's u changed)",
     lambda t: _unchanged(lambda u: fohw.simulate(_misbehaving(simulate=_mut_simulate), u)),
     ModelHookError, "fohw hands a kind the caller's data read-only"),
    ("fit", "jacobian returns an array, not (yhat, J) (issue 43 N34: raw IndexError)",
     lambda t: fohw.fit(_misbehaving(jacobian=lambda self, u: np.ones(3)), _U43, _Y43),
     ModelHookError, "Kind43.jacobian returned an array of shape (3,) (dtype float64); it must "
     "return a pair (yhat, J) or None"),
    ("fit", "linear_start returns a dict (issue 43 N35: raw AttributeError)",
     lambda t: fohw.fit(_misbehaving(linear_start=lambda self, u, y: {"a": 1.0}), _U43, _Y43),
     ModelHookError, "Kind43.linear_start returned dict {'a': 1.0}; a start must be a model"),
    ("fit", "jacobian's J all NaN (issue 43 N36: argmin of an empty sequence)",
     lambda t: fohw.fit(_misbehaving(jacobian=lambda self, u: (self.simulate(u), np.full(
         (len(u), 2), np.nan))), _U43, _Y43),
     ModelHookError, "Kind43.jacobian returned a J with NaN or inf entries (the columns of a, b)"),
    ("fit", "starts returns [None, 'x'] (issue 43 N37: raw AttributeError)",
     lambda t: fohw.fit(_misbehaving(starts=lambda self, u, y: [None, "x"]), _U43, _Y43),
     ModelHookError, "Kind43.starts returned, as start 0, NoneType None; a start must be a model"),
    ("fit", "simulate returns shape (N, 2) (issue 43 N38: raw broadcast error)",
     lambda t: fohw.fit(_misbehaving(simulate=lambda self, u, initial=None: np.zeros(
         (len(u), 2))), _U43, _Y43),
     ModelHookError, "Kind43.simulate returned an output of shape (200, 2) for an input of 200 "
     "samples; it must return the output, shape (200,)"),
    ("fit", "jacobian's J has 5 columns for 2 parameters (issue 43 N39: raw matmul error)",
     lambda t: fohw.fit(_misbehaving(jacobian=lambda self, u: (self.simulate(u), np.ones(
         (len(u), 5)))), _U43, _Y43),
     ModelHookError, "Kind43.jacobian returned a J of shape (200, 5); J must have shape (200, 2)"),
    ("fit", "simulate returns N + 1 samples (issue 43 N40: raw broadcast error)",
     lambda t: fohw.fit(_misbehaving(simulate=lambda self, u, initial=None: np.zeros(
         len(u) + 1)), _U43, _Y43),
     ModelHookError, "Kind43.simulate returned an output of shape (201,) for an input of 200"),
    ("fit", "with_parameters returns 42 (issue 43 N48: blamed __slots__)",
     lambda t: fohw.fit(_misbehaving(with_parameters=lambda self, values: 42), _U43, _Y43),
     ModelHookError, "Kind43.with_parameters returned int 42; it must return a new model of the "
     "kind"),
    ("fit", "an exact jacobian of the wrong sign (issue 43 N49: only 'stuck at its start')",
     lambda t: _warned(lambda: fohw.fit(_misbehaving(jacobian=_wrong_sign_jacobian), _U43,
                                        _Y43)),
     fohw.ConvergenceWarning, "The exact Jacobian (Kind43.jacobian) disagrees with central "
     "finite differences at the start: the columns of a, b"),
    ("fit", "a constant y in one record of a list (issue 43 N27: fitted without a word)",
     lambda t: fohw.fit(_G43, [_R43[0], fohw.Record(u=_R43[1].u, y=np.ones(300), dt=0.1)],
                        **_FIT43),
     fohw.ParameterError, "record 1: `y` is constant (1.0 at all 300 samples)"),
    ("fit", "warmup=10**6 before two records of 300 (issue 43 N5: ran for minutes)",
     lambda t: fohw.fit(_G43, _R43, warmup=10**6, **_FIT43), fohw.ParameterError,
     "`warmup` must be at most 10000 samples (10 times the longest record, 300 samples, or "
     "10000); got 1000000"),
    ("fit", "per_record=3 (issue 43 N43: per_record=None was a raw TypeError; None is none)",
     lambda t: fohw.fit(_G43, _R43, per_record=3, **_FIT43), fohw.ParameterError,
     "`per_record` must be a parameter name or a sequence of names (() for none); got int 3"),
    ("profile_interval", "a per-record parameter (issue 43 N44: scipy's 'f(a) and f(b) must "
     "have different signs')",
     lambda t: _profile_per_record(), fohw.ParameterError,
     "`name` = 'b0' is estimated per record"),
    ("order_test", "validation= the estimation record (issue 43 N28: 'significant and validates')",
     lambda t: _order_test_on_its_own_record(), fohw.ParameterError,
     "`validation` is the record the fit was estimated on (100 samples"),
    ("stream_fits", "timeout=0 (issue 43: a per-record timeout)",
     lambda t: fohw.stream_fits([(_U43, _Y43)], _Lag43(), timeout=0), fohw.ParameterError,
     "`timeout` must be a positive number of seconds (or None: no limit); got 0"),
    # issue 43 (data): FitResult dicts and files, Parameters, Record, resample, CircuitTables
    ("CircuitTables.simulate", "a SOC beyond the last breakpoint (N10: held without a word)",
     lambda t: _tables43().simulate(_cu43(soc=0.95)), fohw.ExtrapolationWarning,
     "the state of charge `u[:, 1]` leaves the breakpoints `soc_points` [0.2, 0.8] (by more "
     "than 5% of their span) at 400 of 400 samples (first: 0.95 at sample 0)"),
    ("CircuitTables.simulate", "a temperature beyond the breakpoints (N11: held without a word)",
     lambda t: _tables43().simulate(_cu43(temperature=60.0)), fohw.ExtrapolationWarning,
     "the temperature `u[:, 2]` leaves the breakpoints `temperature_points` [10, 30]"),
    ("CircuitTables", "temperature breakpoints below absolute zero (N12: accepted)",
     lambda t: _tables43(temperature_points=[-300.0, 10.0], temperature_interpolation="arrhenius"),
     fohw.ParameterError, "`temperature_points` are in degC and must lie above absolute zero "
     "(-273.15 degC); got [-300.0, 10.0]"),
    ("FitResult.from_dict", "a covariance with negative variances (N13: NaN standard errors)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(covariance=(-np.eye(3)).tolist())),
     fohw.ParameterError, "field 'covariance' has a negative variance (-1.0 on its diagonal at 0)"),
    ("FitResult.from_dict", "n_per_record = -3 in a joint fit's dict (N14: accepted)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(True, n_per_record=-3)), fohw.ParameterError,
     "field 'n_per_record' must be an integer >= 0; got -3"),
    ("FitResult.from_dict", "n_samples = 0 (N15: accepted)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(n_samples=0)), fohw.ParameterError,
     "field 'n_samples' must be an integer >= 1; got 0"),
    ("FitResult.from_dict", "n_samples = 2.7 (N16: truncated to 2)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(n_samples=2.7)), fohw.ParameterError,
     "field 'n_samples' must be an integer >= 1; got 2.7"),
    ("FitResult.from_dict", "5 residuals for 300 samples (N17: accepted)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(residuals=[0.0] * 5)), fohw.ParameterError,
     "field 'residuals' has 5 values for n_samples = 300"),
    ("FitResult.from_dict", "sse = -1 (N18: accepted)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(sse=-1.0)), fohw.ParameterError,
     "FitResult.from_dict(d): field 'sse' must be a finite number >= 0; got -1.0"),
    ("load_result", "a joint fit's per_record naming no parameter (N19: loaded)",
     lambda t: fohw.load_result(_fit43_file(t, True, per_record={
         "zz": {"values": [1, 2], "standard_errors": None}})), fohw.DataFileError,
     "field 'per_record' has an entry 'zz', which is not a free parameter of the model (its free "
     "parameters: b0, a0, alpha0)"),
    ("Parameters", "a tied parameter whose value contradicts its tie (N20: b = 2.0 reported)",
     lambda t: fohw.Parameters([fohw.Parameter("a", 1.0),
                                fohw.Parameter("b", 2.0, bounds=(0, 1), tie=("a", 5.0))]).valuesdict(),
     fohw.ParameterError, "parameter 'b' is tied to 'a' (5 times it, 5.0), but its value is 2.0"),
    ("Record.from_dataframe", "the output column also the input (N25: accepted)",
     lambda t: fohw.Record.from_dataframe(_frame43(), "v", "v", dt=0.1), fohw.ParameterError,
     "`u` and `y` name the same column ('v'): the input and the output are different columns"),
    ("resample", "dt longer than the record (N29: one sample returned)",
     lambda t: fohw.model.irregular.resample(np.linspace(0.0, 30.0, 301), np.ones(301), dt=1e6),
     fohw.ParameterError, "`dt` = 1000000.0 is longer than the record (its instants span 30, "
     "from t[0] to t[-1]): the grid would hold one sample; give dt <= 30"),
    ("FitResult.from_dict", "covariance = 'eye' (N30: numpy's float conversion error)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(covariance="eye")), fohw.ParameterError,
     "field 'covariance' must be null or a matrix (list of equal rows) of finite numbers; got 'eye'"),
    ("FitResult.from_dict", "options = [1, 2] (N31: dict's TypeError)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(options=[1, 2])), fohw.ParameterError,
     "field 'options' must be an object; got [1, 2]"),
    ("FitResult.from_dict", "sse = 'abc' (N32: float's ValueError)",
     lambda t: fohw.FitResult.from_dict(_fit43_dict(sse="abc")), fohw.ParameterError,
     "field 'sse' must be a finite number >= 0; got 'abc'"),
    ("FitResult.from_dict", "a list, not a dict (N33: 'list indices must be integers')",
     lambda t: fohw.FitResult.from_dict([1, 2]), fohw.ParameterError,
     "a fit's content must be an object (a dict, as FitResult.to_dict makes)"),
    ("Record.from_dataframe", "a dict of arrays, not a DataFrame (N41: AttributeError)",
     lambda t: fohw.Record.from_dataframe({"i": _UD43, "v": _YD43}, "i", "v", dt=0.1),
     fohw.ParameterError, "`frame` must be a pandas DataFrame; got dict"),
    ("Record.from_dataframe", "units as a list (N42: dict's ValueError)",
     lambda t: fohw.Record.from_dataframe(_frame43(), "i", "v", dt=0.1, units=["A", "V"]),
     fohw.ParameterError, "`units` must map each column to its unit, e.g. {'i': 'A', 'v': 'V'}; "
     "got list"),
    ("load_result", "a fit's file without its model field (N47: 'missing field method')",
     lambda t: fohw.load_result(_fit43_file(t, drop=("model",))), fohw.DataFileError,
     "fit43.json: missing field 'model'"),
    ("Record.from_dataframe", "a NaT in the DatetimeIndex (N52: 't must be strictly increasing')",
     lambda t: fohw.Record.from_dataframe(_frame43(index=_nat_index43()), "i", "v"),
     fohw.ParameterError, "the index holds no time (NaT) at position 3; fohw fills no gaps"),
    ("Record.from_dataframe", "two columns named v (N53: '`y` must be 1-D')",
     lambda t: fohw.Record.from_dataframe(_frame43(("i", "v", "v")), "i", "v", dt=0.1),
     fohw.ParameterError, "the DataFrame has 2 columns named 'v'"),
]

CLI = [
    ("fohw identify", "data file missing",
     lambda t: ["identify", "/nonexistent.dat", "--na", "2", "--nb", "2"],
     "data file not found"),
    ("fohw identify", "column that does not exist",
     lambda t: ["identify", _bad_file(t, "1 2\n3 4\n5 6\n"), "--columns", "0,5",
                "--na", "1", "--nb", "1"],
     "column 5 does not exist"),
    ("fohw identify", "unknown header name",
     lambda t: ["identify", _bad_file(t, "a,b\n1,2\n3,4\n5,6\n"), "--columns", "u,y",
                "--na", "1", "--nb", "1"],
     "'u' is neither a column number nor a header name"),
    ("fohw identify", "basis degree 0",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--f-basis", "0"],
     "a basis is a polynomial degree from 1 to 100"),
    ("fohw identify", "na missing", lambda t: ["identify", "x.dat", "--nb", "1"],
     "the following arguments are required: --na"),
    ("fohw identify", "malformed line",
     lambda t: ["identify", _bad_file(t, "1 2\n3 oops\n"), "--na", "1", "--nb", "1"],
     "line 2: 'oops' is not a number"),
    ("fohw identify", "alpha bounds not a pair",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--alpha-bounds", "0.5"],
     "expected two numbers 'low,high'"),
    ("fohw simulate", "model file is not JSON",
     lambda t: ["simulate", "--model", _bad_file(t, "not json", "m.json"), "--input", _bad_file(t, "1\n2\n")],
     "is not valid JSON"),
    ("fohw reproduce", "unknown target", lambda t: ["reproduce", "table9"], "invalid choice"),
    # issue 14 (case numbers are the issue's)
    ("fohw identify", "--save a directory (checked before the run)",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--save", str(t)],
     "--save '"),
    ("fohw simulate", "--output a directory",
     lambda t: ["simulate", "--model", _model_file(t), "--input", _bad_file(t, "1\n2\n"),
                "--output", str(t)], "--output '"),
    ("fohw simulate", "--model a directory",
     lambda t: ["simulate", "--model", str(t), "--input", _bad_file(t, "1\n2\n")],
     "is a directory, not a fohw JSON file"),
    ("fohw reproduce", "--outdir an existing file",
     lambda t: ["reproduce", "table2", "--fast", "--outdir", _bad_file(t, "x")],
     "is a file, not a folder"),
    ("fohw identify", "--plot with an unknown format (checked before the run)",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--plot", str(t / "f.xyz")],
     "the extension .xyz is not a figure format"),
    ("fohw identify", "--save into a missing folder (checked before the run)",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--save",
                str(t / "no" / "r.json")], "does not exist"),
    ("fohw identify", "--f-basis 10**8 (a hang)",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--f-basis", "100000000"],
     "a basis is a polynomial degree from 1 to 100"),
    ("fohw simulate", "a model with a custom basis",
     lambda t: ["simulate", "--model", _model_file(t, f_basis={"kind": "custom", "names": ["tanh"]}),
                "--input", _bad_file(t, "1\n2\n")], "(the command line cannot)"),
    ("fohw identify", "';' and decimal commas without --decimal-comma",
     lambda t: ["identify", _bad_file(t, "u;y\n0,5;1,25\n-0,25;0,5\n"), "--na", "1", "--nb", "1"],
     "pass decimal=',' (fohw: --decimal-comma)"),
    ("fohw identify", "--decimal-comma on a comma-separated file",
     lambda t: ["identify", _bad_file(t, "u,y\n1,2\n3,4\n", "r.csv"), "--na", "1", "--nb", "1",
                "--decimal-comma"], "is separated by commas, but decimal=',' makes commas"),
    ("fohw identify", "one column",
     lambda t: ["identify", _bad_file(t, "1\n2\n3\n"), "--na", "1", "--nb", "1"],
     "has 1 signal column(s); this command needs 2 (the input and the output)"),
    ("fohw simulate", "a missing --column (was reported as --columns)",
     lambda t: ["simulate", "--model", _model_file(t), "--input", _bad_file(t, "1\n2\n"),
                "--column", "5"], "--column: column 5 does not exist"),
    # issue 28 (28a)
    ("fohw identify", "--save an existing FIFO (it was replaced by a regular file)",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--save",
                os.mkfifo(t / "f.json") or str(t / "f.json")],
     "exists and is not a regular file (a FIFO); fohw does not replace it"),
    ("fohw select", "--top -1 (it printed every row but the last)",
     lambda t: ["select", "x.dat", "--na", "1", "--top", "-1"],
     "argument --top: expected an integer >= 1; got -1"),
    ("fohw select", "--top 0", lambda t: ["select", "x.dat", "--na", "1", "--top", "0"],
     "argument --top: expected an integer >= 1; got 0"),
    ("fohw select", "--orders fancy (every row failed, status 0)",
     lambda t: ["select", "x.dat", "--na", "1", "--orders", "fancy"],
     "argument --orders: each entry is one of commensurate, per_lag, mixed or a number"),
    ("fohw select", "--na 0", lambda t: ["select", "x.dat", "--na", "0"],
     "argument --na: expected comma-separated integers >= 1; got '0'"),
    ("fohw select", "--na 1000 (every candidate fails: status 2, not 0)",
     lambda t: ["select", "@cascaded_tanks", "--columns", "uEst,yEst", "--na", "1000", "-q"],
     "no model selected: the only candidate failed (fit: DimensionError"),
    ("fohw select", "--method hybrid --orders mixed",
     lambda t: ["select", "@cascaded_tanks", "--columns", "uEst,yEst", "--na", "1", "--method",
                "hybrid", "--orders", "mixed", "-q"],
     "no model selected: the only candidate failed (fit: ParameterError: method 'hybrid'"),
    ("fohw identify", "--save /proc/fit.json (checked before the run)",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--save",
                "/proc/fit.json"], "no file can be created in the folder '/proc'"),
    ("fohw identify", "--save a dangling symbolic link",
     lambda t: ["identify", "/nonexistent.dat", "--na", "1", "--nb", "1", "--save",
                (t / "l.json").symlink_to(t / "no" / "x.json") or str(t / "l.json")],
     "is a symbolic link to"),
    ("fohw simulate", "--output /proc/y.txt",
     lambda t: ["simulate", "--model", _model_file(t), "--input", _bad_file(t, "1\n2\n"),
                "--output", "/proc/y.txt"], "--output '/proc/y.txt': no file can be created"),
    ("fohw identify", "@NAME that does not ship with fohw",
     lambda t: ["identify", "@tanks", "--na", "1", "--nb", "1"],
     "no record of that name ships with fohw; use one of @cascaded_tanks, @robot_arm"),
    # issue 24 (initial)
    ("fohw simulate", "a result fitted with past='estimate', without --initial",
     lambda t: ["simulate", "--model", fohw.save_result(_past_result(), t / "p.json") or
                str(t / "p.json"), "--input", _bad_file(t, "1\n2\n")],
     "Say which initial state to start from: --initial fitted (those levels: for the "
     "estimation record itself) or --initial rest"),
    ("fohw simulate", "--initial estimate (needs the output: fohw.compare)",
     lambda t: ["simulate", "--model", "m.json", "--input", "x.dat", "--initial", "estimate"],
     "argument --initial: invalid choice: 'estimate'"),
    # issue 24 (outmap)
    ("fohw identify", "--output-map with an unknown name",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--output-map", "saturate"],
     "an output map is one of saturation, deadzone, piecewise_linear, none or a polynomial "
     "degree from 1 to 100; got 'saturate'"),
    ("fohw identify", "--output-map 0",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--output-map", "0"],
     "a polynomial degree from 1 to 100; got '0'"),
    ("fohw identify", "--output-map with the default method varpro",
     lambda t: ["identify", "@cascaded_tanks", "--columns", "uEst,yEst", "--na", "1", "--nb",
                "1", "--output-map", "saturation", "-q"],
     "method 'varpro' cannot fit a series `output_map`"),
    # issue 24 (nk)
    ("fohw identify", "--nk 1.5", lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1",
                                            "--nk", "1.5"],
     "argument --nk: expected an integer >= 0 (or one per input); got '1.5'"),
    ("fohw identify", "--nk -1",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--nk", "-1"],
     "argument --nk: expected an integer >= 0 (or one per input); got -1"),
    ("fohw select", "--nk -1", lambda t: ["select", "x.dat", "--na", "1", "--nk", "-1"],
     "argument --nk: expected comma-separated integers >= 0; got '-1'"),
    # issue 24 (miso)
    ("fohw identify", "--columns of 2 inputs, --nb with 3 entries",
     lambda t: ["identify", _bad_file(t, "a b y\n" + "".join(f"{v} {-v} {v}\n" for v in U)),
                "--columns", "a,b,y", "--na", "1", "--nb", "1,1,1", "-q"],
     "`nb` gives 3 value(s), one per input, but there are 2 input(s) (columns of `u`)"),
    ("fohw identify", "--nk 0,-1",
     lambda t: ["identify", "x.dat", "--na", "1", "--nb", "1", "--nk", "0,-1"],
     "argument --nk: expected an integer >= 0 (or one per input); got -1"),
    # issue 34 (io)
    ("fohw simulate", "one column for a two-input result (was '`u` must be 2-D')",
     lambda t: ["simulate", "--model", _two_input_file(t), "--input", _bad_file(t, "1\n2\n"),
                "--column", "0"],
     "--column needs 2 entries, one per input of "),
    ("fohw select", "--jobs 1000 (56.6 s for two candidates, 0.5 s with --jobs 1)",
     lambda t: ["select", "x.dat", "--na", "1", "--jobs", "1000"],
     "--jobs must be from 1 to"),
    ("fohw identify", "the data file a FIFO (the read never ended)",
     lambda t: ["identify", os.mkfifo(t / "f.dat") or str(t / "f.dat"), "--na", "1", "--nb", "1"],
     "is a FIFO, not a regular file"),
    # issue 43 (cli) and issue 42: the time column is read, and checked
    ("fohw data", "paper_example --samples 1000000000 (ran > 60 s: no upper bound)",
     lambda t: ["data", "paper_example", "--samples", "1000000000", "--out", str(t / "x.csv")],
     "argument --samples: expected at most 1_000_000 samples"),
    ("fohw identify", "t steps 0.5 under '# dt: 4 s' (the t column was never read)",
     lambda t: ["identify", _bad_file(t, "# dt: 4 s\nt,u,y\n" + _rows(0.5 * np.arange(50)),
                                      "f.csv"), "--columns", "u,y", "--na", "1", "--nb", "1"],
     "f.csv: line 4: the time column 't' steps 0.5 s from line 3, but `# dt: 4 s` (line 1) "
     "says 4 s"),
    ("fohw identify", "'# units: q=V' naming no column (the unit was dropped)",
     lambda t: ["identify", _bad_file(t, "# units: q=V\nu,y\n" + "1,2\n" * 5, "f.csv"),
                "--na", "1", "--nb", "1"],
     "f.csv: line 1: `# units:` names 'q', which is not a column (u, y)"),
    ("fohw identify", "rows 10 and 11 of t swapped (output as for the clean file)",
     lambda t: ["identify", _bad_file(t, "t,u,y\n" + _rows(np.r_[0:10, 11, 10, 12:50] * 0.5),
                                      "f.csv"), "--na", "1", "--nb", "1"],
     "f.csv: line 13: the time column 't' goes back from 5.5 (line 12) to 5.0"),
    ("fohw identify", "an instant repeated (output as for the clean file)",
     lambda t: ["identify", _bad_file(t, "t,u,y\n" + _rows(np.r_[0:11, 10, 12:50] * 0.5),
                                      "f.csv"), "--na", "1", "--nb", "1"],
     "f.csv: line 13 repeats the instant 5.0 of line 12 (time column 't')"),
    ("fohw identify", "ISO stamps out of order",
     lambda t: ["identify", _bad_file(t, "time,u,y\n2024-01-01T00:00:01,1,2\n"
                                      "2024-01-01T00:00:00,2,3\n", "f.csv"), "--na", "1", "--nb", "1"],
     "f.csv: line 3: the time column 'time' goes back from 0.0 (line 2) to -1.0"),
]


def _rows(t):
    """CSV rows ``t,u,y`` of the instants ``t`` (u, y made up)."""
    return "".join(f"{v!r},{float(np.sin(k))!r},{float(np.cos(k))!r}\n"
                   for k, v in enumerate(map(float, t)))


def _lr_fit(orders, n=50, method="varpro", **kw):
    """A fit of U -> U**3 (the first ``n`` samples) for the lr_test rows."""
    kw = {**dict(na=1, nb=1, f_basis=1, g_basis=1), **kw}
    return fohw.identify(U[:n], U[:n] ** 3, orders=orders, method=method, **kw)


_SOC = np.linspace(0.8, 0.7, 50)


def _circuit_u(soc=_SOC):
    return np.column_stack([U, soc])


def _circuit_fit(soc=_SOC, dt=1.0, **held):
    """An R0-only circuit fitted to U (``held``: parameters fixed at values)."""
    model = fohw.EquivalentCircuit([], dt=dt)
    params = model.parameters
    for name, value in held.items():
        params = params.replace(name, value=value, fixed=True)
    return fohw.fit(model.with_parameters(params), _circuit_u(soc), U)


def _cell34(n=600, current=None, soc_shift=0.0):
    """Issue 34's circuit record: 20 s current steps from U(-3, 1.2) A, soc from 0.8, ``(u, v)``."""
    rng = np.random.default_rng(1)
    i = np.repeat(rng.uniform(-3.0, 1.2, 30), 20) if current is None else current
    soc = 0.8 + np.cumsum(i) / (3600 * 5)
    v = _CIRC34.simulate(np.column_stack([i, soc])) + 3.3 + 0.9 * soc
    return np.column_stack([i, soc + soc_shift])[:n], (v + 1e-4 * rng.standard_normal(600))[:n]


def _circ34(elements=("zarc",), ocv=lambda s: 3.3 + 0.9 * s, **kw):
    """The circuit fitted in issue 34 (``kw``: constructor settings)."""
    return fohw.EquivalentCircuit(list(elements), ocv=ocv, tau_bounds=(1.0, 500.0), **kw)


#: Issue 43's circuit and spectrum: a ZARC cell at dt = 1 s, 40 frequencies from 0.01 to 1000 Hz.
_C43 = fohw.EquivalentCircuit([fohw.ZARC(0.012, 5.0, 0.6)], r0=0.015, dt=1.0)
_S43 = fohw.EquivalentCircuit(("zarc",), dt=1.0)
_F43 = np.logspace(-2, 3, 40)


def _disagreeing_data(t):
    """Issue 43's N24: a record of the cell with an OCV and its spectrum times 10 (the warning raised)."""
    import warnings

    ocv = lambda s: 3.3 + 0.9 * np.asarray(s)  # noqa: E731
    i = np.repeat(np.random.default_rng(0).uniform(-3, 1, 20), 20)
    u = np.column_stack([i, 0.6 + np.cumsum(i) / 18000])
    v = fohw.EquivalentCircuit([fohw.ZARC(0.012, 5.0, 0.6)], r0=0.015, ocv=ocv, dt=1.0).simulate(u)
    f = np.logspace(-2, np.log10(0.5), 30)
    with warnings.catch_warnings():
        warnings.simplefilter("error", fohw.DataWarning)
        fit_record_and_impedance(fohw.EquivalentCircuit(("zarc",), ocv=ocv, dt=1.0), u, v, f,
                                 10 * _C43.impedance(f))


def _hybrid():
    d = fohw.datasets.paper_example(300, random_state=0)
    return fohw.identify(d.u, d.y, method="hybrid", **S)


@pytest.mark.parametrize("where, what, call, exc, text", API, ids=[f"{w}: {x}" for w, x, *_ in API])
def test_api_bad_input(where, what, call, exc, text, tmp_path):
    with pytest.raises(exc) as info:
        call(tmp_path)
    assert text in str(info.value)


@pytest.mark.parametrize("where, what, args, text", CLI, ids=[f"{w}: {x}" for w, x, *_ in CLI])
def test_cli_bad_input(where, what, args, text, tmp_path):
    err = io.StringIO()
    with redirect_stderr(err):
        try:
            status = cli(args(tmp_path))
        except SystemExit as stop:          # argparse usage errors
            status = stop.code
    message = err.getvalue()
    assert status == 2
    assert message.count("\n") == 1 and message.startswith("fohw: error:"), message
    assert text in message


#: Entry points that live in a submodule, not in ``fohw.__all__``, and keep their cases here.
SUBMODULE_ENTRY_POINTS = {
    "MultiInnovationRLS": fohw.estimators.rls, "HybridIdentifier": fohw.estimators.hybrid,
    "information_matrix": fohw.model.lagged.regressors, "gl_weights_derivative": fohw.model.gl,
    "as_basis": fohw.model.basis, "end_with_parent": fohw.analysis.batch,
    "fit_impedance": fohw.estimators.impedance_fit, "fit_record_and_impedance": fohw.estimators.impedance_fit,
}


def test_every_public_callable_has_a_bad_input_case():
    """Each public function of fohw, the lagged model and the entry points of submodules that
    the top level does not re-export have at least one entry in the catalogue."""
    covered = {where.split(".")[0].split(":")[0] for where, *_ in API}
    public = {name for name in fohw.__all__ if callable(getattr(fohw, name))
              and not isinstance(getattr(fohw, name), type)
              or name == "HammersteinWiener"}
    assert all(name in module.__all__ for name, module in SUBMODULE_ENTRY_POINTS.items())
    public |= set(SUBMODULE_ENTRY_POINTS)
    missing = sorted(public - covered)
    assert not missing, f"public callables with no bad-input case: {missing}"


def test_compare_matches_a_records_inputs_by_name():
    """Issue 43 N26: a Record's input names are matched to the result's, as a DataFrame's
    columns are: the record with its columns swapped scores what the record in order scores
    (it scored -13 % against 100 %), and a record with other names is refused."""
    import pandas as pd

    d = fohw.datasets.paper_example(300, random_state=0)
    u = np.column_stack([d.u, np.random.default_rng(5).uniform(-1, 1, 300)])
    y = fohw.identify(u, d.y, na=1, nb=[1, 1], f_basis=2, g_basis=1).simulate(u)
    frame = pd.DataFrame({"a": u[:, 0], "b": u[:, 1], "y": y})
    res = fohw.identify(fohw.Record.from_dataframe(frame, u=["a", "b"], y="y", dt=1.0),
                        na=1, nb=[1, 1], f_basis=2, g_basis=1)
    in_order = fohw.compare(res, fohw.Record.from_dataframe(frame, u=["a", "b"], y="y", dt=1.0))
    swapped = fohw.compare(res, fohw.Record.from_dataframe(frame, u=["b", "a"], y="y", dt=1.0))
    assert in_order.fit_simulation > 99.0                   # the data are the model's own run
    assert swapped.fit_simulation == in_order.fit_simulation
    assert fohw.compare(res, frame[["b", "a"]], y).fit_simulation == in_order.fit_simulation
    other = fohw.Record.from_dataframe(frame.rename(columns={"a": "c"}), u=["c", "b"], y="y", dt=1.0)
    with pytest.raises(fohw.DimensionError, match=r"is a Record with the inputs \['c', 'b'\], but "
                                                  r"the model's inputs are \['a', 'b'\]"):
        fohw.compare(res, other)


def markdown():
    lines = ["# Bad input and the errors it gets", "",
             "Every public entry point validates its input through one layer "
             "(`fohw._validation`): errors name the argument and echo what arrived, and input is "
             "never silently fixed. Domain exceptions subclass the matching built-in "
             "(`ParameterError` and `DimensionError` are `ValueError`s, `NotFittedError` is an "
             "`AttributeError`, `SimulationDivergedError` an `ArithmeticError`). The command line "
             "prints one line `fohw: error: …` and exits with status 2, operating-system errors "
             "(permissions, a folder given as a file) included; Ctrl-C prints one line and "
             "exits with status 130. Output paths are checked before a run starts, and results, "
             "models, tables, outputs and figures are written atomically, so a failed or "
             "interrupted save leaves an existing file byte for byte "
             "(`tests/test_reliability.py`).",
             "",
             "This page is generated from `tests/test_bad_input.py`, which checks every row.", "",
             "## Python API", "", "| entry point | bad input | exception | message contains |",
             "|---|---|---|---|"]
    for where, what, _, exc, text in API:
        escaped = text.replace("|", "\\|")
        lines.append(f"| `{where}` | {what} | `{exc.__name__}` | {escaped} |")
    lines += ["", "## Command line", "", "| command | bad input | message contains |",
              "|---|---|---|"]
    for where, what, _, text in CLI:
        lines.append(f"| `{where}` | {what} | {text} |")
    return "\n".join(lines) + "\n"


def test_docs_page_is_current():
    assert (ROOT / "docs" / "bad_input.md").read_text() == markdown()


if __name__ == "__main__":
    sys.stdout.write(markdown())
