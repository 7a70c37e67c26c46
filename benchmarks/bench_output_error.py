"""output_error's solver: the exact free-run sensitivity against finite differences (one run, medians).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_output_error.py [--repeats 3] [--sizes 1e3,1e4,1e5]

On the paper's example (uniform input, seed 0, N samples) the varpro start is computed once per
N; from it the simulation-error fit (``fit_output_error``) runs with the exact Jacobian (the
default: ``-S`` from ``fohw.model.sensitivity.simulation_jacobian``) and with scipy's forward
differences (``_jacobian="2-point"``, the code before, one simulation per parameter per
Jacobian), interleaved, in this process. Printed: medians of ``--repeats`` runs (one run at
N >= 1e5), their ratio, the solver's iterations (Jacobians), the simulations each path ran
(residuals, plus one per parameter per Jacobian for finite differences, plus one per exact
Jacobian), and how far apart the two optima are: the relative difference of the simulation SSE,
|delta alpha|, and the distance of the estimates in the metric of their covariance
``s^2 (S^T S)^-1`` (scipy's ftol = 1e-8 allows about ``2 sqrt(1e-8 (N - d))``).
"""

import argparse
import os
import time
import warnings

import numpy as np

import fohw
from fohw.estimators.output_error import fit_output_error
from fohw.estimators.varpro import separable_least_squares

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def fit(builder, start, jacobian):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        res = fit_output_error(builder, start.linear, start.params, lower=np.array([0.0]),
                               upper=np.array([1.0]), max_nfev=100, _jacobian=jacobian)
    return time.perf_counter() - t0, res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sizes", default="1e3,1e4,1e5")
    args = ap.parse_args(argv)
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    threads = {k: os.environ.get(k, "unset") for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    print(f"BLAS threads: {threads}; cores: {os.cpu_count()}; load average at start "
          f"{os.getloadavg()[0]:.2f}; medians of {args.repeats} runs (1 run at N >= 1e5)\n")
    print("| N | runs | varpro start [s] | finite differences [s] | exact [s] | ratio | "
          "iterations (fd / exact) | simulations (fd / exact) | SSE rel. diff | "
          "abs diff of alpha | distance / sd | load |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        d = fohw.datasets.paper_example(n, random_state=0)
        builder = fohw.RegressorBuilder(d.u, d.y, **STRUCT)
        t0 = time.perf_counter()
        start = separable_least_squares(builder, bounds=(np.array([0.0]), np.array([1.0])))
        t_start = time.perf_counter() - t0
        repeats = args.repeats if n < 100_000 else 1
        runs = {"2-point": [], "exact": []}
        for _ in range(repeats):
            for jacobian in runs:
                runs[jacobian].append(fit(builder, start, jacobian))
        t_fd = float(np.median([t for t, _ in runs["2-point"]]))
        t_ex = float(np.median([t for t, _ in runs["exact"]]))
        fd, ex = runs["2-point"][0][1], runs["exact"][0][1]
        delta = np.r_[ex.linear - fd.linear, ex.params - fd.params]
        distance = float(np.sqrt(delta @ np.linalg.solve(ex.covariance, delta)))
        print(f"| {n:.0e} | {repeats} | {t_start:.2f} | {t_fd:.2f} | {t_ex:.2f} | "
              f"{t_fd / t_ex:.1f} | {fd.nit} / {ex.nit} | {fd.nfev} / {ex.nfev} | "
              f"{(ex.sse - fd.sse) / fd.sse:+.1e} | {abs(ex.params[0] - fd.params[0]):.1e} | "
              f"{distance:.1e} | {os.getloadavg()[0]:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
