"""Reproduce Fig. 5 of the paper: identified model output against the measured output, P = 5.

    python examples/figure_5.py --outdir results [--fast] [--seed 0]

Writes figure_5.png to --outdir.
"""

import sys

from fohw.paper.table2 import main

if __name__ == "__main__":
    sys.exit(main(("figure_5",), __doc__.splitlines()[0]))
