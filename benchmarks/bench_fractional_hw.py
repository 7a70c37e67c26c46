"""fohw.fit of a FractionalHW against the kind's own fitter it replaced, in one run.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fractional_hw.py [--baseline REV] [--rounds 3]

The workloads are the fits of ``tests/test_wiener.py`` and ``docs/transfer_functions.md``:
``u -> u + 0.3 u^2 -> 1 / (2 s^0.6 + 1) -> h``, ``u`` uniform on [-2, 2], noise 0.01, ``dt =
0.05``, from the start ``den_orders = [0.5, 0.0]``, with ``h`` the identity, ``x - 0.2 x^2``
(N = 1000 and 2000) and a saturation. Each is timed in fresh processes, alternately with the
source tree of REV (default ``cd24403``, the last commit with ``fohw.fit_fractional_hw``; read
by ``git archive``) and with this one, ``--rounds`` times (median of 3 fits in each process).
Printed: the medians, their ratio (the issue's target is at most 1.1) and both fits' SSE
(the same minimum is expected).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMON = r"""
import json, statistics, sys, time, warnings
import numpy as np
import fohw
kind, n, seed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(seed)
u = rng.uniform(-2, 2, n)
noise = 0.01 * rng.standard_normal(n)
"""

OLD = COMMON + r"""
G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
out = {"identity": "identity", "polynomial": ("polynomial", [-0.2]),
       "saturation": ("saturation", [0.1, 0.45])}[kind]
y = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=out).simulate(u, dt=0.05) + noise
spec = {"identity": "identity", "polynomial": 2, "saturation": "saturation"}[kind]
def run():
    return fohw.fit_fractional_hw(u, y, dt=0.05, num_orders=[0.0], den_orders=[0.5, 0.0],
                                  f_basis=2, output_map=spec)
"""

NEW = COMMON + r"""
G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
hmap, params = {"identity": (None, None), "polynomial": (fohw.model.output_map.PolynomialMap(2), [-0.2]),
                "saturation": (fohw.model.output_map.Saturation(), [0.1, 0.45])}[kind]
y = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=hmap, output_params=params,
                      dt=0.05).simulate(u) + noise
limits = [float(np.min(y)), float(np.max(y))] if kind == "saturation" else None
start = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), p=[1.0, 0.0],
                          f_basis=2, output_map=hmap, output_params=limits, dt=0.05)
def run():
    return fohw.fit(start, u, y)
"""

TIME = r"""
times = []
for _ in range(3):
    t0 = time.perf_counter(); fit = run(); times.append(time.perf_counter() - t0)
print(json.dumps({"median": statistics.median(times), "sse": float(fit.sse)}))
"""

WORKLOADS = [("identity", 1000, 11), ("polynomial", 1000, 11), ("saturation", 1000, 11),
             ("polynomial", 2000, 7)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="cd24403")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    print(f"fohw bench_fractional_hw: baseline {args.baseline}, {args.rounds} alternating rounds, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}\n")
    print("| h | N | fit_fractional_hw [s] | fohw.fit [s] | new/old | SSE old | SSE new |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    ratios = []
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline, "src"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        trees = {"old": (str(Path(tmp) / "src"), OLD), "new": (str(ROOT / "src"), NEW)}
        for kind, n, seed in WORKLOADS:
            got = {k: [] for k in trees}
            sse = {}
            for _ in range(args.rounds):
                for name, (path, code) in trees.items():
                    env = dict(os.environ, PYTHONPATH=path)
                    out = subprocess.run([sys.executable, "-c", code + TIME, kind, str(n), str(seed)],
                                         capture_output=True, text=True, env=env, check=True)
                    r = json.loads(out.stdout.strip().splitlines()[-1])
                    got[name].append(r["median"])
                    sse[name] = r["sse"]
            old, new = statistics.median(got["old"]), statistics.median(got["new"])
            ratios.append(new / old)
            print(f"| {kind} | {n} | {old:.3f} | {new:.3f} | {new / old:.2f} | {sse['old']:.10g} | "
                  f"{sse['new']:.10g} |", flush=True)
    print(f"\nmedian ratio new/old over the workloads: {statistics.median(ratios):.2f}")


if __name__ == "__main__":
    main()
