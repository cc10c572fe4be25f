"""The Dask options' checks: the bound on the worker count, the scheduler probe against a real
Dask scheduler and against ports that are none."""

from __future__ import annotations

import socket

import pytest

from validation.studies.dask_options import (
    WORKERS_PER_CORE,
    check_dask_options,
    cores,
    max_dask_workers,
    probe_scheduler,
)


def test_the_bound_follows_the_cores():
    assert max_dask_workers() == WORKERS_PER_CORE * cores()
    check_dask_options(None, max_dask_workers())  # at the bound: taken
    with pytest.raises(ValueError, match=r"^dask_workers: at most"):
        check_dask_options(None, max_dask_workers() + 1)
    for bad in (0, -1, True, 2.0):
        with pytest.raises(ValueError, match=r"^dask_workers: "):
            check_dask_options(None, bad)


def test_a_real_scheduler_passes_the_probe():
    """A Dask scheduler over plain TCP writes its handshake first: the probe takes it."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=0, processes=False, dashboard_address=None, scheduler_kwargs={"protocol": "tcp"}
    ) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://")
        probe_scheduler(address)
        probe_scheduler(address.removeprefix("tcp://"))  # no scheme: TCP


@pytest.mark.parametrize("address", ["tcp://", "tcp://host:notaport", "tcp://h:1/x", ""])
def test_a_malformed_address_is_named(address):
    with pytest.raises(ValueError, match=r"^scheduler: "):
        probe_scheduler(address)


def test_a_port_that_listens_but_says_nothing_is_refused_after_the_timeout():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
        with pytest.raises(ValueError, match=r"^scheduler: no Dask scheduler answers at tcp://"):
            probe_scheduler(address, timeout_s=0.5)


def test_the_dashboard_needs_a_cluster_and_bokeh(monkeypatch):
    from importlib import util

    from validation.studies.dask_options import check_dashboard, dashboard_address

    check_dashboard(False, None, None)  # not asked for: nothing to check
    assert dashboard_address(False) is None  # as before: no dashboard
    assert dashboard_address(True).startswith("127.0.0.1:")  # the loopback interface only
    with pytest.raises(ValueError, match=r"^dashboard: .*--dask-workers"):
        check_dashboard(True, None, None)
    monkeypatch.setattr(util, "find_spec", lambda name: None)
    with pytest.raises(ValueError, match=r"^dashboard: .*needs bokeh"):
        check_dashboard(True, None, 2)
