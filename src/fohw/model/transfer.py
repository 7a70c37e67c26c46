"""Fractional transfer functions ``G(s) = sum_j b_j s^{beta_j} / sum_i a_i s^{alpha_i} e^{-s tau}``.

The continuous-time model class of FOMCON's ``fotf`` objects, simulated by the Grünwald–Letnikov
(GL) discretisation of its differential equation ``sum_i a_i D^{alpha_i} y = sum_j b_j D^{beta_j}
u(t - tau)`` (paper Eqs. 1–5 for the GL difference; this class is *not* the paper's lagged model,
see SPEC Sec. 3 and ``docs/transfer_functions.md``).

Sample alignment (the convention every method follows): ``t_k = k dt``; ``y[k]`` approximates
``y(t_k)``; each GL difference uses the current sample (implicit, backward-difference rule), so
``y[k]`` depends on ``u[0..k]`` and ``u[k]`` stands for the input on ``(t_{k-1}, t_k]``. Signals are
zero before ``k = 0``. At ``alpha = 1`` this is the backward Euler rule: an integer-order ``G``
simulates exactly as ``scipy.signal.cont2discrete(..., method="backward_diff")`` followed by
``scipy.signal.dlsim``. The unit step ``H(t)`` (0 for ``t <= 0``, 1 for ``t > 0``) is therefore
``u = [0, 1, 1, …]`` and the unit impulse ``u = [0, 1/dt, 0, …]``.
"""

from __future__ import annotations

import numbers

import numpy as np
import scipy  # submodules (scipy.fft, .signal, ...) load on first use: import time

from .._validation import check_array, check_int, check_scalar
from ..exceptions import DimensionError, ParameterError, SimulationDivergedError
from .base import Model
from .frequency_response import gl_operator_response, operator_response
from .gl import gl_weights, gl_weights_derivative, sampling_scale
from .kernels import causal_product, series_divide, series_reciprocal
from .orders import ORDER_RANGE
from .parameters import Parameter, Parameters
from .transfer_stability import commensurate_base, matignon_roots, rhp_zero_count

__all__ = ["FractionalTF", "operator_weights", "delay_samples", "tf_sensitivities", "NUM_ORDER_RANGE",
           "TF_ORDER_LIMIT", "DIVERGENCE_FACTOR"]

# Orders closer than this are one term (their coefficients are summed).
ORDER_TOL = 1e-12
#: Every order of a FractionalTF lies in ``[-TF_ORDER_LIMIT, TF_ORDER_LIMIT]`` (denominator orders in
#: ``[0, TF_ORDER_LIMIT]``). Not the lagged model's :data:`fohw.model.orders.ORDER_RANGE` ``[0, 2]``,
#: which bounds one GL operator of one lagged term: a transfer function's orders add under a series
#: connection (``G1 * G2``, ``feedback``), and the fit's default bounds reach 3. Beyond 20 the GL
#: weights (up to ``2**order``) and ``dt**-order`` leave double precision at ordinary ``dt``; already
#: an integer polynomial of degree 5 simulates with lost digits at ``dt = 0.01``.
TF_ORDER_LIMIT = 20.0
#: Integer orders make the GL weights a polynomial; up to this many terms :meth:`FractionalTF.simulate`
#: runs the recursion itself (``scipy.signal.lfilter``) and direct sums, not the FFT divide and
#: conquer, which lost 5 digits on ``1/(s + 1)^5`` expanded at ``dt = 0.01`` (1.2e-4 on an output
#: of 0.18 after 300 samples, against 2e-9) and every digit after 2000 samples.
POLYNOMIAL_MAX = 64
#: Default divergence bound of :meth:`FractionalTF.simulate`: ``|y[k]|`` at most this times the
#: largest magnitude that drives the implicit recursion, as in :func:`fohw.simulate`.
DIVERGENCE_FACTOR = 1e8
# A delay counts as a multiple of dt when delay/dt is within this of an integer.
DELAY_TOL = 1e-9
#: Default bounds of a numerator order ``beta_j``: the order range mirrored, ``(-2, 2)``. A
#: numerator order may be negative (a fractional integral, e.g. a Warburg term ``s^{-1/2}``);
#: denominator orders take :data:`fohw.model.orders.ORDER_RANGE` ``[0, 2]`` like every other order.
NUM_ORDER_RANGE = (-ORDER_RANGE[1], ORDER_RANGE[1])


def operator_weights(coefs, orders, h, n):
    """GL weights of ``sum_i coefs[i] D^{orders[i]}``: ``sum_i coefs[i] h^-orders[i] beta^(orders[i])``.

    Parameters
    ----------
    coefs, orders : array_like, shape (m,)
        Coefficients and orders (any real orders; negative ones are fractional sums).
    h : float
        Sampling time.
    n : int
        Number of weights.

    Returns
    -------
    ndarray, shape (n,)
        ``(sum_i coefs[i] D^{orders[i]} x)[k] = sum_{j=0}^{k} w[j] x[k-j]``.

    Examples
    --------
    >>> from fohw.model.transfer import operator_weights
    >>> operator_weights([1.0, 1.0], [1.0, 0.0], 0.5, 3)     # D + 1 with h = 0.5
    array([ 3., -2.,  0.])
    """
    out = np.zeros(int(n))
    for c, a in zip(np.atleast_1d(coefs), np.atleast_1d(orders)):
        out += (float(c) * sampling_scale(float(h), float(a), "dt")) * gl_weights(float(a), int(n))
    return out


def delay_samples(delay, h):
    """``delay / h`` as an int, or a :class:`~fohw.exceptions.ParameterError` if not a multiple.

    Parameters
    ----------
    delay : float
        Input delay, ``>= 0``.
    h : float
        Sampling time.

    Returns
    -------
    int

    Examples
    --------
    >>> from fohw.model.transfer import delay_samples
    >>> delay_samples(0.3, 0.1)
    3
    """
    ratio = float(delay) / float(h)
    k = int(round(ratio))
    if abs(ratio - k) > DELAY_TOL * max(1.0, abs(ratio)):
        raise ParameterError(f"`delay` must be a multiple of the sampling time for the GL simulation; "
                             f"got delay = {delay!r} and dt = {h!r} (ratio {ratio:.6g}).")
    return k


def _check_positive(value, name, allow_none=True):
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.number)):
        raise ParameterError(f"`{name}` must be a positive real number; got {value!r}.")
    value = float(value)
    if not np.isfinite(value) or value <= 0.0:
        raise ParameterError(f"`{name}` must be positive and finite; got {value!r}.")
    return value


def _polynomial(w):
    """``w`` without its trailing zeros (the GL weights of integer orders end)."""
    nz = np.flatnonzero(w)
    return w[:nz[-1] + 1] if nz.size else w[:1]


