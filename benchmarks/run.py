"""fohw benchmark suite: every stage against a plain reference, N = 10^3 ... 10^6.

    python benchmarks/run.py [--quick] [--outdir benchmarks/results]

Each time is the median of several repeats measured in this one run (one repeat for the
slowest cases); the machine is shared, so read the ratios. The plain references are written
here, for the benchmark:

* GL difference: ``numpy.convolve`` (O(N^2), up to 10^5) and the zero-padded 3-FFT linear
  convolution written out (weights by the recurrence, rfft of the signal, rfft of the weights,
  product, irfft, cut: what fohw computes, without its checks and caches) for a new order at
  every call; for a repeated order the same with the weights' spectrum computed beforehand
  (two transforms), as fohw caches it;
* simulator: the per-step full-memory recursion written contiguously (the input term by one
  FFT convolution, then one dot product of two contiguous slices per step, the output
  nonlinearity in scalar arithmetic);
* information matrix for 20 values of alpha: rebuilt from scratch each time
  (``fohw.model.lagged.regressors.information_matrix``) against one ``RegressorBuilder``
  reusing the basis FFTs;
* end-to-end ``fohw.identify`` per method.

Memory: the tracemalloc peak of the stage (NumPy reports its allocations to it) and, with
``--rss``, the peak resident set size of a fresh Python process that imports fohw, prepares the
data and runs the stage once (``VmHWM``; the baseline of such a process doing nothing is
printed). Every table records N, the repeats, the BLAS thread setting and the machine.
Writes benchmarks.md and scaling.png to --outdir and prints the table.
"""

import argparse
import os
import platform
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.fft  # noqa: E402

import fohw  # noqa: E402

# ruff: noqa: B023   (the timed lambdas run inside their loop iteration)

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
    """The textbook recursion written contiguously: one dot product of two slices per step."""
    import scipy.signal

    n = len(u)
    beta = fohw.gl_weights(model.alpha, n)
    beta_rev = np.ascontiguousarray(beta[::-1])      # beta_rev[n-1-j] = beta[j]
    fbar = model.f_basis.combine(model.p, u)
    dfbar = scipy.signal.fftconvolve(fbar, beta)[:n]  # does not depend on y: one FFT
    a, b = [float(c) for c in model.a], [float(c) for c in model.b]
    q1, q2, q3 = (float(c) for c in model.q)
    y = np.zeros(n)
    gbar = np.zeros(n)
    dg = [0.0] * n
    for k in range(n):
        acc = float(v[k])
        for i in range(1, min(len(a), k) + 1):
            acc += a[i - 1] * dg[k - i]
        for i in range(1, min(len(b), k) + 1):
            acc += b[i - 1] * dfbar[k - i]
        y[k] = acc
        gbar[k] = q1 * acc + q2 * acc * acc + q3 * acc * acc * acc
        dg[k] = float(beta_rev[n - 1 - k:] @ gbar[:k + 1])
    return y


def three_fft(x, alpha, w_spec=None):
    """The zero-padded 3-FFT linear convolution with the GL weights, cut to N (2 FFTs if cached)."""
    n = len(x)
    nfft = scipy.fft.next_fast_len(2 * n - 1, real=True)
    if w_spec is None:
        w = np.empty(n)
        w[0] = 1.0
        np.cumprod(1.0 - (alpha + 1.0) / np.arange(1.0, n), out=w[1:])
        w_spec = scipy.fft.rfft(w, n=nfft)
    return scipy.fft.irfft(scipy.fft.rfft(x, n=nfft) * w_spec, n=nfft)[:n]


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


