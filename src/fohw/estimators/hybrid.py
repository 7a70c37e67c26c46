"""The alternating identification driver (paper Section 4, Steps 1–9 and Table 1).

``identify`` estimates ``theta`` by multi-innovation gradient descent (:mod:`fohw.estimators.migd`) and
the fractional order by the multi-innovation Levenberg–Marquardt step (:mod:`fohw.estimators.milm`),
alternately, under one of two schedules the paper describes:

``"recursive"`` (Table 1, the default)
    At every sample ``k``: rebuild the innovation window ``Phi(P, k)`` at the current
    ``alpha`` (exactly, from the full memory), update ``theta`` (Eqs. 29–31), then update
    ``alpha`` by Eq. (48) on the same window with the new ``theta``. One outer iteration is one
    pass over the record; ``max_iter`` passes at most (default 1: Table 1 as printed).
``"iterative"`` (Steps 1–9)
    Outer iteration ``m``: an ``alpha`` step (Steps 3–5), then a full MIGD pass over the
    record at that ``alpha`` (Steps 6–7), then ``J`` (Eq. 41, Step 8); stop when the relative
    change of ``J`` is at most ``tol`` (Step 9).

Where the paper is ambiguous, the reading closest to the text is the default and the other is
an option:

* ``alpha0`` is not given in the paper; the default 0.5 is the middle of its ``(0, 1)``.
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
``method="single_innovation_lm"`` applies the step of Eq. (48) with ``P = 1`` to
``(theta, alpha)`` jointly.
"""

from __future__ import annotations

import warnings

import numpy as np

from .._base import BaseEstimator, check_is_fitted
from .._validation import AlphaBounds, check_array, check_int, check_same_length, check_scalar
from ..exceptions import ConvergenceWarning, ParameterError
from ..model.gl import _weights
from ..model.regressors import RegressorBuilder
from ..model.system import HammersteinWiener
from ..results import IdentificationResult
from .migd import check_migd_options, migd_pass, migd_update
from .milm import alpha_update, check_sensitivity, milm_step, sensitivity_weights
from .varpro import separable_least_squares

__all__ = ["identify", "HybridIdentifier", "METHODS", "SCHEDULES"]

METHODS = ("hybrid", "single_innovation_gradient", "single_innovation_lm", "varpro", "rls",
           "output_error")
SCHEDULES = ("recursive", "iterative")
_DEFAULT_MAX_ITER = {"recursive": 1, "iterative": 50}


def _criterion(J_prev, J):
    return abs(J - J_prev) / abs(J_prev) if J_prev != 0 else (0.0 if J == 0 else np.inf)


