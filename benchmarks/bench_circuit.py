"""The circuit fit's run time against a direct implementation at three lengths, and the former fitter.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_circuit.py [--part direct|spectrum|baseline|all]
                                                              [--repeats 3]

``--part direct`` (default; issue 37): ``fohw.fit`` of a one-ZARC circuit (OCV map known,
``tau`` in ``[dt, 1000 s]``, ``order_grid=1`` as ``examples/battery.py`` fits) to the LG M50LT
drive cycle (``fohw.datasets.battery_cell()``) at N = 2 061, 16 495 and 164 953 samples (block
means of 80 and 10 samples, and the full rate: h = 12, 1.5 and 0.15 s), run twice in one
process: as shipped, and with the circuit's two kernels replaced by a direct implementation.
"Direct" here is the literal per-sample loop of the element's recursion with its full GL sum,
``x[k] = (R i[k] - sum_{j=1}^{k} c[j] x[k-j]) / c[0]`` (one ``numpy.dot`` per sample, O(N^2)),
in place of :func:`fohw.model.kernels.series_divide` (O(N log^2 N)), and the direct O(N^2) sum
``sum_{j<=k} a[j] b[k-j]`` in place of the FFT product :func:`~fohw.model.kernels.causal_product`
(the Jacobian's convolutions). Everything else (scan, starts, optimiser, Jacobian formulas) is
the same code, so both fits take the same path and end at the same SSE (printed, to about 1e-12
relative). The direct fit at N = 164 953 would take tens of minutes of CPU; it is *estimated*,
not run: the number of kernel calls the shipped fit makes there (counted) times the direct
kernels' time per call at that N (measured once each), plus the fit's time outside the
kernels. The same estimate is printed at N = 16 495, where it can be checked against the
measured direct fit. Prints medians of CPU time (``time.process_time``) over ``--repeats``.

``--part spectrum``: ``fit_impedance`` (``fohw.estimators.impedance_fit``) of four circuits to the
cell's measured spectra at SOC 0.4, 0.5 and 0.6 (1e-3 to 0.33 Hz, with the OCV's capacitor), and
``fit_record_and_impedance`` of a ZARC
and of two RC elements to the drive cycle's estimation half (h = 1.5 s, tau <= 20 000 s) with
the SOC 0.6 spectrum, against the record alone: RMS relative impedance errors, validation RMSE
(free run of the second half), CPU times. The numbers of docs/battery.md's "Conventions and the
impedance fit".

``--part baseline``: ``fohw.fit`` against the circuit's former fitter
(``fohw.estimators.circuit_fit.fit_circuit``, deleted by issue 32), imported from the source
tree of ``--baseline`` (``git archive REV``, default ``cd24403``, the last commit that had it)
under the package name ``fohw_old``; both run in this process, interleaved, on the same
records: two simulated cells of ``tests/test_circuit_fit.py`` and the LG M50LT drive cycle's
estimation half (``fohw.datasets.battery_cell().decimate(10)``, h = 1.5 s). Prints the median
CPU time of each (on a machine shared with other jobs it moves less than wall-clock time; run
with one BLAS thread), their ratio (new / old) and both fits' SSE.
"""

import argparse
import contextlib
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
import fohw.model.circuit as circuit_module
from fohw.estimators.impedance_fit import fit_impedance, fit_record_and_impedance
from fohw.model import kernels

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


def direct_series_divide(f, c, *, leaf=None):
    """``sum_{j<=k} c[j] y[k-j] = f[k]`` by the literal per-sample recursion (one dot per sample)."""
    f = np.asarray(f, dtype=np.float64)
    n = f.shape[0]
    c = np.asarray(c, dtype=np.float64)[:n]
    c = np.concatenate([c, np.zeros(n - c.shape[0])])
    crev = c[::-1].copy()                       # crev[n - 1 - j] = c[j]: contiguous slices
    y = np.zeros(n)
    for k in range(n):
        y[k] = (f[k] - np.dot(y[:k], crev[n - 1 - k:n - 1])) / c[0]
    return y


