"""The dask LocalCluster the tests start: loopback only, every port picked by the system (issue 47).

``LocalCluster(dashboard_address=None)`` alone still binds port 8787: distributed's scheduler
always starts its HTTP server (``/health``, ``/metrics``), and ``None`` leaves that server on its
default port 8787. Where something already listens there (another cluster, a notebook's
dashboard) distributed moves to another port with a "Port 8787 is already in use" warning, and
under the suite's ``filterwarnings = error`` the cluster fails to start. :data:`OPTIONS` puts that
server on a port the system picks on 127.0.0.1; the scheduler and the workers already bind port 0
on 127.0.0.1 (tcp, ``processes=True``) or use no socket at all (``processes=False``: in-process
transport). The scratch folder of the scheduler and the workers (``local_directory``) is the
test session's own, added by the ``dask_cluster_options`` fixture in conftest.py, not the
``dask-scratch-space`` every dask process on the machine shares in the system's temporary folder.

:func:`cannot_start` is the suite's one check that such a cluster starts and runs a task; the
fixture stops the run with its one line instead of letting every dask test fail on its own.
"""

import gc
import warnings

LOOPBACK = "127.0.0.1"
#: LocalCluster keywords: no dashboard, the scheduler's HTTP server and every port picked by
#: the system, on loopback.
OPTIONS = {"dashboard_address": None, "worker_dashboard_address": None, "scheduler_port": 0,
           "scheduler_kwargs": {"dashboard_address": f"{LOOPBACK}:0"}}


def cannot_start(options, timeout=60):
    """Why a one-worker LocalCluster with ``options`` cannot start and run a task; None if it can.

    The cluster talks tcp on 127.0.0.1 (real sockets, as the ``processes=True`` clusters of the
    tests do) and runs one task. Warnings are errors here, as in the suite. The answer is one
    line: the exception's type and its message with the line breaks folded.
    """
    import distributed

    reason = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            # distributed leaves the socket of a failed start unclosed; its ResourceWarning,
            # raised when the socket is collected, would be reported against whatever test
            # runs then, not as the failure it follows (collected below)
            warnings.simplefilter("ignore", ResourceWarning)
            with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                          protocol="tcp://", host=LOOPBACK, **options) as cluster, \
                    distributed.Client(cluster, timeout=timeout) as client:
                value = client.submit(sum, [1, 2]).result(timeout=timeout)
        if value != 3:
            reason = f"the cluster ran sum([1, 2]) and returned {value!r}"
    except Exception as exc:              # noqa: BLE001 - the reason is the answer
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())
    if reason is not None:                  # that socket, once the exception has let go of it
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ResourceWarning)
            gc.collect()
    return reason
