"""The result of an identification run (returned by :func:`fohw.identify`)."""

from __future__ import annotations

import enum
import warnings
from dataclasses import dataclass, field

import numpy as np

from ._validation import RANGE_TOLERANCE, input_in_range
from .exceptions import ExtrapolationWarning
from .model.basis import Basis
from .model.orders import Orders
from .model.params import ThetaLayout
from .model.regressors import RegressorBuilder
from .model.simulation import simulate
from .model.structure import Structure
from .model.system import HammersteinWiener

__all__ = ["IdentificationResult", "Status"]


class Status(enum.IntEnum):
    """Why an identification run stopped: ``IdentificationResult.status``, one meaning for every method.

    Modelled on :class:`scipy.optimize.OptimizeResult`'s ``status``; positive values are
    successes, zero is "ran out of iterations", negative values are failures.
    """

    #: The regressors (or the Jacobian) are rank deficient at the estimate: some parameters
    #: are not identifiable from this record; the message names them.
    RANK_DEFICIENT = -2
    #: The optimiser reported a failure (its message says which).
    FAILED = -1
    #: Stopped at the iteration or evaluation limit before meeting the tolerance.
    MAX_ITER = 0
    #: Met the method's convergence test.
    CONVERGED = 1
    #: A recursive estimator made its passes; its convergence was not tested (Table 1 makes
    #: one pass, and a recursive estimate is whatever the last sample leaves).
    NOT_TESTED = 2


