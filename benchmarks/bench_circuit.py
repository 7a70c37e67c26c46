"""fohw.fit of an EquivalentCircuit against the circuit's former fitter, fit_circuit, in one run.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_circuit.py [--baseline REV] [--repeats 5]

The former fitter (``fohw.estimators.circuit_fit.fit_circuit``, deleted by issue 32) is imported
from the source tree of ``--baseline`` (``git archive REV``, default ``cd24403``, the last commit
that had it) under the package name ``fohw_old``; both run in this process, interleaved, on the
same records: two simulated cells of ``tests/test_circuit_fit.py`` and the LG M50LT drive cycle's
estimation half (``fohw.datasets.battery_cell().decimate(10)``, h = 1.5 s). Prints the median
CPU time of each (``time.process_time``: on a machine shared with other jobs it moves less than
wall-clock time; run with one BLAS thread), their ratio (new / old) and both fits' SSE.
"""

import argparse
import importlib.util
import io
import os
import platform
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

import fohw

# ruff: noqa: B023   (the timed closures run inside their loop iteration)

ROOT = Path(__file__).resolve().parents[1]


def load_old(rev):
    """The package ``fohw`` of commit ``rev``, imported as ``fohw_old``."""
    tmp = Path(tempfile.mkdtemp(prefix="fohw_old_"))
    blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/fohw"], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        tar.extractall(tmp, filter="data")
    pkg = tmp / "src" / "fohw"
    spec = importlib.util.spec_from_file_location("fohw_old", pkg / "__init__.py",
                                                  submodule_search_locations=[str(pkg)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["fohw_old"] = module
    spec.loader.exec_module(module)
    importlib.import_module("fohw_old.estimators.circuit_fit")
    return module


def record(n, seed, hold=20):
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-3, 1.2, n // hold + 1), hold)[:n]
    soc = 0.8 + np.concatenate([[0.0], np.cumsum(i[:-1])]) / (3600 * 5.0)
    return i, soc


def ocv(soc):
    return 3.3 + 0.9 * soc - 0.3 * (soc - 0.5) ** 2


def cases():
    """``(name, i, v, soc, h, elements, current_map, ocv, tau_bounds)`` of each workload."""
    true = fohw.EquivalentCircuit([fohw.RC(0.004, 6.0), fohw.ZARC(0.012, 150.0, 0.55)], r0=0.015,
                                  a=0.01, b=-0.02, c3=-1e-4, ocv=ocv)
    i, soc = record(4000, 1)
    v = true.simulate(np.column_stack([i, soc])) + 1e-3 * np.random.default_rng(2).standard_normal(i.size)
    out = [("simulated RC + ZARC + c3 i^3, N = 4000", i, v, soc, 1.0, ("rc", "zarc"), True, ocv,
            (1.0, 1000.0))]
    true = fohw.EquivalentCircuit([fohw.ZARC(0.012, 60.0, 0.5)], r0=0.015, ocv=ocv)
    i, soc = record(3000, 5)
    v = true.simulate(np.column_stack([i, soc])) + 1e-3 * np.random.default_rng(6).standard_normal(i.size)
    out.append(("simulated ZARC, N = 3000", i, v, soc, 1.0, ("zarc",), False, ocv, (1.0, 1000.0)))
    cell = fohw.datasets.battery_cell().decimate(10)
    est = slice(0, cell.n_samples // 2)
    for elements, tau_max in ((("zarc",), 1000.0), (("rc", "rc"), 2000.0)):
        out.append((f"LG M50LT {' + '.join(e.upper() for e in elements)}, tau <= {tau_max:g} s, "
                    f"N = {est.stop}", cell.i[est], cell.v[est], cell.soc[est], cell.dt, elements,
                    False, cell.ocv, (cell.dt, tau_max)))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="cd24403")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    old = load_old(args.baseline)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} logical cores, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"load {os.getloadavg()[0]:.2f}, baseline {args.baseline}, {args.repeats} repeats "
          "(interleaved; medians of CPU time)")
    ratios = []
    for name, i, v, soc, h, elements, cubic, ocv_map, tau_bounds in cases():
        u = np.column_stack([i, soc])
        model = fohw.EquivalentCircuit(elements, c3=0.0 if cubic else None, ocv=ocv_map, dt=h,
                                       tau_bounds=tau_bounds)

        def run_old():
            r = old.estimators.circuit_fit.fit_circuit(i, v, soc, h, elements, current_map=cubic,
                                                       ocv=ocv_map, tau_bounds=tau_bounds)
            return r.rss

        def run_new(grid):
            return fohw.fit(model, u, v, order_grid=grid).sse

        times = {"old": [], "new": [], "new, order_grid=5": []}
        sse = {}
        for _ in range(args.repeats):
            for key, run in (("old", run_old), ("new", lambda: run_new(1)),
                             ("new, order_grid=5", lambda: run_new(5))):
                t0 = time.process_time()
                sse[key] = run()
                times[key].append(time.process_time() - t0)
        med = {k: statistics.median(t) for k, t in times.items()}
        ratios.append(med["new"] / med["old"])
        print(f"\n{name}")
        for key in times:
            print(f"  {key:>18}: {med[key]:7.3f} s   SSE {sse[key]:.12g}"
                  + ("" if key == "old" else f"   ratio {med[key] / med['old']:.2f}"))
    print(f"\nmedian ratio fohw.fit (order_grid=1) / fit_circuit: {statistics.median(ratios):.2f}")


if __name__ == "__main__":
    main()
