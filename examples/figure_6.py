"""Reproduce Fig. 6 of the paper: relative error of the hybrid method (P = 5) against the two
single-innovation baselines.

    python examples/figure_6.py --outdir results [--fast] [--seed 0]

Writes figure_6.png to --outdir.
"""

import sys

from fohw.paper.reproduction import example_main

if __name__ == "__main__":
    sys.exit(example_main(("figure_6",), __doc__.splitlines()[0]))
