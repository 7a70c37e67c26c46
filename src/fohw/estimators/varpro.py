"""Separable least squares (variable projection) for theta and alpha — beyond the paper.

For a fixed ``alpha`` the model ``y = Phi(alpha) theta + v`` is linear in ``theta``, so
``theta(alpha)`` is a linear least-squares solution and ``J(alpha) = mean(residual**2)`` (Eq. 41
at the best theta) is a function of one variable. The estimator

1. scans ``J(alpha)`` on a grid inside the bounds (so a local minimum is not taken for the
   global one),
2. refines the best grid cell by a bounded scalar search (Brent), and
3. polishes ``(theta, alpha)`` jointly by Gauss–Newton steps (QR, backtracking) with the exact
   alpha-sensitivity ``d Phi / d alpha`` (:meth:`fohw.RegressorBuilder.matrix_derivative`).

Each ``J(alpha)`` costs one inverse FFT of the stacked basis signals, whose FFTs are computed once
per record. The result is the equation-error (prediction-error) estimate; under white Gaussian
equation noise it is the conditional maximum-likelihood estimate and reaches the Cramér–Rao
bound (:func:`fohw.crb`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from ..exceptions import ConvergenceWarning
from ..results import IdentificationResult, recover_model

__all__ = ["profile_theta", "separable_least_squares", "parameter_covariance"]


def profile_theta(Phi, y):
    """Least-squares ``theta`` for fixed regressors, by an orthogonal factorisation.

    Parameters
    ----------
    Phi : ndarray, shape (N, n)
    y : ndarray, shape (N,)

    Returns
    -------
    theta : ndarray, shape (n,)
    rss : float
        Residual sum of squares ``||y - Phi theta||^2``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.varpro import profile_theta
    >>> theta, rss = profile_theta(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    ...                            np.array([1.0, 2.0, 3.0]))
    >>> theta.round(12), round(rss, 12)
    (array([1., 2.]), 0.0)
    """
    theta, *_ = scipy.linalg.lstsq(Phi, y, lapack_driver="gelsy", check_finite=False)
    resid = y - Phi @ theta
    return theta, float(resid @ resid)


def parameter_covariance(jacobian, rss, n_samples, *, overwrite=False):
    """Asymptotic covariance ``s^2 (G^T G)^{-1}`` of least-squares estimates.

    Parameters
    ----------
    jacobian : ndarray, shape (N, d)
        Derivative of the predicted output with respect to the ``d`` parameters.
    rss : float
        Residual sum of squares at the estimate.
    n_samples : int
        ``N``.

    Returns
    -------
    covariance : ndarray, shape (d, d)
    noise_variance : float
        ``s^2 = rss / (N - d)``.

    Notes
    -----
    Computed from the triangular factor ``R`` of ``G = QR`` (never from the normal equations):
    ``(G^T G)^{-1} = R^{-1} R^{-T}``. With ``overwrite=True`` the factorisation may reuse the
    memory of ``jacobian`` (no copy of an ``N x d`` array).
    """
    d = jacobian.shape[1]
    s2 = rss / (n_samples - d)
    (r,) = scipy.linalg.qr(jacobian, mode="r", overwrite_a=overwrite, check_finite=False)
    rinv = scipy.linalg.solve_triangular(r[:d, :d], np.eye(d))
    return s2 * (rinv @ rinv.T), s2


@dataclass
class _VarproFit:
    theta: np.ndarray
    alpha: float
    rss: float
    grid: np.ndarray
    grid_J: np.ndarray
    search_alphas: list
    search_J: list
    converged: bool
    message: str
    covariance: np.ndarray
    noise_variance: float


def _jacobian(builder, theta, alpha):
    """``G = [Phi(alpha), dPhi/dalpha @ theta]``, built in one ``N x (n + 1)`` array."""
    n = theta.shape[0]
    G = np.empty((builder.n_samples, n + 1))
    G[:, :n] = builder.matrix(alpha)
    G[:, n] = builder.matrix_derivative(alpha) @ theta
    return G


def _gauss_newton(builder, theta, alpha, rss, lo, hi, max_iter=20):
    """Joint Gauss–Newton polish of ``(theta, alpha)`` with backtracking.

    Each step solves ``min ||G step - r||`` by an orthogonal factorisation (QR with column
    pivoting) of the exact Jacobian; a step is accepted only if it lowers the residual sum of
    squares, halving it up to 30 times otherwise. Memory: one ``N x (n + 1)`` array at a time.
    Returns the new estimates, whether the step size fell below ``1e-10`` relative, and a note.
    """
    y = builder.y
    n = theta.shape[0]
    margin = 1e-9 * (hi - lo)
    for it in range(1, max_iter + 1):
        G = _jacobian(builder, theta, alpha)
        r = y - G[:, :n] @ theta
        step, *_ = scipy.linalg.lstsq(G, r, lapack_driver="gelsy", overwrite_a=True,
                                      overwrite_b=True, check_finite=False)
        del G
        size = np.linalg.norm(step) / (np.linalg.norm(np.append(theta, alpha)) + 1e-300)
        t = 1.0
        for _ in range(30):
            th2 = theta + t * step[:n]
            a2 = float(np.clip(alpha + t * step[n], lo + margin, hi - margin))
            resid = y - builder.matrix(a2) @ th2
            rss2 = float(resid @ resid)
            if rss2 <= rss:
                theta, alpha, rss = th2, a2, rss2
                break
            t *= 0.5
        else:
            return theta, alpha, rss, True, (f"Gauss-Newton stopped after {it} iterations: no "
                                             "descent along the step (at the optimum)")
        if t * size < 1e-10:
            return theta, alpha, rss, True, f"Gauss-Newton converged in {it} iterations"
    return theta, alpha, rss, False, f"Gauss-Newton stopped at {max_iter} iterations"


def separable_least_squares(builder, *, bounds, n_grid=41, xtol=1e-10, polish=True):
    """Separable least-squares estimate of ``(theta, alpha)`` for one record.

    Parameters
    ----------
    builder : RegressorBuilder
        The record.
    bounds : (float, float)
        Open interval searched for alpha.
    n_grid : int
        Grid points of the coarse scan (default 41), equally spaced strictly inside ``bounds``.
    xtol : float
        Absolute tolerance on alpha of the bounded scalar search.
    polish : bool
        Run the joint Gauss–Newton / LM polish with the exact sensitivity (default True).

    Returns
    -------
    _VarproFit
        Internal record; :func:`fohw.identify` wraps it into an ``IdentificationResult``.
    """
    y = builder.y
    n_samples = builder.n_samples
    lo, hi = bounds
    grid = np.linspace(lo, hi, n_grid + 2)[1:-1]
    cache = {}

    def rss_of(alpha):
        alpha = float(alpha)
        if alpha not in cache:
            cache[alpha] = profile_theta(builder.matrix(alpha), y)
        return cache[alpha][1]

    grid_J = np.array([rss_of(a) for a in grid]) / n_samples
    i = int(np.argmin(grid_J))
    left = grid[i - 1] if i > 0 else lo + 1e-6 * (hi - lo)
    right = grid[i + 1] if i < n_grid - 1 else hi - 1e-6 * (hi - lo)
    search_alphas, search_J = [], []

    def traced(alpha):
        value = rss_of(alpha) / n_samples
        search_alphas.append(float(alpha))
        search_J.append(value)
        return value

    opt = scipy.optimize.minimize_scalar(traced, bounds=(left, right), method="bounded",
                                         options={"xatol": xtol, "maxiter": 500})
    alpha = float(opt.x)
    theta, rss = cache[alpha]
    converged, message = bool(opt.success), f"alpha search: {opt.message}"
    if polish:
        theta, alpha, rss, ok, note = _gauss_newton(builder, theta, alpha, rss, lo, hi)
        converged = converged and ok
        message += f"; polish: {note}"
    cov, s2 = parameter_covariance(_jacobian(builder, theta, alpha), rss, n_samples,
                                   overwrite=True)
    return _VarproFit(theta=theta, alpha=alpha, rss=rss, grid=grid, grid_J=grid_J,
                      search_alphas=search_alphas, search_J=search_J, converged=converged,
                      message=message, covariance=cov, noise_variance=s2)


def varpro_result(builder, bounds, n_grid, options):
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
    model, note = recover_model(builder, fit.theta, fit.alpha)
    message += note
    return IdentificationResult(
        method="varpro", schedule="", alpha=fit.alpha, theta=fit.theta, model=model,
        J=fit.rss / builder.n_samples, n_iter=len(fit.search_alphas), converged=fit.converged,
        message=message, alpha_at_bound=at_bound, theta_history=None, alpha_sample_history=None,
        alpha_history=np.array(fit.search_alphas), J_history=np.array(fit.search_J),
        layout=builder.layout, f_basis=builder.f_basis, g_basis=builder.g_basis,
        n_samples=builder.n_samples, options=options, covariance=fit.covariance,
        noise_variance=fit.noise_variance, alpha_profile=np.vstack([fit.grid, fit.grid_J]))
