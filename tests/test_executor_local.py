"""Local worker processes (s2r.executor.local): the cores this process may use, workers started with Ctrl-C and
SIGTERM held back (a signal during their start-up is the parent's, never a worker traceback or a lost signal), a
worker killed from outside named as such, and no /dev/shm meaning one process with a warning, not a failure."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from contextlib import ExitStack
from pathlib import Path

import pytest

from s2r.cli import _report
from s2r.drift.matching import _matching_pool
from s2r.executor import usable_cores
from tests.conftest import make_rig

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str, **kw: object) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=env,
                          timeout=120, check=False, **kw)  # type: ignore[call-overload]


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity on this platform")
def test_usable_cores_follow_the_affinity_mask_not_the_host() -> None:
    out = _python("from s2r.executor import usable_cores; print(usable_cores())",
                  preexec_fn=lambda: os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}))
    assert out.stdout.strip() == "1", out.stderr
    assert 1 <= usable_cores() <= (os.cpu_count() or 1)


_SIGNAL_AT_START = """
import os, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
os.register_at_fork(after_in_child=lambda: os.kill(os.getpid(), signal.SIGINT),   # the group's Ctrl-C, in a worker
                    after_in_parent=lambda: os.kill(os.getpid(), signal.SIGINT))  # ... and in the parent
from s2r.executor import local_pool
try:
    pool = local_pool(2)
except KeyboardInterrupt:
    print("interrupted")
else:
    print("started", pool.submit(os.getpid).result() > 0)
    pool.shutdown()
"""


def test_ctrl_c_while_workers_start_is_the_parents_and_no_worker_prints_a_traceback() -> None:
    out = _python(_SIGNAL_AT_START)
    assert out.stdout.strip() == "interrupted", (out.stdout, out.stderr)
    assert "Traceback" not in out.stderr and "KeyboardInterrupt" not in out.stderr, out.stderr


def test_a_ctrl_c_reaching_starting_workers_alone_is_dropped_and_the_pool_works() -> None:
    code = _SIGNAL_AT_START.replace("after_in_parent=lambda: os.kill(os.getpid(), signal.SIGINT)",
                                    "after_in_parent=lambda: None")
    out = _python(code)
    assert out.stdout.strip() == "started True", (out.stdout, out.stderr)
    assert "Traceback" not in out.stderr, out.stderr


def test_a_worker_killed_from_outside_is_named_not_called_a_bug(capsys: pytest.CaptureFixture[str]) -> None:
    from concurrent.futures.process import BrokenProcessPool

    assert _report(BrokenProcessPool("A process in the process pool was terminated abruptly")) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: a worker process ended abruptly") and "--jobs 1" in err and "bug" not in err


def test_check_matches_images_over_the_detection_size_in_one_process() -> None:
    big = make_rig(name="big", width=4096, height=4096, hfov_rad=1.0, baseline_m=0.1)
    small = make_rig(name="small", width=640, height=480, hfov_rad=1.0, baseline_m=0.1)
    with ExitStack() as stack:
        assert _matching_pool(big, 2, stack) is None  # 8192^2 pairs read ahead for workers would break 1 GB
        assert _matching_pool(small, 1, stack) is None
        assert _matching_pool(small, 2, stack) is not None


@pytest.mark.skipif(shutil.which("unshare") is None or os.geteuid() != 0, reason="needs unshare and root")
def test_without_a_writable_dev_shm_check_and_calibrate_run_in_one_process(tmp_path: Path) -> None:
    data = ROOT.parent / "shared" / "data" / "opencv_stereo_chessboard"
    if not data.is_dir():
        pytest.skip(f"real webcam set not found at {data}")
    s2r = [sys.executable, "-m", "s2r"]
    script = (f"mount -t tmpfs -o ro none /dev/shm && cd {tmp_path} && "
              f"{' '.join(s2r)} calibrate {data} --pattern 9x6 --square 0.025 -o cal.yaml --jobs 2 && "
              f"{' '.join(s2r)} check cal.yaml {data} --jobs 2 --max-frames 3")
    probe = subprocess.run(["unshare", "-m", "true"], capture_output=True, check=False)
    if probe.returncode != 0:
        pytest.skip("unshare -m is not allowed here")
    out = subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True, text=True, timeout=300,
                         check=False, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode in (0, 1), out.stderr
    assert "detecting in one process" in out.stderr and "matching in one process" in out.stderr, out.stderr
    assert "Traceback" not in out.stderr and (tmp_path / "cal.yaml").is_file()