def _is_inf(value):
    return isinstance(value, (float, np.floating)) and value == np.inf


def _vector(x, name):
    try:
        arr = np.atleast_1d(np.asarray(x, dtype=np.float64))
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be a sequence of real numbers; got {x!r}.") from None
    if arr.ndim != 1 or arr.size == 0:
        raise DimensionError(f"`{name}` must be a non-empty 1-D sequence; got shape {arr.shape}.")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ParameterError(f"`{name}` must contain only finite values; got {arr[bad]!r} at index {bad}.")
    return arr.copy()


def _names(m, k):
    """The parameter names of ``m`` numerator and ``k`` denominator terms, in order."""
    return (tuple(f"b{j}" for j in range(m)) + tuple(f"beta{j}" for j in range(m))
            + tuple(f"a{i}" for i in range(k)) + tuple(f"alpha{i}" for i in range(k)))


def _order(name, value, order_range):
    """An order parameter: bounds ``order_range`` (widened to hold ``value``), fixed at 0."""
    lo, hi = order_range
    return Parameter(name, value, bounds=(min(lo, value), max(hi, value)), fixed=value == 0.0,
                     order=True)


def _input(u, name="u"):
    try:
        u = np.asarray(u, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"`{name}` must be an array of real numbers; got {type(u).__name__}.") from None
    if u.ndim != 1 or u.size == 0:
        raise DimensionError(f"`{name}` must be a non-empty 1-D array; got shape {u.shape}.")
    if not np.all(np.isfinite(u)):
        bad = int(np.flatnonzero(~np.isfinite(u))[0])
        raise ParameterError(f"`{name}` must contain only finite values; got {u[bad]!r} at index {bad}.")
    return u


def _merge(coefs, orders):
    """Sum the coefficients of equal orders; sort by decreasing order."""
    idx = np.argsort(-orders, kind="stable")
    coefs, orders = coefs[idx], orders[idx]
    out_c, out_o = [], []
    for c, o in zip(coefs, orders):
        if out_o and abs(out_o[-1] - o) <= ORDER_TOL * max(1.0, abs(o)):
            out_c[-1] += c
        else:
            out_c.append(float(c))
            out_o.append(float(o))
    return np.array(out_c), np.array(out_o)


def _drop_zeros(coefs, orders):
    keep = coefs != 0.0
    if not np.any(keep):
        return np.array([0.0]), np.array([0.0])
    return coefs[keep], orders[keep]


def _term_text(c, o):
    if o == 0:
        return f"{c:g}"
    power = "s" if o == 1 else f"s^{o:g}"
    if c == 1:
        return power
    if c == -1:
        return "-" + power
    return f"{c:g} {power}"


def _poly_text(coefs, orders):
    text = " + ".join(_term_text(c, o) for c, o in zip(coefs, orders))
    return text.replace("+ -", "- ")


def tf_sensitivities(num, num_orders, den, den_orders, wd, x, h, *, orders=True):
    """``d x / d (num, num_orders, den, den_orders)`` of ``x = G wd`` (GL discretisation).

    Parameters
    ----------
    num, num_orders, den, den_orders : ndarray
        ``G``'s terms (any order; equal orders need not be merged).
    wd : ndarray, shape (N,)
        The input, already delayed.
    x : ndarray, shape (N,)
        ``G``'s output for ``wd``.
    h : float
        Sampling time.

    orders : bool, optional
        False: the coefficients' columns only.

    Returns
    -------
    ndarray, shape (N, 2 m + 2 k)
        Columns ``b_0…, beta_0…, a_0…, alpha_0…`` (module notes for the formulas); with
        ``orders=False`` shape ``(N, m + k)``, columns ``b_0…, a_0…``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.transfer import tf_sensitivities
    >>> x = np.array([0.5, 0.75, 0.875])                  # 1 / (s + 1), h = 1, a unit step
    >>> tf_sensitivities(np.ones(1), np.zeros(1), np.ones(2), np.array([1.0, 0.0]),
    ...                  np.ones(3), x, 1.0)[:, 0]       # d x / d b0 = x / b0
    array([0.5  , 0.75 , 0.875])
    """
    n = wd.shape[0]
    c = operator_weights(den, den_orders, h, n)
    if c[0] == 0.0 or not np.isfinite(c[0]):
        raise ParameterError(f"the implicit GL step of `G` is singular for dt = {h!r}.")
    r = series_reciprocal(c, n)
    nfft = scipy.fft.next_fast_len(3 * n - 2, real=True)
    rr = scipy.fft.rfft(r, nfft)
    ww = rr * scipy.fft.rfft(wd, nfft)
    xx = -rr * scipy.fft.rfft(x, nfft)
    log_h = np.log(h)
    cols = []
    for coefs, nus, spec in ((num, num_orders, ww), (den, den_orders, xx)):
        block_c, block_o = [], []
        for cf, nu in zip(coefs, nus):
            s = h ** (-nu)
            w = gl_weights(nu, n)
            block_c.append(scipy.fft.irfft(spec * scipy.fft.rfft(s * w, nfft), nfft)[:n])
            if orders:
                dw = gl_weights_derivative(nu, n) - log_h * w
                block_o.append(scipy.fft.irfft(spec * scipy.fft.rfft(cf * s * dw, nfft), nfft)[:n])
        cols += block_c + block_o
    return np.column_stack(cols)


