"""Running independent tasks serially or on any ``concurrent.futures.Executor``.

fohw depends on no engine: a caller passes ``executor=None`` (serial, in this process), a
:class:`concurrent.futures.ProcessPoolExecutor`, or dask's ``Client.get_executor()``. Results
come back in task order whatever the backend, so tables are identical.
"""

from __future__ import annotations

import sys
from concurrent.futures import Executor

from .exceptions import ParameterError

__all__ = ["run_tasks"]


class TaskError:
    """A task that raised inside the executor machinery (pickling, a lost worker, ...)."""

    def __init__(self, exc):
        self.exception = exc
        self.message = f"{type(exc).__name__}: {exc}"


def _progress_bar(total, label, enabled):
    if not enabled:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return _Counter(total, label)
    return tqdm(total=total, desc=label, file=sys.stderr)


class _Counter:
    """A plain ``label: i/total`` counter on stderr (when tqdm is not installed)."""

    def __init__(self, total, label):
        self.total, self.label, self.n = total, label, 0

    def update(self, n=1):
        self.n += n
        print(f"\r{self.label}: {self.n}/{self.total}", end="", file=sys.stderr, flush=True)

    def close(self):
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
    if progress is None:
        progress = sys.stderr.isatty()
    bar = _progress_bar(len(tasks), label, progress)
    out = []
    try:
        if executor is None:
            for task in tasks:
                out.append(fn(*task))
                if bar is not None:
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
            if bar is not None:
                bar.update(1)
        return out
    finally:
        if bar is not None:
            bar.close()
