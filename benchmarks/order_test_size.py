"""Size and power of the order test's corrections for correlated residuals (issue 36).

    OPENBLAS_NUM_THREADS=1 nice python benchmarks/order_test_size.py [--records 200] [--fast]
        [--outdir benchmarks/results]

Records of the integer-order plant ``y(k) = 0.5 y(k-1) + u(k-1)`` (the lagged kind with
``na = nb = 1``, identity bases, orders 0), or of the same with a commensurate order
``alpha = 0.5`` (``y(k) = 0.5 (Delta^alpha y)(k-1) + (Delta^alpha u)(k-1)``); ``N = 500``,
input uniform on [-1, 1]; output noise an AR(1) with pole 0.9 scaled to the standard deviation
``sd`` (the noise's, not the innovation's), or white. Both classes (orders 0 and a free
commensurate order) are fitted by ``method="output_error"``, and :func:`fohw.lr_test` with the
record reports the white-noise p-value and the corrected one of each ``correction``; the last
column is the sandwich along the difference of the fits' residuals (its fallback without a
score direction), computed from the same residuals. Printed
(and written to ``order_test_size.md`` in ``--outdir``): the rejections at 5 % of each, per
scenario, and the seconds. Seeds are ``0 .. records-1`` (null) and ``10000 + i`` (alpha = 0.5).
``--fast``: 20 records per scenario.

``--shipped``: instead, the order verdict (:meth:`result.order_test` / :func:`fohw.lr_test`
with ``validation=``) on the records shipped with fohw, written to ``order_verdict_shipped.md``:

* cascaded tanks: the docs' structure (na = nb = 2, f degree 2, g degree 1, offset, the
  estimation mean as operating point, dt = 4, output error), commensurate and per-lag
  orders, fitted on the estimation record, validated on the benchmark's validation record;
* robot arm: na = nb = 6, f = g = identity, output error, commensurate, fitted on the
  first half, validated on the second (a near mirror image of the first: a weak check);
* battery drive cycle (``--battery``, a few minutes): examples/battery.py's ZARC circuit
  (time constants up to 250 s) against the same circuit with ``alpha1`` held at 1 (the RC
  element), fitted on the first half of the cycle decimated 10 times, validated on the
  second half (free run from its start, so the elements start at rest there).
"""

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.signal

import fohw
from fohw.analysis.lrtest import criterion_residuals
from fohw.lr_statistic import chi_bar_squared_sf, corrected_statistic

POLE = 0.9
N = 500
KW = dict(na=1, nb=1, f_basis=1, g_basis=1, method="output_error")
CORRECTIONS = ("sandwich", "bartlett", "prewhitened")
#: Columns: the white-noise test, each correction, and the sandwich along the fits' difference
#: (what it falls back to without a score direction).
COLUMNS = ("white",) + CORRECTIONS + ("sandwich (fits' difference)",)


def record(seed, alpha=0.0, sd=0.5, pole=POLE, n=N):
    """``(u, y)``: the plant (orders 0, or commensurate ``alpha``) plus AR(1) output noise."""
    rng = np.random.default_rng(seed)
    if alpha == 0.0:
        m = fohw.HammersteinWiener(a=[0.5], b=[1.0], p=[1.0], q=[1.0], orders=0)
    else:
        m = fohw.HammersteinWiener(a=[0.5], b=[1.0], p=[1.0], q=[1.0], alpha=alpha)
    u = rng.uniform(-1.0, 1.0, n)
    burn = 200                               # the AR(1) started in its stationary regime
    e = rng.standard_normal(n + burn) * sd * math.sqrt(1.0 - pole ** 2)
    v = scipy.signal.lfilter([1.0], [1.0, -pole], e)[burn:]
    return u, fohw.simulate(m, u) + v


