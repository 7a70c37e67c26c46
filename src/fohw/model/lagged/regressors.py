"""The information matrix of fractional differences (paper Eqs. 19–20, 25, 34–38).

Row ``k`` of the information matrix of the paper's model is

``phi[k] = [psi_1[k], …, psi_nq[k], zeta_1[k], …, zeta_np[k]]`` with
``psi_j[k] = [(Δ^α g_j(y))[k-1], …, (Δ^α g_j(y))[k-na]]`` and
``zeta_j[k] = [(Δ^α f_j(u))[k-1], …, (Δ^α f_j(u))[k-nb]]``, zero before ``k = 0``,

so that ``y = Phi @ theta + v`` for a simulated record. For a general structure
(:class:`fohw.Structure`: an order per term, an offset, estimated past levels, a sampling time)
the entry of basis signal ``s`` and term ``t`` is ``(Δ_h^{ν_t} s)[k - i_t]``, plus
``L_s h^{-ν_t} (S_inf(ν_t) - S_{k-i_t}(ν_t))`` when the past level ``L_s`` of the signal is
estimated, and the offset adds a column of ones.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

from ..._types import ArrayLike, PairLike
from ..._validation import check_array, check_inputs, check_int, check_same_length, check_scalar
from ...exceptions import DimensionError, ParameterError
from ..basis import BasisLike
from ..gl import gl_weights, gl_weights_derivative, past_transient, sampling_scale
from ..kernels import CausalConvolution, convolution_at
from ..orders import ORDER_RANGE, OrdersLike
from .structure import Structure

__all__ = ["information_matrix", "RegressorBuilder", "WindowKernel"]


class WindowKernel:
    """Exact information-vector rows of a window, from the basis signals up to the present.

    Parameters
    ----------
    lags : sequence of int
        Number of lags of each stacked basis signal (``na`` for the g-signals, ``nb`` for the
        f-signals).
    """

    def __init__(self, lags):
        self.lags = list(lags)
        self.max_lag = max(self.lags)
        self.n_params = sum(self.lags)
        self._sig_idx = np.repeat(np.arange(len(self.lags)), self.lags)
        self._lag_idx = np.concatenate([np.arange(1, m + 1) for m in self.lags])

    def rows(self, signals, k, innovation_length, weights):
        """Rows ``phi[k], …, phi[k-P+1]`` (index >= 0) for each weight vector.

        ``signals[:, t]`` holds the basis signals at time ``t``, for at least ``t = 0..k-1``;
        each weight vector has at least ``k`` entries. The GL sums are evaluated by
        :func:`fohw.model.kernels.convolution_at` (the whole past, no FFT).
        """
        n_rows = min(innovation_length, k + 1)
        if k == 0:
            return [np.zeros((1, self.n_params)) for _ in weights]
        rows = np.arange(k, k - n_rows, -1)
        t_lo = k - n_rows + 1 - self.max_lag          # earliest time a row needs
        index = (self._sig_idx[None, :], rows[:, None] - self._lag_idx[None, :] - t_lo)
        return [convolution_at(signals, w, t_lo, k - 1)[index] for w in weights]


#: Stacked basis signals up to this size are convolved in one batched FFT call (16 MB: the
#: call's transient is about four times that); larger ones one signal at a time.
_BATCHED_BYTES = 16 * 2**20


class LaggedColumns:
    """The columns of an information matrix (or of a derivative), without the ``N x n`` array.

    Column ``c`` is ``source[k - lag]`` (zero for ``k < lag``; no source: zero), plus
    ``coef * transient[k]`` when an ``extra = (coef, transient)`` is given, plus a constant
    (the offset's ones). The sources are rows of the stacked GL differences, shared by the
    columns, so rows ``start:stop`` of the matrix, ``Phi @ x`` and ``Phi.T @ r`` cost
    ``O(N n)`` and no more memory than the differences themselves.
    """

    def __init__(self, n_samples, specs):
        self.n_samples = n_samples
        self.specs = specs                  # [(source or None, lag, extra or None, constant)]

    @property
    def n_columns(self):
        return len(self.specs)

    def fill(self, start, stop, out):
        """Write rows ``start:stop`` into ``out`` (shape ``(stop - start, n_columns)``)."""
        m = stop - start
        for c, (src, lag, extra, const) in enumerate(self.specs):
            col = out[:, c]
            if src is None:
                col[:] = const
            else:
                first = min(max(lag - start, 0), m)          # rows before the first lagged sample
                col[:first] = 0.0
                if first < m:
                    col[first:] = src[start + first - lag:stop - lag]
            if extra is not None:
                coef, transient = extra
                if src is None:
                    col[:] = coef * transient[start:stop]
                else:
                    col += coef * transient[start:stop]
        return out

    def matvec(self, x):
        """``Phi @ x``, shape ``(N,)``."""
        n = self.n_samples
        out = np.zeros(n)
        for xc, (src, lag, extra, const) in zip(x, self.specs):
            if src is not None and lag < n:
                out[lag:] += xc * src[:n - lag]
            if extra is not None:
                out += (xc * extra[0]) * extra[1]
            if const != 0.0:
                out += xc * const
        return out

    def rmatvec(self, r):
        """``Phi.T @ r``, shape ``(n_columns,)``."""
        n = self.n_samples
        out = np.zeros(len(self.specs))
        for c, (src, lag, extra, const) in enumerate(self.specs):
            if src is not None and lag < n:
                out[c] += src[:n - lag] @ r[lag:]
            if extra is not None:
                out[c] += extra[0] * (extra[1] @ r)
            if const != 0.0:
                out[c] += const * np.sum(r)
        return out


def _evaluate(basis, x, name):
    """The basis signals of ``x``, refusing one that underflows (its column would carry nothing).

    A signal underflows when its largest value is below the smallest normal double although
    ``x`` is not zero: ``u**3`` of ``u`` in units of 1e-150, say. For a polynomial basis a
    signal that is 0 everywhere is the same underflow; a custom function may be 0 by design, and
    a zero column is then reported as rank deficiency.
    """
    values = basis.evaluate(x, name)
    peak_x = float(np.max(np.abs(x)))
    if peak_x == 0.0:
        return values
    tiny = np.finfo(np.float64).tiny
    for row, fname in zip(values, basis.names):
        peak = float(np.max(np.abs(row)))
        if peak < tiny and (peak > 0.0 or basis.is_polynomial):
            raise ParameterError(
                f"basis function {fname!r} of `{name}` underflows: its largest value is "
                f"{peak!r}, below the smallest normal double (2.2e-308), although max |{name}| = "
                f"{peak_x:.3g}; its regressors would carry no information. Rescale `{name}` "
                "(fohw's estimates rescale with the data) or use fewer basis functions.")
    return values


class RegressorBuilder:
    """Information matrices of one record for many values of the nonlinear parameters.

    The basis signals ``g_j(y)``, ``f_j(u)`` and their FFTs are computed once; each
    :meth:`matrix` call then costs one inverse FFT of the stacked signals per distinct order.
    This is what order searches, sensitivities and Jacobians use.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records, same length, finite (deviations from the operating point);
        ``u`` of shape ``(N, m)`` for a structure with ``m`` inputs.
    na, nb : int
        Output and input lag orders (``>= 1``); ``N`` must exceed both.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions.
    orders, offset, past, dt : optional
        The model class (:class:`fohw.Structure`); default the paper's commensurate model.
    structure : Structure, optional
        Instead of ``na … dt``.
    nk : int, optional
        Input delay (default 1; 0: direct feedthrough): input lags ``nk … nk + nb - 1``.

    Notes
    -----
    The columns are the linear parameters of :class:`fohw.Structure`: theta's (``[q ⊗ a,
    p ⊗ b]``, Eq. 20), then a column of ones for the offset. They depend on the nonlinear
    parameters ``params`` (the free orders, then ``u_past``, ``y_past``), given as a vector, or
    as one number when there is only one.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> rng = np.random.default_rng(0)
    >>> u, y = rng.uniform(-1, 1, 200), rng.uniform(-1, 1, 200)
    >>> builder = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> builder.matrix(0.6).shape
    (200, 10)
    >>> mixed = fohw.model.lagged.regressors.RegressorBuilder(u, y, na=2, nb=1, f_basis=1,
    ...                                                       g_basis=1, orders="mixed", offset=True)
    >>> mixed.matrix(0.4).shape, mixed.structure.linear_names[-2:]
    ((200, 7), ('b1_alpha', 'offset'))
    """

    def __init__(self, u, y, *, na=None, nb=None, f_basis=None, g_basis=None, orders=None,
                 offset=False, past="rest", dt=1.0, structure=None, nk=1):
        y = check_array(y, "y")
        if structure is None:
            na = check_int(na, "na", minimum=1)
            m = np.shape(u)[1] if np.ndim(u) == 2 else 1
            inputs = tuple(f"u{i}" for i in range(1, m + 1)) if m > 1 else None
            if inputs is None:
                nb = check_int(nb, "nb", minimum=1)
            structure = Structure.make(na=na, nb=nb, f_basis=f_basis, g_basis=g_basis,
                                       orders=orders, offset=offset, past=past, dt=dt, nk=nk,
                                       inputs=inputs)
        u = check_inputs(u, structure.n_inputs, names=structure.inputs)
        check_same_length(u, y, "u", "y")
        self.structure = structure
        na, nb = structure.na, structure.nb
        n = y.shape[0]
        if n <= structure.max_lag:
            delay = f", nk={structure.nk}" if structure.nk != 1 else ""
            raise DimensionError(f"the record must be longer than the lags: got {n} samples for "
                                 f"na={na}, nb={nb}{delay} (need at least "
                                 f"{structure.max_lag + 1}).")
        self.f_basis, self.g_basis = structure.f_basis, structure.g_basis
        self.layout = structure.layout
        self.n_samples = n
        self.u, self.y = u, y
        # Stacked basis signals: g_1(y), …, g_nq(y), f_1(u), …, f_np(u) (each input's in turn).
        if structure.n_inputs > 1:
            f_signals = [_evaluate(part, u[:, i], f"u[:, {i}]")
                         for i, part in enumerate(self.f_basis.parts)]
            self.signal_inputs = [i for i, part in enumerate(self.f_basis.parts)
                                  for _ in range(len(part))]
            input_lags = [b for b, part in zip(nb, self.f_basis.parts) for _ in range(len(part))]
        else:
            f_signals = [_evaluate(self.f_basis, u, "u")]
            self.signal_inputs = [0] * len(self.f_basis)
            input_lags = [nb] * len(self.f_basis)
        self.signals = np.vstack([_evaluate(self.g_basis, y, "y")] + f_signals)
        self._n_g = len(self.g_basis)
        self.lags = [na] * len(self.g_basis) + input_lags
        self._convolution = CausalConvolution(self.signals)
        self._row_convolutions = None
        self._window_kernel = WindowKernel(self.lags)

    # ---- the paper's commensurate model ---------------------------------------------------------
    def differences(self, alpha, *, derivative=False):
        """GL differences of all basis signals at one order, shape ``(n_g + n_f, N)``.

        With ``derivative=True``, their exact derivative with respect to the order
        (convolution with :func:`fohw.model.gl.gl_weights_derivative`). Divided by ``dt**alpha``.
        ``alpha`` must lie in :data:`fohw.model.orders.ORDER_RANGE` (``[0, 2]``), the orders
        every fohw model allows.
        """
        alpha = check_scalar(alpha, "alpha", lower=ORDER_RANGE[0], upper=ORDER_RANGE[1])
        return self._differences(alpha, derivative)

    def _differences(self, nu, derivative=False):
        n = self.n_samples
        h = self.structure.dt
        if not derivative:
            d = self._convolve(gl_weights(nu, n))
            return d if h == 1.0 else d * sampling_scale(h, nu, "dt")
        d = self._convolve(gl_weights_derivative(nu, n))
        if h == 1.0:
            return d
        return (d - np.log(h) * self._convolve(gl_weights(nu, n))) * sampling_scale(h, nu, "dt")

    def _convolve(self, weights):
        """The stacked basis signals convolved with ``weights``, shape ``(n_g + n_f, N)``.

        Records whose stacked signals exceed :data:`_BATCHED_BYTES` are convolved one signal
        at a time (the weights transformed once), so the transient is one signal's padded
        transform, not all of them (at N = 10^6 and five signals: 48 MB instead of 160 MB);
        the numbers are those of the batched call, which shorter records use (it is faster).
        """
        if self._convolution.direct or self.signals.nbytes <= _BATCHED_BYTES:
            return self._convolution(weights)
        if self._row_convolutions is None:
            self._row_convolutions = [CausalConvolution(x) for x in self.signals]
        spectrum = scipy.fft.rfft(weights, n=self._row_convolutions[0].nfft())
        out = np.empty(self.signals.shape)
        for row, conv in zip(out, self._row_convolutions):
            row[:] = conv(weights, weights_spectrum=spectrum)
        return out

    def window(self, k, innovation_length, weights):
        """Rows ``phi[k], phi[k-1], …, phi[k-P+1]`` (those with index >= 0), for given weights.

        Each row is computed exactly from the full history (no FFT), so this is what a
        recursion whose fractional order changes at every sample uses. The paper's model
        (:attr:`Structure.is_paper_model`) only.

        Parameters
        ----------
        k : int
            Current sample, ``0 <= k < N``.
        innovation_length : int
            ``P``.
        weights : sequence of ndarray
            GL weight vectors (e.g. for ``alpha`` and ``alpha + delta``), each of length at
            least ``k``.

        Returns
        -------
        rows : list of ndarray, each of shape (min(P, k + 1), n)
            One window per weight vector.
        """
        return self._window_kernel.rows(self.signals, k, innovation_length, weights)

    def lag(self, differences):
        """Arrange stacked differences into the ``(N, n)`` matrix of the commensurate model."""
        n = self.n_samples
        phi = np.zeros((n, self.layout.n_params))
        col = 0
        for row, lags in zip(differences, self.lags):
            for i in range(1, lags + 1):
                phi[i:, col] = row[: n - i]
                col += 1
        return phi

    # ---- any structure --------------------------------------------------------------------------
    def check_params(self, params):
        """The nonlinear parameters as a finite vector of :attr:`Structure.n_nonlinear` entries.

        One number is accepted when there is one nonlinear parameter. The free orders must
        lie in :data:`fohw.model.orders.ORDER_RANGE` (``[0, 2]``), as in every model.
        """
        params = np.atleast_1d(np.asarray(params, dtype=np.float64))
        k = self.structure.n_nonlinear
        if params.ndim != 1 or params.shape[0] != k:
            raise DimensionError(f"the nonlinear parameters {self.structure.nonlinear_names} "
                                 f"need {k} value(s); got {params.shape}.")
        if not np.all(np.isfinite(params)):
            raise ParameterError(f"the nonlinear parameters must be finite; got {params}.")
        lo, hi = ORDER_RANGE
        for name, value in zip(self.structure.orders.free, params):
            if not lo <= value <= hi:
                raise ParameterError(f"the order {name!r} must be in [{lo:g}, {hi:g}] (the orders "
                                     f"fohw's models allow); got {float(value)!r}.")
        return params

    def term_orders(self, params):
        """``(output orders, input orders, (u_past, y_past))`` of checked nonlinear parameters."""
        values, past = self.structure.split_nonlinear(params)
        out, inp = self.structure.orders.values(values)
        return out, inp, past

    def _past_levels(self, past):
        """Past level of every stacked basis signal, ``g_j(y_past)`` then ``f_j(u_past)``."""
        u_p, y_p = past
        return np.r_[self.g_basis.evaluate(np.array([y_p]), "y_past")[:, 0],
                     self.f_basis.evaluate(np.array([u_p]), "u_past")[:, 0]]

    def _past_slopes(self, past):
        """Derivatives ``g_j'(y_past)``, ``f_j'(u_past)`` (central differences of the basis)."""
        u_p, y_p = past
        out = []
        for basis, x, scale in ((self.g_basis, y_p, self.y), (self.f_basis, u_p, self.u)):
            peak = float(np.max(np.abs(scale)))      # the RMS without squares that underflow
            rms = peak * float(np.sqrt(np.mean(np.square(scale / peak)))) if peak else 0.0
            step = 1e-6 * max(abs(x), rms, 1e-300)
            hi = basis.evaluate(np.array([x + step]))[:, 0]
            lo = basis.evaluate(np.array([x - step]))[:, 0]
            out.append((hi - lo) / (2 * step))
        return np.r_[out[0], out[1]]

    def columns(self, params, which=None):
        """:class:`LaggedColumns` of ``Phi(params)``, or with ``which = m`` of ``dPhi/dparams[m]``.

        ``params`` must be validated (:meth:`check_params`). The differences are computed once
        (one inverse FFT of the stacked basis signals per distinct order); the columns are
        lagged views of them, so nothing of size ``N x n_linear`` is allocated here.
        """
        struct = self.structure
        n, h = self.n_samples, struct.dt
        out_nu, in_nu, past = self.term_orders(params)
        n_free = len(struct.orders.free)
        d_order = None if which is None or which >= n_free else struct.orders.free[which]
        d_past = None if which is None or which < n_free else which - n_free   # 0: u, 1: y
        levels = self._past_levels(past) if struct.past == "estimate" else None
        slopes = self._past_slopes(past) if d_past is not None else None
        cache = {}

        def diffs(nu, derivative):
            if (nu, derivative) not in cache:
                cache[nu, derivative] = self._differences(nu, derivative)
            return cache[nu, derivative]

        specs = []
        branches = ((range(self._n_g), struct.orders.output, out_nu, 1),
                    (range(self._n_g, self.signals.shape[0]), struct.orders.input, in_nu, 0))
        for signals, terms, nus, past_index in branches:
            for s in signals:
                own = 0 if past_index else self.signal_inputs[s - self._n_g]
                for term, nu in zip(terms, nus):
                    if term.input != own:          # another input's term (several inputs)
                        continue
                    i = term.lag
                    if which is None:
                        extra = (None if levels is None or levels[s] == 0.0 else
                                 (levels[s], past_transient(nu, i, n, h)))
                        specs.append((diffs(nu, False)[s], i, extra, 0.0))
                    elif d_order is not None and term.order == d_order:
                        extra = (None if levels is None or levels[s] == 0.0 else
                                 (levels[s], past_transient(nu, i, n, h, derivative=True)))
                        specs.append((diffs(nu, True)[s], i, extra, 0.0))
                    elif d_past == past_index:
                        specs.append((None, i, (slopes[s], past_transient(nu, i, n, h)), 0.0))
                    else:
                        specs.append((None, i, None, 0.0))
        if struct.offset:
            specs.append((None, 0, None, 1.0 if which is None else 0.0))
        return LaggedColumns(self.n_samples, specs)

    def _build(self, params, which=None):
        """``Phi(params)``, or with ``which = m`` its derivative with respect to ``params[m]``."""
        n = self.n_samples
        return self.columns(params, which).fill(0, n, np.zeros((n, self.structure.n_linear)))

    def matrix(self, params):
        """Information matrix, shape ``(N, n_linear)``: rows ``phi[k]`` at ``params``.

        ``params``: the nonlinear parameters (the order ``alpha`` for the paper's model).
        """
        if self.structure.is_paper_model:
            return self.lag(self.differences(np.asarray(params, dtype=float).item()
                                             if np.ndim(params) else params))
        return self._build(self.check_params(params))

    def matrix_derivatives(self, params):
        """``[dPhi/dparams[0], …]``: one ``(N, n_linear)`` array per nonlinear parameter."""
        params = self.check_params(params)
        if self.structure.is_paper_model:
            return [self.lag(self.differences(params[0], derivative=True))]
        return [self._build(params, which=m) for m in range(params.shape[0])]

    def matrix_derivative(self, alpha):
        """Exact ``d Phi / d alpha``, shape ``(N, n)``: a model with one nonlinear parameter."""
        if self.structure.n_nonlinear != 1:
            raise ParameterError(f"matrix_derivative needs one nonlinear parameter; this model "
                                 f"has {self.structure.nonlinear_names}: use "
                                 "matrix_derivatives.")
        return self.matrix_derivatives(alpha)[0]

    def jacobian(self, linear, params):
        """Jacobian of the one-step predictor ``Phi(params) @ linear``.

        The derivative with respect to ``(linear, params)``: ``[Phi, dPhi/dparams[m] @
        linear …]``, built in one ``N x (n_linear + n_nonlinear)`` array and nothing else of
        that size: the columns of ``Phi`` are written into it from the differences, and each
        derivative column is summed from the lagged derivative differences. The estimators'
        least-squares steps, their covariances and the Cramér–Rao bound all use it.

        Returns
        -------
        G : ndarray, shape (N, n_linear + n_nonlinear)
        """
        linear = check_array(linear, "linear")
        if linear.shape[0] != self.structure.n_linear:
            raise DimensionError(f"`linear` must have {self.structure.n_linear} entries "
                                 f"({self.structure.linear_names}); got {linear.shape[0]}.")
        params = self.check_params(params)
        n = linear.shape[0]
        G = np.empty((self.n_samples, n + params.shape[0]))
        self.columns(params).fill(0, self.n_samples, G[:, :n])
        for m in range(params.shape[0]):
            G[:, n + m] = self.columns(params, which=m).matvec(linear)
        return G

def information_matrix(u: ArrayLike, y: ArrayLike, alpha: float | ArrayLike, *, na: int, nb: int,
                       f_basis: BasisLike, g_basis: BasisLike, orders: OrdersLike | None = None,
                       offset: bool = False, past: str | PairLike = "rest",
                       dt: float = 1.0, nk: int = 1) -> np.ndarray:
    """Information matrix of a fractional-order Hammerstein–Wiener record.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output, same length, finite, zero before ``k = 0``.
    alpha : float or sequence
        The fractional order (paper's model), or the nonlinear parameters of the structure:
        its free orders, then ``u_past``, ``y_past`` (:class:`fohw.Structure`).
    na, nb : int
        Output and input lag orders, ``1 <= na, nb < N``.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree).
    orders, offset, past, dt : optional
        The model class (:class:`fohw.Orders`, :class:`fohw.Structure`); default the paper's
        commensurate model.
    nk : int, optional
        Input delay (default 1): the input columns are ``(Delta^nu f_j(u))[k - i]`` for
        ``i = nk … nk + nb - 1``; ``nk = 0`` includes the present input (direct feedthrough).

    Returns
    -------
    Phi : ndarray, shape (N, n)
        Row ``k`` is ``phi[k]`` of Eq. (20), columns ordered as in docs/conventions.md
        (``n = n_g*na + n_f*nb`` for the paper's model), then a column of ones for an offset;
        entries that would need samples before ``k = 0`` are zero (or the transient of the
        past levels).

    Notes
    -----
    Eqs. (19)–(20) and (34)–(38). All basis signals are differenced in one batched GL call.
    For a record simulated by :func:`fohw.simulate`, ``y - Phi @ model.theta`` equals the
    noise to rounding error.

    Examples
    --------
    >>> import numpy as np, fohw
    >>> model = fohw.HammersteinWiener([0.1, 0.2], [-0.4, -0.2], [1, 0.5], [1, 0.7, 0.35], 0.6)
    >>> u = np.random.default_rng(1).uniform(-1, 1, 500)
    >>> y = fohw.simulate(model, u)
    >>> Phi = fohw.model.lagged.regressors.information_matrix(u, y, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
    >>> bool(np.max(np.abs(y - Phi @ model.theta)) < 1e-12)
    True
    """
    return RegressorBuilder(u, y, na=na, nb=nb, f_basis=f_basis, g_basis=g_basis, orders=orders,
                            offset=offset, past=past, dt=dt, nk=nk).matrix(alpha)
