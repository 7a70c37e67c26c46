"""How the paper's recursive methods scale with the record length (one run, medians).

    python benchmarks/bench_recursive.py [--repeats 3]

The hybrid (Table 1, P = 5) and MI-RLS rebuild their innovation window from the full memory at
every sample, so one pass is O(N^2): doubling N should multiply the time by about 4. Before the
windows were taken out of the BLAS path, the per-sample dot products went multithreaded above
N ~ 10^4 on this 2-core machine and the hybrid took 1.2 s at 10^4 but 83 s at 2 * 10^4. The
target is a ratio T(2 * 10^4) / T(10^4) of at most 4.5. Prints a Markdown table with the BLAS
thread setting of this run.
"""

import argparse
import os
import time
import warnings

import numpy as np

import fohw

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def timed(method, n, repeats, **options):
    d = fohw.datasets.paper_example(n, random_state=0)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", fohw.ConvergenceWarning)
            fohw.identify(d.u, d.y, method=method, **STRUCT, **options)
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    threads = {k: os.environ.get(k, "unset") for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    print(f"BLAS threads: {threads}; cores: {os.cpu_count()}; medians of {args.repeats} runs\n")
    print("| method | T(10^4) [s] | T(2*10^4) [s] | ratio | target |")
    print("|---|---:|---:|---:|---|")
    ok = True
    for method, options in (("hybrid", dict(innovation_length=5)),
                            ("rls", dict(innovation_length=1))):
        t1 = timed(method, 10_000, args.repeats, **options)
        t2 = timed(method, 20_000, args.repeats, **options)
        ratio = t2 / t1
        ok &= ratio <= 4.5
        print(f"| {method} | {t1:.2f} | {t2:.2f} | {ratio:.2f} | <= 4.5: "
              f"{'met' if ratio <= 4.5 else 'NOT met'} |")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
