"""Structure selection the way system identification does it: fit, then score by free-run simulation.

:func:`select_structure` fits every candidate structure on the estimation part of a record,
simulates it in free run over the estimation part *and on into* a held-back part it never saw,
and ranks the candidates by the fit on the held-back part. A candidate that fails (its fit
raises, its simulation diverges, leaves the finite numbers or leaves the plausible envelope of
the measured output) is recorded with the reason and never loses the others; it is never
picked. A candidate the estimation input cannot identify (an input basis with as many columns
as the input has distinct levels, a mixed-class order gone to 0 with cancelling coefficients)
is ``"unidentifiable"``, with the reason, and never picked either. Each fractional candidate
is tested against its nested integer candidate in the grid (``lr_pvalue``, :func:`fohw.lr_test`).
The winner is refitted on all the estimation data; a refit whose free run diverges or
is implausible is not kept either, and the next candidate is refitted instead.

What can be known before any fit is checked at once (a :class:`fohw.ParameterError`): an empty
grid, a keyword that :func:`fohw.identify` does not take, an unknown method, a required
structure keyword (``na``, ``f_basis``, ``g_basis``) missing from a candidate, a held-back
part too short or constant to score. ``nb`` defaults to ``na`` when a candidate does not give
it (as on the command line).

The fits are independent, so they run on any ``concurrent.futures.Executor`` (a process pool,
or dask's ``Client.get_executor()`` for a cluster); the table is the same whatever the backend.
"""

from __future__ import annotations

import collections
import csv
import dataclasses
import difflib
import inspect
import io
import itertools
import numbers
import re
import textwrap
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .._parallel import TaskError, run_tasks
from .._threads import thin_solves
from .._validation import check_array, check_inputs, check_same_length
from ..estimators._common import joint_levels_note
from ..estimators.fit import fit
from ..estimators.problem import split_inputs
from ..exceptions import (
    ExtrapolationWarning,
    NothingSelectedWarning,
    ParameterError,
    SimulationDivergedError,
)
from ..model.base import Model
from ..model.simulate import check_record_sampling
from ..record import Record, check_sampling, record_data, record_info
from .lrtest import cancelled_orders, davies_from_fit, lr_test, nested_fits, null_orders
from .metrics import aic, bic, fit_percent, rmse
from .order_verdict import verdict
from .validation import ENVELOPE, check_envelope, implausible_message, implausible_sample

__all__ = ["select_structure", "Selection", "expand_candidates", "SCORES"]

#: Ranking criteria: name -> (column, True if larger is better).
SCORES = {"fit": ("fit", True), "rmse": ("rmse", False), "aic": ("aic", False),
          "bic": ("bic", False)}

#: The columns of :attr:`Selection.rows` besides the candidate's own keywords.
COLUMNS = ("candidate", "status", "fit", "rmse", "fit_estimation", "aic", "bic", "n_params",
           "estimated_orders", "in_range", "fit_status", "refit_status", "seconds", "reason",
           "lr_pvalue", "lr_reference", "lr_pvalue_corrected", "order_verdict")

#: Every row ``status``: ``"ok"`` (scored), ``"diverged"``, ``"nan"``, ``"implausible"`` (the
#: free run on the estimation input or the held-back part was not scored: it grew without
#: bound, the output basis returned NaN or inf, or it left the measured output's envelope),
#: ``"failed"`` (the fit, the simulation, the scoring or the executor raised),
#: ``"unidentifiable"`` (the estimation input cannot identify the candidate: its input basis
#: has more columns than the input has distinct levels less one, e.g. a polynomial of degree
#: >= the number of levels; or its mixed-class order went to 0 with cancelling coefficients,
#: :func:`unidentifiable`), and for the candidate whose refit on all the data was not kept,
#: ``"refit_failed"``, ``"refit_diverged"``, ``"refit_nan"``, ``"refit_implausible"``.
STATUSES = ("ok", "diverged", "nan", "implausible", "failed", "unidentifiable", "refit_failed",
            "refit_diverged", "refit_nan", "refit_implausible")

#: Keywords of :func:`fohw.identify` a candidate must give (``nb`` defaults to ``na``).
REQUIRED = ("na", "f_basis", "g_basis")


def expand_candidates(candidates, what="identify"):
    """A list of keyword dicts from a list of dicts or a grid (a dict of lists).

    ``{"na": [1, 2], "orders": [0, "mixed"]}`` gives the four combinations, in
    :func:`itertools.product` order (the first key varies slowest). ``what`` names the function
    whose keywords the candidates are, for the messages.
    """
    if isinstance(candidates, Mapping):
        keys = list(candidates)
        if not keys:
            raise ParameterError("`candidates` is an empty grid {}: give each keyword a list of "
                                 "values, e.g. {'na': [1, 2]}.")
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
        raise ParameterError(f"`candidates` must be a list of dicts of {what} keywords or a "
                             f"dict of lists (a grid); got {type(candidates).__name__}.")
    out = []
    for i, c in enumerate(candidates):
        if not isinstance(c, Mapping):
            raise ParameterError(f"`candidates[{i}]` must be a dict of {what} keywords; got "
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
    describe = getattr(value, "describe", None)    # a series output map
    if callable(describe):
        return describe()
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
                     refit_status="", seconds=np.nan, reason=""), **changes)


def unidentifiable(res, u_est):
    """Why the estimation input ``u_est`` cannot identify the fit ``res`` ("" if it can).

    Two reasons, both cheap: (1) the input takes ``L`` distinct levels and the input basis has
    ``m >= L`` columns, so with a constant (the operating point, or the static gain of the
    linear block) its columns are linearly dependent on the levels the data visit: a polynomial
    of degree ``>= L`` (e.g. degree 2 or 3 on a two-level input) is then anything between the
    levels, and its extrapolation is arbitrary (several inputs: the rank of every input basis
    on the *joint* levels the inputs visit, :func:`fohw.estimators._common.joint_levels_note`);
    (2) a free order of the mixed class went to 0
    with its terms cancelling their order-0 partners
    (:func:`fohw.analysis.lrtest.cancelled_orders`): a near-duplicate column pair.
    """
    reasons = []
    f_basis = res.structure.f_basis
    u_est = np.asarray(u_est, dtype=float)
    if u_est.ndim == 2:         # several inputs: the joint levels (a per-input count misses
        # two inputs moved together: four levels each, four joint levels)
        u0 = np.asarray(res.operating_point[0], dtype=float)
        why = joint_levels_note(res.structure, u_est - u0, u0)
        if why:
            reasons.append(why)
    else:
        why = unidentifiable_input(f_basis, u_est, "")
        if why:
            reasons.append(why)
    reasons.extend(f"near-duplicate columns: {note}" for note in cancelled_orders(res).values())
    return "; ".join(reasons)


def unidentifiable_input(f_basis, u_est, which):
    """Why ``f_basis`` is not identified on the levels of ``u_est`` ("" if it is)."""
    m = len(f_basis.names)
    levels = np.unique(u_est)
    if m >= levels.size:
        return (f"the input basis{which} {_describe(f_basis)} has {m} columns and the "
                f"estimation input takes only {levels.size} distinct level(s) "
                f"({', '.join(f'{v:.4g}' for v in levels[:5])}): with the constant, "
                f"{m + 1} columns on {levels.size} levels are linearly dependent, so the "
                "input map is not identified (use a basis of at most "
                f"{max(levels.size - 1, 0)} column(s), or an input with more levels)")
    return ""


