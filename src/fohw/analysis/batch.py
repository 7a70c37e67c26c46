"""Many records, one call: :func:`stream_fits` and :func:`identify_many`, serially or on any executor.

Each record is fitted on its own (one model per record; a fleet of plants, a thousand cells),
by :func:`fohw.fit` from a start model of any kind, or by :func:`fohw.identify` for the
paper's lagged kind. :func:`stream_fits` is the form that scales: records are read one at a
time (an iterable, or file paths read by the worker that fits them), at most a few per worker
are in flight, and each outcome is yielded as it comes (or written to a folder), so the memory
of the calling process does not grow with the number of records. :func:`identify_many` is the
list of the same outcomes. A ``ProcessPoolExecutor`` of your own takes :func:`end_with_parent`
(defined in the private ``fohw._parallel``, public here) as its ``initializer``, so its workers
end when this process dies.
"""

from __future__ import annotations

import math
import numbers
import os
import signal
import threading
import time
import warnings
from dataclasses import dataclass

from .._parallel import TaskError, as_executor, end_with_parent, stream_tasks
from ..exceptions import ConvergenceWarning, ParameterError, TaskTimeoutError
from ..model.base import Model
from ..record import Record

__all__ = ["stream_fits", "identify_many", "identify_quietly", "BatchItem", "end_with_parent"]


def identify_quietly(u, y, **kwargs):
    """:func:`fohw.identify` with :class:`fohw.ConvergenceWarning` silenced.

    For studies that run many fits and report ``status``/``converged`` in their tables: the
    paper's recursive schedule and MI-RLS make one pass and never test convergence, so they
    always warn. Every other warning still shows.
    """
    from ..estimators.identify import identify

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return identify(u, y, **kwargs)


@dataclass(frozen=True, repr=False)
class BatchItem:
    """One record's outcome in :func:`stream_fits`.

    Attributes
    ----------
    index : int
        The record's place in ``records`` (from 0).
    name : str
        What the record is: its file path (given, or the Record's ``path``), else its
        :attr:`fohw.Record.name`, else ``records[index]``.
    result : FitResult, IdentificationResult or None
        The fit; None when it failed, or when it was written to ``out_dir``.
    error : Exception or None
        What its fit (or reading its file) raised; None when it succeeded.
    message : str
        ``""`` when it succeeded, else the record and the error in words.
    path : str or None
        Where ``out_dir`` has its result (or its failure).
    seconds : float
        The wall time of reading and fitting it, in the worker (nan where the executor lost it).
    """

    index: int
    name: str
    result: object = None
    error: BaseException | None = None
    message: str = ""
    path: str | None = None
    seconds: float = float("nan")

    @property
    def ok(self) -> bool:
        """True when the record was fitted (whatever its status), False when it failed."""
        return self.error is None

    def __repr__(self):
        what = (type(self.result).__name__ if self.result is not None else
                f"saved to {self.path!r}") if self.ok else f"failed: {self.message}"
        return f"BatchItem({self.index}, {self.name!r}, {what})"


def _is_path(record):
    return isinstance(record, (str, os.PathLike))


def _record_name(index, record):
    if _is_path(record):
        return os.fspath(record)
    if isinstance(record, Record) and (record.path or record.name):
        return record.path or record.name
    return f"records[{index}]"


def _is_records(record):
    """Several experiments of one system: a list of Records, fitted as one data set."""
    return isinstance(record, (list, tuple)) and bool(record) and \
        all(isinstance(r, Record) for r in record)


def _check_record(index, record):
    """A ParameterError for a record that is neither a Record, a pair (u, y) nor a path."""
    if isinstance(record, Record) or _is_path(record) or _is_records(record):
        return None
    try:
        _, _ = record
    except (TypeError, ValueError):
        return ParameterError(f"`records[{index}]` must be a Record, a pair (u, y) or a file "
                              f"path; got {type(record).__name__}.")
    return None


