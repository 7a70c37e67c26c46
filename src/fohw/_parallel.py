"""Running independent tasks serially or on any ``concurrent.futures.Executor``.

fohw depends on no engine: a caller passes ``executor=None`` (serial, in this process), a
:class:`concurrent.futures.ProcessPoolExecutor`, or dask's ``Client.get_executor()``. Results
come back in task order whatever the backend, so tables are identical.
"""

from __future__ import annotations

import sys
from concurrent.futures import Executor

from .exceptions import ParameterError

__all__ = ["run_tasks", "progress_bar"]


class TaskError:
    """A task that raised inside the executor machinery (pickling, a lost worker, ...)."""

    def __init__(self, exc):
        self.exception = exc
        self.message = f"{type(exc).__name__}: {exc}"


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
        worker) gives a :class:`TaskError` in its place, so one task never loses the others.
        Exceptions raised by ``fn`` itself are the caller's to catch inside ``fn``.
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
            except Exception as exc:          # e.g. an argument that cannot be pickled
                futures.append(TaskError(exc))
        for future in futures:
            if isinstance(future, TaskError):
                out.append(future)
            else:
                try:
                    out.append(future.result())
                except Exception as exc:      # the executor's failure, not fn's
                    out.append(TaskError(exc))
            bar.update(1)
        return out
    finally:
        bar.close()
