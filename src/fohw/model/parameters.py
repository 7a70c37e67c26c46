"""Named parameters of every model kind: value, bounds, free or fixed, ties (one container).

A :class:`Parameter` is one named number with its bounds, whether it is held fixed, whether it
is tied to another one (``value = factor * source``) and whether it is a fractional order.
:class:`Parameters` is an ordered, read-only mapping ``name -> Parameter``; every model kind
(:class:`fohw.Model`) describes its numbers with one, and :func:`fohw.fit`, the Cramér–Rao
bound, the LR test and the profile interval read the free ones from it. Nothing else in fohw
slices a parameter vector by hand. After lmfit's ``Parameter``/``Parameters``.

Fractional orders have one range rule: :data:`ORDER_RANGE` (``[0, 2]``), mirrored to
``(-2, 2)`` where an order may be negative (a numerator order of a transfer function, a fractional
integral: :data:`fohw.model.transfer.NUM_ORDER_RANGE`). A kind whose model was given an order
outside its range widens that order's own bound to its value.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import numbers
from collections.abc import Iterable, Mapping

import numpy as np

from ..exceptions import ParameterError
from .orders import ORDER_RANGE

__all__ = ["Parameter", "Parameters", "ORDER_RANGE", "bounds_overridden"]

_OVERRIDDEN = contextvars.ContextVar("fohw_bounds_overridden", default=False)


@contextlib.contextmanager
def bounds_overridden():
    """Within it, a :class:`Parameter` may be built with a value outside its bounds.

    For :class:`fohw.Model`: a kind builds its parameters with its default bounds, and the
    settings a user gave (wider bounds) replace them right after; the value is checked against
    those.
    """
    token = _OVERRIDDEN.set(True)
    try:
        yield
    finally:
        _OVERRIDDEN.reset(token)


def _number(value, what):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.number)):
        if not (isinstance(value, np.ndarray) and value.ndim == 0):
            raise ParameterError(f"{what} must be a real number; got {value!r}.")
    return float(value)


class Parameter:
    """One named parameter: value, bounds, fixed or free, an optional tie.

    Parameters
    ----------
    name : str
        The parameter's name, unique within its model (a Python identifier is safest).
    value : float
        Its value (the start value when it is free).
    bounds : (float, float), optional
        Closed interval the value must stay in; ``-inf``/``inf`` for none. Default: no bounds
        for a coefficient, :data:`ORDER_RANGE` for an order (a kind gives ``(-2, 2)`` to an
        order that may be negative, such as a transfer function's numerator order).
    fixed : bool, optional
        Held at ``value`` by :func:`fohw.fit` (and left out of covariances). Default False.
    tie : (str, float), optional
        ``(source, factor)``: the value is ``factor`` times the value of the parameter
        ``source`` of the same model (e.g. commensurate orders ``alpha1 = 2 alpha0``). A tied
        parameter is neither free nor fixed on its own.
    order : bool, optional
        True for a fractional order (the LR test and profile intervals treat its bounds as
        boundaries of the parameter space). Default False.

    Examples
    --------
    >>> import fohw
    >>> a = fohw.Parameter("a", 0.5, bounds=(-1, 1))
    >>> a
    Parameter('a', 0.5, bounds=(-1.0, 1.0))
    >>> a.free, a.replace(fixed=True).free
    (True, False)
    """

    __slots__ = ("name", "value", "bounds", "fixed", "tie", "order")

    def __init__(self, name, value, *, bounds=None, fixed=False, tie=None, order=False):
        if not isinstance(name, str) or not name:
            raise ParameterError(f"a parameter's `name` must be a non-empty string; got {name!r}.")
        value = _number(value, f"the value of parameter {name!r}")
        if not math.isfinite(value):
            raise ParameterError(f"the value of parameter {name!r} must be finite; got {value!r}.")
        if not isinstance(fixed, (bool, np.bool_)):
            raise ParameterError(f"`fixed` of parameter {name!r} must be True or False; got {fixed!r}.")
        if not isinstance(order, (bool, np.bool_)):
            raise ParameterError(f"`order` of parameter {name!r} must be True or False; got {order!r}.")
        if bounds is None:
            bounds = ORDER_RANGE if order else (-math.inf, math.inf)
        try:
            lo, hi = bounds
        except (TypeError, ValueError):
            raise ParameterError(f"`bounds` of parameter {name!r} must be a pair (low, high); "
                                 f"got {bounds!r}.") from None
        lo = _number(lo, f"the lower bound of parameter {name!r}")
        hi = _number(hi, f"the upper bound of parameter {name!r}")
        if math.isnan(lo) or math.isnan(hi) or not lo < hi:
            raise ParameterError(f"`bounds` of parameter {name!r} must have low < high; got {bounds!r}.")
        if tie is not None:
            try:
                source, factor = tie
            except (TypeError, ValueError):
                raise ParameterError(f"`tie` of parameter {name!r} must be (source_name, factor); "
                                     f"got {tie!r}.") from None
            if not isinstance(source, str) or source == name:
                raise ParameterError(f"`tie` of parameter {name!r} must name another parameter; "
                                     f"got {source!r}.")
            factor = _number(factor, f"the tie factor of parameter {name!r}")
            if not math.isfinite(factor):
                raise ParameterError(f"the tie factor of parameter {name!r} must be finite; got {factor!r}.")
            tie = (source, factor)
            if fixed:
                raise ParameterError(f"parameter {name!r} is tied to {source!r}; it cannot also be fixed.")
        elif not lo <= value <= hi and not _OVERRIDDEN.get():
            raise ParameterError(f"the value of parameter {name!r} ({value!r}) is outside its bounds "
                                 f"[{lo:g}, {hi:g}].")
        self.name, self.value, self.bounds = name, value, (lo, hi)
        self.fixed, self.tie, self.order = bool(fixed), tie, bool(order)

    @property
    def free(self) -> bool:
        """True when :func:`fohw.fit` estimates it (neither fixed nor tied)."""
        return not self.fixed and self.tie is None

    def replace(self, **changes) -> Parameter:
        """A copy with some attributes changed (``value``, ``bounds``, ``fixed``, ``tie``, ``order``)."""
        kw = {"value": self.value, "bounds": self.bounds, "fixed": self.fixed, "tie": self.tie,
              "order": self.order}
        unknown = set(changes) - set(kw)
        if unknown:
            raise ParameterError(f"Parameter.replace: unknown attribute(s) {sorted(unknown)}; "
                                 f"known: {sorted(kw)}.")
        kw.update(changes)
        return Parameter(self.name, **kw)

    def to_dict(self) -> dict:
        """The parameter as JSON-ready values (infinite bounds as ``null``)."""
        d = {"value": self.value,
             "bounds": [None if math.isinf(b) else b for b in self.bounds]}
        if self.fixed:
            d["fixed"] = True
        if self.tie is not None:
            d["tie"] = list(self.tie)
        if self.order:
            d["order"] = True
        return d

    @classmethod
    def from_dict(cls, name, d) -> Parameter:
        """Inverse of :meth:`to_dict`."""
        if not isinstance(d, Mapping) or "value" not in d:
            raise ParameterError(f"parameter {name!r}: expected a mapping with a 'value'; got {d!r}.")
        unknown = set(d) - {"value", "bounds", "fixed", "tie", "order"}
        if unknown:
            raise ParameterError(f"parameter {name!r}: unknown field(s) {sorted(unknown)}.")
        bounds = d.get("bounds")
        if bounds is not None:
            lo, hi = bounds
            bounds = (-math.inf if lo is None else lo, math.inf if hi is None else hi)
        tie = d.get("tie")
        return cls(name, d["value"], bounds=bounds, fixed=d.get("fixed", False),
                   tie=None if tie is None else tuple(tie), order=d.get("order", False))

    def __eq__(self, other):
        if not isinstance(other, Parameter):
            return NotImplemented
        return all(getattr(self, s) == getattr(other, s) for s in self.__slots__)

    __hash__ = None

    def __repr__(self):
        extra = ""
        if self.bounds != (ORDER_RANGE if self.order else (-math.inf, math.inf)):
            extra += f", bounds={self.bounds}"
        if self.fixed:
            extra += ", fixed=True"
        if self.tie is not None:
            extra += f", tie={self.tie}"
        if self.order:
            extra += ", order=True"
        return f"Parameter({self.name!r}, {self.value!r}{extra})"


def _placed(par, value):
    """``par`` at ``value`` without the bound check (a tied value, or an unchecked read)."""
    if not math.isfinite(value):
        raise ParameterError(f"the value of parameter {par.name!r} must be finite; got {value!r}.")
    out = Parameter.__new__(Parameter)
    for slot in Parameter.__slots__:
        setattr(out, slot, getattr(par, slot))
    out.value = float(value)
    return out


class Parameters(Mapping):
    """An ordered, read-only mapping ``name -> Parameter``: all the numbers of a model.

    Parameters
    ----------
    parameters : iterable of Parameter
        In the model's order; names must be unique and every tie must name a parameter of the
        set that is not itself tied. A tied parameter's value must be its tie's,
        ``factor * source`` (to rounding): a value that contradicts it is refused, naming both
        (:meth:`replace` and :meth:`with_values` set a tied value themselves).

    Examples
    --------
    >>> import fohw
    >>> p = fohw.Parameters([fohw.Parameter("a", 0.5, bounds=(-1, 1)),
    ...                      fohw.Parameter("alpha", 0.6, order=True),
    ...                      fohw.Parameter("b", 2.0, fixed=True)])
    >>> p.free_names, p.valuesdict()["alpha"]
    (('a', 'alpha'), 0.6)
    >>> p.with_values({"a": 0.25})["a"].value
    0.25
    """

    def __init__(self, parameters: Iterable[Parameter] = ()):
        if isinstance(parameters, Parameters):
            parameters = parameters.values()
        items = {}
        for par in parameters:
            if not isinstance(par, Parameter):
                raise ParameterError(f"Parameters holds fohw.Parameter objects; got {par!r}.")
            if par.name in items:
                raise ParameterError(f"two parameters are named {par.name!r}; names must be unique.")
            items[par.name] = par
        for par in items.values():
            if par.tie is not None:
                source = items.get(par.tie[0])
                if source is None or source.tie is not None:
                    raise ParameterError(
                        f"parameter {par.name!r} is tied to {par.tie[0]!r}, which must be a parameter "
                        f"of the same model that is not itself tied; names are {list(items)}.")
                tied = par.tie[1] * source.value
                if not math.isclose(par.value, tied, rel_tol=1e-12, abs_tol=1e-300):
                    raise ParameterError(
                        f"parameter {par.name!r} is tied to {par.tie[0]!r} ({par.tie[1]:g} times it, "
                        f"{tied!r}), but its value is {par.value!r}: a tied parameter takes its "
                        f"tie's value (give value={tied!r}, or no tie).")
        self._items = items

    # Mapping protocol
    def __getitem__(self, name):
        try:
            return self._items[name]
        except KeyError:
            raise KeyError(f"no parameter {name!r}; names are {list(self._items)}.") from None

    def __iter__(self):
        return iter(self._items)

    def __len__(self):
        return len(self._items)

    def __eq__(self, other):
        if not isinstance(other, Parameters):
            return NotImplemented
        return list(self._items.items()) == list(other._items.items())

    __hash__ = None

    def __repr__(self):
        inner = ",\n ".join(repr(p) for p in self._items.values())
        return f"Parameters([{inner}])"

    # Views
    @property
    def names(self) -> tuple[str, ...]:
        """Every name, in order."""
        return tuple(self._items)

    @property
    def free_names(self) -> tuple[str, ...]:
        """The names :func:`fohw.fit` estimates (neither fixed nor tied), in order."""
        return tuple(n for n, p in self._items.items() if p.free)

    def valuesdict(self) -> dict:
        """``{name: value}`` of every parameter (tied ones resolved)."""
        return {n: p.value for n, p in self._items.items()}

    def free_values(self) -> np.ndarray:
        """The values of the free parameters, in :attr:`free_names` order."""
        return np.array([self._items[n].value for n in self.free_names], dtype=np.float64)

    def free_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` of the free parameters."""
        free = [self._items[n] for n in self.free_names]
        return (np.array([p.bounds[0] for p in free], dtype=np.float64),
                np.array([p.bounds[1] for p in free], dtype=np.float64))

    def tie_matrix(self) -> np.ndarray:
        """``T`` with ``d value / d free = T`` (shape ``(len(self), n_free)``): the chain rule of ties."""
        free = {n: j for j, n in enumerate(self.free_names)}
        t = np.zeros((len(self), len(free)))
        for i, (name, par) in enumerate(self._items.items()):
            if name in free:
                t[i, free[name]] = 1.0
            elif par.tie is not None and par.tie[0] in free:
                t[i, free[par.tie[0]]] = par.tie[1]
        return t

    # New sets
    def with_values(self, values, *, check_bounds=True) -> Parameters:
        """A copy with new values (a mapping ``name -> float``; ties re-applied).

        Only the values change: bounds, fixed flags and ties stay. A value outside its bounds
        is refused (unless ``check_bounds=False``: a model's own values read against settings
        that are being changed). Tied parameters follow their source; giving one a value is
        refused.
        """
        if isinstance(values, Parameters):
            values = values.valuesdict()
        if not isinstance(values, Mapping):
            raise ParameterError(f"`values` must be a mapping name -> number; got {type(values).__name__}.")
        unknown = [n for n in values if n not in self._items]
        if unknown:
            raise ParameterError(f"unknown parameter(s) {unknown}; names are {list(self._items)}.")
        new = {}
        for name, par in self._items.items():
            if name in values and par.tie is None:
                value = _number(values[name], f"the value of {name!r}")
                new[name] = par.replace(value=value) if check_bounds else _placed(par, value)
            else:
                new[name] = par
        for name, par in self._items.items():
            if par.tie is not None:
                if name in values and float(values[name]) != par.tie[1] * new[par.tie[0]].value:
                    raise ParameterError(f"parameter {name!r} is tied to {par.tie[0]!r} "
                                         f"({par.tie[1]:g} times it); it takes no value of its own.")
                new[name] = _placed(par, par.tie[1] * new[par.tie[0]].value)
        return Parameters(new.values())

    def with_free(self, x) -> Parameters:
        """A copy whose free parameters take the values ``x`` (in :attr:`free_names` order)."""
        x = np.asarray(x, dtype=np.float64)
        names = self.free_names
        if x.shape != (len(names),):
            raise ParameterError(f"expected {len(names)} free values ({list(names)}); got shape {x.shape}.")
        return self.with_values(dict(zip(names, x.tolist())))

    def replace(self, name, **changes) -> Parameters:
        """A copy in which parameter ``name`` has some attributes changed (see :meth:`Parameter.replace`).

        Tied parameters follow their sources: a new ``tie`` without a ``value`` takes the tie's
        value ``factor * source``, and a new value of a source moves the parameters tied to it.
        """
        if name not in self._items:
            raise ParameterError(f"no parameter {name!r}; names are {list(self._items)}.")
        par = self[name]
        items = {n: par.replace(**changes) if n == name else p for n, p in self._items.items()}
        for n, p in items.items():
            source = items.get(p.tie[0]) if p.tie is not None else None
            if source is not None and source.tie is None and (n != name or "value" not in changes):
                items[n] = _placed(p, p.tie[1] * source.value)
        return Parameters(items.values())

    def merged(self, other) -> Parameters:
        """A copy with the value, bounds, fixed flag and tie of every parameter of ``other``.

        ``other`` must have the same names (the settings of a user's :class:`Parameters`
        applied to a model's own set).
        """
        if not isinstance(other, Parameters):
            raise ParameterError(f"expected fohw.Parameters; got {type(other).__name__}.")
        if set(other) != set(self._items):
            missing = sorted(set(self._items) - set(other))
            extra = sorted(set(other) - set(self._items))
            raise ParameterError(f"the parameters do not match the model's: missing {missing}, "
                                 f"unknown {extra}.")
        return Parameters(other[n] for n in self._items)

    def to_dict(self) -> dict:
        """``{name: Parameter.to_dict()}`` in order."""
        return {n: p.to_dict() for n, p in self._items.items()}

    @classmethod
    def from_dict(cls, d) -> Parameters:
        """Inverse of :meth:`to_dict`."""
        if not isinstance(d, Mapping):
            raise ParameterError(f"`parameters` must be a mapping name -> parameter; got {d!r}.")
        return cls(Parameter.from_dict(n, v) for n, v in d.items())
