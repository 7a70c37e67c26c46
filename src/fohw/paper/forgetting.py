"""The paper's method under a forgetting factor: the map over lambda, P and schedule (not in the paper).

The forgetting map of ``examples/forgetting_map.py`` and ``fohw reproduce forgetting``
(:func:`main`): the hybrid method with ``r(k) = lambda r(k-1) + ||Phi(P, k)||^2``, a forgetting
factor that is NOT in the paper (its Eq. 31 has lambda = 1), over lambda, ``P`` and schedule.
The as-printed reading (lambda = 1) stays the default everywhere.
"""

from __future__ import annotations

import numpy as np

from .._parallel import TaskError, max_jobs, run_tasks
from .._plotting import subplots
from ..datasets import paper_example
from ..exceptions import FohwError, ParameterError
from ..io.files import save_figure
from .common import csv_text, paper_table2
from .table2 import identify_paper_structure

__all__ = ["FORGETTING_FACTORS", "FORGETTING_SCHEDULES", "forgetting_map", "forgetting_summary",
           "forgetting_p_comparison", "best_forgetting", "forgetting_markdown",
           "plot_forgetting_map", "plot_forgetting_best", "main"]


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
                res = identify_paper_structure(data.u, data.y, method="hybrid", innovation_length=P,
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
                    res = identify_paper_structure(data.u[:k], data.y[:k], method="hybrid",
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
        from .._parallel import check_jobs, process_pool

        pool = process_pool(min(check_jobs(jobs, "jobs"), len(tasks)))
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
    out = [f"# The paper's hybrid method under a forgetting factor (N = {n_samples}, "
           f"{n_seeds} seeds)", "",
           "r(k) = lambda r(k-1) + ||Phi(P, k)||^2. **lambda is not in the paper** (its Eq. 31 "
           "has lambda = 1). Academic example (Section 6.1), uniform input, noise variance "
           f"0.01, seeds 0..{n_seeds - 1}, alpha0 = 0.5. delta = ||theta(k) - theta|| / "
           "||theta||. Recursive schedule: the estimate after sample k of one pass; iterative "
           "schedules: a run on the first k samples of the same record.", "",
           "Schedules:", ""]
    out += [f"- `{s}`: {FORGETTING_SCHEDULES[s][0]}" for s in schedules]
    out += _delta_table(summary, schedules, lams, Ps, ks[-1])
    out += _schedule_tables(summary, schedules, lams, Ps, ks)
    out += _p_comparison_table(comparison, schedules, lams, Ps, ks)
    long, kmax = max(Ps), ks[-1]
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


def _delta_table(summary, schedules, lams, Ps, kmax):
    """Median [IQR] delta at the last checkpoint: lambda x (schedule, P)."""
    out = ["", f"## Median delta at k = {kmax} [interquartile range]", "",
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
    return out


def _schedule_tables(summary, schedules, lams, Ps, ks):
    """Per schedule: median delta at every checkpoint and median [IQR] alpha at the last."""
    kmax = ks[-1]
    out = []
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
    return out


def _p_comparison_table(comparison, schedules, lams, Ps, ks):
    """Seeds on which the longest P beats the shortest, per lambda and schedule."""
    long, short, kmax = max(Ps), min(Ps), ks[-1]
    out = ["", f"## Does P = {long} beat P = {short}? (paired by seed)", "",
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
    return out


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
                         squeeze=False, layout=None)       # placed by hand, colour bar included
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
    return fig


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
    return fig


def main(argv=None, description=None):
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
    parser.add_argument("--jobs", type=int, default=min(2, max_jobs()),
                        help="worker processes, at most the processors (default 2)")
    args = parser.parse_args(argv)
    if args.seeds < 1 or not 1 <= args.jobs <= max_jobs():
        parser.error(f"--seeds must be >= 1 and --jobs from 1 to {max_jobs()} (the processors); "
                     f"got {args.seeds} and {args.jobs}.")
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
    (outdir / "forgetting_map.csv").write_text(csv_text(
        [dict(r, error=r["error"].replace(",", ";").replace("\n", " ")) for r in rows], columns))
    fig = plot_forgetting_map(summary)
    save_figure(fig, outdir / "forgetting_map.png", dpi=120)
    fig = plot_forgetting_best(summary, curves, curve_step=step)
    save_figure(fig, outdir / "forgetting_best.png", dpi=120)
    print(text)
    for name in ("forgetting_map.md", "forgetting_map.csv", "forgetting_map.png",
                 "forgetting_best.png"):
        print(f"wrote {outdir / name}")
    print(f"done in {seconds:.1f} s")
    return 0
