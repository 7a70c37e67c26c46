"""The simulator side by side (issue 15, item 2): today's, the pure leaf, the compiled leaf, the floor.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_simulator.py [--sizes 1e4 1e5 1e6]
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_simulator.py --leaves     # choose leaf sizes
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_simulator.py --workloads --baseline REV

One run, the paper's example (``fohw.datasets.paper_model()``, the input and noise of
``benchmarks/run.py``'s simulate stage), medians of interleaved repeats:

* **before**: the simulator before issue 15 (``benchmarks/simulator_before.py``: leaves of 128
  in pure Python, each merge a full zero-padded linear convolution with the weights' spectrum
  computed every time);
* **pure**: the pure-Python leaf (what runs without numba), with the new merges;
* **compiled**: the numba leaf (the ``fast`` extra); its one-time load (numba import and compile
  or cache load) is measured first and reported apart;
* **floor**: the same divide and conquer with a leaf that does nothing (the FFT merges alone, on
  the same segments; this script's ``merges``), at the compiled and at the pure leaf size;
* **per-step**: the contiguous per-step recursion of ``benchmarks/run.py`` (N <= 10^5).

``--workloads`` also times ``fohw.identify(method="output_error")`` at N = 10^4 and a small
``fohw.monte_carlo`` study (varpro and output_error, N = 2000, 4 seeds), each in fresh processes,
alternately with the source tree of ``--baseline`` (``git archive REV``) and with this one.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import fohw
from fohw.model import _compiled
from fohw.model.kernels import HalfMerge, divide_and_conquer
from fohw.model.lagged import simulation

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import simulator_before  # noqa: E402
from run import reference_simulate  # noqa: E402
from simulator_before import simulate_before  # noqa: E402

# ruff: noqa: B023   (the timed lambdas run inside their loop iteration)


def load():
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def data(n):
    rng = np.random.default_rng(n)          # as benchmarks/run.py's simulate stage
    return rng.uniform(-np.sqrt(3), np.sqrt(3), n), 0.1 * rng.standard_normal(n)


def simulate(model, u, v, kernel, leaf_size=None):
    """fohw.simulate(model, u, noise=v) with a chosen leaf (what simulate runs, step for step).

    ``kernel="reference"``: the recursion before issue 15 (``simulator_before.py``).
    """
    if kernel == "reference":
        return simulate_before(lambda: simulate(model, u, v, "pure"))
    return simulation.free_run(model.structure, model.q[:, None], model.a[None, :],
                               np.outer(model.q, model.a), np.outer(model.p, model.b),
                               model.orders, u, v, offset=model.offset, past=model.past,
                               operating_point=model.operating_point, threshold=None,
                               history=None, kernel=kernel, leaf_size=leaf_size)


def merges(model, u, v, leaf_size):
    """The callable timing the FFT merges alone (forcing computed beforehand).

    The recursion's divide and conquer (its setup included) with a leaf that does nothing, so
    only the merges run, on the same segments as :func:`fohw.model.lagged.simulation.recursion`.
    """
    out_terms = [(i, model.alpha) for i in range(1, model.a.shape[0] + 1)]
    in_terms = [(i, model.alpha) for i in range(1, model.b.shape[0] + 1)]
    w = simulation.forcing(np.outer(model.p, model.b), in_terms, None, out_terms, model.f_basis,
                           model.g_basis, u, v, 1.0, 0.0, (0.0, 0.0))
    return merge_floor(model.a[None, :], out_terms, w.shape[0], leaf_size)


def merge_floor(A, out_terms, n, leaf_size):
    """The callable running the FFT merges alone for ``A.shape[0]`` fed-back signals.

    The divide and conquer of :func:`fohw.model.lagged.simulation.recursion` (its setup included) on
    ``n`` samples with a leaf that does nothing. Used by the other simulator benchmarks too.
    """
    size = max(1, min(leaf_size, n))

    def floor():
        acc = simulation.accumulators(A, out_terms, 1.0, n)
        merge = HalfMerge(acc.betas, acc.memory)
        z = np.zeros((A.shape[0], n))
        dz = np.zeros((acc.count, n))
        with np.errstate(over="ignore", invalid="ignore"):
            divide_and_conquer(n, size, lambda lo, hi: None,
                               lambda lo, mid, hi: merge(z, dz, lo, mid, hi))
    return floor


def timed(fns, repeats):
    """Medians over ``repeats`` rounds, each round running every callable once (interleaved)."""
    times = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(t) for name, t in times.items()}


def side_by_side(sizes):
    model = fohw.datasets.paper_model()
    t0 = time.perf_counter()
    kernel = _compiled.load()
    if kernel is None:
        sys.exit("numba is not available: pip install 'fohw[fast]'")
    print(f"compiled leaf: numba import + compile or cache load {time.perf_counter() - t0:.2f} s "
          "(once per process; not in the times below)")
    print(f"leaf sizes: pure {simulation.LEAF_SIZE}, compiled {simulation.LEAF_SIZE_COMPILED}, "
          f"before {simulator_before.LEAF}")
    rows = []
    for n in sizes:
        u, v = data(n)
        ys = {k: simulate(model, u, v, k) for k in ("reference", "pure", "compiled")}
        diff_pure = float(np.max(np.abs(ys["pure"] - ys["reference"])))
        diff_comp = float(np.max(np.abs(ys["compiled"] - ys["pure"])))
        fns = {"before": lambda: simulate(model, u, v, "reference"),
               "pure": lambda: simulate(model, u, v, "pure"),
               "compiled": lambda: simulate(model, u, v, "compiled"),
               "floor": merges(model, u, v, simulation.LEAF_SIZE_COMPILED),
               "floor_pure": merges(model, u, v, simulation.LEAF_SIZE)}
        repeats = 3 if n >= 10**6 else 5
        la0 = load()
        med = timed(fns, repeats)
        if n <= 10**5:
            step = timed({"per-step": lambda: reference_simulate(model, u, v)},
                         1 if n >= 10**5 else 3)
            med.update(step)
        la1 = load()
        rows.append((n, repeats, med, diff_pure, diff_comp, la0, la1))
        print(f"N={n:.0e}  x{repeats}  load {la0:.2f}->{la1:.2f}  "
              + "  ".join(f"{k} {t:.4f} s" for k, t in med.items()), flush=True)
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    print(f"\nOPENBLAS_NUM_THREADS={threads}; medians of x interleaved repeats in this run; "
          "per-step once at 1e5, 3x at 1e4.\n")
    print("| N | x | load | before [s] | pure [s] | compiled [s] | floor (leaf "
          f"{simulation.LEAF_SIZE_COMPILED}) [s] | floor (leaf {simulation.LEAF_SIZE}) [s] | per-step [s] "
          "| before/pure | before/compiled | compiled/floor | pure/floor | per-step/compiled "
          "| max diff pure-before | max diff compiled-pure |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, rep, m, dp, dc, la0, la1 in rows:
        ps = m.get("per-step")
        print(f"| {n:.0e} | {rep} | {la0:.1f}–{la1:.1f} | {m['before']:.4f} | {m['pure']:.4f} | "
              f"{m['compiled']:.4f} | {m['floor']:.4f} | {m['floor_pure']:.4f} | "
              f"{(f'{ps:.4f}' if ps else '–')} | {m['before'] / m['pure']:.2f} | "
              f"{m['before'] / m['compiled']:.2f} | {m['compiled'] / m['floor']:.2f} | "
              f"{m['pure'] / m['floor_pure']:.2f} | "
              f"{(format(ps / m['compiled'], '.1f') if ps else '–')} | {dp:.1e} | {dc:.1e} |")


def leaves(sizes, candidates):
    model = fohw.datasets.paper_model()
    _compiled.load()
    print("| N | leaf | pure [s] | compiled [s] | floor [s] | load |")
    print("|---:|---:|---:|---:|---:|---|")
    for n in sizes:
        u, v = data(n)
        repeats = 3
        fns = {}
        for L in candidates:
            fns[("pure", L)] = lambda L=L: simulate(model, u, v, "pure", L)
            fns[("compiled", L)] = lambda L=L: simulate(model, u, v, "compiled", L)
            fns[("floor", L)] = merges(model, u, v, L)
        la0 = load()
        med = timed(fns, repeats)
        la1 = load()
        for L in candidates:
            print(f"| {n:.0e} | {L} | {med['pure', L]:.4f} | {med['compiled', L]:.4f} | "
                  f"{med['floor', L]:.4f} | {la0:.1f}–{la1:.1f} |", flush=True)


WORKLOAD = r"""
import json, os, statistics, sys, time, warnings
import numpy as np
import fohw
which, repeats = sys.argv[1], int(sys.argv[2])
warnings.simplefilter("ignore")
if which == "output_error":
    d = fohw.datasets.paper_example(10_000, random_state=1)
    run = lambda: fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3,
                                method="output_error")
