"""s2r fleet check on a real cluster: `dask scheduler` and two `dask worker` processes on 127.0.0.1, one worker
killed by PID mid-run (every robot still judged, the loss named), the scheduler killed mid-run (one line, exit 2,
nothing published), and a local run interrupted by SIGINT then finished with --resume."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from s2r.cli import main
from s2r.drift.check import CheckSettings
from s2r.drift.fleet import load_fleet, run_robot
from s2r.drift.fleet_store import JOURNAL
from s2r.executor import child_environment
from tests.drift.fleet_cluster import ROOT, dask_cluster, http_server, stop

pytestmark = pytest.mark.slow


def _fleet(tmp_path: Path, rig_file: Path, recordings: dict[str, Path], count: int, web: str = "") -> Path:
    """``count`` robots alternating the unturned and the turned recording (good, drifted, good, ...); the last
    one read over HTTP from ``web`` when given."""
    robots = [{"name": f"r{k}", "profile": str(rig_file),
               "recording": {"folder": str(recordings["same" if k % 2 == 0 else "turned"]), "max_frames": 3}}
              for k in range(count)]
    if web:
        robots[-1]["recording"] = {"folder": f"{web}/{'same' if (count - 1) % 2 == 0 else 'turned'}/",
                                   "max_frames": 3}
    path = tmp_path / "fleet.yaml"
    path.write_text(json.dumps({"robots": robots}))
    return path


def _start(fleet: Path, out: Path, *extra: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-m", "s2r", "-q", "fleet", "check", str(fleet), "-o", str(out),
                             "--json", *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=child_environment(), cwd=ROOT)


def _wait_for_journal(out: Path, process: subprocess.Popen[bytes], *, count: int = 1) -> None:
    """Until ``count`` robots are journalled as finished (the run is under way)."""
    deadline = time.monotonic() + 300.0
    while time.monotonic() < deadline:
        if (out / JOURNAL).is_dir() and len(list((out / JOURNAL).glob("*.json"))) >= count:
            return
        assert process.poll() is None, process.communicate()
        time.sleep(0.1)
    raise TimeoutError("no robot finished within 300 s")


def _expected(name: str) -> str:
    return "good" if int(name[1:]) % 2 == 0 else "drifted"


def test_a_worker_killed_mid_run_loses_no_robot(tmp_path: Path, drift_rig_file: Path,
                                                recordings: dict[str, Path]) -> None:
    with http_server(recordings["same"].parent) as web, dask_cluster(tmp_path / "cluster") as cluster:
        fleet = _fleet(tmp_path, drift_rig_file, recordings, 6, web=web)
        out = tmp_path / "out"
        process = _start(fleet, out, "--scheduler", cluster.address)
        try:
            _wait_for_journal(out, process)
            victim = cluster.workers[0]
            os.kill(victim.pid, signal.SIGKILL)
            stdout, stderr = process.communicate(timeout=600)
        finally:
            stop(process)
        assert victim.wait(10) == -signal.SIGKILL
        local = run_robot(load_fleet(fleet, settings=CheckSettings())[1])  # r1 in this process
    assert process.returncode == 1, stderr
    summary = json.loads(stdout)
    rows = {r["name"]: r for r in summary["robots"]}
    assert sorted(rows) == [f"r{k}" for k in range(6)]
    assert all(r["verdict"] == _expected(n) for n, r in rows.items()), {n: r["reasons"] for n, r in rows.items()}
    assert rows["r1"]["rotation_error_deg"] == pytest.approx(local["rotation_error_deg"], abs=1e-9)
    assert rows["r5"]["recording"]["source"].startswith("http://127.0.0.1:")  # read by a worker over HTTP
    assert len(summary["lost_workers"]) == 1 and summary["lost_workers"][0].startswith("tcp://127.0.0.1:")
    assert "worker(s) lost during the run" in (out / "index.html").read_text()
    assert json.loads((out / "summary.json").read_text())["lost_workers"] == summary["lost_workers"]
    assert not (out / JOURNAL).exists()


def test_the_scheduler_killed_mid_run_ends_it_in_one_line(tmp_path: Path, drift_rig_file: Path,
                                                          recordings: dict[str, Path]) -> None:
    with dask_cluster(tmp_path / "cluster") as cluster:
        fleet = _fleet(tmp_path, drift_rig_file, recordings, 8)
        out = tmp_path / "out"
        process = _start(fleet, out, "--scheduler", cluster.address)
        try:
            _wait_for_journal(out, process)
            os.kill(cluster.scheduler.pid, signal.SIGKILL)
            killed = time.monotonic()
            _, stderr = process.communicate(timeout=60)
            took = time.monotonic() - killed
        finally:
            stop(process)
    assert process.returncode == 2
    lines = stderr.decode().strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {cluster.address}: --scheduler: lost the Dask "
                                                   "scheduler mid-run"), lines
    assert took < 30.0
    assert sorted(p.name for p in out.iterdir()) == [JOURNAL]  # no output published; the journal for --resume


def test_sigint_ends_a_run_cleanly_and_resume_checks_only_the_rest(tmp_path: Path, drift_rig_file: Path,
                                                                   recordings: dict[str, Path],
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    fleet = _fleet(tmp_path, drift_rig_file, recordings, 4)
    out = tmp_path / "out"
    process = _start(fleet, out, "--workers", "1")
    try:
        _wait_for_journal(out, process)
        children = psutil.Process(process.pid).children(recursive=True)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
    finally:
        stop(process)
    assert process.returncode == 130
    assert "interrupted:" in stderr.decode() and "--resume" in stderr.decode()
    finished = sorted(p.stem for p in (out / JOURNAL).glob("*.json"))
    assert 1 <= len(finished) < 4 and not (out / "summary.json").exists()
    psutil.wait_procs(children, timeout=20)
    assert not [p for p in children if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    assert main(["fleet", "check", str(fleet), "-o", str(out), "--json", "--resume", "--workers", "1"]) == 1
    summary = json.loads(capsys.readouterr().out)
    assert summary["resumed"] == finished
    assert {r["name"]: r["verdict"] for r in summary["robots"]} == {f"r{k}": _expected(f"r{k}") for k in range(4)}
    assert not (out / JOURNAL).exists() and (out / "index.html").is_file()
