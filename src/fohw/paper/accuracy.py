"""Accuracy of every method against the Cramér-Rao bound, on the paper's example and two others.

    fohw reproduce accuracy --outdir results [--fast] [--seeds 20] [--jobs 2]

Part 1: RMS of delta = ||theta_hat - theta|| / ||theta|| and of the alpha error over seeds at
N = 10 000 for the paper's hybrid (P = 1, 3, 5), varpro and MI-RLS (P = 1, 5), beside the CRB.
Part 2: varpro on two further systems (another alpha, other lags and bases) against their CRB.
Part 3: how varpro's error falls with N (10^3 ... 10^5) against the CRB line.
Writes accuracy.md, accuracy.csv, accuracy_methods.png and accuracy_vs_n.png.
"""

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

import fohw
from fohw._parallel import max_jobs
from fohw._plotting import subplots
from fohw.analysis.montecarlo import summarise
from fohw.io.files import save_figure


def cube(x):
    return x**3


def identity(x):
    return x


def system_b():
    """Alpha = 0.3, na = 1, nb = 3, f = [u, u^3], g = [y, y^2]."""
    return fohw.HammersteinWiener([0.4], [0.5, -0.3, 0.2], [1, -0.2], [1, 0.3], 0.3,
                                  f_basis={"u": identity, "u^3": cube}, g_basis=2)


def system_c():
    """Alpha = 1.4, na = 2, nb = 1, f = [u, tanh u], g = [y]."""
    return fohw.HammersteinWiener([0.2, -0.1], [0.8], [1, 0.5], [1], 1.4,
                                  f_basis={"u": identity, "tanh": np.tanh}, g_basis=1)


SYSTEMS = {"B": (system_b, (0.0, 1.0)), "C": (system_c, (0.0, 2.0))}


def make_system_data(seed, system="B", n_samples=10_000):
    model = SYSTEMS[system][0]()
    rng = np.random.default_rng(seed)
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), n_samples)
    v = 0.1 * rng.standard_normal(n_samples)
    y = fohw.simulate(model, u, noise=v)
    return fohw.datasets.SimulatedData(u=u, y=y, noise=v, model=model, input_kind="uniform",
                                       noise_variance=0.01)


def crb_for(make, n, **kw):
    data = make(10**6 + n, n_samples=n, **kw)   # an input independent of the Monte Carlo seeds
    return fohw.crb(data.model, data.u, 0.01, n_realizations=8, random_state=0)


def write_csv(path, rows, keys):
    """The ``keys`` of each row (a dict; missing ones empty) as CSV, quoted where needed."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


def paper_data(seed, n_samples=10_000):
    return fohw.datasets.paper_example(n_samples, random_state=seed)


METHODS = {
    "hybrid P=1 (paper)": dict(method="hybrid", innovation_length=1),
    "hybrid P=3 (paper)": dict(method="hybrid", innovation_length=3),
    "hybrid P=5 (paper)": dict(method="hybrid", innovation_length=5),
    "MI-RLS P=1": dict(method="rls", innovation_length=1),
    "MI-RLS P=5": dict(method="rls", innovation_length=5),
    "varpro": dict(method="varpro"),
}


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outdir", type=Path, default=Path("results"))
    ap.add_argument("--fast", action="store_true", help="3 seeds, N = 2000, N-sweep to 4000")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=min(2, max_jobs()),
                    help="worker processes, at most the processors (default 2)")
    return ap.parse_args(argv)


def methods_table(rows, n_main, n_seeds, mc):
    """Part 1: every method on the paper's example against the CRB (markdown lines, summaries)."""
    bound = crb_for(paper_data, n_main)
    d_sum = summarise(rows, value="delta")
    a_sum = summarise(rows, value="alpha_error")
    lines = ["# Accuracy against the Cramér-Rao bound", "",
             f"## The paper's example, N = {n_main}, {n_seeds} seeds", "",
             "| method | RMS delta | RMS delta / CRB | RMS alpha error | / CRB | median seconds |",
             "|---|---:|---:|---:|---:|---:|"]
    for name in METHODS:
        rd, ra = d_sum[(name,)]["rms"], a_sum[(name,)]["rms"]
        secs = np.median([r["seconds"] for r in rows if r["method"] == name])
        lines.append(f"| {name} | {rd:.4f} | {rd / bound.rms_relative_error:.2f} | {ra:.4f} | "
                     f"{ra / bound.alpha_std:.2f} | {secs:.2f} |")
    lines.append(f"| **CRB** | {bound.rms_relative_error:.4f} | 1 | {bound.alpha_std:.4f} | 1 | |")
    return lines, bound, d_sum, a_sum


