"""`import fohw` loads no heavy scipy submodule, no matplotlib and no numba: they load on first use.

The time itself is measured by ``benchmarks/bench_import.py`` (a benchmark, not a test: it depends on
the machine's load); this test pins down the cause of the time, which does not.
"""

import subprocess
import sys

HEAVY = ("scipy.stats", "scipy.fft", "scipy.optimize", "scipy.signal", "scipy.special",
         "scipy.ndimage", "scipy.linalg", "scipy.interpolate", "matplotlib", "numba",
         "importlib.metadata")


def test_import_fohw_leaves_the_heavy_modules_unloaded():
    code = ("import sys, fohw; print(' '.join(m for m in " + repr(HEAVY)
            + " if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == []


def test_each_loads_where_it_is_first_used():
    code = """
import sys
import numpy as np
import fohw
assert "scipy.fft" not in sys.modules
fohw.gl_difference(np.ones(300), 0.5)
assert "scipy.fft" in sys.modules
d = fohw.datasets.paper_example(300, random_state=0)
res = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3)
assert "scipy.optimize" in sys.modules and "matplotlib" not in sys.modules
fohw.compare(res, d.u, d.y).plot()
assert "matplotlib" in sys.modules and "matplotlib.pyplot" not in sys.modules
print(fohw.__version__)
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip()
