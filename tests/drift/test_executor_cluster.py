"""The executor seam's Dask LocalCluster: loopback only, and no process left behind."""

from __future__ import annotations

import time

import psutil

from s2r.executor import open_runner


def _double(x: int) -> int:
    return 2 * x


def _listening(process: psutil.Process) -> list[str]:
    return [c.laddr.ip for c in process.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN]


def _worker_alive(process: psutil.Process) -> bool:
    """Still running and not multiprocessing's resource tracker (which leaves with this process itself)."""
    try:
        return process.status() != psutil.STATUS_ZOMBIE and "resource_tracker" not in " ".join(process.cmdline())
    except psutil.NoSuchProcess:
        return False


def test_a_local_dask_cluster_listens_on_loopback_only_and_leaves_nothing() -> None:
    me = psutil.Process()
    before = {p.pid for p in me.children(recursive=True)}
    with open_runner(workers=2, dask=True) as runner:
        assert sorted(o.result or 0 for o in runner.as_completed(_double, [1, 2, 3])) == [2, 4, 6]
        workers = [p for p in me.children(recursive=True) if p.pid not in before]
        addresses = _listening(me) + [ip for p in workers for ip in _listening(p)]
        assert len(workers) >= 2 and addresses
        assert set(addresses) == {"127.0.0.1"}, addresses
    deadline = time.monotonic() + 20.0
    alive = workers
    while alive and time.monotonic() < deadline:
        alive = [p for p in alive if _worker_alive(p)]
        time.sleep(0.2)
    assert not alive, [p.cmdline() for p in alive]
