"""Running independent tasks serially or on any ``concurrent.futures.Executor``.

fohw depends on no engine: a caller passes ``executor=None`` (serial, in this process), a
:class:`concurrent.futures.ProcessPoolExecutor`, or dask's ``Client.get_executor()``. Results
come back in task order whatever the backend, so tables are identical.

One task never loses the others: a task whose worker process dies (``os._exit``, a segfault,
the out-of-memory killer) breaks a ``ProcessPoolExecutor`` and with it every task still in it;
those tasks are run again, each alone in a fresh one-worker process pool, so only the task
that kills its worker is lost (:class:`TaskError`, saying so). dask retries a task whose worker
died on other workers by itself and gives up with ``KilledWorker``; a client closed during the
run cancels its tasks. Each case gets a message that says what happened.
"""

from __future__ import annotations

import numbers
import os
import sys
import threading
from concurrent.futures import FIRST_COMPLETED, CancelledError, Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from .exceptions import ParameterError

__all__ = ["run_tasks", "progress_bar", "TaskError", "end_with_parent", "process_pool", "max_jobs",
           "check_jobs"]

#: How often (seconds) a worker's watchdog looks whether its parent process is still there.
PARENT_POLL = 0.5


def end_with_parent(parent=None, poll=PARENT_POLL):
    """Initializer of a worker process: end it when its parent process dies.

    ``ProcessPoolExecutor(initializer=fohw.end_with_parent)``. Without it a pool's workers
    outlive a parent killed by SIGKILL (measured: both workers of ``fohw select --jobs 2`` alive
    120 s after the kill), since nothing tells them. On Linux the kernel sends the worker
    SIGTERM when the parent's thread that started it ends (``prctl(PR_SET_PDEATHSIG)``); on
    every system a daemon thread looks every ``poll`` seconds whether the parent is still the
    worker's parent and ends the worker (``os._exit``) when it is not.

    Parameters
    ----------
    parent : int, optional
        The process id of the pool's creator (:func:`process_pool` passes it); default: this
        process's parent when the initializer runs. The worker also ends when its immediate
        parent (the creator, or a fork server) is gone.
    poll : float, optional
        Seconds between two looks of the watchdog thread (default 0.5).

    Examples
    --------
    >>> from concurrent.futures import ProcessPoolExecutor
    >>> import fohw
    >>> with ProcessPoolExecutor(2, initializer=fohw.end_with_parent) as pool:   # doctest: +SKIP
    ...     rows = fohw.monte_carlo({"varpro": {"method": "varpro"}}, executor=pool)
    """
    if isinstance(poll, bool) or not isinstance(poll, numbers.Real) or not 0.0 < poll <= 60.0:
        raise ParameterError(f"`poll` must be a number of seconds in (0, 60]; got {poll!r}.")
    creator = os.getppid() if parent is None else int(parent)
    parent = os.getppid()                   # the creator, or a fork server that ends with it
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGTERM), 0, 0, 0)          # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):                        # pragma: no cover - no libc
            pass
    def orphaned():
        if os.getppid() != parent:
            return True
        try:
            os.kill(creator, 0)
        except ProcessLookupError:
            return True
        except OSError:                     # it exists, owned by another user
            pass
        return False

    if orphaned():                          # the parent died before the signal was armed
        os._exit(1)

    def watch():
        pause = threading.Event()
        while not pause.wait(poll):
            if orphaned():
                os._exit(1)

    threading.Thread(target=watch, name="fohw-end-with-parent", daemon=True).start()


def process_pool(max_workers):
    """A ``ProcessPoolExecutor`` whose workers end when this process dies (:func:`end_with_parent`)."""
    return ProcessPoolExecutor(max_workers, initializer=end_with_parent, initargs=(os.getpid(),))


def max_jobs():
    """The processors this process may use (its CPU affinity; ``os.cpu_count()`` elsewhere)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:                  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def check_jobs(jobs, name="n_jobs", *, negative=False):
    """``jobs`` worker processes as an int from 1 to :func:`max_jobs`, or a ParameterError.

    ``negative=True`` also allows joblib's ``-1`` (every processor) down to ``-max_jobs()``.
    More workers than processors only add start-up time (measured: ``fohw select --jobs 1000``
    took 56.6 s for two candidates, 0.5 s with ``--jobs 1``).
    """
    limit = max_jobs()
    if isinstance(jobs, bool) or not isinstance(jobs, numbers.Integral):
        raise ParameterError(f"`{name}` must be an integer; got {jobs!r}.")
    jobs = int(jobs)
    if negative and -limit <= jobs <= -1:
        return jobs
    if not 1 <= jobs <= limit:
        also = f" (or -1 to -{limit}, counted from the processors)" if negative else ""
        raise ParameterError(f"`{name}` must be from 1 to {limit}, the processors this process may "
                             f"use{also}; got {jobs}. More worker processes than processors only "
                             "add start-up time.")
    return jobs

#: A task lost with its broken process pool, before its rerun.
_LOST = object()


def _explain(exc, isolated=False):
    """What happened to a task, in words, from the executor's exception."""
    name = type(exc).__name__
    text = str(exc).strip()
    if isinstance(exc, BrokenProcessPool):
        if isolated:
            return ("its worker process died while running it (killed, out of memory, a crash "
                    "or os._exit), again when it was rerun alone in a fresh process: this task "
                    f"kills its worker ({name})")
        return f"its worker process died and the pool broke ({name}: {text})"
    if name == "KilledWorker":              # distributed.scheduler.KilledWorker
        return ("the dask workers that ran it died while running it, each time dask retried it "
                f"(killed, out of memory, a crash or os._exit) ({name}: {text})")
    if isinstance(exc, CancelledError) or name == "CancelledError":
        return ("it was cancelled before it finished: the executor was shut down, or its dask "
                "client closed, during the run" + (f" ({text})" if text else ""))
    return f"{name}: {text}" if text else name


