"""Reproduce Table 2 of the paper (and Figs. 3-6 from the same runs).

    python examples/table_2.py --outdir results [--fast] [--seed 0]

Writes table_2.md, table_2.csv and figure_3.png ... figure_6.png to --outdir and prints the
table. The paper's printed values come from fohw/data/paper_table2.json.
"""

import sys

from fohw.paper.reproduction import OUTPUTS, example_main

if __name__ == "__main__":
    sys.exit(example_main(OUTPUTS, __doc__.splitlines()[0]))
