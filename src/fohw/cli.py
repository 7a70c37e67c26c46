"""Command-line interface ``fohw`` (also ``python -m fohw``).

* ``fohw identify DATA [--columns U,Y] --na 2 --nb 2 [--nk 0] --f-basis 2 --g-basis 3
  [--method varpro] [--offset] [--operating-point mean] [--dt 4] [--output-map saturation]
  [--decimal-comma] [--option NAME=VALUE] [--json] [--plot FILE] [--save FILE]`` — identify
  from a comma-, semicolon- or whitespace-separated file (the sampling time a ``Ts`` column
  gives is the default ``--dt``); prints a summary and the free-run fit on the record (or,
  with ``--json``, both as JSON).
* ``fohw select DATA [--columns U,Y or U1,U2,Y] --na 1,2 [--nb ...] [--nk 0,1] --f-basis 1,2 --g-basis 1
  [--orders 0,commensurate,mixed] [--method output_error] [--validation 0.25] [--offset]
  [--output-map none,saturation] [--operating-point mean] [--dt 4] [--jobs 2] [--csv F]
  [--plot F] [--save F]`` — choose a structure by free-run simulation on a held-back part
  (:func:`fohw.select_structure`); ``--jobs`` at most the processors, and the workers end
  when ``fohw`` does.
* ``fohw simulate --model MODEL.json --input DATA [--column 0] [--noise-std S --seed N]
  [--initial rest|fitted] [--output FILE]`` — simulate a saved model (``fohw.save_model``), or
  the result of ``fohw identify --save`` (``result.simulate``: the fitted predictor), for an
  input, from the initial state ``--initial`` (needed for a result fitted with
  ``past="estimate"``). A result with several inputs (``identify --columns u1,u2,y``) takes one
  ``--column`` per input (``--column u1,u2``, matched by the names it keeps; by default the
  columns of those names); a model or fit of any other kind (``fohw.save_model``,
  ``fohw.save_result``) is simulated by its own ``simulate``, with one ``--column`` per input.
  Without ``--column``: the columns named as the model's inputs (or ``u``), else the file's
  columns other than the time column when there are exactly as many as inputs; never a guess.
  The output is CSV (:func:`fohw.io.text.format_table`): ``#`` comments, the sampling time and
  units, a header, the input's time column (when it gives the time) and the output.
* ``fohw compare --model MODEL.json --data DATA [--columns U,Y] [--initial rest|fitted|estimate]
  [--n-init N] [--json] [--plot FILE]`` — score a saved model or result on a record, as
  :func:`fohw.compare`: free-run and one-step fit % and RMSE, the residual tests.
* ``fohw fit --model START.json --data DATA [--columns U,Y or I,SOC,V] [--order-grid N]
  [--n-starts N] [--max-nfev N] [--warmup N] [--json] [--plot FILE] [--save FILE]`` — fit a
  model of any kind (a fractional transfer function, an equivalent circuit, ...) from a start
  saved by ``fohw.save_model`` (or a saved fit): :func:`fohw.fit` on the file's record.
* ``fohw data [NAME] [--out FILE]`` — write a record shipped with fohw (``cascaded_tanks``,
  ``robot_arm``, ``battery``: the cell's drive cycle as columns t, i, v, soc) or a simulated
  one (``paper_example [--samples N] [--seed S]``) as a file to try the commands on; without
  NAME, list them. The file is CSV: ``#`` comment lines saying what it is, its sampling time
  (``# dt: 4 s``) and units (``# units: uEst=V, ...``), then a header line and one full row
  per sample; ``fohw.read_record`` reads the sampling time and units, pandas reads it with
  ``pd.read_csv(FILE, comment="#")``. ``@cascaded_tanks`` or ``@robot_arm`` in place of
  DATA reads the shipped file directly.
* ``fohw reproduce {table2,figures,forgetting,robot-arm,accuracy} --outdir DIR [--fast]``;
  ``table2`` and ``figures`` also take ``--seed N`` and ``--forgetting LAMBDA`` (a forgetting
  factor on r that is not in the paper; default 1, the paper as printed).

Every verb reads its data file as :func:`fohw.read_record` does (one reader,
:func:`fohw.io.text.record_from_table`): a time column (``t``, ``time``, ``time_s``,
``Time [s]``, ``timestamp``, ...; or ``--time NAME``, ``--time none``) in seconds or ISO 8601
date/times gives the sampling time or the instants, checked (strictly increasing, agreeing with a
``# dt:`` comment or a ``Ts`` column, else an error naming the lines); ``# units:`` gives the
units the summaries and figures show; with more columns than the verb needs, ``--columns``
must say which (the time column is never a signal).

Usage errors, bad input and operating-system errors (permissions, a folder given as a file)
print one line ``fohw: error: …`` and exit with status 2, and so does a command that fitted or
selected nothing (every ``select`` candidate failed, an ``identify`` fit that FAILED); Ctrl-C,
also while fohw is still importing, prints one line and exits with status 130. Results go to
stdout; short stage messages (``fohw: fitting 12 candidates …``, ``fohw: done in 40.2 s``) go to
stderr, terminal or not (``--quiet`` turns them off; progress bars are for terminals only).
Output paths (``--save``, ``--plot``, ``--csv``, ``--output``, ``--out``, ``--outdir``) are
checked before the run. Results, models, tables, outputs and figures (``--save``, ``--csv``,
``--output``, ``--plot``, the figures of ``reproduce``) are written atomically: a failed or
interrupted save, or a full disk, leaves an existing file as it was (the tables of
``reproduce`` are written directly).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from . import __version__
from .io.files import save_figure

_DATA_NAMES = ("cascaded_tanks", "robot_arm", "battery", "pybamm_pulses", "paper_example")

_REPRODUCE = {
    "table2": ("table_2", "figure_3", "figure_4", "figure_5", "figure_6"),
    "figures": ("figure_3", "figure_4", "figure_5", "figure_6"),
}


class UsageError(Exception):
    """A command-line problem reported as one line and exit status 2."""


class _Parser(argparse.ArgumentParser):
    """Usage errors as one line on stderr and exit status 2."""

    def error(self, message):
        self.exit(2, f"fohw: error: {message}\n")


def _progress(message):
    """A status line on stderr when it is a terminal (never in pipes, files or tests)."""
    from ._parallel import progress_bar

    progress_bar(None, "fohw").write(message)


def _stage(args, message):
    """A short stage message on stderr, terminal or not (``--quiet`` turns it off).

    Long runs (numba compiling on a first run, a selection over many candidates) used to be
    silent unless stderr was a terminal; stdout stays for the results.
    """
    if not getattr(args, "quiet", False):
        print(f"fohw: {message}", file=sys.stderr, flush=True)


def _bars(args):
    """Progress bars of the library for the command: a terminal's default, none otherwise.

    In a pipe or a file the stage messages (:func:`_stage`) say what runs; ``--quiet``: nothing.
    """
    return None if sys.stderr.isatty() and not getattr(args, "quiet", False) else False


def _duration(seconds):
    return f"{seconds:.1f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def read_table(path, decimal="."):
    """Read a numeric table with :func:`fohw.io.text.read_table`.

    CSV, semicolon or whitespace columns, a header, comments, trailing separators, values
    given once, decimal commas on request.

    Returns
    -------
    data : ndarray, shape (n_rows, n_columns)
        The signal columns (a column given once, such as ``Ts``, is not among them).
    names : list of str or None
        The header's column names, if the file has a header.
    dt : float or None
        The sampling time the file gives once (a ``Ts`` column, as the cascaded-tanks file), or
        None.
    """
    from .io.text import sampling_time

    table = _load_table(path, decimal)
    return table.data, table.names, sampling_time(table)


def _load_table(path, decimal=".", time=None):
    """The :class:`fohw.io.text.Table` of a data file, the time column found (every verb's reader).

    ``time``: ``--time`` (a column name or number, ``"none"``, or None: the column the header
    names as time).
    """
    import time as clock

    from .io.text import read_table as parse

    path = _data_path(path)
    start = clock.perf_counter()
    _progress(f"reading {path} ...")
    if time is not None:
        time = False if time.lower() == "none" else int(time) if time.isdigit() else time
    table = parse(path, decimal=decimal, time=time)
    _progress(f"read {table.data.shape[0]} rows x {table.data.shape[1]} columns in "
              f"{clock.perf_counter() - start:.1f} s" + (f" ({'; '.join(table.skipped)})"
                                                         if table.skipped else ""))
    return table


def _read(args, path):
    """The data file of a verb as a :class:`fohw.io.text.Table` (``--decimal-comma``, ``--time``)."""
    return _load_table(path, _decimal(args), getattr(args, "time", None))


def _table_record(args, table, idx, path):
    """Columns ``idx`` (inputs, then the output) of ``table`` as a :class:`fohw.Record`.

    The one reader of :func:`fohw.read_record`: a time column checked, the sampling time,
    the names and the units of the file (``# units:``) reach the result and the figures.
    """
    from .io.text import record_from_table

    return record_from_table(table, idx[:-1], idx[-1], dt=getattr(args, "dt", None),
                             name=os.path.basename(str(path)))


def _data_path(path):
    """``@cascaded_tanks`` / ``@robot_arm``: the file shipped with fohw; anything else as given."""
    if isinstance(path, str) and path.startswith("@") and not os.path.exists(path):
        from .datasets import SHIPPED, shipped_file

        if path[1:] not in SHIPPED:
            raise UsageError(f"{path!r}: no record of that name ships with fohw; use one of "
                             f"{', '.join('@' + n for n in SHIPPED)} (see `fohw data`).")
        return shipped_file(path[1:])
    return path


def _column_indices(table, spec, count, path, flag="--columns", what="input and output"):
    """Column indices from ``--columns`` ("0,1" or header names) of the table's columns.

    Without ``spec``: the columns named u and y, else the columns other than the time column
    when there are exactly ``count`` of them; never a guess, and never the time column.
    """
    width, names, time = table.data.shape[1], table.names, table.time_column
    others = [j for j in range(width) if j != time]
    if len(others) < count and (spec is None or width < count):
        needs = ("the input and the output" if count == 2 and what == "input and output" else
                 "the inputs and the output" if what == "input and output" else
                 "one per input" if count > 1 else "the input")
        besides = f" besides the time column {names[time]!r}" if names and time is not None else ""
        raise UsageError(f"{path} has {len(others)} signal column(s){besides}; this command "
                         f"needs {count} ({needs}).")
    if spec is None:
        lower = [n.lower() for n in names] if names else []
        if count == 2 and what == "input and output" and "u" in lower and "y" in lower:
            idx = [lower.index("u"), lower.index("y")]
        elif count == 1 and what == "input" and "u" in lower:
            idx = [lower.index("u")]
        elif len(others) == count:
            idx = others
        else:
            have = f" ({', '.join(names[j] for j in others)})" if names else ""
            besides = f" besides the time column {names[time]!r}" if names and time is not None \
                else ""
            raise UsageError(f"{path} has {len(others)} columns{have}{besides}: say which to use "
                             f"with {flag} (numbers from 0 or header names); fohw does not "
                             "guess.")
    else:
        parts = [p.strip() for p in spec.split(",")]
        if len(parts) != count:
            raise UsageError(f"{flag} needs {count} entr{'y' if count == 1 else 'ies'}; "
                             f"got {spec!r}.")
        idx = []
        for p in parts:
            if p.lstrip("-").isdigit():
                idx.append(int(p))
            elif names is not None and p in names:
                idx.append(names.index(p))
            else:
                raise UsageError(f"{flag}: {p!r} is neither a column number nor a header name"
                                 f" of {path}" + (f" ({', '.join(names)})." if names else "."))
    if len(set(idx)) != len(idx):
        raise UsageError(f"{flag} names the same column twice ({spec!r}): the input and the "
                         "output must be different columns.")
    for i in idx:
        if not 0 <= i < width:
            raise UsageError(f"{flag}: column {i} does not exist; {path} has "
                             f"{width} column(s) (numbered from 0).")
        if i == time:
            raise UsageError(f"{flag}: column {names[i] if names else i!r} is the time column of "
                             f"{path}; to read it as a signal, say --time none (or --time NAME "
                             "for another time column).")
    return idx


def _basis_arg(text):
    from .model.basis import MAX_POLYNOMIAL_DEGREE

    try:
        degree = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a basis is a polynomial degree >= 1; got {text!r}") \
            from None
    if not 1 <= degree <= MAX_POLYNOMIAL_DEGREE:
        raise argparse.ArgumentTypeError(f"a basis is a polynomial degree from 1 to "
                                         f"{MAX_POLYNOMIAL_DEGREE}; got {degree}")
    return degree


def _output_map_arg(text):
    """``--output-map``: a series output map by name, or a polynomial degree."""
    from .model.output_map import MAX_MAP_DEGREE, OUTPUT_MAP_NAMES

    if text == "none":
        return None
    if text in OUTPUT_MAP_NAMES:
        return text
    try:
        degree = int(text)
    except ValueError:
        degree = None
    if degree is None or not 1 <= degree <= MAX_MAP_DEGREE:
        raise argparse.ArgumentTypeError(f"an output map is one of {', '.join(OUTPUT_MAP_NAMES)}, "
                                         f"none or a polynomial degree from 1 to "
                                         f"{MAX_MAP_DEGREE}; got {text!r}")
    return degree


def _output_map_list(text):
    """``fohw select --output-map none,saturation``: output maps to try."""
    return [_output_map_arg(t.strip()) for t in text.split(",")]


def _per_input(check):
    """An argparse type: one value, or a comma-separated list of one per input."""
    def parse(text):
        values = [check(v.strip()) for v in text.split(",")]
        return values[0] if len(values) == 1 else values
    return parse


def _count_arg(text, minimum, what):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}{what}; got "
                                         f"{text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}{what}; got {value}")
    return value


def _check_file_out(path, flag, inputs=()):
    """Check an output file before the run.

    Not a folder, in a folder that exists, and not one of the files the run reads.
    """
    from .exceptions import DataFileError
    from .io.files import check_output_path

    if path is None:
        return
    for source in inputs:
        if os.path.exists(path) and os.path.exists(source) and os.path.samefile(path, source):
            raise UsageError(f"{flag} {path!r} is the file this run reads ({source!r}); give "
                             "another file name.")
    try:
        check_output_path(path, flag)
    except DataFileError as exc:
        raise UsageError(str(exc)) from None


def _check_plot_out(path, flag, inputs=()):
    """As :func:`_check_file_out`, and the extension is a format matplotlib writes."""
    if path is None:
        return
    _check_file_out(path, flag, inputs)
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    ext = os.path.splitext(path)[1].lstrip(".").lower()
    if ext not in formats:
        raise UsageError(f"{flag} {path!r}: the extension {('.' + ext) if ext else '(none)'} is "
                         f"not a figure format; use one of {', '.join(sorted(formats))} "
                         "(e.g. fit.png).")


def _check_outdir(path):
    if os.path.exists(path) and not os.path.isdir(path):
        raise UsageError(f"--outdir {path!r} is a file, not a folder.")


def _pair_arg(text):
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers 'low,high'; got {text!r}") \
            from None
    return lo, hi


def _option_arg(text):
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE; got {text!r}")
    value = value.strip()
    lowered = value.lower()
    if lowered in ("true", "false"):
        return name.strip(), lowered == "true"
    if lowered == "none":
        return name.strip(), None
    for kind in (int, float):
        try:
            return name.strip(), kind(value)
        except ValueError:
            pass
    return name.strip(), value


def _int_list(text, minimum=1):
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers; got {text!r}") \
            from None
    if any(v < minimum for v in values):
        raise argparse.ArgumentTypeError(f"expected comma-separated integers >= {minimum}; got "
                                         f"{text!r}")
    return values


def _delay_list(text):
    """``--nk 0,1``: input delays, integers >= 0."""
    return _int_list(text, minimum=0)


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1; got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1; got {value}")
    return value


#: The largest record ``fohw data paper_example --samples`` writes (about 40 MB of text).
MAX_DATA_SAMPLES = 1_000_000


def _samples_arg(text):
    value = _positive_int(text)
    if value > MAX_DATA_SAMPLES:
        raise argparse.ArgumentTypeError(f"expected at most {MAX_DATA_SAMPLES:_} samples (a "
                                         f"larger record is simulated in Python: "
                                         f"fohw.datasets.paper_example(n)); got {value:_}")
    return value


def _orders_list(text):
    """Classes of orders: the presets by name, a number as a fixed order (0, 0.5, 1, 2.5)."""
    from .model.orders import PRESETS

    out = []
    for v in (v.strip() for v in text.split(",")):
        if v in PRESETS:
            out.append(v)
            continue
        try:
            number = float(v)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"each entry is one of {', '.join(PRESETS)} or a number (a fixed order, e.g. 0 "
                f"or 0.5); got {v!r}") from None
        out.append(int(number) if number.is_integer() and "." not in v and "e" not in v.lower()
                   else number)
    return out


def _validation_arg(text):
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a fraction or a number of samples; got "
                                         f"{text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of the ``fohw`` command."""
    parser = _Parser(prog="fohw",
                     description="Identification of fractional-order Hammerstein-Wiener systems.")
    parser.add_argument("--version", action="version", version=f"fohw {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    _add_identify_parser(sub)
    _add_select_parser(sub)
    _add_simulate_parser(sub)
    _add_compare_parser(sub)
    _add_fit_parser(sub)
    _add_data_parser(sub)
    _add_reproduce_parser(sub)
    return parser


def _add_data_file(cmd, columns_help, decimal_help):
    """The data file, ``--columns``, ``--decimal-comma`` and ``--time`` (identify, select)."""
    cmd.add_argument("data", help="whitespace- or comma-separated columns (optional header)")
    cmd.add_argument("--columns", help=columns_help)
    cmd.add_argument("--decimal-comma", action="store_true", help=decimal_help)
    _add_time(cmd)


def _add_time(cmd):
    cmd.add_argument("--time", default=None, metavar="COLUMN",
                     help="the time column (name or number; seconds or ISO 8601 date/times), "
                     "or 'none'; default: the column named t, time, time_s, 'Time [s]', ... "
                     "(checked: increasing, and agreeing with a '# dt:' comment or Ts column)")


def _add_dt(cmd):
    cmd.add_argument("--dt", type=float, default=None,
                     help="sampling time (default: the file's time column, Ts column or '# dt:' "
                     "comment, else none: one sample is the time unit); checked against a time "
                     "column")


def _add_quiet(cmd, text="no stage messages on stderr"):
    cmd.add_argument("-q", "--quiet", action="store_true", help=text)


def _add_identify_parser(sub):
    from .estimators.hybrid import SCHEDULES
    from .estimators.identify import METHODS

    ide = sub.add_parser("identify", help="identify a model from a data file")
    _add_data_file(ide, "input and output columns, e.g. '0,1' or 'u,y' (default: the columns "
                   "named u and y, or the two columns of a two-column file); several inputs "
                   "then the output, e.g. 'u1,u2,y'",
                   "the file writes 0,5 for 0.5 (columns then separated by ';' or whitespace)")
    ide.add_argument("--na", type=int, required=True, help="output lags")
    ide.add_argument("--nb", type=_per_input(lambda t: _count_arg(t, 1, " (or one per input)")),
                     required=True, help="input lags (several inputs: one per input, e.g. 2,3)")
    ide.add_argument("--nk", type=_per_input(lambda t: _count_arg(t, 0, " (or one per input)")),
                     default=1, help="input delay in samples (default 1; 0: direct "
                     "feedthrough): input lags nk..nk+nb-1; several inputs: one per input")
    ide.add_argument("--f-basis", type=_per_input(_basis_arg), default=1,
                     help="input polynomial degree (several inputs: one per input, e.g. 2,1)")
    ide.add_argument("--g-basis", type=_basis_arg, default=1, help="output polynomial degree")
    ide.add_argument("--method", choices=METHODS, default="varpro",
                     help="estimator (default varpro; the paper's method is 'hybrid')")
    ide.add_argument("--offset", action="store_true", help="estimate a constant term")
    ide.add_argument("--operating-point", choices=("initial", "mean"), default=None,
                     help="remove the first samples or the means before fitting (and add them "
                     "back when simulating)")
    _add_dt(ide)
    ide.add_argument("--alpha-bounds", type=_pair_arg, default=(0.0, 1.0),
                     help="interval for alpha, 'low,high' within [0, 2] (default 0,1)")
    ide.add_argument("--output-map", type=_output_map_arg, default=None,
                     help="a series output block y = h(z) in the data's units: saturation, "
                     "deadzone, piecewise_linear or a polynomial degree (method output_error)")
    ide.add_argument("--schedule", choices=SCHEDULES, default=None,
                     help="hybrid and single-innovation methods: Table 1 or Steps 1-9")
    ide.add_argument("--innovation-length", type=int, default=None, help="hybrid, rls: P")
    ide.add_argument("--max-iter", type=int, default=None,
                     help="hybrid and single-innovation methods: outer iterations")
    ide.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                     type=_option_arg, help="any option of the method (repeatable), e.g. "
                     "--option forgetting=0.95; see fohw.identify")
    ide.add_argument("--json", action="store_true", help="print the estimates as JSON")
    ide.add_argument("--plot", help="write a figure of the free-run simulation and the one-step "
                     "prediction (PNG) to this file")
    ide.add_argument("--save", help="save the full result as JSON (fohw.load_result)")
    _add_quiet(ide, "no stage messages on stderr (errors and warnings still)")


def _add_select_parser(sub):
    from .estimators.identify import METHODS

    sel = sub.add_parser("select", help="choose a structure by free-run simulation on a "
                         "held-back part (fohw.select_structure)")
    _add_data_file(sel, "input and output columns, e.g. '0,1' or 'uEst,yEst' (default: as for "
                   "identify)", "as for identify")
    for flag, what in (("--na", "output lags"), ("--nb", "input lags (default: equal to na)"),
                       ("--nk", "input delays (default 1; 0: direct feedthrough)"),
                       ("--f-basis", "input polynomial degrees"),
                       ("--g-basis", "output polynomial degrees")):
        sel.add_argument(flag, type=_delay_list if flag == "--nk" else _int_list,
                         default=None if flag in ("--nb", "--nk") else [1],
                         help=f"{what}: a comma-separated list, e.g. 1,2,3")
    sel.add_argument("--orders", type=_orders_list, default=["commensurate"],
                     help="classes of orders, e.g. '0,commensurate,mixed,per_lag' "
                     "(default commensurate)")
    sel.add_argument("--method", choices=METHODS, default="varpro",
                     help="estimator of every candidate (default varpro)")
    sel.add_argument("--validation", type=_validation_arg, default=0.25,
                     help="held-back part: a fraction (default 0.25) or a number of samples")
    sel.add_argument("--offset", action="store_true", help="a constant term in every model")
    sel.add_argument("--output-map", type=_output_map_list, default=None,
                     help="series output maps to try, e.g. 'none,saturation' (method "
                     "output_error; default: none)")
    sel.add_argument("--operating-point", choices=("initial", "mean"), default=None,
                     help="remove the first samples or the means before fitting")
    _add_dt(sel)
    sel.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    sel.add_argument("--top", type=_positive_int, default=10, help="rows to print (default 10)")
    sel.add_argument("--csv", help="write every row to this CSV file")
    sel.add_argument("--plot", help="write the scores (PNG) to this file")
    sel.add_argument("--save", help="save the refitted winner as JSON (fohw.load_result)")
    _add_quiet(sel)


def _add_simulate_parser(sub):
    sim = sub.add_parser("simulate", help="simulate a saved model for an input")
    sim.add_argument("--model", required=True, help="model JSON written by fohw.save_model, or "
                     "a result JSON written by `fohw identify --save` (the fitted predictor is "
                     "simulated, as result.simulate does) or fohw.save_result; a model of any "
                     "kind")
    sim.add_argument("--input", required=True, help="data file with the input column(s)")
    sim.add_argument("--column", default=None,
                     help="input column number or name; a result or model with several inputs "
                     "takes one per input, e.g. 'u1,u2', or 'i,soc' for a circuit (default: the "
                     "columns named as its inputs, or u, or the file's columns besides the time "
                     "when it has one per input; never a guess)")
    sim.add_argument("--decimal-comma", action="store_true", help="as for identify")
    _add_time(sim)
    sim.add_argument("--noise-std", type=float, default=0.0,
                     help="white Gaussian noise: in the equation for the lagged kind, on the "
                     "output for any other kind")
    sim.add_argument("--seed", type=int, default=None)
    sim.add_argument("--initial", choices=("rest", "fitted"), default=None,
                     help="the state before the input: rest (the operating point) or fitted "
                     "(the levels a past='estimate' fit estimated before its estimation record, "
                     "right for that record). Default: rest, and a saved model's own levels; "
                     "a result fitted with past='estimate' needs it")
    sim.add_argument("--output", help="write the output here as CSV (comments, a header, the "
                     "time column if the input has one, y); default stdout")
    _add_quiet(sim)


def _add_compare_parser(sub):
    cmp = sub.add_parser("compare", help="score a saved model or result on a record: free run "
                         "and one-step prediction (fohw.compare)")
    cmp.add_argument("--model", required=True, help="model JSON (fohw.save_model) or result "
                     "JSON (`fohw identify --save`, fohw.save_result)")
    cmp.add_argument("--data", required=True, help="data file with the input and output columns "
                     "(or @NAME for a shipped record)")
    cmp.add_argument("--columns", default=None, help="input and output columns, numbers from 0 "
                     "or header names: one per input, then the output, e.g. i,soc,v for a "
                     "circuit (default: u,y, or the file's columns when it has that many)")
    cmp.add_argument("--decimal-comma", action="store_true", help="as for identify")
    _add_time(cmp)
    cmp.add_argument("--initial", choices=("rest", "fitted", "estimate"), default=None,
                     help="the state the free run starts from (fohw.compare's initial=): rest, "
                     "fitted (a past='estimate' fit's levels) or estimate (levels fitted to "
                     "this record's output: optimistic by two parameters)")
    cmp.add_argument("--n-init", type=int, default=0, help="leading samples left out of every "
                     "score (a start-up transient; default 0)")
    cmp.add_argument("--json", action="store_true", help="print the scores as JSON")
    cmp.add_argument("--plot", help="write a figure of the free run and the one-step prediction")
    _add_quiet(cmp)


def _add_fit_parser(sub):
    fit = sub.add_parser("fit", help="fit a model of any kind from a saved start (fohw.fit)",
                         description="Fit a model of any kind (a fractional transfer function, an "
                         "equivalent circuit, a Wiener chain, the lagged kind, ...) by simulation "
                         "error, from a start model saved by fohw.save_model (or a saved fit, "
                         "whose model is the start), or from a small spec written by hand: "
                         "fohw.fit(start, record). A spec is a JSON object {\"kind\": KIND, "
                         "\"args\": {...}, \"fixed\": [names], \"bounds\": {name: [low, high]}}, "
                         "e.g. {\"kind\": \"FractionalTF\", \"args\": {\"num\": [1], "
                         "\"num_orders\": [0], \"den\": [1, 1], \"den_orders\": [1, 0.5], "
                         "\"dt\": 0.1}, \"fixed\": [\"alpha0\"]}: the start KIND(**args) of a "
                         "registered kind, an argument {\"kind\": ..., \"args\": ...} built "
                         "first (FractionalHW's G; an EquivalentCircuit's OCVTable, RC, ZARC, "
                         "Warburg).")
    fit.add_argument("--model", required=True, help="the start model's JSON (fohw.save_model), "
                     "a saved result (its model is the start), or a spec {\"kind\": ..., "
                     "\"args\": {...}} (see above)")
    fit.add_argument("--data", required=True, help="data file with the input(s) and the output")
    fit.add_argument("--columns", default=None, help="input column(s), then the output: numbers "
                     "from 0 or header names, e.g. 'i,soc,v' for a circuit (default: u,y, or the "
                     "file's columns besides the time when it has that many)")
    fit.add_argument("--decimal-comma", action="store_true", help="as for identify")
    _add_time(fit)
    _add_dt(fit)
    for flag, what in (("--order-grid", "scan points per free order (fohw.fit's order_grid)"),
                       ("--n-starts", "starts refined by least squares (n_starts)"),
                       ("--max-nfev", "simulation budget of each refinement (max_nfev)")):
        fit.add_argument(flag, type=_positive_int, default=None, help=what)
    fit.add_argument("--warmup", type=int, default=None,
                     help="samples of the first input held before each record (warmup)")
    fit.add_argument("--json", action="store_true", help="print the estimates as JSON")
    fit.add_argument("--plot", help="write a figure of the fitted model's free run on the record")
    fit.add_argument("--save", help="save the result as JSON (fohw.load_result)")
    _add_quiet(fit)


def _add_data_parser(sub):
    dat = sub.add_parser("data", help="write a record shipped with fohw (or a simulated one) "
                         "to a file, to try the commands on; without NAME, list them")
    dat.add_argument("name", nargs="?", choices=_DATA_NAMES, help="the record")
    dat.add_argument("--out", help="the file to write (default: stdout)")
    dat.add_argument("--samples", type=_samples_arg, default=2000,
                     help=f"paper_example: number of samples (default 2000, at most "
                     f"{MAX_DATA_SAMPLES:_})")
    dat.add_argument("--seed", type=int, default=0, help="paper_example: seed (default 0)")
    dat.add_argument("--temperature", type=float, default=None,
                     help="pybamm_pulses: the ambient temperature [degC] of the record to write, "
                     "one of 0, 10, 25, 35, 45 (default 25)")
    dat.add_argument("--soc", type=float, default=None,
                     help="pybamm_pulses: the initial state of charge of the record to write, "
                     "one of 0.3, 0.5, 0.8 (default 0.5)")


def _add_reproduce_parser(sub):
    rep = sub.add_parser("reproduce", help="reproduce the paper's tables and figures")
    rep.add_argument("what", choices=sorted(list(_REPRODUCE) + ["robot-arm", "accuracy",
                                                                 "forgetting"]),
                     help="table2: Table 2 and Figs. 3-6; figures: Figs. 3-6; robot-arm: "
                     "Section 6.2; accuracy: methods against the Cramér-Rao bound; "
                     "forgetting: Table 2 over a forgetting factor (not in the paper), "
                     "innovation length and schedule")
    rep.add_argument("--outdir", default="results", help="folder for the files (default: results)")
    rep.add_argument("--fast", action="store_true", help="a quick, smaller run")
    rep.add_argument("--seed", type=int, default=0, help="table2/figures: seed of the record")
    rep.add_argument("--data", default=None, help="robot-arm: the DaISy file or its folder")
    rep.add_argument("--forgetting", type=float, default=None, metavar="LAMBDA",
                     help="table2/figures: forgetting factor on r in (0, 1]; not in the paper "
                     "(default 1: the paper as printed)")


def _fohw_warnings():
    from . import exceptions

    return tuple(getattr(exceptions, name) for name in exceptions.__all__
                 if name.endswith("Warning"))


def _decimal(args):
    return "," if args.decimal_comma else "."


def _input_output(args, table):
    """The record of ``--columns`` (several inputs, then the output); ``args.inputs`` names them."""
    count = max(2, len(args.columns.split(","))) if args.columns else 2
    idx = _column_indices(table, args.columns, count, args.data)
    args.inputs = None
    if count > 2 and table.names is not None:       # several inputs, then the output
        args.inputs = tuple(table.names[j] for j in idx[:-1])
    return _table_record(args, table, idx, args.data)


def _identify(args):
    _check_file_out(args.save, "--save", [args.data])
    _check_plot_out(args.plot, "--plot", [args.data])
    record = _input_output(args, _read(args, args.data))
    options = _method_options(args)
    res, check, caught = _fit_and_check(args, record, options)
    _print_warnings(caught)
    _print_identified(args, res, check)
    _print_order_test(args, res, record.u, record.y)
    _save_identified(args, res, check)
    return 0


def _print_order_test(args, res, u, y):
    """The order test corrected for correlated residuals, and its verdict.

    Only where ``summary()`` prints the white-noise test (an ``output_error`` chain's fit);
    the integer class is refitted on the record. Not with ``--json``.
    """
    from .exceptions import FohwError

    if args.json:
        return
    try:
        if res.order_test() is None:
            return
    except FohwError:           # a method with no likelihood (rls, migd, ...): no test to print
        return
    try:
        from .analysis.lrtest import order_test as order_test_with_record

        test = order_test_with_record(res, u, y)
    except FohwError as exc:
        print(f"Order test corrected for correlated residuals: not computed ({exc})")
        return
    print(f"Order test corrected for correlated residuals ({test.correction}): "
          f"LR = {test.statistic_corrected:.4g}, p = {test.pvalue_corrected:.4g} "
          f"(white residuals: p = {test.pvalue:.4g}). Verdict: {test.verdict or 'none'} "
          "(fohw select holds a part back to validate it).")


def _method_options(args):
    """The options of the method: ``--schedule`` and the like, then every ``--option``."""
    options = {name: value for name, value in (("schedule", args.schedule),
                                               ("innovation_length", args.innovation_length),
                                               ("max_iter", args.max_iter)) if value is not None}
    for name, value in args.option:
        if name in options:
            raise UsageError(f"option {name!r} given twice.")
        options[name] = value
    return options


def _fit_and_check(args, record, options):
    """Identify, then the free-run fit on the record: ``(result, check, caught warnings)``."""
    import time
    import warnings

    from . import identify
    from .analysis.validation import compare
    from .exceptions import FohwError

    start = time.perf_counter()
    _stage(args, f"identifying with {args.method} on {record.n_samples} samples ...")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")          # every warning, numpy's too, as one line
        res = identify(record, na=args.na, nb=args.nb, f_basis=args.f_basis,
                       g_basis=args.g_basis, method=args.method,
                       alpha_bounds=args.alpha_bounds, options=options, offset=args.offset,
                       operating_point=args.operating_point, output_map=args.output_map,
                       nk=args.nk, inputs=getattr(args, "inputs", None), progress=_bars(args))
        _progress(f"identified in {time.perf_counter() - start:.1f} s; simulating in free run "
                  "...")
        check = None
        if res.shared_model is not None or res.structure.n_inputs > 1:      # several: result.simulate
            try:
                check = compare(res, record, initial="fitted")    # its own estimation record
            except FohwError as exc:        # e.g. a constant output: no fit index
                warnings.warn(f"no free-run fit on the estimation record: {exc}", stacklevel=1)
    _stage(args, f"done in {_duration(time.perf_counter() - start)}")
    return res, check, caught


def _print_warnings(caught, skip=()):
    """Each caught warning's message once, in order, as ``fohw: warning: ...`` on stderr.

    Warnings of the categories in ``skip`` are left out.
    """
    for message in dict.fromkeys(str(w.message) for w in caught
                                 if not issubclass(w.category, tuple(skip))):
        print(f"fohw: warning: {message}", file=sys.stderr)


def _print_identified(args, res, check):
    """The estimates and the fit on the record: a summary, or JSON with ``--json``."""
    if args.json:
        out = {"alpha": res.alpha, "theta": dict(zip(res.parameter_names, res.theta.tolist())),
               "J": res.J, "converged": res.converged, "status": res.status.name,
               "method": res.method,
               "n_samples": res.n_samples, "message": res.message}
        if res.shared_model is not None:
            out["model"] = {k: getattr(res.shared_model, k).tolist() for k in "abpq"}
        if res.covariance is not None:
            out["standard_errors"] = res.standard_errors()
        out["estimation_record"] = _fit_dict(check)
        print(json.dumps(out, indent=1))
    else:
        print(res.summary())
        print(_fit_text(check))


def _save_identified(args, res, check):
    """``--save`` and ``--plot``; an error, and nothing written, if the fit FAILED.

    An IMPLAUSIBLE fit (its free run leaves the data's range) is plotted if asked, and not
    saved: an error says why.
    """
    from .results import Status

    if res.status == Status.FAILED:
        raise UsageError(f"the fit FAILED ({res.message.rstrip('.')}); nothing was saved or "
                         "plotted (the estimates above are the optimiser's last point).")
    implausible = res.status == Status.IMPLAUSIBLE
    if args.save and not implausible:
        from .io.jsonio import save_result

        save_result(res, args.save)
    if args.plot:
        if check is None:
            raise UsageError("--plot: the result has no model to simulate (see the message "
                             "above); no figure written.")
        fig = check.plot()
        fig.suptitle(f"fohw identify ({res.method}) on the estimation record: free run and "
                     "one-step prediction", fontsize=10)
        save_figure(fig, args.plot, dpi=120)
    if args.save and implausible:
        # the figure (if asked) shows why; a model file would be used as if it were sound
        raise UsageError(f"the fit is IMPLAUSIBLE ({res.message.rstrip('.')}); nothing was "
                         f"saved to {args.save}: its free run on its own record leaves the "
                         "data's range (give an offset or an operating point, or other "
                         "candidates).")


def _fit_dict(check):
    """The free run and the one-step prediction on the estimation record, JSON-ready."""
    if check is None:
        return None
    bounded = check.simulated is not None
    return {"free_run": {"bounded": bounded, "diverged": check.diverged or None,
                         "fit_percent": check.fit_simulation if bounded else None,
                         "rmse": check.rmse_simulation if bounded else None},
            "one_step": {"fit_percent": check.fit_prediction, "rmse": check.rmse_prediction}}


def _fit_text(check):
    if check is None:
        return "No free-run fit on the estimation record (see the messages above)."
    one_step = (f"one-step prediction fit {check.fit_prediction:.1f} % "
                f"(RMSE {check.rmse_prediction:.4g})")
    if check.simulated is None:
        return (f"On the estimation record: the FREE RUN DIVERGED ({check.diverged}); "
                f"{one_step}. A one-step fit says little about simulation: do not use this model "
                "to simulate.")
    return (f"On the estimation record: free-run simulation fit {check.fit_simulation:.1f} % "
            f"(RMSE {check.rmse_simulation:.4g}), stayed bounded; {one_step}.")


def _select(args):
    _check_select_args(args)
    record = _input_output(args, _read(args, args.data))
    candidates = _candidates(args)
    sel, caught = _run_selection(args, record, candidates)
    from .exceptions import NothingSelectedWarning

    # with nothing selected, the error below says it in one line
    _print_warnings(caught, skip=(NothingSelectedWarning,) if sel.best is None else ())
    print(f"{len(sel.rows)} candidates; {sel.validation}; {sel.seconds:.1f} s")
    print(sel.to_markdown(top=args.top))
    if sel.best is None:
        print("no candidate simulated; see the reasons above.")
        if args.csv:                    # the reasons, for the record
            sel.to_csv(args.csv)
        raise UsageError(_nothing_selected(sel))
    print(f"best: {sel.best_row['candidate']} (held-back fit {sel.best_row['fit']:.1f} %), "
          "refitted on all the data:")
    print(sel.best.summary())
    if args.save:
        from .io.jsonio import save_result

        save_result(sel.best, args.save)
    if args.csv:
        sel.to_csv(args.csv)
    if args.plot:
        save_figure(sel.plot(), args.plot, dpi=120)
    return 0


def _check_select_args(args):
    """``--jobs``, ``--top`` and the output files, before the run."""
    from ._parallel import max_jobs

    if not 1 <= args.jobs <= max_jobs():
        raise UsageError(f"--jobs must be from 1 to {max_jobs()}, the processors this process may "
                         f"use (more worker processes only add start-up time); got {args.jobs}.")
    if args.top < 1:
        raise UsageError(f"--top must be >= 1; got {args.top}.")
    _check_file_out(args.save, "--save", [args.data])
    _check_file_out(args.csv, "--csv", [args.data])
    _check_plot_out(args.plot, "--plot", [args.data])


def _candidates(args):
    """The candidates of the grid ``--na``/``--nb``/``--nk``/``--f-basis``/``--g-basis``/``--orders``."""
    from .analysis.selection import expand_candidates

    grid = {"na": args.na, "f_basis": args.f_basis, "g_basis": args.g_basis,
            "orders": args.orders}
    if args.output_map is not None:
        grid["output_map"] = args.output_map
    if args.nb is not None:
        grid["nb"] = args.nb
    if args.nk is not None:
        grid["nk"] = args.nk
    candidates = expand_candidates(grid)
    if args.nb is None:                 # nb = na
        candidates = [dict(c, nb=c["na"]) for c in candidates]
    return candidates


def _run_selection(args, record, candidates):
    """Fit the candidates (in ``--jobs`` processes): ``(selection, caught warnings)``."""
    import time
    import warnings

    from ._parallel import process_pool
    from .analysis.selection import select_structure

    start = time.perf_counter()
    _stage(args, f"fitting {len(candidates)} candidate{'s' * (len(candidates) != 1)} "
           f"({args.method}) on {record.n_samples} samples ...")
    workers = min(args.jobs, len(candidates))
    pool = process_pool(workers) if workers > 1 else None
    try:
        with warnings.catch_warnings(record=True) as caught:
            for category in _fohw_warnings():
                warnings.simplefilter("always", category)
            sel = select_structure(record, candidates, validation=args.validation,
                                   method=args.method, offset=args.offset,
                                   operating_point=args.operating_point,
                                   executor=pool, progress=_bars(args),
                                   **({"inputs": args.inputs} if args.inputs else {}))
    finally:
        if pool is not None:
            pool.shutdown()
    _stage(args, f"done in {_duration(time.perf_counter() - start)}")
    return sel, caught


def _nothing_selected(sel):
    """The error message when no model was selected: what failed, and the first reason."""
    failed = [r for r in sel.rows if r["status"] != "ok"]
    n = len(sel.rows)
    what = ("the winner could not be refitted" if len(failed) < n else
            "the only candidate failed" if n == 1 else f"all {n} candidates failed")
    first = ""
    if failed and failed[0].get("reason"):
        reason = str(failed[0]["reason"]).rstrip(".")
        first = f" ({'the first: ' if n > 1 else ''}{reason[:200]}" \
                f"{' ...' if len(reason) > 200 else ''})"
    return (f"no model selected: {what}{first}; every reason is in the table on stdout, and "
            "nothing was saved.")


def _load_model_or_result(path):
    """A fohw-model file's model, or a fohw-result file's result (``(kind, object)``)."""
    from .io.files import read_json
    from .io.jsonio import model_from_dict, result_from_dict

    d = read_json(path)                       # read once; the format says which it is
    if isinstance(d, dict) and d.get("format") == "fohw-result":
        return "result", result_from_dict(d, path=os.fspath(path))
    if isinstance(d, dict) and d.get("format") != "fohw-model":
        raise UsageError(f"{path} is neither a fohw-model file (fohw.save_model) nor a "
                         "fohw-result file (fohw identify --save, fohw.save_result).")
    return "model", model_from_dict(d, path=os.fspath(path))


def _model_input(args, loaded, table):
    """The input columns of ``--column`` for the loaded model: one, or one per input.

    A result with several inputs takes as many columns, matched by the names it keeps when
    they are header names of the file (``--column`` may list them in any order); by default the
    columns of those names, else the file's columns in order when it has exactly that many.
    """
    import numpy as np

    from .model.simulate import generic_model

    other = generic_model(loaded)
    if other is not None:                   # a model (or fit) of another kind: its input columns
        inputs, n = (), other.n_inputs
    else:
        inputs = loaded.structure.inputs if hasattr(loaded, "structure") else ()
        n = max(1, len(inputs))
    names = table.names
    spec = args.column
    if spec is None and inputs and names and all(i in names for i in inputs):
        spec = ",".join(inputs)
    given = [p.strip() for p in spec.split(",")] if spec is not None else None
    if given is not None and len(given) != n and n > 1:
        example = ",".join(inputs) if inputs else ",".join(str(k) for k in range(n))
        raise UsageError(f"--column needs {n} entries, one per input of {args.model}"
                         + (f" ({', '.join(inputs)})" if inputs else "")
                         + f"; got {len(given)}. E.g. --column {example}.")
    if given is not None and len(given) != n:
        raise UsageError(f"--column gives {len(given)} column(s), but {args.model} has {n} "
                         f"input(s): give {'one column' if n == 1 else 'one column per input'}.")
    if given is not None and n > 1 and sorted(given) == sorted(inputs):
        spec = ",".join(inputs)         # by the result's names, whatever the order given
    idx = _column_indices(table, spec, n, args.input, flag="--column", what="input")
    return table.data[:, idx[0]] if n == 1 else np.column_stack([table.data[:, j] for j in idx])


def _simulate(args):
    import time
    import warnings

    import numpy as np

    from .io.text import table_time
    from .model.lagged.initial import initial_state, simulate_from
    from .model.lagged.simulation import equation_noise
    from .model.simulate import generic_model, own_dt, simulate

    _check_file_out(args.output, "--output", [args.input, args.model])
    kind, loaded = _load_model_or_result(args.model)
    table = _read(args, args.input)
    t, file_dt, time_unit = table_time(table)
    if t is not None:                   # instants: uniform ones say the sampling time
        from .record import Record

        grid = Record(u=t, y=t, t=t)
        if not grid.uniform:
            raise UsageError(f"{args.input}: the instants of its time column are not uniform; "
                             "fohw simulate runs on a uniform grid: resample the input "
                             "(fohw.model.irregular.resample), or simulate a fohw.Record with "
                             "its instants in Python (fohw.simulate).")
        file_dt = grid.dt
    other = generic_model(loaded)
    step = own_dt(loaded)
    if file_dt is not None and step is not None and abs(file_dt - step) > 1e-12 * file_dt:
        raise UsageError(f"{args.input} is sampled every {file_dt:g} (its Ts) but {args.model} "
                         f"has dt = {step:g}: fohw does not change a sampling time silently.")
    if other is not None and args.initial is not None:   # a model (or fit) of another kind
        raise UsageError(f"--initial is for the lagged HammersteinWiener kind; {args.model} "
                         f"holds a {type(other).__name__}, simulated from its own initial state.")
    u = _model_input(args, loaded, table)
    if other is None and kind == "result" and args.initial is None \
            and loaded.structure.past == "estimate":
        raise UsageError(f"{args.model} was fitted with past='estimate': its levels (u_past, "
                         f"y_past) = ({loaded.past[0]:.6g}, {loaded.past[1]:.6g}) are those "
                         "before its estimation record. Say which initial state to start "
                         "from: --initial fitted (those levels: for the estimation record "
                         "itself) or --initial rest (the operating point).")
    start = time.perf_counter()
    _stage(args, f"simulating {u.shape[0]} samples ...")
    with warnings.catch_warnings(record=True) as caught:
        for category in _fohw_warnings():
            warnings.simplefilter("always", category)
        if other is not None:       # white noise on the output of an output-error model
            y = other.simulate(u) + equation_noise(u.shape[0], None, args.noise_std, args.seed)
        elif kind == "result":      # the predictor that was fitted: theta itself, as identify's
            noise = equation_noise(u.shape[0], None, args.noise_std, args.seed)   # free-run fit used
            y = loaded.simulate(u, initial=args.initial, noise=noise)
        elif args.initial is None:
            y = simulate(loaded, u, noise_std=args.noise_std, random_state=args.seed)
        else:
            y = simulate_from(loaded, u, initial_state(loaded, u, None, args.initial),
                              noise_std=args.noise_std, random_state=args.seed)
    _stage(args, f"done in {_duration(time.perf_counter() - start)}")
    for w in caught:
        print(f"fohw: warning: {w.message}", file=sys.stderr)
    text = _output_table(args, loaded, y, t, file_dt, time_unit, table)
    if args.output:
        from .io.files import write_text

        write_text(text, args.output)
    else:
        sys.stdout.write(text)
    return int(not np.all(np.isfinite(y)))


def _fit(args):
    """``fohw fit``: :func:`fohw.fit` of a saved start model on a data file."""
    import time
    import warnings

    from . import fit
    from .model.base import Model
    from .results import Status

    _check_file_out(args.save, "--save", [args.data, args.model])
    _check_plot_out(args.plot, "--plot", [args.data, args.model])
    start = _start_model(args.model)
    if not isinstance(start, Model):
        raise UsageError(f"{args.model} holds no model to start from.")
    table = _read(args, args.data)
    n_in = start.n_inputs
    record = _table_record(args, table, _column_indices(table, args.columns, n_in + 1,
                                                        args.data), args.data)
    options = {name: getattr(args, name) for name in ("order_grid", "n_starts", "max_nfev",
                                                      "warmup")
               if getattr(args, name) is not None}
    began = time.perf_counter()
    _stage(args, f"fitting a {type(start).__name__} on {record.n_samples} samples ...")
    with warnings.catch_warnings(record=True) as caught:
        for category in _fohw_warnings():
            warnings.simplefilter("always", category)
        res = fit(start, record, **options)
    _stage(args, f"done in {_duration(time.perf_counter() - began)}")
    _print_warnings(caught)
    if args.json:
        se = res.standard_errors() if res.covariance is not None else {}
        ci = res.confidence_intervals() if res.covariance is not None else {}
        print(json.dumps({
            "kind": type(res.model).__name__, "status": res.status.name, "message": res.message,
            "estimates": {n: res.parameters[n].value for n in res.parameters},
            "free": list(res.free_names), "standard_errors": se or None,
            "confidence_intervals_95": {n: list(v) for n, v in ci.items()} or None,
            "sse": res.sse, "rmse": res.rmse, "n_samples": res.n_samples,
            "data": dict(res.data)}, indent=1, default=_json_default))
    else:
        print(res.summary())
    if res.status == Status.FAILED:
        raise UsageError(f"the fit FAILED ({res.message.rstrip('.')}); nothing was saved or "
                         "plotted.")
    if args.save:
        from .io.jsonio import save_result

        save_result(res, args.save)
    if args.plot:
        from .analysis.validation import compare

        fig = compare(res, record).plot()
        fig.suptitle(f"fohw fit: {type(res.model).__name__} on {os.path.basename(args.data)}",
                     fontsize=10)
        save_figure(fig, args.plot, dpi=120)
    return 0


#: What a start spec (``fohw fit --model SPEC.json``) holds besides its kind and arguments.
SPEC_FIELDS = ("kind", "args", "fixed", "bounds")
#: Classes a spec's argument may name as ``{"kind": ..., "args": ...}`` besides the model kinds.
SPEC_HELPERS = ("OCVTable", "RC", "ZARC", "Warburg")


def _start_model(path):
    """``fohw fit``'s start: a model file, a result file's model, or a small spec.

    A spec is a JSON object ``{"kind": KIND, "args": {...}}``, with optional ``"fixed": [names]``
    and ``"bounds": {name: [low, high]}`` (``null``: unbounded): the model
    ``KIND(**args)`` of a registered kind (:func:`fohw.model.base.registered_kinds`), its
    parameters then fixed and bounded as given. An argument that is itself ``{"kind": ...,
    "args": ...}`` is built first: a model of a registered kind (``FractionalHW``'s ``G``) or
    one of :data:`SPEC_HELPERS` (an ``EquivalentCircuit``'s ``ocv`` or ``elements``).
    """
    from .io.files import read_json
    from .model.base import Model

    d = read_json(path)
    if isinstance(d, dict) and "format" not in d and "kind" in d:
        start = _model_from_spec(d, path)
    else:
        kind, loaded = _load_model_or_result(path)
        start = loaded if kind == "model" else getattr(loaded, "model", None)
    if not isinstance(start, Model):
        raise UsageError(f"{path} holds no model to start from.")
    return start


def _model_from_spec(spec, path, where="the spec"):
    """The model (or helper) a spec describes (:func:`_start_model`); errors name the field."""
    import fohw

    from .model.base import Model, model_class, registered_kinds

    unknown = sorted(set(spec) - set(SPEC_FIELDS))
    if unknown:
        raise UsageError(f"{path}: {where} has fields {unknown} that a spec does not; a spec has "
                         f"{', '.join(SPEC_FIELDS)} (a saved model file has \"format\": "
                         "\"fohw-model\").")
    kind, args = spec["kind"], spec.get("args", {})
    if kind in SPEC_HELPERS:
        cls = getattr(fohw, kind)
    else:
        try:
            cls = model_class(kind)
        except ValueError:
            raise UsageError(f"{path}: {where}'s kind {kind!r} is neither a model kind "
                             f"({', '.join(registered_kinds())}) nor one of "
                             f"{', '.join(SPEC_HELPERS)}.") from None
    if not isinstance(args, (dict, list)):
        raise UsageError(f"{path}: {where}'s \"args\" must be an object of keyword arguments "
                         f"(or a list of positional ones) of {kind}; got {type(args).__name__}.")

    def built(value, name):
        if isinstance(value, dict) and "kind" in value:
            return _model_from_spec(value, path, f"{where}'s argument {name}")
        if isinstance(value, list):
            return [built(v, f"{name}[{k}]") for k, v in enumerate(value)]
        return value

    try:
        model = (cls(**{k: built(v, k) for k, v in args.items()}) if isinstance(args, dict)
                 else cls(*[built(v, str(k)) for k, v in enumerate(args)]))
    except (TypeError, ValueError) as exc:          # ParameterError is a ValueError
        raise UsageError(f"{path}: {where}: {kind}(...) refused its arguments: {exc}") from None
    extra = {n for n in ("fixed", "bounds") if n in spec}
    if extra and not isinstance(model, Model):
        raise UsageError(f"{path}: {where}: {' and '.join(sorted(extra))} apply to a model's "
                         f"parameters; {kind} has none.")
    return _spec_settings(model, spec, path, where) if extra else model


def _spec_settings(model, spec, path, where):
    """A spec's ``fixed`` names and ``bounds`` on the model's parameters, checked by name."""
    params = model.parameters
    fixed, bounds = spec.get("fixed", []), spec.get("bounds", {})
    if not (isinstance(fixed, list) and all(isinstance(n, str) for n in fixed)):
        raise UsageError(f"{path}: {where}'s \"fixed\" must be a list of parameter names.")
    if not isinstance(bounds, dict):
        raise UsageError(f"{path}: {where}'s \"bounds\" must map parameter names to "
                         "[low, high].")
    for name in [*fixed, *bounds]:
        if name not in params:
            raise UsageError(f"{path}: {where} names the parameter {name!r}, which "
                             f"{type(model).__name__} does not have; it has "
                             f"{', '.join(params)}.")
    try:
        for name in fixed:
            params = params.replace(name, fixed=True)
        for name, pair in bounds.items():
            if not (isinstance(pair, list) and len(pair) == 2):
                raise UsageError(f"{path}: {where}'s bounds of {name!r} must be [low, high] "
                                 f"(null: unbounded); got {pair!r}.")
            params = params.replace(name, bounds=tuple(pair))
        return model.with_parameters(params)
    except (TypeError, ValueError) as exc:
        raise UsageError(f"{path}: {where}: {exc}") from None


def _json_default(obj):
    """JSON of what ``json`` does not know (numpy scalars and arrays, tuples of a result)."""
    import numpy as np

    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return str(obj)


def _output_table(args, loaded, y, t, dt, time_unit, table):
    """The simulated output as CSV (:func:`fohw.io.text.format_table`).

    ``#`` comments, a header, the time column (when the input gives the time) and the output,
    with units.
    """
    import numpy as np

    from .io.text import format_table

    data = getattr(loaded, "data", None)
    data = data if isinstance(data, dict) else {}
    out_name = data.get("output_name") or "y"
    out_unit = data.get("output_unit") or ""
    names = table.names or []
    time_name = names[table.time_column] if table.time_column is not None and names else "t"
    if out_name == time_name or out_name in names:
        out_name = f"{out_name}_simulated"
    columns, units = {}, {}
    if t is not None:                   # the input's own instants
        columns[time_name] = t
    elif dt is not None:                # the time of each sample
        columns[time_name] = np.arange(y.size) * dt
    if columns and time_unit:
        units[time_name] = time_unit
    columns[out_name] = y
    if out_unit:
        units[out_name] = out_unit
    what = "the simulated output" + (f" and the time ({time_name})" if len(columns) > 1 else
                                     " (the input gives no time: one row per sample)")
    return format_table(columns, dt=dt, time_unit=time_unit, units=units,
                        comments=[f"fohw simulate --model {os.path.basename(str(args.model))} "
                                  f"--input {os.path.basename(str(args.input))}: {what}"])


def _compare(args):
    import warnings

    from .analysis.validation import compare

    _check_plot_out(args.plot, "--plot", [args.data, args.model])

    from .model.simulate import generic_model

    _, loaded = _load_model_or_result(args.model)
    table = _read(args, args.data)
    other = generic_model(loaded)
    if other is not None:                   # a model (or fit) of any kind: its inputs, then y
        if args.initial is not None:
            raise UsageError(f"--initial is for the lagged HammersteinWiener kind; {args.model} "
                             f"holds a {type(other).__name__}, simulated from its own initial "
                             "state.")
        n_in = other.n_inputs
    else:
        n_in = loaded.structure.n_inputs if hasattr(loaded, "structure") else 1
    record = _table_record(args, table, _column_indices(table, args.columns, n_in + 1,
                                                        args.data), args.data)
    u = record.u
    _stage(args, f"scoring on {u.shape[0]} samples ...")
    with warnings.catch_warnings(record=True) as caught:
        for category in _fohw_warnings():
            warnings.simplefilter("always", category)
        check = compare(loaded, record, initial=args.initial, n_init=args.n_init)
    _print_warnings(caught)
    if args.json:
        out = _fit_dict(check)
        out.update(status=check.status, n_samples=int(u.shape[0]), n_init=check.n_init)
        print(json.dumps(out, indent=2))
    else:
        print(f"{args.model} on {args.data} ({u.shape[0]} samples"
              + (f", the first {check.n_init} left out" if check.n_init else "") + "):")
        print(check.to_markdown())
    if args.plot:
        fig = check.plot()
        fig.suptitle(f"fohw compare: {os.path.basename(args.model)} on "
                     f"{os.path.basename(args.data)}", fontsize=10)
        save_figure(fig, args.plot, dpi=120)
    return 0


def _data(args):
    """``fohw data``: list the records, or write one to ``--out`` (default stdout)."""
    from .datasets import BATTERY_FILENAME, PULSES_FILENAME, SHIPPED

    if args.name is None:
        for name, (filename, _, what) in SHIPPED.items():
            print(f"{name:15s} {filename}: {what}")
        print(f"{'battery':15s} {BATTERY_FILENAME}: an LG M50LT lithium-ion cell's drive cycle "
              "(164 953 samples at 0.15 s; written as columns t, i, v, soc), its open-circuit "
              "voltage and impedance spectra (all of it: fohw.datasets.battery_cell())")
        print(f"{'pybamm_pulses':15s} {PULSES_FILENAME}: 15 pulse records of an LG M50 cell "
              "simulated with PyBaMM (DFN, Chen2020) at 5 temperatures x 3 states of charge "
              "(one per file: --temperature T --soc S, default 25 and 0.5; written as columns t, i, "
              "soc, temperature, v; all 15 and the OCV table: fohw.datasets.pybamm_pulses())")
        print(f"{'paper_example':15s} simulated (Section 6.1, Eq. 57): columns u, y; --samples N "
              "(default 2000), --seed S")
        print("write one with `fohw data NAME --out FILE`, or read a text record in place as "
              "@NAME (e.g. `fohw identify @cascaded_tanks --columns uEst,yEst ...`).")
        return 0
    _check_file_out(args.out, "--out")
    _check_pulse_args(args)
    text = _data_text(args)
    if args.out is None:
        sys.stdout.write(text)
    else:
        from .io.files import write_text

        write_text(text, args.out)
    return 0


def _check_pulse_args(args):
    """``--temperature`` and ``--soc`` choose one of pybamm_pulses' records; refused elsewhere."""
    from .datasets import pybamm_pulses

    given = [f"--{n}" for n in ("temperature", "soc") if getattr(args, n) is not None]
    if args.name != "pybamm_pulses":
        if given:
            verb = "choose" if len(given) > 1 else "chooses"
            raise UsageError(f"{' and '.join(given)} {verb} a record of pybamm_pulses; "
                             f"{args.name} has none to choose")
        return
    args.temperature = 25.0 if args.temperature is None else args.temperature
    args.soc = 0.5 if args.soc is None else args.soc
    records, _ = pybamm_pulses()
    for flag, value, have in (("--temperature", args.temperature, {r.ambient for r in records}),
                              ("--soc", args.soc, {r.soc0 for r in records})):
        if value not in have:
            choices = ", ".join(f"{v:g}" for v in sorted(have))
            raise UsageError(f"{flag} must be one of {choices} (the records of pybamm_pulses); "
                             f"got {value:g}")


def _data_text(args):
    """The CSV text of ``fohw data NAME`` (:func:`fohw.io.text.format_table`)."""
    import numpy as np

    from .datasets import paper_example
    from .io.text import format_table

    pandas = 'pandas: pd.read_csv(path, comment="#")'
    if args.name == "paper_example":
        d = paper_example(args.samples, random_state=args.seed)
        return format_table({"u": d.u, "y": d.y}, comments=[
            f"the paper's example (Section 6.1, Eq. 57), simulated: {args.samples} samples, "
            f"seed {args.seed} (fohw data paper_example --samples {args.samples} --seed "
            f"{args.seed}); one sample is the time unit", pandas])
    if args.name == "battery":
        from .datasets import BATTERY_SOURCE, battery_cell

        cell = battery_cell()
        t = np.round(np.arange(cell.i.size) * cell.dt, 2)
        return format_table({"t": t, "i": cell.i, "v": cell.v, "soc": cell.soc}, dt=cell.dt,
                            time_unit="s", units={"t": "s", "i": "A", "v": "V", "soc": "1"},
                            comments=["an LG M50LT lithium-ion cell's drive cycle (fohw data "
                                      "battery): t time, i current (negative: discharge), v "
                                      "terminal voltage, soc state of charge (a fraction)",
                                      f"source: {BATTERY_SOURCE}", pandas])
    if args.name == "pybamm_pulses":
        from .datasets import PULSES_FILENAME, pybamm_pulses

        records, _ = pybamm_pulses(temperatures=[args.temperature], socs=[args.soc])
        rec = records[0]
        t = np.round(np.arange(rec.n_samples) * rec.dt, 2)
        return format_table({"t": t, "i": rec.i, "soc": rec.soc, "temperature": rec.temperature,
                             "v": rec.v}, dt=rec.dt, time_unit="s",
                            units={"t": "s", "i": "A", "soc": "1", "temperature": "degC", "v": "V"},
                            comments=[f"a pulse test of an LG M50 cell simulated with PyBaMM (DFN, "
                                      f"Chen2020) at {rec.ambient:g} degC from soc {rec.soc0:g} "
                                      f"(fohw data pybamm_pulses --temperature {rec.ambient:g} --soc "
                                      f"{rec.soc0:g}): t time, i current (positive: charge), soc "
                                      "state of charge (coulomb-counted), temperature cell "
                                      "temperature, v terminal voltage; u = i,soc,temperature is "
                                      "fohw.CircuitTables' input",
                                      f"from {PULSES_FILENAME} (fohw.datasets.pybamm_pulses())", pandas])
    if args.name == "cascaded_tanks":
        from .datasets import CASCADED_TANKS_SOURCE, cascaded_tanks

        tanks = cascaded_tanks()
        est, val = tanks.estimation, tanks.validation
        return format_table({"uEst": est.u, "uVal": val.u, "yEst": est.y, "yVal": val.y},
                            dt=est.dt, time_unit=est.time_unit,
                            units={k: "V" for k in ("uEst", "uVal", "yEst", "yVal")},
                            comments=[f"{tanks.name} (fohw data cascaded_tanks): u pump "
                                      "voltage, y lower tank level (sensor voltage); estimate "
                                      "on uEst,yEst, validate on uVal,yVal",
                                      f"source: {CASCADED_TANKS_SOURCE}", pandas])
    from .datasets import ROBOT_ARM_SOURCE, robot_arm

    arm = robot_arm()
    return format_table({"torque": arm.u, "acceleration": arm.y}, comments=[
        f"{arm.name} (fohw data robot_arm): torque = reaction torque (input), acceleration = "
        "arm acceleration (output); the source gives no sampling time and no units",
        f"source: {ROBOT_ARM_SOURCE}", pandas])


def _reproduce(args):
    _check_outdir(args.outdir)
    if args.what in _REPRODUCE:
        from .paper.table2 import main as example_main

        forwarded = ["--outdir", args.outdir, "--seed", str(args.seed)]
        if args.fast:
            forwarded.append("--fast")
        if args.forgetting is not None:
            if not 0.0 < args.forgetting <= 1.0:
                raise UsageError(f"--forgetting must be in (0, 1]; got {args.forgetting:g}.")
            forwarded += ["--forgetting", repr(args.forgetting)]
        return example_main(_REPRODUCE[args.what], f"fohw reproduce {args.what}", forwarded)
    if args.forgetting is not None:
        raise UsageError(f"--forgetting applies to table2 and figures, not to {args.what}.")
    forwarded = ["--outdir", args.outdir] + (["--fast"] if args.fast else [])
    if args.what == "forgetting":
        from .paper.forgetting import main as forgetting_main

        return forgetting_main(forwarded, "fohw reproduce forgetting")
    if args.what == "robot-arm":
        from .paper.robot_arm import main as study
        if args.data:
            forwarded += ["--data", args.data]
    else:
        from .paper.accuracy import main as study
    return study(forwarded)


def main(argv=None) -> int:
    """Run the ``fohw`` command; return its exit status."""
    from ._startup import release

    try:
        release()                   # Ctrl-C raises KeyboardInterrupt again (see fohw._startup)
        return _run(argv)
    except KeyboardInterrupt:        # Ctrl-C: files being saved are written atomically
        print("fohw: interrupted; no file was left half-written.", file=sys.stderr)
        return 130


def _run(argv):
    from .exceptions import FohwError

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    handler = {"identify": _identify, "select": _select, "simulate": _simulate,
               "compare": _compare, "fit": _fit, "data": _data, "reproduce": _reproduce}
    try:
        return handler[args.command](args)
    except (UsageError, FohwError, FileNotFoundError) as exc:
        message = str(exc).replace("\n", " ")
        print(f"fohw: error: {message}", file=sys.stderr)
        return 2
    except BrokenPipeError:          # e.g. `fohw identify ... | head`: the reader left early
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except OSError as exc:           # permissions, full disk, ...: one line, no traceback
        where = f" ({exc.filename})" if exc.filename else ""
        print(f"fohw: error: {exc.strerror or exc}{where}.", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
