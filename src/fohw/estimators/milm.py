"""Multi-innovation Levenberg–Marquardt step for the fractional order (paper Section 4, Eqs. 41–48).

With the stacked sensitivities ``Xi(P, k) = [dyhat(k)/dalpha, …, dyhat(k-P+1)/dalpha]`` and
the innovations ``E = Y(P, k) - Phi(P, k)^T theta``, Eq. (48) is

``alpha <- alpha + (2/N) [ (2/N) Xi^T Xi + lambda ]^{-1} Xi^T E``.

The same step applied to a vector of parameters (``Xi`` with one column per parameter) is the
single-innovation LM baseline of Fig. 6.
"""

from __future__ import annotations

import numpy as np

from .._validation import check_scalar
from ..exceptions import ParameterError
from ..model.gl import gl_weights_derivative, gl_weights_unchecked

__all__ = ["milm_step", "milm_pass", "output_sensitivity", "alpha_update", "SENSITIVITIES"]

#: ``"finite_difference"``: Eq. (44) with step ``delta_alpha``; ``"exact"``: by the exact
#: derivative of the GL weights (:func:`fohw.model.gl.gl_weights_derivative`).
SENSITIVITIES = ("finite_difference", "exact")


def milm_step(sensitivities, innovations, *, n_samples, lm_lambda=1.0):
    """Levenberg–Marquardt increment of Eq. (48).

    Parameters
    ----------
    sensitivities : ndarray, shape (P,) or (P, d)
        ``Xi``: derivative of the predicted output with respect to the parameter(s), one row
        per sample of the window.
    innovations : ndarray, shape (P,)
        ``Y(P, k) - Phi(P, k)^T theta``.
    n_samples : int
        ``N``, the record length in the ``2/N`` factors (Eqs. 46a–b).
    lm_lambda : float, optional
        Damping ``lambda > 0`` (default 1, Table 1).

    Returns
    -------
    increment : float or ndarray, shape (d,)
        Add it to the current parameter(s). A float when ``sensitivities`` is 1-D.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.milm import milm_step
    >>> # (2/N) = 1: increment = (Xi @ E) / (Xi @ Xi + lambda) = 1 / (2 + 1)
    >>> milm_step(np.array([1.0, 1.0]), np.array([0.5, 0.5]), n_samples=2, lm_lambda=1.0)
    0.3333333333333333
    """
    c = 2.0 / n_samples
    xi = np.asarray(sensitivities, dtype=np.float64)
    if xi.ndim == 1:
        return float(c * (xi @ innovations) / (c * (xi @ xi) + lm_lambda))
    hessian = c * (xi.T @ xi) + lm_lambda * np.eye(xi.shape[1])
    return c * np.linalg.solve(hessian, xi.T @ innovations)


def milm_pass(Phi, y, *, theta0, n_samples, lm_lambda=1.0):
    """The step of Eq. (48) applied to theta at every sample, regressors fixed (``P = 1``).

    ``theta <- theta + (2/N) [(2/N) phi phi^T + lambda I]^{-1} phi e`` with
    ``e = y[k] - phi[k] @ theta``: the Levenberg–Marquardt analogue of one MIGD pass, used by
    the single-innovation LM baseline under the iterative schedule. By the Sherman–Morrison
    identity the step is ``(2/N) phi e / (lambda + (2/N) ||phi||^2)``.

    Parameters
    ----------
    Phi : ndarray, shape (N, n)
        Information matrix at the current alpha.
    y : ndarray, shape (N,)
    theta0 : ndarray, shape (n,)
    n_samples : int
        ``N`` in the ``2/N`` factors.
    lm_lambda : float, optional
        Damping ``lambda > 0``.

    Returns
    -------
    theta_history : ndarray, shape (N, n)
        ``theta(k)`` after the update at sample ``k``.

    Examples
    --------
    >>> import numpy as np
    >>> from fohw.estimators.milm import milm_pass, milm_step
    >>> Phi, y = np.array([[1.0, 2.0]]), np.array([3.0])
    >>> step = milm_step(Phi, y, n_samples=2, lm_lambda=1.0)    # one row: the same update
    >>> bool(np.allclose(milm_pass(Phi, y, theta0=np.zeros(2), n_samples=2)[0], step))
    True
    """
    c = 2.0 / n_samples
    theta = np.array(theta0, dtype=np.float64)
    history = np.empty((Phi.shape[0], theta.shape[0]))
    for k in range(Phi.shape[0]):
        phi = Phi[k]
        theta = theta + (c * (y[k] - phi @ theta) / (lm_lambda + c * (phi @ phi))) * phi
        history[k] = theta
    return history


