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

Two choices say which bound is computed (:attr:`CRBResult.description`):

* ``parametrisation="theta"`` (default): the unstructured linear parameters, theta treated as
  ``n_g * na + n_f * nb`` free numbers; the bound that separable least squares (``"varpro"``)
  reaches. ``"structured"``: the model's own parameters ``(a, b, p_2.., q_2.., offset,
  nonlinear)`` (:attr:`fohw.Structure.structured_names`), with ``theta = [q ⊗ a, p ⊗ b]``
  (Eq. 20). If ``M = d(theta, ...)/d(a, b, p, q, ...)`` (:meth:`fohw.Structure.structured_jacobian`),
  the Jacobian becomes ``G M`` and the bound ``(M^T I M)^{-1}``; mapped back to theta it is
  ``M (M^T I M)^{-1} M^T``, never larger than the unstructured bound, and that is what
  :attr:`CRBResult.rms_relative_error` and :attr:`CRBResult.theta_std` report.
* ``noise="equation"`` (default): white Gaussian noise ``v[k]`` in the equation (Eq. 16), as
  above. ``"output"``: the system runs noise-free and white Gaussian noise ``e[k]`` of variance
  ``sigma^2`` is added to the *measured* output, ``y = ysim(x) + e``. The log-likelihood is
  then ``-||y - ysim(x)||^2 / (2 sigma^2)`` and the Fisher information ``S^T S / sigma^2``
  with ``S = d ysim / dx`` the sensitivity of the free-run simulation
  (:func:`fohw.model.lagged.sensitivity.simulation_jacobian`): deterministic, no averaging.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._linalg import inverse_gram, inverse_gram_triangular, triangular
from .._types import ArrayLike, RandomStateLike
from .._validation import check_array, check_int, check_random_state, check_scalar
from ..estimators.fit import free_jacobian, rank_rcond
from ..exceptions import ParameterError
from ..model.lagged.regressors import RegressorBuilder
from ..model.lagged.sensitivity import simulation_jacobian
from ..model.lagged.system import HammersteinWiener
from ..model.lagged.theta_hw import ThetaHW
from ..model.simulate import check_record_sampling, generic_model, simulate
from ..record import record_data

__all__ = ["crb", "CRBResult"]


@dataclass(frozen=True, repr=False)
class CRBResult:
    """The Cramér–Rao bound of one experiment.

    Attributes
    ----------
    covariance : ndarray, shape (d, d)
        Lower bound on the covariance of any unbiased estimator of the parameters in
        :attr:`estimate_names` order: the structure's linear then nonlinear parameters
        (``parametrisation="theta"``; for the paper's model ``(theta, alpha)``, ``alpha``
        last), or its structured ones (``"structured"``: ``a, b, p_2.., q_2..``, offset,
        nonlinear).
    theta_std : ndarray, shape (n,)
        Square roots of the diagonal of the bound on theta (for ``"structured"``, of
        :attr:`theta_covariance`, the structured bound mapped to theta).
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
        Names of the rows of :attr:`covariance`.
    parametrisation : {"theta", "structured"}
        Which parameters the bound is for.
    noise : {"equation", "output"}
        Where the white Gaussian noise enters (the equation, or the measured output).
    theta_covariance : ndarray, shape (n, n) or None
        The bound on theta's covariance (for ``"structured"``, ``M C M^T``; rank deficient).
    kind : str
        ``""`` for the lagged kind; else the model kind's name. For a kind other than the
        lagged one the bound is of its free parameters (``parametrisation="free"``,
        ``noise="output"``); "theta" then means the free parameters: :attr:`theta_std`,
        :attr:`rms_relative_error` and :attr:`theta_covariance` are of all of them, and
        :attr:`alpha_std` is that of the first free order (``nan`` when none is free).
    jacobian : str
        For another kind: ``"exact"`` (the kind's own Jacobian) or ``"finite differences"``.
    """

    covariance: np.ndarray
    theta_std: np.ndarray
    alpha_std: float
    rms_relative_error: float
    parameter_names: tuple
    n_realizations: int
    estimate_names: tuple = ()
    parametrisation: str = "theta"
    noise: str = "equation"
    theta_covariance: np.ndarray | None = None
    kind: str = ""
    jacobian: str = ""

    @property
    def description(self) -> str:
        """Which bound this is, in words."""
        if self.parametrisation == "free":
            return (f"Cramér–Rao bound of the free parameters {', '.join(self.estimate_names)} "
                    f"of a {self.kind}, under white Gaussian noise on the measured output "
                    f"(Jacobian by {self.jacobian})")
        what = ("the structured parameters " + ", ".join(self.estimate_names)
                if self.parametrisation == "structured" else
                "the unstructured parameters " + ", ".join(self.estimate_names))
        where = ("white Gaussian equation noise (Eq. 16)" if self.noise == "equation" else
                 "white Gaussian noise on the measured output (noise-free system)")
        return f"Cramér–Rao bound of {what}, under {where}"

    @property
    def std(self) -> dict:
        """Square roots of the diagonal by parameter name."""
        return dict(zip(self.estimate_names, np.sqrt(np.diag(self.covariance))))

    def __repr__(self):
        return (f"CRBResult(parametrisation={self.parametrisation!r}, noise={self.noise!r}, "
                f"rms_relative_error={self.rms_relative_error:.4g}, "
                f"alpha_std={self.alpha_std:.4g}, n_realizations={self.n_realizations})")

    def _repr_html_(self):
        from .._repr import html_table

        return html_table("CRBResult", ["parameter", "smallest std"], list(self.std.items()),
                          lines=[self.description,
                                 f"RMS relative error of theta >= {self.rms_relative_error:.4g}; "
                                 f"{self.n_realizations} noise realisations"])


