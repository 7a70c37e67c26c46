"""BLAS threads during fohw's thin solves (fohw._threads; optional threadpoolctl)."""

import numpy as np
import pytest

import fohw
import fohw._threads as threads

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def test_without_threadpoolctl_blas_is_left_as_configured(monkeypatch):
    monkeypatch.setattr(threads, "ThreadpoolController", None)
    with threads.one_blas_thread() as ctx:
        assert ctx is None                       # nullcontext: nothing changed
    d = fohw.datasets.paper_example(500, random_state=0)
    assert np.isfinite(fohw.identify(d.u, d.y, method="varpro", **STRUCT).alpha)


def test_the_solves_ask_threadpoolctl_for_one_blas_thread(monkeypatch):
    """With a stand-in for threadpoolctl: varpro's solves ask for exactly one BLAS thread,
    through the controller. (The stand-in limits nothing, so the equal estimates only show the
    wrapper passes results through; the test below checks the numbers with the real library.)"""
    from contextlib import nullcontext

    calls = []

    class Controller:
        def limit(self, **kwargs):
            calls.append(kwargs)
            return nullcontext()

    d = fohw.datasets.paper_example(500, random_state=0)
    monkeypatch.setattr(threads, "ThreadpoolController", None)
    free = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    monkeypatch.setattr(threads, "ThreadpoolController", Controller)
    monkeypatch.setattr(threads, "_controller", None)
    limited = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    assert calls and all(c == {"limits": 1, "user_api": "blas"} for c in calls)
    np.testing.assert_array_equal(limited.theta, free.theta)


def test_with_threadpoolctl_solves_run_on_one_blas_thread_and_give_the_same_numbers(monkeypatch):
    threadpoolctl = pytest.importorskip("threadpoolctl")

    def blas_threads():
        return [i["num_threads"] for i in threadpoolctl.threadpool_info()
                if i["user_api"] == "blas"]

    before = blas_threads()
    with threads.one_blas_thread():
        assert blas_threads() and set(blas_threads()) == {1}
    assert blas_threads() == before                   # the caller's setting comes back
    d = fohw.datasets.paper_example(2000, random_state=0)
    limited = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    monkeypatch.setattr(threads, "ThreadpoolController", None)
    free = fohw.identify(d.u, d.y, method="varpro", **STRUCT)
    np.testing.assert_allclose(limited.theta, free.theta, rtol=0, atol=1e-12)
    assert abs(limited.alpha - free.alpha) <= 1e-12
