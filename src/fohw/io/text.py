"""Measured records from text files: CSV or whitespace columns, headers, comments, values given once.

:func:`read_record` is the loader users call (``fohw.read_record``); :func:`read_table` is the
parser under it and under the command line. What they accept, and what they refuse rather than
guess:

* separators: semicolons, commas or whitespace, whichever the first line (header or data) uses;
  a trailing separator (an empty last field on every line) is ignored; decimal commas
  (``0,5``) on request (``decimal=","``);
* a UTF-8 byte-order mark; blank lines; comment lines starting with ``#`` or ``%``; fields in
  double or single quotes (``"u","y"`` / ``"0.47","-0.02"``);
* a header line of names, only if **none** of its fields is a number (a first row such as
  ``0x10 1`` or ``0.5 0.3.1`` is an error at line 1, never a header that drops a sample);
* a column given once: a value on the first data line and nothing below (the cascaded-tanks
  file gives ``Ts`` so); it is returned as a scalar, not as a signal;
* header comments above the data that say what the columns are (what ``fohw data`` writes,
  :func:`format_table`): ``# dt: 4 s`` (the sampling time and its unit) and
  ``# units: u=V, y=A`` (a unit per column); other comment lines are ignored, and a ``dt`` or
  ``units`` comment that cannot be read is an error naming its line;
* anything else that is not a number, a missing value (``NA``, ``nan``, an empty field, ...),
  a row with more fields than the header or the first data line (an extra field, ``1,234.5``
  in a comma file), a row with fewer, a second header line, a header that names a column twice,
  or data separated otherwise than the header (``u,y`` above ``1;2``) is an error naming the
  line (and the column): fohw fills no gaps.

A file is read from a path (``str``, ``bytes`` or :class:`os.PathLike`) or from a file object
(text or binary, e.g. :class:`io.StringIO`, an open file). A file on disk that changes while it
is read (its size or modification time differ before and after), or whose last line has no line
end (a file cut while it was written, or still being written), is refused: fohw does not use a
record that may be incomplete.

Clean files are parsed by :func:`numpy.loadtxt` (5 million rows in seconds); the rest, and every
error, by a line-by-line reader that streams the file (it holds the numbers, never the lines).
"""

from __future__ import annotations

import io
import os
from array import array
from dataclasses import dataclass, field
from datetime import datetime
from typing import BinaryIO, TextIO

import numpy as np

from ..exceptions import DataFileError, ParameterError
from ..record import TIME_UNITS, UNIFORM_RTOL, Record, first_disorder, time_column, time_columns
from .files import check_input_file

