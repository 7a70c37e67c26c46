"""The suite's dask LocalCluster (tests/dask_service.py): loopback, ports the system picks, and
one line naming the cause when it cannot start (issue 47)."""

import socket
from pathlib import Path

import dask_service


def _ephemeral_ports():
    """The kernel's range of ports it hands out for port 0 (Linux; else the IANA range)."""
    try:
        low, high = map(int, Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split())
    except OSError:
        low, high = 49152, 65535
    return range(low, high + 1)


def test_the_cluster_listens_only_on_loopback_ports_the_system_picked(dask_cluster_options):
    import distributed

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  **dask_cluster_options) as cluster, \
            distributed.Client(cluster) as client:
        assert client.submit(sum, [1, 2]).result() == 3
        http = cluster.scheduler.http_server            # /health, /metrics: 8787 by default
        addresses = [cluster.scheduler_address, *client.scheduler_info()["workers"]]
        assert http.address == "127.0.0.1" and http.port in _ephemeral_ports(), (http.address,
                                                                                http.port)
        for address in addresses:
            host, port = address.removeprefix("tcp://").rsplit(":", 1)
            assert host == "127.0.0.1" and int(port) in _ephemeral_ports(), address
        assert Path(cluster.scheduler.local_directory).is_relative_to(
            dask_cluster_options["local_directory"])


def test_the_check_names_a_taken_port_in_one_line(dask_cluster_options):
    # the failure of issue 47: the scheduler's HTTP server asked for a port already in use
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        options = dict(dask_cluster_options, scheduler_kwargs={
            **dask_cluster_options["scheduler_kwargs"], "dashboard_address": f"127.0.0.1:{port}"})
        reason = dask_service.cannot_start(options)
    assert reason is not None and "\n" not in reason, reason
    assert f"Port {port} is already in use" in reason, reason
    assert dask_service.cannot_start(dask_cluster_options) is None
