"""Private input validation shared by every public entry point.

Errors name the argument and echo what arrived; nothing is silently fixed.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping

import numpy as np

from .exceptions import DimensionError, ParameterError

__all__: list[str] = []


def _shape_text(x) -> str:
    return "x".join(str(s) for s in np.shape(x)) or "scalar"


def check_scalar(value, name: str, *, lower=None, upper=None, lower_inclusive=True,
                 upper_inclusive=True) -> float:
    """Return ``value`` as a finite float inside the given interval, or raise."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.number)):
        if not (isinstance(value, np.ndarray) and value.ndim == 0):
            raise ParameterError(f"`{name}` must be a real number; got {value!r}.")
    value = float(value)
    if not np.isfinite(value):
        raise ParameterError(f"`{name}` must be finite; got {value!r}.")
    lo_bad = lower is not None and (value < lower or (value == lower and not lower_inclusive))
    hi_bad = upper is not None and (value > upper or (value == upper and not upper_inclusive))
    if lo_bad or hi_bad:
        left = "[" if lower_inclusive else "("
        right = "]" if upper_inclusive else ")"
        lo = "-inf" if lower is None else f"{lower:g}"
        hi = "inf" if upper is None else f"{upper:g}"
        raise ParameterError(f"`{name}` must be in {left}{lo}, {hi}{right}; got {value!r}.")
    return value


