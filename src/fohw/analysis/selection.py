"""Structure selection the way system identification does it: fit, then score by free-run simulation.

:func:`select_structure` fits every candidate structure on the estimation part of a record,
simulates it in free run over the estimation part *and on into* a held-back part it never saw,
and ranks the candidates by the fit on the held-back part. A candidate that fails (its fit
raises, its simulation diverges or leaves the finite numbers) is recorded with the reason and
never loses the others. The winner is refitted on all the estimation data.

The fits are independent, so they run on any ``concurrent.futures.Executor`` (a process pool,
or dask's ``Client.get_executor()`` for a cluster); the table is the same whatever the backend.
"""

from __future__ import annotations

import csv
import io
import itertools
import numbers
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .._parallel import TaskError, run_tasks
from .._threads import thin_solves
from .._validation import check_array, check_same_length
from ..exceptions import ExtrapolationWarning, ParameterError, SimulationDivergedError
from ..record import Record
from .metrics import aic, bic, fit_percent, rmse

__all__ = ["select_structure", "Selection", "expand_candidates", "SCORES"]

#: Ranking criteria: name -> (column, True if larger is better).
SCORES = {"fit": ("fit", True), "rmse": ("rmse", False), "aic": ("aic", False),
          "bic": ("bic", False)}

#: The columns of :attr:`Selection.rows` besides the candidate's own keywords.
COLUMNS = ("candidate", "status", "fit", "rmse", "fit_estimation", "aic", "bic", "n_params",
           "estimated_orders", "in_range", "fit_status", "seconds", "reason")


def expand_candidates(candidates):
    """A list of keyword dicts from a list of dicts or a grid (a dict of lists).

    ``{"na": [1, 2], "orders": [0, "mixed"]}`` gives the four combinations, in
    :func:`itertools.product` order (the first key varies slowest).
    """
    if isinstance(candidates, Mapping):
        keys = list(candidates)
        values = []
        for key in keys:
            v = candidates[key]
            if isinstance(v, (str, bytes)) or not isinstance(v, Sequence):
                raise ParameterError(f"a grid of candidates maps each keyword to a list of "
                                     f"values; `candidates[{key!r}]` is {v!r}. Write [{v!r}] "
                                     "for one value.")
            if len(v) == 0:
                raise ParameterError(f"`candidates[{key!r}]` is empty: the grid has no "
                                     "candidates.")
            values.append(list(v))
        return [dict(zip(keys, combo)) for combo in itertools.product(*values)]
    if isinstance(candidates, (str, bytes)) or not isinstance(candidates, Sequence):
        raise ParameterError("`candidates` must be a list of dicts of identify keywords or a "
                             f"dict of lists (a grid); got {type(candidates).__name__}.")
    out = []
    for i, c in enumerate(candidates):
        if not isinstance(c, Mapping):
            raise ParameterError(f"`candidates[{i}]` must be a dict of identify keywords; got "
                                 f"{type(c).__name__}.")
        out.append(dict(c))
    if not out:
        raise ParameterError("`candidates` is empty.")
    return out


def _describe(value):
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (str, numbers.Number, type(None))):
        return str(value)
    names = getattr(value, "names", None)          # a Basis
    if names is not None:
        return "(" + ", ".join(names) + ")"
    if isinstance(value, (tuple, list)):
        return "(" + ", ".join(_describe(v) for v in value) + ")"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k}: {_describe(v)}" for k, v in value.items()) + "}"
    return getattr(value, "__name__", type(value).__name__)


def _label(candidate):
    return " ".join(f"{k}={_describe(v)}" for k, v in candidate.items())


def _blank_row(**changes):
    """A row before (or without) a fit: every score missing."""
    return dict(dict(status="ok", fit=np.nan, rmse=np.nan, fit_estimation=np.nan, aic=np.nan,
                     bic=np.nan, n_params=0, estimated_orders="", in_range=True, fit_status="",
                     seconds=np.nan, reason=""), **changes)