__all__ = ["Table", "read_table", "read_record", "format_table", "record_from_table",
           "table_time", "signal_columns"]

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
    meta : dict
        What the header comments above the data say: ``dt`` and ``time_unit`` (from
        ``# dt: 4 s``, on line ``dt_line``), ``units`` (``{column name: unit}``, from
        ``# units: u=V, y=A`` on line ``units_line``); ``time_origin``, the first date/time of
        a time column that holds them (its values are seconds from it).
    header_line : int
        The line of the header (0: none).
    time_column : int or None
        The column (of ``data``) that holds the time: the one given, else the one the header
        names as time (:func:`fohw.record.time_column`); None without one.
    time_unit : str
        Its unit (from its name, ``# units:``, or ``"s"`` for date/times).
    """

    data: np.ndarray
    names: list | None
    scalars: dict = field(default_factory=dict)
    path: str = ""
    skipped: list = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    header_line: int = 0
    time_column: int | None = None
    time_unit: str = ""
    source: object = field(default=None, repr=False, compare=False)

    def line_of(self, row):
        """The line number (from 1) of data row ``row`` (from 0) in the file, for messages."""
        if self.source is None:
            return None
        k = -1
        with self.source.open() as fh:
            for lineno, raw in _lines(fh):
                if lineno <= self.header_line:
                    continue
                text = raw.decode("utf-8", "replace").strip()
                if not text or text[0] in "#%":
                    continue
                k += 1
                if k == row:
                    return lineno
        return None


#: Header comments ``# key: value`` that :func:`read_table` reads into ``Table.meta``.
HEADER_KEYS = ("dt", "units")


def _header_comments(src):
    """``Table.meta`` from the comment lines above the first line that is not a comment."""
    meta = {}
    with src.open() as fh:
        for lineno, raw in _lines(fh):
            line = _decode(src, lineno, raw).strip()
            if not line:
                continue
            if line[0] not in "#%":
                break
            key, colon, value = line[1:].partition(":")
            key, value = key.strip().lower(), value.strip()
            if not colon or key not in HEADER_KEYS:
                continue
            meta[f"{key}_line"] = lineno
            if key == "dt":
                number, _, unit = value.partition(" ")
                try:
                    dt = float(number)
                except ValueError:
                    dt = float("nan")
                if not (np.isfinite(dt) and dt > 0.0):
                    raise DataFileError(f"{src.name}: line {lineno}: `# dt:` must give a positive "
                                        f"sampling time and its unit (e.g. '# dt: 4 s'); got "
                                        f"{value!r}.")
                meta["dt"], meta["time_unit"] = dt, unit.strip()
            else:
                units = {}
                for item in filter(None, (f.strip() for f in value.split(","))):
                    name, eq, unit = item.partition("=")
                    if not eq or not name.strip():
                        raise DataFileError(f"{src.name}: line {lineno}: `# units:` must list "
                                            "column=unit pairs separated by commas (e.g. "
                                            f"'# units: u=V, y=A'); got {item!r}.")
                    units[name.strip()] = unit.strip()
                meta["units"] = units
    return meta


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
    return [_unquote(f.strip()) for f in (text.split(delimiter) if delimiter else text.split())]


def _unquote(field):
    """A field without the double or single quotes around it (``"0.47"`` -> ``0.47``)."""
    if len(field) >= 2 and field[0] == field[-1] and field[0] in "\"'":
        return field[1:-1].strip()
    return field


def _header(fields, decimal):
    """The column names if no field of the line is a number (a header line), else None."""
    if any(parse_number(_decimal(f, decimal)) is not None for f in fields if f):
        return None
    return list(fields)


def _comma_separated_header(text, delimiter, decimal):
    """True for a header split at whitespace that holds commas while commas are decimal marks.

    ``u,y`` read with ``decimal=","`` is one column named "u,y" whose rows ``1,2`` read as 1.2:
    a comma-separated file given the wrong decimal mark, refused rather than misread.
    """
    return decimal == "," and delimiter is None and "," in text


def _comma_header_error(path, lineno, text):
    if all(parse_number(part.strip()) is not None for part in text.split(",")):
        return DataFileError(f"{path}: line {lineno}: {text!r} holds numbers separated by commas, "
                             "but decimal=',' makes commas decimal marks (1,5 = 1.5), so it "
                             "cannot be read: read a comma-separated file with decimal='.', or "
                             "separate the columns by ';' or whitespace.")
    return DataFileError(f"{path}: line {lineno}: the header {text!r} is separated by commas, "
                         "but decimal=',' makes commas decimal marks (1,5 = 1.5), so its rows "
                         "would be misread; with decimal commas separate the columns by ';' or "
                         "whitespace, or read a comma-separated file with decimal='.'.")


def _header_note(line, names):
    return f"header on line {line} ({', '.join(n for n in names if n)})"


def _decimal(field, decimal):
    return field.replace(",", ".") if decimal == "," else field


class _Source:
    """Where a table comes from: a file on disk, or the content of a file object.

    ``name`` is what messages call it; :meth:`open` gives a fresh binary stream each time.
    """

    def __init__(self, obj):
        self.path, self.content = None, None
        if isinstance(obj, _Source):
            self.path, self.content, self.name = obj.path, obj.content, obj.name
            return
        if isinstance(obj, (str, bytes, os.PathLike)):
            path = os.fspath(obj)
            self.path = self.name = os.fsdecode(path) if isinstance(path, bytes) else path
            return
        if callable(getattr(obj, "read", None)):
            content = obj.read()
            if isinstance(content, str):
                content = content.encode("utf-8")
            if not isinstance(content, bytes):
                raise ParameterError(f"`path`: the file object's read() returned "
                                     f"{type(content).__name__}, not text or bytes.")
            self.content = content
            name = getattr(obj, "name", None)
            self.name = os.fsdecode(name) if isinstance(name, (str, bytes)) else \
                f"<{type(obj).__name__}>"
            return
        raise ParameterError("`path` must be a file path (str, bytes or os.PathLike) or a file "
                             "object with read() (an open file, io.StringIO, io.BytesIO); got "
                             f"{type(obj).__name__}.")

    def open(self):
        return open(self.path, "rb") if self.path is not None else io.BytesIO(self.content)

    def snapshot(self):
        """``(size, modification time)`` of a file on disk (None for a file object's content)."""
        if self.path is None:
            return None
        st = os.stat(self.path)
        return st.st_size, st.st_mtime_ns

    def last_byte(self):
        with self.open() as fh:
            fh.seek(0, io.SEEK_END)
            if fh.tell() == 0:
                return b""
            fh.seek(-1, io.SEEK_END)
            return fh.read(1)


def read_table(path, *, decimal=".", time=None) -> Table:
    """Parse a numeric text table (see the module notes for what is accepted).

    Parameters
    ----------
    path : str, bytes, os.PathLike or file object
        The file, or an object with ``read()`` giving its text or bytes (an open file,
        :class:`io.StringIO`).
    decimal : {".", ","}
        The decimal mark. With ``","`` (``0,5`` for one half) the columns must be separated by
        ``;`` or whitespace.
    time : str, int or False, optional
        The column that holds the time (header name or number); it may hold numbers or ISO
        8601 date/times (``2024-01-01T00:00:00.5``, read as seconds from the first). Default:
        the column the header names as time (``t``, ``time``, ``time_s``, ``Time [s]``, ...:
        :func:`fohw.record.time_column`), if exactly one does; ``False``: none.

    Returns
    -------
    Table
        ``Table.skipped`` says what was not read as data (the header, comment and blank lines,
        trailing separators).

    Raises
    ------
    FileNotFoundError
        No such file.
    ParameterError
        ``path`` is neither a path nor a file object.
    DataFileError
        A directory, an unreadable file, text that is not UTF-8, a field that is not a number
        (with a hint when it looks like a decimal comma), a missing value (``NA``, empty, ...)
        named by line and column, a row with more or fewer fields than the others, a second
        header line, a header naming a column twice, a header separated by commas while
        ``decimal=","``, a non-finite value, no data, or a file that changed while it was read
        or whose last line has no line end (it may have been cut); a ``# units:`` comment
        naming a column the file does not have; two columns named as time with ``time`` not
        given; date/times mixed with numbers, or with and without a time zone.

    Notes
    -----
    A clean file (one header at most, no comment marks after it, the same number of fields on
    every line) is parsed by :func:`numpy.loadtxt`'s compiled reader; anything else, and every
    error, goes through a line-by-line reader that names the line. Both give the same numbers
    and names (``tests/test_reliability.py``); only the line reader counts blank lines inside
    the data in ``Table.skipped``.
    """
    if decimal not in (".", ","):
        raise ParameterError(f"`decimal` must be '.' or ','; got {decimal!r}.")
    if not (time is None or time is False or isinstance(time, str) or
            (isinstance(time, (int, np.integer)) and not isinstance(time, bool))):
        raise ParameterError(f"`t` must be a column name or number, or False (no time column); "
                             f"got {time!r}.")
    src = _Source(path)
    if src.path is not None:
        check_input_file(src.path, "a data file")
    try:
        before = src.snapshot()
        last = src.last_byte() if src.path is not None else b"\n"
        if last not in (b"\n", b"\r", b""):
            raise DataFileError(f"{src.name}: the last line has no line end, so it may have been "
                                "cut (a file truncated, or still being written); fohw does not "
                                "use a row that may be incomplete. If the file is complete, end "
                                "its last line with a newline.")
        table = _read_fast(src, decimal)
        if table is None:
            table = _read_lines(src, decimal, time)
        table.meta.update(_header_comments(src))
        after = src.snapshot()
    except OSError as exc:
        raise DataFileError(f"{src.name}: cannot be read ({exc.strerror or exc}).") from None
    if before != after:
        raise DataFileError(f"{src.name} changed while it was read (size {before[0]} -> "
                            f"{after[0]} bytes, modification time "
                            f"{'changed' if before[1] != after[1] else 'unchanged'}); fohw does "
                            "not use a record that may be incomplete: read it again once it is "
                            "complete.")
    table.source = src
    _check_units(table)
    _resolve_time(table, time)
    return table


def _check_units(table):
    """A ``# units:`` comment names columns of the file only (never dropped silently)."""
    units = table.meta.get("units", {})
    known = set(table.names or []) | {k for k in table.scalars if isinstance(k, str)}
    unknown = [k for k in units if k not in known]
    if unknown:
        have = ", ".join(n for n in (table.names or []) if n) or \
            "the file has no header naming its columns"
        raise DataFileError(f"{table.path}: line {table.meta.get('units_line')}: `# units:` "
                            f"names {', '.join(map(repr, unknown))}, which "
                            f"{'is' if len(unknown) == 1 else 'are'} not a column ({have}); a "
                            "unit must belong to a column: correct the name or remove it.")


def _resolve_time(table, spec):
    """``table.time_column`` and ``table.time_unit`` from ``spec`` or the header's names."""
    names = table.names or []
    if spec is False:
        return
    if spec is None:
        found = time_columns(names)
        if not found:
            return
        if len(found) > 1:
            raise DataFileError(f"{table.path}: {len(found)} columns could be the time "
                                f"({', '.join(names[j] for j in found)}): say which with t=... "
                                "(fohw: --time NAME), or t=False (--time none) for none.")
        j = found[0]
    else:
        j = _column(table, spec, "t")
    name = names[j] if names else None
    unit = time_column(name)[1] if name is not None else ""
    listed = table.meta.get("units", {}).get(name, "") if name is not None else ""
    if unit and listed and unit != listed:
        raise DataFileError(f"{table.path}: the time column {name!r} says its unit is {unit!r} "
                            f"but `# units:` (line {table.meta.get('units_line')}) says "
                            f"{listed!r}; which one holds? Correct the file.")
    if "time_origin" in table.meta:
        if (unit or listed) not in ("", "s"):
            raise DataFileError(f"{table.path}: the time column {name!r} holds date/times, read "
                                f"as seconds, but its unit is given as {unit or listed!r}.")
        unit = "s"
    table.time_column, table.time_unit = j, unit or listed


def _lines(fh):
    """``(line number, raw bytes)`` of a binary stream, one line at a time.

    Lines end with ``\\n``, ``\\r\\n`` or ``\\r``.
    """
    lineno = 0
    for chunk in fh:
        for raw in chunk.splitlines() or [b""]:
            lineno += 1
            yield lineno, raw


def _decode(src, lineno, raw):
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise DataFileError(f"{src.name}: line {lineno} is not UTF-8 text.") from None
    return text.lstrip("\ufeff") if lineno == 1 else text           # a byte-order mark


def _check_names(src, lineno, names):
    seen = {}
    for j, n in enumerate(names):
        if n and n in seen:
            raise DataFileError(f"{src.name}: the header on line {lineno} names {n!r} twice "
                                f"(columns {seen[n]} and {j}); a column name must say which "
                                "column it is: rename one.")
        seen.setdefault(n, j)


def _check_separator(src, lineno, text, delimiter, header_line, decimal):
    """The first data line must be separated as the header is (``u,y`` above ``1;2`` is not)."""
    found = _delimiter(text, decimal)
    if delimiter in (";", ",") and found in (";", ",") and found != delimiter:
        raise DataFileError(f"{src.name}: line {lineno} is separated by {found!r} but the header "
                            f"on line {header_line} by {delimiter!r}; use one separator in the "
                            "whole file.")


def _head(src, decimal):
    """The separator, the header and its line number, from the first lines of the file."""
    delimiter, names, header_line = "unset", None, 0
    with src.open() as fh:
        for lineno, raw in _lines(fh):
            line = _decode(src, lineno, raw).strip()
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
            if "'" in line or '"' in line:
                return None                      # quoted fields: the line reader
            return delimiter, names, header_line
    return None


def _read_fast(src, decimal):
    """numpy.loadtxt on a clean file; None when the file needs the line reader.

    The file is read from disk by loadtxt's compiled reader (never held as text, except with
    decimal commas or a file object); a comment mark, a missing value, a ragged row, a value
    given once, quotes, text that is not UTF-8 or anything else unusual makes loadtxt fail, and
    the line reader then reads the file (and names the line of any error).
    """
    try:
        head = _head(src, decimal)
        if head is None:                         # no data line, or a header the line reader refuses
            return None
        delimiter, names, header_line = head
        if names is not None and len(set(n for n in names if n)) < len([n for n in names if n]):
            return None                          # a name twice: the line reader names it
        source = src.path
        if decimal == "," or src.path is None:
            with src.open() as fh:
                text = fh.read().decode("utf-8-sig")
            source = io.StringIO(text.replace(",", ".") if decimal == "," else text)
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
    return Table(data=data, names=names, scalars={}, path=src.name, skipped=skipped,
                 header_line=header_line)


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


def _count_error(path, lineno, n, width, where, delimiter, decimal):
    """A row with another number of fields than the header or the first data line."""
    more = n > width
    hint = ""
    if more and delimiter == "," and decimal == ".":
        hint = (" A comma inside a number (1,234.5 or a decimal comma) splits it in two: write "
                "1234.5, or separate the columns by ';' with decimal=',' (fohw: "
                "--decimal-comma).")
    return DataFileError(f"{path}: line {lineno} has {n} field(s) but {where} has {width}: "
                         f"{'an extra field' if more else 'a missing field'} (a ragged row)."
                         f"{hint}")


def _read_lines(src, decimal, time=None):
    """The line-by-line reader: any layout the module notes allow, and every error by line.

    It streams the file and keeps the numbers (one array of floats per column), never the
    lines, so a 5-million-row file with one bad line costs the numbers' memory, not the text's.
    """
    src = _Source(src)
    rows = _Rows(src, decimal, time)
    with src.open() as fh:
        for lineno, raw in _lines(fh):
            text = _decode(src, lineno, raw).strip()
            if not text or text[0] in "#%":
                rows.n_comments += 1
                continue
            if rows.delimiter == "unset":
                rows.delimiter = _delimiter(text, decimal)
            fields = _split(text, rows.delimiter)
            if rows.n_rows == 0 and _header(fields, decimal) is not None:
                if rows.names is None:
                    rows.read_header(lineno, text, fields)
                    continue
                rows.refuse_second_header(lineno, text, fields)
            rows.add(lineno, text, fields)
    return rows.table()


class _Rows:
    """What :func:`_read_lines` has read so far.

    The header, the columns' numbers, and the empty cells and late values that decide which
    error (if any) is the earliest certain one.
    """

    def __init__(self, src, decimal, time=None):
        self.src, self.decimal, self.time = src, decimal, time
        self.time_col, self.origin, self.origin_line = None, None, 0
        self.names, self.header_line, self.delimiter, self.n_comments = None, 0, "unset", 0
        self.width, self.first_line, self.first, self.cols = None, 0, [], []
        self.where = ""
        self.n_rows = 0
        self.empty = {}    # column -> (line, fields on that line) of its first empty cell below row 0
        self.later = set()     # columns with a value below the first data line

    def read_header(self, lineno, text, fields):
        """The header line (the first line without numbers, before any data line)."""
        if _comma_separated_header(text, self.delimiter, self.decimal):
            raise _comma_header_error(self.src.name, lineno, text)
        self.names, self.header_line = _header(fields, self.decimal), lineno
        _check_names(self.src, lineno, self.names)

    def refuse_second_header(self, lineno, text, fields):
        """A second line without numbers: decimal commas, or a second header (errors).

        A line of missing values only (``NA,NA``) passes, to be refused as a data row.
        """
        src, decimal = self.src, self.decimal
        _check_separator(src, lineno, text, self.delimiter, self.header_line, decimal)
        commas = [f for f in fields if parse_number(f.replace(",", ".")) is not None]
        if commas and decimal == ".":
            raise _field_error(src.name, lineno, commas[0], fields.index(commas[0]), decimal)
        if not all(f.lower() in MISSING for f in fields):
            raise DataFileError(f"{src.name}: line {lineno} looks like a second header "
                                f"line (no field is a number) after the header on line "
                                f"{self.header_line}; fohw reads one header line: start the "
                                "others with '#'.")

    def add(self, lineno, text, fields):
        """A data line: its cells added to the columns, or the earliest certain error raised."""
        if self.n_rows == 0:
            self.start(lineno, text, fields)
        elif len(fields) > self.width:
            self.raise_earliest(lineno, _count_error(self.src.name, lineno, len(fields),
                                                     self.width, self.where, self.delimiter,
                                                     self.decimal))
        for j in range(self.width):
            self.add_cell(lineno, fields, j)
        self.n_rows += 1

    def start(self, lineno, text, fields):
        """The first data line sets the width (or the header does, if it is wider)."""
        names = self.names
        if names is not None:
            _check_separator(self.src, lineno, text, self.delimiter, self.header_line,
                             self.decimal)
        self.width = max(len(fields), len(names) if names is not None else 0)
        self.where = (f"the header on line {self.header_line}" if names is not None
                      and len(names) >= len(fields) else f"line {lineno} (the first data line)")
        self.time_col = _raw_time_column(names, self.time)
        self.first_line = lineno
        self.cols = [array("d") for _ in range(self.width)]

    def add_cell(self, lineno, fields, j):
        """Cell ``j`` of a data line: a number, or an empty cell (NaN until the end decides)."""
        cell = fields[j] if j < len(fields) else ""
        if self.n_rows == 0:
            self.first.append(cell)
        if not cell:
            if self.n_rows > 0 and j not in self.empty:
                self.empty[j] = (lineno, len(fields))
                if j in self.later:                  # a signal column: certain now
                    self.raise_earliest(lineno + 1, None)
            self.cols[j].append(np.nan)
            return
        x = parse_number(_decimal(cell, self.decimal))
        if j == self.time_col and (x is None or self.origin is not None):
            x = self.instant(lineno, cell, j, x)
        if x is None or not np.isfinite(x):
            error = self.value_error(lineno, cell, j, x)
            if self.n_rows == 0:
                raise error
            self.later.add(j)
            self.raise_earliest(lineno, error)
        if self.n_rows > 0:
            self.later.add(j)
        self.cols[j].append(x)

    def instant(self, lineno, cell, j, x):
        """A cell of the time column: seconds from its first date/time (ISO 8601), or None.

        A column holds numbers or date/times, not both; and date/times all with a time zone or
        all without.
        """
        label = self.names[j] if self.names is not None and j < len(self.names) else j
        if x is not None:                       # a number below date/times
            raise DataFileError(f"{self.src.name}: line {lineno}: the time column {label!r} "
                                f"holds the number {cell!r}, but date/times from line "
                                f"{self.origin_line} on; write one or the other.")
        try:
            stamp = datetime.fromisoformat(cell)
        except ValueError:
            return None
        if self.origin is None:
            if self.n_rows > 0:
                raise DataFileError(f"{self.src.name}: line {lineno}: the time column {label!r} "
                                    f"holds the date/time {cell!r}, but numbers above it; write "
                                    "one or the other.")
            self.origin, self.origin_line = stamp, lineno
        try:
            return (stamp - self.origin).total_seconds()
        except TypeError:
            raise DataFileError(f"{self.src.name}: line {lineno}: the date/time {cell!r} "
                                f"{'has a' if stamp.tzinfo else 'has no'} time zone, but the "
                                f"first (line {self.origin_line}) "
                                f"{'has none' if stamp.tzinfo else 'has one'}; write all with "
                                "or all without a time zone.") from None

    def value_error(self, lineno, cell, j, x):
        """The error of a cell that is not a number (``x`` None) or not finite."""
        names = self.names
        label = names[j] if names is not None and j < len(names) and names[j] else j
        if x is None and j == self.time_col and cell.strip().lower() not in MISSING:
            return DataFileError(f"{self.src.name}: line {lineno}: {cell!r} is neither a number "
                                 f"nor an ISO 8601 date/time (column {label!r}, the time); write "
                                 "e.g. 12.5 or 2024-01-01T00:00:12.5.")
        if x is None:
            return _field_error(self.src.name, lineno, cell, label, self.decimal)
        return DataFileError(f"{self.src.name}: line {lineno} holds a non-finite value: "
                             f"{cell!r} (column {label!r}); fohw does not fill gaps.")

    def raise_earliest(self, lineno, error):
        _raise_earliest(self.src, self.names, self.empty, self.later, lineno, self.first_line,
                        self.first, self.decimal, self.where, self.width, self.delimiter, error)

    def table(self):
        """The :class:`Table` of the whole file, or the earliest error the end makes certain."""
        src, names, width, n_rows = self.src, self.names, self.width, self.n_rows
        if n_rows == 0:
            raise DataFileError(f"{src.name}: no data lines found.")
        error = _first_empty_error(src, names, self.empty, self.later, self.first_line,
                                   self.first, self.decimal, self.where, width, self.delimiter,
                                   n_rows)
        if error is not None:
            raise error[1]
        skipped = [_header_note(self.header_line, names)] if names else []
        if self.n_comments:
            skipped.append(f"{self.n_comments} comment or blank line(s)")
        padded = (names + [""] * (width - len(names))) if names is not None else None
        columns, col_names, scalars = self.columns(padded)
        if any(not self.first[j] and j not in self.later and not (padded and padded[j])
               for j in range(width)):
            skipped.append("a trailing separator")
        data = np.column_stack(columns) if columns else np.empty((n_rows, 0))
        meta = {"time_origin": self.origin.isoformat()} if self.origin is not None else {}
        return Table(data=data, names=col_names if names is not None else None,
                     scalars=scalars, path=src.name, skipped=skipped, meta=meta,
                     header_line=self.header_line)

    def columns(self, padded):
        """``(signal columns, their names, values given once)``.

        A named empty column is an error; an unnamed one (a trailing separator) is left out.
        """
        columns, col_names, scalars = [], [], {}
        for j in range(self.width):
            name = padded[j] if padded is not None else None
            if not self.first[j] and j not in self.later:          # empty on every line
                if name:
                    raise DataFileError(f"{self.src.name}: column {name!r} has a name but no "
                                        "values.")
                continue
            if j not in self.later and self.n_rows > 1:              # given once
                scalars[name if name else j] = self.cols[j][0]
                continue
            columns.append(np.frombuffer(self.cols[j], dtype=np.float64))
            col_names.append(name)
        return columns, col_names, scalars


def _raw_time_column(names, spec):
    """The position on a line of the time column (where date/times are read), or None."""
    if spec is False:
        return None
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        return int(spec)
    if isinstance(spec, str):
        return names.index(spec) if names is not None and spec in names else None
    found = time_columns(names)
    return found[0] if len(found) == 1 else None


def _first_empty_error(src, names, empty, later, first_line, first, decimal, where, width,
                       delimiter, n_rows):
    """``(line, error)`` of the earliest empty cell in a column that is a signal, or None.

    A column is a signal when it has a value below the first data line (or the file has one
    data line); a column filled on the first line only is a value given once, a column empty
    everywhere a trailing separator (or an error if it has a name).
    """
    found = []
    for j in range(width):
        if j not in later and n_rows > 1:
            continue
        label = names[j] if names is not None and j < len(names) and names[j] else j
        if not first[j]:
            found.append((first_line, _field_error(src.name, first_line, "", label, decimal)))
        elif j in empty:
            line, n = empty[j]
            error = _count_error(src.name, line, n, width, where, delimiter, decimal) \
                if n <= j else _field_error(src.name, line, "", label, decimal)
            found.append((line, error))
    return min(found, key=lambda e: e[0]) if found else None


def _raise_earliest(src, names, empty, later, lineno, first_line, first, decimal, where, width,
                    delimiter, error):
    """Raise ``error`` (of line ``lineno``), or an earlier one already certain (if any)."""
    earlier = _first_empty_error(src, names, empty, later, first_line, first, decimal, where,
                                 width, delimiter, n_rows=2)
    if earlier is not None and earlier[0] < lineno:
        raise earlier[1]
    if error is not None:
        raise error


def sampling_time(table):
    """The sampling time a file gives: once (a column ``Ts``, ``dt``, ...), or in ``# dt: 4 s``.

    The column name is matched in any case; None where the file gives none.
    """
    found = [k for k in table.scalars if isinstance(k, str) and k.lower() in SAMPLING_TIME_NAMES]
    column = table.scalars[found[0]] if found else None
    header = table.meta.get("dt")
    if column is not None and header is not None and column != header:
        raise DataFileError(f"{table.path}: the column {found[0]!r} gives the sampling time "
                            f"{column!r} but the header comment `# dt:` {header!r}; which one "
                            "holds? Correct the file, or pass `dt`.")
    return column if column is not None else header


def format_table(columns, *, dt=None, time_unit="", units=None, comments=()):
    """A record as CSV text that :func:`read_record` and pandas' ``read_csv`` both read.

    ``#`` header comments, one header line, one full row per sample: pandas reads it with
    ``pandas.read_csv(path, comment="#")``.

    Parameters
    ----------
    columns : mapping of str to array_like
        Column name -> samples (1-D, all of one length). A name holds no comma, quote or ``#``.
    dt : float, optional
        The sampling time, written as ``# dt: 4 s`` (nothing when None).
    time_unit : str, optional
        Its unit.
    units : mapping of str to str, optional
        A unit per column, written as ``# units: u=V, y=A``.
    comments : sequence of str
        Lines written first, each as a ``#`` comment (what the record is, its source).

    Returns
    -------
    str
        Numbers are written with ``repr`` (they read back bit for bit); no trailing separator,
        no column given once.

    Examples
    --------
    >>> import io, fohw
    >>> from fohw.io.text import format_table
    >>> text = format_table({"u": [0.0, 1.5], "y": [0.25, 2.0]}, dt=4.0, time_unit="s",
    ...                     units={"u": "V", "y": "V"}, comments=["two samples"])
    >>> print(text, end="")
    # two samples
    # dt: 4.0 s
    # units: u=V, y=V
    u,y
    0.0,0.25
    1.5,2.0
    >>> rec = fohw.read_record(io.StringIO(text))
    >>> rec.dt, rec.time_unit, rec.output_unit
    (4.0, 's', 'V')
    """
    names = list(columns)
    for name in names:
        if not isinstance(name, str) or not name or any(c in name for c in ',"\'#\n\r'):
            raise ParameterError("a column name must be a non-empty string without a comma, "
                                 f"quote, '#' or line end; got {name!r}.")
    values = [np.asarray(columns[name], dtype=float) for name in names]
    if any(v.ndim != 1 or v.shape != values[0].shape for v in values):
        raise ParameterError("every column must be 1-D and of one length; got shapes "
                             f"{[v.shape for v in values]}.")
    head = [f"# {line}" for text in comments for line in str(text).splitlines()]
    if dt is not None:
        head.append(f"# dt: {float(dt)!r}" + (f" {time_unit}" if time_unit else ""))
    if units:
        unknown = [k for k in units if k not in names]
        if unknown:
            raise ParameterError(f"`units` names columns that are not written: {unknown}.")
        head.append("# units: " + ", ".join(f"{k}={v}" for k, v in units.items() if v))
    head.append(",".join(names))
    rows = (",".join(map(repr, map(float, row))) for row in zip(*values))
    return "\n".join(head) + "\n" + "".join(f"{row}\n" for row in rows)


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


def _file_dt(table):
    """``(dt, what says it, its unit)`` of the sampling time the file gives, or Nones."""
    dt = sampling_time(table)
    if dt is None:
        return None, None, ""
    found = [k for k in table.scalars if isinstance(k, str) and k.lower() in SAMPLING_TIME_NAMES]
    if found:
        return dt, f"the column {found[0]!r}", ""
    unit = table.meta.get("time_unit", "")
    return (dt, f"`# dt: {dt:g}{' ' + unit if unit else ''}` (line {table.meta.get('dt_line')})",
            unit)


def _time_factor(unit, column_unit, what, table):
    """The factor from ``unit`` to the time column's unit (1 where either is not given)."""
    if not unit or not column_unit or unit == column_unit:
        return 1.0
    if unit in TIME_UNITS and column_unit in TIME_UNITS:
        return TIME_UNITS[unit] / TIME_UNITS[column_unit]
    raise DataFileError(f"{table.path}: {what} is in {unit!r} but the time column in "
                        f"{column_unit!r}; fohw cannot compare them: give both in one unit.")


def table_time(table, dt=None):
    """The sampling of a table: ``(t, dt, time_unit)``, checked.

    With a time column (:attr:`Table.time_column`): its instants ``t`` (``dt`` None), strictly
    increasing, and on the grid of any sampling time also given (``dt``, a ``Ts`` column, a
    ``# dt:`` comment). Without one: ``t`` None and the sampling time given or in the file.

    Parameters
    ----------
    table : Table
    dt : float, optional
        A sampling time given by the caller (in the time column's unit).

    Returns
    -------
    t : ndarray or None
    dt : float or None
    time_unit : str

    Raises
    ------
    DataFileError
        Instants that go back or repeat (naming both lines), or that do not step as a sampling
        time also given says (naming it and the first line where they part).
    """
    file_dt, what, file_unit = _file_dt(table)
    j = table.time_column
    if j is None:
        if dt is not None:
            return None, dt, ""
        return None, file_dt, file_unit
    t = table.data[:, j]
    name = table.names[j] if table.names else f"column {j}"
    unit = table.time_unit or file_unit
    if t.size < 2:
        raise DataFileError(f"{table.path}: the time column {name!r} has one row; instants need "
                            "two rows to say a sampling time.")
    k = first_disorder(t)
    if k is not None:
        a, b = table.line_of(k), table.line_of(k + 1)
        t = t.tolist()
        if t[k + 1] == t[k]:
            raise DataFileError(f"{table.path}: line {b} repeats the instant {t[k]!r} of line {a} "
                                f"(time column {name!r}); instants must increase strictly: "
                                "remove the repeated row.")
        raise DataFileError(f"{table.path}: line {b}: the time column {name!r} goes back from "
                            f"{t[k]!r} (line {a}) to {t[k + 1]!r}; instants must increase "
                            "strictly (rows out of order?).")
    claims = ([(float(dt), f"`dt` = {dt!r}", "")] if dt is not None else []) + \
        ([(file_dt, what, file_unit)] if file_dt is not None else [])
    for step, said, step_unit in claims:
        h = step * _time_factor(step_unit, table.time_unit, said, table)
        grid = t[0] + h * np.arange(t.size)
        slack = UNIFORM_RTOL * h + 4 * np.finfo(float).eps * float(np.max(np.abs(t)))
        off = np.flatnonzero(np.abs(t - grid) > slack)
        if off.size:
            k = max(int(off[0]), 1)
            u = f" {unit}" if unit else ""
            raise DataFileError(
                f"{table.path}: line {table.line_of(k)}: the time column {name!r} steps "
                f"{t[k] - t[k - 1]:g}{u} from line {table.line_of(k - 1)}, but {said} says "
                f"{h:g}{u}; which one holds? Correct the file, or read it with t=False "
                "(fohw: --time none) to use the sampling time alone.")
    return t, None, unit


def signal_columns(table, spec, count, what="u and y"):
    """Column indices of ``table`` for ``spec`` (names or numbers), or by default.

    Parameters
    ----------
    table : Table
    spec : sequence of (int or str), or None
        The columns, by header name or number (counting signal columns from 0).
    count : int
        How many columns are needed (inputs, then the output).
    what : str
        How the messages call the argument.

    Returns
    -------
    list of int

    Notes
    -----
    Without ``spec``: the columns named ``u`` and ``y`` (one input and the output), else the
    signal columns other than the time column when there are exactly ``count`` of them; with
    more, fohw does not guess. The time column is never a signal.
    """
    names = table.names or []
    others = [j for j in range(table.data.shape[1]) if j != table.time_column]
    if spec is None:
        lower = [n.lower() for n in names]
        if count == 2 and "u" in lower and "y" in lower:
            return [lower.index("u"), lower.index("y")]
        if len(others) == count:
            return others
        have = ", ".join(names[j] if names else str(j) for j in others) or "none"
        time = (f", besides the time column {names[table.time_column]!r}" if names and
                table.time_column is not None else "")
        raise ParameterError(f"{table.path} has {len(others)} signal column"
                             f"{'' if len(others) == 1 else 's'} ({have}{time}) "
                             f"and {count} are needed: say which is the input and which the "
                             f"output with {what} (numbers from 0 or header names); fohw does "
                             "not guess.")
    idx = [_column(table, s, what) for s in spec]
    if len(idx) != count:
        raise ParameterError(f"{what}: {count} column(s) are needed; got {len(idx)}.")
    for s, j in zip(spec, idx):
        if j == table.time_column:
            raise ParameterError(f"{what}: {s!r} is the time column of {table.path}; read it as "
                                 "a signal with t=False (fohw: --time none).")
    if len(set(idx)) != len(idx):
        raise ParameterError(f"{what} names the same column twice ({', '.join(map(repr, spec))})"
                             ": the inputs and the output are different columns.")
    return idx


def record_from_table(table, inputs, output, *, dt=None, name=None, input_unit="",
                      output_unit="", time_unit="", source="") -> Record:
    """A :class:`~fohw.Record` of columns of a :class:`Table`: the reader behind every loader.

    The sampling comes from :func:`table_time` (a time column, checked; a sampling time given
    or in the file), names from the header, units from ``# units:`` where not given.

    Parameters
    ----------
    table : Table
    inputs : list of int
        The input columns (one or several).
    output : int
        The output column.
    dt : float, optional
        A sampling time (checked against a time column).
    name, input_unit, output_unit, time_unit, source : str, optional
        As :func:`read_record`.

    Returns
    -------
    Record
    """
    t, step, unit = table_time(table, dt)
    names = table.names or []
    units = table.meta.get("units", {})
    in_names = [names[j] if names else ("u" if len(inputs) == 1 else f"u{k + 1}")
                for k, j in enumerate(inputs)]
    if isinstance(input_unit, str) and input_unit:
        in_units = [input_unit] * len(inputs)
    elif isinstance(input_unit, str):
        in_units = [units.get(n, "") for n in in_names] if names else [""] * len(inputs)
    else:
        in_units = list(input_unit)
    if names and not output_unit:
        output_unit = units.get(names[output], "")
    u = table.data[:, inputs[0]] if len(inputs) == 1 else table.data[:, inputs]
    return Record(u=u, y=table.data[:, output], dt=step, t=t,
                  name=name if name is not None else os.path.basename(table.path),
                  input_name=in_names[0] if len(inputs) == 1 else tuple(in_names),
                  output_name=names[output] if names else "y",
                  input_unit=in_units[0] if len(inputs) == 1 else tuple(in_units),
                  output_unit=output_unit, time_unit=time_unit or unit, source=source,
                  path=table.path)


def _as_list(spec, what):
    """``spec`` (one column, or a list of them) as a list, or None."""
    if spec is None:
        return None
    if isinstance(spec, (str, int, np.integer)) and not isinstance(spec, bool):
        return [spec]
    if isinstance(spec, (list, tuple)) and spec:
        return list(spec)
    raise ParameterError(f"`{what}` must be a column number, a header name or a list of them; "
                         f"got {spec!r}.")


def read_record(path: str | bytes | os.PathLike | TextIO | BinaryIO,
                u: str | int | list | None = None, y: str | int | list | None = None, *,
                t: str | int | bool | None = None, dt: float | str | None = None,
                name: str | None = None, input_unit: str = "", output_unit: str = "",
                time_unit: str = "", source: str = "", decimal: str = ".") -> Record:
    """Read a measured record from a CSV or whitespace-separated text file.

    Parameters
    ----------
    path : str, bytes, os.PathLike or file object
        The file (see :mod:`fohw.io.text` for the accepted layout), or an object with
        ``read()`` giving its text or bytes (an open file, :class:`io.StringIO`).
    u : int, str or list of them, optional
        The input column(s), by number (from 0, counting signal columns) or header name; a list
        for several inputs (a circuit's ``["i", "soc"]``).
    y : int, str or a list of one, optional
        The output column (a :class:`~fohw.Record` holds one output). Default for both: the
        columns named ``u`` and ``y`` if the header has them, else the two signal columns
        other than the time column when there are exactly two; with more they must be given
        (fohw does not guess which is the input).
    t : int, str or False, optional
        The time column, by number or name. Default: the column the header names as time
        (``t``, ``time``, ``time_s``, ``Time [s]``, ``timestamp``, ...), if one does;
        ``False``: none (every column a signal). Its values are numbers in the unit its name
        or ``# units:`` gives, or ISO 8601 date/times (read as seconds from the first). The
        instants must increase strictly, and agree with any sampling time also given (``dt``,
        a ``Ts`` column, ``# dt:``); uniform instants give the record's ``dt``, others are
        kept as its instants ``t``.
    dt : float or str, optional
        The sampling time, or the name of a column that gives it once (e.g. ``"Ts"``: a value on
        the first data line and nothing below); a signal column is refused.
        Default: a column given once named ``Ts``, ``dt``, ``sampling_time`` or ``sample_time``
        (any case) if there is one, else a header comment ``# dt: 4 s`` (what ``fohw data``
        writes), else the time column, else ``None`` (one sample is the time unit).
    name, input_unit, output_unit, time_unit, source : str, optional
        Stored on the record; the input and output names come from the header, the units
        (when not given) from header comments ``# units: u=V, y=A`` and ``# dt: 4 s`` or the
        time column's name.
    decimal : {".", ","}
        The decimal mark (``","``: columns separated by ``;`` or whitespace).

    Returns
    -------
    Record

    Raises
    ------
    DataFileError
        What :func:`read_table` refuses; instants that go back, repeat or contradict a sampling
        time (naming the lines, and what says otherwise).
    ParameterError
        A column that does not exist, the time column as a signal, one column twice, several
        outputs, or more columns than needed and ``u``, ``y`` not given.

    Examples
    --------
    >>> import io, fohw
    >>> text = "# units: time_s=s, pump=V, level=V\\ntime_s,pump,level\\n0,1.0,2.0\\n0.5,1.5,2.5\\n"
    >>> rec = fohw.read_record(io.StringIO(text))
    >>> rec.u, rec.y, rec.dt, rec.time_unit, rec.input_name, rec.output_unit
    (array([1. , 1.5]), array([2. , 2.5]), 0.5, 's', 'pump', 'V')
    >>> stamps = "time,u,y\\n2024-01-01T00:00:00,1,2\\n2024-01-01T00:00:01.5,2,3\\n" \\
    ...          "2024-01-01T00:00:02,3,4\\n"
    >>> fohw.read_record(io.StringIO(stamps)).time
    array([0. , 1.5, 2. ])
    """
    table = read_table(path, decimal=decimal, time=t)
    ins, outs = _as_list(u, "u"), _as_list(y, "y")
    if (ins is None) != (outs is None):
        raise ParameterError("give both `u` and `y`, or neither.")
    if outs is not None and len(outs) != 1:
        raise ParameterError(f"`y` names {len(outs)} columns; a fohw.Record holds one output: "
                             "read each output as its own record (y='name').")
    spec = None if ins is None else ins + outs
    count = 2 if spec is None else len(spec)
    idx = signal_columns(table, spec, count, what="u=... and y=..." if spec is None else "u, y")
    if isinstance(dt, str):
        key = dt
        if key in table.scalars:
            dt = table.scalars[key]
        elif table.names and key in table.names:
            once = [k for k in table.scalars if isinstance(k, str)]
            raise ParameterError(f"`dt` = {key!r} names a signal column of {table.path} (a value "
                                 "on every line), not a sampling time given once; give `dt` as a "
                                 "number or the name of a column given once" +
                                 (f" ({', '.join(once)})." if once else
                                  " (the file has none)."))
        else:
            raise ParameterError(f"`dt` = {key!r} is not a column of {table.path}.")
    return record_from_table(table, idx[:-1], idx[-1], dt=dt, name=name,
                             input_unit=input_unit, output_unit=output_unit,
                             time_unit=time_unit, source=source)
