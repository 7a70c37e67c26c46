"""Basis functions of the static nonlinearities (paper Section 2.3, Eqs. 12–13).

The input nonlinearity is ``f(u) = sum_j p_j f_j(u)`` and the output nonlinearity
``g(y) = sum_j q_j g_j(y)``, each a combination of known basis functions. A :class:`Basis`
holds those functions with their names. Wherever fohw expects a basis, it also accepts an
``int`` (a polynomial basis of that degree), a sequence of callables, or a mapping from
names to callables.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Union

import numpy as np

from .._validation import check_array, check_int
from ..exceptions import DimensionError, ParameterError

__all__ = ["Basis", "polynomial_basis", "as_basis", "InputBases", "as_input_bases"]



class _Power:
    """``x -> x**n`` as a picklable, printable callable."""

    def __init__(self, n: int):
        self.n = n

    def __call__(self, x):
        x = np.asarray(x, dtype=np.float64)
        return x.copy() if self.n == 1 else x**self.n

    def __repr__(self):
        return f"_Power({self.n})"

    def __eq__(self, other):
        return isinstance(other, _Power) and other.n == self.n

    def __hash__(self):
        return hash(("_Power", self.n))


@dataclass(frozen=True, eq=False)
class Basis:
    """An ordered set of named scalar basis functions.

    Parameters
    ----------
    functions : sequence of callable
        Each maps a 1-D float array to an array of the same shape, elementwise.
    names : sequence of str
        One distinct name per function (used in tables and saved results).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> basis = fohw.Basis((np.tanh, np.sin), names=("tanh", "sin"))
    >>> len(basis), basis.names
    (2, ('tanh', 'sin'))
    >>> basis.evaluate(np.array([0.0, 1.0])).shape
    (2, 2)
    """

    functions: tuple
    names: tuple

    def __post_init__(self):
        functions = tuple(self.functions)
        names = tuple(str(n) for n in self.names)
        if len(functions) == 0:
            raise ParameterError("a basis needs at least one function; got none.")
        for i, f in enumerate(functions):
            if not callable(f):
                raise ParameterError(f"basis function {i} must be callable; got {f!r}.")
        if len(names) != len(functions):
            raise DimensionError(f"`names` must have one entry per function; got {len(names)} "
                                 f"names for {len(functions)} functions.")
        if len(set(names)) != len(names):
            raise ParameterError(f"basis function names must be distinct; got {names}.")
        object.__setattr__(self, "functions", functions)
        object.__setattr__(self, "names", names)

    def __len__(self):
        return len(self.functions)

    def __eq__(self, other):
        return (isinstance(other, Basis) and self.names == other.names
                and all(f is g or f == g for f, g in zip(self.functions, other.functions)))

    def __hash__(self):
        return hash(self.names)

    def __repr__(self):
        return f"Basis({', '.join(self.names)})"

    @property
    def is_polynomial(self) -> bool:
        """True if this is ``polynomial_basis(len(self))``."""
        return self == polynomial_basis(len(self))

    def to_dict(self) -> dict:
        """A JSON-ready description: the degree of a polynomial basis, else the function names.

        Code is never serialised: a custom basis is described by its names only, and
        :meth:`from_dict` needs the functions passed again.

        Examples
        --------
        >>> import fohw
        >>> fohw.polynomial_basis(2).to_dict()
        {'kind': 'polynomial', 'degree': 2}
        """
        if self.is_polynomial:
            return {"kind": "polynomial", "degree": len(self)}
        return {"kind": "custom", "names": list(self.names)}

    @classmethod
    def from_dict(cls, d, basis=None, *, name: str = "basis") -> Basis:
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            ``{"kind": "polynomial", "degree": n}`` or ``{"kind": "custom", "names": [...]}``.
        basis : Basis, int or callables, optional
            The basis the caller expects: required for a custom basis (its functions are
            code) and checked against ``d`` by its names (a polynomial one by its degree).
        name : str
            The argument's name in error messages (``"f_basis"``, ``"g_basis"``).

        Raises
        ------
        ParameterError
            ``d`` is not such a description, a custom basis was not passed, or ``basis`` does
            not match ``d``.
        """
        kind = d.get("kind") if isinstance(d, Mapping) else None
        if kind == "polynomial":
            stored = polynomial_basis(check_int(d.get("degree"), f"{name}['degree']", minimum=1,
                                                maximum=MAX_POLYNOMIAL_DEGREE))
            if basis is not None and as_basis(basis, name) != stored:
                raise ParameterError(f"`{name}` does not match the polynomial basis of degree "
                                     f"{len(stored)} stored.")
            return stored
        if kind != "custom":
            raise ParameterError(f"`{name}` must be described as {{'kind': 'polynomial', "
                                 f"'degree': n}} or {{'kind': 'custom', 'names': [...]}}; got {d!r}.")
        names = d.get("names")
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise ParameterError(f"`{name}['names']` must be a non-empty list of strings; got "
                                 f"{names!r}.")
        if basis is None:
            raise ParameterError(f"`{name}` is a custom basis ({names}); its functions are code, "
                                 "which fohw never stores: pass the same basis again.")
        basis = as_basis(basis, name)
        if list(basis.names) != names:
            raise ParameterError(f"`{name}` has functions {list(basis.names)}, but was saved with "
                                 f"{names}.")
        return basis

    def evaluate(self, x, name: str = "x") -> np.ndarray:
        """Evaluate every function on ``x``.

        Parameters
        ----------
        x : array_like, 1-D
            Signal.
        name : str, optional
            Name of the signal, used in error messages.

        Returns
        -------
        values : ndarray, shape (len(self), len(x))
            Row ``j`` is ``functions[j](x)``.

        Raises
        ------
        DimensionError
            A function returned an array of another shape.
        ParameterError
            A function returned non-finite values.
        """
        x = np.asarray(x, dtype=np.float64)
        out = np.empty((len(self.functions),) + x.shape)
        for j, (f, fname) in enumerate(zip(self.functions, self.names)):
            with np.errstate(all="ignore"):
                val = np.asarray(f(x), dtype=np.float64)
            if val.shape != x.shape:
                raise DimensionError(f"basis function {fname!r} returned shape {val.shape} for "
                                     f"`{name}` of shape {x.shape}; it must act elementwise.")
            if not np.all(np.isfinite(val)):
                k = int(np.flatnonzero(~np.isfinite(val.ravel()))[0])
                raise ParameterError(
                    f"basis function {fname!r} returned {float(val.ravel()[k])!r} at index {k} "
                    f"of `{name}` (where `{name}` = {float(x.ravel()[k])!r}): it returned a "
                    "non-finite value. If the data are merely large, rescale them: fohw's "
                    "estimates rescale with the data.")
            out[j] = val
        return out

    def combine(self, coefficients, x, name: str = "x") -> np.ndarray:
        """Return ``sum_j coefficients[j] * functions[j](x)`` (``fbar`` or ``gbar``)."""
        coefficients = check_array(coefficients, "coefficients")
        if coefficients.shape[0] != len(self):
            raise DimensionError(f"`coefficients` must have {len(self)} entries; "
                                 f"got {coefficients.shape[0]}.")
        return coefficients @ self.evaluate(x, name)


