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

from .exceptions import ParameterError, TaskTimeoutError

__all__ = ["run_tasks", "stream_tasks", "as_executor", "progress_bar", "heartbeat", "TaskError",
           "end_with_parent", "process_pool", "max_jobs", "check_jobs"]

#: How often (seconds) a worker's watchdog looks whether its parent process is still there.
PARENT_POLL = 0.5


def end_with_parent(parent=None, poll=PARENT_POLL):
    """Initializer of a worker process: end it when its parent process dies.

    ``ProcessPoolExecutor(initializer=end_with_parent)``, imported from :mod:`fohw.analysis.batch`
    (this module is private). Without it a pool's workers outlive a parent killed by SIGKILL
    (measured: both workers of ``fohw select --jobs 2`` alive 120 s after the kill), since
    nothing tells them. On Linux the kernel sends the worker SIGTERM when the parent's thread
    that started it ends (``prctl(PR_SET_PDEATHSIG)``); on every system a daemon thread looks
    every ``poll`` seconds whether the parent is still the worker's parent and ends the worker
    (``os._exit``) when it is not.

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
    >>> from fohw.analysis.batch import end_with_parent
    >>> with ProcessPoolExecutor(2, initializer=end_with_parent) as pool:   # doctest: +SKIP
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


#: Seconds a piece of work runs before its progress shows, when nobody asked (``progress=None``):
#: short calls stay silent, long ones are never silent.
AUTO_DELAY = 2.0
#: Seconds between two plain progress lines written to a file or a pipe (not a terminal).
LINE_INTERVAL = 10.0

_active = [0]          # progress displays open in this process (an inner one stays quiet)


def _auto_allowed():
    """Automatic progress: in the main process, outside another progress display."""
    import multiprocessing

    return _active[0] == 0 and multiprocessing.parent_process() is None


def progress_bar(total, label, enabled=None, *, counting=False):
    """Progress on stderr: a bar over ``total`` steps, or stage messages (``total=None``).

    Parameters
    ----------
    total : int or None
        Steps of the bar (tqdm's ``tqdm.auto`` if installed, a widget in a notebook; else a
        plain ``label: i/total`` counter); ``None`` for stage messages only (:meth:`write`),
        or, with ``counting=True``, a count of steps whose total is not known.
    label : str
        Shown beside the count and before every message (``label: message``).
    enabled : bool, optional
        True: shown from the start. False: nothing. None (default): a bar shows once the work
        has run for :data:`AUTO_DELAY` seconds (terminal, notebook or file alike; in a file or a
        pipe as a line every :data:`LINE_INTERVAL` seconds), never inside another progress
        display or in a worker process; stage messages only when stderr is a terminal.

    Returns
    -------
    object
        With ``update(n=1)``, ``write(message)`` and ``close()``; they do nothing when
        disabled.
    """
    delay = 0.0
    counts = total is not None or counting
    if enabled is None:
        if not counts:
            enabled = sys.stderr.isatty()
        else:
            enabled, delay = _auto_allowed(), AUTO_DELAY
    if not enabled:
        return _Silent()
    if counts:
        bar = _tqdm(total, label, delay)
        if bar is not None:
            return _Tqdm(bar, label, delay)
    return _Counter(total, label, delay, counts)


def _auto_tqdm():
    """``tqdm.auto.tqdm``, or None without tqdm.

    In a notebook without ipywidgets tqdm.auto falls back to its text bar with a TqdmWarning
    ("IProgress not found"); the text bar is what fohw shows then, so that warning is not passed on.
    """
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="IProgress not found")
            from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm


def _tqdm(total, label, delay):
    """A ``tqdm.auto`` bar on stderr (a notebook widget where ipywidgets is installed), or None."""
    tqdm = _auto_tqdm()
    if tqdm is None:
        return None
    tty = sys.stderr.isatty()
    kwargs = dict(total=total, desc=label, file=sys.stderr, delay=delay,
                  mininterval=0.1 if tty else LINE_INTERVAL)
    try:
        return tqdm(**kwargs)
    except ImportError:              # a notebook without ipywidgets: the text bar
        from tqdm.std import tqdm as text_tqdm

        return text_tqdm(**kwargs)


class _Silent:
    """A disabled progress display."""

    def update(self, n=1):
        pass

    def write(self, message):
        pass

    def close(self):
        pass


class _Tqdm:
    """A tqdm bar whose messages go to stderr above it (once the bar shows, after its delay)."""

    def __init__(self, bar, label, delay=0.0):
        import time

        self.bar, self.label = bar, label
        self.clock, self.delay = time.monotonic, delay
        self.start = self.clock()
        _active[0] += 1

    def update(self, n=1):
        self.bar.update(n)

    def write(self, message):
        if self.clock() - self.start >= self.delay:
            self.bar.write(f"{self.label}: {message}", file=sys.stderr)

    def close(self):
        if self.bar is not None:
            self.bar.close()
            self.bar = None
            _active[0] -= 1


class _Counter:
    """The plain display (no tqdm): ``label: i/total`` on stderr, and ``label: message`` lines.

    On a terminal the count is rewritten in place; in a file or a pipe it is a line every
    :data:`LINE_INTERVAL` seconds (and the last count at the end), so a log is never flooded.
    Nothing shows before ``delay`` seconds have passed.
    """

    def __init__(self, total, label, delay=0.0, counts=None):
        import time

        self.total, self.label, self.n = total, label, 0
        self.counts = total is not None if counts is None else counts
        self.clock = time.monotonic
        self.start = self.clock()
        self.delay = delay
        self.tty = sys.stderr.isatty()
        self.last = None              # when a count was last shown
        self.shown = False
        if self.counts:               # a bar, not stage messages: inner bars stay quiet
            _active[0] += 1

    def update(self, n=1):
        self.n += n
        now = self.clock()
        if now - self.start < self.delay:
            return
        if self.tty:
            print(f"\r{self.label}: {self._count()}", end="", file=sys.stderr, flush=True)
            self.shown = True
        elif self.last is None or now - self.last >= LINE_INTERVAL or self.n == self.total:
            self._line(now)

    def _count(self):
        return f"{self.n}/{self.total}" if self.total is not None else f"{self.n} done"

    def _line(self, now):
        print(f"{self.label}: {self._count()} ({now - self.start:.0f} s)", file=sys.stderr,
              flush=True)
        self.last, self.shown, self.last_n = now, True, self.n

    def write(self, message):
        if self.shown and self.tty:                   # below the counter's line
            print(file=sys.stderr)
        print(f"{self.label}: {message}", file=sys.stderr, flush=True)

    def close(self):
        if self.label is None:
            return
        if self.counts and self.shown:
            if self.tty:
                print(file=sys.stderr, flush=True)
            elif self.last is not None and self.n != self.last_n:
                self._line(self.clock())
        if self.counts:
            _active[0] -= 1
        self.label = None


class heartbeat:
    """Progress of one call whose length is not known in steps (``with heartbeat(label, progress)``).

    A background thread shows the elapsed time on stderr (a tqdm bar without a total, or a plain
    ``label: running, 12 s`` line every :data:`LINE_INTERVAL` seconds) from the start with
    ``enabled=True``, after :data:`AUTO_DELAY` seconds with ``enabled=None`` (not inside
    another progress display, not in a worker process), never with False; and, if it showed,
    ``label: done in 12.3 s`` at the end. Progress displays opened inside stay quiet.
    """

    def __init__(self, label, enabled=None):
        self.label = label
        self.delay = 0.0 if enabled else AUTO_DELAY
        self.enabled = enabled is True or (enabled is None and _auto_allowed())
        self.thread = None

    def __enter__(self):
        import threading
        import time

        self.start = time.monotonic()
        if self.enabled:
            self.stop = threading.Event()
            self.shown = False
            self.thread = threading.Thread(target=self._run, name="fohw-progress", daemon=True)
            self.thread.start()
        _active[0] += 1
        return self

    def _run(self):
        import time

        if self.stop.wait(self.delay):
            return
        self.shown = True
        tqdm = _auto_tqdm()
        if tqdm is not None:
            try:
                bar = tqdm(desc=self.label, file=sys.stderr, bar_format="{desc}: running, {elapsed}")
            except ImportError:          # a notebook without ipywidgets
                from tqdm.std import tqdm as text_tqdm

                bar = text_tqdm(desc=self.label, file=sys.stderr,
                                bar_format="{desc}: running, {elapsed}")
            while not self.stop.wait(1.0 if sys.stderr.isatty() else LINE_INTERVAL):
                bar.refresh()
            bar.close()
            return
        while True:
            print(f"{self.label}: running, {time.monotonic() - self.start:.0f} s",
                  file=sys.stderr, flush=True)
            if self.stop.wait(LINE_INTERVAL):
                return

    def __exit__(self, *exc):
        import time

        _active[0] -= 1
        if self.thread is not None:
            self.stop.set()
            self.thread.join()
            if self.shown:
                print(f"{self.label}: done in {time.monotonic() - self.start:.1f} s",
                      file=sys.stderr, flush=True)
        return False


def as_executor(executor):
    """``executor`` as a ``concurrent.futures.Executor`` (or None: serial).

    An executor is itself; a dask.distributed ``Client`` gives its ``get_executor()``;
    anything else is a ParameterError.
    """
    if executor is None or isinstance(executor, Executor):
        return executor
    if type(executor).__module__.split(".")[0] == "distributed" and \
            callable(getattr(executor, "get_executor", None)):
        return executor.get_executor()        # a dask.distributed.Client
    raise ParameterError("`executor` must be a concurrent.futures.Executor (e.g. a "
                         "ProcessPoolExecutor), a dask.distributed Client (or its "
                         f"get_executor()) or None; got {type(executor).__name__}.")


def _workers(executor):
    """How many tasks ``executor`` runs at once, or None where it does not say."""
    n = getattr(executor, "_max_workers", None)          # ProcessPool-, ThreadPoolExecutor
    if isinstance(n, numbers.Integral) and n > 0:
        return int(n)
    client = getattr(executor, "_client", None)          # dask's ClientExecutor
    try:
        return max(1, sum(client.nthreads().values())) if client is not None else None
    except Exception:                     # noqa: BLE001 - a closed client: no hint
        return None


#: Seconds beyond a task's ``timeout`` that :func:`stream_tasks` waits for any task to end
#: before it gives up on the tasks in flight (workers that died without the executor noticing:
#: starting worker processes and moving the data take some of it).
STALL_GRACE = 30.0


def stream_tasks(fn, tasks, *, executor=None, progress=None, label="tasks", total=None,
                 max_pending=None, ordered=True, timeout=None):
    """``(i, fn(*task))`` for each task of an iterable, serially or on ``executor``, as they end.

    The streaming sibling of :func:`run_tasks`: ``tasks`` is read lazily (a generator is
    fine) and at most ``max_pending`` tasks are submitted and not yet yielded at any time, so
    the memory held here does not grow with the number of tasks.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled for process and dask executors).
    tasks : iterable of tuple
        Positional arguments of each call, read one at a time as room frees up.
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where to run the calls; default (None) serially in this process, one at a time.
    progress : bool, optional
        As for :func:`run_tasks`.
    label : str
        Name shown beside the progress count.
    total : int, optional
        The number of tasks, for the progress bar (default: ``len(tasks)`` where it has one,
        else a count without a total).
    max_pending : int, optional
        Tasks submitted but not yet yielded (default: four per worker of the executor where it
        says how many it has, else 64).
    ordered : bool, optional
        Yield in task order (default), or as the tasks end (``False``: a slow task does not
        hold back the others, and a finished one is never kept waiting).
    timeout : float, optional
        Seconds a task is expected to take at most (``fn`` enforces it itself). With an
        executor, when no task at all has ended for ``timeout + STALL_GRACE`` seconds, the
        tasks in flight are given up as :class:`TaskError` (a
        :class:`fohw.exceptions.TaskTimeoutError`) and cancelled: the stream never waits
        forever for workers that died without a word. Default None: no limit.

    Yields
    ------
    (int, object)
        The task's number (from 0) and its return value, or a :class:`TaskError` where the
        executor could not run or collect it. Tasks lost with a broken process pool (a worker
        that died) are rerun, each alone in a fresh one-worker pool, so only the task that
        kills its worker is lost; later tasks then run in a pool of fohw's own of the same size
        (the broken one cannot run anything). Closing the generator early cancels the tasks
        not yet started.
    """
    executor = as_executor(executor)
    if total is None and hasattr(tasks, "__len__"):
        total = len(tasks)
    if max_pending is None:
        workers = _workers(executor) if executor is not None else None
        max_pending = 64 if workers is None else 4 * workers
    if isinstance(max_pending, bool) or not isinstance(max_pending, numbers.Integral) \
            or max_pending < 1:
        raise ParameterError(f"`max_pending` must be a positive integer; got {max_pending!r}.")
    return _stream_tasks(fn, tasks, executor, progress, label, total, int(max_pending), ordered,
                         timeout)


def _stream_tasks(fn, tasks, executor, progress, label, total, max_pending, ordered,
                  timeout=None):
    """The generator of :func:`stream_tasks` (its arguments checked)."""
    bar = progress_bar(total, label, progress, counting=True)
    try:
        if executor is None:
            for i, task in enumerate(tasks):
                value = fn(*task)
                bar.update(1)
                yield i, value
            return
        yield from _stream(fn, enumerate(tasks), executor, max_pending, ordered, bar,
                           None if timeout is None else timeout + STALL_GRACE)
    finally:
        bar.close()


def _run_alone(fn, task):
    """``fn(*task)`` alone in a fresh one-worker process pool (a task whose pool broke)."""
    pool = process_pool(1)
    try:
        return pool.submit(fn, *task).result()
    except Exception as exc:                   # noqa: BLE001 - reported as the task's error
        return TaskError(exc, isolated=True)
    finally:
        pool.shutdown(wait=True)


def _stalled(window):
    """The TaskError of a task given up after no task ended for ``window`` seconds."""
    return TaskError(TaskTimeoutError(
        f"no task ended within {window:g} s (the timeout plus {STALL_GRACE:g} s): the executor's "
        "workers died or hang without a word, so the tasks in flight were given up"))


def _stream(fn, numbered, executor, max_pending, ordered, bar, window=None):
    pending = {}                    # future -> (i, task)
    ready = {}                      # i -> value, finished and not yet yielded (ordered)
    following = 0                   # the next i to yield (ordered)
    exhausted = False
    own = None                      # fohw's pool in place of a broken process pool
    try:
        while True:
            finished = []
            while not exhausted and len(pending) + len(ready) < max_pending:
                try:
                    i, task = next(numbered)
                except StopIteration:
                    exhausted = True
                    break
                try:
                    pending[executor.submit(fn, *task)] = (i, task)
                except BrokenProcessPool:      # broken by an earlier task: rerun it alone
                    finished.append((i, _run_alone(fn, task)))
                    workers = max(1, _workers(executor) or 1)
                    if own is not None:
                        own.shutdown(wait=False, cancel_futures=True)
                    executor = own = process_pool(workers)
                except Exception as exc:       # e.g. an argument that cannot be pickled
                    finished.append((i, TaskError(exc)))
            if not pending and not finished:
                if exhausted:
                    return
                continue
            if pending and not finished:
                done, _ = wait(pending, timeout=window, return_when=FIRST_COMPLETED)
                if not done:                   # nothing ended in the window: give up on them
                    for future, (i, _) in list(pending.items()):
                        future.cancel()
                        finished.append((i, _stalled(window)))
                    pending.clear()
                for future in done:
                    i, task = pending.pop(future)
                    try:
                        value = future.result()
                    except BrokenProcessPool:  # lost with the pool, maybe not its fault
                        value = _run_alone(fn, task)
                    except Exception as exc:   # the executor's failure, not fn's
                        value = TaskError(exc)
                    finished.append((i, value))
            for i, value in sorted(finished, key=lambda item: item[0]):
                bar.update(1)
                if not ordered:
                    yield i, value
                else:
                    ready[i] = value
            while following in ready:
                yield following, ready.pop(following)
                following += 1
    finally:
        for future in pending:
            future.cancel()
        if own is not None:
            own.shutdown(wait=False, cancel_futures=True)


def run_tasks(fn, tasks, *, executor=None, progress=None, label="tasks"):
    """``[fn(*task) for task in tasks]``, serially or on ``executor``, in task order.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled for process and dask executors).
    tasks : sequence of tuple
        Positional arguments of each call.
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where to run the calls; default (None) serially in this process.
    progress : bool, optional
        A progress bar on stderr (tqdm if installed, a plain counter otherwise): True from the
        start, False never; default (None): once the tasks have run for :data:`AUTO_DELAY`
        seconds (:func:`progress_bar`).
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
    executor = as_executor(executor)
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
