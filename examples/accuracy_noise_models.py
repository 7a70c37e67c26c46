"""Accuracy against the matching Cramér-Rao bound, per noise model (docs/accuracy.md).

    python examples/accuracy_noise_models.py --outdir results [--fast] [--seeds 100] [--jobs 2]

Part 1: the structured estimator (method="structured") and varpro on
the paper's example, N = 10 000, --seeds seeds: RMS of delta = ||theta_hat - theta|| / ||theta||
and of the alpha error against the unstructured and the structured bound.
Part 2, equation noise: varpro and structured on the paper's example and systems B and C of
docs/accuracy.md, N = 10^3, 10^4, 10^5, against both bounds.
Part 3, output noise (the system runs noise-free, noise of variance 0.01 is added to the
measured output): varpro, structured and output_error on the paper's example and system C,
against the output-noise bounds, with the mean alpha error (bias) of each method.
Every record: uniform input of unit variance, noise variance 0.01. Writes
accuracy_noise_models.md and accuracy_noise_models.csv.
"""

import argparse
import concurrent.futures
import os
import sys
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fohw  # noqa: E402
from fohw.analysis.batch import end_with_parent  # noqa: E402
from fohw.paper.accuracy import system_b, system_c, write_csv  # noqa: E402


def paper():
    """The paper's example: alpha = 0.6, na = nb = 2, f = [u, u^2], g = [y, y^2, y^3]."""
    return fohw.datasets.paper_model()


SYSTEMS = {"paper": (paper, (0.0, 1.0)), "B": (system_b, (0.0, 1.0)),
           "C": (system_c, (0.0, 2.0))}
NOISE_VARIANCE = 0.01


def record(system, noise, n, seed):
    """One record: equation noise (in the recursion) or output noise (added to the output)."""
    model = SYSTEMS[system][0]()
    rng = np.random.default_rng([seed, n, list(SYSTEMS).index(system), noise == "output"])
    u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
    e = np.sqrt(NOISE_VARIANCE) * rng.standard_normal(n)
    y = fohw.simulate(model, u, noise=e) if noise == "equation" else fohw.simulate(model, u) + e
    return model, u, y


def fit(task):
    """Run the methods on one record; rows of (method, delta, alpha error, seconds)."""
    system, noise, n, seed, methods = task
    model, u, y = record(system, noise, n, seed)
    bounds = SYSTEMS[system][1]
    rows = []
    for method in methods:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", fohw.ConvergenceWarning)
            try:
                r = fohw.identify(u, y, na=model.na, nb=model.nb, f_basis=model.f_basis,
                                  g_basis=model.g_basis, method=method, alpha_bounds=bounds)
            except fohw.FohwError as exc:
                rows.append(dict(system=system, noise=noise, n=n, seed=seed, method=method,
                                 error=str(exc)))
                continue
        rows.append(dict(system=system, noise=noise, n=n, seed=seed, method=method,
                         delta=float(r.relative_error(model.theta)),
                         alpha_error=float(r.alpha - model.alpha), converged=r.converged,
                         seconds=time.perf_counter() - t0))
    return rows


def bounds_for(system, noise, n):
    """Both bounds (theta, structured) on an input independent of the Monte Carlo seeds."""
    model, u, _ = record(system, "equation", n, 10**6)
    kw = dict(n_realizations=8, random_state=0) if noise == "equation" else {}
    return {p: fohw.crb(model, u, NOISE_VARIANCE, parametrisation=p, noise=noise, **kw)
            for p in ("theta", "structured")}


def run(tasks, jobs):
    rows = []
    if jobs == 1:
        for t in tasks:
            rows += fit(t)
        return rows
    with concurrent.futures.ProcessPoolExecutor(max_workers=jobs,
                                                initializer=end_with_parent) as pool:
        for out in pool.map(fit, tasks):
            rows += out
    return rows


