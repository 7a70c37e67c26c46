"""Reproduce Fig. 6 of the paper: delta(k) of the hybrid method (P = 5) against the two baselines.

The baselines are the single-innovation gradient and Levenberg-Marquardt methods.

    python examples/figure_6.py --outdir results [--fast] [--seed 0]

Writes figure_6.png to --outdir.
"""

import sys

from fohw.paper.table2 import main

if __name__ == "__main__":
    sys.exit(main(("figure_6",), __doc__.splitlines()[0]))
