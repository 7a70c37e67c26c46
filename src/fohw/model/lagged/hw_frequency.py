"""The linear block of a lagged fractional HW model in the frequency domain: response, static gain, stability.

The paper's model (Eq. 16) and fohw's general class (Eq. 14: a lag ``i_t >= 1``, ``>= 0`` for
input terms, and an order ``nu_t`` per term) are polynomials in the lag operator ``q^{-1}`` and
in ``(1 - q^{-1})/h``:

.. math:: y = A(q)\\,\\bar g(y) + B(q)\\,\\bar f(u), \\quad
          A(z) = \\sum_t a_t z^{-i_t} \\Big(\\frac{1 - z^{-1}}{h}\\Big)^{\\nu_t}, \\quad
          B(z) = \\sum_t b_t z^{-i_t} \\Big(\\frac{1 - z^{-1}}{h}\\Big)^{\\nu_t}.

**Linearisation** (stated once, used everywhere here): the static maps are replaced by their
slopes at the operating point (deviation 0), ``gbar(y) ~ g' y`` and ``fbar(u) ~ f' u`` with
``g' = sum_j q_j g_j'(0)`` and ``f' = sum_j p_j f_j'(0)``. For fohw's polynomial bases
(``x, x^2, ...``) only the first function has a slope at 0, so ``g' = q_1 = 1`` and
``f' = p_1 = 1``: the linear block is the map from ``u`` to ``y`` with ``g = y`` and ``f = u``.
For a custom basis the slopes are central differences (step ``1e-6`` of the basis's unit).
The small-signal transfer function from ``u`` to ``y`` is then

.. math:: H(z) = \\frac{f'\\,B(z)}{1 - g'\\,A(z)}, \\qquad z = e^{j \\omega h}.

**Static gain** ``H(1)``: every term of order ``nu_t > 0`` vanishes at ``z = 1`` (``(1 - 1)^nu =
0``), so only order-0 terms count: ``H(1) = f' B_0 / (1 - g' A_0)`` with ``A_0, B_0`` the sums
of the order-0 coefficients. The paper's commensurate model with ``alpha > 0`` therefore has
static gain 0 (SPEC Sec. 8); ``1 - g' A_0 = 0`` with ``B_0 != 0`` is an integrator (``inf``).

**Stability** (BIBO of the linear block): the impulse response is the power series of
``f' B(x) / D(x)``, ``D(x) = 1 - g' A(x)`` in ``x = z^{-1}``. For orders ``nu >= 0`` the GL
weights of ``(1 - x)^nu`` are absolutely summable, so ``D`` is in the Wiener algebra of the
closed unit disc, and (Wiener's lemma) ``1/D`` has summable coefficients iff ``D`` has no zero
in ``|x| <= 1``. Zeros inside the disc are counted by the argument principle: the winding
number of ``D(e^{j theta})`` around 0 for ``theta`` from 0 to ``2 pi`` (``D`` is continuous on
the circle, including the branch point ``x = 1`` where ``D(1) = 1 - g' A_0``). A zero on the
circle (``min |D| <= 1e-10`` of its scale) is reported as *marginal*. For integer orders ``D``
is a polynomial in ``x`` and the verdict is the classical one (poles ``z = 1/x`` inside the unit
circle; a test checks both agree).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._validation import check_array, check_int
from ...exceptions import ParameterError
from ..frequency_response import gl_operator_response

__all__ = ["LinearBlock", "linear_block", "StabilityVerdict"]

# Central-difference step of the slope of a custom basis at the operating point.
SLOPE_STEP = 1e-6
# |D| below this (relative to sum |terms|) on the unit circle: a zero on the circle.
MARGINAL_TOL = 1e-10


@dataclass(frozen=True)
class StabilityVerdict:
    """Stability of a lagged linear block (the argument principle on the unit circle).

    Attributes
    ----------
    stable : bool
        No zero of ``D(x) = 1 - g' A(x)`` in the closed unit disc (BIBO stable).
    zeros_inside : int
        Zeros of ``D`` in ``|x| < 1`` (the winding number), i.e. unstable poles ``|z| > 1``.
    marginal : bool
        ``D`` vanishes (to ``1e-10`` of its scale) on the unit circle: a pole on ``|z| = 1``.
    min_abs_d : float
        ``min |D(e^{j theta})|`` over the grid (relative to the scale ``sum |terms|``).
    method : str
        How it was decided.
    """

    stable: bool
    zeros_inside: int
    marginal: bool
    min_abs_d: float
    method: str = "argument principle on |z| = 1"

    def __str__(self):
        if self.marginal:
            return f"marginal (a pole on |z| = 1; min |1 - A| = {self.min_abs_d:.3g}; {self.method})"
        word = "stable" if self.stable else f"unstable ({self.zeros_inside} pole(s) with |z| > 1)"
        return f"{word} ({self.method}; min |1 - A| on the circle = {self.min_abs_d:.3g})"


def _basis_slope(basis, coefs):
    """``sum_j coefs[j] basis_j'(0)``: exact for the polynomial basis (``coefs[0]``)."""
    if basis.is_polynomial:
        return float(coefs[0])
    x = np.array([-SLOPE_STEP, SLOPE_STEP])
    vals = np.asarray(coefs, dtype=float) @ basis.evaluate(x)
    return float((vals[1] - vals[0]) / (2 * SLOPE_STEP))