def free_run_check(res, u, reference, envelope, *, initial="fitted"):
    """``(ysim, status, reason)`` of a result's free run on ``u``; ``ysim`` None unless ok.

    ``status`` is ``"ok"``, ``"diverged"``, ``"nan"`` (the output basis) or ``"implausible"``
    (outside the envelope of ``reference``, :func:`fohw.analysis.validation.implausible_sample`).
    ``initial``: the free run's initial state (``result.simulate``); the default
    ``"fitted"`` is right for a record that begins where the estimation record began.
    ExtrapolationWarnings are the caller's to catch.
    """
    try:
        ysim = res.simulate(u, initial=initial)
    except SimulationDivergedError as exc:
        return None, "nan" if exc.cause == "output_basis" else "diverged", str(exc)
    found = implausible_sample(ysim, reference, envelope)
    if found is not None:
        return None, "implausible", implausible_message(found, envelope)
    return ysim, "ok", ""


def own_run_check(res, u, reference, envelope):
    """``(ysim, status, reason)`` of a fit's free run on its own estimation input ``u``.

    The check every fit makes of itself (:func:`fohw.identify`): from the fit's own initial
    state and, for ``past="estimate"``, also from rest (a model that explodes from its
    operating point is unstable, whatever its fitted levels hide), inside the envelope of
    ``reference``.
    """
    got = free_run_check(res, u, reference, envelope)
    if got[1] == "ok" and res.structure.past == "estimate":
        rest = free_run_check(res, u, reference, envelope, initial="rest")
        if rest[1] != "ok":
            return None, rest[1], f"from rest (the operating point): {rest[2]}"
    return got


def _held_back_from_estimate(res, u_est, u_sim, y_score, score_from, reference, envelope,
                             initial, row):
    """``(ysim, status, reason)`` of a candidate validated from a fitted initial state.

    The estimation part from the fit's own state, the held-back part alone from its initial
    state fitted to its output (``initial``: ``"estimate"`` or ``("estimate", n)``,
    :meth:`IdentificationResult.initial_state`), the way it will be validated when the state
    a record starts from is unknown. ``row["n_initial"]``: how many values that fits on the
    held-back output.
    """
    u_val = u_sim[score_from:] if score_from else u_sim
    state = res.initial_state(u_val, y_score, initial)
    row["n_initial"] = int(state.n_estimated)
    yest, status, reason = free_run_check(res, u_est, reference, envelope)
    if status != "ok":
        return None, status, reason
    yval, status, reason = free_run_check(res, u_val, reference, envelope, initial=state)
    if status != "ok":
        return None, status, f"on the held-back part from its fitted initial state: {reason}"
    return (np.r_[yest, yval] if score_from else yval), "ok", ""


def _where(status, reason, score_from):
    """Say on which part a free run failed (the held-back part continues the estimation part)."""
    if not score_from or status not in ("diverged", "nan", "implausible"):
        return reason
    k = re.search(r"sample k = (\d+)", reason)
    if k is None:
        return reason
    part = "estimation part" if int(k.group(1)) < score_from else "held-back part"
    return f"on the {part} (samples 0-{score_from - 1} are the estimation part): {reason}"


@thin_solves
def _fit_and_score(u_est, y_est, u_sim, y_score, score_from, candidate, reference=None,
                   envelope=ENVELOPE, validate_initial=None):
    """One candidate: fit on the estimation part, free-run over ``u_sim``, score the tail.

    Module level (it is pickled for process and dask executors). Never raises: a failure is
    returned as the row's status and reason.
    """
    t0 = time.perf_counter()
    try:
        return _score(u_est, y_est, u_sim, y_score, score_from, candidate,
                      np.r_[y_est, y_score] if reference is None else reference, envelope, t0,
                      validate_initial)
    except Exception as exc:                    # noqa: BLE001 - one candidate never loses the others
        return _blank_row(status="failed", reason=f"scoring: {type(exc).__name__}: {exc}",
                          seconds=time.perf_counter() - t0), None


def _score(u_est, y_est, u_sim, y_score, score_from, candidate, reference, envelope, t0,
           validate_initial=None):
    from ..estimators.identify import identify

    row = _blank_row()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = identify(u_est, y_est, **{"progress": False, **candidate})   # select's own bar
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
            # the held-back part continues the estimation part's free run from its fitted
            # past; a separate record starts at rest (the estimation levels are not its own)
            if validate_initial is None:
                ysim, status, reason = free_run_check(res, u_sim, reference, envelope,
                                                      initial="fitted" if score_from else "rest")
            else:
                ysim, status, reason = _held_back_from_estimate(
                    res, u_est, u_sim, y_score, score_from, reference, envelope,
                    validate_initial, row)
            row.update(status=status, reason=(_where(status, reason, score_from)
                                              if validate_initial is None else reason))
            if status == "ok" and not score_from:     # a separate validation record: and the
                yest, status, reason = free_run_check(res, u_est, reference, envelope)
                if status != "ok":                    # estimation input
                    row.update(status=status, reason=f"on the estimation input: {reason}")
            if status == "ok" and res.structure.past == "estimate":   # and from rest on it
                _, status, reason = own_run_check(res, u_est, reference, envelope)
                if status != "ok":
                    row.update(status=status, reason=f"on the estimation input {reason}")
        except Exception as exc:
            row.update(status="failed", reason=f"simulation: {type(exc).__name__}: {exc}")
        why = unidentifiable(res, u_est)
        unknown = why and row["status"] == "ok"
        if unknown:                   # scored below for the record, never ranked nor picked
            row["status"] = "unidentifiable"
    # result.simulate warns when the input leaves the estimation input's range
    out_of_range = _out_of_range(caught)
    row["in_range"] = out_of_range is None
    if row["status"] != "ok" and not unknown:
        if why:
            row["reason"] = f"{row['reason']}; not identifiable: {why}"
        if out_of_range:
            row["reason"] = f"{row['reason']}; {out_of_range}"
        row["seconds"] = time.perf_counter() - t0
        return row, res
    if np.ptp(y_est) > 0:
        row["fit_estimation"] = fit_percent(y_est, ysim[:score_from] if score_from else yest)
    notes = sorted({str(w.message).split("\n")[0] for w in caught
                    if not issubclass(w.category, ExtrapolationWarning)})   # in `in_range`
    row["rmse"] = rmse(y_score, ysim[score_from:])
    if np.ptp(y_score) > 0:
        row["fit"] = fit_percent(y_score, ysim[score_from:])
    else:
        notes.append("the held-back output is constant: its fit % is undefined (NaN)")
    if unknown:
        notes.insert(0, f"not identifiable: {why}")
    if out_of_range:
        notes.append(out_of_range)
    if notes:
        row["reason"] = "; ".join(notes)
    row["seconds"] = time.perf_counter() - t0
    return row, res


def _out_of_range(caught):
    """Why ``in_range`` is False, for the row's ``reason`` (None when it is True).

    The first :class:`fohw.ExtrapolationWarning` the free runs raised, without its advice (the
    row is the advice): where the input went and the range the candidate was estimated on.
    """
    for w in caught:
        if issubclass(w.category, ExtrapolationWarning):
            return "in_range no: " + str(w.message).split("\n")[0].split("; the basis functions")[0]
    return None


