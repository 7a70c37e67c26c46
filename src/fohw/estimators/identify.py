"""The one-call entry point :func:`fohw.identify` and its table of methods (dispatch only).

The paper's alternating method lives in :mod:`fohw.estimators.hybrid`; the estimators beyond
the paper in :mod:`~fohw.estimators.varpro`, :mod:`~fohw.estimators.output_error` and
:mod:`~fohw.estimators.rls`.
"""

from __future__ import annotations

import numpy as np

from .._validation import AlphaBounds, check_array, check_int, check_same_length, check_scalar
from ..exceptions import ParameterError
from ..model.regressors import RegressorBuilder
from .hybrid import _DEFAULT_MAX_ITER, SCHEDULES, run_alternation
from .migd import check_migd_options
from .milm import check_sensitivity
from .output_error import output_error_result
from .rls import rls_result
from .varpro import varpro_result

__all__ = ["identify", "METHODS", "SCHEDULES"]

METHODS = ("hybrid", "single_innovation_gradient", "single_innovation_lm", "varpro", "rls",
           "output_error")


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
        return varpro_result(builder, bounds, n_grid, dict(alpha_bounds=(bounds.lo, bounds.hi),
                                                           n_grid=n_grid))
    if method == "output_error":
        max_nfev = 100 if max_iter_given is None else max_iter
        return output_error_result(builder, bounds, n_grid, n_init, start, max_nfev)

    if method == "rls":
        return rls_result(builder, P, forgetting, alpha, bounds, p0, u, y)

    return run_alternation(builder, method=method, schedule=schedule, P=P, alpha=alpha, alpha0=alpha0,
                           max_iter=max_iter, tol=tol, bounds=bounds, p0=p0,
                           normalisation=normalisation, forgetting=forgetting,
                           lm_lambda=lm_lambda, delta_alpha=delta_alpha, sensitivity=sensitivity,
                           alpha_window=alpha_window, restart_r=restart_r)