def _read_and_fit(record, model, options, read):
    """Read (a path) and fit one record: its result, or raise."""
    if _is_path(record):
        from ..io.text import read_record

        record = read_record(record, **read)
    if model is None:
        return _identify(record, options)
    from ..estimators.fit import fit

    if isinstance(record, Record) or _is_records(record):
        return fit(model, record, **options)      # its sampling and names go along
    u, y = record
    return fit(model, u, y, **options)


def _fit_record(index, record, model, options, read, out_dir, timeout=None):
    """Read (a path) and fit one record; never raises: the error is part of the outcome."""
    start = time.perf_counter()
    result = error = path = None
    try:
        result = _within(timeout, lambda: _read_and_fit(record, model, options, read))
    except Exception as exc:                 # one record never loses the others
        error = exc
    if out_dir is not None:
        result, error, path = _write_outcome(out_dir, index, result, error)
    return result, error, path, time.perf_counter() - start


def _write_outcome(out_dir, index, result, error, text=None):
    """``(result, error, path)`` once written to ``out_dir``: NNNNNN.json or NNNNNN.failed.txt."""
    stem = os.path.join(out_dir, f"{index:06d}")
    try:
        if error is None:
            from ..io.jsonio import save_result

            save_result(result, path := stem + ".json")
            result = None
        else:
            from ..io.files import write_text

            text = f"{type(error).__name__}: {error}" if text is None else text
            write_text(text + "\n", path := stem + ".failed.txt")
    except Exception as exc:             # noqa: BLE001 - e.g. a full disk: reported
        result, error, path = None, exc, None
    return result, error, path


class _Deadline(BaseException):
    """Raised by the alarm of :func:`_within`.

    A BaseException, so that a kind's ``except Exception`` does not swallow it.
    """


def _within(timeout, work):
    """``work()``, or a :class:`fohw.exceptions.TaskTimeoutError` once it has run ``timeout`` s.

    In a process's main thread (serial runs, a process pool's workers) an alarm signal stops
    the work where it is; elsewhere (a thread pool, dask's worker threads), or while another
    alarm is set, the work runs in a daemon thread that is left behind when it overruns (a
    thread cannot be stopped: it runs on until it returns, holding no worker of the executor).
    """
    if timeout is None:
        return work()
    if hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread() \
            and signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0):
        return _with_alarm(timeout, work)
    box = {}

    def target():
        try:
            box["value"] = work()
        except BaseException as exc:         # noqa: BLE001 - handed to the caller below
            box["error"] = exc

    thread = threading.Thread(target=target, name="fohw-fit", daemon=True)
    thread.start()
    thread.join(timeout)
    if thread.is_alive():
        raise TaskTimeoutError(f"the fit ran longer than `timeout` = {timeout:g} s and was "
                               "abandoned (it runs on in a background thread of its worker, "
                               "which a thread executor cannot stop)")
    if "error" in box:
        raise box["error"]
    return box["value"]


def _with_alarm(timeout, work):
    """:func:`_within` by ``SIGALRM`` (main thread only)."""
    state = {"done": False}

    def ring(signum, frame):
        if not state["done"]:
            raise _Deadline

    previous = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        value = work()
        state["done"] = True
        return value
    except _Deadline:
        raise TaskTimeoutError(f"the fit ran longer than `timeout` = {timeout:g} s and was "
                               "stopped") from None
    finally:
        state["done"] = True
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def _check_timeout(timeout):
    """``timeout`` as seconds (a positive finite number) or None."""
    if timeout is None:
        return None
    if isinstance(timeout, bool) or not isinstance(timeout, numbers.Real) or \
            not (math.isfinite(timeout) and timeout > 0):
        raise ParameterError(f"`timeout` must be a positive number of seconds (or None: no "
                             f"limit); got {timeout!r}.")
    return float(timeout)