#: The highest degree :func:`polynomial_basis` builds.
MAX_POLYNOMIAL_DEGREE = 100


#: A basis of a static nonlinearity as the public API accepts it: a :class:`Basis`, an int (a
#: polynomial degree) or a sequence of callables.
BasisLike = Union[Basis, int, Sequence[Callable[[np.ndarray], np.ndarray]]]


def polynomial_basis(degree: int) -> Basis:
    """Monomials ``x, x**2, ..., x**degree``.

    Parameters
    ----------
    degree : int
        Highest power, ``1 <= degree <= MAX_POLYNOMIAL_DEGREE`` (100: monomials beyond it are
        numerically useless in float64, and a huge degree read from a file would hang).

    Returns
    -------
    Basis
        Named ``"x"``, ``"x^2"``, ….

    Examples
    --------
    >>> import fohw
    >>> fohw.polynomial_basis(3)
    Basis(x, x^2, x^3)
    >>> fohw.polynomial_basis(2).evaluate([2.0, -1.0])
    array([[ 2., -1.],
           [ 4.,  1.]])
    """
    degree = check_int(degree, "degree", minimum=1, maximum=MAX_POLYNOMIAL_DEGREE)
    return Basis(tuple(_Power(n) for n in range(1, degree + 1)),
                 names=tuple("x" if n == 1 else f"x^{n}" for n in range(1, degree + 1)))