PARAMETRISATIONS = ("theta", "structured")
#: The one bound of a model of any other kind: its free parameters, noise on the output.
GENERIC = ("free", "output")
NOISE_MODELS = ("equation", "output")


def crb(model: HammersteinWiener, u: ArrayLike, noise_variance: float, *,
        parametrisation: str | None = None, noise: str | None = None,
        n_realizations: int | None = None, random_state: RandomStateLike = None) -> CRBResult:
    """Cramér–Rao bound of a model's parameters for an input and a noise level.

    Parameters
    ----------
    model : HammersteinWiener or Model
        The true system. A :class:`fohw.Model` of any other kind (a :class:`fohw.FitResult`:
        its fitted model) gets the output-noise bound of its free parameters,
        ``noise_variance (S^T S)^{-1}`` with ``S`` the sensitivity of its free run
        (:func:`fohw.estimators.fit.free_jacobian`: the kind's exact Jacobian, else finite
        differences); ``parametrisation`` is then ``"free"`` and ``noise`` ``"output"``.
    u : array_like, shape (N,), Record or list of Record
        The input of the experiment; or a :class:`fohw.Record` (its input, its sampling time
        checked against the model's); or a list of Records, several experiments: their
        information adds up (the Jacobians' rows are stacked), so the joint bound is the
        inverse of the sum of the records' information.
    noise_variance : float
        Variance ``sigma^2 > 0`` of the white Gaussian noise.
    parametrisation : {"theta", "structured", "free"}, optional
        ``"theta"`` (default for the lagged kind): the structure's linear then nonlinear parameters, theta
        unstructured (for the paper's model ``(theta, alpha)``). ``"structured"``: the model's
        own parameters :attr:`fohw.Structure.structured_names` (``a, b, p_2.., q_2..``, then
        the offset and the nonlinear ones), with ``theta = [q ⊗ a, p ⊗ b]``.
    noise : {"equation", "output"}, optional
        ``"equation"`` (default for the lagged kind): the noise enters the equation (Eq. 16),
        the setting of the paper. ``"output"``: the system runs noise-free and the noise is
        added to the measured output.
    n_realizations : int, optional
        Equation noise: realisations over which ``G^T G`` is averaged (default 4). Output
        noise: not used (the information is deterministic); giving it is an error.
    random_state : None, int or numpy.random.Generator, optional
        Equation noise: source of the realisations. Output noise: not used; giving it is an
        error.

    Returns
    -------
    CRBResult
        Its :attr:`~CRBResult.parametrisation`, :attr:`~CRBResult.noise` and
        :attr:`~CRBResult.description` say which bound it is.

    Raises
    ------
    ParameterError
        An unknown ``parametrisation`` or ``noise``, ``n_realizations``/``random_state``
        with ``noise="output"``, or a singular Fisher information (the message names the
        parameters that the model and input leave unidentifiable).
    SimulationDivergedError
        A realisation (or the noise-free run) escaped to infinity.

    Notes
    -----
    Equation noise: the Fisher information is ``E[G^T G] / sigma^2``, ``G`` the Jacobian of the
    one-step predictor ``Phi(alpha) theta`` (Eq. 19). Output noise: ``S^T S / sigma^2``, ``S``
    the sensitivity of the noise-free simulation. Structured: ``G M`` (or ``S M``) with ``M``
    the derivative of ``theta = [q ⊗ a, p ⊗ b]`` (Eq. 20) with respect to ``(a, b, p, q)``.
    The information matrix is never formed: the bound is inverted from the equilibrated,
    pivoted QR of the stacked ``G`` (or ``S``, times ``M``) (:mod:`fohw._linalg`).

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(10_000, random_state=0)
    >>> bound = fohw.crb(data.model, data.u, 0.01, random_state=1)
    >>> round(bound.rms_relative_error, 2), round(bound.alpha_std, 3)
    (0.03, 0.004)
    >>> tight = fohw.crb(data.model, data.u, 0.01, parametrisation="structured",
    ...                  random_state=1)
    >>> tight.estimate_names
    ('a1', 'a2', 'b1', 'b2', 'p2', 'q2', 'q3', 'alpha')
    >>> round(tight.rms_relative_error, 3), round(tight.alpha_std, 4)
    (0.019, 0.0037)
    """
    records, _, _ = record_data(u, None, what="u")
    if records is not None:
        for r in records:
            check_record_sampling(model, r)
            if r.t is not None:
                raise ParameterError(f"the record{f' {r.name!r}' if r.name else ''} has "
                                     "non-uniform time stamps; the bound is computed on a "
                                     "uniform grid: resample the record first.")
        inputs = [r.u for r in records]
    else:
        inputs = [u]
    other = generic_model(model)
    if other is not None:
        return _crb_model(other, inputs, noise_variance, parametrisation, noise, n_realizations,
                          random_state)
    if not isinstance(model, (HammersteinWiener, ThetaHW)):    # the lagged kind, either map
        raise ParameterError(f"`model` must be a HammersteinWiener, a ThetaHW or a fohw.Model; "
                             f"got {type(model).__name__}.")
    parametrisation = "theta" if parametrisation is None else parametrisation
    noise = "equation" if noise is None else noise
    if parametrisation not in PARAMETRISATIONS:
        raise ParameterError(f"`parametrisation` must be one of {PARAMETRISATIONS}; got "
                             f"{parametrisation!r}.")
    if noise not in NOISE_MODELS:
        raise ParameterError(f"`noise` must be one of {NOISE_MODELS}; got {noise!r}.")
    inputs = [check_array(x, "u") for x in inputs]
    sigma2 = check_scalar(noise_variance, "noise_variance", lower=0.0, lower_inclusive=False)
    structure = model.structure
    linear, nonlinear = model.linear, model.nonlinear
    u0, y0 = model.operating_point
    n_theta = model.theta.shape[0]
    if noise == "equation":
        n_realizations = check_int(4 if n_realizations is None else n_realizations,
                                   "n_realizations", minimum=1)
        rng = check_random_state(random_state)
        n = linear.shape[0] + nonlinear.shape[0]

        def jacobians():
            for _ in range(n_realizations):
                for u in inputs:          # several records: their information adds up
                    v = np.sqrt(sigma2) * rng.standard_normal(u.shape[0])
                    y = simulate(model, u, noise=v)
                    b = RegressorBuilder(u - u0, y - y0, structure=structure)
                    yield b.jacobian(linear, nonlinear)

        # The information is R^T R / (n_realizations sigma2), R the triangle of the stacked G.
        root = triangular(jacobians(), n)
        n_rows = n_realizations * sum(u.shape[0] for u in inputs)
        variance = n_realizations * sigma2
    else:
        for name, value in (("n_realizations", n_realizations), ("random_state", random_state)):
            if value is not None:
                raise ParameterError(f"`{name}` is not used with noise='output' (the bound is "
                                     f"deterministic: no noise realisations); got {value!r}.")
        n_realizations = 0
        root = np.vstack([simulation_jacobian(structure, linear, nonlinear, u - u0)[1]
                          for u in inputs])                                  # S, stacked
        n_rows, variance = root.shape[0], sigma2
    names = structure.linear_names + structure.nonlinear_names
    if parametrisation == "structured":
        x = np.r_[model.a, model.b, model.p[1:], model.q[1:], linear[n_theta:], nonlinear]
        M = structure.structured_jacobian(x)
        cov = _inverse(root @ M, n_rows, variance, structure.structured_names)
        full = M @ cov @ M.T
        names = structure.structured_names
    else:
        cov = full = _inverse(root, n_rows, variance, names)
    theta_cov = full[:n_theta, :n_theta]
    free = structure.orders.free
    alpha_std = float(np.sqrt(cov[names.index(free[0]), names.index(free[0])])) if free \
        else float("nan")
    return CRBResult(covariance=cov, theta_std=np.sqrt(np.diag(theta_cov)), alpha_std=alpha_std,
                     rms_relative_error=float(np.sqrt(np.trace(theta_cov))
                                              / np.linalg.norm(model.theta)),
                     parameter_names=model.parameter_names, n_realizations=n_realizations,
                     estimate_names=names, parametrisation=parametrisation, noise=noise,
                     theta_covariance=theta_cov)