def direct_causal_product(a, b, n=None):
    """``out[k] = sum_{j<=k} a[j] b[k-j]`` by the direct sum (one dot per sample)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = a.shape[0] if n is None else int(n)
    a = np.concatenate([a[:n], np.zeros(max(n - a.shape[0], 0))])
    x = np.zeros(n)
    x[:min(n, b.shape[0])] = b[:n]
    arev = a[::-1].copy()
    out = np.zeros(n)
    for k in range(n):
        out[k] = np.dot(x[:k + 1], arev[n - 1 - k:])
    return out


class Counted:
    """A kernel that counts its calls and their CPU time."""

    def __init__(self, fn):
        self.fn, self.calls, self.seconds = fn, 0, 0.0

    def __call__(self, *args, **kwargs):
        t0 = time.process_time()
        try:
            return self.fn(*args, **kwargs)
        finally:
            self.seconds += time.process_time() - t0
            self.calls += 1


@contextlib.contextmanager
def kernels_of_circuit(divide, product):
    """The circuit module's two kernels replaced (and restored after)."""
    saved = circuit_module.series_divide, circuit_module.causal_product
    circuit_module.series_divide, circuit_module.causal_product = divide, product
    try:
        yield
    finally:
        circuit_module.series_divide, circuit_module.causal_product = saved


def drive_cycle(factor):
    cell = fohw.datasets.battery_cell().decimate(factor)
    model = fohw.EquivalentCircuit(["zarc"], ocv=cell.ocv, dt=cell.dt, tau_bounds=(cell.dt, 1000.0))
    return model, np.column_stack([cell.i, cell.soc]), cell.v


def timed_fit(model, u, v, divide, product):
    """``(cpu seconds, sse, {kernel: (calls, seconds)})`` of one fit with the given kernels."""
    d, p = Counted(divide), Counted(product)
    with kernels_of_circuit(d, p):
        t0 = time.process_time()
        fit = fohw.fit(model, u, v, order_grid=1)
        seconds = time.process_time() - t0
    return seconds, fit.sse, {"divide": (d.calls, d.seconds), "product": (p.calls, p.seconds)}


def kernel_seconds(n, fn, repeats):
    """Median CPU time of one call of a kernel on a ZARC's weights at length ``n``."""
    c = 10.0 * fohw.gl_weights(0.5, n)
    c[0] += 1.0
    f = np.random.default_rng(0).standard_normal(n)
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn(f, c) if fn in (direct_series_divide, kernels.series_divide) else fn(c, f, n)
        times.append(time.process_time() - t0)
    return statistics.median(times)