def identify(u, y, *, na, nb, f_basis, g_basis, method="hybrid", innovation_length=5,
             alpha0=0.5, schedule="recursive", max_iter=None, tol=1e-4, random_state=None,
             alpha_bounds=(0.0, 1.0), p0=1e6, normalisation="window", forgetting=1.0,
             lm_lambda=1.0, delta_alpha=1e-3, sensitivity="finite_difference",
             alpha_window="innovation", restart_r=False, n_grid=41, n_init=0, start=None):
    """Identify a fractional-order Hammerstein–Wiener model from input–output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records (zero before ``k = 0``).
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree).
    method : {"hybrid", "single_innovation_gradient", "single_innovation_lm", "varpro"}, optional
        ``"hybrid"`` (default): MIGD for theta and MI-LM for alpha (the paper). The
        single-innovation methods are the baselines of Fig. 6 (see the module notes).
        ``"varpro"``: separable least squares (:mod:`fohw.estimators.varpro`), beyond the paper: theta by
        linear least squares for each alpha, alpha by a grid scan and a bounded search, then a
        joint Gauss–Newton polish; it reaches the Cramér–Rao bound and reports standard errors.
        It ignores the settings of the recursive methods (``innovation_length``, ``schedule``,
        ``max_iter``, ``tol``, ``p0``, ``lm_lambda``, …) and the starting value ``alpha0``.
        ``"rls"``: one pass of :class:`fohw.MultiInnovationRLS` (recursive least squares with
        recursive alpha), using ``innovation_length``, ``forgetting``, ``alpha0``,
        ``alpha_bounds`` and ``p0``.
        ``"output_error"``: beyond the paper, minimises the free-run *simulation* error over
        ``(theta, alpha)`` (:mod:`fohw.estimators.output_error`), started from the ``"varpro"``
        estimate; the criterion leaves out the first ``n_init`` samples.
    innovation_length : int, optional
        ``P`` (default 5), ``1 <= P <= N``. Forced to 1 by the single-innovation methods.
    alpha0 : float, optional
        Initial fractional order, inside ``alpha_bounds`` (default 0.5).
    schedule : {"recursive", "iterative"}, optional
        Table 1 (default) or Steps 1–9; see the module notes.
    max_iter : int, optional
        Maximum outer iterations (passes). Default: 1 for ``"recursive"`` (one pass, as in
        Table 1), 50 for ``"iterative"``. For ``"output_error"``: the maximum number of
        simulations of the least-squares solver (default 100), Jacobian evaluations aside.
    tol : float, optional
        Stop when ``|J_m - J_{m-1}| / |J_{m-1}| <= tol`` (Step 9), ``tol > 0``. Default 1e-4.
    random_state : None, int or numpy.random.Generator, optional
        Accepted so every method shares one signature; the methods here are deterministic
        and draw no random numbers.
    alpha_bounds : (float, float), optional
        Open interval for alpha, within ``[0, 2]``; default ``(0, 1)`` as in the paper.
        Alpha is held ``1e-3 * (high - low)`` inside it, and the result says if that happened.
    p0 : float, optional
        ``theta(0) = 1/p0`` (default 1e6).
    normalisation : {"window", "current"}, optional
        Growth of ``r(k)``: ``||Phi(P, k)||^2`` (default, Eq. 31) or ``||phi(k)||^2`` (MISG).
    forgetting : float, optional
        Forgetting factor on ``r``, in ``(0, 1]`` (default 1, the paper).
    lm_lambda : float, optional
        LM damping ``lambda > 0`` (default 1, Table 1).
    delta_alpha : float, optional
        Step of Eq. (44) (default 1e-3, Table 1).
    sensitivity : {"finite_difference", "exact"}, optional
        Eq. (44) (default) or the exact derivative of the GL weights.
    alpha_window : {"innovation", "record"}, optional
        Which samples the alpha step of the iterative schedule uses (see the module notes).
    restart_r : bool, optional
        Restart ``r`` at 1 at every pass (default False).
    n_grid : int, optional
        ``"varpro"`` and ``"output_error"``: points of the coarse alpha scan (default 41).
    n_init : int, optional
        ``"output_error"`` only: leading samples left out of the simulation-error criterion
        (start-up transient; default 0).
    start : IdentificationResult or (theta, alpha), optional
        ``"output_error"`` only: the starting point; default the ``"varpro"`` estimate.

    Returns
    -------
    IdentificationResult

    Raises
    ------
    ParameterError, DimensionError
        Invalid settings or data, with the offending argument named.

    Warns
    -----
    ConvergenceWarning
        The run stopped at ``max_iter`` without meeting ``tol`` (always so for a single
        recursive pass, whose convergence is not tested); the result then has
        ``converged=False``.

    Notes
    -----
    Eqs. (29)–(33) (MIGD), (41)–(48) (MI-LM), (39)–(40) (recovery of ``a, b, p, q``), Table 1
    and Steps 1–9. As printed, MIGD's ``1/r(k)`` step shrinks fast: on the paper's example it
    does not reach the accuracy of the paper's Table 2 (see ``docs/reproduction.md``).

    Examples
    --------
    >>> import warnings, fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", fohw.ConvergenceWarning)
    ...     res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> res.theta.shape, res.n_iter, res.converged
    ((10,), 1, False)
    """
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    if method not in METHODS:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    if schedule not in SCHEDULES:
        raise ParameterError(f"`schedule` must be one of {SCHEDULES}; got {schedule!r}.")
    if alpha_window not in ("innovation", "record"):
        raise ParameterError(f"`alpha_window` must be 'innovation' or 'record'; got "
                             f"{alpha_window!r}.")
    if alpha_window == "record" and schedule == "recursive":
        raise ParameterError("`alpha_window='record'` applies to the iterative schedule only; the "
                             "recursive schedule (Table 1) uses the last `innovation_length` "
                             "samples.")
    builder = RegressorBuilder(u, y, na=na, nb=nb, f_basis=f_basis, g_basis=g_basis)
    n_samples = builder.n_samples
    P, p0, normalisation, forgetting = check_migd_options(innovation_length, p0, normalisation,
                                                          forgetting, n_samples)
    if method.startswith("single_innovation"):
        P = 1
    bounds = AlphaBounds(alpha_bounds)
    alpha = check_scalar(alpha0, "alpha0", lower=bounds.lo, upper=bounds.hi,
                         lower_inclusive=False, upper_inclusive=False)
    tol = check_scalar(tol, "tol", lower=0.0, lower_inclusive=False)
    max_iter_given = max_iter
    max_iter = _DEFAULT_MAX_ITER[schedule] if max_iter is None else max_iter
    max_iter = check_int(max_iter, "max_iter", minimum=1)
    lm_lambda = check_scalar(lm_lambda, "lm_lambda", lower=0.0, lower_inclusive=False)
    delta_alpha = check_sensitivity(sensitivity, delta_alpha)
    if not isinstance(restart_r, (bool, np.bool_)):
        raise ParameterError(f"`restart_r` must be True or False; got {restart_r!r}.")

    n_grid = check_int(n_grid, "n_grid", minimum=3)
    n_init = check_int(n_init, "n_init", minimum=0, maximum=n_samples - 2)
    if method == "varpro":
        return _varpro_result(builder, bounds, n_grid, dict(alpha_bounds=(bounds.lo, bounds.hi),
                                                            n_grid=n_grid))
    if method == "output_error":
        max_nfev = 100 if max_iter_given is None else max_iter
        return _output_error_result(builder, bounds, n_grid, n_init, start, max_nfev)

    if method == "rls":
        return _rls_result(builder, P, forgetting, alpha, bounds, p0, u, y)

    cfg = dict(P=P, normalisation=normalisation, forgetting=forgetting, lm_lambda=lm_lambda,
               delta_alpha=delta_alpha, sensitivity=sensitivity, n_samples=n_samples)
    theta = np.full(builder.layout.n_params, 1.0 / p0)
    r = 1.0
    alpha_hist, J_hist = [], []
    converged = False
    Phi = None              # the information matrix at the current alpha, once built
    for m in range(1, max_iter + 1):
        if restart_r:
            r = 1.0
        if schedule == "recursive":
            theta, alpha, r, theta_path, alpha_path = _recursive_pass(
                builder, theta, alpha, r, bounds, joint=(method == "single_innovation_lm"), **cfg)
        else:
            k_now = 0 if m == 1 else n_samples - 1
            rows = None if alpha_window == "record" else np.arange(k_now, max(k_now - P, -1), -1)
            alpha = bounds(alpha_update(builder, theta, alpha, rows=rows, lm_lambda=lm_lambda,
                                        sensitivity=sensitivity, delta_alpha=delta_alpha,
                                        Phi=Phi))
            Phi = builder.matrix(alpha)
            theta_path, r_path, _ = migd_pass(Phi, builder.y, innovation_length=P, theta0=theta,
                                              r0=r, normalisation=normalisation,
                                              forgetting=forgetting)
            theta, r = theta_path[-1].copy(), float(r_path[-1])
            alpha_path = np.full(n_samples, alpha)
        if schedule == "recursive":
            Phi = builder.matrix(alpha)
        J = float(np.mean((builder.y - Phi @ theta) ** 2))
        alpha_hist.append(alpha)
        J_hist.append(J)
        if m >= 2 and _criterion(J_hist[-2], J) <= tol:
            converged = True
            break

    if converged:
        message = (f"converged: relative change of J {_criterion(J_hist[-2], J_hist[-1]):.3g} "
                   f"<= tol = {tol:g} after {m} iterations.")
    elif max_iter == 1:
        message = ("one pass only (max_iter=1): convergence of J was not tested; set "
                   "max_iter >= 2 to test it.")
    else:
        message = (f"stopped at max_iter = {max_iter}: relative change of J "
                   f"{_criterion(J_hist[-2], J_hist[-1]):.3g} > tol = {tol:g}.")
    if not converged:
        warnings.warn(f"fohw.identify({method!r}, schedule={schedule!r}): {message}",
                      ConvergenceWarning, stacklevel=2)
    model, note = _recover_model(builder, theta, alpha)
    message += note
    if bounds.hit:
        message += f" Alpha was held at a bound of {tuple(bounds.inner)} at least once."
    options = dict(innovation_length=P, alpha0=float(alpha0), max_iter=max_iter, tol=tol,
                   alpha_bounds=(bounds.lo, bounds.hi), p0=p0, normalisation=normalisation,
                   forgetting=forgetting, lm_lambda=lm_lambda, delta_alpha=delta_alpha,
                   sensitivity=sensitivity, alpha_window=alpha_window, restart_r=bool(restart_r))
    return IdentificationResult(
        method=method, schedule=schedule, alpha=float(alpha), theta=theta, model=model, J=J_hist[-1],
        n_iter=len(J_hist), converged=converged, message=message, alpha_at_bound=bounds.hit,
        theta_history=theta_path, alpha_sample_history=alpha_path,
        alpha_history=np.array(alpha_hist), J_history=np.array(J_hist), layout=builder.layout,
        f_basis=builder.f_basis, g_basis=builder.g_basis, n_samples=n_samples, options=options)


