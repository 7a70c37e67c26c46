"""Simulating a model on non-uniform sampling instants ``t_0 < t_1 < … < t_{N-1}``.

Every model kind simulates on a uniform grid of step ``dt`` (sample alignment of
:mod:`fohw.model.transfer`: ``u[k]`` stands for the input on ``(t_{k-1}, t_k]``). A record whose
instants are not uniform means the same continuous-time input, held between its instants:

- ``intersample="zoh"`` (zero-order hold, the default): ``u(t) = u_k`` on ``(t_{k-1}, t_k]``,
  the kinds' own alignment (the sample closes the interval it stands for); the value at
  ``t_k`` is ``u_k``, so a direct feedthrough (a circuit's ``R0 i``) reads ``u_k`` at ``t_k``.
  MATLAB's ``iddata`` holds ``u_k`` on ``[t_k, t_{k+1})`` instead: that is this hold with the
  input one sample later (``u_k`` given at ``t_{k+1}``).
- ``intersample="foh"`` (first-order hold): ``u`` linear between ``(t_{k-1}, u_{k-1})`` and
  ``(t_k, u_k)``.

The first sample stands, as in :meth:`~fohw.Model.simulate` (where ``u[0]`` is the input on
``(-dt, 0]``), for the input on ``(t_0 - (t_1 - t_0), t_0]``: the held input starts one first
step before ``t_0``, from rest (zero input and the kind's rest state before it). A record that
starts at rest has ``u_0 = 0``. With this alignment a uniform record means the same
continuous-time input to :meth:`~fohw.Model.simulate` and to :func:`simulate_at`.

How each kind simulates on such instants is its :meth:`fohw.Model.simulate_at` hook:

- **The fine-grid scheme** (:func:`grid_simulate`, the default of every kind whose
  :meth:`~fohw.Model.config` carries ``dt``: :class:`fohw.FractionalTF`,
  :class:`fohw.FractionalHW`, a user's GL kind). The kind is rebuilt at a fine step
  ``h = median(diff(t)) / refine`` (or ``step``) and simulated on a uniform grid through
  ``t_0``; each fine sample takes the mean of the held input over its interval (exactly the
  held value where no instant falls inside; its integral is kept where one does), and the
  output at ``t_k`` is extrapolated linearly from the two grid points at or before ``t_k`` (a
  point after it already carries the next held value). The scheme is first order in ``h`` at
  every instant, the order of the GL discretisation itself (measured in
  ``docs/irregular_time.md``). With uniform instants and ``refine=1`` it *is*
  ``model.simulate(u)``, bit for bit.
- **Exact**: the RC element under either hold at any steps (:func:`rc_response_at`); the
  circuit's static part, ``R0`` and the OCV map, read at the instants
  (:meth:`fohw.EquivalentCircuit.simulate_at`; its ZARC and Warburg elements take the fine grid).
- **Refused**: the lagged :class:`fohw.HammersteinWiener` is discrete in samples (its lags are
  samples, not seconds); its error names the alternatives, :func:`resample` onto a uniform grid
  or a continuous-time kind.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._validation import check_array, check_int, check_scalar
from ..exceptions import DimensionError, ParameterError

__all__ = ["simulate_at", "jacobian_at", "grid_simulate", "rc_response_at", "resample",
           "fine_grid", "FineGrid", "check_instants", "check_intersample", "INTERSAMPLE",
           "DEFAULT_REFINE", "MAX_FINE_SAMPLES"]

#: The intersample behaviours: zero-order hold (default) and first-order hold.
INTERSAMPLE = ("zoh", "foh")
#: Default fine steps per median step of the instants (:func:`grid_simulate`).
DEFAULT_REFINE = 8
#: Most samples the fine grid may have (a record of ``N`` samples at ``refine`` needs about
#: ``N * refine``; a few very long gaps among short steps need more): beyond, the scheme is
#: refused naming ``refine`` and ``step``.
MAX_FINE_SAMPLES = 10_000_000


def check_instants(t, n_samples=None):
    """``t`` as a float array of strictly increasing finite instants (at least two), or raise.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sampling instants.
    n_samples : int, optional
        The number of samples ``t`` must have (the signals' length).

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> from fohw.model.irregular import check_instants
    >>> check_instants([0.0, 0.9, 2.1])
    array([0. , 0.9, 2.1])
    """
    t = check_array(t, "t", min_length=2)
    if n_samples is not None and t.size != n_samples:
        raise DimensionError(f"`t` must have one instant per sample: {n_samples}; got {t.size}.")
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0.0))
    if bad.size:
        k = int(bad[0])
        raise ParameterError(f"`t` must be strictly increasing; got t[{k}] = {float(t[k])!r} and "
                             f"t[{k + 1}] = {float(t[k + 1])!r} ({bad.size} step(s) <= 0 in all).")
    return t


def check_intersample(intersample):
    """``intersample`` if it is one of :data:`INTERSAMPLE`, else a ParameterError naming it."""
    if not (isinstance(intersample, str) and intersample in INTERSAMPLE):
        raise ParameterError(f"`intersample` must be one of {INTERSAMPLE}; got {intersample!r}.")
    return intersample


class FineGrid(NamedTuple):
    """The fine uniform grid of :func:`fine_grid`: ``tau_j = t0 + j step``, ``j < n``."""

    #: The fine step ``h``.
    step: float
    #: Number of fine samples (``tau_{n-1}`` is the last grid point not after the last instant).
    n: int
    #: The first grid point (``t_0`` is a grid point; the grid reaches back to the start of
    #: the first sample's interval, ``t_0 - (t_1 - t_0)``).
    t0: float

    @property
    def times(self):
        """``tau_j = t0 + j step``."""
        return self.t0 + self.step * np.arange(self.n)

    def hold(self, u, t, intersample="zoh"):
        """The input ``u`` at the instants ``t`` held onto this grid (the mean per fine interval)."""
        return _hold(u, t, self, check_intersample(intersample))

    def read(self, y, t):
        """The fine-grid output ``y`` (rows) at the instants ``t`` (extrapolated from the left)."""
        return _read(y, t, self)

    def position(self, t):
        """``(j, w)``: ``t = tau_j + w step`` with ``0 <= w < 1`` (``w = 0`` within 1e-9 of a point)."""
        pos = (np.asarray(t, dtype=np.float64) - self.t0) / self.step
        near = np.rint(pos)
        on = np.abs(pos - near) <= 1e-9 * np.maximum(1.0, near)
        j = np.where(on, near, np.floor(pos)).astype(np.int64)
        j = np.minimum(j, self.n - 1)
        w = np.where(on, 0.0, pos - j)
        return j, w


def fine_grid(t, *, refine=None, step=None, divides=0.0):
    """The fine grid of the scheme: its step and number of points.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Strictly increasing instants (:func:`check_instants`).
    refine : int, optional
        Fine steps per median step of ``t`` (default :data:`DEFAULT_REFINE`).
    step : float, optional
        The fine step itself (then ``refine`` must not be given).
    divides : float, optional
        A length the step must divide (a model's input delay): the step is shrunk to
        ``divides / ceil(divides / step)``.

    Returns
    -------
    FineGrid

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.irregular import fine_grid
    >>> g = fine_grid(np.array([0.0, 1.0, 2.2, 3.0]), refine=2)
    >>> g.step, g.n, g.position([1.0, 2.2])[0].tolist()
    (0.5, 8, [3, 5])
    """
    if step is not None and refine is not None:
        raise ParameterError(f"give `refine` or `step`, not both; got refine={refine!r} and "
                             f"step={step!r}.")
    span = float(t[-1] - t[0])
    if step is None:
        refine = DEFAULT_REFINE if refine is None else check_int(refine, "refine", minimum=1)
        h = float(np.median(np.diff(t))) / refine
    else:
        h = check_scalar(step, "step", lower=0.0, lower_inclusive=False)
        if h > span:
            raise ParameterError(f"`step` must be at most the span of `t` ({span!r}); got {h!r}.")
    if divides:
        h = divides / math.ceil(divides / h * (1.0 - 1e-12))
    back = math.ceil((t[1] - t[0]) / h * (1.0 - 1e-12)) - 1     # grid points before t_0
    n = back + int(math.floor(span / h * (1.0 + 1e-12))) + 1
    if n > MAX_FINE_SAMPLES:
        raise ParameterError(f"the fine grid would have {n} samples (span {span:g} at step {h:g}), "
                             f"more than {MAX_FINE_SAMPLES}; choose a smaller `refine` or a larger "
                             "`step`, or resample the record (fohw.model.irregular.resample).")
    return FineGrid(h, n, float(t[0]) - back * h)


def _extended(u, t):
    """``(u, t)`` with the start of the first sample's interval: ``t_0 - (t_1 - t_0)``, ``u_0``."""
    return np.concatenate([u[:1], u]), np.concatenate([[2.0 * t[0] - t[1]], t])


def _integral(u, t, x, intersample):
    """``int_{t_0}^{x} u(s) ds`` of the held input (``x`` in ``[t_0, t_{N-1}]``; 0 before)."""
    steps = np.diff(t)
    col = (lambda a: a[:, None]) if u.ndim == 2 else (lambda a: a)
    if intersample == "zoh":
        pieces = u[1:] * col(steps)
    else:
        pieces = 0.5 * (u[1:] + u[:-1]) * col(steps)
    cum = np.concatenate([np.zeros((1,) + u.shape[1:]), np.cumsum(pieces, axis=0)])
    k = np.clip(np.searchsorted(t, x, side="left"), 1, t.size - 1)   # x in (t_{k-1}, t_k]
    d = col(np.maximum(x - t[k - 1], 0.0))
    if intersample == "zoh":
        return cum[k - 1] + u[k] * d
    return cum[k - 1] + u[k - 1] * d + (u[k] - u[k - 1]) * d ** 2 / col(2.0 * steps[k - 1])


def _hold(u, t, grid, intersample):
    """The input on the fine grid.

    Fine sample ``j`` is the mean of the held input on ``(tau_j - h, tau_j]`` (zero before the
    first sample's interval).
    """
    tau = grid.times
    j, w = grid.position(t)
    on_grid = np.where(w == 0.0, tau[j], t)                 # instants within 1e-9 of a point
    if np.all(np.diff(on_grid) > 0.0):
        t = on_grid
    u, t = _extended(u, t)
    left = np.concatenate([tau[:1] - grid.step, tau[:-1]])
    k_end = np.searchsorted(t, tau, side="left")            # tau_j in (t_{k-1}, t_k]
    k_start = np.searchsorted(t, left, side="right")        # (tau_j - h)^+ in (t_{k-1}, t_k]
    if intersample == "zoh":
        out = u[k_end]
    else:
        mid = tau - 0.5 * grid.step
        out = (np.interp(mid, t, u) if u.ndim == 1 else
               np.column_stack([np.interp(mid, t, u[:, c]) for c in range(u.shape[1])]))
    out[k_end == 0] = 0.0                                   # before the first interval: rest
    # A fine interval that holds an instant (a switch of the hold, or the start): its mean by
    # the integral of the hold.
    across = np.flatnonzero(k_end != k_start)
    if across.size:
        out[across] = (_integral(u, t, tau[across], intersample)
                       - _integral(u, t, left[across], intersample)) / grid.step
    return out


def _read(y, t, grid):
    """``y`` at the instants.

    ``y[j] + w (y[j] - y[j-1])`` from the two grid points at or before each instant (never a
    point after it, which the next held value already drives).
    """
    j, w = grid.position(t)
    if y.ndim == 2:
        w = w[:, None]
    prev = y[np.maximum(j - 1, 0)]
    first = (j == 0) if y.ndim == 1 else (j == 0)[:, None]
    # before the second grid point there is no point behind: interpolate towards tau_1
    ahead = y[np.minimum(j + 1, grid.n - 1)]
    return np.where(first, y[j] + w * (ahead - y[j]), y[j] + w * (y[j] - prev))


def _at_step(model, h):
    """``model`` rebuilt at the sampling time ``h`` (same parameters and settings)."""
    config = model.config()
    if isinstance(config, dict) and config.get("dt") == h:
        return model
    if not isinstance(config, dict) or "dt" not in config:
        raise ParameterError(
            f"a {type(model).__name__} cannot be simulated at non-uniform instants: its config() "
            "has no sampling time `dt` to refine, so fohw cannot tell it is a discretised "
            "continuous-time model; resample the record to a uniform grid "
            "(fohw.model.irregular.resample), or give the kind a `dt` in config() or its own "
            "simulate_at.")
    return type(model).from_config({**config, "dt": h}).with_parameters(model.parameters)


def _prepare(model, u, t, intersample, refine, step):
    check_intersample(intersample)
    u = model.check_input(u)
    t = check_instants(t, u.shape[0])
    config = model.config()
    delay = config.get("delay") if isinstance(config, dict) else None
    grid = fine_grid(t, refine=refine, step=step, divides=float(delay or 0.0))
    dt = config.get("dt") if isinstance(config, dict) else None
    if dt and grid.step != dt and abs(grid.step - dt) <= 1e-9 * dt:
        grid = fine_grid(t, step=dt)           # the model's own step (uniform instants, refine 1)
    return u, t, grid


def grid_simulate(model, u, t, *, intersample="zoh", refine=None, step=None):
    """The output at the instants ``t`` by the fine-grid scheme (module notes).

    The default of :meth:`fohw.Model.simulate_at` for every kind whose
    :meth:`~fohw.Model.config` carries ``dt``: the kind is rebuilt at the fine step, simulated
    on the held input and read at the instants.

    Parameters
    ----------
    model : Model
    u : array_like, shape (N,) or (N, n_inputs)
        Input at the instants.
    t : array_like, shape (N,)
        Strictly increasing instants (the first sample stands for the first step before
        ``t[0]``, from rest: module notes).
    intersample : {"zoh", "foh"}, optional
        How the input is held between instants (module notes).
    refine : int, optional
        Fine steps per median step of ``t`` (default :data:`DEFAULT_REFINE`).
    step : float, optional
        The fine step itself (instead of ``refine``); shrunk to divide the model's input
        ``delay`` if it has one.

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> import numpy as np
    >>> import fohw
    >>> from fohw.model.irregular import grid_simulate
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    >>> t = np.array([0.0, 0.1, 0.2, 0.3])
    >>> bool(np.array_equal(grid_simulate(G, np.ones(4), t, refine=1), G.simulate(np.ones(4))))
    True
    """
    u, t, grid = _prepare(model, u, t, intersample, refine, step)
    y = np.asarray(_at_step(model, grid.step).simulate(_hold(u, t, grid, intersample)),
                   dtype=np.float64)
    return _read(y, t, grid)


def jacobian_at(model, u, t, *, intersample="zoh", refine=None, step=None):
    """``(yhat, J)`` at the instants for a kind on the fine-grid scheme, or ``None``.

    The fine-grid model's exact :meth:`~fohw.Model.jacobian`, read at the instants like the
    output (``J`` has one column per parameter in :attr:`~fohw.Model.parameters` order).
    ``None`` when the kind has no exact Jacobian or simulates on instants by a hook of its own
    (:func:`fohw.fit` then takes finite differences of :func:`simulate_at`).

    Examples
    --------
    >>> import numpy as np
    >>> import fohw
    >>> from fohw.model.irregular import jacobian_at
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    >>> yhat, J = jacobian_at(G, np.ones(3), [0.0, 0.1, 0.25])
    >>> J.shape                    # b0, beta0, a0, a1, alpha0, alpha1
    (3, 6)
    """
    hook = getattr(type(model), "simulate_at", None)
    if getattr(hook, "__qualname__", None) != "Model.simulate_at":     # a kind's own hook
        return None
    u, t, grid = _prepare(model, u, t, intersample, refine, step)
    out = _at_step(model, grid.step).jacobian(_hold(u, t, grid, intersample))
    if out is None:
        return None
    yhat, jac = (np.asarray(x, dtype=np.float64) for x in out)
    return _read(yhat, t, grid), _read(jac, t, grid)


def simulate_at(model, u, t, *, intersample="zoh", refine=None, step=None):
    """Simulate ``model`` at non-uniform sampling instants ``t``: its output at each instant.

    Parameters
    ----------
    model : Model
        Any kind; it simulates through its :meth:`fohw.Model.simulate_at` hook (module notes:
        the fine-grid scheme for GL kinds, exact for RC elements, refused for the lagged kind).
    u : array_like, shape (N,) or (N, n_inputs)
        The input at the instants.
    t : array_like, shape (N,)
        Strictly increasing instants; ``u[0]`` stands for the input on
        ``(t[0] - (t[1] - t[0]), t[0]]``, from rest before it (module notes).
    intersample : {"zoh", "foh"}, optional
        ``"zoh"`` (default): ``u_k`` held on ``(t_{k-1}, t_k]``; ``"foh"``: linear between
        instants.
    refine : int, optional
        Fine steps per median step of ``t`` for the fine-grid scheme (default
        :data:`DEFAULT_REFINE`; the error falls like ``1 / refine``).
    step : float, optional
        The fine step itself (instead of ``refine``).

    Returns
    -------
    ndarray, shape (N,)
        The output at ``t``.

    Raises
    ------
    ParameterError
        ``t`` not strictly increasing or not finite, an unknown ``intersample``, a kind that
        is discrete in samples (the message names the alternatives), a fine grid beyond
        :data:`MAX_FINE_SAMPLES`.
    DimensionError
        ``t`` and ``u`` of different lengths.

    Examples
    --------
    The step response of ``1 / (s^0.5 + 1)``, ``1 - erfcx(sqrt(t))``, at irregular instants
    (the unit step at ``t = 0`` is ``u = [0, 1, 1, …]``: ``u_0`` is the input before ``t_0``):

    >>> import numpy as np
    >>> from scipy.special import erfcx
    >>> import fohw
    >>> from fohw.model.irregular import simulate_at
    >>> G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    >>> t = np.array([0.0, 0.13, 0.37, 0.5, 0.94, 1.2])
    >>> u = np.array([0.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    >>> exact = 1 - erfcx(np.sqrt(t))
    >>> [round(float(np.max(np.abs(simulate_at(G, u, t, refine=r) - exact))), 4) for r in (8, 64)]
    [0.0085, 0.0012]
    """
    if not callable(getattr(model, "simulate_at", None)):
        raise ParameterError(f"`model` must be a fohw.Model (a fit's model is `result.model`); "
                             f"got {type(model).__name__}.")
    check_intersample(intersample)
    return np.asarray(model.simulate_at(u, t, intersample=intersample, refine=refine, step=step),
                      dtype=np.float64)


def _rc_coefficients(steps, tau):
    """``e = exp(-d / tau)``, ``phi = 1 - e`` and ``psi = 1 - tau phi / d`` (the ramp's weight)."""
    z = steps / tau
    e = np.exp(-z)
    phi = -np.expm1(-z)
    small = z < 1e-2
    # psi = (z - phi) / z: cancels for small z; its series z/2 - z^2/6 + z^3/24 - ... there
    psi = np.where(small, 0.0, (z - phi) / np.where(small, 1.0, z))
    zs = z[small]
    psi[small] = zs * (1 / 2 - zs * (1 / 6 - zs * (1 / 24 - zs * (1 / 120 - zs * (1 / 720)))))
    return e, phi, psi


def rc_response_at(R, tau, i, t, intersample="zoh"):
    """The voltage of an RC element ``R / (1 + tau s)`` at the instants ``t``, exact.

    Parameters
    ----------
    R, tau : float
        Resistance ``>= 0`` and time constant ``> 0``.
    i : array_like, shape (N,)
        Current at the instants.
    t : array_like, shape (N,)
        Strictly increasing instants; the element is at rest before ``t_0 - (t_1 - t_0)``.
    intersample : {"zoh", "foh"}, optional
        How the current is held between instants (module notes).

    Returns
    -------
    ndarray, shape (N,)

    Notes
    -----
    With ``Δ_k = t_k - t_{k-1}``, ``e_k = exp(-Δ_k / tau)``, and the first sample's interval
    ``(t_{-1}, t_0]``, ``t_{-1} = t_0 - Δ_1``, ``i_{-1} = i_0``, ``x_{-1} = 0`` (module notes):

    - zero-order hold (``i_k`` on ``(t_{k-1}, t_k]``): ``x_k = e_k x_{k-1} + R (1 - e_k) i_k``;
    - first-order hold: ``x_k = e_k x_{k-1} + R [(1 - e_k) i_{k-1} + psi_k (i_k - i_{k-1})]``,
      ``psi_k = 1 - tau (1 - e_k) / Δ_k`` (its series for ``Δ_k / tau < 0.01``).

    Both are the solution of ``tau x' + x = R i`` for that input, at any steps.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.irregular import rc_response_at
    >>> x = rc_response_at(2.0, 1.0, np.ones(3), [1.0, 2.0, 4.0])    # a step from t = 0
    >>> bool(np.allclose(x, 2.0 * (1 - np.exp(-np.array([1.0, 2.0, 4.0])))))
    True
    """
    check_intersample(intersample)
    R = check_scalar(R, "R", lower=0.0)
    tau = check_scalar(tau, "tau", lower=0.0, lower_inclusive=False)
    i = check_array(i, "i")
    i, t = _extended(i, check_instants(t, i.size))
    e, phi, psi = _rc_coefficients(np.diff(t), tau)
    drive = phi * i[1:] if intersample == "zoh" else phi * i[:-1] + psi * np.diff(i)
    x = np.zeros(i.size)                        # x[0]: rest before the first interval
    for k in range(1, i.size):                  # a first-order recursion: N scalar steps
        x[k] = e[k - 1] * x[k - 1] + drive[k - 1]
    return R * x[1:]


def resample(t, u, y=None, *, dt=None, intersample="zoh"):
    """A record on instants ``t`` moved onto the uniform grid ``t[0] + k dt``.

    The alternative for a kind that is discrete in samples (the lagged
    :class:`fohw.HammersteinWiener`): the input is read off its hold at the new instants
    (``zoh``: the value of the interval each grid point lies in, the module's alignment;
    ``foh``: linear interpolation), the output is interpolated linearly. Interpolating the
    output smooths its noise and changes its spectrum: a fit on resampled data is not the fit
    on the record.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing instants.
    u : array_like, shape (N,) or (N, m)
    y : array_like, shape (N,), optional
    dt : float, optional
        The new sampling time (default the median step of ``t``).
    intersample : {"zoh", "foh"}, optional

    Returns
    -------
    t_new, u_new[, y_new] : ndarray
        The grid ``t[0] + k dt`` up to ``t[-1]``, and the signals on it.

    Raises
    ------
    ParameterError
        ``dt`` is not positive, longer than the record (the grid would hold one sample), or
        so short that the grid would hold more than :data:`MAX_FINE_SAMPLES` samples.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.model.irregular import resample
    >>> t_new, u_new = resample([0.0, 0.9, 2.1, 3.0], [1.0, 2.0, 3.0, 4.0], dt=1.0)
    >>> t_new.tolist(), u_new.tolist()
    ([0.0, 1.0, 2.0, 3.0], [1.0, 3.0, 3.0, 4.0])
    """
    check_intersample(intersample)
    u = np.asarray(u)
    u = check_array(u, "u", ndim=u.ndim if u.ndim in (1, 2) else 1)
    t = check_instants(t, u.shape[0])
    if dt is None:
        dt = float(np.median(np.diff(t)))
    dt = check_scalar(dt, "dt", lower=0.0, lower_inclusive=False)
    span = float(t[-1] - t[0])
    n_new = np.floor(span / dt * (1 + 1e-12)) + 1
    if n_new < 2:
        raise ParameterError(f"`dt` = {dt!r} is longer than the record (its instants span "
                             f"{span:.6g}, from t[0] to t[-1]): the grid would hold one sample; "
                             f"give dt <= {span:.6g} (the median step is "
                             f"{float(np.median(np.diff(t))):.6g}).")
    if n_new > MAX_FINE_SAMPLES:
        raise ParameterError(f"`dt` = {dt!r} puts {n_new:.4g} samples on the record's span "
                             f"{span:.6g}, more than MAX_FINE_SAMPLES = {MAX_FINE_SAMPLES:,}; give a "
                             "longer dt.")
    t_new = t[0] + dt * np.arange(int(n_new))
    if intersample == "zoh":
        u_new = u[np.searchsorted(t, t_new, side="left")]
    elif u.ndim == 1:
        u_new = np.interp(t_new, t, u)
    else:
        u_new = np.column_stack([np.interp(t_new, t, u[:, c]) for c in range(u.shape[1])])
    if y is None:
        return t_new, u_new
    y = check_array(y, "y")
    if y.size != t.size:
        raise DimensionError(f"`y` must have one sample per instant: {t.size}; got {y.size}.")
    return t_new, u_new, np.interp(t_new, t, y)
