"""Method options: each estimator's own settings, declared once, one meaning per name.

:func:`fohw.identify` takes the model (structure, orders, data handling) as its own keywords and
everything that belongs to one method in that method's options: a frozen dataclass per method
(:class:`~fohw.estimators.hybrid.HybridOptions`, :class:`~fohw.estimators.varpro.VarproOptions`,
…). They arrive as keywords, as a mapping ``options={...}`` (as in
:func:`scipy.optimize.minimize`), or as an instance of the class. A name the method does not
have is an error that says which methods have it. Nothing is silently ignored.

Each options class declares its fields with their defaults and, in :attr:`MethodOptions.constraints`,
what each accepts (scikit-learn's ``_parameter_constraints``): an :class:`Integer` or
:class:`Real` interval (whose ends may depend on the record: :class:`Context`), a
:class:`Choice` of strings, a :class:`Boolean`, or :class:`Anything`. One
:meth:`MethodOptions.check` validates every class. The estimator classes
(:class:`fohw.estimators.hybrid.HybridIdentifier`, :class:`fohw.estimators.rls.MultiInnovationRLS`,
:class:`fohw.estimators.migd.MultiInnovationGradient`) take their settings from these dataclasses, defaults
included.

Names shared by several methods mean the same everywhere:

``tol``
    Relative change of the criterion at which an iteration stops: Step 9's
    ``|J_m - J_{m-1}| / |J_{m-1}|`` (the paper's methods); for the least-squares methods
    (``"varpro"``, ``"structured"``) scipy's ``ftol`` (the relative change of the cost), whose
    ``xtol`` and ``gtol`` take the same value.
``alpha_xtol``
    Absolute step in the fractional order at which ``"varpro"``'s scalar (Brent) search stops.
``max_iter``
    Outer iterations: passes over the record of the paper's methods.
``max_nfev``
    Residual evaluations allowed to :func:`scipy.optimize.least_squares`.
``n_grid``
    Points of the coarse scan of the orders (``"varpro"`` and the starts it gives).
``n_starts``
    Local searches from the best candidate starts (``"output_error"``'s default chain,
    :mod:`fohw.estimators.starts`).
``innovation_length``, ``forgetting``, ``alpha0``
    ``P``; the forgetting factor in ``(0, 1]``; the initial order (default: the middle of
    ``alpha_bounds``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from .._validation import check_int, check_scalar
from ..exceptions import ParameterError

__all__ = ["MethodOptions", "Method", "Context", "Integer", "Real", "Choice", "Boolean",
           "Anything", "every_structure", "POSITIVE", "FORGETTING", "INNOVATION_LENGTH", "ALPHA0",
           "N_GRID", "MAX_NFEV"]


@dataclasses.dataclass(frozen=True)
class Context:
    """What an option's valid range may depend on: the record length and the order bounds.

    Attributes
    ----------
    n_samples : int or None
        Length of the record (None for a stream of unknown length: no limit).
    lower, upper : ndarray
        Bounds of each free order.
    """

    n_samples: int
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def make(cls, n_samples, bounds):
        """From a record length and ``(lower, upper)`` (scalars or one entry per free order)."""
        lower, upper = ((), ()) if bounds is None else bounds
        return cls(None if n_samples is None else int(n_samples),
                   np.atleast_1d(np.asarray(lower, dtype=float)),
                   np.atleast_1d(np.asarray(upper, dtype=float)))


def _at(end, context):
    """An interval end: a number, or a function of the :class:`Context`."""
    return end(context) if callable(end) else end


@dataclasses.dataclass(frozen=True)
class Integer:
    """An integer in ``[low, high]`` (either end None for unbounded, or a function of the context)."""

    low: Any = None
    high: Any = None
    none: bool = False            #: None is accepted (a default filled in later)

    def validate(self, value, name, context):
        """``value`` as an int, or :class:`ParameterError`."""
        if value is None and self.none:
            return None
        return check_int(value, name, minimum=_at(self.low, context),
                         maximum=_at(self.high, context))


@dataclasses.dataclass(frozen=True)
class Real:
    """A finite real number in an interval; ``closed`` says which ends belong to it."""

    low: Any = None
    high: Any = None
    closed: str = "both"          #: "both", "left", "right" or "neither"
    none: bool = False

    def validate(self, value, name, context):
        """``value`` as a float, or :class:`ParameterError`."""
        if value is None and self.none:
            return None
        return check_scalar(value, name, lower=_at(self.low, context),
                            upper=_at(self.high, context),
                            lower_inclusive=self.closed in ("both", "left"),
                            upper_inclusive=self.closed in ("both", "right"))


@dataclasses.dataclass(frozen=True)
class Choice:
    """One of a tuple of strings."""

    options: tuple

    def validate(self, value, name, context):
        """``value`` itself, or :class:`ParameterError`."""
        if value not in self.options:
            raise ParameterError(f"`{name}` must be one of {self.options}; got {value!r}.")
        return value


@dataclasses.dataclass(frozen=True)
class Boolean:
    """True or False (a NumPy bool too)."""

    def validate(self, value, name, context):
        """``value`` as a bool, or :class:`ParameterError`."""
        if not isinstance(value, (bool, np.bool_)):
            raise ParameterError(f"`{name}` must be True or False; got {value!r}.")
        return bool(value)


@dataclasses.dataclass(frozen=True)
class Anything:
    """Any value (the method checks it where it is used)."""

    def validate(self, value, name, context):
        """``value`` itself."""
        return value


#: Constraints shared by several methods' options (one meaning per name).
POSITIVE = Real(0.0, None, closed="right")
FORGETTING = Real(0.0, 1.0, closed="right")
INNOVATION_LENGTH = Integer(1, lambda c: c.n_samples)
ALPHA0 = Real(lambda c: c.lower[0], lambda c: c.upper[0], closed="neither", none=True)
N_GRID = Integer(3, 100_000)
MAX_NFEV = Integer(1, none=True)


@dataclasses.dataclass(frozen=True, kw_only=True)
class MethodOptions:
    """Base class of every method's options (a frozen dataclass of keyword-only fields)."""

    #: ``{field name: constraint}`` for every field (:class:`Integer`, :class:`Real`, …).
    constraints: ClassVar[dict] = {}

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The option names of this method, in definition order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def defaults(cls) -> dict:
        """``{name: default}`` of every option."""
        return {f.name: f.default for f in dataclasses.fields(cls)}

    @classmethod
    def _table(cls):
        """The constraints; a field without one would go unchecked, so that is refused."""
        missing = [n for n in cls.names() if n not in cls.constraints]
        if missing:
            raise TypeError(f"{cls.__name__} declares no constraint for {missing}.")
        return cls.constraints

    @classmethod
    def build(cls, method, given, *, others=None):
        """Options of ``method`` from a mapping (or an instance), checking every name.

        Parameters
        ----------
        method : str
            The method's name (for messages).
        given : mapping, MethodOptions or None
            What the caller passed.
        others : mapping of str to type, optional
            Every method's options class, to say which methods have an unknown name.
        """
        if given is None:
            return cls()
        if isinstance(given, cls):
            return given
        if isinstance(given, MethodOptions):
            raise ParameterError(f"`options` is a {type(given).__name__}, but method {method!r} "
                                 f"takes {cls.__name__}.")
        if not isinstance(given, Mapping):
            raise ParameterError(f"`options` must be a mapping of option names to values or a "
                                 f"{cls.__name__}; got {type(given).__name__}.")
        valid = cls.names()
        for name in given:
            if name in valid:
                continue
            having = sorted(m for m, c in (others or {}).items() if name in c.names())
            where = (f" `{name}` is an option of {', '.join(repr(m) for m in having)}."
                     if having else "")
            raise ParameterError(f"method {method!r} has no option `{name}`; its options are "
                                 f"{', '.join(valid) or '(none)'}.{where}")
        return cls(**dict(given))

    def check(self, *, n_samples, bounds):
        """A validated copy, the defaults that depend on the record filled in.

        Every field is checked against its entry of :attr:`constraints`, then
        :meth:`complete` fills what depends on other fields or on the record.

        Parameters
        ----------
        n_samples : int or None
            Length of the record (None: a stream, no limit from it).
        bounds : (lower, upper) or None
            Bounds of the free orders: scalars, or arrays with one entry per free order (None
            when the options do not depend on them).

        Returns
        -------
        MethodOptions
            Of the same class.
        """
        context = Context.make(n_samples, bounds)
        table = self._table()
        checked = {name: table[name].validate(getattr(self, name), name, context)
                   for name in self.names()}
        return dataclasses.replace(self, **checked).complete(context)

    def complete(self, context):
        """Fill the defaults that depend on other options or the record; check combinations.

        Called by :meth:`check` on the validated copy; returns it unchanged by default.
        """
        return self

    def as_dict(self) -> dict:
        """The options as a plain dict (for results and JSON)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def replace(self, **changes):
        """A copy with some options changed (:func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)


