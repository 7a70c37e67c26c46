"""Many records, one call: fohw.stream_fits serially, on a process pool and on dask, with peak memory.

    python benchmarks/bench_batch.py [--records 1000] [--samples 2000] [--workers 2]
                                     [--kind tf|lagged] [--modes serial,process,dask,dask*25,process/4]

Each record is a different plant of a fleet, simulated with its own seed and fitted on its own:

* ``--kind tf`` (default): a fractional lag ``b0 / (a0 s^alpha + 1)`` at dt = 0.05 (gain, time
  constant and order drawn per record), fitted by ``fohw.fit`` from one start model with
  ``order_grid=1, n_starts=1`` (about 0.1 s a record here);
* ``--kind lagged``: the paper's lagged kind (na = nb = 1, linear bases), by ``fohw.identify``.

The records come from a generator (nothing holds them all) and each outcome is dropped once
read, as a user streaming to disk would. Each mode runs in a fresh interpreter, so its peak
resident memory is its own:

* ``parent``: ``ru_maxrss`` of the interpreter that calls ``stream_fits``;
* ``workers``: the largest peak over the workers (a ``ProcessPoolExecutor``'s processes: their
  ``VmHWM`` in ``/proc`` just before shut-down, else ``RUSAGE_CHILDREN`` after it; dask workers:
  their own ``ru_maxrss``, asked with ``client.run``);
* ``process/4``: the process pool on a quarter of the records: the parent's peak should not
  grow with the number of records;
* ``dask*25``: dask with 25 records per task (``chunksize=25``);
* ``+files`` (e.g. ``dask*25+files``): the records written as CSV files before the clock
  starts, passed as paths that the workers read, and the results written by the workers
  (``out_dir``), as on a cluster with shared storage (the hash is of the files read back after
  the clock stops).

Throughput on a shared machine depends on what else runs, so the table also gives the CPU time
per record of the calling interpreter (for dask it also runs the LocalCluster's scheduler) and
of the workers together (not dask's nanny processes), measured after the workers are up: the
numbers to extrapolate from.

Every mode's fits are hashed in record order (every free value and the SSE, as ``repr``); the
column ``same`` says whether the hash equals the serial run's. BLAS runs one thread per process.
Needs ``pip install 'fohw[distributed]'`` for the dask mode (skipped without it).
"""

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fohw  # noqa: E402

DT = 0.05


MAKING = [0.0]                 # CPU seconds spent making the records, in the caller


