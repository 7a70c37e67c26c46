"""Simulation time and step-response accuracy of fohw.FractionalTF, beside the PyPI `fotf` package;
the time of fohw.fit of a FractionalTF beside the fitter it replaced.

    python benchmarks/bench_transfer_function.py [--fotf-python /work/venv-fotf/bin/python] [--fast]
    python benchmarks/bench_transfer_function.py --fit-only --old-src /tmp/old/src [--repeats 7]

fohw: medians of repeated simulations at 1e4, 1e5, 1e6 samples (1/(s^0.5 + 1), random input), and
the step-response error at every sample against the exact solutions of 1/(s^0.5 + 1)
(1 - exp(t) erfc(sqrt t)) and 1/(s + 1) (1 - exp(-t)).

Fit: ``--old-src`` is the ``src`` of a fohw checkout that still has ``fit_fractional_tf`` (commit
cd24403: ``git worktree add /tmp/old cd24403``); it is imported as a separate package
(``fohw_old``) and both fitters run the same workloads, interleaved, in this one process. Printed:
each workload's median times, the median of the per-repeat ratios new / old, and both SSEs.

`fotf` 0.1.0 needs Python >= 3.12 and is never a fohw dependency: install it in a separate
environment (``python3.12 -m venv /work/venv-fotf && /work/venv-fotf/bin/pip install fotf``) and
pass its interpreter. Its `step_response` is run as published (it passes the numerator where its
solver expects the denominator) and, to judge the solver itself, with the two swapped back.
"""

import argparse
import importlib.util
import json
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.special import erfcx

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from transfer_function_figures import _start  # noqa: E402

import fohw  # noqa: E402

SYSTEMS = {
    "1/(s^0.5+1)": (([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), lambda t: 1 - erfcx(np.sqrt(t))),
    "1/(s+1)": (([1.0], [0.0], [1.0, 1.0], [1.0, 0.0]), lambda t: 1 - np.exp(-t)),
}
T_END = 5.0

FOTF_SCRIPT = r"""
import json, sys, time
import numpy as np
import fotf
out = {}
systems = {"1/(s^0.5+1)": ((1.0,), (0.0,), (1.0, 1.0), (0.5, 0.0)),
           "1/(s+1)": ((1.0,), (0.0,), (1.0, 1.0), (1.0, 0.0))}
sizes = json.loads(sys.argv[1])
for name, (b, nb, a, na) in systems.items():
    G = fotf.FOTF(num=b, nnum=nb, den=a, nden=na)
    for n in sizes:
        t = np.linspace(0.0, 5.0, n)
        t0 = time.perf_counter(); y = G.step_response(t); dt = time.perf_counter() - t0
        t1 = time.perf_counter()
        y2 = fotf.fode_sol9(np.array(a), np.array(na), np.array(b), np.array(nb), np.ones(n), t, 2)
        dt2 = time.perf_counter() - t1
        out[f"{name}|{n}"] = dict(time=dt, y=y.tolist() if n <= 20001 else None, time_swapped=dt2,
                                  y_swapped=y2.tolist() if n <= 20001 else None)
print(json.dumps(out))
"""


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def fohw_timings(sizes):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=1e-3)
    rng = np.random.default_rng(0)
    rows = []
    for n, repeats in sizes:
        u = rng.standard_normal(n)
        G.simulate(u[:1000])
        rows.append((n, median_time(lambda u=u: G.simulate(u), repeats)))
    return rows


def fohw_step_errors(n):
    out = {}
    for name, (args, exact) in SYSTEMS.items():
        t = np.linspace(0.0, T_END, n)
        y = fohw.FractionalTF(*args).step(t)
        out[name] = (float(np.max(np.abs(y[1:] - exact(t[1:])))), float(y[-1]), float(exact(T_END)))
    return out


def run_fotf(python, sizes, timeout):
    try:
        proc = subprocess.run([python, "-c", FOTF_SCRIPT, json.dumps(sizes)], capture_output=True,
                              text=True, timeout=timeout)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return None, f"fotf did not complete: {exc}"
    if proc.returncode != 0:
        return None, f"fotf failed: {proc.stderr[-500:]}"
    return json.loads(proc.stdout), ""


