"""The parameter vector theta and its named blocks (paper Eqs. 17–20, 39–40).

``theta = [q ⊗ a, p ⊗ b] = [a, q_2 a, …, q_nq a, b, p_2 b, …, p_np b]`` with the
normalisation ``p_1 = q_1 = 1``. :class:`ThetaLayout` is the one place that knows this
layout; nothing else in fohw slices theta by hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._validation import check_array, check_int
from ...exceptions import DimensionError, ParameterError

__all__ = ["ThetaLayout"]


@dataclass(frozen=True)
class ThetaLayout:
    """Layout of theta for given lag orders and basis sizes.

    Parameters
    ----------
    na, nb : int
        Number of output and input terms (``>= 1``): the lags of the paper's commensurate model,
        or the terms of a general one (:class:`fohw.Orders`).
    n_g, n_f : int
        Number of output (``g``) and input (``f``) basis functions (``>= 1``).
    a_names, b_names : tuple of str, optional
        Names of the terms (default ``a1 … a{na}``, ``b1 … b{nb}``).
    b_groups : tuple of (str, tuple of str, int), optional
        Several inputs: per input, its name, the names of its terms (without the input's
        name) and its number of basis functions. Theta is then ``[q ⊗ a, p_1 ⊗ b_1, …,
        p_m ⊗ b_m]``; ``nb`` and ``n_f`` are the totals, ``b_names`` the qualified names
        (``u2.b1``), and entries are named ``u2.p2b1``, the structural ``p`` ``u2.p2``.

    Examples
    --------
    >>> import fohw
    >>> layout = fohw.model.lagged.params.ThetaLayout(na=2, nb=2, n_g=3, n_f=2)
    >>> layout.names
    ('a1', 'a2', 'q2a1', 'q2a2', 'q3a1', 'q3a2', 'b1', 'b2', 'p2b1', 'p2b2')
    >>> theta = layout.to_theta(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1, 0.5], q=[1, 0.7, 0.35])
    >>> theta.round(3)
    array([ 0.1  ,  0.2  ,  0.07 ,  0.14 ,  0.035,  0.07 , -0.4  , -0.2  , -0.2  , -0.1  ])
    >>> a, b, p, q = layout.recover(theta)
    >>> q.round(12)
    array([1.  , 0.7 , 0.35])
    """

    na: int
    nb: int
    n_g: int
    n_f: int
    a_names: tuple | None = None
    b_names: tuple | None = None
    b_groups: tuple | None = None

    def __post_init__(self):
        for name in ("na", "nb", "n_g", "n_f"):
            object.__setattr__(self, name, check_int(getattr(self, name), name, minimum=1))
        for name, size, letter in (("a_names", self.na, "a"), ("b_names", self.nb, "b")):
            names = getattr(self, name)
            names = tuple(f"{letter}{i}" for i in range(1, size + 1)) if names is None else \
                tuple(str(n) for n in names)
            if len(names) != size:
                raise DimensionError(f"`{name}` must have {size} entries; got {len(names)}.")
            object.__setattr__(self, name, names)
        if self.b_groups is not None:
            groups = tuple((str(g[0]), tuple(str(n) for n in g[1]), check_int(g[2], "n_f",
                                                                                minimum=1))
                           for g in self.b_groups)
            if sum(len(g[1]) for g in groups) != self.nb or \
                    sum(g[2] for g in groups) != self.n_f:
                raise DimensionError(f"`b_groups` must add up to nb = {self.nb} terms and n_f = "
                                     f"{self.n_f} basis functions; got {groups}.")
            object.__setattr__(self, "b_groups", groups)

    @property
    def groups(self):
        """``[(name, term names, n_f, offset in theta), …]`` per input (one group: name "")."""
        if self.b_groups is None:
            return [("", self.b_names, self.n_f, self.n_output_params)]
        out, offset = [], self.n_output_params
        for name, names, nf in self.b_groups:
            out.append((name, names, nf, offset))
            offset += nf * len(names)
        return out

    @property
    def n_params(self) -> int:
        """Length of theta, ``n = n_g * na + n_f * nb`` (Eq. 20; summed over the inputs)."""
        if self.b_groups is not None:
            return self.n_g * self.na + sum(nf * len(n) for _, n, nf in self.b_groups)
        return self.n_g * self.na + self.n_f * self.nb

    @property
    def n_output_params(self) -> int:
        """Number of entries of theta that multiply output terms (``n_g * na``)."""
        return self.n_g * self.na

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the entries of theta, e.g. ``a1``, ``q2a1``, ``b1``, ``p2b1``."""
        out = []
        for j in range(1, self.n_g + 1):
            out += [(f"q{j}" if j > 1 else "") + a for a in self.a_names]
        if self.b_groups is not None:
            for prefix, names, nf, _ in self.groups:
                for j in range(1, nf + 1):
                    out += [f"{prefix}." + (f"p{j}" if j > 1 else "") + b for b in names]
            return tuple(out)
        for j in range(1, self.n_f + 1):
            out += [(f"p{j}" if j > 1 else "") + b for b in self.b_names]
        return tuple(out)

    @property
    def model_parameter_names(self) -> tuple[str, ...]:
        """Names of the free structural parameters ``a_i, b_i, q_j (j>1), p_j (j>1)``."""
        if self.b_groups is not None:
            return (self.a_names + self.b_names
                    + tuple(f"{prefix}.p{j}" for prefix, _, nf, _ in self.groups
                            for j in range(2, nf + 1))
                    + tuple(f"q{j}" for j in range(2, self.n_g + 1)))
        return (self.a_names + self.b_names
                + tuple(f"p{j}" for j in range(2, self.n_f + 1))
                + tuple(f"q{j}" for j in range(2, self.n_g + 1)))

    def check_theta(self, theta, name: str = "theta") -> np.ndarray:
        """Validate a theta vector of this layout and return it as float64."""
        theta = check_array(theta, name)
        if theta.shape[0] != self.n_params:
            raise DimensionError(f"`{name}` must have {self.n_params} entries for na={self.na}, "
                                 f"nb={self.nb}, {self.n_g} g- and {self.n_f} f-basis functions; "
                                 f"got {theta.shape[0]}.")
        return theta

    def to_theta(self, a, b, p, q) -> np.ndarray:
        """Assemble ``theta = [q ⊗ a, p ⊗ b]`` (one input)."""
        self._single("to_theta")
        a, b, p, q = self._check_blocks(a, b, p, q)
        return np.concatenate([np.kron(q, a), np.kron(p, b)])

    def blocks(self, theta):
        """Return theta reshaped as ``(n_g, na)`` and ``(n_f, nb)`` matrices (rows ``q_j a``, ``p_j b``)."""
        theta = self.check_theta(theta)
        k = self.n_output_params
        if self.b_groups is not None:            # block diagonal over the inputs
            pb = np.zeros((self.n_f, self.nb))
            row = col = 0
            for block in self.input_blocks(theta):
                pb[row:row + block.shape[0], col:col + block.shape[1]] = block
                row, col = row + block.shape[0], col + block.shape[1]
            return theta[:k].reshape(self.n_g, self.na), pb
        return theta[:k].reshape(self.n_g, self.na), theta[k:].reshape(self.n_f, self.nb)

    def input_blocks(self, theta):
        """The ``(n_f_i, nb_i)`` blocks ``[p_ij b_it]`` of theta, one per input.

        With several inputs :meth:`blocks` gives them as one block-diagonal matrix (the
        stacked basis signals of every input against every input term).
        """
        theta = self.check_theta(theta)
        return [theta[off:off + nf * len(names)].reshape(nf, len(names))
                for _, names, nf, off in self.groups]

    def _single(self, what):
        if self.b_groups is not None:
            raise ParameterError(f"{what} is for a single input; this layout has "
                                 f"{len(self.b_groups)} inputs (a, b_i, p_i, q: "
                                 "recover_vector, theta_of_model_vector).")
    def recover(self, theta):
        """Recover ``a, b, p, q`` from theta by Eqs. (39)–(40).

        ``a`` and ``b`` are the first blocks; ``q_j`` is the mean over ``i`` of
        ``theta[q_j a_i] / a_i`` and ``p_j`` likewise with ``b``.

        Raises
        ------
        ParameterError
            An ``a_i`` (or ``b_i``) is exactly zero while ``q`` (``p``) has more than one entry,
            so Eq. (39) (Eq. (40)) is undefined.
        """
        self._single("recover (Eqs. 39-40 into a, b, p, q)")
        qa, pb = self.blocks(theta)
        a, b = qa[0].copy(), pb[0].copy()
        if self.n_g > 1 and np.any(a == 0):
            raise ParameterError(f"cannot recover q by Eq. (39): an entry of `a` is zero ({a}).")
        if self.n_f > 1 and np.any(b == 0):
            raise ParameterError(f"cannot recover p by Eq. (40): an entry of `b` is zero ({b}).")
        q = np.ones(self.n_g)
        p = np.ones(self.n_f)
        q[1:] = (qa[1:] / a).mean(axis=1)
        p[1:] = (pb[1:] / b).mean(axis=1)
        return a, b, p, q

    def recover_vector(self, theta) -> np.ndarray:
        """``[a, b, p_2.., q_2..]`` from theta (Eqs. 39–40), in :attr:`model_parameter_names` order."""
        if self.b_groups is not None:
            qa, _ = self.blocks(theta)
            a, q = _ratio_recovery(qa, "a", "q", "Eq. (39)")
            bp = [_ratio_recovery(block, "b", "p", "Eq. (40)") for block in self.input_blocks(theta)]
            return np.concatenate([a] + [b for b, _ in bp] + [p[1:] for _, p in bp] + [q[1:]])
        a, b, p, q = self.recover(theta)
        return np.concatenate([a, b, p[1:], q[1:]])

    def recover_jacobian(self, theta) -> np.ndarray:
        """Jacobian of :meth:`recover_vector` with respect to theta (for the delta method).

        Returns
        -------
        jac : ndarray, shape (na + nb + n_f - 1 + n_g - 1, n)

        Examples
        --------
        >>> import numpy as np, fohw
        >>> layout = fohw.model.lagged.params.ThetaLayout(na=1, nb=1, n_g=2, n_f=1)
        >>> layout.recover_jacobian([0.5, 0.25, -1.0])   # q2 = theta[1] / theta[0]
        array([[ 1.,  0.,  0.],
               [ 0.,  0.,  1.],
               [-1.,  2.,  0.]])
        """
        if self.b_groups is None:
            self.recover(theta)          # Eqs. (39)-(40) defined: the same errors as recover
        return self._recover_jacobian(theta)

    def _recover_jacobian(self, theta):
        """:meth:`recover_jacobian`, one block of rows per input (a single input: one group)."""
        qa, _ = self.blocks(theta)
        a = qa[0]
        na = self.na
        rows = []

        def unit(i):
            r = np.zeros(self.n_params)
            r[i] = 1.0
            return r
        rows += [unit(i) for i in range(na)]
        groups, blocks = self.groups, self.input_blocks(theta)
        for (_, names, _, off) in groups:
            rows += [unit(off + i) for i in range(len(names))]
        for (_, names, nf, off), pb in zip(groups, blocks):
            nb, b = len(names), pb[0]
            for j in range(1, nf):
                r = np.zeros(self.n_params)
                r[off + j * nb:off + (j + 1) * nb] = 1.0 / (nb * b)
                r[off:off + nb] = -pb[j] / (nb * b**2)
                rows.append(r)
        for j in range(1, self.n_g):
            r = np.zeros(self.n_params)
            r[j * na:(j + 1) * na] = 1.0 / (na * a)
            r[:na] = -qa[j] / (na * a**2)
            rows.append(r)
        return np.array(rows)

    @property
    def n_model_params(self) -> int:
        """Number of free structural parameters, ``na + nb + (n_f - 1) + (n_g - 1)``."""
        if self.b_groups is not None:
            return (self.na + self.nb + sum(nf - 1 for _, _, nf in self.b_groups)
                    + self.n_g - 1)
        return self.na + self.nb + self.n_f - 1 + self.n_g - 1

    def split_model_vector(self, eta):
        """``a, b, p, q`` (with ``p_1 = q_1 = 1``) from ``[a, b, p_2.., q_2..]``.

        ``eta`` is in :attr:`model_parameter_names` order, the inverse of
        :meth:`recover_vector` on a theta of the form ``[q ⊗ a, p ⊗ b]``.
        """
        eta = check_array(eta, "eta")
        if eta.shape[0] != self.n_model_params:
            raise DimensionError(f"`eta` must have {self.n_model_params} entries "
                                 f"{self.model_parameter_names}; got {eta.shape[0]}.")
        if self.b_groups is not None:       # a, [b_i], [p_i], q
            na, pos = self.na, self.na + self.nb
            b, p, start = [], [], na
            for _, names, nf in self.b_groups:
                b.append(eta[start:start + len(names)])
                p.append(np.r_[1.0, eta[pos:pos + nf - 1]])
                start, pos = start + len(names), pos + nf - 1
            return eta[:na], b, p, np.r_[1.0, eta[pos:]]
        na, nb, nf = self.na, self.nb, self.n_f
        a, b = eta[:na], eta[na:na + nb]
        p = np.r_[1.0, eta[na + nb:na + nb + nf - 1]]
        q = np.r_[1.0, eta[na + nb + nf - 1:]]
        return a, b, p, q

    def theta_of_model_vector(self, eta) -> np.ndarray:
        """``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20) from ``eta = [a, b, p_2.., q_2..]``."""
        if self.b_groups is not None:
            a, b, p, q = self.split_model_vector(eta)
            return np.concatenate([np.kron(q, a)] + [np.kron(pi, bi) for pi, bi in zip(p, b)])
        return self.to_theta(*self.split_model_vector(eta))

    def theta_jacobian(self, eta) -> np.ndarray:
        """Jacobian ``d theta / d eta`` of :meth:`theta_of_model_vector` (Eq. 20).

        ``d(q ⊗ a)/da = q ⊗ I``, ``d(q ⊗ a)/dq_j = e_j ⊗ a`` and likewise for ``p ⊗ b``. It maps
        a covariance of the structural parameters to theta's (``M C M^T``, the delta method)
        and the Jacobian of any function of theta to the structural parameters (``G M``).
        Since :meth:`recover_vector` inverts :meth:`theta_of_model_vector`,
        ``recover_jacobian(theta) @ theta_jacobian(eta)`` is the identity.

        Returns
        -------
        jac : ndarray, shape (n, na + nb + n_f - 1 + n_g - 1)

        Examples
        --------
        >>> import fohw
        >>> layout = fohw.model.lagged.params.ThetaLayout(na=1, nb=1, n_g=2, n_f=1)
        >>> layout.theta_jacobian([0.5, -1.0, 0.5])     # theta = [a, q2 a, b]
        array([[1. , 0. , 0. ],
               [0.5, 0. , 0.5],
               [0. , 1. , 0. ]])
        """
        if self.b_groups is not None:
            return self._group_theta_jacobian(eta)
        a, b, p, q = self.split_model_vector(eta)
        na, nb, nf, ng, k = self.na, self.nb, self.n_f, self.n_g, self.n_output_params
        jac = np.zeros((self.n_params, self.n_model_params))
        jac[:k, :na] = np.kron(q[:, None], np.eye(na))
        jac[k:, na:na + nb] = np.kron(p[:, None], np.eye(nb))
        for j in range(1, nf):
            jac[k + j * nb:k + (j + 1) * nb, na + nb + j - 1] = b
        for j in range(1, ng):
            jac[j * na:(j + 1) * na, na + nb + nf - 1 + j - 1] = a
        return jac

    def _group_theta_jacobian(self, eta):
        a, b, p, q = self.split_model_vector(eta)
        na, ng, k = self.na, self.n_g, self.n_output_params
        jac = np.zeros((self.n_params, self.n_model_params))
        jac[:k, :na] = np.kron(q[:, None], np.eye(na))
        col_b, col_p = na, na + self.nb
        for (_, names, nf, off), bi, pi in zip(self.groups, b, p):
            nb = len(names)
            jac[off:off + nf * nb, col_b:col_b + nb] = np.kron(pi[:, None], np.eye(nb))
            for j in range(1, nf):
                jac[off + j * nb:off + (j + 1) * nb, col_p + j - 1] = bi
            col_b, col_p = col_b + nb, col_p + nf - 1
        for j in range(1, ng):
            jac[j * na:(j + 1) * na, col_p + j - 1] = a
        return jac

    def rank_one_recovery(self, theta):
        """``[a, b, p_2.., q_2..]`` from any theta by the best rank-one fits of its blocks.

        The ``(n_g, na)`` block ``[q_j a_i]`` and the ``(n_f, nb)`` block ``[p_j b_i]`` of an
        estimated theta are not exactly rank one; the leading singular triple ``s u v^T`` of
        each is its best rank-one approximation in the Frobenius norm, and the normalisation
        ``q_1 = 1`` gives ``q = u / u_1``, ``a = s u_1 v`` (likewise ``p``, ``b``). Unlike the
        mean of ratios of Eqs. (39)–(40) it weights every entry of the block alike and needs
        no ``a_i`` to be non-zero.

        Raises
        ------
        ParameterError
            The first row of a block's leading singular vector is zero (``q_1 = 1`` cannot be
            imposed: the first basis function does not enter that block).
        """
        if self.b_groups is not None:
            qa, _ = self.blocks(theta)
            pairs = [_rank_one(block, name) for block, name in
                     [(qa, "output (q ⊗ a)")] + [(blk, f"input {g[0]!r} (p ⊗ b)") for blk, g in
                                                 zip(self.input_blocks(theta), self.b_groups)]]
            (a, q), rest = pairs[0], pairs[1:]
            return np.concatenate([a] + [b for b, _ in rest] + [p[1:] for _, p in rest]
                                  + [q[1:]])
        out = []
        for block, name in zip(self.blocks(theta), ("output (q ⊗ a)", "input (p ⊗ b)")):
            u, s, vt = np.linalg.svd(block, full_matrices=False)
            lead = u[0, 0]
            if lead == 0.0 or s[0] == 0.0:
                raise ParameterError(f"cannot normalise the {name} block of theta to a first "
                                     f"coefficient of 1: its rank-one part has a zero first row "
                                     f"(block {block.tolist()}).")
            out.append((s[0] * lead * vt[0], u[:, 0] / lead))
        (a, q), (b, p) = out
        return np.concatenate([a, b, p[1:], q[1:]])

    def _check_blocks(self, a, b, p, q):
        a = check_array(a, "a")
        b = check_array(b, "b")
        p = check_array(p, "p")
        q = check_array(q, "q")
        for name, vec, size in (("a", a, self.na), ("b", b, self.nb), ("p", p, self.n_f),
                                ("q", q, self.n_g)):
            if vec.shape[0] != size:
                raise DimensionError(f"`{name}` must have {size} entries; got {vec.shape[0]}.")
        return a, b, p, q


def _rank_one(block, name):
    """``(coefficients, weights)`` of the best rank-one fit of a block, first weight 1."""
    u, s, vt = np.linalg.svd(block, full_matrices=False)
    lead = u[0, 0]
    if lead == 0.0 or s[0] == 0.0:
        raise ParameterError(f"cannot normalise the {name} block of theta to a first "
                             f"coefficient of 1: its rank-one part has a zero first row "
                             f"(block {block.tolist()}).")
    return s[0] * lead * vt[0], u[:, 0] / lead


def _ratio_recovery(block, coef, weight, eq):
    """Eqs. (39)-(40) on one block: first row, and the mean ratios of the others to it."""
    first = block[0].copy()
    if block.shape[0] > 1 and np.any(first == 0):
        raise ParameterError(f"cannot recover {weight} by {eq}: an entry of `{coef}` is zero "
                             f"({first}).")
    w = np.ones(block.shape[0])
    w[1:] = (block[1:] / first).mean(axis=1)
    return first, w