@thin_solves
def _fit_and_score(u_est, y_est, u_sim, y_score, score_from, candidate):
    """One candidate: fit on the estimation part, free-run over ``u_sim``, score the tail.

    Module level (it is pickled for process and dask executors). Never raises: a failure is
    returned as the row's status and reason.
    """
    from ..estimators.identify import identify

    row = _blank_row()
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = identify(u_est, y_est, **candidate)
        except Exception as exc:                      # one candidate never loses the others
            row.update(status="failed", reason=f"fit: {type(exc).__name__}: {exc}",
                       seconds=time.perf_counter() - t0)
            return row, None
        row["fit_status"] = res.status.name
        row["estimated_orders"] = ", ".join(f"{k}={v:.4g}"
                                            for k, v in (res.orders or {}).items())
        n = len(y_est)
        d = res.linear.size + res.nonlinear.size
        row["n_params"] = int(d)
        criterion = (res.details.get("simulation_sse", np.nan) / n
                     if res.method == "output_error" else res.J)
        if np.isfinite(criterion) and criterion > 0:
            row["aic"] = aic(criterion, n, d)
            row["bic"] = bic(criterion, n, d)
        try:       # the simulator raises on any non-finite output, so ysim is finite
            ysim = res.simulate(u_sim)
        except SimulationDivergedError as exc:
            row.update(status="diverged" if exc.cause == "growth" else "nan", reason=str(exc))
        except Exception as exc:
            row.update(status="failed", reason=f"simulation: {type(exc).__name__}: {exc}")
    # result.simulate warns when the input leaves the estimation input's range
    row["in_range"] = not any(issubclass(w.category, ExtrapolationWarning) for w in caught)
    if row["status"] != "ok":
        row["seconds"] = time.perf_counter() - t0
        return row, res
    if score_from:                      # the held-back part continues the estimation part
        row["fit_estimation"] = fit_percent(y_est, ysim[:score_from])
    else:                               # a separate validation record
        try:
            row["fit_estimation"] = fit_percent(y_est, res.simulate(u_est))
        except Exception:               # noqa: BLE001 - only this column is lost
            pass
    row["fit"] = fit_percent(y_score, ysim[score_from:])
    row["rmse"] = rmse(y_score, ysim[score_from:])
    notes = sorted({str(w.message).split("\n")[0] for w in caught
                    if not issubclass(w.category, ExtrapolationWarning)})   # in `in_range`
    if notes:
        row["reason"] = "; ".join(notes)
    row["seconds"] = time.perf_counter() - t0
    return row, res


