"""``fohw.testing.check_model``: every check can fail, and says which and why.

``Good`` below follows the whole protocol and has every hook (an exact Jacobian, starts, a
linear start, a frequency response, a penalty). Each ``Broken…`` kind breaks one promise; the
test runs every check on it alone and asserts which fail: the broken one, plus those that
cannot help seeing the same fault (a ``config()`` that JSON cannot hold cannot be written to a
file either), each listed with its reason in ``BROKEN``. The shipped kinds are checked in
tests/test_model_protocol.py.
"""

import subprocess
import sys

import numpy as np
import pytest

import fohw
import fohw.testing
from fohw.testing import CHECKS, ModelCheckError, check_model


class Good(fohw.Model):
    """``y[k] = a y[k-1] + b u[k-1]`` with every optional hook of the protocol."""

    def __init__(self, a=0.6, b=2.0, *, dt=0.1, weight=1e-2):
        self.a, self.b, self.step, self.weight = float(a), float(b), float(dt), float(weight)

    @property
    def dt(self):
        return self.step

    def config(self):
        return {"dt": self.step, "weight": self.weight}

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return type(self)(v["a"], v["b"], dt=self.step, weight=self.weight)

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        y = np.zeros(u.size)
        for k in range(1, u.size):
            y[k] = self.a * y[k - 1] + self.b * u[k - 1]
        return y

    def jacobian(self, u):
        # d y[k] / d a = y[k-1] + a d y[k-1] / d a;  d y[k] / d b = u[k-1] + a d y[k-1] / d b
        u = self.check_input(u)
        y = Good.simulate(self, u)         # not a subclass's (broken) simulate
        jac = np.zeros((u.size, 2))
        for k in range(1, u.size):
            jac[k] = [y[k - 1], u[k - 1]] + self.a * jac[k - 1]
        return y, jac

    def starts(self, u, y):
        return [self, self.with_parameters({"a": 0.0})]

    def linear_start(self, u, y):
        x = np.asarray(self.with_parameters({"b": 1.0}).simulate(u))     # y is linear in b
        return self.with_parameters({"b": float(x @ np.asarray(y) / (x @ x))})

    def frequency_response(self, omega):
        z = np.exp(-1j * np.asarray(omega, dtype=float) * self.step)
        return self.b * z / (1 - self.a * z)

    def penalty(self):
        c = np.sqrt(self.weight)
        return c * np.array([self.a - 0.5, self.b - 1.0]), c * np.eye(2)


# --- one broken promise each ------------------------------------------------------------------
class ListParameters(Good):
    @property
    def parameters(self):
        return list(super().parameters.values())


class TwinNames(Good):
    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a), fohw.Parameter("a", self.b)])


class FloatInputs(Good):
    n_inputs = 1.0


class NegativeStep(Good):
    @property
    def dt(self):
        return -self.step


class ListOutput(Good):
    def simulate(self, u, *, initial=None):
        return super().simulate(u).tolist()


class Remembers(Good):
    """Starts each run where the last one ended (a hidden state)."""

    last = 0.0

    def simulate(self, u, *, initial=None):
        y = super().simulate(u) + self.a ** np.arange(np.shape(u)[0]) * self.last
        self.last = float(y[-1])
        return y


class WritesInput(Good):
    def simulate(self, u, *, initial=None):
        if isinstance(u, np.ndarray) and u.ndim == 1:
            u[-1] = 0.0                     # never read (y[k] uses u[k-1]): the output is the same
        return super().simulate(u)


class TakesAnyColumns(Good):
    def check_input(self, u):
        u = np.asarray(u, dtype=float)
        return u[:, 0] if u.ndim == 2 else super().check_input(u)


class WidensBounds(Good):
    """Copies have wider bounds of ``a`` than the model they were made from."""

    def __init__(self, a=0.6, b=2.0, *, dt=0.1, weight=1e-2, copy=False):
        super().__init__(a, b, dt=dt, weight=weight)
        self.copy = copy

    @property
    def parameters(self):
        bound = 1.0 if self.copy else 0.99
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-bound, bound)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return WidensBounds(v["a"], v["b"], dt=self.step, weight=self.weight, copy=True)