def _recover_model(builder, theta, alpha):
    """The model of Eqs. (39)-(40), or None and a note saying why it is undefined."""
    try:
        return HammersteinWiener.from_theta(theta, alpha, na=builder.layout.na,
                                            nb=builder.layout.nb, f_basis=builder.f_basis,
                                            g_basis=builder.g_basis), ""
    except ParameterError as exc:
        return None, f" No model: {exc}"


def _varpro_result(builder, bounds, n_grid, options):
    """Run separable least squares and wrap it as an IdentificationResult."""
    fit = separable_least_squares(builder, bounds=(bounds.lo, bounds.hi), n_grid=n_grid)
    message = ("converged: " if fit.converged else "NOT converged: ") + fit.message
    margin = 1e-6 * (bounds.hi - bounds.lo)
    at_bound = not (bounds.lo + margin < fit.alpha < bounds.hi - margin)
    if at_bound:
        message += (f" The estimate of alpha is at the edge of alpha_bounds = "
                    f"{(bounds.lo, bounds.hi)}: widen the bounds.")
    if not fit.converged:
        warnings.warn(f"fohw.identify('varpro'): {message}", ConvergenceWarning, stacklevel=3)
    model, note = _recover_model(builder, fit.theta, fit.alpha)
    message += note
    return IdentificationResult(
        method="varpro", schedule="", alpha=fit.alpha, theta=fit.theta, model=model,
        J=fit.rss / builder.n_samples, n_iter=len(fit.search_alphas), converged=fit.converged,
        message=message, alpha_at_bound=at_bound, theta_history=None, alpha_sample_history=None,
        alpha_history=np.array(fit.search_alphas), J_history=np.array(fit.search_J),
        layout=builder.layout, f_basis=builder.f_basis, g_basis=builder.g_basis,
        n_samples=builder.n_samples, options=options, covariance=fit.covariance,
        noise_variance=fit.noise_variance, alpha_profile=np.vstack([fit.grid, fit.grid_J]))