def _readonly(a):
    if a is None:
        return None
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, repr=False, eq=False)
class IdentificationResult:
    """Estimates, diagnostics and histories of one identification run.

    Attributes
    ----------
    method : str
        ``"hybrid"``, ``"single_innovation_gradient"``, ``"single_innovation_lm"``, ….
    schedule : str
        ``"recursive"`` (Table 1) or ``"iterative"`` (Steps 1–9); ``""`` where not applicable.
    alpha : float or None
        The first estimated free order (the paper's alpha); ``None`` when every order was fixed.
    theta : ndarray, shape (n,)
        Estimated ``[q ⊗ a, p ⊗ b]``.
    model : HammersteinWiener or None
        ``a, b, p, q`` recovered from ``theta`` by Eqs. (39)–(40); ``None`` if that is undefined
        (an ``a_i`` or ``b_i`` exactly zero; see ``message``).
    J : float
        Eq. (41): mean squared one-step error over the record at (``theta``, ``alpha``).
    status : Status
        Why the run stopped (an ``int``; see :class:`Status`).
    nit : int
        Iterations of the method's outer loop: passes over the record (``"hybrid"``, the
        single-innovation baselines, ``"rls"``), or iterations of the optimiser (``"varpro"``:
        the scalar alpha search plus the least-squares polish; ``"output_error"``: the
        least-squares solver).
    nfev : int
        Evaluations of the model over the whole record: ``J`` (one per pass) for the recursive
        methods, ``J(alpha)`` profiles and polish residuals for ``"varpro"``, free-run
        simulations for ``"output_error"`` (one per residual and one per Jacobian, the exact
        sensitivity of the free run).
    message : str
        Why the run stopped, and anything the user must know about the estimates.
    alpha_at_bound : bool
        Whether ``alpha`` was held at an end of ``alpha_bounds`` at least once.
    theta_history : ndarray, shape (N, n), or None
        ``theta(k)`` after the update at every sample of the last pass (recursive methods;
        ``None`` for ``"varpro"``).
    alpha_sample_history : ndarray, shape (N,), or None
        ``alpha`` after every sample of the last pass (constant within a pass in the
        iterative schedule; ``None`` for ``"varpro"``).
    alpha_history, J_history : ndarray, shape (nit,)
        ``alpha`` and ``J`` at the end of every outer iteration (for ``"varpro"``: at every
        point of the bounded alpha search).
    layout : ThetaLayout
        Names and blocks of theta.
    f_basis, g_basis : Basis
        The basis functions used.
    n_samples : int
        ``N``.
    options : dict
        The settings of the run (innovation length, bounds, …).
    covariance : ndarray, shape (d, d), or None
        Asymptotic covariance ``s^2 (G^T G)^{-1}`` of the ``d`` estimates in
        :attr:`estimate_names` order (the paper's model: ``(theta, alpha)``, ``alpha`` last),
        with ``G`` the Jacobian of the fitted residual (one-step predictor for ``"varpro"``,
        free-run simulation for ``"output_error"``); only for these least-squares estimates.
        For ``"structured"`` it is the covariance ``C`` of the structured parameters mapped to
        ``(theta, nonlinear)``, ``M C M^T`` (:meth:`fohw.Structure.structured_jacobian`; rank
        deficient), so that :meth:`standard_errors` gives ``C``'s own entries for ``a, b, p, q``.
        ``None`` where the estimator is not a least-squares optimum, since standard errors
        would then be meaningless.
    noise_variance : float or None
        ``s^2 = RSS / (N - d)``, with ``covariance``.
    alpha_profile : ndarray, shape (2, n_grid), or None
        ``"varpro"``: the coarse scan, alpha in row 0 and ``J(alpha)`` in row 1. With several
        free orders the scan moves them together, each at the same relative position in its
        bounds, and row 0 is the first order (zeros when only past levels are free).
    structure : Structure
        The model class that was fitted (orders, bases, offset, past, dt).
    orders : dict
        The estimated free orders, ``{name: value}`` in :attr:`Orders.free` order (the
        commensurate model: ``{"alpha": alpha}``).
    offset : float or None
        The estimated constant (``None`` without ``offset=True``).
    past : (float, float)
        The estimated levels ``(u_past, y_past)`` of the unseen past (deviations from the
        operating point; ``(0, 0)`` under ``past="rest"``).
    operating_point : (float, float)
        ``(u0, y0)`` removed before fitting; :meth:`predict` and :meth:`simulate` add it back.
    input_range : (float, float) or None
        The smallest and largest input of the estimation record (data units), set by
        :func:`fohw.identify`; :meth:`simulate` warns (:class:`fohw.ExtrapolationWarning`) on an
        input that goes beyond it by more than 5 % of its span.

    Notes
    -----
    ``covariance`` and :meth:`standard_errors` are ordered as :attr:`estimate_names`: the
    linear parameters (theta's, then ``offset``) and the nonlinear ones (the free orders, then
    ``u_past``, ``y_past``).
    """

    method: str
    schedule: str
    alpha: float
    theta: np.ndarray
    model: HammersteinWiener | None
    J: float
    status: Status
    nit: int
    nfev: int
    message: str
    alpha_at_bound: bool
    theta_history: np.ndarray
    alpha_sample_history: np.ndarray
    alpha_history: np.ndarray
    J_history: np.ndarray
    layout: ThetaLayout
    f_basis: Basis
    g_basis: Basis
    n_samples: int
    options: dict = field(default_factory=dict)
    covariance: np.ndarray | None = None
    noise_variance: float | None = None
    alpha_profile: np.ndarray | None = None
    structure: Structure | None = None
    orders: dict | None = None
    offset: float | None = None
    past: tuple = (0.0, 0.0)
    operating_point: tuple = (0.0, 0.0)
    input_range: tuple | None = None

    def __post_init__(self):
        object.__setattr__(self, "status", Status(self.status))
        if self.structure is None:          # the paper's commensurate model
            object.__setattr__(self, "structure", Structure(
                Orders.preset("commensurate", na=self.layout.na, nb=self.layout.nb),
                self.f_basis, self.g_basis))
        if self.orders is None:
            object.__setattr__(self, "orders", {} if self.alpha is None else
                               dict.fromkeys(self.structure.orders.free, float(self.alpha)))
        object.__setattr__(self, "orders", {k: float(v) for k, v in self.orders.items()})
        object.__setattr__(self, "past", tuple(float(v) for v in self.past))
        object.__setattr__(self, "operating_point",
                           tuple(float(v) for v in self.operating_point))
        for name in ("theta", "theta_history", "alpha_sample_history", "alpha_history",
                     "J_history", "covariance", "alpha_profile"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))

    @property
    def linear(self) -> np.ndarray:
        """The linear parameters: theta, then the offset if there is one."""
        return np.r_[self.theta, self.offset] if self.structure.offset else np.array(self.theta)

    @property
    def nonlinear(self) -> np.ndarray:
        """The nonlinear parameters: the free orders, then ``u_past``, ``y_past`` if estimated."""
        values = list(self.orders.values())
        if self.structure.past == "estimate":
            values += list(self.past)
        return np.array(values, dtype=np.float64)

    @property
    def estimate_names(self) -> tuple[str, ...]:
        """Names of the linear then the nonlinear parameters (the order of ``covariance``)."""
        return self.structure.linear_names + self.structure.nonlinear_names

    @property
    def dt(self) -> float:
        """Sampling time of the model."""
        return self.structure.dt

    @property
    def converged(self) -> bool:
        """``status == Status.CONVERGED``: the method's convergence test was met."""
        return self.status == Status.CONVERGED

    @property
    def n_iter(self) -> int:
        """Alias of :attr:`nit` (the name of fohw 0.1)."""
        return self.nit

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :attr:`theta`."""
        return self.layout.names

    @property
    def na(self) -> int:
        """Output lag order."""
        return self.layout.na

    @property
    def nb(self) -> int:
        """Input lag order."""
        return self.layout.nb

    def _require_covariance(self):
        if self.covariance is not None:
            return
        if self.status == Status.RANK_DEFICIENT:
            raise ValueError("this fit is rank deficient, so some parameters are not identifiable "
                             "and have no standard errors; see `message` for which.")
        raise ValueError(f"method {self.method!r} gives no covariance: standard errors are only "
                         "defined at a least-squares optimum ('varpro', 'output_error').")

    def standard_errors(self) -> dict:
        """Standard errors of the estimates and of the recovered ``a, b, p, q``.

        Returns
        -------
        dict of str to float
            Keyed by :attr:`estimate_names` (theta's names, then ``offset``, the free orders,
            ``u_past``, ``y_past`` where present; the paper's model: theta's names and
            ``"alpha"``) and the model parameter names (``a1``, ``b1``, ``p2``, ``q2``, …; the
            delta method through Eqs. 39–40).

        Raises
        ------
        ValueError
            The method provides no covariance.
        """
        self._require_covariance()
        se = np.sqrt(np.diag(self.covariance))
        out = dict(zip(self.estimate_names, se))
        out.update(zip(self.layout.model_parameter_names, np.sqrt(np.diag(self._model_covariance()))))
        return {k: float(v) for k, v in out.items()}

    def _model_covariance(self):
        jac = self.layout.recover_jacobian(self.theta)
        n = self.theta.shape[0]
        return jac @ self.covariance[:n, :n] @ jac.T

    def confidence_intervals(self, level=0.95) -> dict:
        """Wald confidence intervals ``estimate ± z * se`` (normal quantile ``z``).

        Parameters
        ----------
        level : float
            Coverage, in (0, 1). Default 0.95.

        Returns
        -------
        dict of str to (float, float)
            Same keys as :meth:`standard_errors`.
        """
        from scipy.stats import norm

        from ._validation import check_scalar

        level = check_scalar(level, "level", lower=0.0, upper=1.0, lower_inclusive=False,
                             upper_inclusive=False)
        z = float(norm.ppf(0.5 + level / 2))
        se = self.standard_errors()
        est = self._estimates()
        return {k: (est[k] - z * se[k], est[k] + z * se[k]) for k in se}

    def _estimates(self) -> dict:
        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        est.update(zip(self.layout.model_parameter_names, self.layout.recover_vector(self.theta)))
        return {k: float(v) for k, v in est.items()}

    def relative_error(self, theta_true, *, history=False):
        """``delta = ||theta_hat - theta|| / ||theta||`` (Section 6.1).

        With ``history=True``, for every sample of :attr:`theta_history`.
        """
        theta_true = self.layout.check_theta(theta_true, "theta_true")
        if history and self.theta_history is None:
            raise ValueError(f"method {self.method!r} keeps no per-sample history.")
        est = self.theta_history if history else self.theta
        return np.linalg.norm(est - theta_true, axis=-1) / np.linalg.norm(theta_true)

    def predict(self, u, y):
        """One-step-ahead prediction ``yhat[k] = phi[k] @ [theta, c] + y0`` (Eq. 19).

        ``u`` and ``y`` in the data's units; the operating point is removed and added back.
        """
        u0, y0 = self.operating_point
        u = np.asarray(u, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        builder = RegressorBuilder(u - u0 if u0 else u, y - y0 if y0 else y,
                                   structure=self.structure)
        yhat = builder.matrix(self.nonlinear) @ self.linear
        return yhat + y0 if y0 else yhat

    def simulate(self, u, *, history=None, **kwargs):
        """Free-run simulation of the identified predictor, in the data's units.

        Uses ``theta`` itself (and the offset, orders and past levels), i.e. exactly the model
        that was fitted; for the rank-one ``a, b, p, q`` of Eqs. (39)–(40) use
        ``fohw.simulate(result.model, u)``.

        Parameters
        ----------
        u : array_like
            Input.
        history : (u_past, y_past), optional
            Measured data just before ``u`` (e.g. the estimation record, to simulate the
            validation record that follows it): the GL memory starts from them.
        **kwargs
            ``noise``, ``noise_std``, ``random_state``, ``divergence_threshold``
            (:func:`fohw.simulate`).

        Raises
        ------
        SimulationDivergedError
            The identified model is unstable on this input.

        Warns
        -----
        ExtrapolationWarning
            ``u`` leaves the estimation input's range (:attr:`input_range`) by more than 5 % of
            its span: the basis functions extrapolate there, and a polynomial does so fast.
        """
        if self.input_range is not None:
            u_arr = np.asarray(u, dtype=np.float64)
            if u_arr.ndim == 1 and np.all(np.isfinite(u_arr)) \
                    and not input_in_range(u_arr, self.input_range):
                lo, hi = self.input_range
                warnings.warn(ExtrapolationWarning(
                    f"the input spans [{u_arr.min():.4g}, {u_arr.max():.4g}], beyond the range "
                    f"[{lo:.4g}, {hi:.4g}] the model was estimated on (by more than "
                    f"{RANGE_TOLERANCE:.0%} of its span); the basis functions extrapolate "
                    "there, so check the simulation before trusting it."), stacklevel=2)
        return simulate(self.structure, u, params=np.r_[self.linear, self.nonlinear],
                        operating_point=self.operating_point, history=history, **kwargs)

    def validate(self, u, y, **kwargs):
        """Free-run simulation and one-step prediction on a record: :func:`fohw.compare`."""
        from .analysis.validation import compare

        return compare(self, u, y, **kwargs)

    def to_dict(self) -> dict:
        """A JSON-ready dict (see :mod:`fohw.io.jsonio`)."""
        from .io.jsonio import result_to_dict

        return result_to_dict(self)

    def to_json(self, path):
        """Write the result to a versioned JSON file.

        :func:`fohw.load_result` reads it back with every float exact.
        """
        from .io.jsonio import _write_json

        _write_json(self.to_dict(), path)

    def _display_names(self):
        """The free orders and past levels first (alpha, as the paper lists it), then theta."""
        return list(self.structure.nonlinear_names) + list(self.structure.linear_names)

    def _repr_html_(self):
        import html

        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        rows = "".join(f"<tr><td>{html.escape(n)}</td><td>{est[n]:.6g}</td></tr>"
                       for n in self._display_names())
        return (f"<div><b>IdentificationResult</b> method={html.escape(self.method)!r}, "
                f"N={self.n_samples}, J={self.J:.4g}, status={self.status.name}<br>"
                f"<small>{html.escape(self.message)}</small>"
                f"<table><tr><th>parameter</th><th>estimate</th></tr>{rows}</table></div>")

    def summary(self) -> str:
        """A text table of the estimates and the run's diagnostics."""
        lines = [f"fohw identification: method={self.method!r}"
                 + (f", schedule={self.schedule!r}" if self.schedule else ""),
                 f"  samples N = {self.n_samples}, na = {self.structure.na}, "
                 f"nb = {self.structure.nb}, f_basis = {self.f_basis!r}, "
                 f"g_basis = {self.g_basis!r}"]
        if not self.structure.is_paper_model:
            lines.append(f"  model: {self.structure.describe()}")
        if self.operating_point != (0.0, 0.0):
            lines.append(f"  operating point (u0, y0) = ({self.operating_point[0]:.6g}, "
                         f"{self.operating_point[1]:.6g}), removed before fitting")
        lines += [f"  status = {self.status.name} ({int(self.status)}), iterations = {self.nit}, "
                  f"evaluations = {self.nfev}, J (Eq. 41) = {self.J:.6g}",
                  f"  {self.message}",
                  ""]
        names = self._display_names()
        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        if self.model is not None:
            est = self._estimates()
        if self.covariance is not None:
            se = self.standard_errors()
            ci = self.confidence_intervals()
            width = max(12, max(len(n) for n in names) + 2)
            lines.append(f"  {'parameter':<{width}}{'estimate':>14}{'std err':>12}"
                         f"{'95% CI low':>14}{'95% CI high':>14}")

            def row(n):
                return (f"  {n:<{width}}{est[n]:>14.6g}{se[n]:>12.3g}{ci[n][0]:>14.6g}"
                        f"{ci[n][1]:>14.6g}")
            lines += [row(n) for n in names]
            if self.model is not None and (self.layout.n_f > 1 or self.layout.n_g > 1):
                lines += ["", "  p and q estimated directly (structured least squares):"
                          if self.method == "structured" else
                          "  p and q recovered by Eqs. (39)-(40), delta-method errors:"]
                lines += [row(n) for n in self.layout.model_parameter_names
                          if n[0] in "pq"]
            lines += ["", f"  noise variance estimate s^2 = {self.noise_variance:.6g}"]
        else:
            width = max(12, max(len(n) for n in names) + 2)
            lines.append(f"  {'parameter':<{width}}{'estimate':>14}")
            lines += [f"  {n:<{width}}{est[n]:>14.6g}" for n in names]
            if self.model is not None:
                lines += ["", "  recovered by Eqs. (39)-(40):"]
                for name in "abpq":
                    vals = ", ".join(f"{v:.6g}" for v in getattr(self.model, name))
                    lines.append(f"  {name} = [{vals}]")
        if self.alpha_at_bound:
            lines.append("  alpha was held at (or ended at) a bound of alpha_bounds.")
        return "\n".join(lines)

    def __repr__(self):
        orders = ", ".join(f"{k}={v:.6g}" for k, v in self.orders.items())
        return (f"IdentificationResult(method={self.method!r}, schedule={self.schedule!r}, "
                f"{orders + ', ' if orders else ''}J={self.J:.6g}, status={self.status.name}, "
                f"nit={self.nit}, n_params={self.theta.shape[0]})")

    def plot(self, theta_true=None):
        """Histories of theta (or delta, given ``theta_true``), alpha and J.

        Returns
        -------
        fig, axes
            Matplotlib figure and its three axes; nothing is shown.
        """
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(3, 1, figsize=(8, 7))
        k = np.arange(1, self.n_samples + 1)
        if self.theta_history is None:       # batch methods: no per-sample history
            names = ("alpha",) + self.parameter_names
            axes[0].bar(range(len(names)), [self.alpha, *self.theta])
            axes[0].set_xticks(range(len(names)), names, rotation=60, fontsize=7)
            axes[0].set_ylabel("estimate")
            if self.alpha_profile is not None:
                axes[1].plot(*self.alpha_profile, marker=".")
                axes[1].set_xlabel("alpha")
                axes[1].set_ylabel("J(alpha), profile")
            axes[2].plot(np.arange(1, len(self.J_history) + 1), self.J_history, marker="o")
            axes[2].set_xlabel("evaluation")
            axes[2].set_ylabel("J")
            fig.tight_layout()
            return fig, axes
        if theta_true is None:
            axes[0].plot(k, self.theta_history, lw=0.8)
            axes[0].set_ylabel("theta(k)")
        else:
            axes[0].semilogy(k, self.relative_error(theta_true, history=True))
            axes[0].set_ylabel("delta(k)")
        axes[0].set_xlabel("sample k (last pass)")
        axes[1].plot(k, self.alpha_sample_history)
        axes[1].set_ylabel("alpha(k)")
        axes[1].set_xlabel("sample k (last pass)")
        axes[2].plot(np.arange(1, len(self.J_history) + 1), self.J_history, marker="o")
        axes[2].set_ylabel("J (Eq. 41)")
        axes[2].set_xlabel("iteration m")
        fig.tight_layout()
        return fig, axes


def recover_model(structure, theta, orders, *, offset=None, past=(0.0, 0.0),
                  operating_point=(0.0, 0.0)):
    """The model of Eqs. (39)-(40), or None and a note saying why it is undefined."""
    from .exceptions import ParameterError

    try:
        return HammersteinWiener.from_theta(
            theta, orders, na=structure.na, nb=structure.nb, f_basis=structure.f_basis,
            g_basis=structure.g_basis, orders=structure.orders, dt=structure.dt,
            offset=0.0 if offset is None else offset, past=past,
            operating_point=operating_point), ""
    except ParameterError as exc:
        return None, f" No model: {exc}"
