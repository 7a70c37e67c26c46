"""output_error's solver: the exact free-run sensitivity against finite differences (one run, medians).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_output_error.py [--repeats 3] [--sizes 1e3,1e4,1e5]
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_output_error.py --sensitivity [--sizes 1e4,1e5,1e6]
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_output_error.py --leaves [--sizes 1e5,1e6]

On the paper's example (uniform input, seed 0, N samples) the varpro start is computed once per
N; from it the simulation-error fit (``fit_output_error``) runs with the exact Jacobian (the
default: ``-S`` from ``fohw.model.lagged.sensitivity.simulation_jacobian``) and with scipy's forward
differences (``tests/reference_estimators.py``, the code before, one simulation per parameter per
Jacobian), interleaved, in this process. Printed: medians of ``--repeats`` runs (one run at
N >= 1e5), their ratio, the solver's iterations (Jacobians), the simulations each path ran
(residuals, plus one per parameter per Jacobian for finite differences, plus one per exact
Jacobian), and how far apart the two optima are: the relative difference of the simulation SSE,
|delta alpha|, and the distance of the estimates in the metric of their covariance
``s^2 (S^T S)^-1`` (scipy's ftol = 1e-8 allows about ``2 sqrt(1e-8 (N - d))``). Whether the
simulator and the sensitivity run their compiled leaves is as in any process: numba installed
and not ``FOHW_NO_NUMBA=1``, loaded lazily (``fohw.model._compiled``); the line above the table
says whether they were loaded by the end.

``--sensitivity``: one sensitivity solve against one simulation, the paper's model at its true
parameters (``fohw.model.lagged.sensitivity.simulation_jacobian``, which simulates, builds the
one-step Jacobian ``E`` and solves the recursion, against ``fohw.simulate``), with the compiled
leaves (loaded beforehand, the load reported apart) and with the pure ones (``_compiled.ENABLED``
switched off), interleaved, medians of ``--repeats`` (one run at N >= 1e6); printed: the times,
``k`` = sensitivity / simulation, and the largest difference between the two paths' ``S`` (not
0: the simulator's default leaves differ, 512 compiled and 256 pure, so ``y`` and ``E`` differ
by rounding; the sensitivity's own leaves are both 128 and equal at equal input).

``--leaves``: the recursion alone (``_solve_feedback`` on the same ``E``) at leaf sizes 64..1024,
compiled and pure (pure at N <= 1e5 only), to choose ``sensitivity.LEAF_SIZE`` and
``LEAF_SIZE_COMPILED``.
"""

import argparse
import contextlib
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from reference_estimators import finite_difference_output_error  # noqa: E402

import fohw  # noqa: E402
from fohw.estimators.output_error import fit_output_error  # noqa: E402
from fohw.estimators.varpro import VarproOptions, separable_least_squares  # noqa: E402
from fohw.model import _compiled  # noqa: E402
from fohw.model.lagged import sensitivity  # noqa: E402

# ruff: noqa: B023   (the timed callables run inside their loop iteration)

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def fit(builder, start, jacobian):
    t0 = time.perf_counter()
    fd = jacobian == "2-point"
    with warnings.catch_warnings(), (finite_difference_output_error() if fd
                                     else contextlib.nullcontext()):
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        res = fit_output_error(builder, start.linear, start.params, lower=np.array([0.0]),
                               upper=np.array([1.0]), max_nfev=100)
    return time.perf_counter() - t0, res


def timed(fns, repeats):
    """Medians over ``repeats`` rounds, each round running every callable once (interleaved)."""
    times = {name: [] for name in fns}
    outs = {}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            outs[name] = fn()
            times[name].append(time.perf_counter() - t0)
    return {name: float(np.median(t)) for name, t in times.items()}, outs


def with_leaf(compiled, fn):
    """``fn`` with the compiled leaves switched on or off for its duration."""
    def run():
        saved = _compiled.ENABLED
        _compiled.ENABLED = compiled
        try:
            return fn()
        finally:
            _compiled.ENABLED = saved
    return run


def paper_input(n):
    m = fohw.datasets.paper_model()
    return m, np.random.default_rng(0).uniform(-np.sqrt(3), np.sqrt(3), n)


