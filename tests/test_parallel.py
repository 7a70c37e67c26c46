"""fohw._parallel: tasks in order on any executor, and the one progress display."""

import os
import sys
import threading
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor

import pytest

from fohw._parallel import TaskError, progress_bar, run_tasks


def test_progress_is_silent_unless_asked_or_on_a_terminal(capsys):
    bar = progress_bar(3, "job")                    # stderr is captured: not a terminal
    bar.update(1)
    bar.write("stage")
    bar.close()
    assert capsys.readouterr().err == ""


def test_stage_messages_and_the_plain_counter(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)          # tqdm not installed
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    stages = progress_bar(None, "robot-arm", True)
    stages.write("structure scan")
    stages.close()
    assert capsys.readouterr().err == "robot-arm: structure scan\n"
    bar = progress_bar(2, "tasks", True)
    bar.update(1)
    bar.update(1)
    bar.close()
    assert capsys.readouterr().err == "\rtasks: 1/2\rtasks: 2/2\n"


@pytest.mark.parametrize("progress", [False, True])
def test_run_tasks_keeps_the_order(progress, capsys):
    assert run_tasks(pow, [(2, 3), (3, 2)], progress=progress) == [8, 9]


# issue 28 (28b) -------------------------------------------------------------------------------
def die_in_a_worker(i, main_pid):
    """Kill the worker process that runs task 2 (never the test's own process)."""
    if i == 2 and os.getpid() != main_pid:
        os._exit(3)
    return i * i


def test_a_task_that_kills_its_worker_loses_only_itself():
    # Before: every task still in the pool came back as BrokenProcessPool.
    with ProcessPoolExecutor(2) as pool:
        out = run_tasks(die_in_a_worker, [(i, os.getpid()) for i in range(6)],
                        executor=pool)
    assert [o for i, o in enumerate(out) if i != 2] == [0, 1, 9, 16, 25]
    assert isinstance(out[2], TaskError)
    assert "this task kills its worker" in out[2].message


class CancellingExecutor(Executor):
    """An executor whose tasks are cancelled before they run (a shut-down or closed client)."""

    def submit(self, fn, /, *args, **kwargs):
        future = Future()
        future.cancel()
        return future


def test_a_cancelled_task_says_what_happened():
    # Before: "CancelledError: " with nothing after it.
    out = run_tasks(pow, [(2, 3)], executor=CancellingExecutor())
    assert isinstance(out[0], TaskError)
    assert out[0].message.startswith("it was cancelled before it finished")
    assert "client closed" in out[0].message


def slow_square(i):
    time.sleep(0.4)
    return i * i


@pytest.mark.slow
def test_dask_killed_worker_and_closed_client_say_so():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            out = run_tasks(die_in_a_worker, [(i, os.getpid()) for i in range(4)],
                            executor=client.get_executor())
        # dask counts a worker's death against every task queued on it, so under load a
        # healthy task can be given up too: then its row must say so, never be wrong or blank
        assert "dask workers that ran it died" in out[2].message
        assert all(o == i * i if not isinstance(o, TaskError)
                   else "dask workers that ran it died" in o.message for i, o in enumerate(out))
        assert any(not isinstance(o, TaskError) for o in out)
        client = distributed.Client(cluster)
        threading.Timer(1.0, client.close).start()       # 10 x 0.4 s on 2 workers: 2 s
        out = run_tasks(slow_square, [(i,) for i in range(10)],
                        executor=client.get_executor())
    lost = [o for o in out if isinstance(o, TaskError)]
    assert lost and all("client closed" in o.message for o in lost)
    assert all(o == i * i for i, o in enumerate(out) if not isinstance(o, TaskError))
