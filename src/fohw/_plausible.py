"""Is a free run plausible? The one envelope every check of a simulated output uses.

:func:`fohw.compare`, :func:`fohw.select_structure` and every fit (:func:`fohw.fit` and
:func:`fohw.identify`, on the model's own estimation input) judge a free run by the same test:
finite, and inside the measured output's range widened by :data:`ENVELOPE` times its span on
each side.
"""

from __future__ import annotations

import numpy as np

from ._validation import check_scalar

__all__ = ["ENVELOPE", "check_envelope", "implausible_sample", "implausible_message",
           "free_run_problem"]

#: Default plausibility factor: a free run is implausible when a sample lies more than
#: ``ENVELOPE`` times the measured output's range (max - min) below its minimum or above its
#: maximum (:func:`implausible_sample`).
ENVELOPE = 10.0


def check_envelope(envelope, name="envelope"):
    """``envelope`` as a float ``> 0``; None or ``inf`` switch the test off (``inf``)."""
    if envelope is None or (isinstance(envelope, (float, np.floating)) and envelope == np.inf):
        return np.inf
    return check_scalar(envelope, name, lower=0.0, lower_inclusive=False)


def implausible_sample(simulated, measured, envelope=ENVELOPE):
    """The first sample of a free run that leaves the envelope of a measured output, or None.

    Parameters
    ----------
    simulated : array_like
        A finite free-run output.
    measured : array_like
        The measured output it is judged against (its range ``[lo, hi]``, span ``hi - lo``).
    envelope : float
        The factor: the plausible interval is ``[lo - envelope * span, hi + envelope * span]``
        (default :data:`ENVELOPE`, 10). For a constant measured output the span is
        ``|lo|`` (no test if that is 0 too). ``inf`` or None switches the test off.

    Returns
    -------
    None or (int, float, (float, float))
        The first offending sample ``k``, its value and the plausible interval.

    Examples
    --------
    >>> from fohw.analysis.validation import implausible_sample
    >>> implausible_sample([0.0, 5.0, 20.0], [0.0, 1.0, 2.0]) is None
    True
    >>> implausible_sample([0.0, 5.0, 20.0, 1e6], [0.0, 1.0, 2.0])
    (3, 1000000.0, (-20.0, 22.0))
    """
    factor = check_envelope(envelope)
    ysim = np.asarray(simulated, dtype=float)
    y = np.asarray(measured, dtype=float)
    if not np.isfinite(factor) or y.size == 0:
        return None
    lo, hi = float(np.min(y)), float(np.max(y))
    span = hi - lo if hi > lo else abs(lo)
    if span == 0:
        return None
    low, high = lo - factor * span, hi + factor * span
    outside = np.flatnonzero(~((ysim >= low) & (ysim <= high)))
    if outside.size == 0:
        return None
    k = int(outside[0])
    return k, float(ysim[k]), (low, high)


def implausible_message(found, envelope=ENVELOPE, what="the measured output"):
    """The reason text for :func:`implausible_sample`'s finding."""
    k, value, (low, high) = found
    return (f"the free run is implausible from sample k = {k}: y[k] = {value:.6g}, outside "
            f"[{low:.6g}, {high:.6g}] ({what}'s range widened by {envelope:g} times its span "
            "on each side; the `envelope` parameter). The model is unstable or absurd on this "
            "input, so it is not scored.")


def free_run_problem(simulated, measured, envelope=ENVELOPE, where=None):
    """Why a fit's free run on its own estimation input is absurd (a sentence), or "".

    Not finite (the first such sample), or outside the envelope of the measured output
    (:func:`implausible_sample`, the test :func:`fohw.compare` applies). ``where(k)`` names
    sample ``k`` (default ``"sample k = {k}"``; several records: which record's sample).
    """
    where = where or (lambda k: f"sample k = {k}")
    ysim = np.asarray(simulated, dtype=float)
    bad = np.flatnonzero(~np.isfinite(ysim))
    if bad.size:
        k = int(bad[0])
        return (f"The fitted model's free run on its own estimation input leaves the finite "
                f"numbers at {where(k)} (y[k] = {ysim[k]!r}).")
    found = implausible_sample(ysim, measured, envelope)
    if found is None:
        return ""
    k, value, (low, high) = found
    return (f"The fitted model's free run on its own estimation input is implausible from "
            f"{where(k)}: y[k] = {value:.6g}, outside [{low:.6g}, {high:.6g}] (the "
            f"measured output's range widened by {envelope:g} times its span on each side, "
            "the envelope fohw.compare uses), so the model is unstable or absurd on the data "
            "it was fitted to.")
