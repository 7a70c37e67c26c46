"""A measured input–output record: samples, sampling time, names, units and where it came from.

MATLAB's ``iddata`` is the model users know: one object carries the signals and what they
mean, and splitting it into estimation and validation parts keeps that meaning.
"""

from __future__ import annotations

import numbers
import re
from dataclasses import dataclass, replace

import numpy as np

from ._validation import check_array, check_same_length, check_scalar
from .exceptions import DimensionError, ParameterError

__all__ = ["Record", "Benchmark", "as_records", "record_data", "record_info", "describe_data",
           "check_sampling", "time_column", "time_columns", "first_disorder", "TIME_UNITS",
           "UNIFORM_RTOL"]


#: Time stamps that all lie within this fraction of their mean step of the uniform grid
#: ``t[0] + k * step`` (plus the rounding of their magnitude, ``4 eps max|t|``: stamps in Unix
#: seconds) are uniform: the record keeps ``dt`` (the mean step) and its start time, not the
#: stamps.
UNIFORM_RTOL = 1e-6

INTERSAMPLE = ("zoh", "foh")

#: Time units a time column's name or a ``# dt:`` comment may give, in seconds.
TIME_UNITS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "ns": 1e-9,
              "min": 60.0, "h": 3600.0}

_TIME_NAME = re.compile(r"^\s*(?:t|time|timestamp|time_stamp|datetime|date_time|date)"
                        r"(?:\s*\[(?P<a>[^\]]*)\]|\s*\((?P<b>[^)]*)\)|_(?P<c>s|sec|ms|us|ns|min|h))?"
                        r"\s*$", re.IGNORECASE)


def time_column(name):
    """``(True, unit)`` if a column called ``name`` holds the time, else ``(False, "")``.

    The names a reader takes as the time without being told: ``t``, ``time``, ``timestamp``,
    ``time_stamp``, ``datetime``, ``date_time`` and ``date``, in any case, alone or with a unit:
    ``time_s``, ``Time [s]``, ``t (ms)``.

    Examples
    --------
    >>> from fohw.record import time_column
    >>> time_column("time_s"), time_column("Time [ms]"), time_column("t"), time_column("ts")
    ((True, 's'), (True, 'ms'), (True, ''), (False, ''))
    """
    match = _TIME_NAME.match(name) if isinstance(name, str) else None
    if match is None:
        return False, ""
    return True, (match.group("a") or match.group("b") or match.group("c") or "").strip()


def time_columns(names):
    """The positions of the names in ``names`` that :func:`time_column` takes as the time."""
    return [j for j, n in enumerate(names or []) if time_column(n)[0]]


def first_disorder(t):
    """The first ``k`` with ``t[k + 1] <= t[k]`` (instants not strictly increasing), or None."""
    steps = np.diff(np.asarray(t, dtype=float))
    bad = np.flatnonzero(~(steps > 0))
    return int(bad[0]) if bad.size else None


def _names(value, m, what):
    """``value`` (one string, or one per input column) as a tuple of ``m`` strings."""
    if isinstance(value, str):
        return (value,) if m == 1 else tuple(f"{value}{j + 1}" if value else "" for j in range(m))
    try:
        out = tuple(value)
    except TypeError:
        raise ParameterError(f"`{what}` must be a string or one string per input column; got "
                             f"{value!r}.") from None
    if len(out) != m or not all(isinstance(v, str) for v in out):
        raise ParameterError(f"`{what}` must hold {m} strings (one per input column); got "
                             f"{value!r}.")
    return out


