"""Size and power of the order test's corrections for correlated residuals (issue 36).

    OPENBLAS_NUM_THREADS=1 nice python benchmarks/order_test_size.py [--records 200] [--fast]
        [--outdir benchmarks/results]

Records of the integer-order plant ``y(k) = 0.5 y(k-1) + u(k-1)`` (the lagged kind with
``na = nb = 1``, identity bases, orders 0), or of the same with a commensurate order
``alpha = 0.5`` (``y(k) = 0.5 (Delta^alpha y)(k-1) + (Delta^alpha u)(k-1)``); ``N = 500``,
input uniform on [-1, 1]; output noise an AR(1) with pole 0.9 scaled to the standard deviation
``sd`` (the noise's, not the innovation's), or white. Both classes (orders 0 and a free
commensurate order) are fitted by ``method="output_error"``, and :func:`fohw.lr_test` with the
record reports the white-noise p-value and the corrected one of each ``correction``. Printed
(and written to ``order_test_size.md`` in ``--outdir``): the rejections at 5 % of each, per
scenario, and the seconds. Seeds are ``0 .. records-1`` (null) and ``10000 + i`` (alpha = 0.5).
``--fast``: 20 records per scenario (the test suite runs that).
"""

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.signal

import fohw

POLE = 0.9
N = 500
KW = dict(na=1, nb=1, f_basis=1, g_basis=1, method="output_error")
CORRECTIONS = ("sandwich", "bartlett", "prewhitened")


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
        counts = dict.fromkeys(("white",) + CORRECTIONS, 0)
        for i in range(records):
            u, y = record(offset + i, alpha, sd, pole)
            for k, p in pvalues(u, y).items():
                counts[k] += p < 0.05
        rows.append((label, records, counts, time.perf_counter() - t0))
        print(f"{label}: {counts} of {records} ({rows[-1][3]:.1f} s)", flush=True)
    return rows


def markdown(rows):
    head = "| scenario | records | white noise | " + " | ".join(CORRECTIONS) + " | seconds |"
    lines = [head, "|" + "---|" * (len(CORRECTIONS) + 4)]
    for label, n, counts, sec in rows:
        cells = " | ".join(f"{counts[k]} ({100 * counts[k] / n:.1f} %)"
                           for k in ("white",) + CORRECTIONS)
        lines.append(f"| {label} | {n} | {cells} | {sec:.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=200)
    ap.add_argument("--fast", action="store_true")
    ap.add_argument("--outdir", type=Path, default=Path("benchmarks/results"))
    args = ap.parse_args(argv)
    rows = run(20 if args.fast else args.records)
    text = markdown(rows)
    print(text)
    args.outdir.mkdir(parents=True, exist_ok=True)
    (args.outdir / "order_test_size.md").write_text(text)
    return rows


if __name__ == "__main__":
    main()
