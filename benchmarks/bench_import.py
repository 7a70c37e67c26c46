"""How long ``import fohw`` takes, before and after, measured with ``python -X importtime``.

Each repeat is a fresh interpreter, ``python -X importtime -c "import fohw"``; the number read is
the cumulative time of the ``fohw`` line (the package and everything it imports, numpy included),
and the runs of the two trees alternate so that a change of machine load hits both. The
"before" tree defaults to the main checkout's ``src`` (``--before /path/to/other/src``), the
"after" tree to this checkout's. It also prints which heavy modules (scipy submodules,
matplotlib, numba) ``import fohw`` leaves loaded in each tree.

    python benchmarks/bench_import.py [--repeats 15] [--before /work/main/src]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
AFTER = HERE.parent / "src"
HEAVY = """
import sys, fohw
print(" ".join(sorted(m for m in sys.modules if m in ("matplotlib", "numba")
                      or (m.startswith("scipy.") and m.count(".") == 1
                          and not m.split(".")[1].startswith("_")))))
"""


def _cpu_of(cmd, env):
    """``(user + system CPU seconds, completed process)`` of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), proc


def import_seconds(src):
    """``(wall, cpu)`` seconds of ``import fohw`` in one fresh interpreter, ``src`` on the path.

    wall: the cumulative time of the ``fohw`` line of ``-X importtime`` (the number to read);
    cpu: the child's user + system CPU time minus that of an interpreter that imports nothing
    (less sensitive to the machine's load, but it also counts numpy's BLAS threads starting, so
    it can exceed the wall time).
    """
    env = {**os.environ, "PYTHONPATH": str(src)}
    cpu, proc = _cpu_of([sys.executable, "-X", "importtime", "-c", "import fohw"], env)
    empty, _ = _cpu_of([sys.executable, "-X", "importtime", "-c", "pass"], env)
    line = [ln for ln in proc.stderr.splitlines() if ln.rstrip().endswith("| fohw")][-1]
    return int(line.split("|")[1]) / 1e6, cpu - empty


def heavy_modules(src):
    env = {**os.environ, "PYTHONPATH": str(src)}
    return subprocess.run([sys.executable, "-c", HEAVY], env=env, capture_output=True, text=True,
                          check=True).stdout.strip() or "(none)"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--before", default="/work/main/src", help="src folder of the tree to "
                    "compare with (default: the main checkout)")
    ap.add_argument("--after", default=str(AFTER), help="src folder measured as 'after' "
                    "(default: this checkout)")
    args = ap.parse_args(argv)
    trees = {"before": Path(args.before), "after": Path(args.after)}
    for name, src in trees.items():
        if not (src / "fohw" / "__init__.py").is_file():
            ap.error(f"--{name}: {src} holds no fohw package.")
    print(f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores, "
          f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} (before the runs)")
    for name, src in trees.items():
        print(f"{name:6s} {src}: heavy modules after `import fohw`: {heavy_modules(src)}")
    wall = {name: [] for name in trees}
    cpu = {name: [] for name in trees}
    for _ in range(args.repeats):
        for name, src in trees.items():          # alternate: load changes hit both trees
            w, c = import_seconds(src)
            wall[name].append(w)
            cpu[name].append(c)
    print(f"\n`import fohw`, {args.repeats} fresh interpreters each (seconds):")
    print(f"{'tree':6s} {'wall median':>12s} {'min':>7s} {'max':>7s} {'CPU median':>11s} {'min':>7s}")
    for name in trees:
        w, c = wall[name], cpu[name]
        print(f"{name:6s} {statistics.median(w):12.3f} {min(w):7.3f} {max(w):7.3f} "
              f"{statistics.median(c):11.3f} {min(c):7.3f}")
    ratio = statistics.median(wall["before"]) / statistics.median(wall["after"])
    print(f"\nmedian wall before / after = {ratio:.1f}x; load average after the runs "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