@dataclass
class Selection:
    """The outcome of :func:`select_structure`.

    Attributes
    ----------
    rows : list of dict
        One per candidate, in the order given: the candidate's keywords, then ``candidate``
        (a label), ``status`` (``"ok"``; ``"diverged"``: the free run grew without bound;
        ``"nan"``: a basis function returned NaN or inf during it; ``"failed"``: the fit or the
        simulation raised, the reason says what), ``fit``
        (free-run fit % on the held-back part), ``rmse`` (on it, in the data's units),
        ``fit_estimation`` (free-run fit % on the estimation part), ``aic``, ``bic`` (from the
        method's own criterion on the estimation part: the one-step ``J`` of Eq. 41, or the
        mean squared simulation error for ``"output_error"``), ``n_params``,
        ``estimated_orders`` (the estimated free orders), ``in_range`` (whether the held-back
        input stayed inside the estimation input's range widened by 5 % of its span: no
        :class:`fohw.ExtrapolationWarning` from the simulation), ``fit_status`` (the
        estimator's :class:`fohw.Status` name), ``seconds``, ``reason`` (why a candidate
        failed, or the warnings its fit raised).
    best : IdentificationResult or None
        The winner refitted on all the data given as estimation data (``None`` if every
        candidate failed).
    best_index : int or None
        Its row.
    results : list of IdentificationResult or None
        Each candidate's fit on the estimation part (``None`` where the fit failed).
    score : str
        The ranking criterion (a key of :data:`SCORES`).
    validation : str
        What the held-back part was.
    seconds : float
        Wall time of the candidate fits (the refit excluded).
    """

    rows: list
    best: object
    best_index: int | None
    results: list = field(repr=False)
    score: str = "fit"
    validation: str = ""
    seconds: float = 0.0

    @property
    def best_row(self):
        """The winner's row (``None`` if every candidate failed)."""
        return None if self.best_index is None else self.rows[self.best_index]

    def ranked(self):
        """Rows of the candidates that simulated, best first, then the failed ones."""
        col, larger = SCORES[self.score]
        ok = [r for r in self.rows if r["status"] == "ok" and np.isfinite(r[col])]
        ok.sort(key=lambda r: -r[col] if larger else r[col])
        return ok + [r for r in self.rows if r not in ok]

    def best_by(self, key):
        """The best row for each value of a candidate keyword, e.g. ``best_by("orders")``.

        Returns
        -------
        dict
            ``{value: row}`` over the candidates that simulated, in ranking order (the best
            value first).
        """
        out = {}
        for row in self.ranked():
            if row["status"] != "ok" or key not in row:
                continue
            value = row[key]
            marker = value if isinstance(value, (str, numbers.Number)) else _describe(value)
            if marker not in out:
                out[marker] = row
        return out

    def _columns(self):
        return ["candidate"] + [c for c in COLUMNS if c != "candidate"]

    def to_markdown(self, top=None, columns=None):
        """The table, ranked, as Markdown (``top`` rows; ``columns`` to choose them)."""
        cols = list(columns) if columns is not None else [
            "candidate", "status", "fit", "rmse", "fit_estimation", "estimated_orders",
            "in_range", "seconds", "reason"]
        rows = self.ranked()[:top]
        out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
        for r in rows:
            out.append("| " + " | ".join(_cell(r.get(c, "")) for c in cols) + " |")
        return "\n".join(out) + "\n"

    def to_csv(self, path=None):
        """The rows as CSV (every column), in the order given; written to ``path`` if given."""
        keys = self._columns()
        extra = [k for k in dict.fromkeys(k for r in self.rows for k in r) if k not in keys]
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=keys + extra, lineterminator="\n")
        writer.writeheader()
        for r in self.rows:
            writer.writerow({k: _describe(v) if k in extra else v for k, v in r.items()})
        text = buf.getvalue()
        if path is not None:
            from ..io.files import write_text

            write_text(text, path)          # atomic, as every fohw save
        return text

    def to_frame(self):
        """The rows as a pandas DataFrame (pandas is an optional dependency)."""
        try:
            import pandas as pd
        except ImportError as exc:
            raise ImportError("Selection.to_frame needs pandas (pip install pandas); "
                              "Selection.rows and Selection.to_csv need nothing.") from exc
        return pd.DataFrame(self.rows)

    def plot(self, ax=None):
        """Held-back fit % of every candidate (failed ones marked), the winner highlighted."""
        from .._plotting import subplots

        if ax is None:
            fig, ax = subplots(figsize=(8, 0.32 * len(self.rows) + 1.5))
        else:
            fig = ax.figure
        rows = self.ranked()[::-1]
        y = np.arange(len(rows))
        fits = np.array([r["fit"] if r["status"] == "ok" else np.nan for r in rows], float)
        shown = np.where(np.isfinite(fits), fits, 0.0)
        colors = ["C3" if r is self.best_row else ("C0" if r["status"] == "ok" else "0.7")
                  for r in rows]
        ax.barh(y, shown, color=colors)
        for yi, r in zip(y, rows):
            if r["status"] != "ok":
                ax.text(0, yi, f" {r['status']}", va="center", fontsize=7)
        ax.set_yticks(y, [r["candidate"] for r in rows], fontsize=7)
        ax.set_xlabel("free-run fit % on the held-back part")
        ax.set_title(f"Structure selection ({self.validation})", fontsize=10)
        fig.tight_layout()
        return fig, ax


