"""The initial state of a record: what a free run assumes about the unseen past before ``k = 0``.

A fractional model remembers its whole past (the GL sums of Eq. 4 run back to the start), so a
free run on a record must say what happened before the record began. :func:`initial_state`
answers that for an identified predictor (an :class:`fohw.IdentificationResult`) or a
:class:`fohw.HammersteinWiener`, in one of four ways (``initial=``):

``"rest"``
    The signals sat at the operating point before ``k = 0`` (the GL convention, and the
    default for a fit with ``past="rest"``). Assumes the record starts at rest; costs nothing
    in fairness (no value is taken from the record's output).
``"fitted"``
    The past levels ``(u_past, y_past)`` estimated *with the fit* (``past="estimate"``). They
    belong to the estimation record, so this is right for that record (it reproduces the
    fitted model) or for a record that begins where it began; on any other record it is a
    guess. Costs nothing in fairness on a new record, but is not a statement about it. For a
    ``past="rest"`` fit it is ``"rest"``.
``"estimate"``, or ``("estimate", n)``
    The unseen past of *this* record, fitted by least squares on this record's output with
    the model's parameters fixed, as MATLAB's ``compare(..., InitialCondition='estimate')``:
    constant levels ``u_past``, ``y_past`` before the record (the ``past="estimate"`` model of
    :class:`fohw.Structure`, whose transients are exact), and with ``n`` the last ``n`` output
    samples before the record free as well (a window of free past outputs, the input held at
    ``u_past`` there: for a record that begins in a transient). Assumes the record was
    preceded by such a past. **Costs in fairness**: ``2 + n`` values are fitted on the output
    that is then scored, so the free-run fit is no longer from the input alone (it is
    optimistic, by about as much as ``2 + n`` more parameters would be; compare models with the
    same ``initial``).
``(u_hist, y_hist)``
    Measured input and output just before the record (``initial=(u_past, y_past)``): the free run continues
    from them (for records contiguous in time). A ``past="estimate"`` fit's own levels precede
    the history (right when the history is the estimation record). Costs nothing in fairness,
    but the history must really be the record's past.

Every choice returns an :class:`InitialState`, which can be passed back as ``initial=`` to
simulate from exactly that state again (``result.simulate(u, initial=check.initial)``).
"""

from __future__ import annotations

import dataclasses
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..._validation import check_array, check_inputs, check_same_length, unpack_pair
from ...exceptions import DimensionError, ParameterError, SimulationDivergedError
from ..base import Model
from ..simulate import simulate
from .structure import Structure
from .system import HammersteinWiener

__all__ = ["InitialState", "initial_state", "simulate_from", "check_initial", "default_initial",
           "INITIAL_CHOICES"]

#: The named initial states (besides a measured history ``(u_hist, y_hist)``, an
#: ``("estimate", n)`` window and an :class:`InitialState`).
INITIAL_CHOICES = ("rest", "fitted", "estimate")
#: Solver tolerances of the least-squares fit of an initial state (``ftol``, ``xtol``, ``gtol``).
INITIAL_TOL = 1e-8
#: Singular values of the fitted state's Jacobian below this fraction of the largest count as
#: unidentified directions (its finite differences are good to about 1e-8 relative).
RANK_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class InitialState:
    """The state a free run starts from (returned by :func:`initial_state`, on ``Validation.initial``).

    Pass one back as ``initial=`` to simulate from the same state again.

    Attributes
    ----------
    kind : str
        ``"rest"``, ``"fitted"``, ``"estimate"`` or ``"history"`` (see :mod:`fohw.model.lagged.initial`).
    past : (float, float)
        The constant levels ``(u_past, y_past)`` before the record (before the window or the
        history, if any), as deviations from the operating point, like
        :attr:`IdentificationResult.past` (``(0, 0)``: rest).
    window : ndarray, shape (n,)
        ``"estimate"`` with a window: the last ``n`` outputs before the record, oldest first, in
        the data's units (empty otherwise). The input there is held at ``u_past``.
    history : (ndarray, ndarray) or None
        ``"history"``: the measured ``(u_hist, y_hist)`` just before the record (data units).
    n_estimated : int
        How many values were fitted on this record's output: ``2 + n`` for ``"estimate"``, 0
        otherwise. They are free parameters fitted on the record that is scored.
    operating_point : (float, float)
        The model's ``(u0, y0)``; ``past`` is relative to it.
    message : str
        How the state was had (for ``"estimate"``: the solver's outcome and cost).
    """

    kind: str
    past: tuple = (0.0, 0.0)
    window: np.ndarray = field(default_factory=lambda: np.zeros(0))
    history: tuple | None = None
    n_estimated: int = 0
    operating_point: tuple = (0.0, 0.0)
    message: str = ""

    @property
    def levels(self) -> tuple[float, float]:
        """``past`` in the data's units: ``(u0 + u_past, y0 + y_past)``."""
        (u0, y0), (up, yp) = self.operating_point, self.past
        return (u0 + up, y0 + yp)

    def __repr__(self):
        parts = [f"kind={self.kind!r}", f"past=({self.past[0]:.6g}, {self.past[1]:.6g})"]
        if self.window.size:
            parts.append(f"window={np.array2string(self.window, precision=4)}")
        if self.history is not None:
            parts.append(f"history={self.history[0].shape[0]} samples")
        if self.n_estimated:
            parts.append(f"n_estimated={self.n_estimated}")
        return f"InitialState({', '.join(parts)})"