def _identify(record, options):
    """:func:`fohw.identify` of one record (the lagged kind; a Record carries its sampling)."""
    from ..estimators.identify import identify

    if _is_records(record):
        raise ParameterError("fohw.identify fits one record; fit several experiments as one "
                             "data set with a start model: stream_fits(records, model).")
    if isinstance(record, Record):
        return identify(record, **options)
    u, y = record
    return identify(u, y, **options)


def _message(index, name, error):
    where = f"records[{index}]" + (f" ({name})" if name != f"records[{index}]" else "")
    text = str(error).strip()
    return f"{where}: {type(error).__name__}" + (f": {text}" if text else "")


def _check_call(model, read, out_dir):
    if model is not None and not isinstance(model, Model):
        raise ParameterError(f"`model` must be a fohw.Model (a start model of any kind); got "
                             f"{type(model).__name__}.")
    if read is not None and not isinstance(read, dict):
        raise ParameterError("`read` must be a dict of fohw.read_record keywords (e.g. "
                             f"{{'u': 'current', 'y': 'voltage'}}); got {type(read).__name__}.")
    if out_dir is not None:
        out_dir = os.fspath(out_dir)
        if not os.path.isdir(out_dir):
            raise ParameterError(f"`out_dir` must be an existing folder; got {out_dir!r}.")
    return out_dir