class LinearBlock:
    """The linearised linear block ``H(z) = f' B(z) / (1 - g' A(z))`` of a lagged HW model.

    Parameters
    ----------
    a, b : array_like
        Coefficients of the output and input terms.
    a_terms, b_terms : sequence of (int, float)
        ``(lag, order)`` of each term, lags ``>= 1`` (``>= 0`` for ``b``: feedthrough), orders
        ``>= 0``.
    dt : float
        Sampling time ``h``.
    g_slope, f_slope : float, optional
        ``g'`` and ``f'`` (default 1: the polynomial bases).

    Examples
    --------
    >>> from fohw.model.lagged.hw_frequency import LinearBlock
    >>> blk = LinearBlock([0.5], [1.0], [(1, 0.0)], [(1, 0.0)], dt=1.0)    # y = 0.5 y[k-1] + u[k-1]
    >>> blk.static_gain
    2.0
    >>> blk.stability().stable
    True
    """

    def __init__(self, a, b, a_terms, b_terms, *, dt, g_slope=1.0, f_slope=1.0):
        self.a = np.atleast_1d(np.asarray(a, dtype=float))
        self.b = np.atleast_1d(np.asarray(b, dtype=float))
        self.a_terms = tuple((int(i), float(nu)) for i, nu in a_terms)
        self.b_terms = tuple((int(i), float(nu)) for i, nu in b_terms)
        if len(self.a_terms) != self.a.size or len(self.b_terms) != self.b.size:
            raise ParameterError(f"one (lag, order) per coefficient: got {self.a.size} `a` for "
                                 f"{len(self.a_terms)} terms and {self.b.size} `b` for "
                                 f"{len(self.b_terms)} terms.")
        for least, terms, branch in ((1, self.a_terms, "output"), (0, self.b_terms, "input")):
            for i, nu in terms:
                if i < least or not np.isfinite(nu) or nu < 0:
                    raise ParameterError(f"an {branch} term needs a lag >= {least} and a finite "
                                         f"order >= 0; got (lag {i}, order {nu}).")
        self.dt = float(dt)
        self.g_slope = float(g_slope)
        self.f_slope = float(f_slope)

    def __repr__(self):
        def terms(c, t):
            return "[" + ", ".join(f"{x:.6g} (lag {i}, order {nu:g})" for x, (i, nu) in zip(c, t)) + "]"
        return (f"LinearBlock(a={terms(self.a, self.a_terms)}, b={terms(self.b, self.b_terms)}, "
                f"dt={self.dt:g}, g_slope={self.g_slope:.6g}, f_slope={self.f_slope:.6g})")

    def _repr_html_(self):
        from ..._repr import html_table

        rows = ([("a (output)", i, nu, c) for c, (i, nu) in zip(self.a, self.a_terms)]
                + [("b (input)", i, nu, c) for c, (i, nu) in zip(self.b, self.b_terms)])
        return html_table("LinearBlock H(z) = f' B(z) / (1 - g' A(z))",
                          ["term", "lag", "order", "coefficient"], rows,
                          lines=[f"f' = {self.f_slope:.6g}, g' = {self.g_slope:.6g}, "
                                 f"dt = {self.dt:g}", f"static gain H(1) = {self.static_gain:.6g}",
                                 f"stability: {self.stability()}"], digits=6)

    @classmethod
    def from_model(cls, model):
        """The linear block of a :class:`fohw.HammersteinWiener` (linearised at its operating point).

        Parameters
        ----------
        model : HammersteinWiener or ThetaHW

        Returns
        -------
        LinearBlock

        Examples
        --------
        >>> import fohw
        >>> from fohw.model.lagged.hw_frequency import LinearBlock
        >>> blk = LinearBlock.from_model(fohw.datasets.paper_model())
        >>> blk.static_gain          # commensurate, alpha > 0: no static gain
        0.0
        """
        s = model.structure
        if s.n_inputs > 1:
            raise ParameterError(f"the model has {s.n_inputs} inputs ({', '.join(s.inputs)}): a "
                                 "LinearBlock is of a single-input model (or several inputs are "
                                 "one block per input, not written yet).")
        out_nu, in_nu = s.orders.values(model.orders)
        a_terms = [(t.lag, nu) for t, nu in zip(s.orders.output, out_nu)]
        b_terms = [(t.lag, nu) for t, nu in zip(s.orders.input, in_nu)]
        if not hasattr(model, "a"):
            # a map per lag (fohw.ThetaHW): each term's own slope, sum_j theta_jt basis_j'(0)
            qa, pb = s.layout.blocks(model.theta)
            a = [_basis_slope(s.g_basis, qa[:, t]) for t in range(qa.shape[1])]
            b = [_basis_slope(s.f_basis, pb[:, t]) for t in range(pb.shape[1])]
            return cls(a, b, a_terms, b_terms, dt=model.dt)
        return cls(model.a, model.b, a_terms, b_terms, dt=model.dt,
                   g_slope=_basis_slope(model.g_basis, model.q),
                   f_slope=_basis_slope(model.f_basis, model.p))

    # ---------------------------------------------------------------- z-domain pieces
    def _branch(self, coefs, terms, omega):
        omega = np.asarray(omega, dtype=np.float64)
        out = np.zeros(omega.shape, dtype=complex)
        for c, (lag, nu) in zip(coefs, terms):
            out += gl_operator_response([c], [nu], omega, self.dt) * np.exp(-1j * omega * self.dt * lag)
        return out

    def output_polynomial(self, omega):
        """``A(e^{j omega h})``."""
        return self._branch(self.a, self.a_terms, omega)

    def input_polynomial(self, omega):
        """``B(e^{j omega h})``."""
        return self._branch(self.b, self.b_terms, omega)

    def frequency_response(self, omega):
        """``H(e^{j omega h}) = f' B / (1 - g' A)`` at angular frequencies ``omega`` (rad / time unit).

        Parameters
        ----------
        omega : array_like
            Finite, ``0 < |omega| h < 2 pi`` (``omega = 0`` is :attr:`static_gain`); where the
            response is infinite (a pole on the unit circle) it is refused, never ``inf + nan j``.

        Returns
        -------
        ndarray of complex

        Examples
        --------
        >>> import numpy as np
        >>> from fohw.model.lagged.hw_frequency import LinearBlock
        >>> blk = LinearBlock([0.5], [1.0], [(1, 0.0)], [(1, 0.0)], dt=1.0)
        >>> z = np.exp(1j * 0.3)
        >>> bool(abs(blk.frequency_response([0.3])[0] - (1 / z) / (1 - 0.5 / z)) < 1e-15)
        True
        """
        omega = check_array(omega, "omega", ndim=None, min_length=0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            h = np.asarray(self.f_slope * self.input_polynomial(omega)
                           / (1.0 - self.g_slope * self.output_polynomial(omega)))
        bad = np.flatnonzero(~np.isfinite(h.ravel()))
        if bad.size:
            w = float(omega.ravel()[bad[0]])
            raise ParameterError(f"`omega` = {w!r}: the block's response is infinite there (1 - g' A = 0: "
                                 f"a pole on the unit circle{', an integrator' if w == 0.0 else ''}; "
                                 f"static gain {self.static_gain!r}). Give other frequencies.")
        return h

    @property
    def static_gain(self):
        """``H(1) = f' B_0 / (1 - g' A_0)`` over the order-0 terms; 0 if none; ``±inf``: an integrator."""
        a0 = sum(c for c, (_, nu) in zip(self.a, self.a_terms) if nu == 0.0)
        b0 = sum(c for c, (_, nu) in zip(self.b, self.b_terms) if nu == 0.0)
        num = self.f_slope * b0
        den = 1.0 - self.g_slope * a0
        if num == 0.0:
            return 0.0
        if den == 0.0:
            return float(np.copysign(np.inf, num))
        return float(num / den)

    def default_frequencies(self, n=400):
        """Logarithmic grid from ``10^-3`` of the Nyquist frequency up to it (``pi / h``)."""
        nyq = np.pi / self.dt
        return np.logspace(np.log10(nyq) - 3, np.log10(nyq), check_int(n, "n", minimum=2,
                                                                        maximum=1_000_000))

    def stability(self, points=20_000):
        """BIBO stability of the block: no zero of ``1 - g' A(x)`` in ``|x| <= 1`` (module docstring).

        Parameters
        ----------
        points : int, optional
            Grid points on the circle (half logarithmic towards the branch point ``x = 1``);
            doubled until no step of the phase exceeds ``pi / 8``.

        Returns
        -------
        StabilityVerdict

        Examples
        --------
        >>> from fohw.model.lagged.hw_frequency import LinearBlock
        >>> LinearBlock([1.5], [1.0], [(1, 0.0)], [(1, 0.0)], dt=1.0).stability().zeros_inside
        1
        """
        if not np.any(self.a != 0.0) or self.g_slope == 0.0:
            return StabilityVerdict(True, 0, False, 1.0)
        n = int(points)
        while True:
            half = n // 2
            # theta in (0, pi]: logarithmic down to 1e-300 near the branch point x = 1 (where
            # (1 - x)^nu ~ theta^nu moves slowly for small nu), then uniform; the lower half of
            # the circle is the conjugate (real coefficients).
            theta = np.unique(np.r_[np.logspace(-300, 0, half) * np.pi,
                                    np.linspace(0.0, np.pi, half)[1:]])
            omega = theta / self.dt
            d = 1.0 - self.g_slope * self.output_polynomial(omega)
            scale = 1.0 + sum(abs(self.g_slope * c) * np.abs(gl_operator_response([1.0], [nu], omega,
                                                                                    self.dt))
                              for c, (_, nu) in zip(self.a, self.a_terms))
            d0 = 1.0 - self.g_slope * sum(c for c, (_, nu) in zip(self.a, self.a_terms) if nu == 0.0)
            rel = np.abs(d) / scale
            min_rel = float(min(np.min(rel), abs(d0) / (1.0 + np.sum(np.abs(self.a)))))
            if min_rel <= MARGINAL_TOL:
                return StabilityVerdict(False, -1, True, min_rel)
            full = np.r_[d0, d]
            phase = np.unwrap(np.angle(full))
            if np.max(np.abs(np.diff(phase))) < np.pi / 8 or n >= 16 * int(points):
                break
            n *= 2
        # z = e^{j theta}, theta 0..pi; the lower half mirrors it, so the total change is twice
        # this one (D real at theta = 0 and pi). x = 1/z = e^{-j theta} runs clockwise, so each
        # zero of D inside |x| < 1 turns the phase by -2 pi.
        winding = int(round(2.0 * (phase[-1] - phase[0]) / (2 * np.pi)))
        inside = -winding
        return StabilityVerdict(inside == 0, inside, False, min_rel)


def linear_block(model):
    """The linearised linear block of a lagged HW model or an identification result.

    Parameters
    ----------
    model : HammersteinWiener, ThetaHW or IdentificationResult
        A result uses its fitted model (``result.model``, a map per lag: each term linearised
        with its own map's slope; for polynomial bases that is theta's first block, as the
        rank-one recovery of Eqs. 39–40 gives it).

    Returns
    -------
    LinearBlock

    Examples
    --------
    >>> import fohw
    >>> from fohw.model.lagged.hw_frequency import linear_block
    >>> str(linear_block(fohw.datasets.paper_model()).stability()).split()[0]
    'stable'
    """
    inner = getattr(model, "model", model)
    if not hasattr(inner, "structure") or not hasattr(inner, "theta"):
        raise ParameterError(f"`model` must be a HammersteinWiener, a ThetaHW or an identification "
                             f"result; got {type(model).__name__}.")
    return LinearBlock.from_model(inner)
