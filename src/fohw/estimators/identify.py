"""The one-call entry point :func:`fohw.identify` and its table of methods (dispatch only).

The paper's alternating method lives in :mod:`fohw.estimators.hybrid`; the estimators beyond
the paper in :mod:`~fohw.estimators.varpro`, :mod:`~fohw.estimators.output_error` and
:mod:`~fohw.estimators.rls`. Each method's settings are its own options class
(:mod:`fohw.estimators.options`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._validation import AlphaBounds, check_array, check_same_length
from ..exceptions import ParameterError
from ..model.regressors import RegressorBuilder
from .hybrid import (
    HybridOptions,
    SingleInnovationGradientOptions,
    SingleInnovationLMOptions,
    run_alternation,
)
from .output_error import OutputErrorOptions, output_error_result
from .rls import RlsOptions, rls_result
from .varpro import VarproOptions, varpro_result

__all__ = ["identify", "METHODS", "OPTIONS"]


def _alternation(method):
    def run(builder, options, bounds):
        return run_alternation(builder, method, options.check(builder.n_samples, bounds), bounds)
    return run


#: Every method: its options class and the function that runs it.
_TABLE = {
    "varpro": (VarproOptions, lambda builder, options, bounds: varpro_result(
        builder, options.check(), bounds)),
    "output_error": (OutputErrorOptions, output_error_result),
    "hybrid": (HybridOptions, _alternation("hybrid")),
    "single_innovation_gradient": (SingleInnovationGradientOptions,
                                   _alternation("single_innovation_gradient")),
    "single_innovation_lm": (SingleInnovationLMOptions, _alternation("single_innovation_lm")),
    "rls": (RlsOptions, rls_result),
}
#: The method names, the recommended one first.
METHODS = tuple(_TABLE)
#: ``{method: options class}``.
OPTIONS = {name: cls for name, (cls, _) in _TABLE.items()}


def identify(u, y, *, na, nb, f_basis, g_basis, method="varpro", alpha_bounds=(0.0, 1.0),
             options=None, **method_options):
    """Identify a fractional-order Hammerstein–Wiener model from input–output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and output records (zero before ``k = 0``).
    na, nb : int
        Output and input lag orders.
    f_basis, g_basis : Basis, int or callables
        Input and output basis functions (an int is a polynomial degree).
    method : str, optional
        One of :data:`METHODS`:

        ``"varpro"`` (default, recommended)
            Separable least squares (:mod:`fohw.estimators.varpro`), beyond the paper: theta by
            linear least squares for each alpha, alpha by a grid scan and a bounded search, then
            a joint least-squares polish. Reaches the Cramér–Rao bound of theta; reports
            standard errors. Options: :class:`~fohw.estimators.varpro.VarproOptions`.
        ``"output_error"``
            Beyond the paper: minimises the free-run *simulation* error over
            ``(theta, alpha)`` (:mod:`fohw.estimators.output_error`), started from the
            ``"varpro"`` estimate. Options:
            :class:`~fohw.estimators.output_error.OutputErrorOptions`.
        ``"hybrid"``
            The paper's method: MIGD for theta and MI-LM for alpha, alternately, under the
            schedule of Table 1 or of Steps 1–9 (:mod:`fohw.estimators.hybrid`). As printed it
            does not reach the accuracy of the paper's Table 2 (see ``docs/reproduction.md``).
            Options: :class:`~fohw.estimators.hybrid.HybridOptions`.
        ``"single_innovation_gradient"``, ``"single_innovation_lm"``
            The baselines of the paper's Fig. 6. Options:
            :class:`~fohw.estimators.hybrid.SingleInnovationGradientOptions`,
            :class:`~fohw.estimators.hybrid.SingleInnovationLMOptions`.
        ``"rls"``
            Beyond the paper: one pass of :class:`fohw.MultiInnovationRLS` (recursive least
            squares with recursive alpha). Options: :class:`~fohw.estimators.rls.RlsOptions`.
    alpha_bounds : (float, float), optional
        Interval for alpha, ``0 <= low < high <= 2``; default ``(0, 1)`` as in the paper. The
        batch methods may end on a bound (the result says so); the recursive ones hold alpha
        ``1e-3 * (high - low)`` inside it.
    options : mapping or MethodOptions, optional
        The method's options, as a mapping (``options={"innovation_length": 3}``) or an instance
        of its options class.
    **method_options
        The same options as keywords (``innovation_length=3``). A name the method does not have
        raises :class:`fohw.ParameterError` saying which methods have it.

    Returns
    -------
    IdentificationResult
        With ``status`` (:class:`fohw.Status`), ``nit``, ``nfev`` and ``converged``.

    Raises
    ------
    ParameterError, DimensionError
        Invalid settings or data, with the offending argument named.
    EstimationDivergedError
        The estimates became non-finite (badly scaled data, or an unstable recursion).

    Warns
    -----
    ConvergenceWarning
        The run stopped at its iteration limit, or a recursive method made its passes without
        testing convergence; the result then has ``converged=False``.
    RankDeficiencyWarning
        The information matrix is rank deficient: the message names the parameters that cannot
        be identified; ``status == Status.RANK_DEFICIENT``.

    Notes
    -----
    Eqs. (29)–(33) (MIGD), (41)–(48) (MI-LM), (39)–(40) (recovery of ``a, b, p, q``), Table 1
    and Steps 1–9 for the paper's methods.

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(2000, random_state=0)
    >>> res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    >>> res.method, res.status.name, round(res.alpha, 2)
    ('varpro', 'CONVERGED', 0.6)
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", fohw.ConvergenceWarning)
    ...     paper = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3,
    ...                           method="hybrid", innovation_length=3)
    >>> paper.status.name, paper.nit
    ('NOT_TESTED', 1)
    """
    if method not in _TABLE:
        raise ParameterError(f"`method` must be one of {METHODS}; got {method!r}.")
    options_class, run = _TABLE[method]
    if options is not None and method_options:
        if not isinstance(options, Mapping):
            raise ParameterError("pass a method's options either as keywords or as `options=`, "
                                 f"not both; got `options` and {sorted(method_options)}.")
        both = sorted(set(options) & set(method_options))
        if both:
            raise ParameterError(f"option(s) {both} given both as keywords and in `options`.")
        options = {**options, **method_options}
    elif method_options:
        options = method_options
    opts = options_class.build(method, options, others=OPTIONS)
    u = check_array(u, "u")
    y = check_array(y, "y")
    check_same_length(u, y, "u", "y")
    bounds = AlphaBounds(alpha_bounds)
    builder = RegressorBuilder(u, y, na=na, nb=nb, f_basis=f_basis, g_basis=g_basis)
    # Overflow is not left to NumPy's RuntimeWarning: every estimator checks its estimates
    # and criterion for finiteness and raises EstimationDivergedError with the reason.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return run(builder, opts, bounds)

