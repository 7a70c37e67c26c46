"""A measured input–output record: samples, sampling time, names, units and where it came from.

MATLAB's ``iddata`` is the model users know: one object carries the signals and what they
mean, and splitting it into estimation and validation parts keeps that meaning.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace

import numpy as np

from ._validation import check_array, check_same_length, check_scalar
from .exceptions import ParameterError

__all__ = ["Record", "Benchmark"]


@dataclass(frozen=True, repr=False)
class Record:
    """One measured (or simulated) SISO record.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output samples, finite, in the data's own units.
    dt : float or None, optional
        Sampling time (in ``time_unit``); ``None`` where the source gives none (the model then
        uses one sample as the unit).
    name : str, optional
        What the record is.
    input_name, output_name, input_unit, output_unit, time_unit : str, optional
        What ``u`` and ``y`` measure and in which units.
    source : str, optional
        The citation of the data.
    path : str or None, optional
        The file it was read from.

    Examples
    --------
    >>> import fohw
    >>> tanks = fohw.datasets.cascaded_tanks()
    >>> tanks.estimation.dt, tanks.estimation.output_name
    (4.0, 'lower tank level')
    >>> first, rest = tanks.estimation.split(0.25)
    >>> first.n_samples, rest.n_samples, rest.output_unit
    (256, 768, 'V')
    """

    u: np.ndarray
    y: np.ndarray
    dt: float | None = None
    name: str = ""
    input_name: str = "u"
    output_name: str = "y"
    input_unit: str = ""
    output_unit: str = ""
    time_unit: str = ""
    source: str = ""
    path: str | None = None

    def __post_init__(self):
        u = check_array(self.u, "u")
        y = check_array(self.y, "y")
        check_same_length(u, y, "u", "y")
        for name, value in (("u", u), ("y", y)):
            value = value.copy()
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        if self.dt is not None:
            object.__setattr__(self, "dt", check_scalar(self.dt, "dt", lower=0.0,
                                                        lower_inclusive=False))

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return self.u.shape[0]

    @property
    def sampling_time(self) -> float | None:
        """The sampling time, ``None`` where the source gives none (alias of :attr:`dt`)."""
        return self.dt

    @property
    def time(self) -> np.ndarray:
        """Sample times ``k * dt`` (``k`` where ``dt`` is unknown)."""
        return np.arange(self.n_samples) * (self.dt or 1.0)

    def split(self, at):
        """``(first, second)``: the samples before ``at`` and from ``at`` on.

        ``at`` is a sample index (``1 <= at < N``) or a fraction of the record (``0 < at < 1``).
        Both parts keep the names, units, sampling time and source.
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
        return replace(self, u=self.u[index], y=self.y[index],
                       name=f"{self.name}[{start}:{stop}]" if self.name else "")

    def _signal(self, which):
        name, unit = ((self.input_name, self.input_unit) if which == "u"
                      else (self.output_name, self.output_unit))
        unit = f" [{unit}]" if unit else ""
        return f"{which}{unit} = {name}" if name != which else f"{which}{unit}"

    def __repr__(self):
        unit = f" {self.time_unit}" if self.time_unit else ""
        dt = "unknown" if self.dt is None else f"{self.dt:g}{unit}"
        return (f"Record({self.name!r}, n_samples={self.n_samples}, dt={dt}, "
                f"{self._signal('u')}, {self._signal('y')})")


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