def as_basis(spec: BasisLike, name: str = "basis") -> Basis:
    """Turn what a user passed as a basis into a :class:`Basis`.

    Parameters
    ----------
    spec : Basis, int, sequence of callable, or mapping of str to callable
        An ``int`` is a polynomial degree; callables are named by their ``__name__``.
    name : str
        Argument name for error messages (``"f_basis"``, ``"g_basis"``).

    Returns
    -------
    Basis

    Examples
    --------
    >>> import numpy as np, fohw
    >>> fohw.model.basis.as_basis(2)
    Basis(x, x^2)
    >>> fohw.model.basis.as_basis({"u": lambda x: x, "tanh": np.tanh})
    Basis(u, tanh)
    """
    if isinstance(spec, Basis):
        return spec
    if isinstance(spec, (bool, np.bool_)):
        raise ParameterError(f"`{name}` must be a Basis, an int degree, or callables; got {spec!r}.")
    if isinstance(spec, (int, np.integer)):
        if spec < 1:
            raise ParameterError(f"`{name}` as a polynomial degree must be at least 1; got {spec}.")
        return polynomial_basis(int(spec))
    if isinstance(spec, Mapping):
        items = list(spec.items())
        _check_callables([f for _, f in items], name)
        return Basis(tuple(f for _, f in items), names=tuple(str(k) for k, _ in items))
    if callable(spec):
        spec = [spec]
    if isinstance(spec, Sequence) and not isinstance(spec, str):
        funcs = list(spec)
        _check_callables(funcs, name)
        names = [getattr(f, "__name__", f"{name}_{i + 1}") for i, f in enumerate(funcs)]
        if len(set(names)) != len(names) or "<lambda>" in names:
            names = [f"{name}_{i + 1}" for i in range(len(funcs))]
        return Basis(tuple(funcs), names=tuple(names))
    raise ParameterError(f"`{name}` must be a Basis, an int degree, or callables; got {spec!r}.")


def _check_callables(funcs: Sequence[Callable], name: str) -> None:
    if len(funcs) == 0:
        raise ParameterError(f"`{name}` needs at least one basis function; got none.")
    for i, f in enumerate(funcs):
        if not callable(f):
            raise ParameterError(f"`{name}` entry {i} must be callable; got {f!r}.")