else:
    methods = {"varpro": dict(method="varpro"), "output_error": dict(method="output_error")}
    run = lambda: fohw.monte_carlo(methods, seeds=range(4),
                                   make_data=lambda s: fohw.datasets.paper_example(
                                       2000, random_state=s), progress=False)
times = []
for _ in range(repeats):
    t0 = time.perf_counter(); out = run(); times.append(time.perf_counter() - t0)
if which == "output_error":
    digest = [float(out.alpha)] + [float(x) for x in out.theta]
else:
    digest = [float(r["alpha"]) for r in out]
print(json.dumps({"first": times[0], "warm": statistics.median(times[1:]) if repeats > 1
                  else None, "digest": digest}))
"""


def workloads(baseline, rounds):
    tmp = Path(tempfile.mkdtemp(prefix="fohw_baseline_"))
    archive = subprocess.run(["git", "archive", baseline, "src"], cwd=HERE.parent,
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    trees = {"before": str(tmp / "src"), "after": str(HERE.parent / "src")}
    print(f"baseline {baseline} in {tmp}; {rounds} fresh processes per tree, alternating; in "
          "each: the first call (cold) and the median of 2 more (warm)")
    for which in ("output_error", "monte_carlo"):
        res = {k: [] for k in trees}
        la0 = load()
        for _ in range(rounds):
            for tree, src in trees.items():
                env = dict(os.environ, PYTHONPATH=src)
                out = subprocess.run([sys.executable, "-c", WORKLOAD, which, "3"], env=env,
                                     capture_output=True, text=True, check=True)
                import json
                res[tree].append(json.loads(out.stdout.splitlines()[-1]))
        la1 = load()
        cold = {k: statistics.median(r["first"] for r in v) for k, v in res.items()}
        warm = {k: statistics.median(r["warm"] for r in v) for k, v in res.items()}
        d = max(abs(a - b) for a, b in zip(res["before"][0]["digest"], res["after"][0]["digest"]))
        print(f"{which}: cold before {cold['before']:.2f} s, after {cold['after']:.2f} s "
              f"({cold['before'] / cold['after']:.2f}x); warm before {warm['before']:.2f} s, "
              f"after {warm['after']:.2f} s ({warm['before'] / warm['after']:.2f}x); "
              f"max |estimate difference| {d:.1e}; load {la0:.2f}->{la1:.2f}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--leaves", action="store_true", help="time leaf sizes 64..1024 instead")
    ap.add_argument("--workloads", action="store_true", help="output_error and monte_carlo too")
    ap.add_argument("--baseline", default="main", help="git revision for --workloads' before")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes]
    print(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"{os.cpu_count()} cores, load average {load():.2f}, NumPy {np.__version__}")
    if args.leaves:
        leaves(sizes, [64, 128, 256, 512, 1024])
        return 0
    side_by_side(sizes)
    if args.workloads:
        workloads(args.baseline, args.rounds)
    print(f"load average at the end {load():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