def sensitivity_weights(alpha, n, *, sensitivity="finite_difference", delta_alpha=1e-3,
                        beta=None):
    """Weights whose GL convolution gives the regressor sensitivity ``d phi / d alpha``.

    ``"finite_difference"`` returns ``(beta(alpha + delta) - beta(alpha)) / delta`` (Eq. 44),
    ``"exact"`` returns :func:`fohw.model.gl.gl_weights_derivative`. ``beta``, if given, is
    ``gl_weights(alpha, n)`` already computed.
    """
    if sensitivity == "exact":
        return gl_weights_derivative(alpha, n)
    if beta is None:
        beta = gl_weights_unchecked(alpha, n)
    return (gl_weights_unchecked(alpha + delta_alpha, n) - beta) / delta_alpha


def output_sensitivity(builder, alpha, theta, *, sensitivity="finite_difference",
                       delta_alpha=1e-3):
    """Sensitivity ``d yhat[k] / d alpha`` of the one-step predictor over a whole record.

    Parameters
    ----------
    builder : RegressorBuilder
        The record.
    alpha : float
        Fractional order.
    theta : ndarray, shape (n,)
        Parameters.
    sensitivity : {"finite_difference", "exact"}, optional
        Eq. (44) with step ``delta_alpha`` (default, the paper) or the exact derivative.
    delta_alpha : float, optional
        Step of Eq. (44) (default ``1e-3``, Table 1).

    Returns
    -------
    s : ndarray, shape (N,)

    Examples
    --------
    >>> import fohw
    >>> from fohw.estimators.milm import output_sensitivity
    >>> d = fohw.datasets.paper_example(500, random_state=0)
    >>> b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> fd = output_sensitivity(b, 0.6, d.model.theta)
    >>> ex = output_sensitivity(b, 0.6, d.model.theta, sensitivity="exact")
    >>> bool(abs(fd - ex).max() < 1e-2 * abs(ex).max())
    True
    """
    check_sensitivity(sensitivity, delta_alpha)
    if sensitivity == "exact":
        return builder.matrix_derivative(alpha) @ theta
    return (builder.matrix(alpha + delta_alpha) - builder.matrix(alpha)) @ theta / delta_alpha


def alpha_update(builder, theta, alpha, *, rows=None, lm_lambda=1.0,
                 sensitivity="finite_difference", delta_alpha=1e-3, Phi=None):
    """One MI-LM step of the fractional order on chosen samples of a record (Eq. 48).

    Parameters
    ----------
    builder : RegressorBuilder
        The record.
    theta : ndarray, shape (n,)
        Current parameters (held fixed during the step).
    alpha : float
        Current fractional order.
    rows : slice or index array, optional
        Samples that form ``Xi`` and ``E``: the last ``P`` samples for Eq. (48) as printed,
        ``None`` (default) for the whole record (Eqs. 46a–b summed over the record).
    lm_lambda, sensitivity, delta_alpha
        As in :func:`milm_step` and :func:`output_sensitivity`.
    Phi : ndarray, optional
        ``builder.matrix(alpha)`` if the caller already has it.

    Returns
    -------
    alpha : float
        The updated order, not yet projected onto any bounds.

    Examples
    --------
    >>> import fohw
    >>> from fohw.estimators.milm import alpha_update
    >>> d = fohw.datasets.paper_example(2000, noise_variance=0.0, random_state=0)
    >>> b = fohw.model.lagged.regressors.RegressorBuilder(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> a1 = alpha_update(b, d.model.theta, 0.5)      # true alpha is 0.6
    >>> bool(0.5 < a1 < 0.7)
    True
    """
    check_sensitivity(sensitivity, delta_alpha)
    rows = slice(None) if rows is None else rows
    if Phi is None:
        Phi = builder.matrix(alpha)
    if sensitivity == "exact":
        dPhi = builder.matrix_derivative(alpha)
    else:
        dPhi = (builder.matrix(alpha + delta_alpha) - Phi) / delta_alpha
    xi = dPhi[rows] @ theta
    innov = builder.y[rows] - Phi[rows] @ theta
    return alpha + milm_step(xi, innov, n_samples=builder.n_samples, lm_lambda=lm_lambda)


def check_sensitivity(sensitivity, delta_alpha):
    """Validate the sensitivity settings; return ``delta_alpha`` as float."""
    if sensitivity not in SENSITIVITIES:
        raise ParameterError(f"`sensitivity` must be one of {SENSITIVITIES}; got {sensitivity!r}.")
    return check_scalar(delta_alpha, "delta_alpha", lower=0.0, upper=0.1, lower_inclusive=False)