def _output_error_result(builder, bounds, n_grid, n_init, start, max_nfev):
    """Equation-error start (varpro) or a given one, then the simulation-error fit."""
    from .output_error import fit_output_error

    if start is None:
        vp = separable_least_squares(builder, bounds=(bounds.lo, bounds.hi), n_grid=n_grid)
        theta0, alpha0, origin = vp.theta, vp.alpha, "the varpro estimate"
        J0 = vp.rss / builder.n_samples
    else:
        if isinstance(start, IdentificationResult):
            theta0, alpha0 = start.theta, start.alpha
        else:
            try:
                theta0, alpha0 = start
            except (TypeError, ValueError):
                raise ParameterError("`start` must be an IdentificationResult or a pair "
                                     f"(theta, alpha); got {start!r}.") from None
        theta0 = builder.layout.check_theta(theta0, "start theta")
        alpha0 = check_scalar(alpha0, "start alpha", lower=bounds.lo, upper=bounds.hi)
        origin = "the given start"
        J0 = float(np.mean((builder.y - builder.matrix(alpha0) @ theta0) ** 2))
    fit = fit_output_error(builder.u, builder.y, layout=builder.layout, f_basis=builder.f_basis,
                           g_basis=builder.g_basis, theta0=theta0, alpha0=alpha0,
                           bounds=(bounds.lo, bounds.hi), n_init=n_init, max_nfev=max_nfev)
    message = ("converged: " if fit.converged else "NOT converged: ") + fit.message
    message += (f" Started from {origin} (alpha = {alpha0:.6g})"
                + (f", its output-feedback block shrunk by {fit.start_shrink:.3g} to make it "
                   "stable." if fit.start_shrink < 1 else "."))
    message += f" Simulation error criterion from sample {n_init} on."
    if not fit.converged:
        warnings.warn(f"fohw.identify('output_error'): {message}", ConvergenceWarning,
                      stacklevel=3)
    model, note = _recover_model(builder, fit.theta, fit.alpha)
    message += note
    J = float(np.mean((builder.y - builder.matrix(fit.alpha) @ fit.theta) ** 2))
    return IdentificationResult(
        method="output_error", schedule="", alpha=fit.alpha, theta=fit.theta, model=model, J=J,
        n_iter=fit.nfev, converged=fit.converged, message=message,
        alpha_at_bound=not (bounds.lo < fit.alpha < bounds.hi), theta_history=None,
        alpha_sample_history=None, alpha_history=np.array([alpha0, fit.alpha]),
        J_history=np.array([J0, J]), layout=builder.layout,
        f_basis=builder.f_basis, g_basis=builder.g_basis, n_samples=builder.n_samples,
        options=dict(alpha_bounds=(bounds.lo, bounds.hi), n_grid=n_grid, n_init=n_init,
                     simulation_sse=fit.sse),
        covariance=fit.covariance, noise_variance=fit.noise_variance)


