"""Simulating the input side of issue 24 against the FFT-merge floor, and the paper's model unslowed.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_inputs.py [--sizes 1e4 1e5 1e6]
                                                              [--baseline REV]

One run, medians of interleaved repeats, at each N:

* **paper**: ``fohw.simulate(paper_model, u, noise=v)``, the paper's example (nk = 1, one input);
* **feedthrough**: the same model with ``nk = 0`` (input lags 0 and 1, a term ``b0``);
* **two inputs**: a structure with two inputs, each its own basis (degree 2), lags and delay
  (``nb = [2, 2]``, ``nk = [0, 1]``), the paper's output block (``fohw.simulate(structure, u,
  params=...)``, the path of ``result.simulate``);
* **one-input structure**: today's single-input model through the same structure path
  (``fohw.simulate(structure, u, params=[theta, alpha])``, what ``result.simulate`` runs);
* **floor**: the FFT merges alone of the recursion at the compiled leaf size
  (``benchmarks/bench_simulator.py``'s floor: a divide and conquer whose leaf does nothing). A
  model feeds back its one signal ``gbar(y)``; a structure (any theta) feeds back one signal per
  output term or per g-basis function, whichever is fewer (here 2, the two output terms), so
  its floor is that of two signals (**floor 2**), as today for any result.

The ratios to the floor (the model's to floor, the structures' to floor 2) must stay within 3
(issue 24). ``--baseline REV`` (default: the commit
where this branch left ``main``) also times ``fohw.simulate(paper_model, …)`` in fresh processes,
alternately with the source tree of REV (``git archive``) and with this one: the paper's model
must not be slowed. numba's compiled leaf is loaded first when available (as
``bench_simulator.py`` does); its load time is not in the times.
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
from fohw.model.lagged import simulation

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from bench_simulator import data, load, merge_floor, merges, timed  # noqa: E402

# ruff: noqa: B023   (the timed lambdas run inside their loop iteration)


def models():
    """The paper model, its feedthrough twin, and a two-input structure with its parameters."""
    paper = fohw.datasets.paper_model()
    feed = fohw.HammersteinWiener(paper.a, paper.b, paper.p, paper.q, paper.alpha, nk=0)
    two = fohw.Structure.make(na=2, nb=[2, 2], nk=[0, 1], f_basis=[2, 2], g_basis=3,
                              inputs=("u1", "u2"))
    qa = np.kron(paper.q, paper.a)
    pb1 = np.kron(paper.p, paper.b)
    pb2 = np.kron(paper.p, 0.5 * paper.b)
    params = np.r_[qa, pb1, pb2, paper.alpha]
    return paper, feed, two, params


def side_by_side(sizes):
    paper, feed, two, params = models()
    t0 = time.perf_counter()
    kernel = _compiled.load()
    print("compiled leaf: " + ("numba import + compile or cache load "
                               f"{time.perf_counter() - t0:.2f} s (not in the times)"
                               if kernel is not None else "not available (pure-Python leaf)"))
    rows = []
    for n in sizes:
        u, v = data(n)
        u2 = np.column_stack([u, np.random.default_rng(n + 1).uniform(-np.sqrt(3), np.sqrt(3), n)])
        leaf = simulation.LEAF_SIZE_COMPILED if kernel is not None else simulation.LEAF_SIZE
        one = paper.structure
        fns = {"paper": lambda: fohw.simulate(paper, u, noise=v),
               "feedthrough": lambda: fohw.simulate(feed, u, noise=v),
               "one-input structure": lambda: fohw.simulate(one, u, params=np.r_[paper.theta,
                                                                                  paper.alpha],
                                                            noise=v),
               "two inputs": lambda: fohw.simulate(two, u2, params=params, noise=v),
               "floor": merges(paper, u, v, leaf),
               "floor 2": floor_of(np.eye(2), paper.alpha, n, leaf)}
        for f in fns.values():                    # warm (and check that each runs)
            f()
        repeats = 3 if n >= 10**6 else 5
        la0 = load()
        med = timed(fns, repeats)
        la1 = load()
        rows.append((n, repeats, med, la0, la1))
        print(f"N={n:.0e}  x{repeats}  load {la0:.2f}->{la1:.2f}  "
              + "  ".join(f"{k} {t:.4f} s" for k, t in med.items()), flush=True)
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    print(f"\nOPENBLAS_NUM_THREADS={threads}; medians of x interleaved repeats in this run.\n")
    print("| N | x | load | paper [s] | feedthrough [s] | one-input structure [s] "
          "| two inputs [s] | floor [s] | floor 2 [s] | paper/floor | feedthrough/floor "
          "| one-input structure/floor 2 | two inputs/floor 2 | two inputs/one-input structure |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    worst = {}
    for n, rep, m, la0, la1 in rows:
        r = {"paper": m["paper"] / m["floor"], "feedthrough": m["feedthrough"] / m["floor"],
             "one": m["one-input structure"] / m["floor 2"],
             "two": m["two inputs"] / m["floor 2"]}
        worst[n] = max(r["feedthrough"], r["two"])
        print(f"| {n:.0e} | {rep} | {la0:.1f}–{la1:.1f} | {m['paper']:.4f} | "
              f"{m['feedthrough']:.4f} | {m['one-input structure']:.4f} | "
              f"{m['two inputs']:.4f} | {m['floor']:.4f} | {m['floor 2']:.4f} | "
              f"{r['paper']:.2f} | {r['feedthrough']:.2f} | {r['one']:.2f} | {r['two']:.2f} | "
              f"{m['two inputs'] / m['one-input structure']:.2f} |")
    for n, w in worst.items():
        print(f"N = {n:.0e}: largest ratio of a new kind to its floor {w:.2f} "
              f"({'within' if w <= 3.0 else 'ABOVE'} the issue's 3x)")


def floor_of(A, alpha, n, leaf_size):
    """The FFT merges alone of a recursion feeding back ``A.shape[0]`` signals (one order)."""
    return merge_floor(A, [(i, alpha) for i in range(1, A.shape[1] + 1)], n, leaf_size)


PAPER = r"""
import json, statistics, sys, time
import numpy as np
import fohw
from fohw.model import _compiled
n, repeats = int(sys.argv[1]), int(sys.argv[2])
_compiled.load()
rng = np.random.default_rng(n)
u, v = rng.uniform(-np.sqrt(3), np.sqrt(3), n), 0.1 * rng.standard_normal(n)
m = fohw.datasets.paper_model()
fohw.simulate(m, u, noise=v)
times = []
for _ in range(repeats):
    t0 = time.perf_counter(); y = fohw.simulate(m, u, noise=v); times.append(time.perf_counter() - t0)
