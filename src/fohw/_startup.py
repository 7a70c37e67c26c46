"""Private: Ctrl-C while the ``fohw`` command is still importing ends it with one line.

``import fohw`` takes about a second (NumPy, SciPy, the estimators). A Ctrl-C in that second
used to print a 14-44-line ``KeyboardInterrupt`` traceback and end with status -2, before
:func:`fohw.cli.main` could catch anything. :func:`guard` (run when this module is imported,
which ``fohw/__init__.py`` does first) installs a SIGINT handler that prints one line and exits
with status 130 -- only when this process *is* the ``fohw`` command (``fohw ...`` or
``python -m fohw ...``), so importing fohw as a library changes nothing. :func:`release`
(called by :func:`fohw.cli.main`) gives Ctrl-C back to Python, which raises
``KeyboardInterrupt`` as usual from then on.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

__all__ = ["guard", "release", "is_fohw_command"]

MESSAGE = b"fohw: interrupted while starting; nothing was done.\n"
_OPTIONS_WITH_VALUE = ("-X", "-W", "-Q")


def is_fohw_command(orig_argv=None, argv0=None) -> bool:
    """True when the process was started as ``fohw ...`` or ``python -m fohw ...``."""
    orig_argv = list(getattr(sys, "orig_argv", []) if orig_argv is None else orig_argv)
    argv0 = (sys.argv[0] if sys.argv else "") if argv0 is None else argv0
    args = iter(orig_argv[1:])
    for arg in args:
        if arg == "-m":
            return next(args, None) == "fohw"
        if arg.startswith("-m"):
            return arg[2:] == "fohw"
        if arg in _OPTIONS_WITH_VALUE:
            next(args, None)
            continue
        if arg == "-c" or not arg.startswith("-"):
            break                                   # a command or a script
    name = os.path.basename(argv0).lower()
    return name in ("fohw", "fohw.exe", "fohw-script.py")


def _interrupted(signum, frame):
    try:
        sys.stderr.flush()
    except Exception:       # noqa: BLE001 -- stderr may be closed; the line goes to fd 2
        pass
    os.write(2, MESSAGE)
    os._exit(130)


def guard():
    """Install the one-line Ctrl-C handler if this process is the ``fohw`` command."""
    if threading.current_thread() is threading.main_thread() and is_fohw_command() \
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _interrupted)


def release():
    """Give Ctrl-C back to Python (``KeyboardInterrupt``), if :func:`guard` took it."""
    if threading.current_thread() is threading.main_thread() \
            and signal.getsignal(signal.SIGINT) is _interrupted:
        signal.signal(signal.SIGINT, signal.default_int_handler)


guard()
