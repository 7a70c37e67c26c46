"""Accuracy of every method against the Cramér-Rao bound, on the paper's example and two others.

    python examples/accuracy_vs_crb.py --outdir results [--fast] [--seeds 20] [--jobs 2]

The study lives in fohw.paper.accuracy (also: fohw reproduce accuracy); see its docstring.
"""

import sys

from fohw.paper.accuracy import main

if __name__ == "__main__":
    sys.exit(main())