@dataclass(frozen=True, repr=False)
class Record:
    """One measured (or simulated) experiment: input and output samples and what they mean.

    Parameters
    ----------
    u : array_like, shape (N,) or (N, m)
        Input samples (one column per input), finite, in the data's own units.
    y : array_like, shape (N,)
        Output samples.
    dt : float or None, optional
        Sampling time (in ``time_unit``); ``None`` where the source gives none (the model then
        uses one sample as the unit) or where ``t`` gives the instants.
    t : array_like, shape (N,), optional
        Sampling instants, strictly increasing (instead of ``dt`` and ``t0``). Instants that all
        lie within :data:`UNIFORM_RTOL` of their mean step of a uniform grid are uniform: the
        record then has ``dt`` = that mean step and ``t0 = t[0]``, and :attr:`t` is ``None``.
        Non-uniform instants are kept; the model kinds that can simulate on them do so
        (:func:`fohw.fit` says which cannot).
    intersample : {"zoh", "foh"}, optional
        How the input behaves between samples: held (zero-order hold, the default) or linear
        (first-order hold). :func:`fohw.fit` simulates a record with time stamps, or with a
        first-order hold, between its samples (the kind's ``simulate_at``).
    t0 : float, optional
        The time of the first sample (default 0).
    name : str, optional
        What the record is.
    input_name, input_unit : str or sequence of str, optional
        What each input column measures and its unit (one string for one input).
    output_name, output_unit, time_unit : str, optional
    source : str, optional
        The citation of the data.
    path : str or None, optional
        The file it was read from.

    Notes
    -----
    Several experiments of one system are a list of Records; :func:`fohw.fit` fits one model to
    all of them (shared parameters, each record simulated from its own start).

    Examples
    --------
    >>> import fohw
    >>> tanks = fohw.datasets.cascaded_tanks()
    >>> tanks.estimation.dt, tanks.estimation.output_name
    (4.0, 'lower tank level')
    >>> first, rest = tanks.estimation.split(0.25)
    >>> first.n_samples, rest.n_samples, rest.output_unit
    (256, 768, 'V')
    >>> rec = fohw.Record(u=[1.0, 0.0, 0.0, 1.0], y=[0.0, 1.0, 0.5, 0.2], t=[0.0, 0.5, 1.5, 2.0])
    >>> rec.uniform, rec.time
    (False, array([0. , 0.5, 1.5, 2. ]))
    """

    u: np.ndarray
    y: np.ndarray
    dt: float | None = None
    name: str = ""
    input_name: str | tuple = "u"
    output_name: str = "y"
    input_unit: str | tuple = ""
    output_unit: str = ""
    time_unit: str = ""
    source: str = ""
    path: str | None = None
    t: np.ndarray | None = None
    intersample: str = "zoh"
    t0: float = 0.0

    def __post_init__(self):
        u = check_array(self.u, "u", ndim=None)
        if u.ndim == 2 and u.shape[1] == 1:
            u = u[:, 0]
        if u.ndim not in (1, 2) or u.shape[0] == 0 or (u.ndim == 2 and u.shape[1] == 0):
            raise DimensionError(f"`u` must have shape (N,) or (N, m); got {u.shape}.")
        y = check_array(self.y, "y")
        check_same_length(u, y, "u", "y")
        for name, value in (("u", u), ("y", y)):
            value = value.copy()
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        m = 1 if u.ndim == 1 else u.shape[1]
        names = _names(self.input_name, m, "input_name")
        units = _names(self.input_unit, m, "input_unit")
        object.__setattr__(self, "input_name", names[0] if m == 1 else names)
        object.__setattr__(self, "input_unit", units[0] if m == 1 else units)
        if self.intersample not in INTERSAMPLE:
            raise ParameterError(f"`intersample` must be one of {INTERSAMPLE}; got "
                                 f"{self.intersample!r}.")
        object.__setattr__(self, "t0", check_scalar(self.t0, "t0"))
        if self.t is not None and self.t0 != 0.0:
            raise ParameterError(f"give `t0` or `t`, not both (the instants start at t[0]); got "
                                 f"t0 = {self.t0!r}.")
        if self.t is not None:
            t = check_array(self.t, "t")
            check_same_length(t, y, "t", "y")
            steps = np.diff(t)
            if steps.size and not np.all(steps > 0):
                k = int(np.flatnonzero(steps <= 0)[0])
                raise ParameterError(f"`t` must be strictly increasing; t[{k + 1}] = {t[k + 1]!r}"
                                     f" follows t[{k}] = {t[k]!r}.")
            if steps.size == 0:
                raise DimensionError("`t` needs at least two instants to say a sampling time.")
            mean = (t[-1] - t[0]) / steps.size
            grid = t[0] + mean * np.arange(t.size)
            slack = UNIFORM_RTOL * mean + 4 * np.finfo(float).eps * float(np.max(np.abs(t)))
            uniform = bool(np.max(np.abs(t - grid)) <= slack)
            if self.dt is not None and not (uniform and abs(self.dt - mean) <= slack):
                raise ParameterError(f"give `dt` or `t`, not both: `dt` = {self.dt!r} but the "
                                     f"instants `t` have {'mean ' if not uniform else ''}step "
                                     f"{mean!r}{'' if uniform else ' and are not uniform'}.")
            object.__setattr__(self, "t0", float(t[0]))
            if uniform:
                object.__setattr__(self, "dt", float(mean))
                object.__setattr__(self, "t", None)
            else:
                t = t.copy()
                t.setflags(write=False)
                object.__setattr__(self, "t", t)
        if self.dt is not None:
            object.__setattr__(self, "dt", check_scalar(self.dt, "dt", lower=0.0,
                                                        lower_inclusive=False))

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return self.u.shape[0]

    @property
    def n_inputs(self) -> int:
        """Number of input columns ``m``."""
        return 1 if self.u.ndim == 1 else self.u.shape[1]

    @property
    def input_names(self) -> tuple:
        """The input columns' names (one per column)."""
        return _names(self.input_name, self.n_inputs, "input_name")

    @property
    def input_units(self) -> tuple:
        """The input columns' units (one per column)."""
        return _names(self.input_unit, self.n_inputs, "input_unit")

    @property
    def uniform(self) -> bool:
        """Whether the samples are uniformly spaced (no time stamps kept)."""
        return self.t is None

    @property
    def sampling_time(self) -> float | None:
        """The sampling time, ``None`` where the source gives none (alias of :attr:`dt`)."""
        return self.dt

    @property
    def time(self) -> np.ndarray:
        """Sample instants: :attr:`t`, or ``t0 + k * dt`` (``k`` where ``dt`` is unknown)."""
        if self.t is not None:
            return np.array(self.t)
        return self.t0 + np.arange(self.n_samples) * (self.dt or 1.0)

    @property
    def time_label(self) -> str:
        """The label of a time axis: ``"time [s]"``, or ``"sample k"`` where ``dt`` is unknown."""
        if self.dt is None and self.t is None:
            return "sample k"
        return f"time [{self.time_unit}]" if self.time_unit else "time"

    def label(self, which="y", column=0) -> str:
        """An axis label for the output (``"y"``) or an input column (``"u"``): name [unit]."""
        if which == "y":
            name, unit = self.output_name, self.output_unit
        else:
            name, unit = self.input_names[column], self.input_units[column]
        return f"{name} [{unit}]" if unit else name

    def split(self, at):
        """``(first, second)``: the samples before ``at`` and from ``at`` on.

        ``at`` is a sample index (``1 <= at < N``) or a fraction of the record (``0 < at < 1``).
        Both parts keep the names, units, sampling time (or instants) and source.
        """
        n = self.n_samples
        if isinstance(at, numbers.Integral) and not isinstance(at, bool):
            index = int(at)
        elif isinstance(at, numbers.Real) and not isinstance(at, bool) and 0.0 < at < 1.0:
            index = int(round(at * n))
        else:
            raise ParameterError(f"`at` must be a sample index or a fraction in (0, 1); got "
                                 f"{at!r}.")
        if not 1 <= index < n:
            raise ParameterError(f"`at` must leave samples on both sides: 1 <= at < {n}; got "
                                 f"{at!r} (index {index}).")
        return self[:index], self[index:]

    def __getitem__(self, index):
        if not isinstance(index, slice) or index.step not in (None, 1):
            raise ParameterError("a Record is indexed by a contiguous slice, e.g. record[100:];"
                                 f" got {index!r}.")
        start, stop, _ = index.indices(self.n_samples)
        if stop <= start:
            raise ParameterError(f"the slice {index!r} of a record of {self.n_samples} samples "
                                 "is empty.")
        name = f"{self.name}[{start}:{stop}]" if self.name else ""
        if self.t is not None:
            t = self.t[index]
            if t.size < 2:
                raise ParameterError(f"the slice {index!r} leaves one instant: a record with "
                                     "time stamps keeps at least two.")
            return replace(self, u=self.u[index], y=self.y[index], t=t, t0=0.0, name=name)
        return replace(self, u=self.u[index], y=self.y[index], name=name,
                       t0=self.t0 + start * (self.dt or 1.0))

    # --- tables ---------------------------------------------------------------------------
    @classmethod
    def from_dataframe(cls, frame, u, y, *, time=None, dt=None, units=None, **kwargs):
        """A record from a :class:`pandas.DataFrame` (channel names from its columns).

        Parameters
        ----------
        frame : pandas.DataFrame
        u : str or sequence of str
            The input column(s).
        y : str
            The output column.
        time : str, optional
            A column of sampling instants: numbers (in the unit its name gives, ``time_s`` or
            ``Time [ms]``), or date/times or time deltas (seconds from the first, ``time_unit``
            "s"). Default: the index if it is a :class:`~pandas.DatetimeIndex` or
            :class:`~pandas.TimedeltaIndex` (the same), else, without ``dt``, the one column
            named as time (``t``, ``time``, ``time_s``, ... as :func:`fohw.read_record` finds
            it) that is not ``u`` or ``y``, else none. Instants must increase strictly (the
            error names the rows).
        dt : float, optional
            The sampling time, where no time column or time index gives the instants.
        units : mapping, optional
            ``column -> unit``.
        **kwargs
            Further :class:`Record` fields (``name``, ``time_unit``, ``source``, ``intersample``).

        Raises
        ------
        ParameterError
            ``frame`` is not a DataFrame; a column named in ``u``, ``y`` or ``time`` is missing,
            named twice in the frame or given twice (the output also an input); ``units`` is not
            a mapping; the time index holds a missing instant (``NaT``).
        """
        if not (hasattr(frame, "columns") and hasattr(frame, "index")):
            raise ParameterError(f"`frame` must be a pandas DataFrame; got "
                                 f"{type(frame).__name__} (pandas.DataFrame(frame) makes one; "
                                 "fohw.Record(u=..., y=...) takes arrays).")
        if units is not None and not hasattr(units, "items"):
            raise ParameterError("`units` must map each column to its unit, e.g. "
                                 f"{{'i': 'A', 'v': 'V'}}; got {type(units).__name__}.")
        columns = [u] if isinstance(u, str) else list(u)
        named = columns + [y] + ([] if time is None else [time])
        for col in named:
            if col not in frame.columns:
                raise ParameterError(f"{col!r} is not a column of the DataFrame (columns: "
                                     f"{', '.join(map(str, frame.columns))}).")
            if list(frame.columns).count(col) > 1:
                raise ParameterError(f"the DataFrame has {list(frame.columns).count(col)} "
                                     f"columns named {col!r}; a name must say which column it "
                                     "is: rename one.")
        if y in columns:
            raise ParameterError(f"`u` and `y` name the same column ({y!r}): the input and the "
                                 "output are different columns.")
        for col in named:
            if named.count(col) > 1:
                raise ParameterError(f"the column {col!r} is given twice among `u`, `y` and "
                                     "`time`: the inputs, the output and the time are distinct "
                                     "columns.")
        units = dict(units or {})
        index = frame.index
        kind = getattr(index, "inferred_type", "")
        dated = kind in ("datetime64", "timedelta64", "datetime", "timedelta") or \
            str(getattr(index, "dtype", "")).startswith(("datetime64", "timedelta64"))
        if time is None and dt is None and not dated:
            found = [c for c in frame.columns if isinstance(c, str) and time_column(c)[0]
                     and c not in columns + [y]]
            time = found[0] if len(found) == 1 else None
        t = None
        if time is not None:
            t = _instants(frame[time], f"frame[{time!r}]", frame.index, kwargs)
            unit = time_column(time)[1] if isinstance(time, str) else ""
            if unit or time in units:
                kwargs.setdefault("time_unit", unit or units[time])
        elif dated:
            t = _instants(index, "the index", index, kwargs)
        if t is not None and dt is not None:
            raise ParameterError("give `dt` or a time column/index, not both.")
        uu = frame[columns].to_numpy(dtype=float)
        return cls(u=uu[:, 0] if len(columns) == 1 else uu, y=frame[y].to_numpy(dtype=float),
                   dt=dt, t=t, input_name=columns[0] if len(columns) == 1 else tuple(columns),
                   output_name=y,
                   input_unit=units.get(columns[0], "") if len(columns) == 1 else
                   tuple(units.get(c, "") for c in columns),
                   output_unit=units.get(y, ""), **kwargs)

    def to_dataframe(self):
        """A :class:`pandas.DataFrame`: a time column, the inputs, then the output.

        Units are in ``frame.attrs["units"]``; the record's other fields in ``frame.attrs``.
        """
        import pandas as pd

        data = {"time": self.time}
        u = self.u.reshape(self.n_samples, -1)
        for j, name in enumerate(self.input_names):
            data[name] = u[:, j]
        data[self.output_name] = self.y
        if len(data) != 2 + self.n_inputs:
            raise ParameterError("the record's channel names are not distinct "
                                 f"({self.input_names}, {self.output_name!r}); cannot make columns.")
        frame = pd.DataFrame(data)
        frame.attrs["units"] = {**dict(zip(self.input_names, self.input_units)),
                                self.output_name: self.output_unit, "time": self.time_unit}
        frame.attrs.update(name=self.name, dt=self.dt, source=self.source,
                           intersample=self.intersample)
        return frame

    def _signal(self, which):
        if which == "u" and self.n_inputs > 1:
            return "u = " + ", ".join(self.label("u", j) for j in range(self.n_inputs))
        name, unit = ((self.input_name, self.input_unit) if which == "u"
                      else (self.output_name, self.output_unit))
        unit = f" [{unit}]" if unit else ""
        return f"{which}{unit} = {name}" if name != which else f"{which}{unit}"

    def __repr__(self):
        unit = f" {self.time_unit}" if self.time_unit else ""
        if self.t is not None:
            dt = f"non-uniform, mean step {(self.t[-1] - self.t[0]) / (self.n_samples - 1):g}{unit}"
        else:
            dt = "unknown" if self.dt is None else f"{self.dt:g}{unit}"
        return (f"Record({self.name!r}, n_samples={self.n_samples}, dt={dt}, "
                f"{self._signal('u')}, {self._signal('y')})")


