"""BLAS threads and fohw's thin solves: with and without the one-thread limit (one run, medians).

    python benchmarks/bench_threads.py [--repeats 5] [--busy 2]   # BLAS threads as the machine sets them

Run it WITHOUT ``OPENBLAS_NUM_THREADS=1``: it measures what the limit of ``fohw._threads`` (active
when the optional ``threadpoolctl`` is installed) does against BLAS at its default thread count.
Prints the BLAS libraries and their thread counts, then ``identify(method="varpro")`` and
``"output_error"`` on the paper example with the limit and without it (the same process, runs
interleaved), the largest difference of the estimates, and ``monte_carlo`` serial against two
worker processes with the limit on (the honest speed-up of the workers). ``--busy k`` starts k
busy-loop processes for the duration of the run, to measure a loaded machine on purpose.
"""

import argparse
import os
import subprocess
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import fohw
import fohw._threads as threads

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)

# ruff: noqa: B023   (the timed closures run inside their loop iteration)


def make_record(seed):
    return fohw.datasets.paper_example(2000, random_state=seed)


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--busy", type=int, default=0,
                    help="start this many busy-loop processes for the run (a loaded machine)")
    args = ap.parse_args(argv)
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
            for _ in range(args.busy)]
    try:
        run(args)
    finally:
        for p in busy:
            p.terminate()
            p.wait()


def run(args):
    if threads.ThreadpoolController is None:
        raise SystemExit("threadpoolctl is not installed: pip install 'fohw[threads]'")
    from threadpoolctl import threadpool_info
    libs = [(i["internal_api"], i["num_threads"]) for i in threadpool_info()
            if i["user_api"] == "blas"]
    print(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}; "
          f"BLAS libraries and threads: {libs}; cores: {os.cpu_count()}; load average "
          f"{os.getloadavg()[0]:.2f}; busy-loop processes: {args.busy}; medians of {args.repeats} "
          "interleaved runs\n")
    print("| fit | N | limited to 1 thread [s] | BLAS default [s] | ratio | max abs diff |")
    print("|---|---:|---:|---:|---:|---:|")
    controller = threads.ThreadpoolController
    for method, sizes in (("varpro", (1_000, 10_000)), ("output_error", (1_000,))):
        for n in sizes:
            d = fohw.datasets.paper_example(n, random_state=0)

            def fit():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", fohw.ConvergenceWarning)
                    return fohw.identify(d.u, d.y, method=method, **STRUCT)
            t_on, t_off = [], []
            for _ in range(args.repeats):
                threads.ThreadpoolController = controller
                t, on = timed(fit)
                t_on.append(t)
                threads.ThreadpoolController = None          # the path without threadpoolctl
                t, off = timed(fit)
                t_off.append(t)
            threads.ThreadpoolController = controller
            diff = max(float(np.max(np.abs(on.theta - off.theta))), abs(on.alpha - off.alpha))
            a, b = np.median(t_on), np.median(t_off)
            print(f"| {method} | {n:.0e} | {a:.3f} | {b:.3f} | {b / a:.1f} | {diff:.1e} |",
                  flush=True)

    methods = {"varpro": {"method": "varpro"}}
    kw = dict(seeds=range(40), make_data=make_record, progress=False)
    t_serial, rows_s = timed(lambda: fohw.monte_carlo(methods, **kw))
    with ProcessPoolExecutor(2) as ex:
        fohw.monte_carlo(methods, **{**kw, "seeds": range(2)}, executor=ex)     # warm the workers
        t_par, rows_p = timed(lambda: fohw.monte_carlo(methods, **kw, executor=ex))
    same = all(r["alpha"] == q["alpha"] for r, q in zip(rows_s, rows_p))
    print("\n| monte_carlo, 40 seeds, varpro, N = 2000 | serial [s] | 2 workers [s] | speed-up | "
          "identical |")
    print("|---|---:|---:|---:|---|")
    print(f"| one BLAS thread in each task | {t_serial:.2f} | {t_par:.2f} | "
          f"{t_serial / t_par:.2f} | {same} |")


if __name__ == "__main__":
    main()