def records(n_records, n_samples, kind):
    """The fleet, one record at a time: ``(u, y)`` of plant ``k`` (seed ``k``)."""
    for k in range(n_records):
        start = time.process_time()
        rng = np.random.default_rng(k)
        u = np.repeat(rng.standard_normal(n_samples // 10 + 1), 10)[:n_samples]
        if kind == "tf":
            gain, tau, alpha = rng.uniform(0.5, 2.0), rng.uniform(0.5, 3.0), rng.uniform(0.4, 0.9)
            plant = fohw.FractionalTF([gain], [0.0], [tau, 1.0], [alpha, 0.0], dt=DT)
        else:
            plant = fohw.HammersteinWiener([rng.uniform(0.1, 0.4)], [rng.uniform(0.5, 1.5)],
                                           [1.0], [1.0], rng.uniform(0.3, 0.8))
        y = plant.simulate(u) + 0.01 * rng.standard_normal(n_samples)
        MAKING[0] += time.process_time() - start
        yield u, y


def fit_options(kind):
    if kind == "tf":
        start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=DT)
        return dict(model=start, order_grid=1, n_starts=1)
    return dict(na=1, nb=1, f_basis=1, g_basis=1)


def fingerprint(result):
    if isinstance(result, fohw.FitResult):
        values = [result.parameters[name].value for name in result.free_names]
    else:
        values = list(result.theta) + [result.alpha]
    return repr([float(v) for v in values] + [float(result.sse)])


def _cpu(who):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def _worker_cpu():
    """CPU seconds of this (dask worker) process so far."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _peak_mb(kb):
    return kb / 1024.0                     # ru_maxrss and VmHWM are in KiB on Linux


def _vmhwm_kb(pid):
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def run_mode(mode, n_records, n_samples, kind, workers, chunksize=1, files=False):
    """One mode in this interpreter: wall time, fits, hash and peak memory (a dict)."""
    options = fit_options(kind)
    source = records(n_records, n_samples, kind)
    if files:                            # written before the clock starts; read by the workers
        import tempfile

        from fohw.io.files import write_text
        from fohw.io.text import format_table

        folder = tempfile.mkdtemp(prefix="bench_batch_")
        paths = []
        for k, (u, y) in enumerate(source):
            paths.append(os.path.join(folder, f"{k:06d}.csv"))
            write_text(format_table({"u": u, "y": y}), paths[-1])
        os.mkdir(os.path.join(folder, "out"))
        source, options = paths, dict(options, out_dir=os.path.join(folder, "out"))
        MAKING[0] = 0.0
    digest, ok, failed, busy = hashlib.sha256(), 0, 0, 0.0
    cluster = client = pool = None
    worker_kb = None
    if mode == "dask":
        from distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
        client.run(lambda: None)                         # workers up before the clock starts
        executor = client
    elif mode == "process":
        from fohw._parallel import process_pool

        pool = process_pool(workers)
        pool.submit(int, 0).result()                     # workers up before the clock starts
        executor = pool
    else:
        executor = None
    cpu0 = _cpu(resource.RUSAGE_SELF)
    workers_cpu0 = sum(client.run(_worker_cpu).values()) if client is not None else 0.0
    t0 = time.perf_counter()
    saved = []
    for item in fohw.stream_fits(source, executor=executor,
                                 total=n_records, progress=False, chunksize=chunksize,
                                 **options):
        if item.ok and files:
            ok += 1
            saved.append(item.path)
        elif item.ok:
            ok += 1
            digest.update(fingerprint(item.result).encode())
        else:
            failed += 1
            digest.update(item.message.encode())
        busy += item.seconds
    wall = time.perf_counter() - t0
    cpu = _cpu(resource.RUSAGE_SELF) - cpu0
    for path in saved:                   # after the clock: the fits the workers wrote
        digest.update(fingerprint(fohw.load_result(path)).encode())
    if files:
        import shutil

        shutil.rmtree(folder)
    workers_cpu = None
    if pool is not None:
        peaks = [_vmhwm_kb(pid) for pid in list(pool._processes)]
        pool.shutdown(wait=True)
        if all(p is not None for p in peaks) and peaks:
            worker_kb = max(peaks)
        else:
            worker_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        workers_cpu = _cpu(resource.RUSAGE_CHILDREN)        # the pool's workers, joined
    if client is not None:
        workers_cpu = sum(client.run(_worker_cpu).values()) - workers_cpu0
        peaks = client.run(lambda: __import__("resource").getrusage(
            __import__("resource").RUSAGE_SELF).ru_maxrss)
        worker_kb = max(peaks.values())
        client.close()
        cluster.close()
    return {"mode": mode, "records": n_records, "wall": wall, "ok": ok, "failed": failed,
            "busy": busy, "hash": digest.hexdigest(), "cpu": cpu, "workers_cpu": workers_cpu,
            "making": MAKING[0],
            "parent_mb": _peak_mb(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss),
            "worker_mb": None if worker_kb is None else _peak_mb(worker_kb)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=1000)
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--kind", choices=["tf", "lagged"], default="tf")
    ap.add_argument("--modes", default="serial,process,dask,dask*25,process/4",
                    help="comma-separated: serial, process, dask; '/4' on a quarter of the "
                    "records, '*K' with K records per task (chunksize)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--chunksize", type=int, default=1, help=argparse.SUPPRESS)
    ap.add_argument("--files", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(run_mode(args.child, args.records, args.samples, args.kind,
                                  args.workers, args.chunksize, args.files)))
        return 0
    rows = []
    for mode in args.modes.split(","):
        n = args.records // 4 if mode.endswith("/4") else args.records
        files = mode.endswith("+files")
        child, _, chunk = mode.split("/")[0].removesuffix("+files").partition("*")
        chunk = int(chunk or 1)
        if child == "dask":
            try:
                import distributed  # noqa: F401
            except ImportError:
                print("dask: skipped (pip install 'fohw[distributed]')", file=sys.stderr)
                continue
        cmd = [sys.executable, __file__, "--child", child, "--records", str(n), "--samples",
               str(args.samples), "--workers", str(args.workers), "--kind", args.kind,
               "--chunksize", str(chunk)] + (["--files"] if files else [])
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
        row = json.loads(out.strip().splitlines()[-1])
        row["label"] = mode
        rows.append(row)
        print(f"{mode}: {row['wall']:.1f} s", file=sys.stderr, flush=True)
    serial = next((r for r in rows if r["label"] == "serial"), None)
    what = ("FractionalTF b0/(a0 s^alpha + 1), fohw.fit order_grid=1 n_starts=1"
            if args.kind == "tf" else "lagged kind, fohw.identify na=nb=1")
    print(f"{what}; N = {args.samples}; {args.workers} workers; load average "
          f"{os.getloadavg()[0]:.1f} at the end")
    print("| mode | records | wall (s) | records/s | vs serial | wall per fit, in the worker "
          "(ms) | CPU per record: caller (ms) | of which making the record (ms) | "
          "CPU per record: workers (ms) | failed | "
          "peak RSS caller (MB) | peak RSS per worker (MB) | same fits |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        rate = r["records"] / r["wall"]
        ratio = rate / (serial["records"] / serial["wall"]) if serial else float("nan")
        same = "—" if serial is None or r["records"] != serial["records"] else \
            str(r["hash"] == serial["hash"])
        worker = "—" if r["worker_mb"] is None else f"{r['worker_mb']:.0f}"
        workers_cpu = "—" if r["workers_cpu"] is None else \
            f"{1000 * r['workers_cpu'] / r['records']:.1f}"
        print(f"| {r['label']} | {r['records']} | {r['wall']:.1f} | {rate:.2f} | {ratio:.2f} | "
              f"{1000 * r['busy'] / r['records']:.0f} | {1000 * r['cpu'] / r['records']:.1f} | "
              f"{1000 * r['making'] / r['records']:.1f} | {workers_cpu} | {r['failed']} | "
              f"{r['parent_mb']:.0f} | {worker} | {same} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