def stage(name, n):
    """The fohw computation of one stage at size n, as a zero-argument callable (data prepared)."""
    rng = np.random.default_rng(n)
    if name == "gl_difference":
        x = rng.standard_normal(n)
        return lambda: fohw.gl_difference(x, 0.6)
    if name == "simulate":
        model = fohw.datasets.paper_model()
        u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
        v = 0.1 * rng.standard_normal(n)
        return lambda: fohw.simulate(model, u, noise=v)
    d = fohw.datasets.paper_example(n, random_state=1)
    if name == "matrices":
        def reuse():
            b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, **STRUCT)
            for a in np.linspace(0.1, 0.9, 20):
                b.matrix(a)
        return reuse
    opts = {"varpro": dict(method="varpro"),
            "hybrid": dict(method="hybrid", innovation_length=5),
            "rls": dict(method="rls", innovation_length=1)}[name]

    def run():
        fohw.identify(d.u, d.y, **STRUCT, **opts)
    return run


def high_water_mb():
    """Peak RSS of this process in MB: VmHWM (Linux), else ru_maxrss.

    Not ru_maxrss on Linux: across fork and exec it keeps the parent's high-water mark.
    """
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return float(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def peak_rss(name, n):
    """Peak RSS (MB) of a fresh process running the stage once; ``name=None``: imports only."""
    args = [sys.executable, __file__, "--stage", name or "none", "--n", str(n)]
    out = subprocess.run(args, capture_output=True, text=True, check=True)
    return float(out.stdout.split()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N up to 10^5, fewer repeats")
    ap.add_argument("--rss", action="store_true", help="also the peak RSS of each stage")
    ap.add_argument("--outdir", type=Path, default=Path("benchmarks/results"))
    ap.add_argument("--stage", help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.stage:                       # child of peak_rss: run once, print ru_maxrss in MB
        fn = None if args.stage == "none" else stage(args.stage, args.n)
        if fn is not None:
            fn()
        print(high_water_mb())
        return 0
    sizes = [10**3, 10**4, 10**5] if args.quick else [10**3, 10**4, 10**5, 10**6]
    args.outdir.mkdir(parents=True, exist_ok=True)
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    base_rss = peak_rss(None, 0) if args.rss else None
    if args.rss:
        print(f"peak RSS of a process that only imports fohw: {base_rss:.0f} MB")
    rows = []

    def add(name, n, fohw_t, ref_name, ref_t, peak, rep):
        rss = peak_rss(name.split()[0], n) if args.rss else None
        rows.append(dict(stage=name, n=n, fohw=fohw_t, ref_name=ref_name, ref=ref_t, peak=peak,
                         rss=rss, rep=rep))
        ratio = f"{ref_t / fohw_t:.1f}" if ref_t else "–"
        print(f"{name:<28} N={n:>8} x{rep} fohw {fohw_t:9.4f} s  {ref_name:<22} "
              f"{(f'{ref_t:9.4f} s' if ref_t else '       –   ')}  ratio {ratio:>6}  "
              f"tracemalloc {peak:7.1f} MB" + (f"  RSS {rss:7.0f} MB" if rss else ""), flush=True)

    for n in sizes:
        rep = 3 if (args.quick or n >= 10**5) else 7
        x = np.random.default_rng(n).standard_normal(n)
        t, peak = measure(stage("gl_difference", n), rep)      # same order: spectrum cached
        fresh = iter(np.linspace(0.1, 0.9, 10 * rep + 10))
        t_cold, _ = measure(lambda: fohw.gl_difference(x, next(fresh)), rep)
        fresh_ref = iter(np.linspace(0.1, 0.9, 10 * rep + 10))
        t3, _ = measure(lambda: three_fft(x, next(fresh_ref)), rep)
        nfft = scipy.fft.next_fast_len(2 * n - 1, real=True)
        w_spec = scipy.fft.rfft(fohw.gl_weights(0.6, n), n=nfft)
        t2, _ = measure(lambda: three_fft(x, 0.6, w_spec), rep)
        if n <= 10**5:
            w = fohw.gl_weights(0.6, n)
            tc, _ = measure(lambda: np.convolve(x, w)[:n], 1 if n >= 10**5 else rep)
            add("gl_difference (new alpha)", n, t_cold, "numpy.convolve", tc, peak, rep)
        add("gl_difference (new alpha)", n, t_cold, "3-FFT convolution", t3, peak, rep)
        add("gl_difference (same alpha)", n, t, "2-FFT, cached weights", t2, peak, rep)

    model = fohw.datasets.paper_model()
    from fohw.model import _compiled

    t0 = time.perf_counter()
    leaf = "compiled" if _compiled.available() and _compiled.load() is not None else "pure"
    print(f"simulator leaf: {leaf} (loading it took {time.perf_counter() - t0:.2f} s, not timed "
          "below; benchmarks/bench_simulator.py compares both)")
    for n in sizes:
        rng = np.random.default_rng(n)
        u = rng.uniform(-np.sqrt(3), np.sqrt(3), n)
        v = 0.1 * rng.standard_normal(n)
        rep = 3 if n >= 10**5 else 5
        t, peak = measure(stage("simulate", n), rep)
        ref = None
        if n == sizes[0]:
            diff = np.max(np.abs(fohw.simulate(model, u, noise=v) - reference_simulate(model, u, v)))
            print(f"simulate vs reference at N={n}: max |difference| = {diff:.2e}")
            assert diff < 1e-10
        if n <= 10**5:
            ref, _ = measure(lambda: reference_simulate(model, u, v), 1 if n >= 10**5 else 3)
        add("simulate", n, t, "contiguous per-step", ref, peak, rep)

    alphas = np.linspace(0.1, 0.9, 20)
    for n in sizes:
        d = fohw.datasets.paper_example(n, random_state=1)
        rep = 1 if n >= 10**5 else 3

        def scratch():
            for a in alphas:
                fohw.model.lagged.regressors.information_matrix(d.u, d.y, a, **STRUCT)

        t, peak = measure(stage("matrices", n), rep)
        ts, _ = measure(scratch, rep)
        add("matrices (20 alphas)", n, t, "rebuilt from scratch", ts, peak, rep)
        names = ["varpro"] + (["hybrid"] if n <= 10**5 else []) + (["rls"] if n <= 10**4 else [])
        for name in names:
            r = 1 if n >= 10**5 else 3
            t, peak = measure(stage(name, n), r)
            add(name, n, t, "", None, peak, r)

    lines = ["# fohw benchmarks", "", f"Machine: {machine()}. OPENBLAS_NUM_THREADS={threads}.", "",
             "Times are medians of the repeats (column x) in one run; ratio = reference time / "
             "fohw time (the reference runs once at 10^5).",
             f"RSS: peak of a fresh process running the stage once (imports alone: {base_rss} MB).",
             "", "| stage | N | x | fohw [s] | reference | reference [s] | ratio | tracemalloc [MB] "
             "| RSS [MB] |", "|---|---:|---:|---:|---|---:|---:|---:|---:|"]
    for r in rows:
        ref = f"{r['ref']:.4f}" if r["ref"] else "–"
        ratio = f"{r['ref'] / r['fohw']:.2f}" if r["ref"] else "–"
        rss = f"{r['rss']:.0f}" if r["rss"] else "–"
        lines.append(f"| {r['stage']} | {r['n']:.0e} | {r['rep']} | {r['fohw']:.4f} | "
                     f"{r['ref_name'] or '–'} | {ref} | {ratio} | {r['peak']:.1f} | {rss} |")
    (args.outdir / "benchmarks.md").write_text("\n".join(lines) + "\n")

    fig, ax = plt.subplots(figsize=(7, 5))
    stages = []
    for r in rows:
        if r["stage"] not in stages:
            stages.append(r["stage"])
    for s in stages:
        pts = sorted({(r["n"], r["fohw"]) for r in rows if r["stage"] == s})
        ax.loglog(*zip(*pts), "o-", label=f"fohw: {s}")
    for ref_name, style in (("contiguous per-step", "k--"), ("numpy.convolve", "k:")):
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
