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

import os
import sys
from concurrent.futures import FIRST_COMPLETED, CancelledError, Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from .exceptions import ParameterError

__all__ = ["run_tasks", "progress_bar", "TaskError"]

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
                pool = ProcessPoolExecutor(1)
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