def sensitivity_stage(sizes, repeats):
    t0 = time.perf_counter()
    if _compiled.load() is None:
        raise SystemExit("--sensitivity needs the compiled leaves (numba, FOHW_NO_NUMBA unset)")
    print(f"compiled leaves loaded in {time.perf_counter() - t0:.2f} s (not in the times)\n")
    print("| N | runs | simulate, compiled [s] | sensitivity, compiled [s] | k compiled | "
          "simulate, pure [s] | sensitivity, pure [s] | k pure | pure / compiled (sensitivity) | "
          "max abs diff of S (simulator leaves 512 / 256) | load |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        m, u = paper_input(n)

        def jac():
            return sensitivity.simulation_jacobian(m.structure, m.linear, m.nonlinear, u)[1]

        def sim():
            return fohw.simulate(m, u)

        reps = repeats if n < 1_000_000 else 1
        t, out = timed({"sim_c": with_leaf(True, sim), "jac_c": with_leaf(True, jac),
                        "sim_p": with_leaf(False, sim), "jac_p": with_leaf(False, jac)}, reps)
        diff = float(np.max(np.abs(out["jac_c"] - out["jac_p"])))
        print(f"| {n:.0e} | {reps} | {t['sim_c']:.3f} | {t['jac_c']:.3f} | "
              f"{t['jac_c'] / t['sim_c']:.1f} | {t['sim_p']:.3f} | {t['jac_p']:.3f} | "
              f"{t['jac_p'] / t['sim_p']:.1f} | {t['jac_p'] / t['jac_c']:.1f} | {diff:.1e} | "
              f"{os.getloadavg()[0]:.2f} |", flush=True)
        del out


def leaves_stage(sizes, repeats, candidates=(64, 128, 256, 512, 1024)):
    if _compiled.load() is None:
        raise SystemExit("--leaves needs the compiled leaves (numba, FOHW_NO_NUMBA unset)")
    print("| N | leaf | compiled [s] | pure [s] | load |")
    print("|---:|---:|---:|---:|---:|")
    for n in sizes:
        m, u = paper_input(n)
        _, E, lags, betas, coefs = sensitivity._feedback_problem(m.structure, m.linear,
                                                                 m.nonlinear, u)
        fns = {}
        for leaf in candidates:
            fns["compiled", leaf] = (lambda leaf=leaf: sensitivity._solve_feedback(
                E, lags, betas, coefs, kernel="compiled", leaf_size=leaf))
            if n <= 100_000:
                fns["pure", leaf] = (lambda leaf=leaf: sensitivity._solve_feedback(
                    E, lags, betas, coefs, kernel="pure", leaf_size=leaf))
        t, _ = timed(fns, repeats if n < 1_000_000 else 1)
        for leaf in candidates:
            pure = f"{t['pure', leaf]:.3f}" if ("pure", leaf) in t else "-"
            print(f"| {n:.0e} | {leaf} | {t['compiled', leaf]:.3f} | {pure} | "
                  f"{os.getloadavg()[0]:.2f} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sizes", default=None)
    ap.add_argument("--sensitivity", action="store_true",
                    help="one sensitivity solve against one simulation instead")
    ap.add_argument("--leaves", action="store_true", help="time the solve's leaf sizes instead")
    args = ap.parse_args(argv)
    default = "1e4,1e5,1e6" if args.sensitivity else "1e5,1e6" if args.leaves else "1e3,1e4,1e5"
    sizes = [int(float(s)) for s in (args.sizes or default).split(",")]
    threads = {k: os.environ.get(k, "unset") for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    print(f"BLAS threads: {threads}; cores: {os.cpu_count()}; load average at start "
          f"{os.getloadavg()[0]:.2f}; FOHW_NO_NUMBA={os.environ.get('FOHW_NO_NUMBA', 'unset')}; "
          f"medians of {args.repeats} runs\n")
    if args.sensitivity:
        sensitivity_stage(sizes, args.repeats)
        return 0
    if args.leaves:
        leaves_stage(sizes, args.repeats)
        return 0
    print("| N | runs | varpro start [s] | finite differences [s] | exact [s] | ratio | "
          "iterations (fd / exact) | simulations (fd / exact) | SSE rel. diff | "
          "abs diff of alpha | distance / sd | load |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        d = fohw.datasets.paper_example(n, random_state=0)
        builder = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, **STRUCT)
        t0 = time.perf_counter()
        start = separable_least_squares(builder, bounds=(np.array([0.0]), np.array([1.0])),
                                        options=VarproOptions())
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
    print(f"\ncompiled leaves loaded by the end: {_compiled._state['kernel'] is not None} "
          f"(load {_compiled._state['load_seconds'] or 0:.2f} s, inside the first timed fit "
          "that reached LOAD_AFTER)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