class TaskError:
    """A task that could not be run or collected by the executor (pickling, a lost worker, ...).

    ``exception`` is the executor's exception; ``message`` says in words what happened.
    """

    def __init__(self, exc, *, isolated=False):
        self.exception = exc
        self.message = _explain(exc, isolated)


def progress_bar(total, label, enabled=None):
    """Progress on stderr: a bar over ``total`` steps, or stage messages (``total=None``).

    Parameters
    ----------
    total : int or None
        Steps of the bar (tqdm if installed, else a plain ``label: i/total`` counter); ``None``
        for stage messages only (:meth:`write`).
    label : str
        Shown beside the count and before every message (``label: message``).
    enabled : bool, optional
        Default (None): only when stderr is a terminal, never in pipes, files or tests.

    Returns
    -------
    object
        With ``update(n=1)``, ``write(message)`` and ``close()``; they do nothing when
        disabled.
    """
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return _Silent()
    if total is not None:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            pass
        else:
            return _Tqdm(tqdm(total=total, desc=label, file=sys.stderr), label)
    return _Counter(total, label)


class _Silent:
    """A disabled progress display."""

    def update(self, n=1):
        pass

    def write(self, message):
        pass

    def close(self):
        pass


class _Tqdm:
    """A tqdm bar whose messages go to stderr above it."""

    def __init__(self, bar, label):
        self.bar, self.label = bar, label

    def update(self, n=1):
        self.bar.update(n)

    def write(self, message):
        self.bar.write(f"{self.label}: {message}", file=sys.stderr)

    def close(self):
        self.bar.close()


class _Counter:
    """A plain ``label: i/total`` counter and ``label: message`` lines on stderr."""

    def __init__(self, total, label):
        self.total, self.label, self.n = total, label, 0

    def update(self, n=1):
        self.n += n
        print(f"\r{self.label}: {self.n}/{self.total}", end="", file=sys.stderr, flush=True)

    def write(self, message):
        if self.n:                                    # below the counter's line
            print(file=sys.stderr)
        print(f"{self.label}: {message}", file=sys.stderr, flush=True)

    def close(self):
        if self.total is not None:
            print(file=sys.stderr, flush=True)


def run_tasks(fn, tasks, *, executor=None, progress=None, label="tasks"):
    """``[fn(*task) for task in tasks]``, serially or on ``executor``, in task order.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled for process and dask executors).
    tasks : sequence of tuple
        Positional arguments of each call.
    executor : concurrent.futures.Executor, optional
        Where to run the calls; default (None) serially in this process.
    progress : bool, optional
        A progress bar on stderr (tqdm if installed, a plain counter otherwise); default: only
        when stderr is a terminal.
    label : str
        Name shown beside the progress count.

    Returns
    -------
    list
        The return values; a call that could not be run or collected (a pickling error, a lost
        worker) gives a :class:`TaskError` in its place, so one task never loses the others:
        the tasks of a process pool broken by a dying worker are rerun, each alone in a fresh
        one-worker pool (at most ``os.cpu_count()`` at a time), so only the task that kills its
        worker is lost. Exceptions raised by ``fn`` itself are the caller's to catch inside
        ``fn``.
    """
    if executor is not None and not isinstance(executor, Executor):
        raise ParameterError("`executor` must be a concurrent.futures.Executor (e.g. a "
                             "ProcessPoolExecutor, or dask's Client.get_executor()) or None; "
                             f"got {type(executor).__name__}.")
    bar = progress_bar(len(tasks), label, progress)
    out = []
    try:
        if executor is None:
            for task in tasks:
                out.append(fn(*task))
                bar.update(1)
            return out
        futures = []
        for task in tasks:
            try:
                futures.append(executor.submit(fn, *task))
            except BrokenProcessPool:         # broken by an earlier task: rerun it alone
                futures.append(_LOST)
            except Exception as exc:          # e.g. an argument that cannot be pickled
                futures.append(TaskError(exc))
        broken = []
        for i, future in enumerate(futures):
            if future is _LOST or isinstance(future, TaskError):
                out.append(future)
            else:
                try:
                    out.append(future.result())
                except BrokenProcessPool:     # lost with the pool, maybe not its fault
                    out.append(_LOST)
                except Exception as exc:      # the executor's failure, not fn's
                    out.append(TaskError(exc))
            if out[-1] is _LOST:
                broken.append(i)
            else:
                bar.update(1)
        if broken:
            _run_isolated(fn, tasks, broken, out, bar)
        return out
    finally:
        bar.close()


def _run_isolated(fn, tasks, indices, out, bar):
    """Rerun ``tasks[indices]``, each alone in a fresh one-worker process pool.

    A task that kills its worker then loses only itself. At most ``os.cpu_count()`` pools run
    at a time.
    """
    workers = max(1, min(len(indices), os.cpu_count() or 1))
    queue = list(indices)
    running = {}
    try:
        while queue or running:
            while queue and len(running) < workers:
                i = queue.pop(0)
                pool = process_pool(1)
                try:
                    running[pool.submit(fn, *tasks[i])] = (i, pool)
                except Exception as exc:       # noqa: BLE001 - reported as the task's error
                    out[i] = TaskError(exc, isolated=True)
                    pool.shutdown(wait=False)
                    bar.update(1)
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                i, pool = running.pop(future)
                try:
                    out[i] = future.result()
                except Exception as exc:       # noqa: BLE001 - reported as the task's error
                    out[i] = TaskError(exc, isolated=True)
                pool.shutdown(wait=True)
                bar.update(1)
    finally:
        for _, pool in running.values():
            pool.shutdown(wait=False, cancel_futures=True)