def check_int(value, name: str, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """Return ``value`` as an int (no bools, no floats), inside ``[minimum, maximum]``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, np.integer)):
        raise ParameterError(f"`{name}` must be an integer; got {value!r}.")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ParameterError(f"`{name}` must be at least {minimum}; got {value}.")
    if maximum is not None and value > maximum:
        raise ParameterError(f"`{name}` must be at most {maximum}; got {value}.")
    return value


def check_array(x, name: str, *, ndim: int | None = 1, min_length: int = 1) -> np.ndarray:
    """Return ``x`` as a float64 array of the given dimension with only finite values.

    Only real numbers are samples: booleans, integers and floats are converted; complex
    numbers, strings, dates (``datetime64``), durations (``timedelta64``) and arbitrary objects
    are refused, never read as numbers. A masked array is accepted only when nothing is masked
    (fohw never fits the values hidden under a mask).
    """
    if np.ma.isMaskedArray(x):
        mask = np.ma.getmaskarray(x)
        if mask.any():
            where = np.argwhere(mask)[0]
            first = int(where[0]) if mask.ndim == 1 else tuple(int(i) for i in where)
            raise ParameterError(
                f"`{name}` is a masked array with {int(mask.sum())} masked sample(s) (the first "
                f"at index {first}); fohw does not skip masked samples and will not fit the "
                f"values under the mask. Fill them (`{name}.filled(value)`, or interpolate) or "
                "cut the record to a stretch without masked samples.")
        x = np.ma.getdata(x)
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"`{name}` must be an array of real numbers; got {type(x).__name__}"
                             f" that cannot be converted ({exc}).") from None
    kind = raw.dtype.kind
    if kind == "c":
        raise ParameterError(f"`{name}` must be real; got a complex array.")
    if kind in "mM":
        raise ParameterError(
            f"`{name}` must be an array of real numbers; got {raw.dtype} values (dates or "
            "durations), which fohw will not read as numbers. Pass the samples themselves; a "
            "time stamp column gives the sampling time `dt`, not a signal.")
    if kind not in "biuf":
        what = {"U": "strings", "S": "bytes", "O": "Python objects", "V": "structured records"}
        raise ParameterError(
            f"`{name}` must be an array of real numbers; got an array of "
            f"{what.get(kind, 'values')} (dtype {raw.dtype}). Convert it first, e.g. "
            f"np.asarray({name}, dtype=float), or read the file with fohw.read_record.")
    try:
        arr = raw.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError) as exc:      # pragma: no cover - numeric kinds
        raise ParameterError(f"`{name}` must be an array of real numbers; got {raw.dtype} "
                             f"values that cannot be converted ({exc}).") from None
    if ndim is not None and arr.ndim != ndim:
        raise DimensionError(f"`{name}` must be {ndim}-D; got an array of shape ({_shape_text(arr)}).")
    if arr.ndim >= 1 and arr.shape[-1] < min_length:
        raise DimensionError(f"`{name}` must have at least {min_length} sample(s) along its last "
                             f"axis; got {arr.shape[-1]}.")
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.isfinite(arr.ravel()))[0]
        idx = np.unravel_index(bad, arr.shape)
        where = idx[0] if arr.ndim == 1 else tuple(int(i) for i in idx)
        raise ParameterError(f"`{name}` must contain only finite values; got "
                             f"{arr.ravel()[bad]!r} at index {where}.")
    return arr


def unpack_pair(value, name: str, form: str):
    """``value`` unpacked as a pair; a dict (read by its keys) or anything else is refused."""
    if isinstance(value, Mapping):
        raise ParameterError(f"`{name}` must be the pair {form}; got a {type(value).__name__} with the "
                             f"keys {list(value)!r} (a pair is read by position, and a dict read so "
                             f"gives its keys, not its values). Pass {form}, e.g. "
                             f"({', '.join(f'd[{k!r}]' for k in value)}).")
    try:
        first, second = value
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be the pair {form}; got {type(value).__name__}.") from None
    return first, second


def check_same_length(x: np.ndarray, y: np.ndarray, xname: str, yname: str) -> None:
    """Raise if two signals differ in length (samples along the first axis)."""
    if x.shape[0] != y.shape[0]:
        raise DimensionError(f"`{xname}` and `{yname}` must have the same length; got "
                             f"{x.shape[0]} and {y.shape[0]}.")


def check_inputs(u, n_inputs: int, name: str = "u", names=()) -> np.ndarray:
    """The input record: 1-D for one input (as :func:`check_array`), ``(N, m)`` for ``m > 1``.

    ``names``: the model's input names (``Structure.inputs``). A pandas DataFrame's columns are
    then matched by those names, whatever their order; a frame whose columns are other names is
    refused, unless the model's names are the defaults ``u1, u2, …`` (it was fitted to an array
    without names: the columns are taken in order).
    """
    if n_inputs > 1 and names:
        u = _columns_by_name(u, tuple(names), name)
    if np.ndim(u) == 2 and np.shape(u)[1] == 0:
        raise DimensionError(f"`{name}` has no columns (shape ({_shape_text(np.asarray(u))})): give "
                             "one column per input.")
    if n_inputs == 1:
        if np.ndim(u) == 2 and np.shape(u)[1] == 1:            # one column: the one input
            return check_array(np.asarray(u)[:, 0], name)
        return check_array(u, name)
    arr = check_array(u, name, ndim=2)
    if arr.shape[1] != n_inputs:
        raise DimensionError(f"`{name}` must have {n_inputs} columns (one per input); got shape "
                             f"({_shape_text(arr)}).")
    return arr


def _columns_by_name(u, names, name):
    """``u``'s columns in the order of ``names`` when ``u`` is a DataFrame; ``u`` otherwise."""
    if not type(u).__module__.startswith("pandas") or np.ndim(u) != 2:
        return u
    order = column_order(u.columns, names, name)
    return u if order is None else np.asarray(u)[:, order]


def column_order(columns, names, name="u", what="a DataFrame with the columns"):
    """The indices that put named ``columns`` in the order of the model's input ``names``.

    None keeps them as they are: already in order, or the model knows no names (the defaults
    ``u1, u2, …``: it was fitted to an array). Other names are a DimensionError naming ``name``.
    One rule for a DataFrame's columns and a :class:`fohw.Record`'s input names.
    """
    columns = [str(c) for c in columns]
    if columns == list(names):
        return None
    if sorted(columns) == sorted(names) and len(set(columns)) == len(columns):
        return [columns.index(n) for n in names]
    if tuple(names) == tuple(f"u{i}" for i in range(1, len(names) + 1)):
        return None                         # the model knows no names: the columns in order
    raise DimensionError(f"`{name}` is {what} {columns}, but the model's inputs "
                         f"are {list(names)} (the names kept from its fit); fohw matches columns by "
                         f"name. Select and rename them (e.g. {name}[{list(names)}]), or pass an "
                         "array whose columns are in the model's order.")