def _crb_model(model, inputs, noise_variance, parametrisation, noise, n_realizations,
               random_state):
    """:func:`crb` of a model of any kind but the lagged one: its free parameters, output noise."""
    kind = type(model).__name__
    for name, value, allowed in (("parametrisation", parametrisation, GENERIC[0]),
                                 ("noise", noise, GENERIC[1])):
        if value is not None and value != allowed:
            raise ParameterError(f"`{name}` must be {allowed!r} (or omitted) for a {kind}: its "
                                 "bound is of its free parameters with white noise on the "
                                 f"measured output (an output-error model); got {value!r}.")
    for name, value in (("n_realizations", n_realizations), ("random_state", random_state)):
        if value is not None:
            raise ParameterError(f"`{name}` is not used for a {kind} (its bound is "
                                 f"deterministic: no noise realisations); got {value!r}.")
    sigma2 = check_scalar(noise_variance, "noise_variance", lower=0.0, lower_inclusive=False)
    inputs = [model.check_input(u) for u in inputs]
    names = model.parameters.free_names
    if not names:
        raise ParameterError(f"every parameter of the {kind} is fixed or tied: no free "
                             "parameter has a bound.")
    runs = [free_jacobian(model, u) for u in inputs]     # several records: rows stacked
    yhat = np.concatenate([r[0] for r in runs])
    jac = np.vstack([r[1] for r in runs])
    how = runs[0][2]
    if not (np.all(np.isfinite(yhat)) and np.all(np.isfinite(jac))):
        raise ParameterError(f"the {kind}'s free run or its sensitivity on `u` is not finite: "
                             "no bound at a model that does not simulate this input.")
    cov = _named(*inverse_gram(jac, rcond=rank_rcond(how, *jac.shape)), sigma2, names)
    values = model.parameters.free_values()
    orders = [i for i, n in enumerate(names) if model.parameters[n].order]
    std = np.sqrt(np.diag(cov))
    return CRBResult(covariance=cov, theta_std=std,
                     alpha_std=float(std[orders[0]]) if orders else float("nan"),
                     rms_relative_error=float(np.sqrt(np.trace(cov)) / np.linalg.norm(values)),
                     parameter_names=names, n_realizations=0, estimate_names=names,
                     parametrisation=GENERIC[0], noise=GENERIC[1], theta_covariance=cov,
                     kind=kind, jacobian=how)


def _inverse(root, n_rows, variance, names):
    """``variance (A^T A)^{-1}``, symmetrised, with ``A = Q root`` of ``n_rows`` rows.

    The information matrix is ``A^T A / variance``; it is inverted from the equilibrated,
    pivoted QR of ``root`` (:func:`fohw._linalg.inverse_gram_triangular`), never formed.
    """
    return _named(*inverse_gram_triangular(root, n_rows), variance, names)


def _named(inverse, fac, variance, names):
    """``variance * inverse``, symmetrised; a singular one raises naming the parameters."""
    if inverse is None:
        dependent = ", ".join(names[i] for i in fac.dependent)
        raise ParameterError("the Fisher information is singular: the parameters "
                             f"{dependent} are not identifiable from this model and input.")
    cov = variance * inverse
    return 0.5 * (cov + cov.T)
