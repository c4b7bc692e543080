"""The executor seam's Dask LocalCluster: loopback only, and no process left behind."""

from __future__ import annotations

import json
import time
from pathlib import Path

import psutil
import pytest

from s2r.cli import main
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


def test_fleet_check_runs_on_a_running_scheduler(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--scheduler ADDRESS: the robots go to an existing cluster (here one started for the test, on loopback)."""
    from distributed import LocalCluster

    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": n, "profile": "missing.yaml", "recording": "r"}
                                            for n in ("a", "b", "c")]}))
    with LocalCluster(n_workers=1, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                      silence_logs=40, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        code = main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--json",
                     "--scheduler", cluster.scheduler_address])
    summary = json.loads(capsys.readouterr().out)
    assert code == 1 and summary["counts"]["failed"] == 3
    assert all(str(tmp_path / "missing.yaml") in r["reasons"][0] for r in summary["robots"])
