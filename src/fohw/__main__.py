"""``python -m fohw`` runs the command-line interface.

A Ctrl-C while fohw is importing ends the command with one line and status 130
(:mod:`fohw._startup` for ``import fohw``; the ``except`` below for ``fohw.cli``).
"""

import sys

try:
    from .cli import main
except KeyboardInterrupt:
    print("fohw: interrupted while starting; nothing was done.", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