def _cell(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "" if np.isnan(v) else f"{v:.4g}"
    return str(v).replace("|", "/")


def _split(u, y, validation):
    """``(u_est, y_est, u_sim, y_score, score_from, description)``."""
    n = len(y)
    if isinstance(validation, Record):
        validation = (validation.u, validation.y)
    if isinstance(validation, tuple) and len(validation) == 2:
        uv = check_array(validation[0], "validation input")
        yv = check_array(validation[1], "validation output")
        check_same_length(uv, yv, "validation input", "validation output")
        return u, y, uv, yv, 0, f"a separate validation record of {len(yv)} samples"
    if isinstance(validation, bool) or not isinstance(validation, numbers.Real):
        raise ParameterError("`validation` must be a fraction in (0, 1), a number of samples, "
                             "or a separate record (u_val, y_val); got "
                             f"{type(validation).__name__}.")
    if isinstance(validation, numbers.Integral):
        n_val = int(validation)
    else:
        if not 0.0 < validation < 1.0:
            raise ParameterError(f"`validation` as a fraction must be in (0, 1); got "
                                 f"{validation!r}.")
        n_val = int(round(validation * n))
    if not 1 <= n_val <= n - 2:
        raise ParameterError(f"`validation` holds back {n_val} of {n} samples; it must leave "
                             "at least 2 for estimation and hold back at least 1.")
    n_est = n - n_val
    return (u[:n_est], y[:n_est], u, y[n_est:], n_est,
            f"the last {n_val} of {n} samples held back; free run from sample 0")


def select_structure(u, y=None, candidates=None, *, validation=0.25, method=None, score="fit",
                     refit=True, executor=None, progress=None, **common):
    """Choose a model structure by free-run simulation on data the fits never saw.

    Parameters
    ----------
    u, y : array_like or Record
        The estimation data (``u`` may be a :class:`fohw.Record`, then ``y`` is omitted).
        Only this record is used to choose: the benchmark's validation record stays unseen.
    candidates : list of dict, or dict of lists
        Keyword arguments of :func:`fohw.identify` for each candidate, or a grid
        ``{"na": [1, 2, 3], "orders": [0, "mixed"], ...}`` (all combinations).
    validation : float, int or (u_val, y_val), optional
        The held-back part: a fraction (default 0.25) or a number of samples at the end of the
        record. Each candidate is fitted on the samples before it and simulated in free run
        from sample 0 through both parts (the held-back part continues the simulation, with its
        GL memory). Or a separate record, simulated from the model's operating point.
    method : str, optional
        The ``identify`` method of every candidate that does not name its own (default: that of
        :func:`fohw.identify`, ``"varpro"``).
    score : {"fit", "rmse", "aic", "bic"}
        How candidates are ranked (default: the held-back fit %; AIC and BIC use the
        estimation part only).
    refit : bool
        Refit the winner on all of ``u, y`` (default True). With a separate validation record
        there is nothing more to fit, and the winner's fit is returned as it is.
    executor : concurrent.futures.Executor, optional
        Run the candidates on it (a ``ProcessPoolExecutor``, dask's ``Client.get_executor()``);
        default serially. Basis functions must then be picklable (module-level functions, not
        lambdas). The table does not depend on the backend.
    progress : bool, optional
        A progress bar on stderr; default: when stderr is a terminal.
    **common
        Keywords of :func:`fohw.identify` shared by every candidate (a candidate's own value
        wins), e.g. ``offset=True, operating_point="mean", dt=4.0``.

    Returns
    -------
    Selection
        ``.rows`` (one dict per candidate with ``"fit"`` and ``"status"``), ``.best`` (the
        refitted winner), ``.to_markdown()``, ``.to_csv()``, ``.to_frame()``, ``.plot()``.

    Raises
    ------
    ParameterError
        Bad ``candidates``, ``validation`` or ``score``. Errors inside one candidate's fit are
        not raised: they are that candidate's ``status`` and ``reason``.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(600, random_state=0)
    >>> sel = fohw.select_structure(data.u, data.y, {"na": [1, 2], "nb": [2]},
    ...                             f_basis=2, g_basis=3)
    >>> [r["status"] for r in sel.rows], sel.best_row["na"]
    (['ok', 'ok'], 2)
    """
    if isinstance(u, Record):
        if y is not None and candidates is None:     # select_structure(record, candidates)
            y, candidates = None, y
        if y is not None:
            raise ParameterError("`u` is a Record: give the output through it, not as `y`.")
        u, y = u.u, u.y
    if y is None:
        raise ParameterError("`y` is missing: give u and y, or a Record as `u`.")
    if candidates is None:
        raise ParameterError("`candidates` is missing: a list of dicts of identify keywords "
                             "or a dict of lists (a grid).")
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if score not in SCORES:
        raise ParameterError(f"`score` must be one of {sorted(SCORES)}; got {score!r}.")
    if method is not None:
        common = dict(common, method=method)
    own = expand_candidates(candidates)
    cands = [dict(common, **c) for c in own]
    u_est, y_est, u_sim, y_score, score_from, described = _split(u, y, validation)
    tasks = [(u_est, y_est, u_sim, y_score, score_from, c) for c in cands]
    t0 = time.perf_counter()
    outcomes = run_tasks(_fit_and_score, tasks, executor=executor, progress=progress,
                         label="select_structure")
    seconds = time.perf_counter() - t0
    rows, results = [], []
    for c, mine, outcome in zip(cands, own, outcomes):
        if isinstance(outcome, TaskError):
            row = _blank_row(status="failed", reason=f"executor: {outcome.message}")
            res = None
        else:
            row, res = outcome
        rows.append(dict(c, candidate=_label(mine), **row))
        results.append(res)
    selection = Selection(rows=rows, best=None, best_index=None, results=results, score=score,
                          validation=described, seconds=seconds)
    ranked = selection.ranked()
    if ranked and ranked[0]["status"] == "ok":
        index = next(i for i, r in enumerate(rows) if r is ranked[0])
        selection.best_index = index
        if refit and score_from > 0:
            from ..estimators.identify import identify

            selection.best = identify(u, y, **cands[index])
        else:
            selection.best = results[index]
    return selection
