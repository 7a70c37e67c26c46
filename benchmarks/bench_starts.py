"""output_error's default chain of starts (issue 26) against the code before it, in one run.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_starts.py [--baseline main] [--rounds 1] [--full]
        [--workloads fit,grid]

The source tree of ``--baseline`` (``git archive REV src``, as ``bench_simulator.py --workloads``
does) and this one run the same two workloads alternately, each in a fresh process:

``grid``
    The docs' cascaded-tanks selection grid (``docs/real_data.md``): every candidate fitted by
    ``method="output_error"`` with an offset, the estimation mean as operating point and
    ``dt = 4`` on estimation samples 0-767, serially. ``--full``: na = nb in {1, 2, 3}, f in
    {1, 2, 3}, g in {1, 2}, the four classes of orders (72 fits); default: na = nb in {1, 2},
    f in {1, 2}, g = 1 (16 fits). Printed: the time of each tree, their ratio, and how many
    fits ended MAX_ITER and how many fractional ones ended above their orders-0 candidate.
``fit``
    One output-error fit of the tanks (na = nb = 2, f = g = 2, commensurate, N = 1024) against
    one free-run simulation of the same structure: ``time / (nfev * t_sim)``, the cost of the
    fit in simulations beyond the simulations it counts.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

WORKLOAD = r"""
import json, statistics, sys, time, warnings
import numpy as np
import fohw
warnings.simplefilter("ignore")
which, full = sys.argv[1], sys.argv[2] == "1"
e = fohw.datasets.cascaded_tanks().estimation
kw = dict(offset=True, operating_point="mean", dt=4.0, method="output_error")
if which == "grid":
    u, y = e.u[:768], e.y[:768]
    ns, fs, gs = ([1, 2, 3], [1, 2, 3], [1, 2]) if full else ([1, 2], [1, 2], [1])
    cands = [dict(na=n, nb=n, f_basis=f, g_basis=g, orders=o) for n in ns for f in fs for g in gs
             for o in (0, "commensurate", "mixed", "per_lag")]
    fohw.identify(u, y, **cands[1], **kw)              # compile and load outside the clock
    t0 = time.perf_counter()
    out = []
    for c in cands:
        try:
            r = fohw.identify(u, y, **c, **kw)
            out.append((r.status.name, r.details["simulation_sse"]))
        except Exception as exc:
            out.append((type(exc).__name__, float("nan")))
    dt = time.perf_counter() - t0
    maxiter = sum(s == "MAX_ITER" for s, _ in out)
    worse = sum(out[i][1] > out[i - i % 4][1] * (1 + 1e-6) for i in range(len(out)) if i % 4)
    print(json.dumps({"time": dt, "n": len(out), "max_iter": maxiter, "worse": worse}))
else:
    c = dict(na=2, nb=2, f_basis=2, g_basis=2, orders="commensurate")
    r = fohw.identify(e.u, e.y, **c, **kw)
    times = []
    for _ in range(3):
        t0 = time.perf_counter(); r = fohw.identify(e.u, e.y, **c, **kw)
        times.append(time.perf_counter() - t0)
    s = fohw.Structure.make(**c, offset=True, dt=4.0)
    from fohw.model.lagged.simulation import simulate_predictor
    lin, par = np.r_[r.theta, r.offset], np.array([0.3])
    sims = []
    for _ in range(20):
        t0 = time.perf_counter(); simulate_predictor(s, lin, par, e.u - e.u.mean())
        sims.append(time.perf_counter() - t0)
    t, ts = statistics.median(times), statistics.median(sims)
    print(json.dumps({"time": t, "nfev": r.nfev, "t_sim": ts, "ratio": t / (r.nfev * ts),
                      "sse": r.details["simulation_sse"]}))
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="main", help="git revision of the 'before' tree")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--full", action="store_true", help="the docs' full 72-candidate grid")
    ap.add_argument("--workloads", default="fit,grid",
                    help="comma-separated: fit, grid (the fit workload needs a baseline with "
                         "fohw.model.lagged.simulation, i.e. after issue 23)")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="fohw_baseline_"))
    archive = subprocess.run(["git", "archive", args.baseline, "src"], cwd=HERE.parent,
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    trees = {"before": str(tmp / "src"), "after": str(HERE.parent / "src")}
    print(f"baseline {args.baseline}; {args.rounds} round(s), fresh processes, alternating; "
          f"cpus {os.cpu_count()}, OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    for which in args.workloads.split(","):
        res = {k: [] for k in trees}
        for _ in range(args.rounds):
            for tree, src in trees.items():
                env = dict(os.environ, PYTHONPATH=src)
                out = subprocess.run([sys.executable, "-c", WORKLOAD, which, str(int(args.full))],
                                     env=env, capture_output=True, text=True, check=True)
                res[tree].append(json.loads(out.stdout.splitlines()[-1]))
        for tree, rows in res.items():
            med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
            print(which, tree, json.dumps(med), flush=True)
        key = "time"
        b = statistics.median(r[key] for r in res["before"])
        a = statistics.median(r[key] for r in res["after"])
        print(f"{which}: time after / before = {a / b:.2f}", flush=True)


if __name__ == "__main__":
    main()
