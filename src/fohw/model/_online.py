"""Online causal convolution by divide and conquer (the simulator's memory, Eqs. 14, 16).

A feedback recursion whose sample ``k`` needs ``D[t] = sum_{m <= t} beta[t - m] z[m]`` at times
``t < k``, while ``z[m]`` is only known once sample ``m`` is finished, is solved over time by
divide and conquer: :func:`divide_and_conquer` finishes the first half of ``[lo, hi)``, lets
:class:`HalfMerge` add the contribution of ``z[lo:mid]`` to ``D[mid:hi]`` by FFT, then finishes
the second half. Leaves of at most ``leaf_size`` samples add their own past directly. The cost
is ``O(N log^2 N)``. :func:`fohw.model.simulation.recursion` (the simulator) and
:func:`fohw.model.sensitivity._solve_feedback` (its derivative) share this skeleton.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules (scipy.fft, .optimize, ...) load on first use: import time

__all__ = ["HalfMerge", "divide_and_conquer"]


def divide_and_conquer(n, leaf_size, leaf, merge):
    """Call ``leaf(lo, hi)`` on consecutive segments of ``[0, n)`` and ``merge`` between them.

    ``solve(lo, hi)``: a segment of at most ``leaf_size`` samples is a leaf; a longer one is
    split at ``mid = (lo + hi) // 2``: ``solve(lo, mid)``, ``merge(lo, mid, hi)``,
    ``solve(mid, hi)``. Segments of one level differ in length by at most one sample.
    """
    def solve(lo, hi):
        if hi - lo <= leaf_size:
            leaf(lo, hi)
            return
        mid = (lo + hi) // 2
        solve(lo, mid)
        merge(lo, mid, hi)
        solve(mid, hi)

    if n > 0:
        solve(0, n)


class HalfMerge:
    """Add ``sum_{m in [lo, mid)} w_a[t - m] z[s_a, m]`` to ``dz[a, t]`` for ``t in [mid, hi)``.

    The merge step of :func:`divide_and_conquer` for any number of accumulators ``a``, each
    the convolution of one signal ``s_a`` with one weight vector ``w_a`` (time on axis 1 of
    ``z`` and ``dz``; further axes are carried along).

    Parameters
    ----------
    weights : sequence of ndarray, shape (n,)
        The distinct weight vectors (full length).
    pairs : sequence of (int, int, int)
        ``(accumulator, signal, weight index)`` for every accumulator that has memory.

    Notes
    -----
    The outputs needed, ``t - lo in [mid - lo, hi - lo)``, see weights ``w[1 .. hi - lo - 1]``
    only, so a circular convolution of any size ``nfft >= hi - lo`` gives them without
    wrap-around: ``z[lo:mid]`` zero-padded to ``nfft`` and ``w[:nfft]`` (whose entries beyond
    ``hi - lo`` reach only outputs past ``hi``). One FFT size ``next_fast_len(hi - lo)`` thus
    serves every segment of a level (their lengths differ by at most one), half the size of a
    full linear convolution, and the weights' spectra are computed once per FFT size and kept
    for the call. Each merge then costs one real FFT per signal and one inverse per accumulator.
    """

    def __init__(self, weights, pairs):
        self.weights = [np.asarray(w, dtype=np.float64) for w in weights]
        self.pairs = [(int(a), int(s), int(k)) for a, s, k in pairs]
        self.signals = sorted({s for _, s, _ in self.pairs})
        self._spectra = {}

    def spectra(self, nfft):
        """The rfft of every weight vector cut to ``nfft``, shape ``(n_weights, nfft // 2 + 1)``."""
        spec = self._spectra.get(nfft)
        if spec is None:
            stack = np.zeros((len(self.weights), nfft))
            for i, w in enumerate(self.weights):
                m = min(nfft, w.shape[0])
                stack[i, :m] = w[:m]
            spec = self._spectra[nfft] = scipy.fft.rfft(stack, axis=1)
        return spec

    def __call__(self, z, dz, lo, mid, hi):
        """``dz[a, mid:hi] +=`` the contribution of ``z[s_a, lo:mid]`` (in place)."""
        if not self.pairs:
            return
        nfft = scipy.fft.next_fast_len(hi - lo, real=True)
        spec = self.spectra(nfft)
        extra = (1,) * (z.ndim - 2)            # the weights act along time only
        zf = {s: scipy.fft.rfft(z[s, lo:mid], n=nfft, axis=0) for s in self.signals}
        for a, s, k in self.pairs:
            prod = zf[s] * spec[k].reshape(spec.shape[1:] + extra)
            dz[a, mid:hi] += scipy.fft.irfft(prod, n=nfft, axis=0,
                                             overwrite_x=True)[mid - lo:hi - lo]
