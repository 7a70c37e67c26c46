"""Monte Carlo studies: many seeds × methods × settings, serially or in parallel — beyond the paper.

``monte_carlo`` draws one record per (setting, seed), runs every method on it and returns a
tidy table (one row per setting, seed and method). With ``n_jobs != 1`` the records run in
parallel through joblib (the optional extra ``fohw[parallel]``); without joblib, or with
``n_jobs=1``, they run serially and give the same numbers, since every record is drawn from its
own seed.

Any ``concurrent.futures.Executor`` runs it too (``executor=``), which is how it goes onto a
cluster: point a dask client at a running scheduler and pass its executor (``pip install
'fohw[distributed]'``)::

    from dask.distributed import Client
    client = Client("tcp://scheduler-address:8786")
    rows = fohw.monte_carlo(methods, seeds=range(1000), executor=client.get_executor())
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .._parallel import TaskError, check_jobs, progress_bar, run_tasks
from .._threads import thin_solves
from ..datasets import paper_example
from ..estimators.fit import fit
from ..exceptions import (
    ConvergenceWarning,
    FohwError,
    ParameterError,
    RankDeficiencyWarning,
    SimulationDivergedError,
)
from ..model.base import Model
from .batch import identify_quietly

__all__ = ["monte_carlo", "summarise"]


def _paper_data(seed, n_samples=10_000, **kwargs):
    return paper_example(n_samples, random_state=seed, **kwargs)


@thin_solves
def _run_task(make_data, methods, seed, setting):
    rows = []
    try:
        data = make_data(seed, **setting)
    except SimulationDivergedError as exc:
        return [dict(seed=seed, **setting, method=name, error=str(exc)) for name in methods]
    model = data.model
    if not all(isinstance(options, Model) for options in methods.values()):
        struct = dict(na=model.na, nb=model.nb, f_basis=model.f_basis, g_basis=model.g_basis)
        if model.nk != 1:
            struct["nk"] = model.nk
        theta = model.theta
    for name, options in methods.items():
        t0 = time.perf_counter()
        if isinstance(options, Model):
            rows.append(dict(seed=seed, **setting, method=name,
                             **_fit_row(options, data, t0)))
            continue
        res = identify_quietly(data.u, data.y, **{**struct, **options})
        rows.append(dict(seed=seed, **setting, method=name, alpha=res.alpha,
                         alpha_error=res.alpha - model.alpha,
                         delta=float(np.linalg.norm(res.theta - theta) / np.linalg.norm(theta)),
                         J=res.J, status=res.status.name, converged=res.converged,
                         nit=res.nit, nfev=res.nfev,
                         seconds=time.perf_counter() - t0, error=""))
    return rows


def _fit_row(start, data, t0):
    """The row of :func:`fohw.fit` from ``start`` on ``data``: estimates, errors, status."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            warnings.simplefilter("ignore", RankDeficiencyWarning)
            res = fit(start, data.u, data.y)
    except FohwError as exc:
        return dict(status="", converged=False, error=f"{type(exc).__name__}: {exc}",
                    seconds=time.perf_counter() - t0)
    row = {name: res.parameters[name].value for name in res.free_names}
    truth = getattr(data, "model", None)
    known = [n for n in res.free_names if isinstance(truth, Model) and n in truth.parameters]
    for n in known:
        row[f"{n}_error"] = res.parameters[n].value - truth.parameters[n].value
    if known and len(known) == res.n_free:
        x = np.array([truth.parameters[n].value for n in known])
        row["delta"] = float(np.linalg.norm([row[f"{n}_error"] for n in known])
                             / np.linalg.norm(x))
    return dict(row, sse=res.sse, status=res.status.name, converged=res.converged,
                nfev=res.nfev, seconds=time.perf_counter() - t0, error="")