def _instants(values, what, labels, kwargs):
    """Instants of a time column or index, strictly increasing; a gap (NaT, NaN) named by its row.

    Numbers as they are; date/times or time deltas in seconds from the first (``time_unit`` "s").
    """
    dtype = str(getattr(values, "dtype", ""))
    if dtype.startswith(("datetime64", "timedelta64")):
        raw = np.asarray(values)
        missing = np.flatnonzero(np.isnat(raw))
        if missing.size:
            k = int(missing[0])
            row = "" if labels is values else f" (row {labels[k]!r})"
            raise ParameterError(f"{what} holds no time (NaT) at position {k}{row}; fohw fills "
                                 "no gaps: drop the row or give its time.")
        t = (raw - raw[0]).astype("timedelta64[ns]").astype(np.int64) / 1e9
        kwargs.setdefault("time_unit", "s")
    else:
        try:
            t = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{what} must hold numbers, date/times or time deltas; got "
                                 f"dtype {dtype}.") from None
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise ParameterError(f"{what} holds {t[bad[0]]!r} at row {labels[bad[0]]!r}; fohw "
                                 "fills no gaps: drop the row or give its time.")
    k = first_disorder(t)
    if k is not None:
        how = "repeats the instant of" if t[k + 1] == t[k] else "goes back from"
        raise ParameterError(f"{what} must increase strictly: row {labels[k + 1]!r} {how} row "
                             f"{labels[k]!r} ({float(t[k])!r} -> {float(t[k + 1])!r}).")
    return t


