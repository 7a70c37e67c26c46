"""Simulating with a series output map y = h(z) (issue 24, item 2) against the FFT-merge floor.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_output_map.py [--sizes 1e4 1e5 1e6]
        [--baseline-src /path/to/other/src]

One run, the paper's example (``fohw.datasets.paper_model()``, the input and noise of
``benchmarks/bench_simulator.py``), medians of interleaved repeats, the compiled leaf loaded
first when numba is installed (as ``bench_simulator.py`` does):

* **paper**: ``fohw.simulate(model, u, noise=v)``, the paper's model (its path is unchanged by
  the output map; ``--baseline-src`` times the same call with another source tree in a fresh
  process, e.g. ``git worktree`` of main, to show it is not slowed);
* **structure**: ``fohw.simulate(structure, u, params=...)`` of the same model as a Structure
  without an output map (theta's blocks);
* **saturation**, **piecewise linear**: the same Structure with a series output map
  (limits at the 5th and 95th percentiles of the output; 5 breakpoints), i.e. one more
  elementwise pass over the output;
* **series HW**: the classical series Hammerstein–Wiener model u -> f -> linear fractional
  block -> h (the paper's a, b, p, alpha with g the identity, one fed-back signal as in the
  paper's model) with the saturation;
* **floor**: the divide and conquer with a leaf that does nothing (the FFT merges alone:
  ``bench_simulator.merges``) for the model's one fed-back signal, the floor the issue measures
  against (target: within 3x); **structure floor**: the same for the Structure's own
  representation (two fed-back signals here), the floor of the Structure paths.
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import fohw
from fohw.model import _compiled
from fohw.model.lagged import simulation

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_simulator import data, load, merge_floor, merges, timed  # noqa: E402

# ruff: noqa: B023   (the timed lambdas run inside their loop iteration)

BASELINE = """
import statistics, sys, time
import numpy as np
import fohw
from fohw.model import _compiled
_compiled.load()
n, repeats = int(sys.argv[1]), int(sys.argv[2])
rng = np.random.default_rng(n)
u, v = rng.uniform(-np.sqrt(3), np.sqrt(3), n), 0.1 * rng.standard_normal(n)
m = fohw.datasets.paper_model()
fohw.simulate(m, u, noise=v)
t = []
for _ in range(repeats):
    t0 = time.perf_counter(); fohw.simulate(m, u, noise=v); t.append(time.perf_counter() - t0)
print(statistics.median(t))
"""


def structure_floor(structure, params, u, v, leaf_size):
    """The FFT merges alone for a Structure's own representation (theta's blocks).

    A Structure is simulated with the fewer of its basis signals and its output terms fed back
    (2 signals for the paper's na = 2, g of degree 3), so its floor has that many accumulators;
    ``bench_simulator.merges`` is the floor of the model's one signal (gbar).
    """
    qa, _ = structure.layout.blocks(params[:structure.layout.n_params])
    A = qa if qa.shape[0] <= qa.shape[1] else np.eye(qa.shape[1])
    alpha = float(params[-1])
    out_terms = [(t.lag, alpha) for t in structure.orders.output]
    return merge_floor(A, out_terms, u.shape[0], leaf_size)


def baseline_time(src, n, repeats):
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run([sys.executable, "-c", BASELINE, str(n), str(repeats)], env=env,
                         capture_output=True, text=True, check=True, cwd="/")
    return float(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--baseline-src", type=Path, default=None,
                    help="another source tree (its src/) to time the paper's model with")
    args = ap.parse_args(argv)
    print(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"{os.cpu_count()} cores, load average {load():.2f}, NumPy {np.__version__}")
    t0 = time.perf_counter()
    compiled = _compiled.load() is not None
    print(f"compiled leaf: {'loaded' if compiled else 'not available (pure leaf)'} in "
          f"{time.perf_counter() - t0:.2f} s (once per process; not in the times below)")
    model = fohw.datasets.paper_model()
    s = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=3)
    params = np.r_[model.theta, model.alpha]
    leaf = simulation.LEAF_SIZE_COMPILED if compiled else simulation.LEAF_SIZE
    rows = []
    for n in (int(x) for x in args.sizes):
        u, v = data(n)
        y = fohw.simulate(model, u, noise=v)
        lo, hi = np.percentile(y, [5, 95])
        sat = s.with_output_map("saturation")
        pwl = s.with_output_map(fohw.model.output_map.PiecewiseLinear(np.linspace(lo, hi, 5)))
        eta_pwl = np.linspace(lo, hi, 5) * 1.1
        ys = fohw.simulate(sat, u, params=np.r_[params, lo, hi], noise=v)
        z = fohw.simulate(s, u, params=params, noise=v)
        assert np.array_equal(ys, np.clip(z, lo, hi))
        hw = fohw.Structure.make(na=2, nb=2, f_basis=2, g_basis=1, output_map="saturation")
        hw_params = np.r_[model.a, model.b, model.p[1] * model.b, model.alpha]
        z_hw = fohw.simulate(hw.inner, u, params=hw_params, noise=v)
        hw_lim = np.percentile(z_hw, [5, 95])
        fns = {"paper": lambda: fohw.simulate(model, u, noise=v),
               "series HW": lambda: fohw.simulate(hw, u, params=np.r_[hw_params, hw_lim],
                                                  noise=v),
               "structure": lambda: fohw.simulate(s, u, params=params, noise=v),
               "saturation": lambda: fohw.simulate(sat, u, params=np.r_[params, lo, hi], noise=v),
               "piecewise linear": lambda: fohw.simulate(pwl, u, params=np.r_[params, eta_pwl],
                                                         noise=v),
               "floor": merges(model, u, v, leaf),
               "structure floor": structure_floor(s, params, u, v, leaf)}
        repeats = 3 if n >= 10**6 else 5
        la0 = load()
        med = timed(fns, repeats)
        if args.baseline_src is not None:
            med["paper (baseline src)"] = baseline_time(args.baseline_src, n, repeats)
        la1 = load()
        rows.append((n, repeats, med, la0, la1))
        print(f"N={n:.0e}  x{repeats}  load {la0:.2f}->{la1:.2f}  "
              + "  ".join(f"{k} {t:.4f} s" for k, t in med.items()), flush=True)
    print("\n| N | x | paper [s] | series HW [s] | structure [s] | saturation [s] | "
          "piecewise linear [s] | floor [s] | structure floor [s] | paper/floor | "
          "series HW/floor | saturation/structure floor | pwl/structure floor | "
          "saturation/structure | paper/baseline |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, repeats, m, _, _ in rows:
        base = m.get("paper (baseline src)")
        sf = m["structure floor"]
        print(f"| {n:.0e} | {repeats} | {m['paper']:.4f} | {m['series HW']:.4f} | "
              f"{m['structure']:.4f} | "
              f"{m['saturation']:.4f} | {m['piecewise linear']:.4f} | {m['floor']:.4f} | "
              f"{sf:.4f} | {m['paper'] / m['floor']:.2f} | {m['series HW'] / m['floor']:.2f} | "
              f"{m['saturation'] / sf:.2f} | "
              f"{m['piecewise linear'] / sf:.2f} | {m['saturation'] / m['structure']:.3f} | "
              + (f"{m['paper'] / base:.3f}" if base else "-") + " |")
    print(f"\nleaf size {leaf}; medians of x interleaved repeats in this run; load average at "
          f"the end {load():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