def monte_carlo(methods, *, seeds=range(20), settings=({},), make_data=None, n_jobs=1,
                progress=None, executor=None):
    """Run identification methods over many simulated records.

    Parameters
    ----------
    methods : dict of str to dict or Model
        Name of each configuration and the keyword arguments of :func:`fohw.identify` it uses
        (the model structure is taken from the simulated record unless given), or a start
        :class:`fohw.Model` of any kind, fitted by :func:`fohw.fit` (with a ``make_data``
        whose records carry ``u``, ``y`` and, for the errors, the true ``model``).
    seeds : iterable of int, optional
        One record per seed and setting (default ``range(20)``).
    settings : sequence of dict, optional
        Keyword arguments of ``make_data`` to vary (e.g. ``[{"n_samples": 1000},
        {"n_samples": 10000}]``); default one setting with no arguments.
    make_data : callable, optional
        ``make_data(seed, **setting)`` returns a :class:`fohw.datasets.SimulatedData`. Default:
        the paper's example, ``paper_example(n_samples=10000, random_state=seed, ...)``.
    n_jobs : int, optional
        Parallel workers through joblib (``-1``: all cores), at most the processors this
        process may use (more are refused). 1 (default) runs serially. If joblib is not
        installed the run is serial, with a ``RuntimeWarning``.
    progress : bool, optional
        A progress bar on stderr (tqdm, a notebook widget, if installed; plain lines
        otherwise): True from the start, False never; default (None) once the work has run
        for 2 s.
    executor : concurrent.futures.Executor, optional
        Run the records on it instead (a ``ProcessPoolExecutor``, or dask's
        ``Client.get_executor()`` for a cluster); then ``n_jobs`` must stay 1. ``make_data``
        must be picklable (a module-level function). The rows do not depend on the backend.

    Returns
    -------
    list of dict
        One row per (setting, seed, method): ``seed``, the setting's keys, ``method``,
        ``alpha``, ``alpha_error``, ``delta`` (``||theta_hat - theta|| / ||theta||``), ``J``,
        ``status`` (the name of :class:`fohw.Status`), ``converged``, ``nit``, ``nfev``,
        ``seconds``, ``error`` (the message when the record diverged, else ``""``). For a
        Model method: each free parameter's estimate by name, ``<name>_error`` against the
        record's true model (where it has that parameter), ``delta`` (``||x_hat - x|| /
        ||x||`` over the free parameters, when all have a true value), ``sse``, ``status``,
        ``converged``, ``nfev``, ``seconds``, ``error`` (a fit that raised).

    Examples
    --------
    >>> import fohw
    >>> rows = fohw.monte_carlo({"varpro": {"method": "varpro"}}, seeds=range(2),
    ...                         settings=[{"n_samples": 500}])
    >>> len(rows), sorted(rows[0])[:4]
    (2, ['J', 'alpha', 'alpha_error', 'converged'])
    """
    make_data = _paper_data if make_data is None else make_data
    tasks = [(seed, dict(setting)) for setting in settings for seed in seeds]
    calls = [(make_data, methods, seed, setting) for seed, setting in tasks]
    if executor is not None and n_jobs != 1:
        raise ParameterError("give `executor` or `n_jobs`, not both; got n_jobs="
                             f"{n_jobs!r} with an executor.")
    if n_jobs != 1:
        check_jobs(n_jobs, "n_jobs", negative=True)
    joblib = None
    if executor is None and n_jobs != 1:
        try:
            import joblib
        except ImportError:
            warnings.warn("joblib is not installed (pip install 'fohw[parallel]'); running "
                          "serially.", RuntimeWarning, stacklevel=2)
    if joblib is not None:
        parts = _joblib_tasks(joblib, calls, n_jobs, progress)
    else:
        parts = run_tasks(_run_task, calls, executor=executor, progress=progress,
                          label="monte_carlo")
    rows = []
    for (seed, setting), part in zip(tasks, parts):
        if isinstance(part, TaskError):
            raise FohwError(f"monte_carlo: the record of seed {seed} (setting {setting}) "
                            f"could not be run on the executor: {part.message}") \
                from part.exception
        rows.extend(part)
    return rows


def _joblib_tasks(joblib, calls, n_jobs, progress):
    """``[_run_task(*call) for call in calls]`` on joblib's workers, in order, with progress."""
    bar = progress_bar(len(calls), "monte_carlo", progress)
    out = []
    try:
        for part in joblib.Parallel(n_jobs=n_jobs, return_as="generator")(
                joblib.delayed(_run_task)(*call) for call in calls):
            out.append(part)
            bar.update(1)
    finally:
        bar.close()
    return out


def summarise(rows, *, by=("method",), value="delta"):
    """Root-mean-square, median and count of a column, grouped.

    Parameters
    ----------
    rows : list of dict
        Output of :func:`monte_carlo`.
    by : tuple of str
        Columns to group by.
    value : str
        Column to summarise (rows with an ``error`` are skipped).

    Returns
    -------
    dict
        ``{group key tuple: {"rms": ..., "median": ..., "n": ...}}``.
    """
    groups = {}
    for r in rows:
        if r.get("error"):
            continue
        groups.setdefault(tuple(r[b] for b in by), []).append(r[value])
    return {k: dict(rms=float(np.sqrt(np.mean(np.square(v)))), median=float(np.median(v)), n=len(v))
            for k, v in groups.items()}