def _rls_result(builder, P, forgetting, alpha0, bounds, p0, u, y):
    """One pass of MultiInnovationRLS wrapped as an IdentificationResult."""
    from .rls import MultiInnovationRLS

    est = MultiInnovationRLS(builder.layout.na, builder.layout.nb, builder.f_basis,
                             builder.g_basis, innovation_length=P, forgetting=forgetting,
                             alpha0=alpha0, alpha_bounds=(bounds.lo, bounds.hi), p0=p0).fit(u, y)
    J = float(np.mean((y - builder.matrix(est.alpha_) @ est.theta_) ** 2))
    message = ("one pass only (max_iter=1): convergence of J was not tested; a recursive "
               "estimator's final value is its estimate.")
    warnings.warn(f"fohw.identify('rls'): {message}", ConvergenceWarning, stacklevel=3)
    if est.alpha_at_bound_:
        message += " Alpha was held at a bound at least once."
    model, note = _recover_model(builder, est.theta_, est.alpha_)
    message += note
    return IdentificationResult(
        method="rls", schedule="recursive", alpha=est.alpha_, theta=est.theta_, model=model, J=J,
        n_iter=1, converged=False, message=message, alpha_at_bound=est.alpha_at_bound_,
        theta_history=est.theta_history_, alpha_sample_history=est.alpha_history_,
        alpha_history=np.array([est.alpha_]), J_history=np.array([J]), layout=builder.layout,
        f_basis=builder.f_basis, g_basis=builder.g_basis, n_samples=builder.n_samples,
        options=dict(innovation_length=P, forgetting=forgetting, alpha0=alpha0,
                     alpha_bounds=(bounds.lo, bounds.hi), p0=p0))