print(json.dumps({"median": statistics.median(times), "digest": float(np.sum(np.abs(y)))}))
"""


def baseline(sizes, rev, rounds=3):
    """``fohw.simulate(paper_model)`` in fresh processes, REV's tree and this one alternately."""
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        trees = {"baseline": str(Path(tmp) / "src"), "this": str(ROOT / "src")}
        print(f"\npaper model, fresh processes, baseline {rev} vs this tree "
              f"({rounds} alternating rounds, median of 3 runs in each):\n")
        print("| N | baseline [s] | this [s] | this/baseline | same output |")
        print("|---:|---:|---:|---:|---|")
        import json
        for n in sizes:
            got = {k: [] for k in trees}
            digest = {}
            for _ in range(rounds):
                for name, path in trees.items():
                    env = dict(os.environ, PYTHONPATH=path)
                    out = subprocess.run([sys.executable, "-c", PAPER, str(int(n)), "3"],
                                         capture_output=True, text=True, env=env, check=True)
                    r = json.loads(out.stdout.strip().splitlines()[-1])
                    got[name].append(r["median"])
                    digest[name] = r["digest"]
            b, t = statistics.median(got["baseline"]), statistics.median(got["this"])
            print(f"| {n:.0e} | {b:.4f} | {t:.4f} | {t / b:.2f} | "
                  f"{'yes' if digest['baseline'] == digest['this'] else 'NO'} |", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--baseline", default=None,
                    help="git revision to compare the paper model with (default: merge-base "
                    "with main); 'none' to skip")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes]
    print(f"fohw bench_inputs: N = {sizes}, {os.cpu_count()} CPUs, python {sys.version.split()[0]}")
    side_by_side(sizes)
    rev = args.baseline
    if rev is None:
        rev = subprocess.run(["git", "-C", str(ROOT), "merge-base", "HEAD", "main"],
                             capture_output=True, text=True).stdout.strip() or "none"
    if rev != "none":
        baseline(sizes, rev)


if __name__ == "__main__":
    main()
