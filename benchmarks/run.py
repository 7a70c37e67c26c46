"""fohw benchmark suite: every stage against a plain reference, N = 10^3 ... 10^6.

    python benchmarks/run.py [--quick] [--outdir benchmarks/results]

Each time is the median of several repeats measured in this one run (one repeat for the
slowest cases); the machine is shared, so read the ratios. The plain references are written
here, for the benchmark:

* GL difference: ``numpy.convolve`` (O(N^2), up to 10^5) and a bare ``scipy.fft`` rfft/irfft
  round trip of the same padded size (a lower bound for any FFT method), for a new order at
  every call (three transforms) and for a repeated order (the weights' spectrum is cached);
* simulator: the per-step full-memory dot product (the textbook recursion);
* information matrix for 20 values of alpha: rebuilt from scratch each time
  (``fohw.information_matrix``) against one ``RegressorBuilder`` reusing the basis FFTs;
* end-to-end ``fohw.identify`` per method.

Peak memory is the tracemalloc peak of the stage (NumPy reports its allocations to it).
Writes benchmarks.md and scaling.png to --outdir and prints the table.
"""

import argparse
import os
import platform
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.fft  # noqa: E402

import fohw  # noqa: E402

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def measure(fn, repeats):
    """Median seconds over repeats, and the tracemalloc peak (MB) of one extra run."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return float(np.median(times)), peak


def reference_simulate(model, u, v):
    """The textbook recursion: one full-memory dot product per step, gbar evaluated per step."""
    n = len(u)
    beta = fohw.gl_weights(model.alpha, n)
    fbar = model.f_basis.combine(model.p, u)
    dfbar = np.array([beta[: k + 1] @ fbar[k::-1] for k in range(n)])
    y = np.zeros(n)
    gbar = np.zeros(n)
    dg = np.zeros(n)
    for k in range(n):
        acc = v[k]
        for i in range(1, model.na + 1):
            if k - i >= 0:
                acc += model.a[i - 1] * dg[k - i]
        for i in range(1, model.nb + 1):
            if k - i >= 0:
                acc += model.b[i - 1] * dfbar[k - i]
        y[k] = acc
        gbar[k] = model.q @ np.array([acc, acc**2, acc**3])
        dg[k] = beta[: k + 1] @ gbar[k::-1]
    return y


def machine():
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return (f"{cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.machine()}, "
            f"Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}")


def bare_round_trip(x):
    nfft = scipy.fft.next_fast_len(2 * len(x) - 1, real=True)
    return scipy.fft.irfft(scipy.fft.rfft(x, n=nfft), n=nfft)[: len(x)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N up to 10^5, fewer repeats")
    ap.add_argument("--outdir", type=Path, default=Path("benchmarks/results"))
    args = ap.parse_args(argv)
    sizes = [10**3, 10**4, 10**5] if args.quick else [10**3, 10**4, 10**5, 10**6]
    args.outdir.mkdir(parents=True, exist_ok=True)
    rows = []

    def add(stage, n, fohw_t, ref_name, ref_t, peak):
        rows.append(dict(stage=stage, n=n, fohw=fohw_t, ref_name=ref_name, ref=ref_t, peak=peak))
        ratio = f"{ref_t / fohw_t:.1f}" if ref_t else "–"
        print(f"{stage:<34} N={n:>8}  fohw {fohw_t:9.4f} s  {ref_name:<26} "
              f"{(f'{ref_t:9.4f} s' if ref_t else '       –   ')}  ratio {ratio:>6}  peak {peak:7.1f} MB",
              flush=True)

    rng = np.random.default_rng(0)
    for n in sizes:
        rep = 3 if (args.quick or n >= 10**5) else 7
        x = rng.standard_normal(n)
        # warm: the same order every call (the weight spectrum is cached after the first);
        # cold: a new order every call (weights and their spectrum computed each time).
        t, peak = measure(lambda: fohw.gl_difference(x, 0.6), rep)
        fresh = iter(np.linspace(0.1, 0.9, 10 * rep + 10))
        t_cold, _ = measure(lambda: fohw.gl_difference(x, next(fresh)), rep)
        if n <= 10**5:
            w = fohw.gl_weights(0.6, n)
            tc, _ = measure(lambda: np.convolve(x, w)[:n], 1 if n >= 10**5 else rep)
            add("gl_difference (new alpha)", n, t_cold, "numpy.convolve", tc, peak)
        tf, _ = measure(lambda: bare_round_trip(x), rep)
        add("gl_difference (new alpha)", n, t_cold, "bare rfft/irfft round trip", tf, peak)
        add("gl_difference (same alpha)", n, t, "bare rfft/irfft round trip", tf, peak)

    model = fohw.datasets.paper_model()
    for n in sizes:
        u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
        v = 0.1 * rng.standard_normal(n)
        rep = 1 if n >= 10**5 else 3
        t, peak = measure(lambda: fohw.simulate(model, u, noise=v), rep)
        ref = None
        if n == sizes[0]:
            diff = np.max(np.abs(fohw.simulate(model, u, noise=v) - reference_simulate(model, u, v)))
            print(f"simulate vs reference at N={n}: max |difference| = {diff:.2e}")
            assert diff < 1e-10
        if n <= 10**5:
            ref, _ = measure(lambda: reference_simulate(model, u, v), 1)
        add("simulate", n, t, "per-step reference", ref, peak)

    alphas = np.linspace(0.1, 0.9, 20)
    for n in sizes:
        d = fohw.datasets.paper_example(n, random_state=1)
        rep = 1 if n >= 10**5 else 3

        def reuse():
            b = fohw.RegressorBuilder(d.u, d.y, **STRUCT)
            for a in alphas:
                b.matrix(a)

        def scratch():
            for a in alphas:
                fohw.information_matrix(d.u, d.y, a, **STRUCT)

        t, peak = measure(reuse, rep)
        ts, _ = measure(scratch, rep)
        add("information matrix, 20 alphas", n, t, "rebuilt from scratch", ts, peak)

        methods = {"varpro": {}}
        if n <= 10**4:
            methods.update({"hybrid (P=5)": dict(method="hybrid", innovation_length=5),
                            "rls": dict(method="rls", innovation_length=1)})
        for name, opts in methods.items():
            opts = dict(opts)
            opts.setdefault("method", name)

            def run():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", fohw.ConvergenceWarning)
                    fohw.identify(d.u, d.y, **STRUCT, **opts)
            t, peak = measure(run, 1 if n >= 10**5 else 3)
            add(f"identify {name}", n, t, "", None, peak)

    lines = ["# fohw benchmarks", "", f"Machine: {machine()}.", "",
             "Times are medians of repeats in one run; ratio = reference time / fohw time.", "",
             "| stage | N | fohw [s] | reference | reference [s] | ratio | peak memory [MB] |",
             "|---|---:|---:|---|---:|---:|---:|"]
    for r in rows:
        ref = f"{r['ref']:.4f}" if r["ref"] else "–"
        ratio = f"{r['ref'] / r['fohw']:.2f}" if r["ref"] else "–"
        lines.append(f"| {r['stage']} | {r['n']:.0e} | {r['fohw']:.4f} | {r['ref_name'] or '–'} | "
                     f"{ref} | {ratio} | {r['peak']:.1f} |")
    (args.outdir / "benchmarks.md").write_text("\n".join(lines) + "\n")

    fig, ax = plt.subplots(figsize=(7, 5))
    stages = []
    for r in rows:
        if r["stage"] not in stages:
            stages.append(r["stage"])
    for s in stages:
        pts = sorted({(r["n"], r["fohw"]) for r in rows if r["stage"] == s})
        ax.loglog(*zip(*pts), "o-", label=f"fohw: {s}")
    for ref_name, style in (("per-step reference", "k--"), ("numpy.convolve", "k:")):
        pts = sorted({(r["n"], r["ref"]) for r in rows if r["ref_name"] == ref_name})
        if pts:
            ax.loglog(*zip(*pts), style, label=ref_name)
    ax.set_xlabel("N (samples)")
    ax.set_ylabel("seconds (median)")
    ax.set_title("fohw scaling")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.outdir / "scaling.png", dpi=120)
    plt.close(fig)
    print(f"wrote {args.outdir / 'benchmarks.md'} and {args.outdir / 'scaling.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