def load_old_fohw(src):
    """The fohw package under ``src`` imported as ``fohw_old`` (beside this tree's ``fohw``)."""
    init = Path(src) / "fohw" / "__init__.py"
    spec = importlib.util.spec_from_file_location("fohw_old", init,
                                                  submodule_search_locations=[str(init.parent)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["fohw_old"] = module
    spec.loader.exec_module(module)
    return module


def fit_workloads(old):
    """``{name: (old call, new call)}``: the identifications of docs/transfer_functions.md."""
    rng = np.random.default_rng(2025)
    h, n = 0.05, 2000
    u = rng.standard_normal(n)
    records = []
    for G in (fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0]),
              fohw.FractionalTF([1.5], [0.0], [0.8, 1.2, 1.0], [1.4, 0.45, 0.0])):
        y0 = G.simulate(u, dt=h)
        records.append(y0 + 0.05 * np.std(y0) * rng.standard_normal(n))
    y1, y2 = records
    pos = {"a0": (0, np.inf), "a1": (0, np.inf)}
    return {
        "1/(a s^alpha + 1), N = 2000": (
            lambda: old.fit_fractional_tf(u, y1, dt=h, num_orders=[0.0], den_orders=[0.5, 0.0]),
            lambda: fohw.fit(_start([0.0], [0.5, 0.0], h), u, y1)),
        "two fractional terms, N = 2000": (
            lambda: old.fit_fractional_tf(u, y2, dt=h, num_orders=[0.0], den_orders=[1.0, 0.6, 0.0],
                                          bounds=pos),
            lambda: fohw.fit(_start([0.0], [1.0, 0.6, 0.0], h, bounds=pos), u, y2)),
        "1/(a s^alpha + 1), grid 3, 1 start, N = 1000": (
            lambda: old.fit_fractional_tf(u[:1000], y1[:1000], dt=h, num_orders=[0.0],
                                          den_orders=[0.5, 0.0], order_grid=3, n_refine=1),
            lambda: fohw.fit(_start([0.0], [0.5, 0.0], h), u[:1000], y1[:1000], order_grid=3,
                             n_starts=1)),
    }


def fit_timings(old_src, repeats):
    """Median times of fohw.fit and of the old fit_fractional_tf, interleaved; their SSEs."""
    old = load_old_fohw(old_src)
    print(f"## fohw.fit of a FractionalTF against fit_fractional_tf ({old_src}), {repeats} repeats\n")
    print("| workload | old [s] | fohw.fit [s] | median ratio | old SSE | fohw.fit SSE |")
    print("|---|---:|---:|---:|---:|---:|")
    ratios = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, (run_old, run_new) in fit_workloads(old).items():
            t_old, t_new = [], []
            for _ in range(repeats):
                t0 = time.perf_counter()
                fit_old = run_old()
                t_old.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                fit_new = run_new()
                t_new.append(time.perf_counter() - t0)
            ratio = float(np.median(np.array(t_new) / np.array(t_old)))
            ratios.append(ratio)
            print(f"| {name} | {np.median(t_old):.3f} | {np.median(t_new):.3f} | {ratio:.2f} | "
                  f"{fit_old.sse:.6g} | {fit_new.sse:.6g} |")
    print(f"\nmedian ratio over the workloads: {np.median(ratios):.2f} (target <= 1.1)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fotf-python", default="/work/venv-fotf/bin/python")
    parser.add_argument("--fast", action="store_true", help="1e4 and 1e5 samples only")
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("--old-src", help="src of a fohw checkout with fit_fractional_tf (cd24403)")
    parser.add_argument("--repeats", type=int, default=7, help="repeats of each fit workload")
    parser.add_argument("--fit-only", action="store_true", help="only the fit timings")
    args = parser.parse_args()

    if args.old_src:
        fit_timings(args.old_src, args.repeats)
        print()
    elif args.fit_only:
        parser.error("--fit-only needs --old-src")
    if args.fit_only:
        return

    sizes = [(10_000, 9), (100_000, 5)] + ([] if args.fast else [(1_000_000, 3)])
    print("## fohw.FractionalTF.simulate, 1/(s^0.5 + 1), median wall time\n")
    print("| samples | fohw [s] |\n|---:|---:|")
    for n, sec in fohw_timings(sizes):
        print(f"| {n:,} | {sec:.4f} |")

    fotf_sizes = [1001, 10001, 20001]
    fotf, why = run_fotf(args.fotf_python, fotf_sizes, args.timeout) if Path(args.fotf_python).exists() \
        else (None, f"no interpreter at {args.fotf_python}: fotf not measured")
    print("\n## Step response on t in [0, 5] (n samples), max error over the samples t > 0\n")
    print("| system | n | fohw max error | fohw y(5) | fotf max error | fotf y(5) | fotf (num/den swapped "
          "back) max error | exact y(5) | fotf time [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in fotf_sizes:
        ours = fohw_step_errors(n)
        for name, (_, exact) in SYSTEMS.items():
            err, y5, ex5 = ours[name]
            t = np.linspace(0.0, T_END, n)
            if fotf is not None:
                rec = fotf[f"{name}|{n}"]
                yf, ys = np.array(rec["y"]), np.array(rec["y_swapped"])
                ferr = np.max(np.abs(yf[1:] - exact(t[1:])))
                serr = np.max(np.abs(ys[1:] - exact(t[1:])))
                extra = f"{ferr:.3g} | {yf[-1]:.4f} | {serr:.3g} | {ex5:.4f} | {rec['time']:.2f}"
            else:
                extra = f"– | – | – | {ex5:.4f} | –"
            print(f"| {name} | {n:,} | {err:.3g} | {y5:.4f} | {extra} |")
    if why:
        print(f"\n{why}")
    print(f"\nPython {sys.version.split()[0]}, numpy {np.__version__}, fohw {fohw.__version__}")


if __name__ == "__main__":
    main()
