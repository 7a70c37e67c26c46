"""Why a fit stopped: :class:`Status`, one meaning for every kind and every method.

It lives below every kind and every result (the foundation layer of CONTRIBUTING.md), so that
:class:`fohw.FitResult`, the lagged kind's :class:`fohw.IdentificationResult` and every
estimator speak of one status.
"""

from __future__ import annotations

import enum

__all__ = ["Status"]


class Status(enum.IntEnum):
    """Why a fit stopped: ``FitResult.status``, one meaning for every kind and every method.

    Modelled on :class:`scipy.optimize.OptimizeResult`'s ``status``; positive values are
    successes, zero is "ran out of iterations", negative values are failures.
    """

    #: The fitted model's free run on its own estimation input leaves the finite numbers or
    #: the envelope :func:`fohw.compare` uses (from the fit's initial state, or from rest for
    #: estimated past levels): the model is unstable or absurd on the data it was fitted to,
    #: whatever its criterion; the message names the sample.
    IMPLAUSIBLE = -3
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