class _OwnParameters:
    """``parameters`` from a mixin, not the kind's class body: fohw.Model cannot see it to keep
    the settings a fohw.Parameters brings."""

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])


class DropsSettings(_OwnParameters, Good):
    pass


class Mutates(Good):
    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        self.a = v["a"]
        return type(self)(v["a"], v["b"], dt=self.step, weight=self.weight)


class AlwaysEqual(Good):
    def __eq__(self, other):
        return True

    __hash__ = None


class SetConfig(Good):
    def config(self):
        return {"dt": self.step, "weight": {self.weight}}


class ForgetsStep(Good):
    @classmethod
    def from_config(cls, config):
        return cls()


class ForgetsFixed(Good):
    """Its file layout writes no fixed flags (the lagged HammersteinWiener's, today)."""

    def to_dict(self):
        d = super().to_dict()
        d["parameters"] = {n: {k: v for k, v in p.items() if k != "fixed"}
                           for n, p in d["parameters"].items()}
        return d


class WrongColumn(Good):
    def jacobian(self, u):
        y, jac = super().jacobian(u)
        jac[:, 1] *= 1.001
        return y, jac


class NoStarts(Good):
    def starts(self, u, y):
        return []


class OtherLinearStart(Good):
    def linear_start(self, u, y):
        return Good(self.a, self.b)


class RealResponse(Good):
    def frequency_response(self, omega):
        return np.abs(super().frequency_response(omega))


class PenaltySign(Good):
    def penalty(self):
        r, jac = super().penalty()
        return r, -jac


_EVERY_CHECK_BUT = set(CHECKS) - {"n_inputs", "dt", "simulate", "simulate_deterministic",
                                  "simulate_leaves_input", "refuses_wrong_columns", "config_json",
                                  "frequency_response"}

#: ``(kind, the check it breaks, the other checks that see it too)``.
BROKEN = [
    # Everything that reads the parameters fails with them.
    (ListParameters, "parameters", _EVERY_CHECK_BUT - {"parameters"}),
    (TwinNames, "parameters", _EVERY_CHECK_BUT - {"parameters"}),
    (FloatInputs, "n_inputs", set()),
    (NegativeStep, "dt", set()),
    (ListOutput, "simulate", set()),
    # The original's output, read before and after with_parameters, moves with the hidden state.
    (Remembers, "simulate_deterministic", {"with_parameters_does_not_mutate"}),
    (WritesInput, "simulate_leaves_input", set()),
    (TakesAnyColumns, "refuses_wrong_columns", set()),
    # with_parameters(its own values) has the copy's bounds, so is not == the model.
    (WidensBounds, "with_parameters_values", {"equality"}),
    (DropsSettings, "with_parameters_settings", set()),
    # The difference quotients move the model they differentiate.
    (Mutates, "with_parameters_does_not_mutate", {"jacobian"}),
    (AlwaysEqual, "equality", set()),
    # A config JSON cannot hold cannot be written to a model file.
    (SetConfig, "config_json", {"save_load", "save_load_settings"}),
    (ForgetsStep, "save_load", set()),
    (ForgetsFixed, "save_load_settings", set()),
    (WrongColumn, "jacobian", set()),
    (NoStarts, "starts", set()),
    (OtherLinearStart, "linear_start", set()),
    (RealResponse, "frequency_response", set()),
    (PenaltySign, "penalty", set()),
]


def test_good_passes_every_check():
    report = check_model(lambda: Good(dt=0.2))
    assert list(report) == list(CHECKS) and set(report.values()) == {"passed"}


@pytest.mark.parametrize("kind, check, also", BROKEN, ids=[k.__name__ for k, _, _ in BROKEN])
def test_each_check_fails_on_the_kind_that_breaks_it(kind, check, also):
    factory = (lambda: kind(dt=0.2)) if kind is ForgetsStep else kind
    with pytest.raises(ModelCheckError) as err:
        check_model(factory)                    # every check, stopping at the first failure
    assert err.value.check == check and err.value.kind == kind.__name__
    assert str(err.value).startswith(f"{kind.__name__}: check {check!r} failed: ")
    failing = set()
    for name in CHECKS:
        try:
            check_model(factory, checks=[name])
        except ModelCheckError as exc:
            assert exc.check == name
            failing.add(name)
    assert failing == {check} | also