def every_structure(structure):
    """A method that fits every model structure: no reason to refuse one."""
    return None


@dataclasses.dataclass(frozen=True)
class Method:
    """One estimation method as :func:`fohw.identify` dispatches it, declared in its module.

    Attributes
    ----------
    name : str
        The ``method=`` string.
    options : type
        Its :class:`MethodOptions` subclass.
    run : callable
        ``run(builder, options, bounds, *, operating_point) -> IdentificationResult`` with
        checked options and ``bounds = (lower, upper)`` over the free orders.
    supports : callable
        ``supports(structure) -> None or str``: None if the method fits that
        :class:`fohw.Structure`, else why not (a sentence completing "method 'name' …").
    parallel : bool
        ``run`` takes ``executor=`` (independent starts it can run in parallel).
    output_map : bool
        ``run`` fits a series output map ``y = h(z)`` (a simulation-error method); the others
        are refused one by :func:`~fohw.estimators.problem.fit_method`.
    kinds : tuple of str
        The model kinds it fits (``fohw.fit(model, data, method=name)``): the lagged kind's
        identification form, :class:`fohw.ThetaHW`, for every method of the table; every
        other kind is fitted by the engine (``method=None``).
    """

    name: str
    options: type
    run: Callable
    supports: Callable = every_structure
    parallel: bool = False
    output_map: bool = False
    kinds: tuple = ("ThetaHW",)
