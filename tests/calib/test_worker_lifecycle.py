"""Issue 14 item 6: ``kill -9`` of ``s2r calibrate --jobs 2`` leaves no worker alive; a killed run's half-written
corner-cache temporaries are removed by the next run."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from s2r.calib.detect import CornerCache
from s2r.calib.detect.stream import DETECTOR_VERSION

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")


def _children(pid: int) -> list[int]:
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; only its exit status waits to be collected


def test_kill_9_of_calibrate_leaves_no_orphan_worker(small_set: Path, tmp_path: Path) -> None:
    for side in ("left", "right"):  # 8 pairs x 8 copies: long enough a detection to kill it mid-way
        for image in sorted((small_set / side).glob("*.png")):
            for copy in range(1, 8):
                shutil.copy(image, image.with_name(f"{copy}{image.name}"))
    cmd = [sys.executable, "-m", "s2r", "calibrate", *BOARD, str(small_set), "--jobs", "2", "--no-cache", "-o",
           str(tmp_path / "out.yaml")]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    workers: list[int] = []
    while time.monotonic() < deadline and len(workers) < 2 and proc.poll() is None:
        workers = _children(proc.pid)
        time.sleep(0.05)
    assert len(workers) >= 2, "the workers never started"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    orphans = [w for w in workers if _alive(w)]
    for w in orphans:  # clean up before failing
        os.kill(w, signal.SIGKILL)
    assert not orphans, f"workers {orphans} outlived their parent by 5 s"


def test_stale_cache_temporaries_are_removed(tmp_path: Path) -> None:
    entry = f"{'ab' * 32}-9x6-v{DETECTOR_VERSION}.json"
    stale, fresh = tmp_path / f".s2r-tmp-{entry}.x1k_9.tmp", tmp_path / f".s2r-tmp-{entry}.x2q3z.tmp"
    foreign = tmp_path / ".notes.tmp"  # not s2r's: never deleted, however old
    for path in (stale, fresh, foreign):
        path.write_text("{", encoding="utf-8")
    old = time.time() - 3600
    for path in (stale, foreign):
        os.utime(path, (old, old))
    CornerCache(tmp_path)
    assert not stale.exists() and fresh.exists()  # a fresh one may belong to a run writing right now
    assert foreign.exists()
