"""The stages of fohw.fit, one at a time: the problem's free vector, the ranking of the starts
and the verdict on an estimate.

The kinds are a gain ``y = k u`` (linear: its least-squares estimate and covariance are the
textbook ones, ``k = u.y / u.u`` and ``s^2 / u.u``) and a first-order lag with an offset whose
free run is a recursion written here; every expected number comes from those, not from fohw.
"""

from types import SimpleNamespace

import numpy as np
import pytest

import fohw
from fohw.estimators.fit import (
    ESCAPE,
    _Data,
    _Estimate,
    _Problem,
    _ranked_starts,
    _verdict,
    prepare_data,
)


class Gain(fohw.Model):
    """``y = k u``."""

    kind = "TestFitStagesGain"

    def __init__(self, k=1.0):
        self.k = float(k)

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("k", self.k, bounds=(-10.0, 10.0))])

    def with_parameters(self, values):
        return Gain(self.parameters.with_values(values).valuesdict()["k"])

    def simulate(self, u, *, initial=None):
        return self.k * self.check_input(u)


class OffsetLag(fohw.Model):
    """``y[k] = x[k] + c`` with ``x[k] = a x[k-1] + b u[k-1]``, ``x[0] = 0``."""

    kind = "TestFitStagesOffsetLag"

    def __init__(self, a=0.5, b=1.0, c=0.0):
        self.a, self.b, self.c = float(a), float(b), float(c)

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b), fohw.Parameter("c", self.c)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return OffsetLag(v["a"], v["b"], v["c"])

    def simulate(self, u, *, initial=None):
        return lag_run(self.a, self.b, self.check_input(u)) + self.c


class ExactOffsetLag(OffsetLag):
    """OffsetLag with its exact Jacobian: the sensitivity recursions of a and b, and 1 for c."""

    kind = "TestFitStagesExactOffsetLag"

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return ExactOffsetLag(v["a"], v["b"], v["c"])

    def jacobian(self, u):
        u = self.check_input(u)
        x = lag_run(self.a, self.b, u)
        da, db = np.zeros(u.size), np.zeros(u.size)
        for k in range(1, u.size):
            da[k] = x[k - 1] + self.a * da[k - 1]
            db[k] = u[k - 1] + self.a * db[k - 1]
        return x + self.c, np.column_stack([da, db, np.ones(u.size)])


def lag_run(a, b, u):
    x = np.zeros(u.size)
    for k in range(1, u.size):
        x[k] = a * x[k - 1] + b * u[k - 1]
    return x


def problem_of(model, u, y=None, per_record=()):
    experiments, _ = prepare_data(model, u, y, None, 0)
    return _Problem(model, model.parameters, _Data(experiments), tuple(per_record), True)


@pytest.mark.parametrize("kind, how", [(OffsetLag, "finite differences"),
                                       (ExactOffsetLag, "exact")])
def test_the_free_vector_holds_the_shared_values_then_each_records_copies(kind, how):
    rng = np.random.default_rng(0)
    recs = [fohw.Record(u=rng.standard_normal(30), y=rng.standard_normal(30)) for _ in range(3)]
    problem = problem_of(kind(), recs, per_record=["c"])
    assert problem.names == ("a", "b", "c") and problem.extra_names == ["c[1]", "c[2]"]
    # record 0's c is the model's own; records 1 and 2 follow the shared values
    assert [problem.column(0, r) for r in range(3)] == [2, 3, 4]
    np.testing.assert_array_equal(problem.extend([0.5, 2.0, 7.0]), [0.5, 2.0, 7.0, 7.0, 7.0])
    x = np.array([0.5, 2.0, 7.0, -1.0, 3.0])
    assert [problem.at(x, r).c for r in range(3)] == [7.0, -1.0, 3.0]
    assert all(problem.at(x, r).a == 0.5 for r in range(3))
    # d yhat / d c is 1 on its own record's rows and 0 on the others'
    _, jac, got = problem.full_jacobian(x)
    assert got == how and jac.shape == (90, 5)
    for r in range(3):
        rows = slice(30 * r, 30 * (r + 1))
        np.testing.assert_allclose(jac[rows, problem.column(0, r)], 1.0, rtol=1e-8)
        for other in set(range(3)) - {r}:
            assert not np.any(jac[rows, problem.column(0, other)])
    # the bounds of the copies are those of c
    np.testing.assert_array_equal(problem.lower, [-0.99, -np.inf, -np.inf, -np.inf, -np.inf])


