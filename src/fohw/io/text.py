"""Measured records from text files: CSV or whitespace columns, headers, comments, values given once.

:func:`read_record` is the loader users call (``fohw.read_record``); :func:`read_table` is the
parser under it and under the command line. What they accept, and what they refuse rather than
guess:

* separators: semicolons, commas or whitespace, whichever the first line (header or data) uses;
  a trailing separator (an empty last field on every line) is ignored; decimal commas
  (``0,5``) on request (``decimal=","``);
* a UTF-8 byte-order mark; blank lines; comment lines starting with ``#`` or ``%``;
* a header line of names, only if **none** of its fields is a number (a first row such as
  ``0x10 1`` or ``0.5 0.3.1`` is an error at line 1, never a header that drops a sample);
* a column given once: a value on the first data line and nothing below (the cascaded-tanks
  file gives ``Ts`` so); it is returned as a scalar, not as a signal;
* anything else that is not a number, a missing value (``NA``, ``nan``, an empty field, ...)
  or a second header line is an error naming the line and the column: fohw fills no gaps.

Clean files are parsed by :func:`numpy.loadtxt` (5 million rows in seconds); the rest, and every
error, by a line-by-line reader.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import DataFileError, ParameterError
from ..record import Record

__all__ = ["Table", "read_table", "read_record"]

#: Names of a column given once that :func:`read_record` takes as the sampling time.
SAMPLING_TIME_NAMES = ("ts", "dt", "sampling_time", "sample_time")


@dataclass
class Table:
    """The numeric content of a text file.

    Attributes
    ----------
    data : ndarray, shape (n_rows, n_columns)
        The full columns (signals).
    names : list of str or None
        Their header names (``None`` without a header).
    scalars : dict
        Columns given once, ``{name or column number: value}``.
    path : str
    skipped : list of str
        What was read but is not data: the header line, comment and blank lines, a trailing
        separator.
    """

    data: np.ndarray
    names: list | None
    scalars: dict = field(default_factory=dict)
    path: str = ""
    skipped: list = field(default_factory=list)


def parse_number(text):
    """A number as written in data files (ASCII, no digit separators), or ``None``.

    ``float`` alone would take ``1_000`` and non-ASCII digits, which numpy's reader refuses.

    Examples
    --------
    >>> from fohw.io.text import parse_number
    >>> parse_number("-1.5e3"), parse_number("1_000"), parse_number("1,5")
    (-1500.0, None, None)
    """
    if "_" in text or not text.isascii():
        return None
    try:
        return float(text)
    except ValueError:
        return None


#: Spellings of a missing value; fohw never fills a gap, so each is an error naming its place.
MISSING = ("", "na", "n/a", "nan", "null", "none", "-", "?")


def _delimiter(text, decimal):
    """The separator of a file, from its first non-comment line (the header or the data)."""
    if ";" in text:
        return ";"
    if "," in text and decimal != ",":
        return ","
    return None                                         # whitespace


def _split(text, delimiter):
    return [f.strip() for f in (text.split(delimiter) if delimiter else text.split())]


def _header(fields, decimal):
    """The column names if no field of the line is a number (a header line), else None."""
    if any(parse_number(_decimal(f, decimal)) is not None for f in fields if f):
        return None
    return [f.strip('"').strip("'") for f in fields]


def _comma_separated_header(text, delimiter, decimal):
    """True for a header split at whitespace that holds commas while commas are decimal marks.

    ``u,y`` read with ``decimal=","`` is one column named "u,y" whose rows ``1,2`` read as 1.2:
    a comma-separated file given the wrong decimal mark, refused rather than misread.
    """
    return decimal == "," and delimiter is None and "," in text


def _comma_header_error(path, lineno, text):
    return DataFileError(f"{path}: line {lineno}: the header {text!r} is separated by commas, "
                         "but decimal=',' makes commas decimal marks (1,5 = 1.5), so its rows "
                         "would be misread; with decimal commas separate the columns by ';' or "
                         "whitespace, or read a comma-separated file with decimal='.'.")


def _header_note(line, names):
    return f"header on line {line} ({', '.join(n for n in names if n)})"


def _decimal(field, decimal):
    return field.replace(",", ".") if decimal == "," else field


def read_table(path, *, decimal=".") -> Table:
    """Parse a numeric text table (see the module notes for what is accepted).

    Parameters
    ----------
    path : str or os.PathLike
    decimal : {".", ","}
        The decimal mark. With ``","`` (``0,5`` for one half) the columns must be separated by
        ``;`` or whitespace.

    Returns
    -------
    Table
        ``Table.skipped`` says what was not read as data (the header, comment and blank lines,
        trailing separators).

    Raises
    ------
    FileNotFoundError
        No such file.
    DataFileError
        A directory, an unreadable file, text that is not UTF-8, a field that is not a number
        (with a hint when it looks like a decimal comma), a missing value (``NA``, empty, ...)
        named by line and column, a second header line, a header separated by commas while
        ``decimal=","``, a row with another number of fields, a non-finite value, or no data.

    Notes
    -----
    A clean file (one header at most, no comment marks after it, the same number of fields on
    every line) is parsed by :func:`numpy.loadtxt`'s compiled reader; anything else, and every
    error, goes through a line-by-line reader that names the line. Both give the same numbers
    and names (``tests/test_reliability.py``); only the line reader counts blank lines inside
    the data in ``Table.skipped``.
    """
    path = os.fspath(path)
    if decimal not in (".", ","):
        raise ParameterError(f"`decimal` must be '.' or ','; got {decimal!r}.")
    if os.path.isdir(path):
        raise DataFileError(f"{path!r} is a directory, not a data file.")
    if not os.path.exists(path):
        raise FileNotFoundError(f"data file not found: {path!r}")
    try:
        table = _read_fast(path, decimal)
    except OSError as exc:
        raise DataFileError(f"{path}: cannot be read ({exc.strerror or exc}).") from None
    return table if table is not None else _read_lines(path, decimal)


def _head(path, decimal):
    """The separator, the header and its line number, from the first lines of the file."""
    delimiter, names, header_line = "unset", None, 0
    with open(path, encoding="utf-8-sig") as fh:
        for lineno, line in enumerate(fh, start=1):
            line = line.strip()
            if not line or line[0] in "#%":
                continue
            if delimiter == "unset":
                delimiter = _delimiter(line, decimal)
            header = _header(_split(line, delimiter), decimal) if names is None else None
            if header is not None:
                if _comma_separated_header(line, delimiter, decimal):
                    return None                  # the line reader names the error
                names, header_line = header, lineno
                continue
            return delimiter, names, header_line
    return None


def _read_fast(path, decimal):
    """numpy.loadtxt on a clean file; None when the file needs the line reader.

    The file is read from disk by loadtxt's compiled reader (never held as text, except with
    decimal commas); a comment mark, a missing value, a ragged row, a value given once, text
    that is not UTF-8 or anything else unusual makes loadtxt fail, and the line reader then
    reads the file (and names the line of any error).
    """
    try:
        head = _head(path, decimal)
        if head is None:                         # no data line, or a header the line reader refuses
            return None
        delimiter, names, header_line = head
        source = path
        if decimal == ",":
            with open(path, encoding="utf-8-sig") as fh:
                source = io.StringIO(fh.read().replace(",", "."))
        data = np.loadtxt(source, delimiter=delimiter, skiprows=header_line, ndmin=2,
                          dtype=np.float64, comments=None, encoding="utf-8-sig")
    except (ValueError, UnicodeDecodeError):
        return None
    if data.size == 0 or not np.all(np.isfinite(data)) \
            or (names is not None and len(names) != data.shape[1]):
        return None
    skipped = [_header_note(header_line, names)] if names else []
    if header_line > 1:
        skipped.append(f"{header_line - 1} comment or blank line(s)")
    return Table(data=data, names=names, scalars={}, path=path, skipped=skipped)


def _field_error(path, lineno, value, column, decimal):
    where = f"line {lineno}: "
    col = f" (column {column!r})"
    if value.strip().lower() in MISSING:
        what = "no value (an empty field)" if not value.strip() else \
            f"{value!r}, a missing value"
        return DataFileError(f"{path}: {where}column {column!r} has {what}; fohw does not fill "
                             "gaps: remove the row or fill it yourself.")
    hint = ""
    if decimal == "." and parse_number(value.replace(",", ".")) is not None:
        hint = (" It looks like a decimal comma: pass decimal=',' (fohw: --decimal-comma), "
                "with columns separated by ';' or whitespace.")
    return DataFileError(f"{path}: {where}{value!r} is not a number{col}.{hint}")


def _read_lines(path, decimal):
    """The line-by-line reader: any layout the module notes allow, and every error by line."""
    with open(path, "rb") as fh:
        raw_lines = fh.read().splitlines()
    names, rows, linenos, delimiter, header_line = None, [], [], "unset", 0
    n_comments = 0
    for lineno, raw in enumerate(raw_lines, start=1):
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise DataFileError(f"{path}: line {lineno} is not UTF-8 text.") from None
        if lineno == 1:
            text = text.lstrip("\ufeff")                 # a byte-order mark
        text = text.strip()
        if not text or text[0] in "#%":
            n_comments += 1
            continue
        if delimiter == "unset":
            delimiter = _delimiter(text, decimal)
        fields = _split(text, delimiter)
        if not rows and _header(fields, decimal) is not None:
            if names is None:
                if _comma_separated_header(text, delimiter, decimal):
                    raise _comma_header_error(path, lineno, text)
                names, header_line = _header(fields, decimal), lineno
                continue
            # a second line without numbers: decimal commas, or a second header
            commas = [f for f in fields if parse_number(f.replace(",", ".")) is not None]
            if commas and decimal == ".":
                raise _field_error(path, lineno, commas[0], fields.index(commas[0]), decimal)
            if not all(f.lower() in MISSING for f in fields):
                raise DataFileError(f"{path}: line {lineno} looks like a second header line "
                                    f"(no field is a number) after the header on line "
                                    f"{header_line}; fohw reads one header line: start the "
                                    "others with '#'.")
        rows.append(fields)
        linenos.append(lineno)
    if not rows:
        raise DataFileError(f"{path}: no data lines found.")
    width = max(len(r) for r in rows)
    if names is not None:
        width = max(width, len(names))
    # trailing separators: drop columns that are empty on every line (and unnamed)
    cells = [r + [""] * (width - len(r)) for r in rows]
    keep = [j for j in range(width)
            if any(c[j] for c in cells) or (names is not None and j < len(names) and names[j])]
    skipped = [_header_note(header_line, names)] if names else []
    if n_comments:
        skipped.append(f"{n_comments} comment or blank line(s)")
    if len(keep) < width:
        skipped.append("a trailing separator")
    if names is not None:
        names = names + [""] * (width - len(names))
    columns, col_names, scalars = [], [], {}
    for j in keep:
        name = names[j] if names is not None else None
        label = name or j
        values = [_decimal(c[j], decimal) for c in cells]
        filled = [i for i, v in enumerate(values) if v]
        if not filled:
            raise DataFileError(f"{path}: column {label!r} has a name but no values.")
        if filled == [0] and len(values) > 1:               # given once
            value = parse_number(values[0])
            if value is None:
                raise _field_error(path, linenos[0], cells[0][j], label, decimal)
            scalars[name if name else j] = value
            continue
        col = []
        for i, v in enumerate(values):
            x = parse_number(v)
            if x is None:                       # an empty field included
                raise _field_error(path, linenos[i], cells[i][j], label, decimal)
            if not np.isfinite(x):
                raise DataFileError(f"{path}: line {linenos[i]} holds a non-finite value: "
                                    f"{v!r} (column {label!r}); fohw does not fill gaps.")
            col.append(x)
        columns.append(col)
        col_names.append(name)
    data = np.array(columns, dtype=np.float64).T if columns else np.empty((len(rows), 0))
    return Table(data=data, names=col_names if names is not None else None, scalars=scalars,
                 path=path, skipped=skipped)


def sampling_time(table):
    """The sampling time a file gives once (a column named ``Ts``, ``dt``, ... ; any case)."""
    found = [k for k in table.scalars if isinstance(k, str) and k.lower() in SAMPLING_TIME_NAMES]
    return table.scalars[found[0]] if found else None


def _column(table, spec, what):
    if isinstance(spec, bool):
        raise ParameterError(f"`{what}` must be a column number or a header name; got {spec!r}.")
    if isinstance(spec, (int, np.integer)):
        if not 0 <= spec < table.data.shape[1]:
            raise ParameterError(f"`{what}` = {spec}: {table.path} has {table.data.shape[1]} "
                                 "signal column(s), numbered from 0.")
        return int(spec)
    if isinstance(spec, str):
        if table.names is None or spec not in table.names:
            have = f" ({', '.join(table.names)})" if table.names else " (the file has no header)"
            raise ParameterError(f"`{what}` = {spec!r} is not a column of {table.path}{have}.")
        return table.names.index(spec)
    raise ParameterError(f"`{what}` must be a column number or a header name; got "
                         f"{type(spec).__name__}.")


def read_record(path, u=None, y=None, *, dt=None, name=None, input_unit="", output_unit="",
                time_unit="", source="", decimal=".") -> Record:
    """Read a measured record from a CSV or whitespace-separated text file.

    Parameters
    ----------
    path : str or os.PathLike
        The file (see :mod:`fohw.io.text` for the accepted layout).
    u, y : int or str, optional
        The input and output columns, by number (from 0, counting signal columns) or header
        name. Default: the columns named ``u`` and ``y`` if the header has them, else columns 0
        and 1 when the file has exactly two signal columns; with more columns they must be given
        (fohw does not guess which is the input).
    dt : float or str, optional
        The sampling time, or the name of a column that holds it (e.g. ``"Ts"``, given once).
        Default: a column given once named ``Ts``, ``dt``, ``sampling_time`` or ``sample_time``
        (any case) if there is one, else ``None`` (one sample is the time unit).
    name, input_unit, output_unit, time_unit, source : str, optional
        Stored on the record; the input and output names come from the header.
    decimal : {".", ","}
        The decimal mark (``","``: columns separated by ``;`` or whitespace).

    Returns
    -------
    Record

    Examples
    --------
    >>> import os, tempfile, fohw
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = os.path.join(d, "r.csv")
    ...     with open(path, "w") as fh:
    ...         _ = fh.write("t,u,y,Ts,\\n0,1.0,2.0,0.5,\\n1,1.5,2.5,,\\n")
    ...     rec = fohw.read_record(path)
    >>> rec.u, rec.y, rec.dt, rec.input_name
    (array([1. , 1.5]), array([2. , 2.5]), 0.5, 'u')
    """
    table = read_table(path, decimal=decimal)
    n_cols = table.data.shape[1]
    lower = [n.lower() for n in table.names] if table.names else []
    if u is None and y is None:
        if "u" in lower and "y" in lower:
            u, y = lower.index("u"), lower.index("y")
        elif n_cols == 2:
            u, y = 0, 1
        else:
            have = ", ".join(table.names) if table.names else f"{n_cols} unnamed columns"
            raise ParameterError(f"{table.path} has {n_cols} signal columns ({have}): say "
                                 "which is the input and which the output with u=... and "
                                 "y=... (a number or a header name).")
    elif u is None or y is None:
        raise ParameterError("give both `u` and `y`, or neither.")
    iu, iy = _column(table, u, "u"), _column(table, y, "y")
    if iu == iy:
        raise ParameterError(f"`u` and `y` name the same column ({u!r}, {y!r}).")
    if isinstance(dt, str):
        key = dt
        if key in table.scalars:
            dt = table.scalars[key]
        elif table.names and key in table.names:
            dt = float(table.data[0, table.names.index(key)])
        else:
            raise ParameterError(f"`dt` = {key!r} is not a column of {table.path}.")
    elif dt is None:
        dt = sampling_time(table)
    names = table.names or []
    return Record(u=table.data[:, iu], y=table.data[:, iy], dt=dt,
                  name=name if name is not None else os.path.basename(table.path),
                  input_name=names[iu] if names else "u",
                  output_name=names[iy] if names else "y", input_unit=input_unit,
                  output_unit=output_unit, time_unit=time_unit, source=source, path=table.path)
