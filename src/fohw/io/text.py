"""Measured records from text files: CSV or whitespace columns, headers, comments, values given once.

:func:`read_record` is the loader users call (``fohw.read_record``); :func:`read_table` is the
parser under it and under the command line. What they accept, and what they refuse rather than
guess:

* separators: commas (a line with a comma) or whitespace; a trailing separator (an empty last
  field on every line) is ignored;
* a UTF-8 byte-order mark; blank lines; comment lines starting with ``#`` or ``%``;
* a header line of names, only if **none** of its fields is a number (a first row such as
  ``0x10 1`` or ``0.5 0.3.1`` is an error at line 1, never a header that drops a sample);
* a column given once: a value on the first data line and nothing below (the cascaded-tanks
  file gives ``Ts`` so); it is returned as a scalar, not as a signal;
* anything else that is not a number, or a missing value inside a column, is an error naming
  the line.
"""

from __future__ import annotations

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
    """

    data: np.ndarray
    names: list | None
    scalars: dict = field(default_factory=dict)
    path: str = ""


def _number(text):
    try:
        return float(text)
    except ValueError:
        return None


def read_table(path) -> Table:
    """Parse a numeric text table (see the module notes for what is accepted).

    Raises
    ------
    FileNotFoundError
        No such file.
    DataFileError
        A directory, an unreadable file, text that is not UTF-8, a field that is not a number,
        a row with another number of fields, a missing value inside a column, a non-finite
        value, or no data.
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        raise DataFileError(f"{path!r} is a directory, not a data file.")
    if not os.path.exists(path):
        raise FileNotFoundError(f"data file not found: {path!r}")
    try:
        with open(path, "rb") as fh:
            raw_lines = fh.read().splitlines()
    except OSError as exc:
        raise DataFileError(f"{path}: cannot be read ({exc.strerror or exc}).") from None
    names, rows, linenos = None, [], []
    for lineno, raw in enumerate(raw_lines, start=1):
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise DataFileError(f"{path}: line {lineno} is not UTF-8 text.") from None
        if lineno == 1:
            text = text.lstrip("\ufeff")                 # a byte-order mark
        text = text.strip()
        if not text or text[0] in "#%":
            continue
        fields = [f.strip() for f in (text.split(",") if "," in text else text.split())]
        if names is None and not rows and all(_number(f) is None for f in fields if f):
            names = [f.strip('"').strip("'") for f in fields]
            continue
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
    if names is not None:
        names = names + [""] * (width - len(names))
    columns, col_names, scalars = [], [], {}
    for j in keep:
        name = names[j] if names is not None else None
        values = [c[j] for c in cells]
        filled = [i for i, v in enumerate(values) if v]
        if not filled:
            raise DataFileError(f"{path}: column {name or j!r} has a name but no values.")
        if filled == [0] and len(values) > 1:               # given once
            value = _number(values[0])
            if value is None:
                raise DataFileError(f"{path}: line {linenos[0]}: {values[0]!r} is not a number.")
            scalars[name if name else j] = value
            continue
        if len(filled) != len(values):
            i = next(i for i, v in enumerate(values) if not v)
            raise DataFileError(f"{path}: line {linenos[i]}: column "
                                f"{(name or str(j))!r} has no value (a row with fewer fields).")
        col = []
        for i, v in enumerate(values):
            x = _number(v)
            if x is None:
                raise DataFileError(f"{path}: line {linenos[i]}: {v!r} is not a number.")
            if not np.isfinite(x):
                raise DataFileError(f"{path}: line {linenos[i]} holds a non-finite value: "
                                    f"{v!r}.")
            col.append(x)
        columns.append(col)
        col_names.append(name)
    data = np.array(columns, dtype=np.float64).T if columns else np.empty((len(rows), 0))
    return Table(data=data, names=col_names if names is not None else None, scalars=scalars,
                 path=path)


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
                time_unit="", source="") -> Record:
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
    table = read_table(path)
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
        found = [k for k in table.scalars if isinstance(k, str)
                 and k.lower() in SAMPLING_TIME_NAMES]
        dt = table.scalars[found[0]] if found else None
    names = table.names or []
    return Record(u=table.data[:, iu], y=table.data[:, iy], dt=dt,
                  name=name if name is not None else os.path.basename(table.path),
                  input_name=names[iu] if names else "u",
                  output_name=names[iy] if names else "y", input_unit=input_unit,
                  output_unit=output_unit, time_unit=time_unit, source=source, path=table.path)
