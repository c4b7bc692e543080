"""Issue 14 items 3 and 5 and the output messages: device nodes, symlinks and FIFOs are never replaced (not even
with --force), racing runs cannot both write one output, ``depth -o FILE`` says it expected a folder."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import OutputExistsError, S2RError
from s2r.fileio import atomic_write_bytes, atomic_write_text, check_output_dir, prepare_output_dir

REPO = Path(__file__).resolve().parents[2]
PROFILE = REPO / "profiles" / "real" / "realsense_d435_848x480.yaml"


def _fifo(tmp_path: Path) -> Path:
    path = tmp_path / "pipe"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("force", [False, True])
def test_fifo_and_symlink_outputs_are_refused_even_with_force(tmp_path: Path, force: bool) -> None:
    target = tmp_path / "target.txt"
    target.write_text("keep", encoding="utf-8")
    link = tmp_path / "link.yaml"
    link.symlink_to(target)
    fifo = _fifo(tmp_path)
    with pytest.raises(OutputExistsError, match="symbolic link"):
        atomic_write_text(link, "new", force=force)
    with pytest.raises(OutputExistsError, match="not a regular file"):
        atomic_write_text(fifo, "new", force=force)
    assert link.is_symlink() and target.read_text(encoding="utf-8") == "keep"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.yaml", "pipe", "target.txt"]  # no temp left


def test_dev_null_is_refused_before_anything_is_touched() -> None:
    """The real /dev/null, as root, with --force: refused by the check, which runs before any write."""
    before = os.lstat("/dev/null")
    assert stat.S_ISCHR(before.st_mode)
    with pytest.raises(OutputExistsError, match="not a regular file"):
        atomic_write_bytes("/dev/null", b"x", force=True)
    after = os.lstat("/dev/null")
    assert stat.S_ISCHR(after.st_mode) and after.st_ino == before.st_ino and after.st_rdev == before.st_rdev


@pytest.mark.parametrize("force", ["", "--force"])
def test_cli_refuses_a_symlink_output_with_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  force: str) -> None:
    target = tmp_path / "victim.txt"
    target.write_text("keep", encoding="utf-8")
    link = tmp_path / "out.yaml"
    link.symlink_to(target)
    argv = ["profile", "convert", str(PROFILE), "--to", "s2r", "-o", str(link), *([force] if force else [])]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and str(link) in err
    assert link.is_symlink() and target.read_text(encoding="utf-8") == "keep"


def test_output_folder_checks(tmp_path: Path) -> None:
    a_file = tmp_path / "file"
    a_file.write_text("x", encoding="utf-8")
    with pytest.raises(OutputExistsError, match="is a file, expected a folder"):
        check_output_dir(a_file, force=True)
    with pytest.raises(S2RError, match="is a file, expected a folder"):
        atomic_write_text(a_file / "depth.png", "x", force=True)
    link = tmp_path / "dirlink"
    link.symlink_to(tmp_path)
    with pytest.raises(OutputExistsError, match="symbolic link"):
        prepare_output_dir(link, force=True)


def test_depth_output_that_is_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import cv2
    import numpy as np

    image, right = tmp_path / "img.png", tmp_path / "right.png"
    for path in (image, right):
        cv2.imwrite(str(path), np.zeros((480, 848), np.uint8))
    out = tmp_path / "existing.txt"
    out.write_text("keep", encoding="utf-8")
    code = main(["depth", str(image), str(right), "--profile", str(PROFILE), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "is a file, expected a folder" in err and "File exists" not in err
    assert out.read_text(encoding="utf-8") == "keep"


def test_racing_writers_at_most_one_wins(tmp_path: Path) -> None:
    """Eight threads publish the same new output at once without --force: exactly one succeeds."""
    out = tmp_path / "out.txt"
    barrier = threading.Barrier(8)
    results: list[str] = []

    def write(i: int) -> None:
        barrier.wait()
        try:
            atomic_write_text(out, f"writer {i}")
            results.append(f"ok {i}")
        except OutputExistsError:
            results.append("refused")

    threads = [threading.Thread(target=write, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    winners = [r for r in results if r.startswith("ok")]
    assert len(winners) == 1 and results.count("refused") == 7
    assert out.read_text(encoding="utf-8") == f"writer {winners[0].split()[1]}"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_output_appearing_after_the_check_is_not_replaced(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The check-then-rename race of the finding, made deterministic: another run writes between check and
    publish; this run must fail and leave the other's file."""
    out = tmp_path / "out.txt"
    real_fsync = os.fsync

    def other_run_writes(fd: int) -> None:
        real_fsync(fd)
        out.write_text("first run", encoding="utf-8")

    monkeypatch.setattr(os, "fsync", other_run_writes)
    with pytest.raises(OutputExistsError, match="another run"):
        atomic_write_text(out, "second run")
    assert out.read_text(encoding="utf-8") == "first run"


def test_two_cli_runs_racing_for_one_output(tmp_path: Path) -> None:
    out = tmp_path / "out.yaml"
    cmd = [sys.executable, "-m", "s2r", "profile", "convert", str(PROFILE), "--to", "kalibr", "-o", str(out)]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=120), p.stderr.read() if p.stderr else "") for p in procs]
    codes = sorted(code for code, _ in results)
    assert codes[0] == 0 and codes[1] in (0, 2)
    assert codes.count(0) == 1, results  # at most one of two racing runs succeeds
    assert all("Traceback" not in err for _, err in results)
