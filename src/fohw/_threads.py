"""BLAS threads for fohw's thin least-squares solves (private).

The solves of varpro, output_error and the studies factor tall, thin matrices (N x n with n
about 10). Multithreaded BLAS does not speed these up, and on a loaded machine its threads
wait for each other: with two OpenBLAS threads on a busy 2-core machine such solves were
measured 10-57 times slower than with one. With the optional ``threadpoolctl``
(``pip install 'fohw[threads]'``) fohw runs its own solves with one BLAS thread and restores
the caller's setting afterwards; without it BLAS runs as configured (``OPENBLAS_NUM_THREADS``
and the like). The numbers are the same either way to rounding (the factorizations do not
depend on the thread count beyond the order of some sums).
"""

from __future__ import annotations

import functools
from contextlib import nullcontext

try:
    from threadpoolctl import ThreadpoolController
except ImportError:          # the optional extra is not installed: BLAS as configured
    ThreadpoolController = None

__all__: list[str] = []

_controller = None


def one_blas_thread():
    """Context manager: BLAS on one thread inside (threadpoolctl installed), else unchanged."""
    global _controller
    if ThreadpoolController is None:
        return nullcontext()
    if _controller is None:
        # The controller sees the BLAS libraries loaded when it is made: scipy's own OpenBLAS
        # (scipy.linalg, loaded on first use) is another library than numpy's, so load it first
        # (else scipy's SVDs and triangular solves kept 2 threads: 0.35 s per SVD of a 1000 x 37
        # Jacobian on the busy 2-core machine against 2 ms).
        import scipy.linalg  # noqa: F401

        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")


def thin_solves(fn):
    """Decorator: run ``fn`` inside :func:`one_blas_thread`."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return fn(*args, **kwargs)
    return wrapper
