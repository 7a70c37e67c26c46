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
    "ModelHookError",
    "TaskTimeoutError",
    "NotFittedError",
    "EstimationDivergedError",
    "ConvergenceWarning",
    "NothingSelectedWarning",
    "RankDeficiencyWarning",
    "ExtrapolationWarning",
    "DataWarning",
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
    cause : {"growth", "output_basis", "transfer_function"}
        ``"growth"``: the model is unstable for this input (the output grew past the bound).
        ``"transfer_function"``: the same for a :class:`fohw.FractionalTF` (its own advice).
        ``"output_basis"``: the output basis ``g`` returned NaN or inf at a finite ``y[k]`` (a
        function used outside its domain, such as ``sqrt`` of a negative output). An input
        basis that does so is caught before the simulation starts (a ``ParameterError``).
    overflow : bool, optional
        With ``"output_basis"``: the basis values overflowed (``y[k]**3`` past the largest
        double) rather than left a function's domain; the message says so.
    """

    CAUSES = ("growth", "output_basis", "transfer_function")

    def __init__(self, sample: int, value: float, threshold: float, cause: str = "growth",
                 overflow: bool = False):
        self.sample = int(sample)
        self.value = float(value)
        self.threshold = float(threshold)
        if cause not in self.CAUSES:            # a programming error inside fohw: say so
            raise ValueError(f"`cause` must be one of {self.CAUSES}; got {cause!r}.")
        self.cause = cause
        self.overflow = bool(overflow) and cause == "output_basis"
        k = self.sample
        if self.overflow:
            text = (f"the output basis g overflowed at sample k = {k}: y[k] = {self.value!r} is so "
                    "large that g(y[k]) (a power of it, or its sum with the coefficients) passes "
                    "the largest double, 1.8e308. The output is out of scale: the model is "
                    "unstable for this input, or its parameters (a result file edited by hand?) "
                    "or the data are in extreme units; rescale, fohw's estimates rescale with "
                    "the data.")
        elif self.cause == "output_basis":
            text = (f"the output basis g returned a non-finite value at sample k = {k} "
                    f"(y[k] = {self.value!r}): a basis function is not defined there (e.g. "
                    "sqrt or log of a negative value). Check the output's range (an operating "
                    "point shifts it), or use basis functions defined on the whole line.")
        elif self.cause == "transfer_function":
            text = (f"the simulated output diverged at sample k = {k}: y[k] = {self.value!r} "
                    f"(|y| must stay finite and at most {self.threshold:g}, by default 1e8 times "
                    "the output scale of a bounded response). The transfer function "
                    "is unstable for this input (see G.is_stable()), or grows without bound (an "
                    "integrator on a long record); pass divergence_threshold=np.inf to get the "
                    "growing output anyway.")
        else:
            text = (f"the simulated output diverged at sample k = {k}: y[k] = {self.value!r} "
                    f"(|y| must stay finite and at most {self.threshold:g}). The model is "
                    "unstable for this input. Check that the input stays in the range the "
                    "model was estimated on (a polynomial basis extrapolates fast), prefer "
                    "structures chosen by free-run simulation (fohw.select_structure), or fit "
                    "with method='output_error', which rejects unstable simulations.")
        super().__init__(text)

    def __reduce__(self):               # picklable across process and dask executors
        return (type(self), (self.sample, self.value, self.threshold, self.cause, self.overflow))


class DataFileError(FohwError, ValueError):
    """A data file is malformed, truncated or does not match its expected checksum."""


class ModelHookError(FohwError, ValueError):
    """A model kind's hook broke the :class:`fohw.Model` protocol.

    Raised by :func:`fohw.fit` (and the verbs built on it) and :func:`fohw.simulate` when a
    kind's ``simulate``, ``jacobian``, ``starts``, ``linear_start`` or ``with_parameters``
    returned something the protocol does not allow (an output of the wrong shape, a Jacobian
    with the wrong columns or non-finite entries, a start that is not a model), or raised an
    exception other than fohw's own and arithmetic ones. The message names the kind, the hook
    and what it returned; ``hook`` holds the hook's name. A fault of the kind's code, not of
    the data: fix the kind (``fohw.testing.check_model`` tests one).
    """

    def __init__(self, message, hook=""):
        super().__init__(message)
        self.hook = hook

    def __reduce__(self):               # picklable across process and dask executors
        return (type(self), (str(self), self.hook))


class TaskTimeoutError(FohwError, TimeoutError):
    """A task (one record's fit in :func:`fohw.stream_fits`) ran longer than its ``timeout``."""


class NotFittedError(FohwError, AttributeError):
    """An estimator was used before ``fit`` was called."""


class EstimationDivergedError(FohwError, ArithmeticError):
    """An estimator's iterates became non-finite (overflow), so no estimate exists."""


class ConvergenceWarning(UserWarning):
    """An iterative estimator stopped at ``max_iter`` before meeting its tolerance."""


class NothingSelectedWarning(ConvergenceWarning):
    """A structure selection scored no candidate it could keep (``Selection.best`` is None)."""


class RankDeficiencyWarning(UserWarning):
    """The regressors (or the Jacobian) are rank deficient: some parameters are not identifiable.

    The message names the columns (parameters) that are linear combinations of the others; the
    result has ``status == Status.RANK_DEFICIENT`` and ``converged == False``.
    """


class DataWarning(UserWarning):
    """The data look unlike what the model assumes or can represent.

    Issued by :func:`fohw.identify` for a level far from 0 with neither offset nor operating
    point, and for an output so small (RMS below 1.5e-154) that its squares underflow.
    """


class ExtrapolationWarning(UserWarning):
    """A model was simulated on an input outside the range it was estimated on."""
