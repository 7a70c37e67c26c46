"""Serial against dask.distributed on this machine: structure selection and a 1000-seed Monte Carlo.

    python benchmarks/bench_distributed.py [--workers 2] [--seeds 1000] [--quick]

Starts a dask.distributed.LocalCluster (one thread per worker process, one BLAS thread), runs
fohw.select_structure on the cascaded-tanks estimation record (12 output-error candidates) and
fohw.monte_carlo over --seeds records of the paper's example, once serially and once on the
cluster through ``client.get_executor()``, checks the tables are identical, and prints the wall
times and their ratio (one run each; the machine is shared, so read the ratio, not the seconds).
Needs ``pip install 'fohw[distributed]'``.
"""

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import fohw  # noqa: E402

DROP = ("seconds",)


def strip(rows):
    return [{k: v for k, v in r.items() if k not in DROP} for r in rows]


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=1000)
    ap.add_argument("--quick", action="store_true", help="4 candidates and 100 seeds")
    args = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    est = fohw.datasets.cascaded_tanks().estimation
    grid = {"na": [1, 2] if args.quick else [1, 2, 3], "f_basis": [2] if args.quick else [1, 2],
            "orders": [0, "mixed"]}
    common = dict(g_basis=1, method="output_error", offset=True, operating_point="mean", dt=4.0,
                  validation=256, progress=False)
    seeds = range(100 if args.quick else args.seeds)
    mc = dict(methods={"varpro": {"method": "varpro"}}, seeds=seeds,
              settings=[{"n_samples": 300}], progress=False)

    sel_serial, t_sel_serial = timed(lambda: fohw.select_structure(
        est, [dict(c, nb=c["na"]) for c in fohw.analysis.selection.expand_candidates(grid)],
        **common))
    mc_serial, t_mc_serial = timed(lambda: fohw.monte_carlo(**mc))
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        executor = client.get_executor()
        client.run(lambda: None)                       # workers up before timing
        sel_dask, t_sel_dask = timed(lambda: fohw.select_structure(
            est, [dict(c, nb=c["na"]) for c in fohw.analysis.selection.expand_candidates(grid)],
            executor=executor, **common))
        mc_dask, t_mc_dask = timed(lambda: fohw.monte_carlo(executor=executor, **mc))
    same_sel = strip(sel_serial.rows) == strip(sel_dask.rows)
    same_mc = strip(mc_serial) == strip(mc_dask)
    print(f"| job | serial (s) | dask, {args.workers} workers (s) | speed-up | identical |")
    print("|---|---:|---:|---:|---|")
    print(f"| select_structure, {len(sel_serial.rows)} output-error candidates (tanks) | "
          f"{t_sel_serial:.1f} | {t_sel_dask:.1f} | {t_sel_serial / t_sel_dask:.2f} | "
          f"{same_sel} |")
    print(f"| monte_carlo, {len(seeds)} seeds, varpro, N = 300 | {t_mc_serial:.1f} | "
          f"{t_mc_dask:.1f} | {t_mc_serial / t_mc_dask:.2f} | {same_mc} |")
    return 0 if same_sel and same_mc else 1


if __name__ == "__main__":
    raise SystemExit(main())
