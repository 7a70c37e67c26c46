"""Reproduction of the paper's academic example: Table 2 and Figs. 3–6 (Section 6.1).

The functions here run the estimators once and turn the results into the tables and figures
that ``examples/table_2.py``, ``examples/figure_3.py`` … ``figure_6.py`` and
``fohw reproduce table2`` write. The paper's printed numbers come from the package data file
``fohw/data/paper_table2.json`` (with its source and the paper's misprints kept).

The second half is the forgetting map of ``examples/forgetting_map.py`` and
``fohw reproduce forgetting``: the same method with ``r(k) = lambda r(k-1) + ||Phi(P, k)||^2``,
a forgetting factor that is not in the paper, over lambda, ``P`` and schedule. The as-printed
reading (lambda = 1) stays the default everywhere.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from importlib import resources

import numpy as np

from .._parallel import TaskError, run_tasks
from .._plotting import subplots
from ..datasets import SimulatedData, paper_example
from ..estimators.identify import OPTIONS, identify
from ..exceptions import ConvergenceWarning, FohwError, ParameterError
from ..results import IdentificationResult

__all__ = ["paper_table2", "PaperRuns", "run_paper_example", "table2_rows", "table2_markdown",
           "monte_carlo_table2", "plot_figure_3", "plot_figure_4", "plot_figure_5",
           "plot_figure_6", "MISPRINT_RATIO", "OUTPUTS", "write_outputs", "example_main",
           "FORGETTING_FACTORS", "FORGETTING_SCHEDULES", "forgetting_map", "forgetting_summary",
           "forgetting_p_comparison", "best_forgetting", "forgetting_markdown",
           "plot_forgetting_map", "plot_forgetting_best", "forgetting_main"]

#: A printed entry is flagged as a likely misprint when its ratio to the true value is
#: outside ``[1/MISPRINT_RATIO, MISPRINT_RATIO]`` (the paper's slips are factors of ten).
MISPRINT_RATIO = 5.0

_STRUCTURE = dict(na=2, nb=2, f_basis=2, g_basis=3)


def paper_table2() -> dict:
    """The paper's Table 2 as printed (and Table 3's error ranges), with its source.

    Examples
    --------
    >>> from fohw.paper.reproduction import paper_table2
    >>> t = paper_table2()
    >>> t["true"]["alpha"], len(t["rows"])
    (0.6, 9)
    """
    text = resources.files("fohw").joinpath("data/paper_table2.json").read_text()
    return json.loads(text)


@dataclass(frozen=True)
class PaperRuns:
    """One simulated record of the academic example and the runs made on it.

    Attributes
    ----------
    data : SimulatedData
    hybrid : dict of int to IdentificationResult
        The paper's method for each innovation length ``P``.
    baselines : dict of str to IdentificationResult
        The Fig. 6 baselines (``"single_innovation_gradient"``, ``"single_innovation_lm"``).
    """

    data: SimulatedData
    hybrid: dict
    baselines: dict


def _identify_quietly(u, y, **kwargs) -> IdentificationResult:
    # A single recursive pass (Table 1) never tests convergence, so identify warns; the
    # result still says converged=False, and the docs explain it.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return identify(u, y, **_STRUCTURE, **kwargs)


def run_paper_example(n_samples=10_000, *, random_state=0, innovation_lengths=(1, 3, 5),
                      baselines=True, **identify_options) -> PaperRuns:
    """Simulate the academic example and run the paper's hybrid method (and the baselines).

    Parameters
    ----------
    n_samples : int
        Record length (10 000 in the paper).
    random_state : int or Generator
        Seed of :func:`fohw.datasets.paper_example`.
    innovation_lengths : sequence of int
        The ``P`` values of Table 2.
    baselines : bool
        Also run the two single-innovation baselines of Fig. 6.
    **identify_options
        Options of the hybrid method (:class:`fohw.HybridOptions`; default: the recursive
        schedule of Table 1, one pass, ``alpha0 = 0.5``); the baselines get those they have.

    Returns
    -------
    PaperRuns
    """
    data = paper_example(n_samples, random_state=random_state)
    hybrid = {P: _identify_quietly(data.u, data.y, method="hybrid", innovation_length=P,
                                   **identify_options)
              for P in innovation_lengths}
    base = {}
    if baselines:
        for method in ("single_innovation_gradient", "single_innovation_lm"):
            shared = {k: v for k, v in identify_options.items() if k in OPTIONS[method].names()}
            base[method] = _identify_quietly(data.u, data.y, method=method, **shared)
    return PaperRuns(data=data, hybrid=hybrid, baselines=base)


def _is_misprint(value, true):
    ratio = value / true
    return not (1.0 / MISPRINT_RATIO <= ratio <= MISPRINT_RATIO)


def table2_rows(runs: PaperRuns, checkpoints=(2000, 5000, 10000)) -> list[dict]:
    """Rows of Table 2: for every ``P`` and checkpoint ``k``, ours beside the paper's.

    Each row has ``P``, ``k``, ``parameter``, ``true``, ``fohw``, ``paper`` (``nan`` where the
    paper has no row) and ``paper_misprint`` (a flag, see :data:`MISPRINT_RATIO`). The
    parameters are alpha, the ten entries of theta, and ``delta``
    (``||theta_hat(k) - theta|| / ||theta||``; the paper's is computed from its printed entries).
    """
    ref = paper_table2()
    true = ref["true"]
    names = ref["theta_order"]
    theta_true = np.array([true[n] for n in names])
    printed = {(row["P"], row["k"]): row for row in ref["rows"]}
    rows = []
    for P, res in runs.hybrid.items():
        for k in checkpoints:
            if k > res.n_samples:
                continue
            theta_k = res.theta_history[k - 1]
            alpha_k = res.alpha_sample_history[k - 1]
            paper = printed.get((P, k))
            ours = {"alpha": alpha_k, **dict(zip(names, theta_k))}
            for name in ["alpha"] + names:
                p_val = paper[name] if paper else np.nan
                rows.append(dict(P=P, k=k, parameter=name, true=true[name], fohw=float(ours[name]),
                                 paper=p_val, paper_misprint=bool(paper) and _is_misprint(p_val, true[name])))
            delta = float(np.linalg.norm(theta_k - theta_true) / np.linalg.norm(theta_true))
            p_delta = (float(np.linalg.norm(np.array([paper[n] for n in names]) - theta_true)
                             / np.linalg.norm(theta_true)) if paper else np.nan)
            rows.append(dict(P=P, k=k, parameter="delta", true=0.0, fohw=delta, paper=p_delta,
                             paper_misprint=False))
    return rows


def table2_markdown(rows: list[dict]) -> str:
    """Format :func:`table2_rows` as one Markdown table per ``P``: ours beside the paper's.

    Printed entries flagged as misprints are marked with ``†``; ``–`` where the paper has no
    value.
    """
    ref = paper_table2()
    params = ["alpha"] + ref["theta_order"] + ["delta"]
    by = {(r["P"], r["k"], r["parameter"]): r for r in rows}
    out = []
    for P in sorted({r["P"] for r in rows}):
        ks = sorted({r["k"] for r in rows if r["P"] == P})
        out.append(f"**P = {P}**\n")
        out.append("| parameter | true | " + " | ".join(f"k={k} fohw | k={k} paper" for k in ks) + " |")
        out.append("|---|---:|" + "---:|---:|" * len(ks))
        for name in params:
            cells = []
            for k in ks:
                r = by[(P, k, name)]
                paper = ("–" if np.isnan(r["paper"]) else
                         f"{r['paper']:.4f}" + ("†" if r["paper_misprint"] else ""))
                cells.append(f"{r['fohw']:.4f} | {paper}")
            true = "" if name == "delta" else f"{ref['true'][name]:g}"
            out.append(f"| {name} | {true} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


def _one_seed(seed, n_samples, innovation_lengths, checkpoints, options):
    runs = run_paper_example(n_samples, random_state=seed, innovation_lengths=innovation_lengths,
                             baselines=False, **options)
    theta_true = runs.data.model.theta
    out = []
    for P, res in runs.hybrid.items():
        delta = res.relative_error(theta_true, history=True)
        for k in checkpoints:
            if k <= n_samples:
                out.append(dict(seed=seed, P=P, k=k, delta=float(delta[k - 1]),
                                alpha=float(res.alpha_sample_history[k - 1])))
    return out


def monte_carlo_table2(seeds=range(10), n_samples=10_000, *, innovation_lengths=(1, 3, 5),
                       checkpoints=(2000, 5000, 10000), jobs=1, **identify_options):
    """Table 2 over many seeds: one tidy row per (seed, P, k) with ``delta`` and ``alpha``.

    Parameters
    ----------
    seeds : iterable of int
        Seeds of :func:`fohw.datasets.paper_example`.
    n_samples : int
        Record length.
    innovation_lengths, checkpoints
        As in :func:`run_paper_example` and :func:`table2_rows`.
    jobs : int
        Worker processes (``concurrent.futures``); 1 runs serially. The numbers do not
        depend on it.
    **identify_options
        Passed to :func:`fohw.identify`.

    Returns
    -------
    list of dict
    """
    seeds = list(seeds)
    args = [(s, n_samples, tuple(innovation_lengths), tuple(checkpoints), identify_options)
            for s in seeds]
    if jobs == 1:
        parts = [_one_seed(*a) for a in args]
    else:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=jobs) as pool:
            parts = list(pool.map(_one_seed, *zip(*args)))
    return [row for part in parts for row in part]


def _forgetting_of(runs: PaperRuns) -> float:
    """The forgetting factor of the hybrid runs (1, the paper, unless one was given)."""
    values = {res.options.get("forgetting", 1.0) for res in runs.hybrid.values()}
    return float(values.pop()) if len(values) == 1 else 1.0


def _forgetting_title(ax, runs: PaperRuns):
    # Only when a forgetting factor was given: the as-printed figures stay as they were.
    lam = _forgetting_of(runs)
    if lam != 1.0:
        ax.set_title(ax.get_title() + f"\nforgetting factor lambda = {lam:g} (not in the paper)",
                     fontsize=10)


def _checkpoint_lines(ax, n):
    for k in (2000, 5000, 10000):
        if k <= n:
            ax.axvline(k, color="0.85", lw=0.8, zorder=0)


def plot_figure_3(runs: PaperRuns):
    """Fig. 3: relative error ``delta(k)`` for every ``P``. Returns ``(fig, ax)``."""
    fig, ax = subplots(figsize=(7, 4))
    theta = runs.data.model.theta
    for P, res in runs.hybrid.items():
        k = np.arange(1, res.n_samples + 1)
        ax.semilogy(k, res.relative_error(theta, history=True), label=f"fohw, P = {P}")
    printed = paper_table2()["relative_error_delta_as_printed"]
    for P in runs.hybrid:
        if f"P{P}_k10000" in printed and runs.data.n_samples >= 10000:
            ax.plot([10000], [printed[f"P{P}_k10000"]], "kx")
    ax.plot([], [], "kx", label="paper, printed delta at k = 10000")
    _checkpoint_lines(ax, runs.data.n_samples)
    ax.set_xlabel("sample k")
    ax.set_ylabel("delta = ||theta(k) - theta|| / ||theta||")
    ax.set_title("Fig. 3: parameter estimation error, hybrid MIGD + MI-LM (Table 1)")
    ax.legend()
    _forgetting_title(ax, runs)
    fig.tight_layout()
    return fig, ax


def plot_figure_4(runs: PaperRuns):
    """Fig. 4: the fractional-order estimate ``alpha(k)`` for every ``P``. Returns ``(fig, ax)``."""
    fig, ax = subplots(figsize=(7, 4))
    ref = paper_table2()
    for P, res in runs.hybrid.items():
        line, = ax.plot(np.arange(1, res.n_samples + 1), res.alpha_sample_history,
                        label=f"fohw, P = {P}")
        pts = [(r["k"], r["alpha"]) for r in ref["rows"] if r["P"] == P and r["k"] <= res.n_samples]
        if pts:
            ax.plot(*zip(*pts), "x", color=line.get_color(), ms=8)
    ax.plot([], [], "kx", label="paper, Table 2 (same colour as P)")
    ax.axhline(runs.data.model.alpha, color="k", ls="--", lw=1, label="true alpha = 0.6")
    ax.set_xlabel("sample k")
    ax.set_ylabel("alpha estimate")
    ax.set_title("Fig. 4: fractional-order estimate")
    ax.legend(loc="lower left", fontsize=8)
    _forgetting_title(ax, runs)
    fig.tight_layout()
    return fig, ax


def plot_figure_5(runs: PaperRuns, P=5, window=200):
    """Fig. 5: model output against measured output for ``P`` (last ``window`` samples).

    Shows the one-step-ahead prediction (Eq. 19) and, where the identified model is stable
    on this input, its free-run simulation. Returns ``(fig, axes)``.
    """
    from ..exceptions import SimulationDivergedError

    res = runs.hybrid[P]
    data = runs.data
    n = data.n_samples
    k = np.arange(n - window, n)
    pred = res.predict(data.u, data.y)
    fig, axes = subplots(2, 1, figsize=(8, 5.5), sharex=True)
    axes[0].plot(k, data.y[k], "k", lw=1.2, label="measured y")
    axes[0].plot(k, pred[k], "C1--", lw=1, label=f"one-step prediction, P = {P}")
    try:
        sim = res.simulate(data.u)
        axes[0].plot(k, sim[k], "C0:", lw=1, label="free-run simulation")
    except (SimulationDivergedError, ValueError):
        sim = None
    axes[0].set_ylabel("output")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"Fig. 5: identified model (P = {P}) against the measured output")
    axes[1].plot(k, data.y[k] - pred[k], "C1", lw=0.8, label="one-step error")
    if sim is not None:
        axes[1].plot(k, data.y[k] - sim[k], "C0", lw=0.8, label="simulation error")
    axes[1].set_xlabel("sample k")
    axes[1].set_ylabel("error")
    axes[1].legend(loc="upper right", fontsize=8)
    _forgetting_title(axes[0], runs)
    fig.tight_layout()
    return fig, axes


def plot_figure_6(runs: PaperRuns, P=5):
    """Fig. 6: ``delta(k)`` of the hybrid method (``P``) against the two baselines."""
    fig, ax = subplots(figsize=(7, 4))
    theta = runs.data.model.theta
    curves = [(f"hybrid MIGD + MI-LM, P = {P}", runs.hybrid[P])]
    curves += [(name.replace("_", " "), res) for name, res in runs.baselines.items()]
    for label, res in curves:
        ax.semilogy(np.arange(1, res.n_samples + 1), res.relative_error(theta, history=True),
                    label=label)
    ax.set_xlabel("sample k")
    ax.set_ylabel("delta")
    ax.set_title("Fig. 6: relative error, this method against the baselines")
    ax.legend()
    _forgetting_title(ax, runs)
    fig.tight_layout()
    return fig, ax


OUTPUTS = ("table_2", "figure_3", "figure_4", "figure_5", "figure_6")
_FIGURES = {"figure_3": plot_figure_3, "figure_4": plot_figure_4, "figure_5": plot_figure_5,
            "figure_6": plot_figure_6}


def _fmt_csv(rows, columns):
    lines = [",".join(columns)]
    for r in rows:
        lines.append(",".join(repr(r[c]) if isinstance(r[c], float) else str(r[c]) for c in columns))
    return "\n".join(lines) + "\n"


def write_outputs(runs: PaperRuns, outdir, which=OUTPUTS, checkpoints=(2000, 5000, 10000)):
    """Write the requested tables (Markdown and CSV) and figures (PNG) to ``outdir``.

    Returns
    -------
    dict of str to list of pathlib.Path
        The files written for each output.
    """
    from pathlib import Path

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written = {}
    for name in which:
        if name == "table_2":
            rows = table2_rows(runs, checkpoints)
            n = runs.data.n_samples
            head = (f"# Table 2: fohw beside the paper\n\nAcademic example (Section 6.1), N = {n}, "
                    "uniform input on [-sqrt 3, sqrt 3], noise variance 0.01, one seed; the "
                    "paper's hybrid MIGD + MI-LM with the recursive schedule of Table 1, one "
                    "pass, alpha0 = 0.5. `†`: a printed entry more than 5x away from the true "
                    "value (a likely misprint, kept as printed). The paper's delta is computed "
                    "from its printed entries.\n\n")
            lam = _forgetting_of(runs)
            if lam != 1.0:
                head += (f"**Forgetting factor lambda = {lam:g}**: r(k) = {lam:g} r(k-1) + "
                         "||Phi(P, k)||^2. The paper has no forgetting factor (lambda = 1, "
                         "Eq. 31); this is a reading under which its claims appear, not the "
                         "algorithm as printed.\n\n")
            (outdir / "table_2.md").write_text(head + table2_markdown(rows))
            (outdir / "table_2.csv").write_text(_fmt_csv(rows, ["P", "k", "parameter", "true",
                                                                "fohw", "paper", "paper_misprint"]))
            written[name] = [outdir / "table_2.md", outdir / "table_2.csv"]
        else:
            fig, _ = _FIGURES[name](runs)
            fig.savefig(outdir / f"{name}.png", dpi=120)
            written[name] = [outdir / f"{name}.png"]
    return written


def example_main(which, description, argv=None):
    """Command line of the example scripts: ``--outdir``, ``--fast``, ``--seed``, ``--forgetting``.

    ``--forgetting LAMBDA`` runs the hybrid method (and the single-innovation gradient
    baseline) with ``r(k) = LAMBDA r(k-1) + ||Phi(P, k)||^2``. The paper has no forgetting
    factor; the default, 1, is the algorithm as printed and is not passed on at all.
    """
    import argparse
    import time

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--outdir", default="results", help="folder for the files (created)")
    parser.add_argument("--fast", action="store_true",
                        help="N = 2000 instead of 10 000 (checkpoint k = 2000 only)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the simulated record")
    parser.add_argument("--forgetting", type=float, default=1.0, metavar="LAMBDA",
                        help="forgetting factor on r in (0, 1]; NOT in the paper (default 1: "
                        "the paper as printed). See examples/forgetting_map.py")
    args = parser.parse_args(argv)
    if not 0.0 < args.forgetting <= 1.0:
        parser.error(f"--forgetting must be in (0, 1]; got {args.forgetting:g}.")
    n = 2000 if args.fast else 10_000
    t0 = time.perf_counter()
    need_baselines = "figure_6" in which
    extra = {} if args.forgetting == 1.0 else {"forgetting": args.forgetting}
    runs = run_paper_example(n, random_state=args.seed, baselines=need_baselines, **extra)
    written = write_outputs(runs, args.outdir, which)
    if "table_2" in which:
        print(table2_markdown(table2_rows(runs)))
    for paths in written.values():
        for p in paths:
            print(f"wrote {p}")
    print(f"done in {time.perf_counter() - t0:.1f} s")
    return 0


# --------------------------------------------------------------------------------------------
# The forgetting map (issue 16): the paper's method under r(k) = lambda r(k-1) + ||Phi(P,k)||^2.
# The forgetting factor lambda is NOT in the paper (its Eq. 31 has lambda = 1).

#: The forgetting factors of the map; 1 is the paper as printed.
FORGETTING_FACTORS = (1.0, 0.999, 0.99, 0.97, 0.95, 0.9, 0.8, 0.6)

#: The schedules of the map: name -> (description, options of ``method="hybrid"``).
FORGETTING_SCHEDULES = {
    "recursive": ("recursive (Table 1), one pass", dict(schedule="recursive")),
    "iterative": ("iterative (Steps 1-9), alpha step on the last P samples",
                  dict(schedule="iterative")),
    "iterative-record": ("iterative, alpha step on the whole record, r restarted each pass",
                         dict(schedule="iterative", alpha_window="record", restart_r=True,
                              max_iter=200)),
}


def _forgetting_task(seed, n_samples, schedule, forgetting, innovation_lengths, checkpoints,
                     curve_step, max_iter):
    """One record, one schedule, one forgetting factor, every P: rows at the checkpoints.

    The recursive schedule makes one pass and is read at every checkpoint ``k`` (the estimate
    after sample ``k``, as in Table 2). The iterative schedules pass over the record many times,
    so ``k`` means the record length: they run on the first ``k`` samples of the same record.
    """
    import time

    from ..exceptions import FohwError

    data = paper_example(n_samples, random_state=seed)
    theta_true = data.model.theta
    norm = np.linalg.norm(theta_true)
    opts = dict(FORGETTING_SCHEDULES[schedule][1], forgetting=forgetting)
    if max_iter is not None and schedule != "recursive":
        opts["max_iter"] = max_iter
    rows, curves = [], {}
    base = dict(seed=seed, schedule=schedule, forgetting=forgetting)
    for P in innovation_lengths:
        if schedule == "recursive":
            t0 = time.perf_counter()
            try:
                res = _identify_quietly(data.u, data.y, method="hybrid", innovation_length=P,
                                        **opts)
            except FohwError as exc:     # an estimate that left the finite numbers
                for k in checkpoints:
                    rows.append(dict(base, P=P, k=k, delta=np.inf, alpha=np.nan, n_iter=0,
                                     converged=False, seconds=np.nan, error=str(exc)))
                continue
            seconds = time.perf_counter() - t0
            delta = res.relative_error(theta_true, history=True)
            for k in checkpoints:
                rows.append(dict(base, P=P, k=k, delta=float(delta[k - 1]),
                                 alpha=float(res.alpha_sample_history[k - 1]), n_iter=1,
                                 converged=False, seconds=seconds, error=""))
            curves[P] = (delta[curve_step - 1::curve_step].copy(),
                         res.alpha_sample_history[curve_step - 1::curve_step].copy())
        else:
            for k in checkpoints:
                t0 = time.perf_counter()
                try:
                    res = _identify_quietly(data.u[:k], data.y[:k], method="hybrid",
                                            innovation_length=P, **opts)
                except FohwError as exc:
                    rows.append(dict(base, P=P, k=k, delta=np.inf, alpha=np.nan, n_iter=0,
                                     converged=False, seconds=np.nan, error=str(exc)))
                    continue
                rows.append(dict(base, P=P, k=k,
                                 delta=float(np.linalg.norm(res.theta - theta_true) / norm),
                                 alpha=float(res.alpha), n_iter=int(res.nit),
                                 converged=bool(res.converged),
                                 seconds=time.perf_counter() - t0, error=""))
    return rows, {(schedule, forgetting, seed): curves} if curves else {}


def forgetting_map(seeds=range(10), n_samples=10_000, *, forgetting=FORGETTING_FACTORS,
                   innovation_lengths=(1, 3, 5), schedules=tuple(FORGETTING_SCHEDULES),
                   checkpoints=(2000, 5000, 10000), max_iter=None, jobs=1, curve_step=50,
                   progress=False):
    """The paper's hybrid method over forgetting factors, innovation lengths and schedules.

    Runs ``fohw.identify(..., method="hybrid", forgetting=lam, innovation_length=P, ...)`` on
    the academic example for every seed, ``lam``, ``P`` and schedule of
    :data:`FORGETTING_SCHEDULES`. The forgetting factor is **not in the paper**: Eq. (31) is
    ``r(k) = r(k-1) + ||Phi(P, k)||^2``; here ``r(k) = lam r(k-1) + ||Phi(P, k)||^2``, and
    ``lam = 1`` is the paper.

    Parameters
    ----------
    seeds : iterable of int
        Seeds of :func:`fohw.datasets.paper_example` (one record of ``n_samples`` each).
    n_samples : int
        Record length.
    forgetting : sequence of float
        Forgetting factors in ``(0, 1]``.
    innovation_lengths : sequence of int
        ``P`` values.
    schedules : sequence of str
        Keys of :data:`FORGETTING_SCHEDULES`.
    checkpoints : sequence of int
        Samples ``k`` at which ``delta`` and ``alpha`` are read. Under the recursive schedule the
        estimate after sample ``k`` of one pass; under the iterative ones the result of a run on
        the first ``k`` samples of the record.
    max_iter : int, optional
        Override the outer iterations of the iterative schedules (default: theirs, 50 and 200).
    jobs : int
        Worker processes (:class:`concurrent.futures.ProcessPoolExecutor`); 1 runs serially.
        The numbers do not depend on it.
    curve_step : int
        Keep ``delta(k)`` and ``alpha(k)`` of the recursive runs every ``curve_step`` samples.
    progress : bool
        Print progress to stderr.

    Returns
    -------
    rows : list of dict
        One row per (seed, schedule, forgetting, P, k): ``delta``, ``alpha``, ``n_iter``,
        ``converged``, ``seconds`` (of the run that produced the row), ``error``.
    curves : dict
        ``{(schedule, forgetting, seed): {P: (delta, alpha)}}`` for the recursive schedule,
        sampled at ``k = curve_step, 2 curve_step, ...``.
    """
    checkpoints = tuple(int(k) for k in checkpoints)
    if max(checkpoints) > n_samples:
        raise ParameterError(f"`checkpoints` must not exceed `n_samples` = {n_samples}; got "
                         f"{checkpoints}.")
    unknown = [s for s in schedules if s not in FORGETTING_SCHEDULES]
    if unknown:
        raise ParameterError(f"`schedules` must be among {tuple(FORGETTING_SCHEDULES)}; got "
                         f"{unknown}.")
    # The most expensive tasks first, so that the two workers finish together.
    order = {"iterative-record": 0, "recursive": 1, "iterative": 2}
    tasks = [(seed, n_samples, s, float(lam), tuple(innovation_lengths), checkpoints, curve_step,
              max_iter)
             for s in sorted(schedules, key=lambda s: order.get(s, 3))
             for lam in sorted(forgetting) for seed in seeds]
    pool = None
    if jobs != 1:
        from concurrent.futures import ProcessPoolExecutor

        pool = ProcessPoolExecutor(max_workers=jobs)
    try:
        parts = run_tasks(_forgetting_task, tasks, executor=pool, progress=progress,
                          label="forgetting map")
    finally:
        if pool is not None:
            pool.shutdown()
    rows, curves = [], {}
    for task, part in zip(tasks, parts):
        if isinstance(part, TaskError):
            raise FohwError(f"forgetting map: the task {task[:4]} could not be run: "
                            f"{part.message}") from part.exception
        rows.extend(part[0])
        curves.update(part[1])
    names = list(FORGETTING_SCHEDULES)
    rows.sort(key=lambda r: (names.index(r["schedule"]), -r["forgetting"], r["P"], r["k"],
                             r["seed"]))
    return rows, curves


def _quantiles(values):
    v = np.asarray(values, dtype=float)
    return (float(np.median(v)), float(np.percentile(v, 25)), float(np.percentile(v, 75)))


def forgetting_summary(rows):
    """Median and interquartile range of ``delta`` and ``alpha`` per (schedule, lam, P, k).

    Returns
    -------
    dict
        ``{(schedule, forgetting, P, k): {"delta": (median, q25, q75), "alpha": (...),
        "n": seeds, "failed": runs whose estimate left the finite numbers}}``.
    """
    groups = {}
    for r in rows:
        groups.setdefault((r["schedule"], r["forgetting"], r["P"], r["k"]), []).append(r)
    return {key: dict(delta=_quantiles([r["delta"] for r in g]),
                      alpha=_quantiles([r["alpha"] for r in g if np.isfinite(r["alpha"])] or [np.nan]),
                      n=len(g), failed=sum(bool(r["error"]) for r in g))
            for key, g in groups.items()}


def forgetting_p_comparison(rows, long=5, short=1):
    """Paired by seed: on how many seeds ``P = long`` has a smaller ``delta`` than ``P = short``.

    Returns
    -------
    dict
        ``{(schedule, forgetting, k): {"wins": int, "n": int, "median_difference": float}}``
        with the difference ``delta(P=short) - delta(P=long)`` (positive: the longer
        innovation is better).
    """
    by = {(r["schedule"], r["forgetting"], r["k"], r["P"], r["seed"]): r["delta"] for r in rows}
    out = {}
    for (s, lam, k, P, seed), d_long in by.items():
        if P != long or (s, lam, k, short, seed) not in by:
            continue
        entry = out.setdefault((s, lam, k), {"diffs": []})
        entry["diffs"].append(by[(s, lam, k, short, seed)] - d_long)
    for entry in out.values():
        diffs = np.array(entry.pop("diffs"))
        entry.update(wins=int(np.sum(diffs > 0)), n=len(diffs),
                     median_difference=float(np.median(diffs)))
    return out


def best_forgetting(summary, schedule, P=5):
    """The forgetting factor with the smallest median ``delta`` at the last checkpoint."""
    cands = [(v["delta"][0], lam) for (s, lam, p, k), v in summary.items()
             if s == schedule and p == P and k == max(kk for (_, _, _, kk) in summary)]
    return min(cands)[1]


def _lam(lam):
    return f"{lam:g}" + (" (paper)" if lam == 1.0 else "")


def forgetting_markdown(rows, summary, comparison, *, n_seeds, n_samples, seconds, jobs):
    """The map as Markdown: median [IQR] delta at the last checkpoint, delta(k), alpha, P."""
    schedules = [s for s in FORGETTING_SCHEDULES if any(k[0] == s for k in summary)]
    lams = sorted({k[1] for k in summary}, reverse=True)
    Ps = sorted({k[2] for k in summary})
    ks = sorted({k[3] for k in summary})
    kmax = ks[-1]
    out = [f"# The paper's hybrid method under a forgetting factor (N = {n_samples}, "
           f"{n_seeds} seeds)", "",
           "r(k) = lambda r(k-1) + ||Phi(P, k)||^2. **lambda is not in the paper** (its Eq. 31 "
           "has lambda = 1). Academic example (Section 6.1), uniform input, noise variance "
           f"0.01, seeds 0..{n_seeds - 1}, alpha0 = 0.5. delta = ||theta(k) - theta|| / "
           "||theta||. Recursive schedule: the estimate after sample k of one pass; iterative "
           "schedules: a run on the first k samples of the same record.", "",
           "Schedules:", ""]
    out += [f"- `{s}`: {FORGETTING_SCHEDULES[s][0]}" for s in schedules]
    out += ["", f"## Median delta at k = {kmax} [interquartile range]", "",
            "| lambda | " + " | ".join(f"{s} P={P}" for s in schedules for P in Ps) + " |",
            "|---|" + "---:|" * (len(schedules) * len(Ps))]
    for lam in lams:
        cells = []
        for s in schedules:
            for P in Ps:
                v = summary[(s, lam, P, kmax)]
                m, lo, hi = v["delta"]
                cells.append(f"{m:.3f} [{lo:.3f}, {hi:.3f}]"
                             + (f" ({v['failed']} failed)" if v["failed"] else ""))
        out.append(f"| {_lam(lam)} | " + " | ".join(cells) + " |")
    for s in schedules:
        out += ["", f"## `{s}`: median delta at k = {', '.join(map(str, ks))}; median alpha at "
                f"k = {kmax}", "", "| lambda | " + " | ".join(f"P = {P}" for P in Ps) + " |",
                "|---|" + "---|" * len(Ps)]
        for lam in lams:
            cells = []
            for P in Ps:
                ds = " / ".join(f"{summary[(s, lam, P, k)]['delta'][0]:.3f}" for k in ks)
                a = summary[(s, lam, P, kmax)]["alpha"]
                cells.append(f"{ds}; alpha {a[0]:.3f} [{a[1]:.3f}, {a[2]:.3f}]")
            out.append(f"| {_lam(lam)} | " + " | ".join(cells) + " |")
    long, short = max(Ps), min(Ps)
    out += ["", f"## Does P = {long} beat P = {short}? (paired by seed)", "",
            f"Seeds on which delta(P = {long}) < delta(P = {short}), at k = "
            f"{', '.join(map(str, ks))}; in brackets the median over seeds of delta(P = {short}) "
            f"- delta(P = {long}) at k = {kmax} (positive: P = {long} better).", "",
            "| lambda | " + " | ".join(schedules) + " |", "|---|" + "---|" * len(schedules)]
    for lam in lams:
        cells = []
        for s in schedules:
            c = [comparison[(s, lam, k)] for k in ks]
            cells.append(" / ".join(f"{e['wins']}" for e in c) + f" of {c[-1]['n']} "
                         f"({c[-1]['median_difference']:+.4f})")
        out.append(f"| {_lam(lam)} | " + " | ".join(cells) + " |")
    out += ["", "## Best forgetting factor per schedule (smallest median delta at "
            f"k = {kmax}, P = {long})", ""]
    for s in schedules:
        lam = best_forgetting(summary, s, long)
        v = summary[(s, lam, long, kmax)]
        out.append(f"- `{s}`: lambda = {lam:g}: median delta {v['delta'][0]:.4f}, median alpha "
                   f"{v['alpha'][0]:.4f}")
    n_runs = len({(r["seed"], r["schedule"], r["forgetting"], r["P"], r["k"] if r["schedule"]
                   != "recursive" else 0) for r in rows})
    failed = sum(bool(r["error"]) for r in rows)
    out += ["", f"{n_runs} runs of the hybrid method ({failed} left the finite numbers), "
            f"{seconds:.0f} s wall time with {jobs} worker process(es)."]
    return "\n".join(out) + "\n"


def plot_forgetting_map(summary):
    """Heat map of the median ``delta`` at the last checkpoint: lam x P, one panel per schedule."""
    from matplotlib.colors import LogNorm

    schedules = [s for s in FORGETTING_SCHEDULES if any(k[0] == s for k in summary)]
    lams = sorted({k[1] for k in summary}, reverse=True)
    Ps = sorted({k[2] for k in summary})
    kmax = max(k[3] for k in summary)
    grids = [np.array([[summary[(s, lam, P, kmax)]["delta"][0] for P in Ps] for lam in lams])
             for s in schedules]
    finite = np.concatenate([g[np.isfinite(g)] for g in grids])
    norm = LogNorm(vmin=min(finite.min(), 0.01), vmax=max(finite.max(), 1.0))
    fig, axes = subplots(1, len(schedules), figsize=(3.3 * len(schedules) + 2.2, 4.6),
                         squeeze=False)
    axes = axes[0]
    fig.subplots_adjust(left=0.13, right=0.86, wspace=0.08, top=0.86, bottom=0.1)
    for ax, s, grid in zip(axes, schedules, grids):
        im = ax.imshow(grid, norm=norm, cmap="viridis_r", aspect="auto")
        for i in range(len(lams)):
            for j in range(len(Ps)):
                v = grid[i, j]
                ax.text(j, i, f"{v:.3f}" if np.isfinite(v) else "diverged", ha="center",
                        va="center", fontsize=9,
                        color="white" if np.isfinite(v) and norm(v) > 0.55 else "black")
        ax.set_xticks(range(len(Ps)), [f"P = {P}" for P in Ps])
        ax.set_yticks(range(len(lams)),
                      [f"{lam:g}" for lam in lams] if ax is axes[0] else [""] * len(lams))
        ax.set_title(s, fontsize=10)
    axes[0].set_ylabel("forgetting factor lambda (1 = the paper)")
    fig.colorbar(im, cax=fig.add_axes([0.88, 0.1, 0.02, 0.76]),
                 label=f"median delta at k = {kmax}")
    fig.suptitle("Hybrid MIGD + MI-LM with r(k) = lambda r(k-1) + ||Phi||^2 (lambda: not in "
                 "the paper)", fontsize=10)
    return fig, axes


def plot_forgetting_best(summary, curves, *, curve_step=50):
    """``delta(k)`` and ``alpha(k)`` at each schedule's best lam, against the printed Table 2.

    Top row: median ``delta`` (band: interquartile range) for every ``P``, the paper's delta
    computed from its printed entries (crosses), and lam = 1 (dotted). Bottom row: ``alpha``.
    """
    ref = paper_table2()
    names = ref["theta_order"]
    theta_true = np.array([ref["true"][n] for n in names])
    printed = {(r["P"], r["k"]): r for r in ref["rows"]}
    schedules = [s for s in FORGETTING_SCHEDULES if any(k[0] == s for k in summary)]
    Ps = sorted({k[2] for k in summary})
    ks = sorted({k[3] for k in summary})
    fig, axes = subplots(2, len(schedules), figsize=(4.4 * len(schedules), 7), squeeze=False,
                         sharex=True)
    for j, s in enumerate(schedules):
        lam = best_forgetting(summary, s, max(Ps))
        ax_d, ax_a = axes[0, j], axes[1, j]
        for i, P in enumerate(Ps):
            color = f"C{i}"
            sel = [v[P] for (ss, ll, _), v in curves.items() if ss == s and ll == lam and P in v]
            if sel:          # the recursive schedule: the whole path
                d = np.array([c[0] for c in sel])
                a = np.array([c[1] for c in sel])
                kk = curve_step * np.arange(1, d.shape[1] + 1)
                ax_d.plot(kk, np.median(d, axis=0), color=color, label=f"P = {P}")
                ax_d.fill_between(kk, *np.percentile(d, [25, 75], axis=0), color=color,
                                  alpha=0.2, lw=0)
                ax_a.plot(kk, np.median(a, axis=0), color=color, label=f"P = {P}")
                ax_a.fill_between(kk, *np.percentile(a, [25, 75], axis=0), color=color,
                                  alpha=0.2, lw=0)
            else:
                for ax, key in ((ax_d, "delta"), (ax_a, "alpha")):
                    q = np.array([summary[(s, lam, P, k)][key] for k in ks])
                    ax.errorbar(ks, q[:, 0], yerr=[q[:, 0] - q[:, 1], q[:, 2] - q[:, 0]],
                                color=color, marker="o", ms=4, capsize=3, label=f"P = {P}")
            base = np.array([summary[(s, 1.0, P, k)]["delta"][0] for k in ks]) \
                if (s, 1.0, P, ks[0]) in summary else None
            if base is not None:
                ax_d.plot(ks, base, ":", color=color, marker=".")
            pk = [k for k in ks if (P, k) in printed]
            if pk:
                pd = [np.linalg.norm(np.array([printed[(P, k)][n] for n in names]) - theta_true)
                      / np.linalg.norm(theta_true) for k in pk]
                ax_d.plot(pk, pd, "x", color=color, ms=9, mew=2)
                ax_a.plot(pk, [printed[(P, k)]["alpha"] for k in pk], "x", color=color, ms=9,
                          mew=2)
        ax_d.plot([], [], "kx", label="paper, Table 2 as printed")
        ax_d.plot([], [], "k:", marker=".", label="lambda = 1 (the paper)")
        ax_d.set_yscale("log")
        ax_d.set_title(f"{s}, lambda = {lam:g}", fontsize=10)
        ax_a.axhline(0.6, color="k", ls="--", lw=1, label="true alpha = 0.6")
        ax_a.set_xlabel("sample k" if s == "recursive" else "record length k")
        for ax in (ax_d, ax_a):
            for k in ks:
                ax.axvline(k, color="0.85", lw=0.8, zorder=0)
        if j == 0:
            ax_d.set_ylabel("delta (median, IQR)")
            ax_a.set_ylabel("alpha estimate (median, IQR)")
            ax_d.legend(fontsize=7, loc="lower left")
            ax_a.legend(fontsize=7, loc="lower right")
    fig.suptitle("At each schedule's best forgetting factor (not in the paper) against Table 2 "
                 "as printed", fontsize=10)
    fig.tight_layout()
    return fig, axes


def forgetting_main(argv=None, description=None):
    """Command line of ``examples/forgetting_map.py`` and ``fohw reproduce forgetting``."""
    import argparse
    import time
    from pathlib import Path

    parser = argparse.ArgumentParser(description=description or "The paper's hybrid method "
                                     "under a forgetting factor (not in the paper).")
    parser.add_argument("--outdir", type=Path, default=Path("results"),
                        help="folder for the files (created)")
    parser.add_argument("--fast", action="store_true",
                        help="a smoke run: 2 seeds, N = 600, lambda in (1, 0.9), P in (1, 5), "
                        "at most 10 passes of the iterative schedules")
    parser.add_argument("--seeds", type=int, default=10, help="number of seeds (0, 1, ...)")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.jobs < 1:
        parser.error(f"--seeds and --jobs must be >= 1; got {args.seeds} and {args.jobs}.")
    if args.fast:
        n_seeds, n, lams, Ps, ks, step = 2, 600, (1.0, 0.9), (1, 5), (300, 600), 10
    else:
        n_seeds, n, lams, Ps, ks, step = (args.seeds, 10_000, FORGETTING_FACTORS, (1, 3, 5),
                                          (2000, 5000, 10000), 50)
    t0 = time.perf_counter()
    rows, curves = forgetting_map(range(n_seeds), n, forgetting=lams, innovation_lengths=Ps,
                                  checkpoints=ks, max_iter=10 if args.fast else None,
                                  jobs=1 if args.fast else args.jobs, curve_step=step,
                                  progress=not args.fast)
    seconds = time.perf_counter() - t0
    summary = forgetting_summary(rows)
    comparison = forgetting_p_comparison(rows, long=max(Ps), short=min(Ps))
    text = forgetting_markdown(rows, summary, comparison, n_seeds=n_seeds, n_samples=n,
                               seconds=seconds, jobs=1 if args.fast else args.jobs)
    outdir = args.outdir
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "forgetting_map.md").write_text(text)
    columns = ["seed", "schedule", "forgetting", "P", "k", "delta", "alpha", "n_iter",
               "converged", "seconds", "error"]
    (outdir / "forgetting_map.csv").write_text(_fmt_csv(
        [dict(r, error=r["error"].replace(",", ";").replace("\n", " ")) for r in rows], columns))
    fig, _ = plot_forgetting_map(summary)
    fig.savefig(outdir / "forgetting_map.png", dpi=120)
    fig, _ = plot_forgetting_best(summary, curves, curve_step=step)
    fig.savefig(outdir / "forgetting_best.png", dpi=120)
    print(text)
    for name in ("forgetting_map.md", "forgetting_map.csv", "forgetting_map.png",
                 "forgetting_best.png"):
        print(f"wrote {outdir / name}")
    print(f"done in {seconds:.1f} s")
    return 0