def as_records(data, y=None, *, what="data"):
    """``data`` as a list of :class:`Record` (a Record, a DataFrame needs columns: refused here).

    Returns ``None`` when ``data`` is not a record or a list of records (arrays: the caller
    reads ``u, y``).
    """
    if isinstance(data, Record):
        records = [data]
    elif isinstance(data, (list, tuple)) and any(isinstance(r, Record) for r in data):
        other = [k for k, r in enumerate(data) if not isinstance(r, Record)]
        if other:
            raise ParameterError(f"`{what}` mixes Records and other data (entry {other[0]} is a "
                                 f"{type(data[other[0]]).__name__}); a list of experiments holds "
                                 "Records only (fohw.Record(u=..., y=...) for arrays).")
        records = list(data)
    elif isinstance(data, (list, tuple)) and len(data) == 0:
        raise ParameterError(f"`{what}` is an empty list: give a Record, a list of Records, or "
                             "arrays u and y.")
    elif type(data).__name__ == "DataFrame":
        raise ParameterError(f"`{what}` is a DataFrame: say which columns are the input and the "
                             "output with fohw.Record.from_dataframe(frame, u=..., y=...).")
    else:
        return None
    if y is not None:
        raise ParameterError(f"`{what}` is a Record (or a list of them), which carries its output;"
                             f" do not also pass `y`.")
    return records


