"""Which term of the linear block has which fractional order (paper Eqs. 7, 11, 14).

The paper writes the linear block with an order per term, ``A(z) = sum_i a_i z^{-alpha_i}``
and ``B(z) = sum_i b_i z^{-gamma_i}`` (its "nonhomogeneous" case, Eq. 7), and then restricts
itself to one order factor, ``z^{-i + alpha} x = Delta^alpha x(k - i)`` (Eqs. 8–9, 16). fohw
implements the general class: each term of the output branch is ``a_t (Delta^{nu_t} gbar(y))
(k - i_t)`` and each term of the input branch ``b_t (Delta^{nu_t} fbar(u))(k - i_t)``, for a lag
``i_t`` and an order ``nu_t``. Output lags are ``>= 1`` (the recursion needs them); input lags
are ``>= 0``: the input terms of the presets sit at lags ``nk … nk + nb - 1`` for an input
delay ``nk >= 0`` (default 1, the paper's lags ``1 … nb``; ``nk = 0`` is direct feedthrough,
a term ``b0`` acting on ``fbar(u)(k)``), and the input coefficients are named by their lag
(``b0, b1`` for ``nk = 0, nb = 2``; ``b3, b4`` for ``nk = 3``). An order is a fixed number in
``[0, 2]`` (0 included: the memoryless term ``x(k - i)`` that carries a static gain) or the
*name* of a free order to be estimated; terms that name the same free order share it (tied orders).

Presets (``orders=`` in :func:`fohw.identify` and :class:`fohw.HammersteinWiener`):

``"commensurate"`` (default)
    The paper's model, Eq. (16): every term ``Delta^alpha x(k - i)``, one free order ``alpha``.
``"per_lag"``
    The paper's nonhomogeneous model, Eq. (14): a free order for every term, ``alpha_a1 …
    alpha_a{na}`` (output branch) and ``alpha_b1 … alpha_b{nb}`` (input branch; named by the
    lag, ``alpha_b{nk} …`` for an input delay ``nk``).
``"mixed"``
    Order 0 *and* a free order ``alpha`` at every lag of both branches: a static gain beside
    fractional dynamics. The commensurate model has no static gain for ``alpha > 0``
    (``Delta^alpha`` of a constant decays like ``k**-alpha``), so on records with a static
    response its fits drive alpha to 0; the mixed model keeps both.
a number
    Every term fixed at that order (``orders=0``: the integer-order model).

Anything else is written per lag: ``Orders.from_lags(a=[(0, "alpha"), (0, "alpha")],
b=[(0, "alpha")])``, or the same as a dict, ``orders={"a": [...], "b": [...]}``: one entry per
lag, each an order or a tuple of orders (one term per order); the input entries start at lag
``nk`` (``Orders.from_lags(a, b, nk=0)``).
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Union

import numpy as np

from .._validation import check_int, check_scalar
from ..exceptions import DimensionError, ParameterError

__all__ = ["Orders", "Term", "PRESETS", "ORDER_RANGE", "OrdersLike", "check_nk"]

#: The orders a term may have (fixed or free): ``[0, 2]``. The one order range of fohw: a
#: transfer function's numerator order, which may be negative, takes it mirrored, ``(-2, 2)``
#: (:data:`fohw.model.transfer.NUM_ORDER_RANGE`).
ORDER_RANGE = (0.0, 2.0)
#: The named presets.
PRESETS = ("commensurate", "per_lag", "mixed")


@dataclass(frozen=True)
class Term:
    """One term of a branch: a lag and an order (a fixed number or a free order's name).

    The lag is ``>= 1`` in the output branch and ``>= 0`` in the input branch (``0``: direct
    feedthrough). ``input`` is the index of the input an input term acts on (0 for the first
    or only input; several inputs: :class:`Orders` notes).
    """

    lag: int
    order: float | str
    input: int = 0

    @property
    def free(self) -> bool:
        """Whether the order is a free parameter."""
        return isinstance(self.order, str)

    def label(self) -> str:
        """The order as text: its name, or the fixed number (``0``, ``0.5``)."""
        return self.order if self.free else f"{self.order:g}"


def check_nk(nk, name="nk"):
    """The input delay ``nk`` as an int ``>= 0`` (no bool, no float, no string)."""
    if isinstance(nk, (bool, np.bool_)) or not isinstance(nk, (numbers.Integral, np.integer)):
        raise ParameterError(f"`{name}` (the input delay in samples) must be an integer >= 0 "
                             f"(0: direct feedthrough); got {nk!r}.")
    if nk < 0:
        raise ParameterError(f"`{name}` (the input delay in samples) must be an integer >= 0 "
                             f"(0: direct feedthrough); got {int(nk)}.")
    return int(nk)


def _order(value, where):
    if isinstance(value, str):
        name = value.strip()
        if not name or _is_number(name):
            raise ParameterError(f"{where}: a free order is named by a non-empty, non-numeric "
                                 f"string; got {value!r}.")
        return name
    if isinstance(value, (bool,)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{where}: an order is a number in [0, 2] or the name of a free "
                             f"order; got {value!r}.")
    value = float(value)
    if not ORDER_RANGE[0] <= value <= ORDER_RANGE[1]:
        raise ParameterError(f"{where} must be in [0, 2]; got {value!r}.")
    return value


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


class Orders:
    """The terms of the linear block and their orders (paper Eqs. 7, 14).

    Parameters
    ----------
    a, b : sequence of Term or (lag, order)
        Terms of the output branch (coefficients ``a``, acting on ``gbar(y)``) and of the input
        branch (``b``, on ``fbar(u)``), in the order of the coefficients. Output lags are
        ``>= 1``, input lags ``>= 0`` (lag 0: direct feedthrough); an order is a number in
        ``[0, 2]`` or a free order's name. A ``(lag, order)`` pair may
        appear once per branch (once per input). With several inputs an input term is
        ``(lag, order, input)`` (the input's index, from 0), the terms of input 0 first, then
        those of input 1, and so on: input ``i`` has its own lags, delay and orders, and
        ``theta = [q ⊗ a, p_1 ⊗ b_1, …, p_m ⊗ b_m]``.
    inputs : sequence of str, optional
        Names of the inputs when there are several (default ``u1, u2, …``; a DataFrame's
        column names with :func:`fohw.identify`). Their coefficients are named
        ``<input>.b<lag>`` (``u2.b1``, ``u2.p2b1``) and per-lag free orders
        ``alpha_<input>.b<lag>``. One input: no names, today's ``b1``.

    Attributes
    ----------
    output, input : tuple of Term
    free : tuple of str
        The free orders, in order of first appearance (output branch first): the order of
        ``IdentificationResult.orders`` and of every vector of orders.

    Examples
    --------
    >>> import fohw
    >>> fohw.Orders.preset("mixed", na=1, nb=2)
    Orders(a=[(1, 0), (1, alpha)], b=[(1, 0), (1, alpha), (2, 0), (2, alpha)])
    >>> o = fohw.Orders.from_lags(a=[0.5], b=[(0, "nu"), "nu"])
    >>> o.free, o.a_names, o.b_names
    (('nu',), ('a1',), ('b1_0', 'b1_nu', 'b2'))
    >>> d = fohw.Orders.preset("commensurate", na=1, nb=2, nk=0)
    >>> d.b_names, d.nk, d.nb
    (('b0', 'b1'), 0, 2)
    >>> two = fohw.Orders.preset("commensurate", na=1, nb=[1, 2], nk=[0, 1],
    ...                          inputs=("heat", "flow"))
    >>> two.b_names, two.nk, two.nb
    (('heat.b0', 'flow.b1', 'flow.b2'), (0, 1), (1, 2))
    """

    def __init__(self, a, b, *, inputs=None):
        self.output = self._terms(a, "a")
        self.input = self._terms(b, "b")
        used = [t.input for t in self.input]
        m = max(used) + 1
        if used != sorted(used) or set(used) != set(range(m)):
            raise ParameterError(f"`orders`: the input terms must be grouped by input, 0, 1, …, "
                                 f"each input with at least one term; got inputs {used}.")
        self.inputs = self._input_names(inputs, m)
        free = []
        for t in self.output + self.input:
            if t.free and t.order not in free:
                free.append(t.order)
        self.free = tuple(free)

    @staticmethod
    def _input_names(inputs, m):
        if inputs is None:
            return tuple(f"u{i}" for i in range(1, m + 1)) if m > 1 else ()
        if isinstance(inputs, (str, bytes)) or not isinstance(inputs, Sequence):
            raise ParameterError(f"`inputs` must be a sequence of names, one per input; got "
                                 f"{inputs!r}.")
        names = tuple(inputs)
        if m == 1 and len(names) <= 1:
            return ()
        if len(names) != m:
            raise DimensionError(f"`inputs` names {len(names)} inputs, but the input terms act "
                                 f"on {m}.")
        for name in names:
            if not isinstance(name, str) or not name.strip() or "." in name:
                raise ParameterError(f"`inputs`: each input's name is a non-empty string "
                                     f"without '.'; got {name!r}.")
        if len(set(names)) != len(names):
            raise ParameterError(f"`inputs`: the names must be distinct; got {list(names)}.")
        return names

    @property
    def n_inputs(self) -> int:
        """Number of inputs (1: the paper's single-input model)."""
        return self.input[-1].input + 1

    def input_terms(self, i):
        """The input terms of input ``i`` (in coefficient order)."""
        return tuple(t for t in self.input if t.input == i)

    @staticmethod
    def _terms(spec, branch):
        if isinstance(spec, (str, bytes)) or not isinstance(spec, Sequence) or not spec:
            raise ParameterError(f"`orders`: branch {branch!r} needs a non-empty sequence of "
                                 f"(lag, order) terms; got {spec!r}.")
        terms, seen = [], set()
        for n, item in enumerate(spec):
            index = 0
            if isinstance(item, Term):
                lag, order, index = item.lag, item.order, item.input
            else:
                try:
                    if branch == "b" and isinstance(item, Sequence) and len(item) == 3:
                        lag, order, index = item
                    else:
                        lag, order = item
                except (TypeError, ValueError):
                    raise ParameterError(f"`orders`: term {n} of branch {branch!r} must be a "
                                         f"(lag, order) pair; got {item!r}.") from None
            if isinstance(index, bool) or not isinstance(index, numbers.Integral) or index < 0:
                raise ParameterError(f"`orders`: the input of term {n} of branch {branch!r} "
                                     f"must be an integer >= 0; got {index!r}.")
            least = 1 if branch == "a" else 0
            if isinstance(lag, bool) or not isinstance(lag, numbers.Integral) or lag < least:
                raise ParameterError(f"`orders`: the lag of term {n} of branch {branch!r} must "
                                     f"be an integer >= {least}; got {lag!r}.")
            lag = int(lag)
            order = _order(order, f"`orders`: the order of term {n} of branch {branch!r}")
            if (lag, order, index) in seen:
                where = f" of input {index}" if index else ""
                raise ParameterError(f"`orders`: branch {branch!r} has the term (lag {lag}, "
                                     f"order {order!r}){where} twice.")
            seen.add((lag, order, index))
            terms.append(Term(lag, order, int(index)))
        return tuple(terms)

    # ---- construction -------------------------------------------------------------------------
    @classmethod
    def preset(cls, name, *, na, nb, nk=1, inputs=None):
        """One of :data:`PRESETS` for ``na`` output and ``nb`` input lags, input delay ``nk``.

        The input terms sit at lags ``nk … nk + nb - 1`` (default ``nk = 1``: ``1 … nb``).
        With several inputs (``inputs``: their names), ``nb`` and ``nk`` are one per input or
        one for all; ``"commensurate"`` and ``"mixed"`` share the one ``alpha`` across inputs.
        """
        na = check_int(na, "na", minimum=1)
        lags = cls._input_lags(nb, nk, inputs)
        names = cls._input_names(inputs, len(lags))
        if name == "commensurate":
            return cls([(i, "alpha") for i in range(1, na + 1)],
                       [(i, "alpha", m) for m, r in enumerate(lags) for i in r], inputs=names)
        if name == "per_lag":
            def b_name(m, i):
                return f"alpha_{names[m]}.b{i}" if names else f"alpha_b{i}"
            return cls([(i, f"alpha_a{i}") for i in range(1, na + 1)],
                       [(i, b_name(m, i), m) for m, r in enumerate(lags) for i in r],
                       inputs=names)
        if name == "mixed":
            return cls([(i, o) for i in range(1, na + 1) for o in (0.0, "alpha")],
                       [(i, o, m) for m, r in enumerate(lags) for i in r for o in (0.0, "alpha")],
                       inputs=names)
        raise ParameterError(f"`orders` must be one of {PRESETS}, a number, an Orders or a "
                             f"dict of per-lag orders; got {name!r}.")

    @staticmethod
    def _input_lags(nb, nk, inputs):
        """``range(nk_i, nk_i + nb_i)`` per input; ``nb``, ``nk`` one per input or one for all."""
        m = 1 if inputs is None else max(len(inputs), 1)
        out = []
        for value, name, check in ((nb, "nb", lambda v, n: check_int(v, n, minimum=1)),
                                   (nk, "nk", check_nk)):
            if isinstance(value, Sequence) and not isinstance(value, (str, bytes)) \
                    or isinstance(value, np.ndarray):
                values = list(value)
                if len(values) != m:
                    raise DimensionError(f"`{name}` gives {len(values)} value(s), one per input, "
                                         f"but there {'is' if m == 1 else 'are'} {m} input(s) "
                                         f"(columns of `u`).")
                out.append([check(v, f"{name}[{i}]") for i, v in enumerate(values)])
            else:
                out.append([check(value, name)] * m)
        return [range(k, k + b) for b, k in zip(*out)]

    @classmethod
    def fixed(cls, value, *, na, nb, nk=1, inputs=None):
        """Every term ``Delta^value x(k - i)``, no free order (``value = 0``: integer order)."""
        na = check_int(na, "na", minimum=1)
        lags = cls._input_lags(nb, nk, inputs)
        return cls([(i, value) for i in range(1, na + 1)],
                   [(i, value, m) for m, r in enumerate(lags) for i in r],
                   inputs=cls._input_names(inputs, len(lags)))

    @classmethod
    def from_lags(cls, a, b, *, nk=1, inputs=None):
        """Terms written per lag: entry ``i - 1`` of ``a`` holds the order(s) of lag ``i``.

        Each entry is an order (one term) or a tuple/list of orders (a term per order). The
        entries of ``b`` start at the input delay ``nk``: entry ``j`` holds lag ``nk + j``.
        With several inputs (``inputs``: their names), ``b`` holds one such list per input
        and ``nk`` is one per input or one for all.
        """
        if inputs is not None and len(inputs) > 1:
            m = len(inputs)
            if isinstance(b, (str, bytes)) or not isinstance(b, Sequence) or len(b) != m:
                raise ParameterError(f"`orders`: with {m} inputs, 'b' needs one list of per-lag "
                                     f"orders per input; got {b!r}.")
            delays = [r.start for r in cls._input_lags(1, nk, inputs)]
            single = [cls.from_lags(a, bi, nk=k) for bi, k in zip(b, delays)]
            return cls(single[0].output, [(t.lag, t.order, i) for i, o in enumerate(single)
                                          for t in o.input], inputs=inputs)
        nk = check_nk(nk[0] if isinstance(nk, Sequence) and len(nk) == 1 else nk)

        def expand(spec, branch, first):
            if isinstance(spec, (str, bytes)) or not isinstance(spec, Sequence) or not spec:
                raise ParameterError(f"`orders`: {branch!r} needs one entry per lag; got "
                                     f"{spec!r}.")
            out = []
            for i, entry in enumerate(spec, start=first):
                group = entry if isinstance(entry, (tuple, list)) else (entry,)
                if not group:
                    raise ParameterError(f"`orders`: lag {i} of {branch!r} has no order.")
                out += [(i, o) for o in group]
            return out
        return cls(expand(a, "a", 1), expand(b, "b", nk))

    @classmethod
    def resolve(cls, spec, *, na, nb, nk=1, inputs=None):
        """An :class:`Orders` from what a user passed as ``orders`` (with the lag orders).

        ``na`` and ``nb`` are the numbers of lags and ``nk`` the input delay; a resolved
        :class:`Orders` or dict must use output lags up to ``na`` and input lags from ``nk`` to
        ``nk + nb - 1``. Several inputs: ``inputs`` names them, ``nb`` and ``nk`` are one per
        input or one for all.
        """
        if inputs is not None and len(inputs) > 1:
            lags = cls._input_lags(nb, nk, inputs)
            nb, nk = tuple(len(r) for r in lags), tuple(r.start for r in lags)
        else:                                          # one input: a list has one entry
            (lags,) = cls._input_lags(nb, nk, None)
            nb, nk = len(lags), lags.start
        if spec is None:
            spec = "commensurate"
        if isinstance(spec, str):
            return cls.preset(spec, na=na, nb=nb, nk=nk, inputs=inputs)
        if isinstance(spec, numbers.Real) and not isinstance(spec, bool):
            return cls.fixed(spec, na=na, nb=nb, nk=nk, inputs=inputs)
        if isinstance(spec, Mapping):
            extra = set(spec) - {"a", "b"}
            if extra or not {"a", "b"} <= set(spec):
                raise ParameterError(f"`orders` as a dict needs exactly the keys 'a' and 'b' "
                                     f"(per-lag orders of each branch); got {sorted(spec)}.")
            spec = cls.from_lags(spec["a"], spec["b"], nk=nk, inputs=inputs)
        if not isinstance(spec, Orders):
            raise ParameterError(f"`orders` must be one of {PRESETS}, a number, an Orders or a "
                                 f"dict of per-lag orders; got {spec!r}.")
        default = tuple(f"u{i}" for i in range(1, len(inputs) + 1)) if inputs else ()
        if inputs is not None and len(inputs) > 1 and spec.inputs != tuple(inputs) and not (
                tuple(inputs) == default and spec.n_inputs == len(inputs)):
            # (an Orders names its inputs; the data's default names u1, u2, ... give way)
            raise ParameterError(f"`orders` has the inputs {list(spec.inputs) or 1}, but the "
                                 f"data have {list(inputs)}.")
        if spec.na != na or spec.nb != nb or spec.nk != nk:
            if spec.nk == 1 and nk == 1:
                raise ParameterError(f"`orders` uses lags up to {spec.na} (output) and "
                                     f"{spec.nb} (input), but na = {na} and nb = {nb}.")
            raise ParameterError(f"`orders` uses output lags up to {spec.na} and input lags "
                                 f"{spec.nk}..{spec.max_input_lag}, but na = {na}, nb = {nb} "
                                 f"and nk = {nk} (input lags {nk}..{nk + nb - 1}).")
        return spec

    @classmethod
    def infer(cls, spec, n_a, n_b, nk=None):
        """An :class:`Orders` for a model with ``n_a`` and ``n_b`` coefficients (terms).

        ``nk`` is the input delay of a preset or of per-lag orders (``None``: 1); an
        :class:`Orders` carries its own lags (a given ``nk`` must agree with its smallest
        input lag).
        """
        given = nk is not None
        nk = check_nk(nk) if given else 1
        if spec is None or spec in ("commensurate", "per_lag") or (
                isinstance(spec, numbers.Real) and not isinstance(spec, bool)):
            return cls.resolve(spec, na=n_a, nb=n_b, nk=nk)
        if spec == "mixed":
            if n_a % 2 or n_b % 2:
                raise ParameterError("`orders='mixed'` has two terms per lag (orders 0 and "
                                     f"alpha), so `a` and `b` need even lengths; got {n_a} and "
                                     f"{n_b}.")
            return cls.preset("mixed", na=n_a // 2, nb=n_b // 2, nk=nk)
        if isinstance(spec, Mapping):
            spec = cls.from_lags(spec["a"], spec["b"], nk=nk) if {"a", "b"} == set(spec) \
                else spec
        orders = cls.resolve(spec, na=getattr(spec, "na", 1), nb=getattr(spec, "nb", 1),
                             nk=getattr(spec, "nk", nk))
        if given and orders.nk != nk:
            raise ParameterError(f"`orders` has input lags from {orders.nk}, but nk = {nk}.")
        if (len(orders.output), len(orders.input)) != (n_a, n_b):
            raise ParameterError(f"`orders` has {len(orders.output)} output and "
                                 f"{len(orders.input)} input terms, but `a` and `b` have {n_a} "
                                 f"and {n_b} coefficients.")
        return orders

    # ---- reading --------------------------------------------------------------------------------
    @property
    def na(self) -> int:
        """Largest output lag."""
        return max(t.lag for t in self.output)

    @property
    def nb(self):
        """Number of input lags, ``nk … nk + nb - 1`` (the largest input lag when ``nk = 1``).

        A tuple, one per input, when there are several.
        """
        if self.n_inputs > 1:
            return tuple(max(t.lag for t in g) - min(t.lag for t in g) + 1
                         for g in map(self.input_terms, range(self.n_inputs)))
        return self.max_input_lag - self.nk + 1

    @property
    def nk(self):
        """Input delay: the smallest input lag (1 for the paper's model, 0: direct feedthrough).

        A tuple, one per input, when there are several.
        """
        if self.n_inputs > 1:
            return tuple(min(t.lag for t in self.input_terms(i)) for i in range(self.n_inputs))
        return min(t.lag for t in self.input)

    @property
    def max_input_lag(self) -> int:
        """Largest input lag, ``nk + nb - 1``."""
        return max(t.lag for t in self.input)

    @property
    def max_lag(self) -> int:
        """Largest lag of either branch: a record must be longer than this."""
        return max(self.na, self.max_input_lag)

    @property
    def is_commensurate(self) -> bool:
        """The paper's Eq. (16): lags ``1..na`` and ``1..nb`` once each, one shared free order."""
        return (len(self.free) == 1 and self.n_inputs == 1
                and [t.lag for t in self.output] == list(range(1, len(self.output) + 1))
                and [t.lag for t in self.input] == list(range(1, len(self.input) + 1))
                and all(t.order == self.free[0] for t in self.output + self.input))

    def _names(self, terms, letter):
        count = {}
        for t in terms:
            count[t.lag] = count.get(t.lag, 0) + 1
        return tuple(f"{letter}{t.lag}" if count[t.lag] == 1 else f"{letter}{t.lag}_{t.label()}"
                     for t in terms)

    @property
    def a_names(self) -> tuple[str, ...]:
        """Names of the output-branch coefficients.

        ``a1`` when lag 1 has one term; ``a1_0``, ``a1_alpha`` when it has several.
        """
        return self._names(self.output, "a")

    @property
    def b_names(self) -> tuple[str, ...]:
        """Names of the input-branch coefficients (as :attr:`a_names`; ``u2.b1`` with inputs)."""
        return tuple((f"{prefix}." if prefix else "") + name
                     for prefix, names in self.input_groups() for name in names)

    def input_groups(self):
        """``[(input name or "", coefficient names without it), …]``, one per input."""
        if self.n_inputs == 1:
            return [("", self._names(self.input, "b"))]
        return [(name, self._names(self.input_terms(i), "b"))
                for i, name in enumerate(self.inputs)]

    def values(self, free_values, *, check=True):
        """``(output orders, input orders)``: a number per term, given the free orders' values.

        ``free_values`` is a mapping by name or a sequence in :attr:`free` order; with
        ``check=False`` a mapping is used as given (already validated, any finite order).
        """
        mapping = (free_values if not check and isinstance(free_values, Mapping)
                   else self.free_mapping(free_values))
        get = (lambda t: mapping[t.order] if t.free else t.order)  # noqa: E731
        return tuple(get(t) for t in self.output), tuple(get(t) for t in self.input)

    def free_mapping(self, free_values, name="alpha"):
        """``{free order: value}`` from a mapping, a sequence, or (one free order) a number."""
        if isinstance(free_values, Mapping):
            missing = [n for n in self.free if n not in free_values]
            extra = [n for n in free_values if n not in self.free]
            if missing or extra:
                raise ParameterError(f"`{name}` must give the free orders {list(self.free)}; "
                                     f"missing {missing}, unknown {extra}.")
            values = [free_values[n] for n in self.free]
        elif isinstance(free_values, numbers.Real) and not isinstance(free_values, bool):
            values = [free_values] * len(self.free) if len(self.free) == 1 else None
            if values is None:
                raise ParameterError(f"`{name}` is one number, but there are "
                                     f"{len(self.free)} free orders {list(self.free)}; pass a "
                                     "sequence or a dict.")
        elif free_values is None:
            values = []
            if self.free:
                raise ParameterError(f"`{name}` must give the free orders {list(self.free)}.")
        else:
            values = list(free_values)
            if len(values) != len(self.free):
                raise ParameterError(f"`{name}` must have {len(self.free)} entries (the free "
                                     f"orders {list(self.free)}); got {len(values)}.")
        return {n: check_scalar(v, f"{name}[{n!r}]", lower=ORDER_RANGE[0], upper=ORDER_RANGE[1])
                for n, v in zip(self.free, values)}

    def to_dict(self) -> dict:
        """JSON-ready: ``{"a": [[lag, order], …], "b": […]}``.

        Several inputs: input terms ``[lag, order, input]`` and ``"inputs"``: their names (a
        single-input description is unchanged).
        """
        if self.n_inputs > 1:
            return {"a": [[t.lag, t.order] for t in self.output],
                    "b": [[t.lag, t.order, t.input] for t in self.input],
                    "inputs": list(self.inputs)}
        return {"a": [[t.lag, t.order] for t in self.output],
                "b": [[t.lag, t.order] for t in self.input]}

    @classmethod
    def from_dict(cls, d):
        """Inverse of :meth:`to_dict` (terms are checked as by the constructor)."""
        if not isinstance(d, Mapping) or set(d) not in ({"a", "b"}, {"a", "b", "inputs"}):
            raise ParameterError("`orders` must be described as {'a': [[lag, order], ...], "
                                 f"'b': [...]}} (and 'inputs' for several); got {d!r}.")
        orders = cls(d["a"], d["b"], inputs=d.get("inputs"))
        if "inputs" in d and orders.n_inputs == 1:
            raise ParameterError(f"`orders`: 'inputs' is written for several inputs only; got "
                                 f"{d['inputs']!r} for one.")
        return orders

    def __eq__(self, other):
        return (isinstance(other, Orders) and self.output == other.output
                and self.input == other.input and self.inputs == other.inputs)

    def __hash__(self):
        return hash((self.output, self.input, self.inputs))

    def __repr__(self):
        def fmt(terms, named):
            return "[" + ", ".join(
                f"({t.lag}, {t.label()}" + (f", {self.inputs[t.input]})" if named else ")")
                for t in terms) + "]"
        return f"Orders(a={fmt(self.output, False)}, b={fmt(self.input, bool(self.inputs))})"


#: A class of orders as the public API accepts it: a preset name (``"commensurate"``,
#: ``"mixed"``, ``"per_lag"``), a fixed order, an :class:`Orders`, or a mapping
#: ``{"a": [...], "b": [...]}`` of per-lag orders.
OrdersLike = Union[str, float, Orders, Mapping[str, Sequence]]