class FractionalTF(Model):
    """A fractional transfer function ``G(s) = sum_j b_j s^{beta_j} / sum_i a_i s^{alpha_i} e^{-s delay}``.

    Parameters
    ----------
    num, num_orders : array_like, shape (m,)
        Numerator coefficients ``b_j`` and their orders ``beta_j`` in ``[-20, 20]``
        (:data:`TF_ORDER_LIMIT`). Orders may be negative (a fractional integral such as the
        Warburg term ``sigma s^{-1/2}``).
    den, den_orders : array_like, shape (n,)
        Denominator coefficients ``a_i`` and orders ``alpha_i`` in ``[0, 20]`` (a negative
        denominator order is the same model with numerator and denominator multiplied by
        ``s^{-alpha}``: write it that way). The coefficient of the highest denominator order must
        be non-zero. The one rule for a transfer function's orders: denominator in ``[0, 20]``,
        numerator in ``[-20, 20]``; orders add under :meth:`__mul__` and :meth:`feedback`, so they
        are not confined to the lagged model's per-term range ``[0, 2]``.
    dt : float, optional
        Sampling time used by :meth:`simulate` (and :meth:`step`, :meth:`impulse`) when they are
        not given one. Required by :func:`fohw.fit` and every verb that calls
        ``simulate(u)`` (a clear error otherwise).
    delay : float, optional
        Input delay ``tau >= 0``; the simulation needs it to be a multiple of the sampling time.

    Attributes
    ----------
    num, num_orders, den, den_orders : ndarray
        The terms after merging equal orders and dropping zero coefficients, sorted by
        decreasing order (read-only copies).
    dt, delay : float or None, float
    parameters : Parameters
        The terms as given (before merging), named ``b0, b1, …`` (numerator coefficients),
        ``beta0, …`` (their orders), ``a0, …`` (denominator coefficients), ``alpha0, …`` (their
        orders), indexed in the order given. By default every coefficient is free except the
        normalising denominator coefficient (the one of the lowest order: numerator and
        denominator can be scaled together), and every order is free except those that are 0.
        Orders are bounded by the one order range: denominator orders by
        :data:`fohw.model.orders.ORDER_RANGE` ``[0, 2]``, numerator orders by
        :data:`NUM_ORDER_RANGE` ``(-2, 2)``; an order given outside that range widens its own
        bound to its value. Change any of this with
        ``G.with_parameters(G.parameters.replace(name, fixed=..., bounds=..., tie=...))``.

    Notes
    -----
    Simulation: the GL discretisation of ``sum_i a_i D^{alpha_i} y = sum_j b_j D^{beta_j} u`` with
    the current sample on both sides, ``sum_k c[k] y[n-k] = sum_k d[k] u[n-k]`` where ``c`` and
    ``d`` are the combined weights :func:`operator_weights`. The recursion is solved as a power
    series quotient (:func:`fohw.model.kernels.series_divide`), ``O(N log^2 N)``. The
    method is first order in ``dt`` (measured in ``docs/transfer_functions.md``). Sample
    alignment: see the module docstring.

    A :class:`fohw.Model`: :func:`fohw.fit` estimates its free parameters by simulation error
    with the exact Jacobian (:meth:`jacobian`), starting from a scan of the free orders with
    the coefficients of each grid point from the linear equation error (:meth:`linear_start`).

    Examples
    --------
    >>> import numpy as np
    >>> import fohw
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.01)   # 1 / (s^0.5 + 1)
    >>> print(G)
    1 / (s^0.5 + 1)
    >>> G.dcgain, G.is_stable()
    (1.0, True)
    >>> y = G.step(np.array([0.0, 1.0, 2.0]))
    >>> np.round(y, 3)            # exact: 1 - E_0.5(-t^0.5) = 0, 0.573, 0.664
    array([0.   , 0.572, 0.663])
    """

    def __init__(self, num, num_orders, den, den_orders, *, dt=None, delay=0.0):
        b = _vector(num, "num")
        beta = _vector(num_orders, "num_orders")
        a = _vector(den, "den")
        alpha = _vector(den_orders, "den_orders")
        if b.shape != beta.shape:
            raise DimensionError(f"`num` and `num_orders` must have the same length; got {b.size} "
                                 f"and {beta.size}.")
        if a.shape != alpha.shape:
            raise DimensionError(f"`den` and `den_orders` must have the same length; got {a.size} "
                                 f"and {alpha.size}.")
        if np.any(alpha < 0):
            bad = float(alpha[np.argmin(alpha)])
            raise ParameterError(f"`den_orders` must be non-negative; got {bad!r}. Multiply numerator "
                                 "and denominator by s^(-that order) to write the same model.")
        for name, orders, lo in (("num_orders", beta, -TF_ORDER_LIMIT), ("den_orders", alpha, 0.0)):
            far = np.flatnonzero(np.abs(orders) > TF_ORDER_LIMIT)
            if far.size:
                raise ParameterError(
                    f"`{name}` must lie in [{lo:g}, {TF_ORDER_LIMIT:g}]; got {float(orders[far[0]])!r} at "
                    f"index {int(far[0])}. A transfer function's orders are bounded by fohw.model.transfer."
                    "TF_ORDER_LIMIT: beyond it dt**-order and the GL weights leave double precision.")
        # The terms as given name the parameters (b0 is num[0], ...); the merged ones simulate.
        self._terms = tuple(x.copy() for x in (b, beta, a, alpha))
        a, alpha = _merge(a, alpha)
        if a[0] == 0.0:
            raise ParameterError(f"`den`: the leading coefficient (of s^{alpha[0]:g}, the highest "
                                 "denominator order) is zero; drop that term.")
        self._den, self._den_orders = _drop_zeros(a, alpha)
        self._num, self._num_orders = _drop_zeros(*_merge(b, beta))
        self._dt = _check_positive(dt, "dt")
        if isinstance(delay, (bool, np.bool_)) or not isinstance(delay, (numbers.Real, np.number)):
            raise ParameterError(f"`delay` must be a real number; got {delay!r}.")
        delay = float(delay)
        if not np.isfinite(delay) or delay < 0:
            raise ParameterError(f"`delay` must be finite and non-negative; got {delay!r}.")
        if self._dt is not None:
            delay_samples(delay, self._dt)
        self._delay = delay
        for arr in (self._num, self._num_orders, self._den, self._den_orders, *self._terms):
            arr.setflags(write=False)

    # ------------------------------------------------------------------ attributes
    num = property(lambda self: self._num, doc="Numerator coefficients (decreasing order).")
    num_orders = property(lambda self: self._num_orders, doc="Numerator orders (decreasing).")
    den = property(lambda self: self._den, doc="Denominator coefficients (decreasing order).")
    den_orders = property(lambda self: self._den_orders, doc="Denominator orders (decreasing).")
    dt = property(lambda self: self._dt, doc="Default sampling time, or None.")
    delay = property(lambda self: self._delay, doc="Input delay.")

    def __repr__(self):
        def fmt(x):
            return "[" + ", ".join(repr(float(v)) for v in x) + "]"
        return (f"FractionalTF({fmt(self._num)}, {fmt(self._num_orders)}, {fmt(self._den)}, "
                f"{fmt(self._den_orders)}, dt={self._dt!r}, delay={self._delay!r})")

    def __str__(self):
        num = _poly_text(self._num, self._num_orders)
        den = _poly_text(self._den, self._den_orders)
        num = f"({num})" if len(self._num) > 1 else num
        den = f"({den})" if len(self._den) > 1 else den
        text = num if (len(self._den) == 1 and self._den[0] == 1 and self._den_orders[0] == 0) \
            else f"{num} / {den}"
        if self._delay:
            text += f" · exp(-{self._delay:g} s)"
        return text

    # ------------------------------------------------------------------ the Model protocol
    @property
    def parameters(self):
        """The terms as given, named ``b0…``, ``beta0…``, ``a0…``, ``alpha0…`` (see the class).

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
        >>> G.parameters.free_names                    # a1 normalises; beta0 = 0 is fixed
        ('b0', 'a0', 'alpha0')
        >>> G.parameters["alpha0"].bounds
        (0.0, 2.0)
        """
        b, beta, a, alpha = self._terms
        normaliser = int(np.argmin(alpha))
        pars = [Parameter(f"b{j}", v) for j, v in enumerate(b.tolist())]
        pars += [_order(f"beta{j}", v, NUM_ORDER_RANGE) for j, v in enumerate(beta.tolist())]
        pars += [Parameter(f"a{i}", v, fixed=i == normaliser) for i, v in enumerate(a.tolist())]
        pars += [_order(f"alpha{i}", v, ORDER_RANGE) for i, v in enumerate(alpha.tolist())]
        return Parameters(pars)

    def with_parameters(self, values):
        """A copy with new values (a mapping ``name -> float`` or a :class:`fohw.Parameters`).

        ``dt`` and ``delay`` are kept. A :class:`fohw.Parameters` also sets which parameters
        are free, fixed, tied and their bounds (:func:`fohw.fit` holds them).

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
        >>> print(G.with_parameters({"a0": 3.0, "alpha0": 0.5}))
        1 / (3 s^0.5 + 1)
        """
        m, k = self._terms[0].size, self._terms[2].size
        if isinstance(values, Parameters):
            if values.names != _names(m, k):
                self.parameters.merged(values)              # raises naming the difference
            v = values.valuesdict()
            for name, par in values.items():               # ties applied (fohw.fit's are)
                if par.tie is not None:
                    v[name] = par.tie[1] * v[par.tie[0]]
        else:
            v = self.parameters.with_values(values).valuesdict()
        return FractionalTF([v[f"b{j}"] for j in range(m)], [v[f"beta{j}"] for j in range(m)],
                            [v[f"a{i}"] for i in range(k)], [v[f"alpha{i}"] for i in range(k)],
                            dt=self._dt, delay=self._delay)

    def config(self):
        """``{"dt", "delay", "n_num", "n_den"}``: the settings that are not parameters.

        ``n_num`` and ``n_den`` (the numbers of terms as given) let :meth:`from_config` rebuild
        the parameter names.
        """
        return {"dt": self._dt, "delay": self._delay, "n_num": int(self._terms[0].size),
                "n_den": int(self._terms[2].size)}

    @classmethod
    def from_config(cls, config):
        """A transfer function with :meth:`config`'s settings and default values (1, order 0)."""
        config = dict(config)
        try:
            m, k = int(config.pop("n_num")), int(config.pop("n_den"))
        except (KeyError, TypeError, ValueError):
            raise ParameterError("a FractionalTF's config needs integer 'n_num' and 'n_den' (its "
                                 f"numbers of terms); got {config!r}.") from None
        return cls(np.ones(m), np.zeros(m), np.ones(k), np.zeros(k), **config)

    def check_input(self, u):
        """``u`` checked as a 1-D signal; refused when the model has no ``dt`` to simulate with."""
        if self._dt is None:
            raise ParameterError("this FractionalTF has no sampling time: fohw.fit and the other "
                                 "verbs simulate it with its own `dt`; build it with "
                                 "FractionalTF(..., dt=...).")
        return super().check_input(u)

    def _delayed(self, u, h):
        u = _input(u)
        shift = delay_samples(self._delay, h)
        ud = np.zeros(u.size)
        if shift < u.size:
            ud[shift:] = u[:u.size - shift]
        return ud

    def jacobian(self, u):
        """``(yhat, J)``: the free run and its exact derivative by every parameter.

        With ``c`` and ``d`` the GL weights of the denominator and numerator
        (:func:`operator_weights`), ``R = 1 / c`` (power-series reciprocal) and ``W_nu`` the
        weights of ``dt^{-nu} D^nu``: ``d yhat / d b_j = R * W_{beta_j} * u``,
        ``d yhat / d beta_j = R * b_j (d W_{beta_j} / d beta_j) * u``, ``d yhat / d a_i =
        -R * W_{alpha_i} * yhat`` and ``d yhat / d alpha_i = -R * a_i (d W_{alpha_i} / d alpha_i)
        * yhat``, each a causal convolution by one zero-padded FFT product.

        Parameters
        ----------
        u : array_like, shape (N,)
            Input (the model's ``dt`` and ``delay`` apply).

        Returns
        -------
        yhat : ndarray, shape (N,)
        J : ndarray, shape (N, len(parameters))
            Columns in :attr:`parameters` order (fixed ones included).

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0], dt=1.0)
        >>> yhat, J = G.jacobian(np.ones(3))
        >>> J[:, 0]                                  # d yhat / d b0 = yhat / b0
        array([0.5  , 0.75 , 0.875])
        """
        h = self._resolve_dt(None)
        ud = self._delayed(u, h)
        yhat = self.simulate(u, divergence_threshold=np.inf)   # the free run, as fit scores it
        with np.errstate(over="ignore", invalid="ignore"):
            return yhat, tf_sensitivities(*self._terms, ud, yhat, h)

    def check_settings(self, parameters):
        """Refuse a tie between an order and a coefficient, naming the parameter.

        A tie joins two orders or two coefficients; an order tied to a coefficient mixes a
        dimensionless exponent with a gain.
        """
        for name, par in parameters.items():
            if par.tie is not None and par.order != parameters[par.tie[0]].order:
                raise ParameterError(f"{name!r} is tied to {par.tie[0]!r}: a tie joins two orders "
                                     "or two coefficients, not an order and a coefficient.")

    def linear_start(self, u, y):
        """The model with its free coefficients from the linear equation error (or ``None``).

        At the current orders, ``sum_i a_i W_{alpha_i} y - sum_j b_j W_{beta_j} u`` is linear in
        the coefficients; its least-squares solution (fixed and tied coefficients honoured,
        clipped into the bounds) is the start :func:`fohw.fit` ranks beside the model itself
        at each point of its scan of the orders. ``None`` when no coefficient is free or a
        coefficient is tied to an order.

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0], dt=0.05)
        >>> u = np.random.default_rng(0).standard_normal(300)
        >>> start = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.6, 0.0], dt=0.05)
        >>> print(start.linear_start(u, G.simulate(u)))   # exact from noiseless data
        1 / (2 s^0.6 + 1)
        """
        params = self.parameters
        m, k = self._terms[0].size, self._terms[2].size
        t_all = params.tie_matrix()
        coef_idx = np.r_[0:m, 2 * m:2 * m + k]
        order_idx = np.r_[m:2 * m, 2 * m + k:2 * m + 2 * k]
        t_coef = t_all[coef_idx]
        free_coef = np.flatnonzero(np.any(t_coef != 0, axis=0))
        if free_coef.size == 0 or np.any(t_all[np.ix_(order_idx, free_coef)] != 0):
            return None
        h = self._resolve_dt(None)
        ud = self._delayed(u, h)
        y = _input(y, "y")
        if y.size != ud.size:
            raise DimensionError(f"`u` and `y` must have the same length; got {ud.size} and {y.size}.")
        n = y.size
        b, beta, a, alpha = self._terms
        theta = np.array(list(params.valuesdict().values()))
        names = params.names
        free_idx = np.array([names.index(f) for f in params.free_names], dtype=int)
        lower, upper = params.free_bounds()
        with np.errstate(over="ignore", invalid="ignore"):
            cols = [-causal_product(operator_weights([1.0], [nu], h, n), ud, n) for nu in beta]
            cols += [causal_product(operator_weights([1.0], [nu], h, n), y, n) for nu in alpha]
            mat = np.column_stack(cols)
            base = theta[coef_idx] - t_coef[:, free_coef] @ theta[free_idx[free_coef]]
            lhs = mat @ t_coef[:, free_coef]
            rhs = -mat @ base
            scale = np.linalg.norm(lhs, axis=0)
        scale[scale == 0] = 1.0
        if not (np.all(np.isfinite(lhs)) and np.all(np.isfinite(rhs)) and np.all(np.isfinite(scale))):
            return None                  # the equations overflow: no linear start, not an error
        try:
            sol = np.linalg.lstsq(lhs / scale, rhs, rcond=None)[0] / scale
        except np.linalg.LinAlgError:
            return None
        p = theta[free_idx].copy()
        p[free_coef] = np.clip(sol, lower[free_coef], upper[free_coef])
        p = np.where(np.isfinite(p), p, theta[free_idx])
        try:
            return self.with_parameters(params.with_free(p))
        except ParameterError:        # e.g. a highest denominator coefficient solved to 0
            return None

    # ------------------------------------------------------------------ time domain
    def _resolve_dt(self, dt):
        dt = _check_positive(dt, "dt")
        if dt is None:
            dt = self._dt
        if dt is None:
            raise ParameterError("`dt` is needed: pass dt=... here or to FractionalTF(...).")
        return dt

    def simulate(self, u, dt=None, *, initial=None, divergence_threshold=None):
        """Output for the input samples ``u`` (zero initial conditions), by the GL discretisation.

        Parameters
        ----------
        u : array_like, shape (N,)
            Input samples ``u[k]``, standing for the input on ``(t_{k-1}, t_k]``.
        dt : float, optional
            Sampling time (default: the model's ``dt``).
        initial : None or "rest", optional
            The state before ``k = 0``: only rest (zero signals) is implemented.
        divergence_threshold : float, optional
            The output is declared divergent when ``|y[k]|`` exceeds this or is not finite.
            Default: ``1e8`` (:data:`DIVERGENCE_FACTOR`) times the output scale of a bounded
            response, ``max |f| / min(|c[0]|, |sum_k c[k]|)`` (``f`` the GL-filtered input, ``c``
            the denominator's weights over the record: ``c[0] = sum_i a_i dt^{-alpha_i}`` at the
            first sample, ``sum_k c[k]`` once settled), so the test means the same in every unit
            and catches exponential growth, as in :func:`fohw.simulate`; a pole at ``s = 0`` (an
            integrator: ``sum_k c[k] -> 0``) widens it with the record. Pass ``np.inf`` for no bound.

        Returns
        -------
        y : ndarray, shape (N,)
            ``y[k]`` approximates ``y(t_k)``, ``t_k = k dt``. Samples before the input (delayed)
            first differs from zero are exactly 0, so prepending zeros to ``u`` shifts ``y`` by
            as many samples, bit for bit.

        Raises
        ------
        ParameterError
            No sampling time; a delay that is not a multiple of ``dt``; ``u`` not finite; the
            implicit step is singular (``sum_i a_i dt^{-alpha_i} = 0``); ``dt**-order``
            overflows; an ``initial`` other than rest.
        SimulationDivergedError
            The output grew past ``divergence_threshold`` (an unstable model for this input).

        Notes
        -----
        Solves ``sum_{k'<=k} c[k'] y[k-k'] = sum_{k'<=k} d[k'] u[k-k'-n_delay]`` (GL weights of
        denominator and numerator, :func:`operator_weights`) by power-series division in
        ``O(N log^2 N)``; every sample equals the implicit recursion
        ``y[k] = (f[k] - sum_{j>=1} c[j] y[k-j]) / c[0]`` to rounding error; integer orders (a
        polynomial of at most 64 weights, :data:`POLYNOMIAL_MAX`) run that recursion itself,
        which keeps the digits an expanded polynomial has. The solve starts at the
        first sample the input reaches (the samples before are exactly zero by causality): the
        FFT products would otherwise leave rounding noise of ``1e-16`` of the largest value there,
        which an unstable model amplifies (measured: ``1e-13`` before the delay, and an output that
        changed 1.5 to 1e15 times when 1 to 64 zeros were prepended, on an unstable improper
        model with a delay).

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])     # 1 / (s + 1)
        >>> G.simulate([1.0, 1.0, 1.0], dt=1.0)                             # backward Euler
        array([0.5  , 0.75 , 0.875])
        """
        if not (initial is None or (isinstance(initial, str) and initial == "rest")):
            raise ParameterError("a FractionalTF simulates from rest (zero signals before k = 0): "
                                 f"`initial` must be None or 'rest'; got {initial!r}.")
        h = self._resolve_dt(dt)
        u = check_array(u, "u")
        if divergence_threshold is not None and not _is_inf(divergence_threshold):
            divergence_threshold = check_scalar(divergence_threshold, "divergence_threshold",
                                                lower=0.0, lower_inclusive=False)
        n = u.size
        shift = delay_samples(self._delay, h)
        c0 = float(np.sum([a * sampling_scale(h, o, "dt") for a, o in zip(self._den, self._den_orders)]))
        if c0 == 0.0:
            raise ParameterError(f"the implicit GL step is singular for dt = {h!r}: sum_i a_i dt^(-alpha_i)"
                                 " = 0 (`den`); choose another dt.")
        y = np.zeros(n)
        reached = np.flatnonzero(u[:max(n - shift, 0)])
        if reached.size == 0:                           # the (delayed) input never leaves 0
            return y
        first = int(reached[0])
        start = shift + first                           # y[:start] = 0 exactly (causality)
        m = n - start
        ud = u[first:first + m]
        c = operator_weights(self._den, self._den_orders, h, m)
        with np.errstate(over="ignore", invalid="ignore"):
            if np.all(self._num_orders == 0.0):             # a constant numerator: no convolution
                f = float(np.sum(self._num)) * ud
            else:
                d = _polynomial(operator_weights(self._num, self._num_orders, h, m))
                f = np.convolve(d, ud)[:m] if d.size <= POLYNOMIAL_MAX else causal_product(d, ud, m)
            c_short = _polynomial(c)
            y[start:] = (scipy.signal.lfilter([1.0], c_short, f) if c_short.size <= POLYNOMIAL_MAX
                         else series_divide(f, c))
            # The output scale of a bounded response: |f| / |c[0]| at the first sample, |f| / |sum c|
            # once settled (a slow stable model, an integrator: sum c -> 0 makes the bound infinite).
            gain = min(abs(c[0]), abs(float(np.sum(c))))
            drive = float(np.max(np.abs(f))) / gain if gain > 0.0 else np.inf
        threshold = DIVERGENCE_FACTOR * drive if divergence_threshold is None else divergence_threshold
        escaped = ~(np.abs(y) <= threshold)             # also catches nan
        if np.any(escaped):
            k = int(np.flatnonzero(escaped)[0])
            raise SimulationDivergedError(k, float(y[k]), threshold, "transfer_function")
        return y

    def _grid(self, t, dt):
        try:
            t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        except (TypeError, ValueError):
            raise ParameterError(f"`t` must be an array of times; got {type(t).__name__}.") from None
        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ParameterError(f"`t` must be a non-empty 1-D array of finite times >= 0; got {t!r}.")
        dt = _check_positive(dt, "dt")
        h = dt if dt is not None else self._dt
        if h is None:
            if t.size < 2 or t[0] != 0.0:
                raise ParameterError("`t` must start at 0 with at least two equally spaced times when "
                                     "no dt is given (pass dt=... or FractionalTF(..., dt=...)).")
            h = float(t[1] - t[0])
            _check_positive(h, "t[1] - t[0]")
        k = np.rint(t / h)
        if np.any(np.abs(t / h - k) > 1e-9 * np.maximum(1.0, k)):
            raise ParameterError(f"`t` must lie on the sampling grid k * dt with dt = {h!r}.")
        return h, k.astype(np.int64)

    def step(self, t, dt=None, *, divergence_threshold=None):
        """Unit-step response at the times ``t`` (on the sampling grid ``k dt``).

        Parameters
        ----------
        t : array_like of float
            Times ``>= 0``, multiples of the sampling time.
        dt : float, optional
            Sampling time (default: the model's ``dt``, else ``t[1] - t[0]`` of an equally
            spaced ``t`` starting at 0).
        divergence_threshold : float, optional
            As in :meth:`simulate` (``np.inf``: the growing response of an unstable model).

        Returns
        -------
        ndarray, shape of ``t``
            The response to ``H(t)`` (0 for ``t <= 0``, 1 after): the simulation of
            ``u = [0, 1, 1, …]`` read at ``t / dt``; ``0`` (to rounding) at ``t = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0], [0.5])       # s^-0.5: 2 sqrt(t / pi)
        >>> np.round(G.step([0.0, 1.0], dt=0.001), 4), round(2 / np.pi ** 0.5, 4)
        (array([0.    , 1.1282]), 1.1284)
        """
        h, k = self._grid(t, dt)
        u = np.ones(int(k.max()) + 1)
        u[0] = 0.0
        y = self.simulate(u, h, divergence_threshold=divergence_threshold)
        y[0] = 0.0                          # f[0] = 0 exactly; the FFT leaves ~1e-17
        return y[k]

    def impulse(self, t, dt=None, *, divergence_threshold=None):
        """Unit-impulse response at the times ``t``: the simulation of ``u = [0, 1/dt, 0, …]``.

        Parameters
        ----------
        t : array_like of float
            Times ``>= 0``, multiples of the sampling time.
        dt : float, optional
            As in :meth:`step`.
        divergence_threshold : float, optional
            As in :meth:`simulate` (``np.inf``: the growing response of an unstable model).

        Returns
        -------
        ndarray, shape of ``t``
            The first difference of :meth:`step` divided by ``dt``; ``0`` at ``t = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])    # exp(-t)
        >>> np.round(G.impulse([1.0, 2.0], dt=0.001), 3), np.round(np.exp([-1.0, -2.0]), 3)
        (array([0.368, 0.135]), array([0.368, 0.135]))
        """
        h, k = self._grid(t, dt)
        u = np.zeros(int(k.max()) + 1)
        if u.size > 1:
            u[1] = 1.0 / h
        y = self.simulate(u, h, divergence_threshold=divergence_threshold)
        y[0] = 0.0                          # f[0] = 0 exactly; the FFT leaves ~1e-17
        return y[k]

    # ------------------------------------------------------------------ frequency domain
    def frequency_response(self, omega):
        """``G(j omega)``, exact (principal branch ``(j omega)^alpha = omega^alpha e^{j alpha pi/2}``).

        The :meth:`fohw.Model.frequency_response` hook: :meth:`bode` and :meth:`nyquist` draw it.

        Parameters
        ----------
        omega : array_like
            Finite angular frequencies (rad per time unit); negative ones give the complex
            conjugate. At ``omega = 0`` the value is the limit :attr:`dcgain`.

        Returns
        -------
        ndarray of complex, shape of ``omega``

        Raises
        ------
        ParameterError
            ``omega`` not real numbers or not finite; ``omega = 0`` where ``G`` has a pole at
            ``s = 0`` (an integrator, a Warburg term: the response is infinite there, never
            returned as ``inf`` or ``nan``); a response beyond the largest double.

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])
        >>> G.frequency_response([1.0])
        array([0.5-0.5j])
        """
        omega = check_array(omega, "omega", ndim=None, min_length=0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g = self._ratio(omega, operator_response(self._num, self._num_orders, omega),
                            operator_response(self._den, self._den_orders, omega))
        if self._delay:
            g = g * np.exp(-1j * omega * self._delay)
        return g

    def _ratio(self, omega, num, den):
        """``num / den``; ``G(0)`` is :attr:`dcgain` (a limit); an infinite value is refused."""
        g = np.asarray(num / den, dtype=complex)
        zero = omega == 0.0
        if np.any(zero) and np.isfinite(self.dcgain):
            g[zero] = self.dcgain
        bad = np.flatnonzero(~np.isfinite(g.ravel()))
        if bad.size:
            i = int(bad[0])
            w = float(omega.ravel()[i])
            where = f"`omega` = {w!r} (index {i})" if omega.ndim else f"`omega` = {w!r}"
            if w == 0.0:
                raise ParameterError(
                    f"{where}: G has a pole at s = 0 (dcgain = {self.dcgain!r}, G ~ s^"
                    f"{self._num_orders[-1] - self._den_orders[-1]:g} there), so its response is "
                    "infinite; give frequencies above 0.")
            if np.ravel(den)[i] == 0.0 and np.isfinite(np.ravel(num)[i]):
                raise ParameterError(f"{where}: the denominator is zero there (a pole on the "
                                     "imaginary axis), so the response is infinite.")
            raise ParameterError(
                f"{where}: the response is beyond the largest double (|omega|^order overflows for "
                f"the orders {self._num_orders.tolist()} / {self._den_orders.tolist()}); give "
                "frequencies nearer 1 or rescale the time unit.")
        return g

    def discrete_frequency_response(self, omega, dt=None):
        """Frequency response of the GL-discretised system that :meth:`simulate` runs.

        Parameters
        ----------
        omega : array_like
            Finite angular frequencies, ``|omega| dt < 2 pi``; as in :meth:`frequency_response`,
            ``omega = 0`` gives :attr:`dcgain` and an infinite response is refused.
        dt : float, optional
            Sampling time (default: the model's ``dt``).

        Returns
        -------
        ndarray of complex
            ``sum_j b_j s_h^{beta_j} / sum_i a_i s_h^{alpha_i} e^{-j omega delay}`` with
            ``s_h = (1 - e^{-j omega dt}) / dt``; tends to :meth:`frequency_response` as
            ``dt -> 0``.

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> abs(G.discrete_frequency_response([1.0], dt=1e-4) - G.frequency_response([1.0]))[0] < 1e-4
        np.True_
        """
        h = self._resolve_dt(dt)
        shift = delay_samples(self._delay, h)
        omega = check_array(omega, "omega", ndim=None, min_length=0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g = self._ratio(omega, gl_operator_response(self._num, self._num_orders, omega, h),
                            gl_operator_response(self._den, self._den_orders, omega, h))
        return g * np.exp(-1j * omega * h * shift) if shift else g

    def default_frequencies(self, n=400):
        """A logarithmic grid two decades beyond the corner frequencies where terms balance.

        Parameters
        ----------
        n : int, optional
            Number of frequencies, 2 to 1 000 000.

        Returns
        -------
        ndarray, shape (n,)

        Examples
        --------
        >>> import fohw
        >>> w = fohw.FractionalTF([1.0], [0.0], [10.0, 1.0], [1.0, 0.0]).default_frequencies(5)
        >>> float(w[0]), float(w[-1])
        (0.001, 10.0)
        """
        n = check_int(n, "n", minimum=2, maximum=1_000_000)
        corners = []
        for c, o in ((self._num, self._num_orders), (self._den, self._den_orders)):
            for i in range(len(c)):
                for j in range(i):
                    if c[i] != 0 and c[j] != 0 and o[i] != o[j]:
                        corners.append((abs(c[i]) / abs(c[j])) ** (1.0 / (o[j] - o[i])))
        lo, hi = (min(corners), max(corners)) if corners else (1.0, 1.0)
        return np.logspace(np.log10(lo) - 2, np.log10(hi) + 2, n)

    @property
    def dcgain(self):
        """Static gain ``lim_{s -> 0} G(s)``: ``b_0 / a_0`` of the lowest orders, 0 or ±inf.

        Examples
        --------
        >>> import fohw
        >>> fohw.FractionalTF([2.0], [0.0], [1.0, 4.0], [0.7, 0.0]).dcgain
        0.5
        """
        b_lo, beta_lo = self._num[-1], self._num_orders[-1]
        a_lo, alpha_lo = self._den[-1], self._den_orders[-1]
        if b_lo == 0.0:
            return 0.0
        if abs(beta_lo - alpha_lo) <= ORDER_TOL:
            return float(b_lo / a_lo)
        return 0.0 if beta_lo > alpha_lo else float(np.copysign(np.inf, b_lo / a_lo))

    def commensurate_order(self, max_denominator=100):
        """Commensurate base ``q`` of the denominator orders, or ``None`` (see :func:`commensurate_base`).

        Parameters
        ----------
        max_denominator : int, optional
            Largest denominator of the rational approximations of the orders.

        Returns
        -------
        float or None

        Examples
        --------
        >>> import fohw
        >>> fohw.FractionalTF([1.0], [0.0], [1.0, 2.0, 1.0], [1.2, 0.8, 0.0]).commensurate_order()
        0.4
        """
        return commensurate_base(self._den_orders, max_denominator=max_denominator)

    def poles(self, max_denominator=100):
        """Poles on the principal Riemann sheet (commensurate denominators only).

        Parameters
        ----------
        max_denominator : int, optional
            For :meth:`commensurate_order`.

        Returns
        -------
        ndarray of complex
            ``s = lambda^{1/q}`` for the roots ``lambda`` of the polynomial in ``s^q`` with
            ``|arg lambda| < q pi`` (the others lie on other sheets and do not show in the response).

        Raises
        ------
        ParameterError
            The denominator orders are not commensurate (use :meth:`is_stable`).

        Examples
        --------
        >>> import fohw
        >>> fohw.FractionalTF([1.0], [0.0], [1.0, 3.0, 2.0], [2.0, 1.0, 0.0]).poles()
        array([-2.+0.j, -1.+0.j])
        """
        q = self.commensurate_order(max_denominator)
        if q is None:
            raise ParameterError(f"`den_orders` {self._den_orders.tolist()} are not commensurate "
                                 f"(no base 1/d with d <= {max_denominator}): the poles are not roots of a "
                                 "polynomial; is_stable() uses the argument principle instead.")
        roots, _ = matignon_roots(self._den, self._den_orders, q)
        keep = np.abs(np.angle(roots)) <= q * np.pi * (1.0 + 1e-12)    # q = 1: the negative axis
        roots = roots[keep]
        s = np.abs(roots) ** (1.0 / q) * np.exp(1j * np.angle(roots) / q)
        return np.sort_complex(s)

    def is_stable(self, method="auto", max_denominator=100):
        """Whether every pole lies in the open left half of the principal sheet.

        Parameters
        ----------
        method : {"auto", "matignon", "argument"}, optional
            ``"matignon"``: the roots ``lambda`` of the polynomial in ``s^q`` satisfy
            ``|arg lambda| > q pi / 2`` (commensurate orders only); ``"argument"``: the argument
            principle counts no zero of the denominator in ``Re s >= 0``
            (:func:`fohw.model.transfer_stability.rhp_zero_count`); ``"auto"``: Matignon when the
            orders are commensurate, the argument principle otherwise.
        max_denominator : int, optional
            For :meth:`commensurate_order`.

        Returns
        -------
        bool
            ``False`` also for a pole at ``s = 0`` (``G ~ s^{-nu}``, an integrator). This is the
            pole condition; an improper ``G`` (numerator order above the denominator's) passes it
            though its response to a bounded input need not stay bounded.

        Examples
        --------
        >>> import fohw
        >>> fohw.FractionalTF([1.0], [0.0], [1.0, -1.0], [0.5, 0.0]).is_stable()     # s^0.5 - 1
        False
        >>> fohw.FractionalTF([1.0], [0.0], [1.0, 0.5], [2 ** 0.5, 0.0]).is_stable()
        True
        """
        if method not in ("auto", "matignon", "argument"):
            raise ParameterError(f"`method` must be 'auto', 'matignon' or 'argument'; got {method!r}.")
        lowest = self._den_orders[-1]
        if self._num[0] != 0.0 and self._num_orders[-1] < lowest - ORDER_TOL:
            return False                              # G ~ s^(beta - alpha) with beta < alpha at 0
        den, orders = self._den, self._den_orders - lowest
        if orders.size == 1:
            return True
        q = commensurate_base(orders, max_denominator=max_denominator)
        if method == "matignon" or (method == "auto" and q is not None):
            if q is None:
                raise ParameterError("`method`='matignon' needs commensurate `den_orders`; got "
                                     f"{self._den_orders.tolist()}.")
            return matignon_roots(den, orders, q)[1]
        return rhp_zero_count(den, orders) == 0

    # ------------------------------------------------------------------ arithmetic
    def _join(self, other, what):
        if not isinstance(other, FractionalTF):
            other = FractionalTF([float(other)], [0.0], [1.0], [0.0])
        if self._dt is not None and other.dt is not None and self._dt != other.dt:
            raise ParameterError(f"{what}: the sampling times differ ({self._dt!r} and {other.dt!r}).")
        dt = self._dt if self._dt is not None else other.dt
        return other, dt

    @staticmethod
    def _from_terms(num, num_orders, den, den_orders, dt, delay):
        shift = min(0.0, float(np.min(den_orders)))          # keep den orders >= 0
        return FractionalTF(num, np.asarray(num_orders) - shift, den, np.asarray(den_orders) - shift,
                            dt=dt, delay=delay)

    @staticmethod
    def _product(c1, o1, c2, o2):
        return np.outer(c1, c2).ravel(), np.add.outer(o1, o2).ravel()

    def __mul__(self, other):
        """Series connection ``G1 G2`` (delays add)."""
        if not isinstance(other, (FractionalTF, numbers.Real, np.number)):
            return NotImplemented
        other, dt = self._join(other, "series connection")
        num, num_orders = self._product(self._num, self._num_orders, other.num, other.num_orders)
        den, den_orders = self._product(self._den, self._den_orders, other.den, other.den_orders)
        return self._from_terms(num, num_orders, den, den_orders, dt, self._delay + other.delay)

    __rmul__ = __mul__

    def __add__(self, other):
        """Parallel connection ``G1 + G2`` (equal delays only: otherwise the sum leaves the class)."""
        if not isinstance(other, (FractionalTF, numbers.Real, np.number)):
            return NotImplemented
        other, dt = self._join(other, "parallel connection")
        if other.delay != self._delay:
            raise ParameterError(f"parallel connection: the delays differ ({self._delay!r} and "
                                 f"{other.delay!r}); the sum is not a fractional transfer function.")
        n1, o1 = self._product(self._num, self._num_orders, other.den, other.den_orders)
        n2, o2 = self._product(other.num, other.num_orders, self._den, self._den_orders)
        den, den_orders = self._product(self._den, self._den_orders, other.den, other.den_orders)
        return self._from_terms(np.concatenate([n1, n2]), np.concatenate([o1, o2]), den, den_orders,
                                dt, self._delay)

    __radd__ = __add__

    def __neg__(self):
        return FractionalTF(-self._num, self._num_orders, self._den, self._den_orders,
                            dt=self._dt, delay=self._delay)

    def __sub__(self, other):
        if not isinstance(other, (FractionalTF, numbers.Real, np.number)):
            return NotImplemented
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def feedback(self, other=1.0, sign=-1):
        """Closed loop ``G / (1 - sign G H)`` (negative feedback by default).

        Parameters
        ----------
        other : FractionalTF or float, optional
            The feedback path ``H`` (default 1: unity feedback).
        sign : {-1, 1}, optional
            ``-1`` for negative feedback.

        Returns
        -------
        FractionalTF

        Raises
        ------
        ParameterError
            A delay in the loop (``exp(-s tau)`` in the denominator leaves the class).

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0], [0.5])          # s^-0.5
        >>> print(G.feedback())
        1 / (s^0.5 + 1)
        """
        if sign not in (-1, 1):
            raise ParameterError(f"`sign` must be -1 or 1; got {sign!r}.")
        other, dt = self._join(other, "feedback")
        if self._delay or other.delay:
            raise ParameterError("feedback: a delay inside the loop puts exp(-s tau) in the "
                                 f"denominator (delays {self._delay!r}, {other.delay!r}); not in this "
                                 "class.")
        num, num_orders = self._product(self._num, self._num_orders, other.den, other.den_orders)
        d1, o1 = self._product(self._den, self._den_orders, other.den, other.den_orders)
        d2, o2 = self._product(self._num, self._num_orders, other.num, other.num_orders)
        return self._from_terms(num, num_orders, np.concatenate([d1, -sign * d2]),
                                np.concatenate([o1, o2]), dt, 0.0)

    # ------------------------------------------------------------------ figures and export
    def response_label(self):
        """``str(G)``: the curve's name in :meth:`bode` and :meth:`nyquist` (fohw.Model's, inherited)."""
        return str(self)

    def oustaloup(self, band=(1e-3, 1e3), order=5, method="oustaloup"):
        """Integer-order approximation in a frequency band (FOMCON ``oustapp``).

        Parameters
        ----------
        band : (float, float), optional
            ``(omega_b, omega_h)``.
        order : int, optional
            ``N``: each fractional power gets ``2N + 1`` zeros and poles.
        method : {"oustaloup", "refined"}, optional
            Oustaloup's filter or Xue's refined filter.

        Returns
        -------
        fohw.model.oustaloup.OustaloupApproximation

        Examples
        --------
        >>> import fohw
        >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
        >>> approx = G.oustaloup((1e-3, 1e3), order=5)
        >>> round(approx.max_relative_error(band=(1e-1, 1e1)), 4)      # a decade inside the band
        0.0036
        """
        from .oustaloup import oustaloup_approximation

        return oustaloup_approximation(self, band=band, order=order, method=method)
