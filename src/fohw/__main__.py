"""``python -m fohw`` runs the command-line interface."""

import sys

from .io.cli import main

sys.exit(main())