def pvalues(u, y):
    """``{"white": p, correction: p, ...}`` of orders 0 against a free commensurate order."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # ConvergenceWarning of a null fit at alpha = 0
        r0 = fohw.identify(u, y, orders=0, **KW)
        rc = fohw.identify(u, y, orders="commensurate", **KW)
    out = {}
    for c in CORRECTIONS:
        t = fohw.lr_test(r0, rc, u=u, y=y, correction=c)
        out["white"], out[c] = t.pvalue, t.pvalue_corrected
    e_r, e_f = criterion_residuals(r0, u, y), criterion_residuals(rc, u, y)
    x, _ = corrected_statistic(e_r, e_f, t.statistic)             # no direction
    out[COLUMNS[-1]] = chi_bar_squared_sf(x, 1)
    return out


SCENARIOS = (   # (label, alpha, sd, pole, seed offset)
    ("integer plant, AR(1) noise sd 0.5 (size)", 0.0, 0.5, POLE, 0),
    ("alpha = 0.5, AR(1) noise sd 0.5 (power)", 0.5, 0.5, POLE, 10_000),
    ("integer plant, AR(1) noise sd 1.0 (size)", 0.0, 1.0, POLE, 20_000),
    ("alpha = 0.5, AR(1) noise sd 1.0 (power)", 0.5, 1.0, POLE, 30_000),
    ("integer plant, white noise sd 0.5 (size)", 0.0, 0.5, 0.0, 40_000),
)


def run(records, scenarios=SCENARIOS):
    rows = []
    for label, alpha, sd, pole, offset in scenarios:
        t0 = time.perf_counter()
        counts = dict.fromkeys(COLUMNS, 0)
        for i in range(records):
            u, y = record(offset + i, alpha, sd, pole)
            for k, p in pvalues(u, y).items():
                counts[k] += p < 0.05
        rows.append((label, records, counts, time.perf_counter() - t0))
        print(f"{label}: {counts} of {records} ({rows[-1][3]:.1f} s)", flush=True)
    return rows


def markdown(rows):
    head = "| scenario | records | white noise | " + " | ".join(COLUMNS[1:]) + " | seconds |"
    lines = [head, "|" + "---|" * (len(COLUMNS) + 3)]
    for label, n, counts, sec in rows:
        cells = " | ".join(f"{counts[k]} ({100 * counts[k] / n:.1f} %)"
                           for k in COLUMNS)
        lines.append(f"| {label} | {n} | {cells} | {sec:.0f} |")
    return "\n".join(lines) + "\n"


def _quiet(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")      # ConvergenceWarning, ExtrapolationWarning
        return call(*args, **kwargs)


def shipped(battery=False):
    """``[(record, class, estimated orders, LRTest, seconds)]`` on the shipped records."""
    out = []
    tanks = fohw.datasets.cascaded_tanks()
    e, v = tanks.estimation, tanks.validation
    kw = dict(na=2, nb=2, f_basis=2, g_basis=1, offset=True, operating_point="mean", dt=4.0,
              method="output_error")
    for orders in ("commensurate", "per_lag"):
        t0 = time.perf_counter()
        full = _quiet(fohw.identify, e.u, e.y, orders=orders, **kw)
        test = _quiet(fohw.order_test, full, e.u, e.y, validation=(v.u, v.y))
        out.append(("cascaded tanks", orders, full.orders, test, time.perf_counter() - t0))
    arm = fohw.datasets.robot_arm()
    kw = dict(na=6, nb=6, f_basis=1, g_basis=1, method="output_error")
    t0 = time.perf_counter()
    full = _quiet(fohw.identify, arm.u[:512], arm.y[:512], orders="commensurate", **kw)
    test = _quiet(fohw.order_test, full, arm.u[:512], arm.y[:512],
                  validation=(arm.u[512:], arm.y[512:]))
    out.append(("robot arm", "commensurate", full.orders, test, time.perf_counter() - t0))
    if battery:
        import sys

        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
        from battery import fit_circuit, inputs

        t0 = time.perf_counter()
        cell = fohw.datasets.battery_cell().decimate(10)
        n = cell.n_samples
        est, val = slice(0, n // 2), slice(n // 2, n)
        kw = {"model": {}, "fit": {}}
        frac, _ = _quiet(fit_circuit, cell, est, ("zarc",), False, 250.0, kw)
        rc, _ = _quiet(fit_circuit, cell, est, ("zarc",), False, 250.0, kw, held={"alpha1": 1.0})
        test = _quiet(fohw.lr_test, rc, frac, u=inputs(cell, est), y=cell.v[est],
                      validation=(inputs(cell, val), cell.v[val]))
        out.append(("battery drive cycle", "ZARC vs alpha1 = 1", {"alpha1": frac.parameters[
            "alpha1"].value}, test, time.perf_counter() - t0))
    return out


def shipped_markdown(rows):
    lines = ["| record | class | estimated orders | LR (white) | p (white) | kappa | LR corrected "
             "| p corrected | held-back fit % orders 0 / fractional | verdict | seconds |",
             "|" + "---|" * 11]
    for name, cls, orders, t, sec in rows:
        est = ", ".join(f"{k} = {v:.3g}" for k, v in orders.items())
        kappa = t.correction.split("factor ")[1].split(",")[0] if "factor" in t.correction else ""
        fits = " / ".join(f"{f:.2f}" for f in t.validation)
        lines.append(f"| {name} | {cls} | {est} | {t.statistic:.4g} | {t.pvalue:.2g} | {kappa} | "
                     f"{t.statistic_corrected:.4g} | {t.pvalue_corrected:.2g} | {fits} | "
                     f"{t.verdict} | {sec:.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=200)
    ap.add_argument("--fast", action="store_true")
    ap.add_argument("--shipped", action="store_true")
    ap.add_argument("--battery", action="store_true")
    ap.add_argument("--outdir", type=Path, default=Path("benchmarks/results"))
    args = ap.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    if args.shipped:
        rows = shipped(args.battery)
        text = shipped_markdown(rows)
        print(text)
        (args.outdir / "order_verdict_shipped.md").write_text(text)
        return rows
    rows = run(20 if args.fast else args.records)
    text = markdown(rows)
    print(text)
    (args.outdir / "order_test_size.md").write_text(text)
    return rows


if __name__ == "__main__":
    main()
