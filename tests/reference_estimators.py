"""Reference implementations the estimators' fast paths replaced, kept to compare with them.

They are test scaffolding, not part of the package (issue 23, item 8):

* :class:`FullMatrixProfile` / :class:`FullMatrixBuilder`: varpro's solves with the whole
  ``N x n`` matrix and its pivoted QR with ``Q`` at every point (what varpro did before the
  blocked TSQR solves of :mod:`fohw.estimators.profile`); :func:`full_matrix_varpro` puts them
  in place of the blocked ones for a whole fit.
* :func:`reference_windows`: the recursive schedule's windows rebuilt from the GL weights at
  every sample (``O(N^2)`` per pass, the code before the expansion in alpha);
  :func:`rebuilt_windows` puts it in place of :func:`fohw.estimators.hybrid.expanded_windows`.
* :class:`ReferenceRLS`: :class:`fohw.estimators.rls.MultiInnovationRLS` with each window rebuilt from the
  weights.
* :class:`FiniteDifferenceResidual` / :func:`finite_difference_output_error`: output_error's
  solver with scipy's forward differences (``"2-point"``) instead of the exact sensitivity.

Used by the tests and by ``benchmarks/`` (which put ``tests/`` on ``sys.path``).
"""

import contextlib
from unittest import mock

import numpy as np
import scipy.linalg

import fohw
from fohw import _linalg
from fohw.estimators import hybrid, output_error, varpro_search
from fohw.estimators.milm import sensitivity_weights
from fohw.estimators.profile import Profile, parameter_covariance
from fohw.model.lagged.regressors import WindowKernel


class FullMatrixProfile(Profile):
    """The reference: the whole ``N x n`` matrix and its pivoted QR with ``Q`` at every point."""

    def _evaluate(self, params):
        matrix = self.builder.matrix(params)
        return (matrix, *_linalg.lstsq(matrix, self.builder.y))

    def residual(self, params):
        matrix, linear, _, _ = self.solve(params)
        return self.builder.y - matrix @ linear

    def golub_pereyra(self, params):
        # d/dp of P_perp y: -P_perp dPhi theta - (Phi^+)^T dPhi^T r (Golub and Pereyra);
        # Kaufman's approximation drops the second term, exact only at a zero residual.
        matrix, linear, _, fac = self.solve(params)
        k = fac.rank
        q, r_tri = fac.q[:, :k], fac.r[:k, :k]
        resid = self.builder.y - matrix @ linear
        cols = []
        for d in self.builder.matrix_derivatives(params):
            v = d @ linear
            w = ((d.T @ resid) / fac.scale)[fac.perm[:k]]
            z = scipy.linalg.solve_triangular(r_tri, w, trans="T")
            cols.append(-(v - q @ (q.T @ v)) - q @ z)
        return np.column_stack(cols)

    def covariance(self, linear, params, rss):
        return parameter_covariance(self.builder.jacobian(linear, params), rss,
                                    self.builder.n_samples)


class FullMatrixBuilder:
    """A :class:`fohw.model.lagged.regressors.RegressorBuilder` whose :meth:`jacobian` is the reference one.

    The reference Jacobian forms ``Phi`` and every ``dPhi/dparams[m]`` in full and multiplies
    (what :meth:`fohw.model.lagged.regressors.RegressorBuilder.jacobian` did before it wrote the
    columns in place);
    everything else is the builder's.
    """

    def __init__(self, builder):
        self.wrapped = builder

    def __getattr__(self, name):
        return getattr(self.wrapped, name)

    def jacobian(self, linear, params):
        linear = np.asarray(linear, dtype=np.float64)
        n = linear.shape[0]
        derivs = self.wrapped.matrix_derivatives(params)
        G = np.empty((self.wrapped.n_samples, n + len(derivs)))
        G[:, :n] = self.wrapped.matrix(params)
        for m, d in enumerate(derivs):
            G[:, n + m] = d @ linear
        return G


def full_matrix_profile(builder):
    """The reference profile of a builder, with the reference Jacobian for the polish."""
    return FullMatrixProfile(FullMatrixBuilder(builder))


@contextlib.contextmanager
def full_matrix_varpro():
    """Within it, varpro (and the methods started from it) run the full-matrix reference."""
    with mock.patch.object(varpro_search, "Profile", full_matrix_profile):
        yield


def reference_windows(builder, bounds, P, sensitivity, delta_alpha):
    """Like :func:`fohw.estimators.hybrid.expanded_windows`: each window from the GL weights."""

    def window(k, alpha):
        length = max(k, 1)
        beta = fohw.gl_weights(alpha, length)
        return np.stack(builder.window(k, P, [
            beta, sensitivity_weights(alpha, length, sensitivity=sensitivity,
                                      delta_alpha=delta_alpha, beta=beta)]))

    return window


@contextlib.contextmanager
def rebuilt_windows():
    """Within it, the paper's recursive schedule rebuilds every window from the weights."""
    with mock.patch.object(hybrid, "expanded_windows", reference_windows):
        yield


class ReferenceRLS(fohw.estimators.rls.MultiInnovationRLS):
    """MI-RLS with each window rebuilt from the GL weights (``O(N^2)``), not streamed."""

    def _start_windows(self, lo, hi):
        self._kernel = WindowKernel(self._lags)

    def _append_signals(self, start, stop):
        pass

    def _windows(self, k, alpha):
        length = max(k, 1)
        weights = [fohw.gl_weights(alpha, length)]
        if self._estimate_alpha:
            weights.append(fohw.model.gl.gl_weights_derivative(alpha, length))
        return self._kernel.rows(self._signals, k, self._P, weights)


class FiniteDifferenceResidual(output_error.SimulationResidual):
    """output_error's residual, its Jacobian left to scipy's forward differences."""

    def scaled(self, scale, y_scale):
        residual, _ = super().scaled(scale, y_scale)
        return residual, "2-point"


@contextlib.contextmanager
def finite_difference_output_error():
    """Within it, output_error's solver uses forward differences (the path before the exact
    sensitivity: one simulation per parameter per Jacobian)."""
    with mock.patch.object(output_error, "SimulationResidual", FiniteDifferenceResidual):
        yield