def _recursive_pass(builder, theta, alpha, r, bounds, *, joint, P, normalisation, forgetting,
                    lm_lambda, delta_alpha, sensitivity, n_samples):
    """One pass of Table 1: at each k, theta by Eq. (29) then alpha by Eq. (48).

    With ``joint=True`` (the single-innovation LM baseline) both are updated together by the
    step of Eq. (48) applied to ``(theta, alpha)``.
    """
    y = builder.y
    n = theta.shape[0]
    theta_path = np.empty((n_samples, n))
    alpha_path = np.empty(n_samples)
    for k in range(n_samples):
        length = max(k, 1)
        beta = _weights(alpha, length)
        phi_w, dphi_w = builder.window(k, P, [
            beta, sensitivity_weights(alpha, length, sensitivity=sensitivity,
                                      delta_alpha=delta_alpha, beta=beta)])
        y_w = y[k:k - phi_w.shape[0]:-1] if k - phi_w.shape[0] >= 0 else y[k::-1]
        if joint:
            jac = np.hstack([phi_w, (dphi_w @ theta)[:, None]])
            step = milm_step(jac, y_w - phi_w @ theta, n_samples=n_samples, lm_lambda=lm_lambda)
            theta = theta + step[:n]
            alpha = bounds(alpha + step[n])
        else:
            theta, r, _ = migd_update(theta, phi_w, y_w, r, normalisation=normalisation,
                                      forgetting=forgetting)
            alpha = bounds(alpha + milm_step(dphi_w @ theta, y_w - phi_w @ theta,
                                             n_samples=n_samples, lm_lambda=lm_lambda))
        theta_path[k] = theta
        alpha_path[k] = alpha
    return theta, alpha, r, theta_path, alpha_path


class HybridIdentifier(BaseEstimator):
    """Estimator interface to :func:`fohw.identify` (scikit-learn conventions, no dependency).

    Parameters
    ----------
    na, nb, f_basis, g_basis
        Model structure, as in :func:`fohw.identify`.
    **options
        Any keyword argument of :func:`fohw.identify` (``method``, ``innovation_length``, …),
        stored as the attribute of the same name.

    Attributes
    ----------
    result_ : IdentificationResult
    theta_, alpha_, model_, n_iter_
        Shortcuts into ``result_``.

    Examples
    --------
    >>> import warnings, fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> est = fohw.HybridIdentifier(na=2, nb=2, f_basis=2, g_basis=3, schedule="iterative",
    ...                             max_iter=30)
    >>> est.get_params()["schedule"]
    'iterative'
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", fohw.ConvergenceWarning)
    ...     est = est.fit(data.u, data.y)
    >>> est.theta_.shape
    (10,)
    """

    _OPTIONS = ("method", "innovation_length", "alpha0", "schedule", "max_iter", "tol",
                "random_state", "alpha_bounds", "p0", "normalisation", "forgetting",
                "lm_lambda", "delta_alpha", "sensitivity", "alpha_window", "restart_r", "n_grid",
                "n_init", "start")

    def __init__(self, na, nb, f_basis, g_basis, **options):
        self.na = na
        self.nb = nb
        self.f_basis = f_basis
        self.g_basis = g_basis
        unknown = set(options) - set(self._OPTIONS)
        if unknown:
            raise ParameterError(f"unknown option(s) {sorted(unknown)}; valid: {self._OPTIONS}.")
        self._options = dict(options)
        for key, value in options.items():
            setattr(self, key, value)

    def get_params(self, deep=True):
        """Return the structure and every option that was set."""
        params = {k: getattr(self, k) for k in ("na", "nb", "f_basis", "g_basis")}
        params.update({k: getattr(self, k) for k in self._OPTIONS if hasattr(self, k)})
        return params

    def set_params(self, **params):
        """Set structure or options by name; returns ``self``."""
        for key, value in params.items():
            if key not in ("na", "nb", "f_basis", "g_basis") + self._OPTIONS:
                raise ValueError(f"invalid parameter {key!r} for HybridIdentifier.")
            setattr(self, key, value)
        return self

    def fit(self, u, y):
        """Identify from ``(u, y)``; return ``self``."""
        opts = {k: getattr(self, k) for k in self._OPTIONS if hasattr(self, k)}
        self.result_ = identify(u, y, na=self.na, nb=self.nb, f_basis=self.f_basis,
                                g_basis=self.g_basis, **opts)
        self.theta_ = np.array(self.result_.theta)
        self.alpha_ = self.result_.alpha
        self.model_ = self.result_.model
        self.n_iter_ = self.result_.n_iter
        return self

    def predict(self, u, y):
        """One-step-ahead prediction with the fitted model (Eq. 19)."""
        check_is_fitted(self, "result_")
        return self.result_.predict(u, y)
