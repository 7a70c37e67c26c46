"""Method options: each estimator's own settings, one meaning per name.

:func:`fohw.identify` takes the model (structure, orders, data handling) as its own keywords and
everything that belongs to one method in that method's options: a frozen dataclass per method
(:class:`~fohw.estimators.hybrid.HybridOptions`, :class:`~fohw.estimators.varpro.VarproOptions`,
…). They arrive as keywords, as a mapping ``options={...}`` (as in
:func:`scipy.optimize.minimize`), or as an instance of the class. A name the method does not
have is an error that says which methods have it; a name that was renamed is an error that gives
the new spelling. Nothing is silently ignored.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import ClassVar

from ..exceptions import ParameterError

__all__ = ["MethodOptions"]


@dataclasses.dataclass(frozen=True, kw_only=True)
class MethodOptions:
    """Base class of every method's options (a frozen dataclass of keyword-only fields)."""

    #: ``{old name: new name}`` of options renamed since fohw 0.1, for the error message.
    renamed: ClassVar[dict] = {}
    #: ``{name: why}`` of names that used to be accepted but mean nothing for this method.
    removed: ClassVar[dict] = {}

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The option names of this method, in definition order."""
        return tuple(f.name for f in dataclasses.fields(cls))

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
            if name in cls.renamed:
                raise ParameterError(f"method {method!r}: the option `{name}` is now called "
                                     f"`{cls.renamed[name]}`.")
            if name in cls.removed:
                raise ParameterError(f"method {method!r} has no option `{name}`: "
                                     f"{cls.removed[name]}")
            having = sorted(m for m, c in (others or {}).items() if name in c.names())
            where = (f" `{name}` is an option of {', '.join(repr(m) for m in having)}."
                     if having else "")
            raise ParameterError(f"method {method!r} has no option `{name}`; its options are "
                                 f"{', '.join(valid) or '(none)'}.{where}")
        return cls(**dict(given))

    def as_dict(self) -> dict:
        """The options as a plain dict (for results and JSON)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def replace(self, **changes):
        """A copy with some options changed (:func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)
