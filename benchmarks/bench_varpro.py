"""varpro at N = 1e4, 1e5, 1e6: the blocked solves against the full-matrix reference.

    python benchmarks/bench_varpro.py [--sizes 1e4 1e5 1e6]

Issue 15, item 5. For each N and each path, a fresh process (``OPENBLAS_NUM_THREADS=1``)
simulates the paper's example (``fohw.datasets.paper_example(N, random_state=1)``), then runs
``varpro_result`` (the builder included, as ``fohw.identify`` does) with the full-matrix reference
of ``tests/reference_estimators.py`` in place (the full N x n matrix and its QR at every point:
what varpro did before) or without (blocks of rows, TSQR). It reports

* the time: the median of the repeats (3 up to 1e5, 1 at 1e6), the first run included;
* the peak RSS: VmHWM of that process after its first run (``run.high_water_mb``), and the
  VmHWM before it (imports and the simulated record: the simulator's own peak at 1e6);
* the tracemalloc peak of one more run (NumPy's allocations during the fit);
* the largest difference of the estimates (theta, alpha) between the two paths.

The two paths of one N run one after the other, so their ratio is measured under the same load.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from run import STRUCT, high_water_mb  # noqa: E402


def _fit(n, reference):
    import contextlib

    from reference_estimators import full_matrix_varpro

    import fohw
    from fohw.estimators.varpro import VarproOptions, varpro_result

    d = fohw.datasets.paper_example(n, random_state=1)
    bounds = (np.array([0.0]), np.array([1.0]))

    def run():
        with full_matrix_varpro() if reference else contextlib.nullcontext():
            builder = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, **STRUCT)
            options = VarproOptions().check(n_samples=n, bounds=bounds)
            return varpro_result(builder, options, bounds)
    return run


def child(path, n, repeats):
    """One case in this (fresh) process: print a JSON line."""
    run = _fit(n, path == "reference")
    before = high_water_mb()
    times = []
    t0 = time.perf_counter()
    res = run()
    times.append(time.perf_counter() - t0)
    rss = high_water_mb()
    for _ in range(repeats - 1):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    tracemalloc.start()
    run()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    print(json.dumps(dict(path=path, n=n, times=times, rss=rss, before=before, tracemalloc=peak,
                          theta=res.theta.tolist(), alpha=float(res.alpha),
                          status=res.status.name)))


def blas_threads():
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}"
    info = [f"{i['internal_api']}:{i['num_threads']}" for i in threadpool_info()
            if i.get("user_api") == "blas"]
    return f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')} ({', '.join(info)})"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", nargs="+", type=float, default=[1e4, 1e5, 1e6])
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        path, n, repeats = args.child
        child(path, int(n), int(repeats))
        return 0
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    os.environ.update(OPENBLAS_NUM_THREADS="1")
    import numpy  # noqa: F401  (threads as the children see them)

    print(f"BLAS threads: {blas_threads()}; load average at start: "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}", flush=True)
    rows = []
    for n in (int(s) for s in args.sizes):
        repeats = 3 if n <= 10**5 else 1
        out = {}
        for path in ("reference", "blocked"):
            load = os.getloadavg()[0]
            proc = subprocess.run([sys.executable, __file__, "--child", path, str(n),
                                   str(repeats)], capture_output=True, text=True, env=env,
                                  check=True)
            out[path] = json.loads(proc.stdout.strip().splitlines()[-1])
            out[path]["load"] = load
            r = out[path]
            print(f"N={n:.0e} {path:<9} x{repeats} median {np.median(r['times']):8.3f} s  "
                  f"RSS {r['rss']:6.0f} MB (before the fit {r['before']:4.0f})  tracemalloc "
                  f"{r['tracemalloc']:6.1f} MB  load {load:.2f}  {r['status']}", flush=True)
        ref, new = out["reference"], out["blocked"]
        d_theta = float(np.max(np.abs(np.subtract(new["theta"], ref["theta"]))))
        d_alpha = abs(new["alpha"] - ref["alpha"])
        rows.append((n, repeats, ref, new, d_theta, d_alpha))

    print("\n| N | x | reference [s] | blocked [s] | ratio | RSS ref / blocked [MB] | "
          "RSS before the fit [MB] | tracemalloc ref / blocked [MB] | max abs diff theta | "
          "abs diff alpha | load |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, repeats, ref, new, d_theta, d_alpha in rows:
        t_ref, t_new = np.median(ref["times"]), np.median(new["times"])
        print(f"| {n:.0e} | {repeats} | {t_ref:.3f} | {t_new:.3f} | {t_ref / t_new:.2f} | "
              f"{ref['rss']:.0f} / {new['rss']:.0f} | {ref['before']:.0f} / "
              f"{new['before']:.0f} | {ref['tracemalloc']:.0f} / {new['tracemalloc']:.0f} | "
              f"{d_theta:.1e} | {d_alpha:.1e} | {ref['load']:.1f}, {new['load']:.1f} |")
    print(f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    big = [r for r in rows if r[0] >= 10**6]
    if big:
        print(f"RSS <= 1 GB at 1e6 (blocked): {big[0][3]['rss'] <= 1024}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
