"""Leftovers of an interrupted run (SIGKILL, power loss: nothing could clean up) are reported, never removed: a
later run writing beside them names each ``.s2r-tmp-*`` entry in one warning line, with what to do (before: they
stayed hidden for ever). A concurrent run may own them, hence no removal."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from s2r.fileio import TEMP_PREFIX
from tests.depth.stream_inputs import known_frames, known_rig, write_folder, write_profile
from tests.hostile._limits import run_s2r


@pytest.fixture(scope="module")
def known(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("leftovers")
    write_folder(known_frames(rig, distances_m=(0.9, 1.3)), root / "rec")
    return {"profile": str(write_profile(profile, root / "profile.yaml")), "rec": str(root / "rec")}


def _warnings(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("warning:") and TEMP_PREFIX in line]


def test_planted_leftovers_are_named_once_and_kept(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = run_s2r("-q", "depth", known["profile"], known["rec"], "-o", str(out), timeout_s=120)
    assert first.returncode == 0, first.stderr
    assert not _warnings(first.stderr)  # a clean folder: nothing reported
    old = tmp_path / f"{TEMP_PREFIX}out.ab12cd_x.old"  # what `--force` moved aside before a SIGKILL
    (old / "depth").mkdir(parents=True)
    (old / "frames.csv").write_text("name\n")
    tmp = tmp_path / f"{TEMP_PREFIX}out.q9z.tmp"  # a plain temporary
    tmp.write_bytes(b"half")
    done = run_s2r("depth", known["profile"], known["rec"], "-o", str(out), "--force", timeout_s=120)
    assert done.returncode == 0, done.stderr
    lines = _warnings(done.stderr)
    assert len(lines) == 1, done.stderr
    assert f"{old}: left by an interrupted s2r run (the previous out, moved aside by --force)" in lines[0]
    assert f"`mv {old} {out}`" in lines[0]
    assert f"{tmp}: left by an interrupted s2r run (a temporary): safe to delete" in lines[0]
    assert old.is_dir() and tmp.read_bytes() == b"half"  # never removed
    assert (out / "frames.csv").is_file() and (out / "depth").is_dir()


def test_a_run_killed_mid_write_is_reported_by_the_next(known: dict[str, Any], tmp_path: Path) -> None:
    """A real SIGKILL of ``depth --force`` while it writes: whatever ``.s2r-tmp-*`` it left is named by the
    next run, which still succeeds."""
    out = tmp_path / "out"
    assert run_s2r("-q", "depth", known["profile"], known["rec"], "-o", str(out), timeout_s=120).returncode == 0
    argv = [sys.executable, "-m", "s2r", "-q", "depth", known["profile"], known["rec"], "-o", str(out), "--force"]
    child = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and child.poll() is None:
            if any(p.name.startswith(TEMP_PREFIX) for p in tmp_path.iterdir()):
                break
            time.sleep(0.001)
        child.send_signal(signal.SIGKILL)
    finally:
        child.wait(timeout=30)
    left = sorted(p for p in tmp_path.iterdir() if p.name.startswith(TEMP_PREFIX))
    if child.returncode != -signal.SIGKILL or not left:
        pytest.skip("the run ended before a temporary could be caught (too fast here)")
    done = run_s2r("depth", known["profile"], known["rec"], "-o", str(out), "--force", timeout_s=120)
    assert done.returncode == 0, done.stderr
    lines = _warnings(done.stderr)
    assert len(lines) == 1 and all(str(p) in lines[0] for p in left), done.stderr
    assert all(os.path.lexists(p) for p in left)