def record_data(data, y=None, *, what="u", several=True):
    """The data a verb was given, as ``(records, u, y)``: the one conversion every verb calls.

    Parameters
    ----------
    data : array_like, Record, list of Record or DataFrame
        What the verb got in place of ``u``.
    y : array_like or None
        What it got as ``y``.
    what : str
        The argument's name, for the messages.
    several : bool
        Whether the verb takes a list of Records (several experiments).

    Returns
    -------
    records : list of Record or None
        ``None`` for arrays (``u, y`` are then ``data, y`` as given).
    u, y : ndarray or None
        One record's samples; ``None, None`` for several records.

    Raises
    ------
    ParameterError
        A DataFrame as the data (without ``y``): which columns are the input and the output is
        said with :meth:`Record.from_dataframe`, never guessed; a Record with ``y`` also given;
        several records where the verb takes one.
    """
    if y is None and type(data).__name__ == "DataFrame":
        raise ParameterError(
            f"`{what}` is a pandas DataFrame: fohw does not guess which columns are the input "
            "and the output. Build a record with fohw.Record.from_dataframe(frame, u=..., y=..., "
            "time=... or dt=..., units=...) and pass it.")
    records = as_records(data, y, what=what) if type(data).__name__ != "DataFrame" else None
    if records is None:
        return None, data, y
    if len(records) == 1 and isinstance(data, Record):
        return records, records[0].u, records[0].y
    if not several:
        raise ParameterError(f"`{what}` holds {len(records)} records; this takes one record (a "
                             "fohw.Record or arrays). Fit several experiments with fohw.fit.")
    return records, None, None


