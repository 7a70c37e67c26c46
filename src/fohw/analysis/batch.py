"""Many records, one call: :func:`identify_many`, serially or on any executor."""

from __future__ import annotations

import warnings

from .._parallel import TaskError, run_tasks
from ..exceptions import ConvergenceWarning, ParameterError
from ..model.base import Model
from ..record import Record

__all__ = ["identify_many", "identify_quietly"]


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


def _identify_one(u, y, kwargs):
    from ..estimators.identify import identify

    try:
        return identify(u, y, **kwargs)
    except Exception as exc:                 # one record never loses the others
        return exc


def _fit_one(model, u, y, kwargs):
    from ..estimators.fit import fit

    try:
        return fit(model, u, y, **kwargs)
    except Exception as exc:                 # one record never loses the others
        return exc


def identify_many(records, *, executor=None, progress=None, model=None, **kwargs):
    """Run :func:`fohw.identify` (or :func:`fohw.fit` of a model) with the same keywords on many records.

    Parameters
    ----------
    records : sequence of Record or (u, y)
        The records.
    executor : concurrent.futures.Executor, optional
        Where to run them (a ``ProcessPoolExecutor``, dask's ``Client.get_executor()``);
        default serially. The results do not depend on the backend.
    progress : bool, optional
        A progress bar on stderr (tqdm, a notebook widget, if installed; plain lines
        otherwise): True from the start, False never; default (None) once the work has run
        for 2 s.
    model : Model, optional
        A start model of any kind: every record is fitted by :func:`fohw.fit` from it (then
        ``**kwargs`` are keywords of :func:`fohw.fit`: ``order_grid``, ``n_starts``, …).
    **kwargs
        Keywords of :func:`fohw.identify` (``na``, ``nb``, ``f_basis``, ``g_basis``, …), or of
        :func:`fohw.fit` with ``model``.

    Returns
    -------
    list
        One entry per record, in order: its :class:`fohw.IdentificationResult` (a
        :class:`fohw.FitResult` with ``model``), or the exception its fit raised (so one bad
        record never loses the others; test with ``isinstance(entry, Exception)``).

    Examples
    --------
    >>> import fohw
    >>> recs = [fohw.datasets.paper_example(400, random_state=s) for s in range(3)]
    >>> out = fohw.identify_many([(r.u, r.y) for r in recs], na=2, nb=2, f_basis=2, g_basis=3)
    >>> [type(r).__name__ for r in out]
    ['IdentificationResult', 'IdentificationResult', 'IdentificationResult']
    """
    if model is not None and not isinstance(model, Model):
        raise ParameterError(f"`model` must be a fohw.Model (a start model of any kind); got "
                             f"{type(model).__name__}.")
    tasks = []
    for i, rec in enumerate(records):
        if isinstance(rec, Record):
            u, y = rec.u, rec.y
        else:
            try:
                u, y = rec
            except (TypeError, ValueError):
                raise ParameterError(f"`records[{i}]` must be a Record or a pair (u, y); got "
                                     f"{type(rec).__name__}.") from None
        tasks.append((u, y, kwargs) if model is None else (model, u, y, kwargs))
    out = run_tasks(_identify_one if model is None else _fit_one, tasks, executor=executor,
                    progress=progress, label="identify_many")
    return [entry.exception if isinstance(entry, TaskError) else entry for entry in out]
