"""Exceptions and warnings raised by fohw.

Every domain exception subclasses both :class:`FohwError` and the matching
built-in exception, so ``except ValueError`` keeps working in user code.
"""

from __future__ import annotations

__all__ = [
    "FohwError",
    "DimensionError",
    "ParameterError",
    "SimulationDivergedError",
    "DataFileError",
    "NotFittedError",
    "EstimationDivergedError",
    "ConvergenceWarning",
    "RankDeficiencyWarning",
]


class FohwError(Exception):
    """Base class of every error raised by fohw on purpose."""


class DimensionError(FohwError, ValueError):
    """An array has the wrong shape or length (mismatched signals, too short a record)."""


class ParameterError(FohwError, ValueError):
    """A scalar or vector argument is outside its admissible set."""


class SimulationDivergedError(FohwError, ArithmeticError):
    """The simulated output escaped (non-finite, or beyond the divergence threshold).

    Parameters
    ----------
    sample : int
        Index ``k`` of the first sample whose output escaped.
    value : float
        The offending output value (may be ``inf`` or ``nan``).
    threshold : float
        The bound on ``|y[k]|`` that was exceeded.
    """

    def __init__(self, sample: int, value: float, threshold: float):
        self.sample = int(sample)
        self.value = float(value)
        self.threshold = float(threshold)
        super().__init__(
            f"the simulated output diverged at sample k = {self.sample}: y[k] = {self.value!r} "
            f"(|y| must stay finite and at most {self.threshold:g}). The model is unstable for "
            "this input; for the paper's example use a bounded (uniform) input or a smaller "
            "input amplitude."
        )


class DataFileError(FohwError, ValueError):
    """A data file is malformed, truncated or does not match its expected checksum."""


class NotFittedError(FohwError, AttributeError):
    """An estimator was used before ``fit`` was called."""


class EstimationDivergedError(FohwError, ArithmeticError):
    """An estimator's iterates became non-finite (overflow), so no estimate exists."""


class ConvergenceWarning(UserWarning):
    """An iterative estimator stopped at ``max_iter`` before meeting its tolerance."""


class RankDeficiencyWarning(UserWarning):
    """The regressors (or the Jacobian) are rank deficient: some parameters are not identifiable.

    The message names the columns (parameters) that are linear combinations of the others; the
    result has ``status == Status.RANK_DEFICIENT`` and ``converged == False``.
    """