def record_info(records):
    """What the data were (names, units, sampling), as a result keeps it (``result.data``)."""
    first = records[0]
    return {"input_names": list(first.input_names), "input_units": list(first.input_units),
            "output_name": first.output_name, "output_unit": first.output_unit,
            "time_unit": first.time_unit, "dt": first.dt,
            "records": [{"name": r.name, "n_samples": r.n_samples, "t0": r.t0,
                         "uniform": r.uniform, "dt": r.dt} for r in records]}


def describe_data(info):
    """One line of what the data were (:func:`record_info`), as ``summary()`` prints it."""
    inputs = ", ".join(f"{n} [{u}]" if u else n
                       for n, u in zip(info["input_names"], info["input_units"]))
    out = f"{info['output_name']} [{info['output_unit']}]" if info["output_unit"] else \
        info["output_name"]
    dt = "" if info.get("dt") is None else \
        f", dt = {info['dt']:g} {info.get('time_unit', '')}".rstrip()
    return f"data: {len(info['records'])} record(s); input {inputs}; output {out}{dt}"


def check_sampling(records, dt, *, what="the model's dt"):
    """Refuse records sampled at another step than ``dt`` (``None``: a model in samples).

    fohw never changes a sampling time silently: a record at 4 s and a model at 1 s are two
    different systems.
    """
    for k, r in enumerate(records):
        if r.uniform and r.dt is not None and dt is not None and \
                abs(r.dt - dt) > UNIFORM_RTOL * r.dt:
            name = f" {r.name!r}" if r.name else (f" {k}" if len(records) > 1 else "")
            raise ParameterError(
                f"the record{name} is sampled every {r.dt!r} {r.time_unit}".rstrip()
                + f" but {what} = {dt!r}; use dt={r.dt!r} (the record's sampling time): "
                "fohw does not change it silently.")


@dataclass(frozen=True, repr=False)
class Benchmark:
    """A benchmark: its estimation and validation records and the rules it is judged by.

    Attributes
    ----------
    estimation, validation : Record
    name : str
    source : str
        The citation.
    rules : str
        How results are compared (what is simulated, which error is reported).
    """

    estimation: Record
    validation: Record
    name: str
    source: str
    rules: str

    def __repr__(self):
        return (f"Benchmark({self.name!r}, estimation={self.estimation.n_samples}, "
                f"validation={self.validation.n_samples} samples)")
