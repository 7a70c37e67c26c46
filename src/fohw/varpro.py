"""Separable least squares (variable projection) for theta and alpha — beyond the paper.

For a fixed ``alpha`` the model ``y = Phi(alpha) theta + v`` is linear in ``theta``, so
``theta(alpha)`` is a linear least-squares solution and ``J(alpha) = mean(residual**2)`` (Eq. 41
at the best theta) is a function of one variable. The estimator

1. scans ``J(alpha)`` on a grid inside the bounds (so a local minimum is not taken for the
   global one),
2. refines the best grid cell by a bounded scalar search (Brent), and
3. polishes ``(theta, alpha)`` jointly by a trust-region Gauss–Newton / LM solver with the exact
   alpha-sensitivity ``d Phi / d alpha`` (:meth:`fohw.RegressorBuilder.matrix_derivative`).

Each ``J(alpha)`` costs one inverse FFT of the stacked basis signals, whose FFTs are computed once
per record. The result is the equation-error (prediction-error) estimate; under white Gaussian
equation noise it is the conditional maximum-likelihood estimate and reaches the Cramér–Rao
bound (:func:`fohw.crb`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

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
    >>> from fohw.varpro import profile_theta
    >>> theta, rss = profile_theta(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    ...                            np.array([1.0, 2.0, 3.0]))
    >>> theta.round(12), round(rss, 12)
    (array([1., 2.]), 0.0)
    """
    theta, *_ = scipy.linalg.lstsq(Phi, y, lapack_driver="gelsy", check_finite=False)
    resid = y - Phi @ theta
    return theta, float(resid @ resid)


def parameter_covariance(jacobian, rss, n_samples):
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
    Computed from the singular values of ``G`` (never from the normal equations), so an
    ill-conditioned Jacobian costs accuracy only in the poorly determined directions.
    """
    d = jacobian.shape[1]
    s2 = rss / (n_samples - d)
    _, sing, vt = np.linalg.svd(jacobian, full_matrices=False)
    inv = vt.T @ np.diag(1.0 / sing**2) @ vt
    return s2 * inv, s2


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
        n = theta.shape[0]

        def residual(x):
            return y - builder.matrix(x[n]) @ x[:n]

        def jacobian(x):
            return -np.hstack([builder.matrix(x[n]), (builder.matrix_derivative(x[n]) @ x[:n])[:, None]])

        margin = 1e-9 * (hi - lo)
        x0 = np.append(theta, np.clip(alpha, lo + margin, hi - margin))
        ls = scipy.optimize.least_squares(
            residual, x0, jac=jacobian, method="trf", x_scale="jac", xtol=1e-12, ftol=1e-12,
            gtol=1e-12, bounds=(np.r_[np.full(n, -np.inf), lo + margin],
                                np.r_[np.full(n, np.inf), hi - margin]))
        new_rss = float(ls.fun @ ls.fun)
        if new_rss <= rss:        # the polish can only improve on the profile optimum
            theta, alpha, rss = ls.x[:n].copy(), float(ls.x[n]), new_rss
        converged = converged and ls.status > 0
        message += f"; polish: {ls.message}"
    jac = np.hstack([builder.matrix(alpha), (builder.matrix_derivative(alpha) @ theta)[:, None]])
    cov, s2 = parameter_covariance(jac, rss, n_samples)
    return _VarproFit(theta=theta, alpha=alpha, rss=rss, grid=grid, grid_J=grid_J,
                      search_alphas=search_alphas, search_J=search_J, converged=converged,
                      message=message, covariance=cov, noise_variance=s2)