def _fitted_past(model):
    s = model.structure
    if s.past != "estimate":
        return (0.0, 0.0)
    nl = np.asarray(model.nonlinear, dtype=float)
    n_free = len(s.orders.free)
    return (float(nl[n_free]), float(nl[n_free + 1]))


def check_initial(initial, *, default=None):
    """``(choice, value)`` of an ``initial`` argument, checked.

    ``choice`` is one of ``"rest"``, ``"fitted"``, ``"estimate"`` (``value``: the window
    length), ``"history"`` (``value``: the checked pair) or ``"given"`` (``value``: the
    :class:`InitialState`). ``initial=None`` gives ``(default, None)`` (``None`` when the
    caller has no default).
    """
    if initial is None:
        return default, None
    if isinstance(initial, InitialState):
        return "given", initial
    if isinstance(initial, str):
        if initial not in INITIAL_CHOICES:
            raise ParameterError(f"`initial` must be one of {INITIAL_CHOICES}, ('estimate', n), "
                                 f"(u_hist, y_hist) or an InitialState; got {initial!r}.")
        return initial, 0 if initial == "estimate" else None
    if isinstance(initial, tuple) and len(initial) == 2 and isinstance(initial[0], str):
        n = initial[1]
        if initial[0] != "estimate" or isinstance(n, bool) or not isinstance(n, numbers.Integral) \
                or n < 0:
            raise ParameterError("`initial` as a pair of a word and a number must be "
                                 "('estimate', n), n >= 0 free past output samples; got "
                                 f"{initial!r}.")
        return "estimate", int(n)
    if isinstance(initial, Mapping):
        unpack_pair(initial, "initial", "(u_hist, y_hist)")
    try:
        u_hist, y_hist = initial
    except (TypeError, ValueError):
        raise ParameterError(f"`initial` must be one of {INITIAL_CHOICES}, ('estimate', n), a "
                             "measured history (u_hist, y_hist) or an InitialState; got "
                             f"{_describe(initial)}.") from None
    u_hist = check_array(u_hist, "initial history u")
    y_hist = check_array(y_hist, "initial history y")
    check_same_length(u_hist, y_hist, "initial history u", "initial history y")
    return "history", (u_hist, y_hist)


def _describe(value):
    if isinstance(value, (str, numbers.Number)):
        return repr(value)
    if isinstance(value, (tuple, list)):
        return f"a {type(value).__name__} of {len(value)} item(s)"
    return type(value).__name__


def default_initial(model):
    """The choice ``initial=None`` stands for: ``"rest"``, or a model's own levels.

    A model (:class:`fohw.HammersteinWiener`, :class:`fohw.ThetaHW`) carries the levels it was
    written with (``"fitted"``, as
    :func:`fohw.simulate` runs it); a fit with ``past="rest"`` starts at rest. A fit with
    ``past="estimate"`` has no default: its levels belong to the estimation record, so a
    ParameterError asks which state to use.
    """
    if isinstance(model, Model):        # a model carries its levels (HammersteinWiener, ThetaHW)
        return "fitted"
    if model.structure.past != "estimate":
        return "rest"
    u_past, y_past = _fitted_past(model)
    raise ParameterError(
        f"this result was fitted with past='estimate': its levels (u_past, y_past) = "
        f"({u_past:.6g}, {y_past:.6g}) are those before the *estimation* record and are not "
        "applied to another record unless asked. Say which initial state to start from: "
        "initial='fitted' (those levels: right for the estimation record itself, or a record "
        "that begins where it began), initial='rest' (the operating point), "
        "initial='estimate' with the record's output `y` (its own levels, fitted to it), or a "
        "measured history initial=(u_hist, y_hist).")