def run_direct(repeats):
    print("fohw.fit of a one-ZARC circuit to the LG M50LT drive cycle: shipped kernels against the "
          "direct per-sample loops (O(N^2)); medians of CPU time")
    print("\n| N | h (s) | fohw.fit (s) | direct (s) | direct / fohw.fit | kernel calls "
          "(divide, product) | SSE fohw.fit | SSE direct |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = []
    for factor in (80, 10, 1):
        model, u, v = drive_cycle(factor)
        n = u.shape[0]
        fast = [timed_fit(model, u, v, kernels.series_divide, kernels.causal_product)
                for _ in range(repeats if n < 100_000 else max(1, repeats - 1))]
        fast_s = statistics.median(t for t, _, _ in fast)
        _, sse_fast, calls = fast[0]
        # Direct kernels, one call each at this N; the estimate of the direct fit from them.
        k_rep = 1 if n > 100_000 else repeats
        per_call = {"divide": kernel_seconds(n, direct_series_divide, k_rep),
                    "product": kernel_seconds(n, direct_causal_product, k_rep)}
        outside = statistics.median(t - sum(s for _, s in c.values()) for t, _, c in fast)
        estimate = outside + sum(calls[k][0] * per_call[k] for k in calls)
        if n < 100_000:
            direct = [timed_fit(model, u, v, direct_series_divide, direct_causal_product)
                      for _ in range(repeats if n < 10_000 else max(1, repeats - 2))]
            direct_s = statistics.median(t for t, _, _ in direct)
            sse_direct = f"{direct[0][1]:.12g}"
            text = f"{direct_s:.2f}"
            note = f" (estimate {estimate:.1f})"
        else:
            direct_s, sse_direct, text, note = estimate, "not run", f"~{estimate:.0f} (estimate)", ""
        rows.append((n, direct_s / fast_s))
        print(f"| {n} | {model.dt:g} | {fast_s:.2f} | {text}{note} | {direct_s / fast_s:.1f} | "
              f"{calls['divide'][0]}, {calls['product'][0]} | {sse_fast:.12g} | {sse_direct} |",
              flush=True)
    print("\nOne call of each kernel at the largest N (CPU seconds): "
          f"series_divide {kernel_seconds(rows[-1][0], kernels.series_divide, 3):.3f}, "
          f"causal_product {kernel_seconds(rows[-1][0], kernels.causal_product, 3):.3f}; direct: "
          f"{kernel_seconds(rows[-1][0], direct_series_divide, 1):.2f} and "
          f"{kernel_seconds(rows[-1][0], direct_causal_product, 1):.2f}")


def run_spectrum():
    import warnings

    from fohw.model.circuit import impedance_error

    cell = fohw.datasets.battery_cell()
    f = cell.impedance_f
    band = (f >= 1e-3) & (f <= 0.33)

    def slope(soc, step=0.01):
        return (cell.ocv(soc + step) - cell.ocv(soc - step)) / (2 * step)

    def z_at(soc):
        return cell.impedance[band, int(np.argmin(np.abs(cell.impedance_soc - soc)))]

    def error(fit, soc):
        _, _, rel = impedance_error(fit, f[band], z_at(soc), capacity=cell.capacity,
                                    ocv_slope=slope(soc))
        return 100 * float(np.sqrt(np.mean(rel ** 2)))

    print(f"\nfit_impedance to the measured spectra ({int(band.sum())} frequencies, 1e-3 to "
          "0.33 Hz), RMS relative error (%) at SOC 0.4 / 0.5 / 0.6, CPU s per fit")
    for elements in (["zarc"], ["rc", "rc"], ["rc", "zarc"], ["rc", "rc", "rc"]):
        model = fohw.EquivalentCircuit(elements, dt=1.5, tau_bounds=(1.5, 20000.0))
        errors, alphas, seconds = [], [], []
        for soc in (0.4, 0.5, 0.6):
            t0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fit = fit_impedance(model, f[band], z_at(soc), capacity=cell.capacity,
                                    ocv_slope=slope(soc))
            seconds.append(time.process_time() - t0)
            errors.append(error(fit, soc))
            alphas += [f"{fit.parameters[n].value:.3f}" for n in fit.parameters if n[:5] == "alpha"]
        print(f"  {' + '.join(e.upper() for e in elements):>13} ({fit.n_free} free): "
              f"{' / '.join(f'{e:.2f}' for e in errors)} %, alpha {' '.join(alphas) or '-'}, "
              f"{statistics.median(seconds):.2f} s")
    d = cell.decimate(10)
    n = d.n_samples
    est, val = slice(0, n // 2), slice(n // 2, n)
    u = np.column_stack([d.i, d.soc])
    print("\nThe record's estimation half alone and jointly with the SOC 0.6 spectrum "
          "(validation RMSE of the free run on the second half; impedance error at SOC 0.4/0.5/0.6)")
    for elements in (["zarc"], ["rc", "rc"]):
        model = fohw.EquivalentCircuit(elements, ocv=d.ocv, dt=d.dt, tau_bounds=(d.dt, 20000.0))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.process_time()
            alone = fohw.fit(model, u[est], d.v[est], order_grid=1)
            t1 = time.process_time()
            joint = fit_record_and_impedance(model, u[est], d.v[est], f[band], z_at(0.6),
                                             capacity=cell.capacity, ocv_slope=slope(0.6))
            t2 = time.process_time()
        for name, fit, sec in (("record alone", alone, t1 - t0), ("joint", joint, t2 - t1)):
            e = fit.simulate(u)[val] - d.v[val]
            slow = {k: round(p.value, 3) for k, p in fit.parameters.items() if k[:3] in ("tau", "alp")}
            print(f"  {' + '.join(e.upper() for e in elements):>8} {name:>12}: validation "
                  f"{1e3 * float(np.sqrt(np.mean(e ** 2))):.2f} mV, impedance "
                  f"{' / '.join(f'{error(fit, s):.1f}' for s in (0.4, 0.5, 0.6))} %, {slow}, "
                  f"{sec:.1f} s" + (f", noise {fit.options['noise']}" if name == "joint" else ""))


def run_baseline(baseline, repeats):
    old = load_old(baseline)
    print(f"baseline {baseline}, {repeats} repeats (interleaved; medians of CPU time)")
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
        for _ in range(repeats):
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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=("direct", "spectrum", "baseline", "all"),
                        default="direct")
    parser.add_argument("--baseline", default="cd24403")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} logical cores, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"load {os.getloadavg()[0]:.2f}")
    if args.part in ("direct", "all"):
        run_direct(args.repeats)
    if args.part in ("spectrum", "all"):
        run_spectrum()
    if args.part in ("baseline", "all"):
        run_baseline(args.baseline, args.repeats)


if __name__ == "__main__":
    main()