def stream_fits(records, model=None, *, executor=None, progress=None, read=None, out_dir=None,
                ordered=True, max_pending=None, chunksize=1, total=None, timeout=None, **options):
    """Fit every record on its own, on any executor, yielding each outcome as it comes.

    A generator: the records are read one at a time, at most ``max_pending`` are in flight,
    and nothing is kept once yielded, so the memory of this process stays flat however many
    records there are (measured in ``docs/performance.md``). One record's failure (its file,
    its data, its fit) is its own outcome; the others go on.

    Parameters
    ----------
    records : iterable of Record, (u, y), path or list of Record
        The records: :class:`fohw.Record` objects (their sampling, names and units go with the
        fit), pairs ``(u, y)`` of arrays, paths of text files that the worker reads with
        :func:`fohw.read_record` (nothing is read here), or lists of Records (several
        experiments of one unit, fitted jointly as :func:`fohw.fit` does). Any iterable; a
        generator is read only as room frees up.
    model : Model, optional
        A start model of any kind: every record is fitted by :func:`fohw.fit` from it.
        Default: :func:`fohw.identify` (the paper's lagged kind; a Record is passed as it is,
        its sampling time and names with it).
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where to run the fits: a ``ProcessPoolExecutor``, a ``ThreadPoolExecutor``, a dask
        client (or its ``get_executor()``); default serially in this process. The results do
        not depend on it.
    progress : bool, optional
        A progress bar on stderr: True from the start, False never, None (default) once the
        work has run for 2 s. Its total is ``len(records)`` (or ``total``) where known.
    read : dict, optional
        Keywords of :func:`fohw.read_record` for records given as paths (``u``, ``y``, ``dt``,
        units, ``decimal``).
    out_dir : str or os.PathLike, optional
        An existing folder (shared by the workers): each result is written there by the
        worker that made it, as ``NNNNNN.json`` (:func:`fohw.load_result` reads it), each
        failure as ``NNNNNN.failed.txt`` (``NNNNNN`` the record's index); the yielded items
        then carry the path, not the result.
    ordered : bool, optional
        Yield in the order of ``records`` (default), or as the fits end (False: a slow record
        does not hold back the others).
    max_pending : int, optional
        Tasks in flight (submitted and not yet yielded); default four per worker of the
        executor where it says how many it has, else 64.
    chunksize : int, optional
        Records per task (default 1). Each task costs the executor and this process some time
        whatever it does (dask's scheduler: about a millisecond); for fits of tens of
        milliseconds on many workers, a few dozen records per task keep that cost from
        bounding the throughput (``docs/performance.md``). A task lost by the executor loses
        the records of its chunk.
    total : int, optional
        The number of records, for the progress bar, when ``records`` has no ``len``.
    timeout : float, optional
        Seconds one record's reading and fit may take (default None: no limit). A record that
        takes longer is a failed outcome (a :class:`fohw.exceptions.TaskTimeoutError`; with
        ``out_dir``, its ``NNNNNN.failed.txt``) and the others go on. Serially and in a process
        pool's workers the fit is stopped where it is; in a thread pool or on dask's worker
        threads it is abandoned (a thread cannot be stopped: it runs on in the background
        until it returns, but no longer holds a worker). With an executor, the stream also
        stops waiting when no task at all has ended for ``timeout`` times ``chunksize`` plus a
        grace of 30 s (workers that died without a word): the
        tasks in flight are then failed outcomes saying so.
    **options
        Keywords of :func:`fohw.fit` with ``model`` (``order_grid``, ``n_starts``, ...), else of
        :func:`fohw.identify` (``na``, ``nb``, ``f_basis``, ``g_basis``, ...).

    Yields
    ------
    BatchItem
        ``index``, ``name``, and ``result`` (a :class:`fohw.FitResult`, or a
        :class:`fohw.IdentificationResult` without ``model``) or ``error`` and ``message``
        naming the record and what went wrong.

    Raises
    ------
    ParameterError
        ``model`` is not a :class:`fohw.Model`, ``read`` not a dict, ``out_dir`` not a folder,
        ``executor`` not an executor, ``max_pending`` or ``chunksize`` not a positive
        integer, or ``timeout`` not a positive number (when called, before any record is read).

    See Also
    --------
    identify_many : the same outcomes as a list.

    Notes
    -----
    A record that is neither a Record, a pair nor a path is a failed outcome here (a
    ParameterError naming it); :func:`identify_many` raises instead. Records given as arrays
    travel to the workers with their task; give paths to let each worker read its own (on a
    cluster, a path every worker can open). A worker process that dies is handled as in
    :func:`fohw.select_structure`: only the record that kills its worker is lost, and it is a
    failed outcome like any other (with ``out_dir``, its ``NNNNNN.failed.txt`` is written by
    this process, saying what happened).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> plant = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
    >>> def records():                       # read one at a time, as room frees up
    ...     for seed in range(3):
    ...         u = np.random.default_rng(seed).standard_normal(300)
    ...         yield (u, plant.simulate(u) if seed != 1 else np.full(300, np.nan))
    >>> start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05)
    >>> for item in fohw.stream_fits(records(), start, order_grid=1):
    ...     print(item.index, item.message[:44] or type(item.result).__name__)
    0 FitResult
    1 records[1]: ParameterError: `y` must contain
    2 FitResult
    """
    out_dir = _check_call(model, read, out_dir)
    timeout = _check_timeout(timeout)
    executor = as_executor(executor)
    if total is None and hasattr(records, "__len__"):
        total = len(records)
    if isinstance(chunksize, bool) or not isinstance(chunksize, numbers.Integral) or \
            chunksize < 1:
        raise ParameterError(f"`chunksize` must be a positive integer; got {chunksize!r}.")
    read = dict(read or {})
    chunks = {}                      # task number -> [(index, name)] of the records in flight

    def task(number, chunk):
        chunks[number] = [(j, name) for j, name, _, _ in chunk]
        return [(j, r, b) for j, _, r, b in chunk], model, options, read, out_dir, timeout

    def tasks():
        chunk, number = [], 0
        for i, record in enumerate(records):
            bad = _check_record(i, record)
            chunk.append((i, _record_name(i, record), None if bad else record, bad))
            if len(chunk) == chunksize:
                yield task(number, chunk)
                chunk, number = [], number + 1
        if chunk:
            yield task(number, chunk)

    if total is not None:
        total = -(-total // chunksize)
    stream = stream_tasks(_task, tasks(), executor=executor, progress=progress, label="fits",
                          total=total, max_pending=max_pending, ordered=ordered,
                          timeout=None if timeout is None else timeout * chunksize)
    return _items(stream, chunks, out_dir)


def _items(stream, chunks, out_dir=None):
    """The generator of :func:`stream_fits`: each record's outcome as a :class:`BatchItem`."""
    try:
        for task, value in stream:
            for k, (i, name) in enumerate(chunks.pop(task)):
                if isinstance(value, TaskError):     # the executor lost it (pickling, a worker)
                    error, path = value.exception, None
                    message = _message(i, name, error) + f" ({value.message})"
                    if out_dir is not None:          # no worker wrote it: written here
                        _, error, path = _write_outcome(
                            out_dir, i, None, error,
                            f"{type(error).__name__}: {str(error).strip()} ({value.message})")
                    yield BatchItem(i, name, error=error, message=message, path=path)
                    continue
                result, error, path, seconds = value[k]
                yield BatchItem(i, name, result=result, error=error,
                                message="" if error is None else _message(i, name, error),
                                path=path, seconds=seconds)
    finally:
        stream.close()


def _task(chunk, model, options, read, out_dir, timeout=None):
    """One task: the records of a chunk, each read and fitted on its own (within ``timeout`` s)."""
    return [(None, bad, None, 0.0) if bad is not None else
            _fit_record(i, record, model, options, read, out_dir, timeout)
            for i, record, bad in chunk]


def identify_many(records, *, executor=None, progress=None, model=None, read=None, **kwargs):
    """Run :func:`fohw.identify` (or :func:`fohw.fit` of a model) with the same keywords on many records.

    Parameters
    ----------
    records : iterable of Record, (u, y) or path
        The records (paths are read with :func:`fohw.read_record` by the worker that fits
        them).
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where to run them (a ``ProcessPoolExecutor``, a dask client or its
        ``get_executor()``); default serially. The results do not depend on the backend.
    progress : bool, optional
        A progress bar on stderr (tqdm, a notebook widget, if installed; plain lines
        otherwise): True from the start, False never; default (None) once the work has run
        for 2 s.
    model : Model, optional
        A start model of any kind: every record is fitted by :func:`fohw.fit` from it (then
        ``**kwargs`` are keywords of :func:`fohw.fit`: ``order_grid``, ``n_starts``, …).
    read : dict, optional
        Keywords of :func:`fohw.read_record` for records given as paths.
    **kwargs
        Keywords of :func:`fohw.identify` (``na``, ``nb``, ``f_basis``, ``g_basis``, …), or of
        :func:`fohw.fit` with ``model``.

    Returns
    -------
    list
        One entry per record, in order: its :class:`fohw.IdentificationResult` (a
        :class:`fohw.FitResult` with ``model``), or the exception its fit raised (so one bad
        record never loses the others; test with ``isinstance(entry, Exception)``). For many
        records, :func:`fohw.stream_fits` gives the same outcomes one at a time, without
        holding them all.

    Raises
    ------
    ParameterError
        A record of a list or tuple that is neither a Record, a pair (u, y) nor a path
        (before anything runs).

    Examples
    --------
    >>> import fohw
    >>> recs = [fohw.datasets.paper_example(400, random_state=s) for s in range(3)]
    >>> out = fohw.identify_many([(r.u, r.y) for r in recs], na=2, nb=2, f_basis=2, g_basis=3)
    >>> [type(r).__name__ for r in out]
    ['IdentificationResult', 'IdentificationResult', 'IdentificationResult']
    """
    _check_call(model, read, None)
    total = len(records) if hasattr(records, "__len__") else None
    if isinstance(records, (list, tuple)):
        for i, record in enumerate(records):
            if (bad := _check_record(i, record)) is not None:
                raise bad

    def checked():                           # a generator's bad record raises when reached
        for i, record in enumerate(records):
            if (bad := _check_record(i, record)) is not None:
                raise bad
            yield record

    return [item.result if item.ok else item.error
            for item in stream_fits(checked(), model, executor=executor, progress=progress,
                                    read=read, total=total, **kwargs)]
