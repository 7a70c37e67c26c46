"""Cramér–Rao bound for the parameters of the equation-error model — beyond the paper.

With white Gaussian equation noise of variance ``sigma^2``, the output given its past is
Gaussian with mean ``phi[k](alpha) @ theta`` (Eq. 19), so the log-likelihood of a record is
``-sum_k (y[k] - phi[k] theta)^2 / (2 sigma^2)`` up to a constant and the Fisher information of
``(theta, alpha)`` is ``E[G^T G] / sigma^2``, with ``G = [Phi(alpha), dPhi/dalpha @ theta]`` the
Jacobian of the one-step predictor. Because ``Phi`` depends on the noisy output, the expectation
is estimated by averaging ``G^T G`` over simulated noise realisations.

For the general model class (:class:`fohw.Structure`: an order per term, an offset, past
levels) the parameters are the structure's linear ones (theta, then ``offset``) and its
nonlinear ones (the free orders, then ``u_past``, ``y_past``), and ``G`` is the same
one-step-predictor Jacobian with a column per nonlinear parameter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validation import check_array, check_int, check_random_state, check_scalar
from ..exceptions import ParameterError
from ..model.regressors import RegressorBuilder
from ..model.system import HammersteinWiener, simulate

__all__ = ["crb", "CRBResult"]


@dataclass(frozen=True, repr=False)
class CRBResult:
    """The Cramér–Rao bound of one experiment.

    Attributes
    ----------
    covariance : ndarray, shape (n_linear + n_nonlinear,) * 2
        Lower bound on the covariance of any unbiased estimator of the structure's linear
        then nonlinear parameters (for the paper's model ``(theta, alpha)``, ``alpha`` last).
    theta_std : ndarray, shape (n,)
        Square roots of the theta diagonal.
    alpha_std : float
        Square root of the entry of the first free order (``nan`` when every order is fixed).
    rms_relative_error : float
        ``sqrt(trace(cov_theta)) / ||theta||``: the smallest root-mean-square of
        ``delta = ||theta_hat - theta|| / ||theta||`` an unbiased estimator can have.
    parameter_names : tuple of str
        Names of theta's entries.
    n_realizations : int
        Noise realisations averaged in the Fisher information.
    estimate_names : tuple of str
        Names of the rows of :attr:`covariance` (linear, then nonlinear parameters).
    """

    covariance: np.ndarray
    theta_std: np.ndarray
    alpha_std: float
    rms_relative_error: float
    parameter_names: tuple
    n_realizations: int
    estimate_names: tuple = ()

    @property
    def std(self) -> dict:
        """Square roots of the diagonal by parameter name."""
        return dict(zip(self.estimate_names, np.sqrt(np.diag(self.covariance))))

    def __repr__(self):
        return (f"CRBResult(rms_relative_error={self.rms_relative_error:.4g}, "
                f"alpha_std={self.alpha_std:.4g}, n_realizations={self.n_realizations})")


def crb(model, u, noise_variance, *, n_realizations=4, random_state=None):
    """Cramér–Rao bound of a model's parameters for an input and a noise level.

    The parameters are the structure's linear then nonlinear ones
    (:attr:`CRBResult.estimate_names`): for the paper's model ``(theta, alpha)``.

    Parameters
    ----------
    model : HammersteinWiener
        The true system.
    u : array_like, shape (N,)
        The input of the experiment.
    noise_variance : float
        Variance ``sigma^2 > 0`` of the white Gaussian equation noise.
    n_realizations : int, optional
        Noise realisations over which ``G^T G`` is averaged (default 4).
    random_state : None, int or numpy.random.Generator, optional
        Source of the noise realisations.

    Returns
    -------
    CRBResult

    Raises
    ------
    SimulationDivergedError
        A realisation escaped to infinity.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(10_000, random_state=0)
    >>> bound = fohw.crb(data.model, data.u, 0.01, random_state=1)
    >>> round(bound.rms_relative_error, 2), round(bound.alpha_std, 3)
    (0.03, 0.004)
    """
    if not isinstance(model, HammersteinWiener):
        raise ParameterError(f"`model` must be a HammersteinWiener; got {type(model).__name__}.")
    u = check_array(u, "u")
    sigma2 = check_scalar(noise_variance, "noise_variance", lower=0.0, lower_inclusive=False)
    n_realizations = check_int(n_realizations, "n_realizations", minimum=1)
    rng = check_random_state(random_state)
    structure = model.structure
    linear, nonlinear = model.linear, model.nonlinear
    u0, y0 = model.operating_point
    n_theta = model.theta.shape[0]
    n = linear.shape[0] + nonlinear.shape[0]
    info = np.zeros((n, n))
    for _ in range(n_realizations):
        v = np.sqrt(sigma2) * rng.standard_normal(u.shape[0])
        y = simulate(model, u, noise=v)
        b = RegressorBuilder(u - u0, y - y0, structure=structure)
        g = b.jacobian(linear, nonlinear)
        info += g.T @ g
    info /= n_realizations * sigma2
    cov = np.linalg.inv(info)
    cov = 0.5 * (cov + cov.T)
    std = np.sqrt(np.diag(cov))
    n_lin = linear.shape[0]
    alpha_std = float(std[n_lin]) if structure.orders.free else float("nan")
    return CRBResult(covariance=cov, theta_std=std[:n_theta], alpha_std=alpha_std,
                     rms_relative_error=float(np.sqrt(np.trace(cov[:n_theta, :n_theta]))
                                              / np.linalg.norm(model.theta)),
                     parameter_names=model.parameter_names, n_realizations=n_realizations,
                     estimate_names=structure.linear_names + structure.nonlinear_names)
