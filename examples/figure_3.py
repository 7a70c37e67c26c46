"""Reproduce Fig. 3 of the paper: relative parameter error delta(k) for P = 1, 3, 5.

    python examples/figure_3.py --outdir results [--fast] [--seed 0]

Writes figure_3.png to --outdir.
"""

import sys

from fohw.paper.table2 import main

if __name__ == "__main__":
    sys.exit(main(("figure_3",), __doc__.splitlines()[0]))