def test_every_check_has_a_kind_that_breaks_it():
    assert {check for _, check, _ in BROKEN} == set(CHECKS)


@pytest.mark.parametrize("kind, words", [
    (ListParameters, "`parameters` must be a fohw.Parameters; got list"),
    (TwinNames, "two parameters are named 'a'"),
    (FloatInputs, "`n_inputs` must be a positive integer (the input's columns); got 1.0"),
    (NegativeStep, "`dt` must be positive and finite; got -0.1"),
    (ListOutput, "simulate(u) must return a numpy array; got list"),
    (Remembers, "simulate(u) gave another output the second time"),
    (WritesInput, "simulate(u) changed the caller's array `u`"),
    (TakesAnyColumns, "check_input(u) took an input of shape (100, 2) (2 columns; the kind takes 1)"),
    (WidensBounds, "'a' has bounds (-1.0, 1.0), not (-0.99, 0.99)"),
    (DropsSettings, "with 'a' fixed and 'b' at 2.1 in the bounds (1.8, 2.2) did not keep them: 'a' "
                    "has fixed False, not True"),
    (Mutates, "with_parameters changed the original model: 'a' has the value 0.601, not 0.6"),
    (AlwaysEqual, "a model with other parameter values compares equal to it"),
    (SetConfig, "config() must hold JSON values only"),
    (ForgetsFixed, "written and read back, lost them: 'a' has fixed False, not True"),
    (WrongColumn, "jacobian(u)'s column 1 ('b') differs from the difference quotient"),
    (NoStarts, "starts(u, y) gave no start"),
    (OtherLinearStart, "linear_start(u, y) gave a Good, not a OtherLinearStart"),
    (RealResponse, "frequency_response(omega) must return a complex array; got float64"),
    (PenaltySign, "penalty()'s column 0 ('a') differs from the difference quotient"),
])
def test_the_message_says_what_was_found(kind, words):
    with pytest.raises(ModelCheckError) as err:
        check_model(kind)
    assert words in err.value.reason


def test_a_model_read_back_with_another_step_is_named():
    with pytest.raises(ModelCheckError, match="the model read back is not equal"):
        check_model(ForgetsStep(dt=0.2), checks=["save_load"])


def test_the_error_is_an_assertion_and_a_fohw_error():
    with pytest.raises(ModelCheckError) as err:
        check_model(NoStarts)
    assert isinstance(err.value, AssertionError) and isinstance(err.value, fohw.FohwError)
    assert err.value.check == "starts" and err.value.kind == "NoStarts"


def test_an_exception_inside_the_kind_is_reported_under_its_check():
    class Raises(Good):
        def starts(self, u, y):
            raise KeyError("boom")

    with pytest.raises(ModelCheckError, match=r"Raises: check 'starts' failed: starts\(u, y\) "
                                              r"raised KeyError: 'boom'"):
        check_model(Raises)


def test_the_default_input_is_named_when_the_kind_refuses_it():
    class Positive(Good):
        def simulate(self, u, *, initial=None):
            if np.min(u) < 0:
                raise fohw.ParameterError("`u` must be non-negative.")
            return super().simulate(u)

    with pytest.raises(ModelCheckError, match="check_model's default, standard normal samples; "
                                              "pass `u`"):
        check_model(Positive)
    u = np.random.default_rng(1).uniform(0.0, 1.0, 50)
    assert check_model(Positive, u=u)["simulate"] == "passed"


def test_two_inputs_and_absent_hooks():
    class TwoGains(fohw.Model):
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

    report = check_model(TwoGains(0.5, -2.0))
    absent = {name: why for name, why in report.items() if why != "passed"}
    assert absent == {"jacobian": "not applicable: the kind has no exact jacobian",
                      "linear_start": "not applicable: the kind has no linear start",
                      "frequency_response": "not applicable: the kind has no frequency_response",
                      "penalty": "not applicable: the kind has no penalty"}


