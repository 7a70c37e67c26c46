"""The result of an identification run (returned by :func:`fohw.identify`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .basis import Basis
from .params import ThetaLayout
from .regressors import RegressorBuilder
from .system import HammersteinWiener, simulate

__all__ = ["IdentificationResult"]


def _readonly(a):
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
    alpha : float
        Estimated fractional order.
    theta : ndarray, shape (n,)
        Estimated ``[q ⊗ a, p ⊗ b]``.
    model : HammersteinWiener or None
        ``a, b, p, q`` recovered from ``theta`` by Eqs. (39)–(40); ``None`` if that is undefined
        (an ``a_i`` or ``b_i`` exactly zero; see ``message``).
    J : float
        Eq. (41): mean squared one-step error over the record at (``theta``, ``alpha``).
    n_iter : int
        Outer iterations (passes over the record) performed.
    converged : bool
        Whether the stopping rule (relative change of ``J`` at most ``tol``) was met.
    message : str
        Why the run stopped, and anything the user must know about the estimates.
    alpha_at_bound : bool
        Whether ``alpha`` was held at an end of ``alpha_bounds`` at least once.
    theta_history : ndarray, shape (N, n)
        ``theta(k)`` after the update at every sample of the last pass.
    alpha_sample_history : ndarray, shape (N,)
        ``alpha`` after every sample of the last pass (constant within a pass in the
        iterative schedule).
    alpha_history, J_history : ndarray, shape (n_iter,)
        ``alpha`` and ``J`` at the end of every outer iteration.
    layout : ThetaLayout
        Names and blocks of theta.
    f_basis, g_basis : Basis
        The basis functions used.
    n_samples : int
        ``N``.
    options : dict
        The settings of the run (innovation length, bounds, …).
    """

    method: str
    schedule: str
    alpha: float
    theta: np.ndarray
    model: HammersteinWiener | None
    J: float
    n_iter: int
    converged: bool
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

    def __post_init__(self):
        for name in ("theta", "theta_history", "alpha_sample_history", "alpha_history",
                     "J_history"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))

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

    def relative_error(self, theta_true, *, history=False):
        """``delta = ||theta_hat - theta|| / ||theta||`` (Section 6.1).

        With ``history=True``, for every sample of :attr:`theta_history`.
        """
        theta_true = self.layout.check_theta(theta_true, "theta_true")
        est = self.theta_history if history else self.theta
        return np.linalg.norm(est - theta_true, axis=-1) / np.linalg.norm(theta_true)

    def predict(self, u, y):
        """One-step-ahead prediction ``yhat[k] = phi[k](alpha) @ theta`` (Eq. 19)."""
        builder = RegressorBuilder(u, y, na=self.na, nb=self.nb, f_basis=self.f_basis,
                                   g_basis=self.g_basis)
        return builder.matrix(self.alpha) @ self.theta

    def simulate(self, u, **kwargs):
        """Free-run simulation of the identified model (:func:`fohw.simulate`)."""
        if self.model is None:
            raise ValueError("this result has no model (see `message`): " + self.message)
        return simulate(self.model, u, **kwargs)

    def summary(self) -> str:
        """A text table of the estimates and the run's diagnostics."""
        lines = [f"fohw identification: method={self.method!r}"
                 + (f", schedule={self.schedule!r}" if self.schedule else ""),
                 f"  samples N = {self.n_samples}, na = {self.na}, nb = {self.nb}, "
                 f"f_basis = {self.f_basis!r}, g_basis = {self.g_basis!r}",
                 f"  iterations = {self.n_iter}, converged = {self.converged}, J (Eq. 41) = "
                 f"{self.J:.6g}",
                 f"  {self.message}",
                 "",
                 f"  {'parameter':<12}{'estimate':>14}",
                 f"  {'alpha':<12}{self.alpha:>14.6g}" + ("  (held at a bound)"
                                                          if self.alpha_at_bound else "")]
        lines += [f"  {n:<12}{v:>14.6g}" for n, v in zip(self.parameter_names, self.theta)]
        if self.model is not None:
            lines += ["", "  recovered by Eqs. (39)-(40):"]
            for name in "abpq":
                vals = ", ".join(f"{v:.6g}" for v in getattr(self.model, name))
                lines.append(f"  {name} = [{vals}]")
        return "\n".join(lines)

    def __repr__(self):
        return (f"IdentificationResult(method={self.method!r}, schedule={self.schedule!r}, "
                f"alpha={self.alpha:.6g}, J={self.J:.6g}, n_iter={self.n_iter}, "
                f"converged={self.converged}, n_params={self.theta.shape[0]})")

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
        axes[2].plot(np.arange(1, self.n_iter + 1), self.J_history, marker="o")
        axes[2].set_ylabel("J (Eq. 41)")
        axes[2].set_xlabel("iteration m")
        fig.tight_layout()
        return fig, axes
