"""The alternating identification driver (paper Section 4, Steps 1–9 and Table 1).

``identify`` estimates ``theta`` by multi-innovation gradient descent (:mod:`fohw.estimators.migd`) and
the fractional order by the multi-innovation Levenberg–Marquardt step (:mod:`fohw.estimators.milm`),
alternately, under one of two schedules the paper describes:

``"recursive"`` (Table 1, the default)
    At every sample ``k``: rebuild the innovation window ``Phi(P, k)`` at the current
    ``alpha`` (from the full memory, with the GL weights expanded in alpha to within a proven
    ``1e-16`` of the exact ones: :mod:`fohw.model.gl_expansion`, ``O(M N log N)`` per pass),
    update ``theta`` (Eqs. 29–31), then update ``alpha`` by Eq. (48) on the same window with
    the new ``theta``. One outer iteration is one pass over the record; ``max_iter`` passes at
    most (default 1: Table 1 as printed).
``"iterative"`` (Steps 1–9)
    Outer iteration ``m``: an ``alpha`` step (Steps 3–5), then a full MIGD pass over the
    record at that ``alpha`` (Steps 6–7), then ``J`` (Eq. 41, Step 8); stop when the relative
    change of ``J`` is at most ``tol`` (Step 9).

Where the paper is ambiguous, the reading closest to the text is the default and the other is
an option:

* ``alpha0`` is not given in the paper; the default is the middle of ``alpha_bounds`` (0.5 for
  the paper's ``(0, 1)``).
* ``alpha_window`` (iterative schedule): ``"innovation"`` (default) uses Eq. (48) as printed,
  the last ``P`` samples at the current ``k`` — at ``m = 1`` that is ``k = 0`` (Step 1 sets
  ``k = 1``), afterwards the end of the record; ``"record"`` uses every sample, i.e.
  Eqs. (46a–b) summed over the record (a damped Gauss–Newton step on Eq. 41). The recursive
  schedule always uses the last ``P`` samples (Table 1, lines 20–26).
* ``restart_r``: ``r`` continues across passes (default; Table 1 sets ``r(0) = 1`` once) or
  restarts at 1 every pass.
* ``sensitivity``: the finite difference of Eq. (44) with ``delta_alpha = 1e-3`` (default) or
  the exact derivative of the GL weights.
* The order of the two steps follows each source: ``theta`` then ``alpha`` in Table 1;
  ``alpha`` then ``theta`` in Steps 3–6.

The baselines of Fig. 6 are named configurations of the same code:
``method="single_innovation_gradient"`` is ``"hybrid"`` with ``P = 1``, and
``method="single_innovation_lm"`` applies the step of Eq. (48) with ``P = 1``: to
``(theta, alpha)`` jointly at every sample under the recursive schedule; under the iterative
schedule, an alpha step as in the hybrid, then a pass of Eq. (48) steps on theta at that alpha
(:func:`fohw.estimators.milm.milm_pass`, where the hybrid makes an MIGD pass).

Each method's settings are a frozen dataclass (:class:`HybridOptions`,
:class:`SingleInnovationGradientOptions`, :class:`SingleInnovationLMOptions`); an option a
method does not have is an error (:mod:`fohw.estimators.options`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._base import REQUIRED, BaseEstimator, check_is_fitted
from .._validation import AlphaBounds
from ..exceptions import ParameterError
from ..model.gl_expansion import ExpandedWindows, GLExpansion
from ..results import Status
from ._common import check_finite_estimate, finish, paper_model_only
from .migd import NORMALISATIONS, migd_pass, migd_update
from .milm import SENSITIVITIES, alpha_update, milm_pass, milm_step
from .options import (
    ALPHA0,
    FORGETTING,
    INNOVATION_LENGTH,
    POSITIVE,
    Boolean,
    Choice,
    Integer,
    Method,
    MethodOptions,
    Real,
)
from .problem import fit_method

__all__ = ["HybridOptions", "SingleInnovationGradientOptions", "SingleInnovationLMOptions",
           "run_alternation", "HybridIdentifier", "SCHEDULES", "METHODS"]

SCHEDULES = ("recursive", "iterative")
ALPHA_WINDOWS = ("innovation", "record")
_DEFAULT_MAX_ITER = {"recursive": 1, "iterative": 50}


@dataclass(frozen=True, kw_only=True)
class SingleInnovationLMOptions(MethodOptions):
    """Options of ``method="single_innovation_lm"`` (and the base of the paper's methods).

    Attributes
    ----------
    schedule : {"recursive", "iterative"}
        Table 1 (default) or Steps 1–9 (see the module notes).
    alpha0 : float or None
        Initial fractional order, strictly inside ``alpha_bounds``; default (None) their middle.
    max_iter : int or None
        Outer iterations: passes over the record. Default 1 for ``"recursive"`` (Table 1 as
        printed), 50 for ``"iterative"``.
    tol : float
        Stop when ``|J_m - J_{m-1}| / |J_{m-1}| <= tol`` (Step 9), ``tol > 0``; default 1e-4.
    p0 : float
        ``theta(0) = 1/p0`` in every entry (the paper's notation; default ``1e6``).
    lm_lambda : float
        LM damping ``lambda > 0`` (default 1, Table 1).
    delta_alpha : float
        Step of Eq. (44) (default ``1e-3``, Table 1).
    sensitivity : {"finite_difference", "exact"}
        Eq. (44) (default) or the exact derivative of the GL weights.
    alpha_window : {"innovation", "record"}
        Samples of the alpha step in the iterative schedule (see the module notes).
    """

    constraints = {"schedule": Choice(SCHEDULES), "alpha0": ALPHA0,
                   "max_iter": Integer(1, 10**6, none=True), "tol": POSITIVE, "p0": POSITIVE,
                   "lm_lambda": POSITIVE, "delta_alpha": Real(0.0, 0.1, closed="right"),
                   "sensitivity": Choice(SENSITIVITIES), "alpha_window": Choice(ALPHA_WINDOWS)}

    schedule: str = "recursive"
    alpha0: float | None = None
    max_iter: int | None = None
    tol: float = 1e-4
    p0: float = 1e6
    lm_lambda: float = 1.0
    delta_alpha: float = 1e-3
    sensitivity: str = "finite_difference"
    alpha_window: str = "innovation"

    def complete(self, context):
        """``alpha0`` and ``max_iter`` defaults (from the bounds and the schedule); combinations."""
        if self.alpha_window == "record" and self.schedule == "recursive":
            raise ParameterError("`alpha_window='record'` applies to the iterative schedule only; "
                                 "the recursive schedule (Table 1) uses the last "
                                 "`innovation_length` samples.")
        alpha0 = (float(0.5 * (context.lower[0] + context.upper[0])) if self.alpha0 is None
                  else self.alpha0)
        max_iter = _DEFAULT_MAX_ITER[self.schedule] if self.max_iter is None else self.max_iter
        return self.replace(alpha0=alpha0, max_iter=max_iter)

    @property
    def P(self):
        """Innovation length (1 for the single-innovation methods)."""
        return 1


@dataclass(frozen=True, kw_only=True)
class SingleInnovationGradientOptions(SingleInnovationLMOptions):
    """Options of ``method="single_innovation_gradient"``: the hybrid with ``P = 1``.

    Attributes
    ----------
    normalisation : {"window", "current"}
        Growth of ``r(k)``: ``||Phi(P, k)||^2`` (default, Eq. 31) or ``||phi(k)||^2`` (MISG).
    forgetting : float
        Forgetting factor on ``r`` in ``(0, 1]``: ``r(k) = forgetting * r(k-1) + …``
        (default 1, the paper).
    restart_r : bool
        Restart ``r`` at 1 at every pass (default False).

    Also every attribute of :class:`SingleInnovationLMOptions`.
    """

    constraints = {**SingleInnovationLMOptions.constraints,
                   "normalisation": Choice(NORMALISATIONS), "forgetting": FORGETTING,
                   "restart_r": Boolean()}

    normalisation: str = "window"
    forgetting: float = 1.0
    restart_r: bool = False


@dataclass(frozen=True, kw_only=True)
class HybridOptions(SingleInnovationGradientOptions):
    """Options of ``method="hybrid"``, the paper's MIGD + MI-LM alternation.

    Attributes
    ----------
    innovation_length : int
        ``P``, the number of innovations per update, ``1 <= P <= N`` (default 5).

    Also every attribute of :class:`SingleInnovationGradientOptions` and
    :class:`SingleInnovationLMOptions`.
    """

    constraints = {**SingleInnovationGradientOptions.constraints,
                   "innovation_length": INNOVATION_LENGTH}

    innovation_length: int = 5

    @property
    def P(self):
        """Innovation length."""
        return self.innovation_length


def _criterion(J_prev, J):
    return abs(J - J_prev) / abs(J_prev) if J_prev != 0 else (0.0 if J == 0 else np.inf)


def run_alternation(builder, method, options, bounds, *, operating_point=(0.0, 0.0)):
    """The paper's alternation of MIGD (theta) and MI-LM (alpha) under one schedule.

    Parameters
    ----------
    builder : RegressorBuilder
        The record.
    method : {"hybrid", "single_innovation_gradient", "single_innovation_lm"}
    options : HybridOptions, SingleInnovationGradientOptions or SingleInnovationLMOptions
        Validated (``options.check``).
    bounds : AlphaBounds
    operating_point : (float, float)
        Removed from the data before; recorded in the result.

    Returns
    -------
    IdentificationResult

    Notes
    -----
    Under the recursive schedule the window ``Phi(P, k)`` and its sensitivity at the current
    alpha come from the GL weights expanded in Chebyshev polynomials of alpha on
    ``[lo, hi + delta_alpha]`` (:class:`fohw.model.gl_expansion.GLExpansion`, whose proven
    bound keeps the windows within ``1e-16 max|x|`` of the exact ones): the alpha path equals
    that of the direct rebuild to rounding (measured: 2e-15 at ``N = 10**4``;
    ``tests/reference_estimators.py`` keeps the direct rebuild, which the tests and
    ``benchmarks/bench_recursive.py`` put in place of :func:`expanded_windows`).
    """
    n_samples = builder.n_samples
    o = options
    lm = method == "single_innovation_lm"
    normalisation = getattr(o, "normalisation", "window")
    forgetting = getattr(o, "forgetting", 1.0)
    theta = np.full(builder.layout.n_params, 1.0 / o.p0)
    alpha = o.alpha0
    r = 1.0
    alpha_hist, J_hist = [], []
    status = Status.MAX_ITER
    Phi = None              # the information matrix at the current alpha, once built
    windows = None          # the recursive schedule's windows, built once for all passes
    if o.schedule == "recursive":
        windows = expanded_windows(builder, bounds, o.P, o.sensitivity, o.delta_alpha)
    for m in range(1, o.max_iter + 1):
        if getattr(o, "restart_r", False):
            r = 1.0
        if o.schedule == "recursive":
            theta, alpha, r, theta_path, alpha_path = _recursive_pass(
                builder, theta, alpha, r, bounds, method=method, joint=lm, P=o.P,
                normalisation=normalisation, forgetting=forgetting, lm_lambda=o.lm_lambda,
                windows=windows)
            Phi = builder.matrix(alpha)
        else:
            k_now = 0 if m == 1 else n_samples - 1
            rows = (None if o.alpha_window == "record"
                    else np.arange(k_now, max(k_now - o.P, -1), -1))
            step = alpha_update(builder, theta, alpha, rows=rows, lm_lambda=o.lm_lambda,
                                sensitivity=o.sensitivity, delta_alpha=o.delta_alpha, Phi=Phi)
            check_finite_estimate(method, theta, step, f" in iteration {m}")
            alpha = bounds(step)
            Phi = builder.matrix(alpha)
            if lm:
                theta_path = milm_pass(Phi, builder.y, theta0=theta, n_samples=n_samples,
                                       lm_lambda=o.lm_lambda)
            else:
                theta_path, r_path, _ = migd_pass(Phi, builder.y, innovation_length=o.P,
                                                  theta0=theta, r0=r, normalisation=normalisation,
                                                  forgetting=forgetting)
                r = float(r_path[-1])
            theta = theta_path[-1].copy()
            check_finite_estimate(method, theta, alpha, f" in iteration {m}")
            alpha_path = np.full(n_samples, alpha)
        J = float(np.mean((builder.y - Phi @ theta) ** 2))
        alpha_hist.append(alpha)
        J_hist.append(J)
        if m >= 2 and _criterion(J_hist[-2], J) <= o.tol:
            status = Status.CONVERGED
            break

    if status == Status.CONVERGED:
        message = (f"converged: relative change of J {_criterion(J_hist[-2], J_hist[-1]):.3g} "
                   f"<= tol = {o.tol:g} after {m} iterations.")
    elif o.max_iter == 1:
        status = Status.NOT_TESTED
        message = ("one pass only (max_iter=1): convergence of J was not tested; set "
                   "max_iter >= 2 to test it.")
    else:
        message = (f"stopped at max_iter = {o.max_iter}: relative change of J "
                   f"{_criterion(J_hist[-2], J_hist[-1]):.3g} > tol = {o.tol:g}.")
    if bounds.hit:
        message += f" Alpha was held at a bound of {tuple(bounds.inner)} at least once."
    return finish(builder, method=method, schedule=o.schedule, linear=theta, params=[alpha],
                  status=status, nit=len(J_hist), nfev=len(J_hist), message=message,
                  alpha_at_bound=bounds.hit, Phi=Phi, operating_point=operating_point,
                  options=dict(o.as_dict(), alpha_bounds=(bounds.lo, bounds.hi)),
                  theta_history=theta_path, alpha_sample_history=alpha_path,
                  alpha_history=alpha_hist, J_history=J_hist)


def expanded_windows(builder, bounds, P, sensitivity, delta_alpha):
    """The recursion's windows from GL weights expanded in alpha (:mod:`fohw.model.gl_expansion`).

    The interval covers every order the pass evaluates: ``alpha`` stays in ``bounds`` and the
    finite difference of Eq. (44) also needs ``alpha + delta_alpha``.

    Returns
    -------
    callable
        ``window(k, alpha)``: ``Phi(P, k)^T`` and its derivative in alpha (the finite
        difference of Eq. 44 or the exact one), shape ``(2, rows, n)``, ``O(M N log N)`` for a
        whole pass.
    """
    hi = bounds.hi + (delta_alpha if sensitivity == "finite_difference" else 0.0)
    expansion = GLExpansion(bounds.lo, hi, builder.n_samples)
    windows = ExpandedWindows(builder.signals, builder.lags, expansion, P)
    vectors = np.empty((2, expansion.degree + 1))

    def window(k, alpha):
        expansion.basis_pair(alpha, sensitivity=sensitivity, delta_alpha=delta_alpha,
                             out=vectors)
        return windows.rows(k, vectors)

    return window


def _recursive_pass(builder, theta, alpha, r, bounds, *, method, joint, P, normalisation,
                    forgetting, lm_lambda, windows):
    """One pass of Table 1: at each k, theta by Eq. (29) then alpha by Eq. (48).

    With ``joint=True`` (the single-innovation LM baseline) both are updated together by the
    step of Eq. (48) applied to ``(theta, alpha)``. ``windows(k, alpha)`` gives the window
    ``Phi(P, k)^T`` and its sensitivity (:func:`expanded_windows`).
    """
    y = builder.y
    n_samples = builder.n_samples
    n = theta.shape[0]
    theta_path = np.empty((n_samples, n))
    alpha_path = np.empty(n_samples)
    inner_lo, inner_hi = bounds.inner
    for k in range(n_samples):
        windows_k = windows(k, alpha)                   # (2, rows, n): Phi(P, k)^T, dPhi/dalpha
        phi_w = windows_k[0]
        y_w = y[k:k - phi_w.shape[0]:-1] if k - phi_w.shape[0] >= 0 else y[k::-1]
        if joint:
            jac = np.hstack([phi_w, (windows_k[1] @ theta)[:, None]])
            step = milm_step(jac, y_w - phi_w @ theta, n_samples=n_samples, lm_lambda=lm_lambda)
            theta = theta + step[:n]
            alpha = alpha + step[n]
        else:
            theta, r, _ = migd_update(theta, phi_w, y_w, r, normalisation=normalisation,
                                      forgetting=forgetting)
            pred = windows_k @ theta                      # yhat and its sensitivity
            alpha = alpha + milm_step(pred[1], y_w - pred[0], n_samples=n_samples,
                                      lm_lambda=lm_lambda)
        if not (math.isfinite(alpha) and math.isfinite(theta @ theta)):    # exact check if not
            check_finite_estimate(method, theta, alpha, f" at sample k = {k}")
        if not inner_lo <= alpha <= inner_hi:
            alpha = bounds(alpha)
        theta_path[k] = theta
        alpha_path[k] = alpha
    return theta, alpha, r, theta_path, alpha_path


def _runner(method):
    """The run of a paper method: its one free order's bounds as :class:`AlphaBounds`."""
    def run(builder, options, bounds, *, operating_point):
        lo, hi = bounds
        return run_alternation(builder, method, options, AlphaBounds((float(lo[0]), float(hi[0]))),
                               operating_point=operating_point)
    return run


#: The paper's methods as :func:`fohw.identify` dispatches them (the commensurate model only).
METHODS = tuple(Method(name, options, _runner(name), supports=paper_model_only)
                for name, options in (("hybrid", HybridOptions),
                                      ("single_innovation_gradient",
                                       SingleInnovationGradientOptions),
                                      ("single_innovation_lm", SingleInnovationLMOptions)))


class HybridIdentifier(BaseEstimator):
    """The paper's hybrid method as an estimator (scikit-learn conventions, no dependency).

    ``fit(u, y)`` runs ``fohw.identify(u, y, method="hybrid", ...)`` with these settings; for
    the other methods call :func:`fohw.identify` with their name.

    Parameters
    ----------
    na, nb, f_basis, g_basis
        Model structure, as in :func:`fohw.identify` (keywords, as every parameter).
    alpha_bounds : (float, float), optional
        Interval for alpha (default ``(0, 1)``, the paper's).
    schedule, alpha0, max_iter, tol, p0, lm_lambda, delta_alpha, sensitivity, alpha_window, \
normalisation, forgetting, restart_r, innovation_length
        The options of the hybrid method, with their defaults (:class:`HybridOptions`).

    Attributes
    ----------
    result_ : IdentificationResult
    theta_, alpha_, model_, status_, n_iter_
        Shortcuts into ``result_``: what was fitted.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> est = fohw.estimators.hybrid.HybridIdentifier(na=2, nb=2, f_basis=2, g_basis=3, innovation_length=3)
    >>> est.get_params()["schedule"]
    'recursive'
    >>> est.fit(data.u, data.y).theta_.shape
    (10,)
    >>> est.status_.name        # one pass of Table 1: convergence is not tested, no warning
    'NOT_TESTED'
    """

    _model = (("na", REQUIRED), ("nb", REQUIRED), ("f_basis", REQUIRED), ("g_basis", REQUIRED),
              ("alpha_bounds", (0.0, 1.0)))
    _options = HybridOptions

    def fit(self, u, y):
        """Identify from ``(u, y)``; return ``self``."""
        model = {name: getattr(self, name) for name, _ in self._model}
        self.result_ = fit_method(METHODS[0], self._given_options(), u, y, **model)
        self.theta_ = np.array(self.result_.theta)
        self.alpha_ = self.result_.alpha
        self.model_ = self.result_.model
        self.status_ = self.result_.status
        self.n_iter_ = self.result_.nit
        return self

    def predict(self, u, y):
        """One-step-ahead prediction with the fitted model (Eq. 19).

        Uses what was fitted (``result_``): settings changed after ``fit`` do not affect it.
        """
        check_is_fitted(self, "result_")
        return self.result_.predict(u, y)