def test_the_starts_are_ranked_by_simulation_error_and_those_off_bounds_skipped():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(200)
    y = lag_run(0.8, 2.0, u) + 0.1 + 0.05 * rng.standard_normal(200)
    # the fit's bounds on a are (0, 0.9): a start at a = -0.5 is the kind's but not the fit's
    start = OffsetLag().with_parameters(OffsetLag().parameters.replace("a", bounds=(0.0, 0.9)))
    problem = problem_of(start, u, y)
    candidates = [OffsetLag(0.3, 1.0), OffsetLag(0.8, 2.0, 0.1), OffsetLag(-0.5, 2.0),
                  OffsetLag(0.6, 1.5), OffsetLag(0.3, 1.0),          # a repeat
                  OffsetLag(0.5, 1e6)]                                 # beyond ESCAPE max|y|
    table = _ranked_starts(problem, candidates)

    def sse(a, b, c=0.0):
        return float(np.sum((y - lag_run(a, b, u) - c) ** 2))

    inside = [(0.3, 1.0, 0.0), (0.8, 2.0, 0.1), (0.6, 1.5, 0.0)]
    expected = sorted((sse(*p), p) for p in inside)
    assert [x for _, x in table[:3]] == [p for _, p in expected]
    np.testing.assert_allclose([s for s, _ in table[:3]], [s for s, _ in expected], rtol=1e-12)
    # the escaping run (|yhat| ~ 1e6 against max|y| ~ 10) ranks last, at inf
    assert np.max(np.abs(OffsetLag(0.5, 1e6).simulate(u))) > ESCAPE * np.max(np.abs(y))
    assert table[3] == (np.inf, (0.5, 1e6, 0.0)) and len(table) == 4
    # every candidate inside the bounds was simulated, the repeat too; the one outside not
    assert problem.nfev == 5


def _estimate(problem, k, *, ls_status, sse0):
    x = np.array([k])
    r = problem.residual(x)
    ls = SimpleNamespace(status=ls_status, message="`xtol` termination condition is satisfied.",
                         x=x, fun=r)
    return _Estimate(float(r @ r), x, fohw.Status.CONVERGED, ls, sse0)


def test_a_search_that_made_no_step_from_a_non_stationary_start_is_failed():
    rng = np.random.default_rng(2)
    u = rng.standard_normal(100)
    y = 3.0 * u + 0.1 * rng.standard_normal(100)
    problem = problem_of(Gain(), u, y)
    k_hat = float(u @ y / (u @ u))
    # ended where it started (the criterion there is the start's), half a unit off the optimum
    stuck = _estimate(problem, k_hat + 0.5, ls_status=3, sse0=float(np.sum((y - (k_hat + 0.5) * u) ** 2)))
    verdict = _verdict(problem, stuck, max_nfev=200)
    assert verdict.status == fohw.Status.FAILED
    assert "stuck at its start" in verdict.messages[-1]
    # the same stop at the least-squares optimum is a converged search that needed no step
    at_optimum = _estimate(problem, k_hat, ls_status=3, sse0=float(np.sum((y - k_hat * u) ** 2)))
    verdict = _verdict(problem, at_optimum, max_nfev=200)
    assert verdict.status == fohw.Status.CONVERGED and len(verdict.messages) == 1
    # its covariance is the linear one, s^2 / u.u with s^2 = sse / (N - 1)
    sse = float(np.sum((y - k_hat * u) ** 2))
    assert verdict.sse == pytest.approx(sse, rel=1e-12)
    assert verdict.full_cov[0, 0] == pytest.approx(sse / 99 / float(u @ u), rel=1e-9)
    # a search that lowered the criterion from its start is not stuck, wherever it stopped
    moved = _estimate(problem, k_hat + 0.5, ls_status=3, sse0=1e6)
    assert _verdict(problem, moved, max_nfev=200).status == fohw.Status.CONVERGED
