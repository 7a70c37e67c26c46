"""Reading a large data file: numpy.loadtxt's compiled reader against the line-by-line reader.

``fohw.io.text.read_table`` sends a clean file (one header at most, no comment marks after it,
the same number of fields on every line) to :func:`numpy.loadtxt`, and everything else to the
line-by-line reader, which is the reader fohw used for every file before (it names the line of
any error). This script writes a two-column file of ``--rows`` rows (default 5 000 000, the
file of issue 14) and times each reader in a fresh process, with its peak resident memory
(``VmHWM``, as ``benchmarks/run.py`` measures it) beside the memory of the process after its
imports.

    python benchmarks/bench_read.py [--rows 5000000] [--repeats 1]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = """
import sys, time
sys.path.insert(0, sys.argv[3])
from run import high_water_mb           # VmHWM: ru_maxrss keeps the parent's mark across exec
import fohw
from fohw.io import text
before = high_water_mb()
start = time.perf_counter()
if sys.argv[2] == "fast":
    table = text.read_table(sys.argv[1])
elif sys.argv[2] == "lines":
    table = text._read_lines(sys.argv[1], ".")
else:
    table = None
seconds = time.perf_counter() - start
rows = 0 if table is None else table.data.shape[0]
print(seconds, high_water_mb(), before, rows)
"""


def measure(path, reader):
    here = os.path.dirname(os.path.abspath(__file__))
    out = subprocess.run([sys.executable, "-c", CHILD, path, reader, here], capture_output=True,
                         text=True, check=True).stdout.split()
    return float(out[0]), float(out[1]), float(out[2]), int(out[3])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=5_000_000)
    parser.add_argument("--repeats", type=int, default=1)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "big.csv")
        data = rng.standard_normal((args.rows, 2))
        np.savetxt(path, data, fmt="%.17g", delimiter=",", header="u,y", comments="")
        size = os.path.getsize(path) / 2**20
        print(f"{args.rows} rows x 2 columns, {size:.0f} MB, CSV with a header; "
              f"{args.repeats} run(s) per reader, each in a fresh process; median time")
        results = {}
        for reader in ("fast", "lines"):
            runs = [measure(path, reader) for _ in range(args.repeats)]
            results[reader] = (float(np.median([r[0] for r in runs])),
                               max(r[1] for r in runs), runs[0][2], runs[0][3])
        print("| reader | seconds | peak RSS (MB) | RSS after import (MB) | rows |")
        print("|---|---:|---:|---:|---:|")
        names = {"fast": "numpy.loadtxt (read_table, clean file)",
                 "lines": "line by line (every file before; now errors and odd layouts)"}
        for reader, (sec, peak, imp, rows) in results.items():
            print(f"| {names[reader]} | {sec:.1f} | {peak:.0f} | {imp:.0f} | {rows} |")
        print(f"time ratio line/loadtxt: {results['lines'][0] / results['fast'][0]:.1f}x; "
              f"memory above import: {results['lines'][1] - results['lines'][2]:.0f} MB vs "
              f"{results['fast'][1] - results['fast'][2]:.0f} MB")


if __name__ == "__main__":
    main()
