"""Reproduce Fig. 4 of the paper: the fractional-order estimate alpha(k) for P = 1, 3, 5.

    python examples/figure_4.py --outdir results [--fast] [--seed 0]

Writes figure_4.png to --outdir.
"""

import sys

from fohw.paper.table2 import main

if __name__ == "__main__":
    sys.exit(main(("figure_4",), __doc__.splitlines()[0]))
