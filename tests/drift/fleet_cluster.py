"""A real Dask cluster for tests: `dask scheduler` and `dask worker` as separate processes on 127.0.0.1.

Every process is started with its own PID recorded and stopped by that PID (SIGTERM, then SIGKILL) when the
context ends, also when the test fails. The scheduler picks a free port itself (``--port 0``) and publishes its
address in a scheduler file; workers run without a nanny, so one PID is one worker.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from s2r.executor import child_environment

DASK = str(Path(sys.executable).with_name("dask"))
ROOT = Path(__file__).resolve().parents[2]


def stop(process: subprocess.Popen[bytes], *, grace_s: float = 10.0) -> None:
    """End ``process`` by its PID: SIGTERM, then SIGKILL after ``grace_s``; reaped either way."""
    if process.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.kill(process.pid, signal.SIGTERM)
        try:
            process.wait(grace_s)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.kill(process.pid, signal.SIGKILL)
            process.wait(grace_s)


@dataclass
class Cluster:
    """The address of the scheduler and the processes started (scheduler first)."""

    address: str
    folder: Path
    scheduler: subprocess.Popen[bytes]
    workers: list[subprocess.Popen[bytes]] = field(default_factory=list)

    def add_worker(self, name: str) -> subprocess.Popen[bytes]:
        log = (self.folder / f"{name}.log").open("wb")
        process = subprocess.Popen(
            [DASK, "worker", self.address, "--no-nanny", "--nthreads", "1", "--host", "127.0.0.1",
             "--no-dashboard", "--name", name, "--death-timeout", "30"],
            stdout=log, stderr=subprocess.STDOUT, env=child_environment(), cwd=ROOT)
        log.close()
        self.workers.append(process)
        return process

    def wait_for_workers(self, count: int, *, timeout_s: float = 60.0) -> None:
        """Until ``count`` workers have registered (read from the worker logs, no client needed)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            logs = [p.read_text(errors="replace") for p in self.folder.glob("w*.log")]
            if sum("Registered to" in text for text in logs) >= count:
                return
            time.sleep(0.2)
        raise TimeoutError(f"{count} workers did not register within {timeout_s} s: {self.folder}")


@contextlib.contextmanager
def dask_cluster(folder: Path, *, workers: int = 2) -> Iterator[Cluster]:
    """A scheduler and ``workers`` single-threaded workers, all on loopback; every one stopped by PID at the end."""
    folder.mkdir(parents=True, exist_ok=True)
    info = folder / "scheduler.json"
    for stale in [info, *folder.glob("*.log")]:
        stale.unlink(missing_ok=True)
    log = (folder / "scheduler.log").open("wb")
    scheduler = subprocess.Popen(
        [DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(info)],
        stdout=log, stderr=subprocess.STDOUT, env=child_environment(), cwd=ROOT)
    log.close()
    cluster: Cluster | None = None
    try:
        deadline = time.monotonic() + 60.0
        while not info.is_file() or not info.read_text().strip().endswith("}"):
            if time.monotonic() > deadline or scheduler.poll() is not None:
                raise RuntimeError(f"the scheduler did not start: {(folder / 'scheduler.log').read_text()}")
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:"), address
        cluster = Cluster(address, folder, scheduler)
        for k in range(workers):
            cluster.add_worker(f"w{k}")
        cluster.wait_for_workers(workers)
        yield cluster
    finally:
        for process in [*(cluster.workers if cluster else []), scheduler]:
            stop(process)


@contextlib.contextmanager
def http_server(folder: Path) -> Iterator[str]:
    """``python -m http.server`` serving ``folder`` on 127.0.0.1 (a free port it picks itself); its base URL.
    Stopped by PID at the end."""
    process = subprocess.Popen([sys.executable, "-u", "-m", "http.server", "0", "--bind", "127.0.0.1",
                                "--directory", str(folder)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                               env=child_environment())
    try:
        assert process.stdout is not None
        line = process.stdout.readline().decode()  # "Serving HTTP on 127.0.0.1 port 43503 (http://...) ..."
        port = int(line.split(" port ")[1].split()[0])
        yield f"http://127.0.0.1:{port}"
    finally:
        stop(process)
        if process.stdout is not None:
            process.stdout.close()