def systems_table(seeds, n_main, n_seeds, mc):
    """Part 2: varpro on systems B and C against their CRBs (markdown lines, the rows)."""
    lines = ["", f"## Two further systems, varpro, N = {n_main}, {n_seeds} seeds", "",
             "| system | RMS delta | CRB | ratio | RMS alpha error | CRB | ratio |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    rows = []
    for name, (factory, bounds) in SYSTEMS.items():
        srows = fohw.monte_carlo({"varpro": dict(method="varpro", alpha_bounds=bounds)},
                                 seeds=seeds, settings=[{"system": name, "n_samples": n_main}],
                                 make_data=make_system_data, **mc)
        rows += srows
        b = crb_for(make_system_data, n_main, system=name)
        rd = summarise(srows)[("varpro",)]["rms"]
        ra = summarise(srows, value="alpha_error")[("varpro",)]["rms"]
        lines.append(f"| {name}: {factory.__doc__} | {rd:.4f} | {b.rms_relative_error:.4f} | "
                     f"{rd / b.rms_relative_error:.2f} | {ra:.5f} | {b.alpha_std:.5f} | "
                     f"{ra / b.alpha_std:.2f} |")
    return lines, rows


def sweep_table(seeds, sweep, n_seeds, mc):
    """Part 3: varpro against the record length (markdown lines, rows, summaries, bounds)."""
    sweep_rows = fohw.monte_carlo({"varpro": dict(method="varpro")}, seeds=seeds,
                                  settings=[{"n_samples": n} for n in sweep],
                                  make_data=paper_data, **mc)
    s_sum = summarise(sweep_rows, by=("n_samples",))
    sa_sum = summarise(sweep_rows, by=("n_samples",), value="alpha_error")
    bounds_n = {n: crb_for(paper_data, n) for n in sweep}
    lines = ["", f"## varpro against N (paper's example, {n_seeds} seeds)", "",
             "| N | RMS delta | CRB | ratio | RMS alpha error | CRB | ratio |",
             "|---:|---:|---:|---:|---:|---:|---:|"]
    for n in sweep:
        rd, ra, b = s_sum[(n,)]["rms"], sa_sum[(n,)]["rms"], bounds_n[n]
        lines.append(f"| {n} | {rd:.4f} | {b.rms_relative_error:.4f} | "
                     f"{rd / b.rms_relative_error:.2f} | {ra:.5f} | {b.alpha_std:.5f} | "
                     f"{ra / b.alpha_std:.2f} |")
    return lines, sweep_rows, s_sum, sa_sum, bounds_n


def plot_methods(path, bound, d_sum, a_sum, n_main, n_seeds):
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    fig, axes = subplots(1, 2, figsize=(11, 4), sharey=True)
    names = list(METHODS)
    y = np.arange(len(names))
    for ax, values, crb, color, label in (
            (axes[0], [d_sum[(m,)]["rms"] for m in names], bound.rms_relative_error, "C0",
             "RMS delta"),
            (axes[1], [a_sum[(m,)]["rms"] for m in names], bound.alpha_std, "C1",
             "RMS alpha error")):
        # Dots, not bars: a bar on a log axis has no zero to start from.
        ax.hlines(y, crb, values, color=color, lw=1, alpha=0.5)
        ax.plot(values, y, "o", color=color, ms=7)
        ax.axvline(crb, color="k", ls="--", label="CRB")
        ax.set_xscale("log")
        # Labels at 1, 2 and 5 per decade only: the default minor labels overlap on a short axis.
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(FormatStrFormatter(""))
        ax.set_xlabel(label)
        ax.grid(True, axis="x", which="major", alpha=0.3)
        ax.legend(loc="center right")
    axes[0].set_yticks(y, names)
    fig.suptitle(f"Paper's example, N = {n_main}, {n_seeds} seeds")
    save_figure(fig, path, dpi=120)


def plot_sweep(path, sweep, s_sum, sa_sum, bounds_n):
    fig, ax = subplots(figsize=(6, 4))
    ax.loglog(sweep, [s_sum[(n,)]["rms"] for n in sweep], "o-", label="varpro, RMS delta")
    ax.loglog(sweep, [bounds_n[n].rms_relative_error for n in sweep], "k--", label="CRB")
    ax.loglog(sweep, [sa_sum[(n,)]["rms"] for n in sweep], "s-", label="varpro, RMS alpha error")
    ax.loglog(sweep, [bounds_n[n].alpha_std for n in sweep], "k:", label="CRB (alpha)")
    ax.set_xlabel("N")
    ax.set_ylabel("error")
    ax.legend()
    ax.set_title("Error against record length")
    save_figure(fig, path, dpi=120)


def main(argv=None):
    args = parse_args(argv)
    t0 = time.perf_counter()
    n_seeds = 3 if args.fast else args.seeds
    n_main = 2000 if args.fast else 10_000
    sweep = [500, 1000, 2000, 4000] if args.fast else [1000, 3000, 10_000, 30_000, 100_000]
    seeds = range(n_seeds)
    mc = dict(n_jobs=args.jobs)
    args.outdir.mkdir(parents=True, exist_ok=True)
    rows = fohw.monte_carlo(METHODS, seeds=seeds, settings=[{"n_samples": n_main}],
                            make_data=paper_data, **mc)
    lines, bound, d_sum, a_sum = methods_table(rows, n_main, n_seeds, mc)
    more, system_rows = systems_table(seeds, n_main, n_seeds, mc)
    lines += more
    more, sweep_rows, s_sum, sa_sum, bounds_n = sweep_table(seeds, sweep, n_seeds, mc)
    lines += more
    all_rows = ([dict(r, system="paper") for r in rows] + system_rows
                + [dict(r, system="paper, N sweep") for r in sweep_rows])
    failures = [r for r in all_rows if r.get("error")]
    lines += ["", f"Records that diverged: {len(failures)}. Total time {time.perf_counter() - t0:.0f} s "
              f"with --jobs {args.jobs}."]
    text = "\n".join(lines) + "\n"
    (args.outdir / "accuracy.md").write_text(text)
    keys = ["system", "n_samples", "seed", "method", "delta", "alpha", "alpha_error", "J",
            "converged", "seconds"]
    write_csv(args.outdir / "accuracy.csv", all_rows, keys)
    plot_methods(args.outdir / "accuracy_methods.png", bound, d_sum, a_sum, n_main, n_seeds)
    plot_sweep(args.outdir / "accuracy_vs_n.png", sweep, s_sum, sa_sum, bounds_n)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