@dataclass
class Selection:
    """The outcome of :func:`select_structure`.

    Attributes
    ----------
    rows : list of dict
        One per candidate, in the order given: the candidate's keywords, then ``candidate``
        (a label), ``status`` (``"ok"``; ``"diverged"``: the free run grew without bound;
        ``"nan"``: a basis function returned NaN or inf during it; ``"implausible"``: it left
        the envelope of the measured output, see ``envelope``; each on the estimation input or
        the held-back part, the reason says which, with the sample and value; ``"failed"``:
        the fit, the simulation, the scoring or the executor raised, the reason says what;
        ``"refit_..."``: the candidate won but its refit on all the data failed, diverged or
        was implausible, so the next one was refitted: :data:`STATUSES`), ``fit``
        (free-run fit % on the held-back part; NaN unless the status is ``"ok"``, and for a
        constant held-back output), ``rmse`` (on it, in the data's units),
        ``fit_estimation`` (free-run fit % on the estimation part), ``aic``, ``bic`` (from the
        method's own criterion on the estimation part: the one-step ``J`` of Eq. 41, or the
        mean squared simulation error for ``"output_error"``), ``n_params``,
        ``estimated_orders`` (the estimated free orders), ``in_range`` (whether the held-back
        input stayed inside the estimation input's range widened by 5 % of its span: no
        :class:`fohw.ExtrapolationWarning` from the simulation; when it did not, ``reason``
        says where the input went and the range it was estimated on), ``fit_status`` (the
        estimator's :class:`fohw.Status` name on the estimation part), ``refit_status`` (the
        refit's status name where the candidate was refitted on all the data, e.g.
        ``RANK_DEFICIENT``, or ``diverged``/``implausible``/``failed``), ``seconds``,
        ``reason`` (why a candidate failed, or the warnings its fit raised), ``lr_pvalue``
        (does the fractional order earn its keep: the p-value of :func:`fohw.lr_test` of the
        candidate against its nested integer candidate, the same keywords with orders 0, if
        the grid has it; on the estimation part's criterion, with the chi-bar-squared mixture
        of Self & Liang for orders on the boundary; NaN for the mixed class unless Davies'
        bound is cheap, a ``"varpro"`` fit of one order; :func:`lr_columns`),
        ``lr_reference`` (the reference distribution and the nested candidate, or why the
        p-value was not computed), ``lr_pvalue_corrected`` (the same test corrected for the
        correlation of the residuals, :func:`fohw.lr_test`'s default ``correction``) and
        ``order_verdict`` (that p-value read beside the held-back ``fit`` of the candidate
        and of its nested one: :mod:`fohw.analysis.order_verdict`).
    best : IdentificationResult, FitResult or None
        The winner refitted on all the data given as estimation data (a
        :class:`fohw.FitResult` for model candidates). ``None`` means nothing
        was selected: every candidate failed, or every refit was rejected (a
        :class:`fohw.ConvergenceWarning` says so).
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

    def __repr__(self):
        n_ok = sum(r["status"] == "ok" for r in self.rows)
        best = ("nothing selected" if self.best_row is None else
                f"best {self.best_row['candidate']!r}, {self.score} "
                f"{_cell(self.best_row.get(SCORES[self.score][0], float('nan')))}")
        return (f"Selection({len(self.rows)} candidates, {n_ok} scored, {best}; "
                f"{self.validation}; {self.seconds:.1f} s)")

    def _repr_html_(self, top=20):
        from .._repr import html_table

        lines = self.to_markdown(top=top).splitlines()
        header = [c.strip() for c in lines[0].strip("|").split("|")]
        rows = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:] if line]
        more = len(self.rows) - len(rows)
        best = ("nothing selected" if self.best_row is None else
                f"best: {self.best_row['candidate']} (refitted on all the data)")
        return html_table(f"Selection of {len(self.rows)} candidates", header, rows,
                          lines=[f"{self.validation}; ranked by {self.score}; {self.seconds:.1f} s",
                                 best],
                          notes=[f"... {more} more (Selection.to_markdown())" if more > 0 else ""])

    @property
    def best_row(self):
        """The winner's row (``None`` if every candidate failed)."""
        return None if self.best_index is None else self.rows[self.best_index]

    def ranked(self):
        """Rows of the candidates that were scored (status ``"ok"``), best first, then the rest."""
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
        """The table, ranked, as Markdown (``top`` rows; ``columns`` to choose them).

        The default columns include ``lr_pvalue``, ``lr_pvalue_corrected`` and
        ``order_verdict`` when some row has a p-value.
        """
        cols = list(columns) if columns is not None else [
            "candidate", "status", "fit", "rmse", "fit_estimation", "estimated_orders",
            "fit_status", "refit_status", "in_range", "seconds", "reason"]
        if columns is None and any("n_initial" in r for r in self.rows):
            cols.insert(cols.index("fit") + 1, "n_initial")
        if columns is None and any(np.isfinite(r.get("lr_pvalue", np.nan)) for r in self.rows):
            at = cols.index("estimated_orders") + 1
            cols[at:at] = ["lr_pvalue", "lr_pvalue_corrected", "order_verdict"]
        if columns is None:        # rows without an in_range, ... column leave it out
            cols = [c for c in cols if any(c in r for r in self.rows)]
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
        """Held-back fit % of every candidate (failed ones marked), the winner highlighted.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: a new figure, its height growing with the candidates).

        Returns
        -------
        matplotlib.figure.Figure
            A new figure is not registered with pyplot (no window; ``fig.savefig`` writes it)
            and shows as the last expression of a notebook cell.
        """
        from .._plotting import axes_for

        fig, (ax,) = axes_for(ax, 1, figsize=(8, 0.32 * len(self.rows) + 1.5))
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
        # wrapped to the axes' width (about 11 characters an inch at 10 pt): never clipped
        width = max(30, int(11 * ax.get_position().width * fig.get_figwidth()))
        ax.set_title(textwrap.fill(f"Structure selection ({self.validation})", width), fontsize=10)
        return fig