class InputBases:
    """One :class:`Basis` per input of a model with several inputs.

    It acts as the input basis of the whole model: :meth:`evaluate` of a ``(N, m)`` input
    stacks the basis signals of every input, ``f_{1,1}(u_1), …, f_{1,n_1}(u_1), f_{2,1}(u_2),
    …``, so that ``fbar_i = sum_j p_ij f_ij`` of input ``i`` enters through its own block of
    theta.

    Parameters
    ----------
    parts : sequence of Basis, int or callables
        The basis of each input.
    inputs : sequence of str
        The inputs' names (as in :attr:`fohw.Orders.inputs`).

    Examples
    --------
    >>> import numpy as np, fohw
    >>> b = fohw.model.basis.InputBases([2, 1], ("u1", "u2"))
    >>> len(b), b.names
    (3, ('u1.x', 'u1.x^2', 'u2.x'))
    >>> b.evaluate(np.array([[2.0, 3.0], [1.0, -1.0]]))
    array([[ 2.,  1.],
           [ 4.,  1.],
           [ 3., -1.]])
    """

    is_polynomial = False

    def __init__(self, parts, inputs):
        inputs = tuple(inputs)
        if isinstance(parts, (str, bytes)) or not isinstance(parts, Sequence):
            raise ParameterError(f"`f_basis` must give one basis per input; got {parts!r}.")
        if len(parts) != len(inputs):
            raise DimensionError(f"`f_basis` gives {len(parts)} bases (one per input), but there "
                                 f"are {len(inputs)} inputs (columns of `u`).")
        self.parts = tuple(as_basis(p, f"f_basis[{i}]") for i, p in enumerate(parts))
        self.inputs = inputs

    def __len__(self):
        return sum(len(p) for p in self.parts)

    @property
    def names(self) -> tuple[str, ...]:
        """``<input>.<function>`` for every stacked basis signal."""
        return tuple(f"{i}.{n}" for i, p in zip(self.inputs, self.parts) for n in p.names)

    def evaluate(self, x, name: str = "u") -> np.ndarray:
        """The stacked basis signals of a ``(N, m)`` input (or of one sample, shape ``(m,)``)."""
        x = np.asarray(x, dtype=np.float64)
        if x.ndim == 0 or x.shape[-1] != len(self.parts):
            raise DimensionError(f"`{name}` must have {len(self.parts)} columns (one per input); "
                                 f"got shape {x.shape}.")
        return np.concatenate([p.evaluate(x[..., i], f"{name}[:, {i}]")
                               for i, p in enumerate(self.parts)])

    def to_dict(self) -> dict:
        """``{"kind": "inputs", "parts": [<each basis' dict>]}`` (names: :class:`fohw.Orders`)."""
        return {"kind": "inputs", "parts": [p.to_dict() for p in self.parts]}

    @classmethod
    def from_dict(cls, d, inputs, bases=None, *, name="f_basis") -> InputBases:
        """Inverse of :meth:`to_dict`; custom parts need ``bases`` (one per input) again."""
        parts = d.get("parts") if isinstance(d, Mapping) else None
        if parts is None or d.get("kind") != "inputs" or not isinstance(parts, list) \
                or len(parts) != len(inputs):
            raise ParameterError(f"`{name}` must be described as {{'kind': 'inputs', 'parts': "
                                 f"[...]}} with one basis per input ({len(inputs)}); got {d!r}.")
        given = bases.parts if isinstance(bases, InputBases) else bases
        if given is not None and (not isinstance(given, Sequence) or len(given) != len(parts)):
            raise ParameterError(f"`{name}` must give one basis per input ({len(parts)}); got "
                                 f"{bases!r}.")
        return cls([Basis.from_dict(p, None if given is None else given[i],
                                    name=f"{name}[{i}]") for i, p in enumerate(parts)], inputs)

    def __eq__(self, other):
        return (isinstance(other, InputBases) and self.parts == other.parts
                and self.inputs == other.inputs)

    def __hash__(self):
        return hash((self.parts, self.inputs))

    def __repr__(self):
        return "InputBases(" + ", ".join(f"{i}: {p!r}" for i, p in zip(self.inputs, self.parts)) \
            + ")"


def as_input_bases(spec, inputs, name="f_basis"):
    """One basis per input: an :class:`InputBases`, a list (one per input), or one for all.

    One basis (an int, a :class:`Basis`) applies to every input. With several inputs a list or
    tuple is always one entry per input (a single basis of several callables is written
    ``fohw.Basis(...)`` or as a dict).
    """
    if isinstance(spec, InputBases):
        if spec.inputs != tuple(inputs):
            return InputBases(spec.parts, inputs)
        return spec
    if isinstance(spec, (list, tuple)):
        return InputBases(spec, inputs)
    one = as_basis(spec, name)
    return InputBases([one] * len(inputs), inputs)
