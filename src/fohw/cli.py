"""Command-line interface ``fohw`` (also ``python -m fohw``).

``fohw reproduce table2 --outdir DIR [--fast]`` reproduces Table 2 and Figs. 3–6 of the paper;
``fohw reproduce figures`` writes the figures only.
"""

from __future__ import annotations

import argparse
import sys

from . import __version__

_REPRODUCE = {
    "table2": ("table_2", "figure_3", "figure_4", "figure_5", "figure_6"),
    "figures": ("figure_3", "figure_4", "figure_5", "figure_6"),
}


class _Parser(argparse.ArgumentParser):
    """Usage errors as one line on stderr and exit status 2."""

    def error(self, message):
        self.exit(2, f"fohw: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of the ``fohw`` command."""
    parser = _Parser(prog="fohw",
                     description="Identification of fractional-order Hammerstein-Wiener systems.")
    parser.add_argument("--version", action="version", version=f"fohw {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    rep = sub.add_parser("reproduce", help="reproduce the paper's tables and figures")
    rep.add_argument("what", choices=sorted(_REPRODUCE), help="table2: Table 2 and Figs. 3-6; "
                     "figures: Figs. 3-6 only")
    rep.add_argument("--outdir", default="results", help="folder for the files (default: results)")
    rep.add_argument("--fast", action="store_true", help="N = 2000 instead of 10 000")
    rep.add_argument("--seed", type=int, default=0, help="seed of the simulated record (default 0)")
    return parser


def main(argv=None) -> int:
    """Run the ``fohw`` command; return its exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    if args.command == "reproduce":
        from .reproduction import example_main

        forwarded = ["--outdir", args.outdir, "--seed", str(args.seed)]
        if args.fast:
            forwarded.append("--fast")
        return example_main(_REPRODUCE[args.what], f"fohw reproduce {args.what}", forwarded)
    return 0  # pragma: no cover


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