def _cell(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "" if np.isnan(v) else f"{v:.4g}"
    return str(v).replace("|", "/")


def split_validation(u, y, validation, names=()):
    """``(u_est, y_est, u_sim, y_score, score_from, description)`` of ``validation``.

    A fraction or a number of samples held back at the end (``score_from`` is where they
    start), or a separate record ``(u_val, y_val)`` (``score_from`` 0); checked, with a
    :class:`fohw.ParameterError` naming ``validation``; a separate record's DataFrame columns
    are matched by the input ``names``.
    """
    n = len(y)
    if isinstance(validation, Record):
        validation = (validation.u, validation.y)
    if isinstance(validation, tuple) and len(validation) == 2:
        uv = check_inputs(validation[0], 1 if np.ndim(u) == 1 else np.shape(u)[1],
                          "validation input", names=names or ())
        yv = check_array(validation[1], "validation output")
        check_same_length(uv, yv, "validation input", "validation output")
        if len(yv) < 2:
            raise ParameterError(f"the `validation` record has {len(yv)} sample; it needs at "
                                 "least 2 to be scored.")
        return u, y, uv, yv, 0, f"a separate validation record of {len(yv)} samples"
    if isinstance(validation, bool) or not isinstance(validation, numbers.Real):
        raise ParameterError("`validation` must be a fraction in (0, 1), a number of samples, "
                             "or a separate record (u_val, y_val); got "
                             f"{type(validation).__name__}.")
    if isinstance(validation, numbers.Integral):
        n_val = int(validation)
        if not 2 <= n_val <= n - 2:
            raise ParameterError(f"`validation` = {n_val} (an int: a number of samples) holds "
                                 f"back {n_val} of {n} samples; it must leave at least 2 for "
                                 "estimation and hold back at least 2 (a fit % needs 2). A "
                                 "fraction of the record is a float in (0, 1), e.g. 0.25.")
    else:
        if not 0.0 < validation < 1.0:
            raise ParameterError(f"`validation` as a fraction must be in (0, 1); got "
                                 f"{validation!r}.")
        n_val = int(round(validation * n))
        if not 2 <= n_val <= n - 2:
            raise ParameterError(f"`validation` = {validation!r} holds back {n_val} of {n} "
                                 "samples; it must leave at least 2 for estimation and hold "
                                 "back at least 2 (a fit % needs 2).")
    n_est = n - n_val
    return (u[:n_est], y[:n_est], u, y[n_est:], n_est,
            f"the last {n_val} of {n} samples held back; free run from sample 0")


def _keyword_source(i, key, own):
    return f"`candidates[{i}]`" if key in own[i] else "the keywords shared by every candidate"


def check_candidates(own, common):
    """The candidates' full keywords (shared ones merged, ``nb`` = ``na`` where absent), checked.

    Raises a :class:`fohw.ParameterError` at once, before any fit, for an unknown method, a
    keyword that :func:`fohw.identify` does not take with the candidate's method, and a
    required keyword (:data:`REQUIRED`) missing from a candidate.
    """
    from ..estimators.identify import METHODS, OPTIONS, identify

    signature = [p for p in inspect.signature(identify).parameters.values()
                 if p.kind is p.KEYWORD_ONLY]
    default_method = next(p.default for p in signature if p.name == "method")
    named = {p.name for p in signature}
    cands = []
    for i, mine in enumerate(own):
        c = dict(common, **mine)
        if "nb" not in c and "na" in c:
            c["nb"] = c["na"]                         # one rule with the command line
        method = c.get("method", default_method)
        if not isinstance(method, str) or method not in METHODS:
            where = (f"`candidates[{i}]['method']`" if "method" in mine else "`method`")
            raise ParameterError(f"{where} must be one of {METHODS}; got {method!r}.")
        known = named | set(OPTIONS[method].names())
        for key in c:
            if key in known:
                continue
            others = [m for m, opts in OPTIONS.items() if key in opts.names()]
            if others:
                why = (f"an option of method(s) {others}, not of {method!r} (the method of "
                       f"candidate {i})")
            else:
                close = difflib.get_close_matches(key, sorted(known), n=1)
                why = "not a keyword of fohw.identify" + (f"; did you mean {close[0]!r}?"
                                                           if close else "")
            raise ParameterError(f"{_keyword_source(i, key, own)} gives {key!r}: {why}.")
        cands.append(c)
    for key in REQUIRED:
        missing = [i for i, c in enumerate(cands) if key not in c]
        if missing:
            which = ("every candidate" if len(missing) == len(cands)
                     else "candidates " + ", ".join(map(str, missing[:10]))
                     + (" ..." if len(missing) > 10 else ""))
            raise ParameterError(f"`{key}` is required by fohw.identify and missing from "
                                 f"{which}: give it in `candidates` or as a keyword shared by "
                                 f"every candidate (select_structure(..., {key}=...)).")
    return cands


def select_structure(u, y=None, candidates=None, *, validation=0.25, method=None, score="fit",
                     refit=True, executor=None, progress=None, envelope=ENVELOPE,
                     hold_out="end", validate_initial=None, **common):
    """Choose a model structure by free-run simulation on data the fits never saw.

    Parameters
    ----------
    u, y : array_like, Record or list of Record
        The estimation data (``u`` may be a :class:`fohw.Record`, then ``y`` is omitted).
        Only this record is used to choose: the benchmark's validation record stays unseen.
        A Record's sampling time is every candidate's: the ``dt`` of identify candidates
        (another ``dt`` is refused), checked against a model candidate's own. A list of
        Records (several experiments) takes model candidates, fitted jointly by
        :func:`fohw.fit` (``**common`` such as ``per_record=``); ``hold_out`` says what is
        held back.
    candidates : list of dict, dict of lists, list of Model or dict of Model
        Keyword arguments of :func:`fohw.identify` for each candidate, or a grid
        ``{"na": [1, 2, 3], "orders": [0, "mixed"], ...}`` (all combinations). ``na``,
        ``f_basis`` and ``g_basis`` are required (here or in ``**common``); ``nb`` defaults to
        ``na`` (as ``fohw select`` without ``--nb``). Or start models of any kinds
        (:class:`fohw.Model`; a dict labels them): each is fitted by :func:`fohw.fit` on the
        estimation part (``**common`` are then its keywords: ``order_grid``, ``n_starts``,
        …), simulated by its own ``simulate`` over the whole record (or from rest on a
        separate one) and scored the same way; the winner is refitted on all the data from
        its estimate, and ``.best`` is a :class:`fohw.FitResult`. Rows then have ``kind`` and
        no ``in_range``; ``lr_pvalue`` tests a candidate against the nested one (same kind,
        some of its free parameters fixed) with the most free parameters, if any
        (:func:`fohw.lr_test` of the estimation fits).
    validation : float, int or (u_val, y_val), optional
        The held-back part: a fraction (default 0.25, a float in (0, 1)) or a number of
        samples (an int, at least 2) at the end of the record. Each candidate is fitted on the
        samples before it and simulated in free run from sample 0 through both parts (the
        held-back part continues the simulation, with its GL memory, from the initial state
        of the fit: ``initial="fitted"``, the estimated levels of a ``past="estimate"``
        candidate, which belong to sample 0). Or a separate record, simulated from the model's
        operating point (``initial="rest"``, for every candidate: the levels a
        ``past="estimate"`` candidate estimated are those before the estimation record, not
        before this one).
    method : str, optional
        The ``identify`` method of every candidate that does not name its own (default: that of
        :func:`fohw.identify`, ``"varpro"``). Not with model candidates.
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
        A progress bar on stderr (tqdm, a notebook widget, if installed; plain lines
        otherwise): True from the start, False never; default (None) once the work has run
        for 2 s.
    envelope : float or None
        Plausibility factor (default 10, :data:`fohw.analysis.validation.ENVELOPE`): a free
        run (on the estimation input or the held-back part) that goes more than ``envelope``
        times the measured output's range (max - min of every output given) outside that
        range is ``"implausible"``, not scored and never picked. None switches the test off.
    hold_out : {"end", "records"}
        For a list of records: ``"end"`` (default) holds back the end of each record
        (``validation`` a fraction or a number of samples of each), every record simulated
        in free run from its start through its held-back end (with its own ``per_record``
        values); ``"records"`` holds back whole records at the end of the list
        (``validation`` a fraction of the records, or an int number of records), simulated
        from rest (not with ``per_record``, whose values belong to the fitted records). The
        pooled held-back samples are scored (one fit %, one RMSE). Not used for one record.
    validate_initial : None, "estimate" or ("estimate", n), optional
        How the held-back part's free run starts. None (default): it continues the estimation
        part's run (or, for a separate record, starts at rest). ``"estimate"``: it is simulated
        alone from its initial state fitted to its own output (the levels ``u_past, y_past``;
        ``("estimate", n)`` also ``n`` past outputs), as ``fohw.compare(...,
        initial="estimate")`` will validate it: rank candidates this way when the state a
        record starts from is unknown (docs/real_data.md), with ``past="estimate"``
        candidates among them. Rows then have ``n_initial``, the values fitted on the
        held-back output. Identify keyword candidates only.
    **common
        Keywords of :func:`fohw.identify` shared by every candidate (a candidate's own value
        wins), e.g. ``offset=True, operating_point="mean", dt=4.0``.

    Returns
    -------
    Selection
        ``.rows`` (one dict per candidate with ``"fit"`` and ``"status"``), ``.best`` (the
        refitted winner; None when nothing was selected), ``.to_markdown()``, ``.to_csv()``,
        ``.to_frame()``, ``.plot()``.

    Raises
    ------
    ParameterError
        At once, before any fit: bad or empty ``candidates``, a keyword ``identify`` does not
        take with the candidate's method, an unknown ``method``, a required keyword missing
        from a candidate, a bad ``validation`` (too short, or a constant held-back output when
        ranking by ``score="fit"``), ``score`` or ``envelope``. Errors inside one candidate's
        fit, simulation or scoring are not raised: they are that candidate's ``status`` and
        ``reason``.

    Warns
    -----
    ConvergenceWarning
        Nothing was selected (every candidate failed, diverged or was implausible, or every
        refit was rejected): ``best`` is None, and the rows say why.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(600, random_state=0)
    >>> sel = fohw.select_structure(data.u, data.y, {"na": [1, 2], "nb": [2]},
    ...                             f_basis=2, g_basis=3)
    >>> [r["status"] for r in sel.rows], sel.best_row["na"]
    (['ok', 'ok'], 2)
    """
    if candidates is None and (isinstance(y, Mapping) or (
            isinstance(y, (list, tuple)) and y and isinstance(y[0], (Mapping, Model)))):
        y, candidates = None, y                       # select_structure(record, candidates)
    records, u, y = record_data(u, y, what="u")
    if records is None and y is None:
        raise ParameterError("`y` is missing: give u and y, or a Record as `u`.")
    if candidates is None:
        raise ParameterError("`candidates` is missing: a list of dicts of identify keywords "
                             "or a dict of lists (a grid).")
    if hold_out not in HOLD_OUT:
        raise ParameterError(f"`hold_out` must be one of {HOLD_OUT}; got {hold_out!r}.")
    models = model_candidates(candidates)
    if records is not None:
        common = _record_settings(records, validation, models, common)
    if models is not None:
        if method is not None:
            raise ParameterError(f"`method` is for identify keyword candidates; model "
                                 f"candidates are fitted by fohw.fit; got method={method!r}.")
        if validate_initial is not None:
            raise ParameterError("`validate_initial` is for identify keyword candidates (the "
                                 "lagged kind, whose results fit a record's initial state); "
                                 f"got validate_initial={validate_initial!r} with models.")
        if records is not None and u is None:
            return _select_records(records, models, validation, hold_out, score, refit,
                                   executor, progress, envelope, common)
        selection = _select_models(u, y, models, validation, score, refit, executor,
                                   progress, envelope, common)
        return _with_record_info(selection, records)
    if records is not None and u is None:
        raise ParameterError(
            f"`u` holds {len(records)} records: several experiments are fitted by fohw.fit, so "
            "give model candidates (e.g. fohw.HammersteinWiener start models, or any kind); "
            "identify keyword candidates take one record.")
    u, names = split_inputs(u)
    if names is not None and "inputs" not in common:
        common = dict(common, inputs=names)
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if score not in SCORES:
        raise ParameterError(f"`score` must be one of {sorted(SCORES)}; got {score!r}.")
    if method is not None:
        common = dict(common, method=method)
    own = expand_candidates(candidates)
    cands = check_candidates(own, common)
    factor = check_envelope(envelope)
    u_est, y_est, u_sim, y_score, score_from, described = split_validation(
        u, y, validation, common.get("inputs") or names or ())
    if score == "fit" and np.ptp(y_score) == 0:
        raise ParameterError(f"the held-back output ({described}) is constant ({float(y_score[0])!r}): "
                             "no candidate can be ranked by its fit %. Hold back a part where "
                             "the output moves (`validation`), or rank by score='rmse'.")
    reference = np.r_[y, y_score] if score_from == 0 else y     # every measured output
    validate_initial = _check_validate_initial(validate_initial)
    if validate_initial is not None:
        n = 2 + (0 if isinstance(validate_initial, str) else validate_initial[1])
        described = described.replace("; free run from sample 0", "")
        described += (f"; the held-back part simulated alone from its initial state fitted to "
                      f"its output (initial={validate_initial!r}: {n} values)")
    tasks = [(u_est, y_est, u_sim, y_score, score_from, c, reference, factor, validate_initial)
             for c in cands]
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
    lr_columns(rows, results, cands, u_est, y_est)
    selection = Selection(rows=rows, best=None, best_index=None, results=results, score=score,
                          validation=described, seconds=seconds)
    _pick(selection, cands, u, y, refit and score_from > 0, factor)
    _with_record_info(selection, records)
    if selection.best is None:
        warn_nothing_selected("select_structure", rows)
    return selection


def _with_record_info(selection, records):
    """The refitted winner keeps what the record was (names, units, sampling)."""
    if records is not None and selection.best is not None and \
            selection.best is not selection.results[selection.best_index]:   # refitted on it
        selection.best = dataclasses.replace(selection.best, data=record_info(records))
    return selection


#: What a list of records holds back (:func:`select_structure`'s ``hold_out``).
HOLD_OUT = ("end", "records")


def _record_settings(records, validation, models, common):
    """Check the records' sampling against the candidates; identify candidates get its ``dt``.

    A Record's sampling time is every candidate's (``fohw select`` reads it from the file the
    same way): identify candidates are fitted at it, and a ``dt`` that says otherwise is
    refused, as is a model candidate at another step.
    """
    extra = [validation] if isinstance(validation, Record) else (
        list(validation) if isinstance(validation, (list, tuple)) and validation
        and all(isinstance(v, Record) for v in validation) else [])
    every = records + extra
    if models is not None:
        for _, m in models:
            for r in every:
                check_record_sampling(m, r)
        return common
    for r in every:
        if not r.uniform:
            raise ParameterError(
                f"the record{f' {r.name!r}' if r.name else ''} has non-uniform time stamps; "
                "identify candidates run on a uniform grid: resample it, or give model "
                "candidates of a kind that simulates on time stamps.")
    dts = {r.dt for r in every if r.dt is not None}
    if not dts:
        return common
    if len(dts) > 1:
        raise ParameterError(f"the records have different sampling times ({sorted(dts)}).")
    dt = dts.pop()
    if common.get("dt") is not None:
        check_sampling(every, float(common["dt"]), what="`dt`")
    out = dict(common, dt=dt)
    if records[0].n_inputs > 1 and "inputs" not in common:
        out["inputs"] = records[0].input_names
    return out


def _records_split(records, validation, hold_out):
    """``(estimation records, scored records, score_from per scored record, description)``."""
    n_rec = len(records)
    if hold_out == "records":
        if isinstance(validation, bool) or not isinstance(validation, numbers.Real):
            raise ParameterError("`validation` with hold_out='records' is a fraction of the "
                                 "records or a number of records; got "
                                 f"{type(validation).__name__}.")
        k = int(validation) if isinstance(validation, numbers.Integral) else \
            int(round(validation * n_rec))
        if not 1 <= k <= n_rec - 1:
            raise ParameterError(f"`validation` = {validation!r} holds back {k} of {n_rec} "
                                 "records; it must hold back at least 1 and leave at least 1.")
        return (records[:n_rec - k], records[n_rec - k:], [0] * k,
                f"the last {k} of {n_rec} records held back; each simulated from rest")
    if isinstance(validation, (tuple, list, Record)):
        raise ParameterError("`validation` with several records is a fraction or a number "
                             "of samples held back at the end of each record.")
    est, froms = [], []
    for r in records:
        parts = split_validation(r.u, r.y, validation)
        est.append(r[:parts[4]])
        froms.append(parts[4])
    total = sum(r.n_samples - f for r, f in zip(records, froms))
    return (est, records, froms, f"the end of each of {n_rec} records held back ({total} "
            "samples in all); each simulated from its start")


def _per_record_model(res, k):
    """The fitted model of record ``k`` (its ``per_record`` values put in)."""
    if not res.per_record:
        return res.model
    return res.model.with_parameters({n: v["values"][k] for n, v in res.per_record.items()})


def _records_free_runs(res, scored, froms, reference, envelope):
    """``(runs, status, reason)`` of each scored record's free run (``runs`` None unless ok)."""
    runs = []
    for k, r in enumerate(scored):
        model = _per_record_model(res, k) if froms[k] else res.model
        ysim, status, reason = model_free_run(model, r.u, reference, envelope)
        if status != "ok":
            return None, status, f"record {k}: {reason}"
        runs.append(ysim)
    return runs, "ok", ""


@thin_solves
def _fit_and_score_records(est, scored, froms, model, options, reference, envelope):
    """One model candidate on several records: joint fit, free runs, the pooled held-back score.

    Module level (it is pickled for process and dask executors). Never raises.
    """
    t0 = time.perf_counter()
    row = _model_row()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                res = fit(model, est, **options)
            except Exception as exc:          # noqa: BLE001 - one candidate never loses the others
                row.update(status="failed", reason=f"fit: {type(exc).__name__}: {exc}",
                           seconds=time.perf_counter() - t0)
                return row, None
            n, d = res.n_samples, res.n_free
            orders = [k for k in res.free_names if res.parameters[k].order]
            row.update(n_params=d, fit_status=res.status.name, estimated_orders=", ".join(
                f"{k}={res.parameters[k].value:.4g}" for k in orders))
            if res.sse > 0:
                row["aic"], row["bic"] = aic(res.sse / n, n, d), bic(res.sse / n, n, d)
            runs, status, reason = _records_free_runs(res, scored, froms, reference, envelope)
        notes = sorted({str(w.message).split("\n")[0] for w in caught})
        row["seconds"] = time.perf_counter() - t0
        if status != "ok":
            row.update(status=status, reason="; ".join([reason, *notes]))
            return row, res
        y_score = np.concatenate([r.y[f:] for r, f in zip(scored, froms)])
        y_sim = np.concatenate([s[f:] for s, f in zip(runs, froms)])
        y_est = np.concatenate([r.y for r in est])
        if np.ptp(y_est) > 0:
            row["fit_estimation"] = fit_percent(y_est, y_est - res.residuals)
        row["rmse"] = rmse(y_score, y_sim)
        if np.ptp(y_score) > 0:
            row["fit"] = fit_percent(y_score, y_sim)
        else:
            notes.append("the held-back output is constant: its fit % is undefined (NaN)")
        row["reason"] = "; ".join(notes)
        return row, res
    except Exception as exc:                    # noqa: BLE001 - one candidate never loses the others
        return _model_row(status="failed", reason=f"scoring: {type(exc).__name__}: {exc}",
                          seconds=time.perf_counter() - t0), None


def _check_score_refit(score, refit):
    """A ParameterError unless ``score`` is one of SCORES and ``refit`` a bool."""
    if score not in SCORES:
        raise ParameterError(f"`score` must be one of {sorted(SCORES)}; got {score!r}.")
    if not isinstance(refit, (bool, np.bool_)):
        raise ParameterError(f"`refit` must be True or False; got {refit!r}.")


def _score_models(worker, tasks, models, score, described, executor, progress):
    """The :class:`Selection` (no best yet) of model candidates scored by ``worker``."""
    t0 = time.perf_counter()
    outcomes = run_tasks(worker, tasks, executor=executor, progress=progress,
                         label="select_structure")
    seconds = time.perf_counter() - t0
    rows, results = [], []
    for (label, m), outcome in zip(models, outcomes):
        if isinstance(outcome, TaskError):
            row, res = _model_row(status="failed", reason=f"executor: {outcome.message}"), None
        else:
            row, res = outcome
        rows.append(dict(candidate=label, kind=type(m).__name__, **row))
        results.append(res)
    model_lr_columns(rows, results)
    selection = Selection(rows=rows, best=None, best_index=None, results=results, score=score,
                          validation=described, seconds=seconds)
    return selection


def _note_refit_status(row, best):
    """A kept refit's status in its row (``pick_refitted``'s ``finish``)."""
    row["refit_status"] = best.status.name


def _select_records(records, models, validation, hold_out, score, refit, executor, progress,
                    envelope, common):
    """:func:`select_structure` of model candidates on several records (joint fits)."""
    _check_score_refit(score, refit)
    if hold_out == "records" and common.get("per_record"):
        raise ParameterError("`per_record` parameters have values for the fitted records only, "
                             "none for a held-back record: hold back the end of each record "
                             "(hold_out='end'), or fit without per_record.")
    factor = check_envelope(envelope)
    est, scored, froms, described = _records_split(records, validation, hold_out)
    reference = np.concatenate([r.y for r in records])
    if score == "fit" and np.ptp(np.concatenate([r.y[f:] for r, f in zip(scored, froms)])) == 0:
        raise ParameterError(f"the held-back output ({described}) is constant: no candidate can "
                             "be ranked by its fit %; rank by score='rmse'.")
    tasks = [(est, scored, froms, m, common, reference, factor) for _, m in models]
    selection = _score_models(_fit_and_score_records, tasks, models, score, described,
                              executor, progress)
    results = selection.results

    def refit_one(index):
        start = None if results[index] is None else results[index].model
        best = fit(models[index][1], records, start=start, **common)
        runs = _records_free_runs(best, records, [1] * len(records), reference, factor)
        return (best, *runs[1:])

    pick_refitted(selection, refit_one, _note_refit_status, refit=bool(refit))
    if selection.best is None:
        warn_nothing_selected("select_structure", selection.rows)
    return selection


def _check_validate_initial(value):
    """``validate_initial`` as None, ``"estimate"`` or ``("estimate", n)``, else a ParameterError."""
    if value is None or (isinstance(value, str) and value == "estimate"):
        return value
    if (isinstance(value, (tuple, list)) and len(value) == 2 and value[0] == "estimate"
            and isinstance(value[1], numbers.Integral) and not isinstance(value[1], bool)
            and value[1] >= 0):
        return ("estimate", int(value[1]))
    raise ParameterError("`validate_initial` must be None, 'estimate' or ('estimate', n) with "
                         f"an integer n >= 0; got {value!r}.")


def model_candidates(candidates):
    """``[(label, Model)]`` when ``candidates`` are models (a list, or a dict label -> model).

    None when they are keyword dicts (the lagged kind's candidates); a mixture is refused.
    """
    if isinstance(candidates, Mapping):
        items = list(candidates.items())
    elif isinstance(candidates, Sequence) and not isinstance(candidates, (str, bytes)):
        items = [(None, c) for c in candidates]
    else:
        return None
    is_model = [isinstance(m, Model) for _, m in items]
    if not any(is_model):
        return None
    if not all(is_model):
        i = is_model.index(False)
        raise ParameterError(f"`candidates` mixes fohw.Model start models with other entries "
                             f"(entry {i} is {type(items[i][1]).__name__}): give models only, "
                             "or identify keyword dicts only.")
    out = []
    for i, (key, m) in enumerate(items):
        if key is None:
            fixed = ", ".join(f"{n}={p.value:g}" for n, p in m.parameters.items() if p.fixed)
            key = f"{i}: {type(m).__name__}" + (f" ({fixed})" if fixed else "")
        out.append((str(key), m))
    return out


def _model_row(**changes):
    """A row of a model candidate before (or without) a fit."""
    return dict(dict(status="ok", fit=np.nan, rmse=np.nan, fit_estimation=np.nan, aic=np.nan,
                     bic=np.nan, n_params=0, estimated_orders="", fit_status="",
                     refit_status="", seconds=np.nan, reason="", lr_pvalue=np.nan,
                     lr_reference="", lr_pvalue_corrected=np.nan, order_verdict=""),
                **changes)


def model_free_run(model, u, reference, envelope):
    """``(ysim, status, reason)`` of a model's free run on ``u``; ``ysim`` None unless ok."""
    try:
        with np.errstate(all="ignore"):
            ysim = np.asarray(model.simulate(u), dtype=float)
    except SimulationDivergedError as exc:
        return None, "diverged" if exc.cause == "growth" else "nan", str(exc)
    bad = np.flatnonzero(~np.isfinite(ysim))
    if bad.size:
        return None, "diverged", (f"the free run leaves the finite numbers at sample "
                                  f"k = {int(bad[0])}.")
    found = implausible_sample(ysim, reference, envelope)
    if found is not None:
        return None, "implausible", implausible_message(found, envelope)
    return ysim, "ok", ""


@thin_solves
def _fit_and_score_model(u_est, y_est, u_sim, y_score, score_from, model, options, reference,
                         envelope):
    """One model candidate: :func:`fohw.fit` on the estimation part, free run, score the tail.

    Module level (it is pickled for process and dask executors). Never raises.
    """
    t0 = time.perf_counter()
    row = _model_row()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                res = fit(model, u_est, y_est, **options)
            except Exception as exc:          # noqa: BLE001 - one candidate never loses the others
                row.update(status="failed", reason=f"fit: {type(exc).__name__}: {exc}",
                           seconds=time.perf_counter() - t0)
                return row, None
            n, d = len(y_est), res.n_free
            orders = [k for k in res.free_names if res.parameters[k].order]
            row.update(n_params=d, fit_status=res.status.name, estimated_orders=", ".join(
                f"{k}={res.parameters[k].value:.4g}" for k in orders))
            if res.sse > 0:
                row["aic"], row["bic"] = aic(res.sse / n, n, d), bic(res.sse / n, n, d)
            ysim, status, reason = model_free_run(res.model, u_sim, reference, envelope)
            reason = _where(status, reason, score_from)
            if status == "ok" and not score_from:            # a separate validation record
                yest, status, reason = model_free_run(res.model, u_est, reference, envelope)
                reason = reason and f"on the estimation input: {reason}"
        notes = sorted({str(w.message).split("\n")[0] for w in caught})
        row["seconds"] = time.perf_counter() - t0
        if status != "ok":
            row.update(status=status, reason="; ".join([reason, *notes]))
            return row, res
        if np.ptp(y_est) > 0:
            row["fit_estimation"] = fit_percent(y_est, ysim[:score_from] if score_from else yest)
        row["rmse"] = rmse(y_score, ysim[score_from:])
        if np.ptp(y_score) > 0:
            row["fit"] = fit_percent(y_score, ysim[score_from:])
        else:
            notes.append("the held-back output is constant: its fit % is undefined (NaN)")
        row["reason"] = "; ".join(notes)
        return row, res
    except Exception as exc:                    # noqa: BLE001 - one candidate never loses the others
        return _model_row(status="failed", reason=f"scoring: {type(exc).__name__}: {exc}",
                          seconds=time.perf_counter() - t0), None


def model_lr_columns(rows, results):
    """Fill ``lr_pvalue`` and ``lr_reference`` of model candidates (in place).

    Each fit is tested against the nested candidate of most free parameters (the same kind
    with some of them fixed) by :func:`fohw.lr_test` on the estimation part (no refits).
    """
    fitted = [(i, r) for i, r in enumerate(results) if r is not None]
    for i, full in fitted:
        nested = []
        for j, restricted in fitted:
            try:
                nested_fits(restricted, full)
            except ParameterError:
                continue
            nested.append((restricted.n_free, j))
        if not nested:
            continue
        j = max(nested)[1]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            test = lr_test(results[j], full)
        rows[i]["lr_pvalue"] = test.pvalue
        _verdict_columns(rows, i, j, test)
        rows[i]["lr_reference"] = (f"{test.distribution}, {test.criterion} vs "
                                   f"{rows[j]['candidate']} ({test.hypothesis})"
                                   + "".join(f"; {w.message}" for w in caught))


def _select_models(u, y, models, validation, score, refit, executor, progress, envelope,
                   common):
    """:func:`select_structure` of model candidates (any kind), fitted by :func:`fohw.fit`."""
    known = {p.name for p in inspect.signature(fit).parameters.values()
             if p.kind is p.KEYWORD_ONLY} - {"start"}
    unknown = sorted(set(common) - known)
    if unknown:
        close = difflib.get_close_matches(unknown[0], sorted(known), n=1)
        raise ParameterError(f"the keywords shared by every model candidate give "
                             f"{unknown[0]!r}: not a keyword of fohw.fit ({sorted(known)})"
                             + (f"; did you mean {close[0]!r}?" if close else "") + ".")
    y = check_array(y, "y")
    for _, m in models:                        # every input checked before any fit
        check_same_length(m.check_input(u), y, "u", "y")
    u = np.asarray(u, dtype=float)
    _check_score_refit(score, refit)
    factor = check_envelope(envelope)
    u_est, y_est, u_sim, y_score, score_from, described = split_validation(u, y, validation)
    if score == "fit" and np.ptp(y_score) == 0:
        raise ParameterError(f"the held-back output ({described}) is constant "
                             f"({float(y_score[0])!r}): no candidate can be ranked by its fit %. "
                             "Hold back a part where the output moves (`validation`), or rank "
                             "by score='rmse'.")
    reference = np.r_[y, y_score] if score_from == 0 else y
    tasks = [(u_est, y_est, u_sim, y_score, score_from, m, common, reference, factor)
             for _, m in models]
    selection = _score_models(_fit_and_score_model, tasks, models, score, described,
                              executor, progress)
    results = selection.results

    def refit_one(index):
        start = None if results[index] is None else results[index].model
        best = fit(models[index][1], u, y, start=start, **common)
        return (best, *model_free_run(best.model, u, y, factor)[1:])

    pick_refitted(selection, refit_one, _note_refit_status, refit=bool(refit) and score_from > 0)
    if selection.best is None:
        warn_nothing_selected("select_structure", selection.rows)
    return selection


def warn_nothing_selected(who, rows):
    """A NothingSelectedWarning, from the caller of ``who``, counting the rows' statuses."""
    counts = collections.Counter(r["status"] for r in rows)
    text = ", ".join(f"{v} {k}" for k, v in counts.items())
    warnings.warn(NothingSelectedWarning(
        f"{who} selected nothing: of {len(rows)} candidates, {text}; "
        "Selection.rows give each one's status and reason (Selection.best is None)."),
        stacklevel=3)


def _verdict_columns(rows, i, j, test):
    """``lr_pvalue_corrected`` and ``order_verdict`` of row ``i`` tested against row ``j``."""
    rows[i]["lr_pvalue_corrected"] = test.pvalue_corrected
    rows[i]["order_verdict"] = verdict(test.pvalue_corrected, rows[j].get("fit", np.nan),
                                       rows[i].get("fit", np.nan))


def lr_columns(rows, results, cands, u=None, y=None):
    """Fill ``lr_pvalue`` and ``lr_reference`` of every row (in place).

    A row whose fit has free orders is tested by :func:`fohw.lr_test` against its nested
    integer candidate: the row of the grid with the same keywords but ``orders`` (its fit's
    orders are those of the fractional fit at 0), both fits on the same estimation part. The
    reference is lr_test's ``"auto"``: the chi-bar-squared mixture (``0.5 chi2_0 + 0.5 chi2_1``
    for one order; Self & Liang 1987) when every order is on the boundary under the null; for
    an order that is not identified under the null (the mixed class), Davies' (1987) bound
    only when it is cheap (a ``"varpro"`` fit of one order keeps the profile), else NaN and
    ``lr_reference`` says so. No nested candidate in the grid: NaN and an empty reference.
    With the estimation part ``u, y``, the corrected p-value and the verdict too.
    """
    for row in rows:
        row["lr_pvalue"], row["lr_reference"] = np.nan, ""
        row["lr_pvalue_corrected"], row["order_verdict"] = np.nan, ""
    fitted = [(i, r) for i, r in enumerate(results) if r is not None]
    for i, full in fitted:
        if not full.structure.orders.free:
            continue
        null, _, unidentified = null_orders(full.structure.orders)
        mine = {k: _describe(v) for k, v in cands[i].items() if k != "orders"}
        nested = next((j for j, r in fitted if not r.structure.orders.free
                       and r.structure.orders == null
                       and {k: _describe(v) for k, v in cands[j].items() if k != "orders"}
                       == mine), None)
        if nested is None:
            continue
        against = f"vs {rows[nested]['candidate']}"
        if unidentified and not davies_from_fit(full):
            rows[i]["lr_reference"] = (
                f"not computed {against}: order(s) {', '.join(unidentified)} not identified "
                "under the null and Davies' bound needs refits here; call fohw.lr_test(..., "
                "reference='davies' or 'bootstrap', u=, y=)")
            continue
        try:
            try:                    # the record gives the residuals the correction needs
                test = lr_test(results[nested], full, u=u, y=y)
            except ParameterError:
                test = lr_test(results[nested], full)
        except (ParameterError, ValueError, ArithmeticError) as exc:
            rows[i]["lr_reference"] = f"not computed {against}: {str(exc).split('. ')[0]}"
            continue
        rows[i]["lr_pvalue"] = test.pvalue
        _verdict_columns(rows, i, nested, test)
        rows[i]["lr_reference"] = f"{test.distribution}, {test.criterion} {against}"


def _pick(selection, cands, u, y, refit, envelope):
    """The best row that simulated, refitted on all the data if asked (:func:`pick_refitted`)."""
    from ..estimators.identify import identify

    def refit_one(index):
        best = identify(u, y, **{"progress": False, **cands[index]})
        scored = selection.results[index]
        if scored is not None and (best.method != scored.method
                                   or best.structure != scored.structure):
            return best, "failed", (f"the refit is not the fit that was scored (the refit: "
                                    f"method {best.method!r}, {best.structure.describe()}; "
                                    f"scored: {scored.method!r}, {scored.structure.describe()})")
        return (best, *own_run_check(best, u, y, envelope)[1:])

    def finish(row, best):
        row["refit_status"] = best.status.name
        if best.status.name == "RANK_DEFICIENT":
            row["reason"] = ("refit on all the data ended RANK_DEFICIENT (its summary() names "
                             "the parameters)" + (f"; {row['reason']}" if row["reason"] else ""))

    pick_refitted(selection, refit_one, _note_refit_status, refit=refit,
                  keep=lambda w: not issubclass(w.category, ExtrapolationWarning))


def pick_refitted(selection, refit_one, finish, *, refit, keep=lambda w: True):
    """Set ``selection.best``: the best scored row, refitted on all the data if ``refit``.

    ``refit_one(index) -> (fit, status, reason)`` refits candidate ``index`` and checks its
    free run; ``finish(row, fit)`` records a kept refit in its row. A refit that raises, or
    whose status is not ``"ok"``, is not kept: its row says why (``refit_*`` status, with its
    warnings) and the next ranked candidate is refitted. The kept refit's warnings are the
    user's (re-issued), those ``keep`` rejects excepted. Used by :func:`select_structure`.
    """
    col = SCORES[selection.score][0]
    rows = selection.rows
    for row in selection.ranked():
        if row["status"] != "ok" or not (isinstance(row[col], numbers.Real)
                                         and np.isfinite(row[col])):
            break
        index = next(i for i, r in enumerate(rows) if r is row)
        if not refit:
            selection.best_index, selection.best = index, selection.results[index]
            return
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                best, status, reason = refit_one(index)
            except Exception as exc:                    # noqa: BLE001 - reported in the row
                best, status, reason = None, "failed", f"{type(exc).__name__}: {exc}"
        kept = [w for w in caught if keep(w)]
        if status != "ok":         # not kept: its warnings go to its row, not to the user
            notes = sorted({str(w.message).split("\n")[0] for w in kept})
            row.update(status=f"refit_{status}", refit_status=status,
                       reason="; ".join([f"refit on all the data: {reason}", *notes,
                                         *([row["reason"]] if row["reason"] else [])]))
            continue
        for w in kept:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        finish(row, best)
        selection.best_index, selection.best = index, best
        return
