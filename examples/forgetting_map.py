"""The paper's hybrid method under a forgetting factor: delta and alpha over lambda x P x schedule.

    python examples/forgetting_map.py --outdir results [--fast] [--seeds 10] [--jobs 2]

The paper's Eq. (31) grows r(k) = r(k-1) + ||Phi(P, k)||^2 without bound, which is why the
printed algorithm stalls (docs/reproduction.md). This runs the hybrid MIGD + MI-LM method with
r(k) = lambda r(k-1) + ||Phi(P, k)||^2 -- a forgetting factor lambda that is NOT in the paper --
for lambda in (1, 0.999, 0.99, 0.97, 0.95, 0.9, 0.8, 0.6), P in (1, 3, 5) and three schedules
(Table 1; Steps 1-9 as printed; Steps 1-9 with the alpha step on the whole record and r
restarted each pass), on 10 seeds of the academic example, and reports delta and alpha at
k = 2000, 5000, 10000 (median and interquartile range) and on how many seeds P = 5 beats
P = 1. Writes forgetting_map.md, forgetting_map.csv, forgetting_map.png (heat map of the median
delta at k = 10000) and forgetting_best.png (delta(k) and alpha(k) at each schedule's best
lambda against the printed Table 2). Also `fohw reproduce forgetting`.
"""

import sys

from fohw.paper.forgetting import main

if __name__ == "__main__":
    sys.exit(main(description=__doc__.splitlines()[0]))
