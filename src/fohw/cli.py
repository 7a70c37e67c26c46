"""Command-line interface ``fohw`` (also ``python -m fohw``)."""

from __future__ import annotations

import argparse
import sys

from . import __version__


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of the ``fohw`` command."""
    parser = argparse.ArgumentParser(
        prog="fohw", description="Identification of fractional-order Hammerstein-Wiener systems.")
    parser.add_argument("--version", action="version", version=f"fohw {__version__}")
    parser.add_subparsers(dest="command", metavar="COMMAND")
    return parser


def main(argv=None) -> int:
    """Run the ``fohw`` command; return its exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