def test_fully_fixed_parameters_have_no_settings_to_check():
    class Fixed(Good):
        @property
        def parameters(self):
            return fohw.Parameters([fohw.Parameter("a", self.a, fixed=True),
                                    fohw.Parameter("b", self.b, fixed=True)])

    report = check_model(Fixed)
    assert report["with_parameters_settings"] == "not applicable: no free parameter"
    assert report["save_load_settings"] == "not applicable: no free parameter"


def test_checks_selects_and_orders():
    assert list(check_model(Good, checks=["penalty", "parameters"])) == ["parameters", "penalty"]
    assert list(check_model(Good, checks="dt")) == ["dt"]


@pytest.mark.parametrize("kwargs, match", [
    ({"checks": ["parameters", "nope"]}, r"`checks` has unknown check\(s\) \['nope'\]"),
    ({"rtol": 0.0}, "`rtol` must be positive and finite; got 0.0"),
    ({"rtol": float("nan")}, "`rtol` must be positive and finite"),
])
def test_bad_arguments_are_refused(kwargs, match):
    with pytest.raises(fohw.ParameterError, match=match):
        check_model(Good, **kwargs)


def test_a_factory_that_gives_no_model_is_refused():
    with pytest.raises(fohw.ParameterError, match="`factory` must return a fohw.Model; it "
                                                  "returned int"):
        check_model(lambda: 3)
    with pytest.raises(fohw.ParameterError, match="`factory` must be a fohw.Model or a callable"):
        check_model(3)


def test_rtol_is_the_jacobians_tolerance():
    # WrongColumn's column is 1e-3 off: a tolerance of 1e-2 lets it pass, the default does not.
    assert check_model(WrongColumn, checks=["jacobian"], rtol=1e-2)["jacobian"] == "passed"
    with pytest.raises(ModelCheckError):
        check_model(WrongColumn, checks=["jacobian"])


def test_each_check_gets_a_fresh_model():
    made = []

    def factory():
        made.append(Good())
        return made[-1]

    check_model(factory, checks=["parameters", "simulate", "equality"])
    assert len(made) >= 4 and len({id(m) for m in made}) == len(made)
    model = Mutates()
    with pytest.raises(ModelCheckError):
        check_model(model, checks=["with_parameters_does_not_mutate"])
    assert model.a == 0.6                  # a model given as such: each check works on a copy


def test_iter_checks_runs_one_check_each():
    checks = list(fohw.testing.iter_checks(Good))
    assert [c.name for c in checks] == list(CHECKS)
    assert repr(checks[0]) == "Good-parameters" and checks[0].label == "Good"
    assert checks[0]() == "passed"
    (broken,) = fohw.testing.iter_checks(NoStarts, checks=["starts"])
    with pytest.raises(ModelCheckError, match="'starts'"):
        broken()


_CELL = np.column_stack([np.repeat([1.0, -2.0, 0.5, 0.0], 25), np.linspace(0.9, 0.7, 100)])


def cell():
    return fohw.EquivalentCircuit(["zarc"], ocv=fohw.OCVTable([0.0, 1.0], [3.3, 4.2]),
                                  tau_bounds=(1.0, 500.0))


@fohw.testing.parametrize_with_checks([Good, (cell, _CELL)], checks=["simulate", "jacobian"])
def test_parametrize_with_checks(model_check):
    assert model_check() == "passed"


def test_parametrize_with_checks_makes_one_test_per_kind_and_check():
    mark = fohw.testing.parametrize_with_checks([Good, (cell, _CELL)], checks=["simulate", "starts"])
    argname, params = mark.args
    assert argname == "model_check"
    assert [repr(p) for p in params] == ["Good-simulate", "Good-starts", "cell-simulate",
                                         "cell-starts"]
    assert mark.kwargs["ids"] == [repr(p) for p in params]


def test_import_fohw_does_not_load_it_nor_it_pytest():
    code = ("import sys, fohw; assert 'fohw.testing' not in sys.modules; import fohw.testing; "
            "assert 'pytest' not in sys.modules and fohw.testing.CHECKS; print('ok')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
