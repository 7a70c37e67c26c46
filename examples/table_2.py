"""Reproduce Table 2 of the paper (and Figs. 3-6 from the same runs).

    python examples/table_2.py --outdir results [--fast] [--seed 0] [--forgetting 1]

Writes table_2.md, table_2.csv and figure_3.png ... figure_6.png to --outdir and prints the
table. The paper's printed values come from fohw/data/paper_table2.json.

--forgetting LAMBDA (default 1, the paper as printed) sets r(k) = LAMBDA r(k-1) + ||Phi(P, k)||^2
in the hybrid method: a forgetting factor that is not in the paper, under which its qualitative
claims appear (see examples/forgetting_map.py and docs/reproduction.md).
"""

import sys

from fohw.paper.table2 import OUTPUTS, main

if __name__ == "__main__":
    sys.exit(main(OUTPUTS, __doc__.splitlines()[0]))