def stats(rows, **key):
    sel = [r for r in rows if all(r[k] == v for k, v in key.items()) and "error" not in r]
    if not sel:
        return None
    d = np.array([r["delta"] for r in sel])
    a = np.array([r["alpha_error"] for r in sel])
    return dict(rms_delta=float(np.sqrt(np.mean(d**2))), rms_alpha=float(np.sqrt(np.mean(a**2))),
                mean_alpha=float(np.mean(a)), sd_alpha=float(np.std(a, ddof=1)) if a.size > 1
                else float("nan"), n=len(sel), seconds=float(np.median([r["seconds"]
                                                                        for r in sel])))


def ratio_sd(bound, n_seeds, alpha=False):
    """Sampling sd of RMS/bound for an efficient estimator: 0.5 sqrt(2 / (n nu)),
    nu = (tr C)^2 / tr(C^2) of theta's bound (nu = 1 for alpha)."""
    if alpha:
        nu = 1.0
    else:
        c = bound.theta_covariance
        nu = np.trace(c) ** 2 / np.trace(c @ c)
    return 0.5 * np.sqrt(2.0 / (n_seeds * nu))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outdir", type=Path, default=Path("results"))
    ap.add_argument("--fast", action="store_true", help="a few seeds, short records")
    ap.add_argument("--seeds", type=int, default=100, help="seeds of part 1")
    ap.add_argument("--sweep-seeds", type=int, nargs=3, default=(40, 20, 5),
                    help="seeds of parts 2-3 at N = 1e3, 1e4, 1e5")
    ap.add_argument("--output-sizes", type=int, nargs="+", default=(1000, 3000, 10000))
    ap.add_argument("--output-seeds", type=int, nargs="+", default=(40, 20, 8))
    ap.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                    help="worker processes, at most the processors (default 2)")
    ap.add_argument("--parts", default="123")
    args = ap.parse_args(argv)
    if not 1 <= args.jobs <= (os.cpu_count() or 1):
        ap.error(f"--jobs must be from 1 to {os.cpu_count() or 1} (the processors); got {args.jobs}.")
    t_start = time.perf_counter()
    if args.fast:
        n_main, seeds_main = 1000, 3
        sweep = {500: 2, 1000: 2}
        out_sweep = {500: 2}
    else:
        n_main, seeds_main = 10_000, args.seeds
        sweep = dict(zip((1000, 10_000, 100_000), args.sweep_seeds))
        out_sweep = dict(zip(args.output_sizes, args.output_seeds))
    args.outdir.mkdir(parents=True, exist_ok=True)
    lines = ["# Accuracy against the matching Cramér-Rao bound", ""]
    all_rows = []
    eq_methods = ("varpro", "structured")

    if "1" in args.parts:
        rows = run([("paper", "equation", n_main, s, eq_methods) for s in range(seeds_main)],
                   args.jobs)
        all_rows += rows
        b = bounds_for("paper", "equation", n_main)
        bt, bs = b["theta"], b["structured"]
        lines += [f"## The paper's example, equation noise, N = {n_main}, {seeds_main} seeds", "",
                  f"Bounds: unstructured (theta, alpha) RMS delta {bt.rms_relative_error:.4f}, "
                  f"alpha sd {bt.alpha_std:.5f}; structured (a, b, p, q, alpha) RMS delta "
                  f"{bs.rms_relative_error:.4f}, alpha sd {bs.alpha_std:.5f}.", "",
                  "| method | RMS delta | / theta CRB | / structured CRB | RMS alpha error | "
                  "/ theta CRB | / structured CRB | mean alpha error | median s |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for m in eq_methods:
            st = stats(rows, method=m)
            lines.append(
                f"| {m} | {st['rms_delta']:.4f} | {st['rms_delta'] / bt.rms_relative_error:.3f} "
                f"| {st['rms_delta'] / bs.rms_relative_error:.3f} | {st['rms_alpha']:.5f} | "
                f"{st['rms_alpha'] / bt.alpha_std:.3f} | {st['rms_alpha'] / bs.alpha_std:.3f} | "
                f"{st['mean_alpha']:+.5f} | {st['seconds']:.2f} |")
        lines += ["", f"Sampling sd of a ratio for an efficient estimator over {seeds_main} seeds: "
                  f"delta {ratio_sd(bs, seeds_main):.3f}, alpha "
                  f"{ratio_sd(bs, seeds_main, alpha=True):.3f} (0.5 sqrt(2 / (n nu)))."]

    if "2" in args.parts:
        lines += ["", "## Equation noise: RMS error against N", "",
                  "| system | N | seeds | method | RMS delta | theta CRB | ratio | structured CRB "
                  "| ratio | RMS alpha error | theta CRB | structured CRB | ratio |",
                  "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        tasks = [(s, "equation", n, seed, eq_methods) for s in SYSTEMS for n, k in sweep.items()
                 for seed in range(k)]
        rows = run(tasks, args.jobs)
        all_rows += rows
        for s in SYSTEMS:
            for n in sweep:
                b = bounds_for(s, "equation", n)
                bt, bs = b["theta"], b["structured"]
                for m in eq_methods:
                    st = stats(rows, system=s, n=n, method=m)
                    lines.append(
                        f"| {s} | {n} | {st['n']} | {m} | {st['rms_delta']:.4f} | "
                        f"{bt.rms_relative_error:.4f} | {st['rms_delta'] / bt.rms_relative_error:.2f} "
                        f"| {bs.rms_relative_error:.4f} | "
                        f"{st['rms_delta'] / bs.rms_relative_error:.2f} | {st['rms_alpha']:.5f} | "
                        f"{bt.alpha_std:.5f} | {bs.alpha_std:.5f} | "
                        f"{st['rms_alpha'] / bs.alpha_std:.2f} |")

    if "3" in args.parts:
        oe_methods = ("varpro", "structured", "output_error")
        lines += ["", "## Output noise: RMS error against N", "",
                  "Ratios of output_error are to the unstructured (theta) output-noise bound, "
                  "which is what a simulation-error fit of theta can reach; the equation-error "
                  "methods are biased under output noise (mean alpha error against its standard "
                  "error over seeds, in the column t).", "",
                  "| system | N | seeds | method | RMS delta | theta CRB | ratio | RMS alpha error "
                  "| theta CRB | ratio | mean alpha error | t |",
                  "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        out_systems = ("paper", "C")
        tasks = [(s, "output", n, seed, oe_methods) for s in out_systems
                 for n, k in out_sweep.items() for seed in range(k)]
        rows = run(tasks, args.jobs)
        all_rows += rows
        for s in out_systems:
            for n in out_sweep:
                bt = bounds_for(s, "output", n)["theta"]
                for m in oe_methods:
                    st = stats(rows, system=s, n=n, method=m)
                    if st is None:
                        continue
                    t = st["mean_alpha"] / (st["sd_alpha"] / np.sqrt(st["n"]))
                    lines.append(
                        f"| {s} | {n} | {st['n']} | {m} | {st['rms_delta']:.4f} | "
                        f"{bt.rms_relative_error:.4f} | {st['rms_delta'] / bt.rms_relative_error:.2f} "
                        f"| {st['rms_alpha']:.5f} | {bt.alpha_std:.5f} | "
                        f"{st['rms_alpha'] / bt.alpha_std:.2f} | {st['mean_alpha']:+.5f} | "
                        f"{t:+.1f} |")

    failures = [r for r in all_rows if "error" in r]
    lines += ["", f"Records that failed: {len(failures)}"
              + "".join(f"\n- {r['system']} N={r['n']} seed {r['seed']} {r['method']}: "
                        f"{r['error']}" for r in failures),
              f"Total time {time.perf_counter() - t_start:.0f} s with --jobs {args.jobs}."]
    text = "\n".join(lines) + "\n"
    (args.outdir / "accuracy_noise_models.md").write_text(text)
    keys = ["system", "noise", "n", "seed", "method", "delta", "alpha_error", "converged",
            "seconds", "error"]
    write_csv(args.outdir / "accuracy_noise_models.csv", all_rows, keys)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