def check_alpha(alpha, name: str = "alpha", *, lower: float = 0.0, upper: float = 2.0,
                inclusive: bool = False) -> float:
    """Validate a fractional order."""
    return check_scalar(alpha, name, lower=lower, upper=upper, lower_inclusive=inclusive,
                        upper_inclusive=inclusive)


def check_random_state(random_state) -> np.random.Generator:
    """Turn ``None | int | Generator`` into a Generator; never touch the global generator."""
    if random_state is None:
        return np.random.default_rng()
    if isinstance(random_state, np.random.Generator):
        return random_state
    if isinstance(random_state, (numbers.Integral, np.integer)) and not isinstance(random_state, bool):
        if random_state < 0:
            raise ParameterError(f"`random_state` must be non-negative; got {random_state}.")
        return np.random.default_rng(int(random_state))
    raise ParameterError("`random_state` must be None, a non-negative int or a "
                         f"numpy.random.Generator; got {random_state!r}.")


class AlphaBounds:
    """The interval ``[lo, hi]`` for alpha; calling it keeps a recursive estimate a margin inside.

    ``lo`` and ``hi`` may be any ``0 <= lo < hi <= 2``. The recursive methods hold alpha in
    ``inner = (lo + m, hi - m)`` with ``m = 1e-3 (hi - lo)`` and record that they did (``hit``).
    """

    def __init__(self, bounds, name="alpha_bounds"):
        try:
            lo, hi = (float(b) for b in bounds)
        except (TypeError, ValueError):
            raise ParameterError(f"`{name}` must be a pair (low, high); got {bounds!r}.") \
                from None
        if not (0.0 <= lo < hi <= 2.0):
            raise ParameterError(f"`{name}` must satisfy {0.0:g} <= low < high "
                                 f"<= {2.0:g}; got {bounds!r}.")
        self.lo, self.hi = lo, hi
        margin = 1e-3 * (hi - lo)
        self.inner = (lo + margin, hi - margin)
        self.hit = False

    def __call__(self, alpha):
        if not np.isfinite(alpha):
            from .exceptions import EstimationDivergedError

            raise EstimationDivergedError(f"the alpha estimate became {alpha!r}; there is no "
                                          "estimate to hold inside `alpha_bounds`.")
        if alpha < self.inner[0] or alpha > self.inner[1]:
            self.hit = True
            return float(np.clip(alpha, *self.inner))
        return alpha


#: How far (a fraction of the estimation input's span) an input may go beyond the estimation
#: range before it counts as outside it: an i.i.d. input exceeds its own sample range a little.
RANGE_TOLERANCE = 0.05


def input_in_range(u, u_range, tolerance=RANGE_TOLERANCE) -> bool:
    """Whether ``u`` stays within ``u_range = (lo, hi)`` widened by ``tolerance`` of its span."""
    u = np.asarray(u)
    if u.ndim == 2:                      # several inputs: ranges ((lo_1, ...), (hi_1, ...))
        lo, hi = (np.asarray(r, dtype=float) for r in u_range)
        slack = tolerance * (hi - lo)
        return bool(u.size == 0 or (np.all(u.min(axis=0) >= lo - slack)
                                    and np.all(u.max(axis=0) <= hi + slack)))
    lo, hi = u_range
    slack = tolerance * (hi - lo)
    return bool(u.size == 0 or (u.min() >= lo - slack and u.max() <= hi + slack))


def check_pair(value, name):
    """``value`` as a pair of finite floats (``past``, ``operating_point``), or a ParameterError."""
    if isinstance(value, Mapping):
        unpack_pair(value, name, "of numbers (a, b)")
    try:
        a, b = value
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be a pair of numbers; got {value!r}.") from None
    return check_scalar(a, f"{name}[0]"), check_scalar(b, f"{name}[1]")