def initial_state(model, u, y=None, initial=None) -> InitialState:
    """The state a free run of ``model`` on the record ``(u, y)`` starts from.

    Parameters
    ----------
    model : IdentificationResult or HammersteinWiener
        Anything with ``structure``, ``linear``, ``nonlinear`` and ``operating_point``.
    u : array_like, shape (N,)
        The record's input (data units).
    y : array_like, shape (N,), optional
        The record's output (data units); needed for ``"estimate"`` only, refused otherwise.
    initial : str, tuple, InitialState or None
        None (:func:`default_initial`: ``"rest"``, or a model's own levels), ``"rest"``,
        ``"fitted"``, ``"estimate"``, ``("estimate", n)``, a measured history
        ``(u_hist, y_hist)`` or an :class:`InitialState` (see the module notes for what each
        assumes and costs).

    Returns
    -------
    InitialState

    Raises
    ------
    ParameterError
        No ``initial`` for a ``past="estimate"`` fit (:func:`default_initial`); an unknown
        ``initial``; ``"estimate"`` without ``y``; ``y`` with another choice.
    DimensionError
        ``y`` and ``u`` differ in length; the record has no more samples than the unknowns of
        ``"estimate"`` (``2 + n``).

    Notes
    -----
    ``"estimate"`` minimises ``sum_k (y[k] - ysim[k])**2`` over the levels (and the window)
    by :func:`scipy.optimize.least_squares` (trust-region reflective, finite-difference
    Jacobian), the model's parameters fixed, from two starts (the record's first samples, and
    the fit's own levels or the operating point), keeping the better; a window starts from the
    levels so fitted (its outputs at ``y_past``, the same state), so it never fits worse. The
    levels are bounded to the record's range widened by its span on each side (a basis
    function far outside the data extrapolates, and the free run may blow up there). Values
    the record does not identify (singular values of the Jacobian below :data:`RANK_TOL` of
    the largest) are named in the state's ``message``. The past levels enter through
    exact GL transients (:func:`fohw.model.gl.past_transient`), the window through the
    simulator's history.

    Examples
    --------
    >>> import numpy as np, fohw

    A record that began after the levels ``u_past = 0.3``, ``y_past = -0.8``, and a fit of
    its model made with ``past="rest"``:

    >>> kw = dict(na=2, nb=2, f_basis=1, g_basis=1, orders="commensurate")
    >>> theta, alpha = [0.3, -0.2, 1.0, 0.5], 0.5
    >>> u = np.random.default_rng(0).uniform(-1, 1, 200)
    >>> y = fohw.simulate(fohw.Structure.make(past="estimate", **kw), u,
    ...                   params=[*theta, alpha, 0.3, -0.8])
    >>> res = fohw.IdentificationResult(method="varpro", structure=fohw.Structure.make(**kw),
    ...     theta=theta, orders={"alpha": alpha}, J=0.0, status=1, nit=0, nfev=0, message="",
    ...     n_samples=200)
    >>> st = res.initial_state(u, y, "estimate")
    >>> st.kind, np.round(st.past, 6).tolist(), st.n_estimated
    ('estimate', [0.3, -0.8], 2)
    >>> bool(np.max(np.abs(res.simulate(u, initial=st) - y)) < 1e-9)
    True
    """
    n_inputs = model.structure.n_inputs
    if n_inputs > 1 and (initial == "estimate" or (
            initial is not None and not isinstance(initial, (str, InitialState)))):
        what = f"initial={_describe(initial)}"
        raise ParameterError(f"{what} is implemented for single-input models; this one has "
                             f"{n_inputs} inputs (its past levels would be one per input). Use "
                             "initial='rest', or simulate a longer record that contains the "
                             "history.")
    choice, value = check_initial(initial)
    if choice is None:
        choice = default_initial(model)
    u = check_inputs(u, n_inputs, names=model.structure.inputs)
    u0, y0 = model.operating_point
    op = (float(u0) if n_inputs == 1 else tuple(float(v) for v in u0), float(y0))
    if y is not None and choice != "estimate":
        raise ParameterError(f"`y` is used only by initial='estimate' (to fit the record's "
                             f"initial state); got `y` with initial={_describe(initial)}.")
    if choice == "given":
        return value
    if choice == "rest":
        return InitialState("rest", operating_point=op, message="rest: the operating point "
                            "before k = 0.")
    if choice == "fitted":
        return InitialState("fitted", past=_fitted_past(model), operating_point=op,
                            message="the levels estimated with the fit (the estimation "
                            "record's past).")
    if choice == "history":
        return InitialState("history", past=_fitted_past(model), history=value,
                            operating_point=op, message=f"a measured history of "
                            f"{value[0].shape[0]} samples.")
    if y is None:
        raise ParameterError("initial='estimate' fits the record's initial state to its "
                             "output: pass the measured output as `y`.")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    return _estimate(model, u, y, value, op)


def _level_structure(structure):
    """``structure`` with ``past="estimate"``: it simulates from any constant past levels."""
    if structure.past == "estimate":
        return structure
    return dataclasses.replace(structure, past="estimate")


def simulate_from(model, u, state, **kwargs):
    """Free run of ``model`` on ``u`` from :class:`InitialState` ``state`` (data units).

    ``model`` as for :func:`initial_state`; ``kwargs``: ``noise``, ``noise_std``,
    ``random_state``, ``divergence_threshold`` of :func:`fohw.simulate`. A ``past="rest"``
    model at rest, and a ``past="estimate"`` model from its own levels, run exactly as
    ``fohw.simulate`` runs them (the same numbers).
    """
    s: Structure = model.structure
    linear = np.asarray(model.linear, dtype=float)
    nonlinear = np.asarray(model.nonlinear, dtype=float)
    n_free = len(s.orders.free)
    past = tuple(float(v) for v in state.past)
    history = state.history
    if state.window.size:
        u0, y0 = model.operating_point
        history = (np.full(state.window.size, u0 + past[0]), state.window)
    if isinstance(model, HammersteinWiener):       # through its rank-one blocks, as simulate
        if past != model.past:
            model = HammersteinWiener(model.a, model.b, model.p, model.q, dict(model.orders),
                                      f_basis=model.f_basis, g_basis=model.g_basis,
                                      orders=s.orders, dt=model.dt, offset=model.offset,
                                      past=past, operating_point=model.operating_point)
        return simulate(model, u, initial=history, **kwargs)
    if s.past == "rest" and past == (0.0, 0.0):
        params = np.r_[linear, nonlinear]
    else:
        params = np.r_[linear, nonlinear[:n_free], past, s.output_map_params(nonlinear)]
        s = _level_structure(s)
    return simulate(s, u, params=params, operating_point=model.operating_point,
                    initial=history, **kwargs)


def _estimate(model, u, y, n_window, op):
    import scipy.optimize

    n_unknowns = 2 + n_window
    if y.shape[0] <= n_unknowns:
        raise DimensionError(f"initial='estimate' fits {n_unknowns} unknowns (u_past, y_past"
                             f"{f' and {n_window} past outputs' if n_window else ''}) to the "
                             f"record's output, which has {y.shape[0]} sample(s): it needs "
                             f"more samples than unknowns (`initial`, `y`).")
    u0, y0 = op
    ud, yd = u - u0, y - y0
    lo = np.array([ud.min() - np.ptp(ud), yd.min() - np.ptp(yd)])
    hi = np.array([ud.max() + np.ptp(ud), yd.max() + np.ptp(yd)])
    same = hi <= lo                       # a constant signal: a unit box around it
    lo, hi = np.where(same, lo - 1.0, lo), np.where(same, hi + 1.0, hi)
    lower = np.r_[lo, np.full(n_window, lo[1])]
    upper = np.r_[hi, np.full(n_window, hi[1])]
    penalty = np.full(y.shape[0], 1e3 * max(float(np.ptp(y)), float(np.max(np.abs(yd))), 1.0))

    def state_of(x):
        return InitialState("estimate", past=(float(x[0]), float(x[1])),
                            window=np.asarray(x[2:], dtype=float) + y0,
                            n_estimated=n_unknowns, operating_point=op)

    def residual(x):
        try:
            return y - simulate_from(model, u, state_of(x))
        except SimulationDivergedError:
            return penalty

    if n_window:             # from the levels alone (nested: the window can only do better)
        past = _estimate(model, u, y, 0, op).past
        starts = [np.r_[past, np.full(n_window, past[1])]]
    else:
        starts = [np.r_[ud[0], yd[0]], np.r_[_fitted_past(model)]]
    best = None
    for x0 in starts:
        ls = scipy.optimize.least_squares(residual, np.clip(x0, lower, upper), jac="2-point",
                                          method="trf", bounds=(lower, upper), x_scale="jac",
                                          ftol=INITIAL_TOL, xtol=INITIAL_TOL, gtol=INITIAL_TOL,
                                          max_nfev=50 * n_unknowns)
        if best is None or ls.cost < best.cost:
            best = ls
    state = state_of(best.x)
    rms = float(np.sqrt(2.0 * best.cost / y.shape[0]))
    sv = np.linalg.svd(np.asarray(best.jac, dtype=float), compute_uv=False)
    # numerical rank: the finite-difference Jacobian is good to about 1e-8 relative
    rank = int(np.sum(sv > sv[0] * RANK_TOL)) if sv.size and sv[0] > 0 else 0
    unidentified = "" if rank == n_unknowns else (
        f"; only {rank} of the {n_unknowns} values are identified by this record (the "
        "Jacobian is rank deficient: e.g. input and output terms of the same lags and orders "
        "see the two levels only through one combination), so this state is one of many that "
        "give the same free run")
    return dataclasses.replace(state, message=(
        f"fitted by least squares on this record's output ({n_unknowns} values: "
        f"{'; '.join(['u_past, y_past'] + ([f'{n_window} past outputs'] if n_window else []))}); "
        f"free-run RMSE {rms:.4g} at the estimate; solver: {best.message.rstrip('.')}"
        f"{unidentified}."))
